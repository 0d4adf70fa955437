//! Render farms: one frame split into regions rendered on many machines, each written as
//! an OpenEXR part that says what render it belongs to ([`note`]), read back
//! ([`read_part`]) and merged ([`Canvas`]) into the image one machine would have made.
//!
//! Merging is exact because every pixel's random numbers depend only on (pixel, sample,
//! seed): a part holds the same float pixels as the whole frame, and the merged film is
//! written by the same writer as a one-machine render, so the files are equal byte for
//! byte.

use std::io::Cursor;

use glam::Vec3;

use crate::imaging::openexr::{
    read_exr_counts, read_exr_pixels, Placement, COUNT_CHANNEL, EXR_NOTE,
};
use crate::imaging::Film;
use crate::limits::check_image_size;
use crate::render::cost::CostMap;
use crate::render::region::{Region, TileIndex};
use crate::render::{RenderOptions, Sampling};
use crate::scene::Scene;

/// FNV-1a, 64 bits: identifies a scene file's bytes in a part's note. A check against
/// mixing up scenes by mistake, not against forgery.
pub fn scene_hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The line of a note that names the tile; every other line must agree between parts.
const TILE_KEY: &str = "tile: ";

/// The text of an EXR file's `p3trace` attribute: the program, the scene (its file's name,
/// not its path, which may differ between machines, and the hash of its bytes), and every
/// setting that changes pixels. Threads, the structure and the ray mode are left out:
/// they never change a colour. A cost image (`cost`, from the structure named
/// `structure`) says so in a line of its own, with the structure and the mode, which
/// change its counts. A part rendered with `--tile` adds its tile as the last line.
pub fn note(
    scene: &Scene,
    scene_hash: u64,
    options: &RenderOptions,
    skybox: bool,
    cost: Option<(CostMap, &str)>,
    tile: Option<TileIndex>,
) -> String {
    let shade = &options.shade;
    let samples = match options.sampling {
        Sampling::Centre => "1, the pixel centre".to_string(),
        Sampling::Jittered(g) => format!("{}x{} jittered", g.columns, g.rows),
    };
    let soft = shade
        .soft_light_size
        .map_or("off".to_string(), |s| format!("{s:?}"));
    let file_name = std::path::Path::new(&scene.name)
        .file_name()
        .map_or(scene.name.clone(), |n| n.to_string_lossy().into_owned());
    let mut text = format!(
        "p3trace {} (commit {})\n\
         scene: {} (fnv1a64 {scene_hash:016x})\n\
         resolution: {}x{}\n\
         samples: {samples}\n\
         seed: {}\n\
         shading: profile {:?}, max depth {}, schlick {}, soft lights {soft}, \
         light grid {}x{}, roughness {:?}\n\
         camera: aperture {:?}, focal {:?}\n\
         shutter: {:?},{:?}\n\
         skybox: {}",
        crate::machine::VERSION,
        crate::machine::COMMIT,
        file_name,
        options.width,
        options.height,
        options.seed,
        shade.profile,
        shade.max_depth,
        shade.schlick,
        shade.light_grid.columns,
        shade.light_grid.rows,
        shade.roughness,
        scene.camera.aperture,
        scene.camera.focal,
        options.shutter[0],
        options.shutter[1],
        if skybox { "yes" } else { "no" },
    );
    if let Some((cost, structure)) = cost {
        text.push_str(&format!("\n{}", cost.note_line(structure, options.mode)));
    }
    if let Some(tile) = tile {
        text.push_str(&format!("\n{TILE_KEY}{tile}"));
    }
    text
}

/// A region read back from an EXR file.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// The file, for messages.
    pub name: String,
    /// The note without its tile line: equal for every part of one frame.
    pub identity: String,
    /// The tile it claims to be, if it was rendered with `--tile`.
    pub tile: Option<TileIndex>,
    /// The whole image's width and height (the display window).
    pub image: (u32, u32),
    /// Its pixels' place in the image (the data window).
    pub region: Region,
    /// Its pixels, top row first.
    pub pixels: Vec<Vec3>,
}

/// Reads a part from the bytes of an EXR file `name`: one layer of 32-bit float R, G and B
/// whose data window lies inside a display window at the origin, with a `p3trace` note.
/// Anything else is an error naming the file; nothing here panics or allocates more than
/// the header's checked size.
pub fn read_part(bytes: &[u8], name: &str) -> Result<Part, String> {
    use exr::compression::Compression;
    use exr::meta::attribute::{AttributeValue, SampleType};
    let bad = |why: String| format!("{name}: {why}");
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), true)
        .map_err(|e| bad(format!("not a readable OpenEXR file ({e})")))?;
    let [header] = meta.headers.as_slice() else {
        return Err(bad(format!(
            "{} layers; a part has one",
            meta.headers.len()
        )));
    };
    if header.deep {
        return Err(bad("deep data; a part has flat RGB".into()));
    }
    let channels: Vec<(String, SampleType)> = header
        .channels
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_type))
        .collect();
    let rgb = ["B", "G", "R"].map(|c| (c.to_string(), SampleType::F32));
    let counts = [(COUNT_CHANNEL.to_string(), SampleType::F32)];
    // How to read its pixels, and the bytes of each.
    type Reader = fn(&[u8], u32, u32) -> Result<Vec<Vec3>, String>;
    let (read_pixels, bytes_per_pixel): (Reader, u64) = if channels == rgb {
        (read_exr_pixels, 12)
    } else if channels == counts {
        (read_exr_counts, 4)
    } else {
        return Err(bad(format!(
            "channels {:?}; a part has R, G and B (a colour image) or {COUNT_CHANNEL} (a \
             cost image) as 32-bit floats",
            channels.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>()
        )));
    };
    let display = header.shared_attributes.display_window;
    let side = |n: usize| u32::try_from(n).ok().filter(|&n| n > 0);
    let (Some(width), Some(height)) = (side(display.size.x()), side(display.size.y())) else {
        return Err(bad("an empty display window".into()));
    };
    if display.position.x() != 0 || display.position.y() != 0 {
        return Err(bad("a display window that does not start at 0,0".into()));
    }
    check_image_size(width, height).map_err(bad)?;
    let corner = header.own_attributes.layer_position;
    let (x0, y0) = match (u32::try_from(corner.x()), u32::try_from(corner.y())) {
        (Ok(x), Ok(y)) => (x, y),
        _ => return Err(bad("a data window left of or above the image".into())),
    };
    let size = header.layer_size;
    let region = match (side(size.x()), side(size.y())) {
        (Some(w), Some(h))
            if u64::from(x0) + u64::from(w) <= u64::from(width)
                && u64::from(y0) + u64::from(h) <= u64::from(height) =>
        {
            Region {
                x0,
                x1: x0 + w,
                y0,
                y1: y0 + h,
            }
        }
        _ => {
            return Err(bad(format!(
                "a data window outside its {width}x{height} display window"
            )))
        }
    };
    // Only lossless compressions keep the floats exact, and deflate expands at most
    // 1032-fold: a forged header cannot make the reader allocate more pixels than the
    // file's bytes could hold.
    let fold = match header.compression {
        Compression::Uncompressed => 1,
        Compression::ZIP1 | Compression::ZIP16 => 1032,
        other => {
            return Err(bad(format!(
                "compressed with {other:?}; p3trace writes parts with ZIP"
            )))
        }
    };
    if region.pixels() * bytes_per_pixel > bytes.len() as u64 * fold {
        return Err(bad(format!(
            "too short ({} bytes) for its {}x{} pixels",
            bytes.len(),
            region.width(),
            region.height()
        )));
    }
    let note = match header.own_attributes.other.get(EXR_NOTE.as_bytes()) {
        Some(AttributeValue::Text(text)) => std::str::from_utf8(text.bytes())
            .map_err(|_| bad(format!("its '{EXR_NOTE}' attribute is not UTF-8")))?
            .to_string(),
        _ => {
            return Err(bad(format!(
                "no '{EXR_NOTE}' attribute: not a part written by p3trace render -o NAME.exr"
            )))
        }
    };
    let (identity, tile) = match note.rsplit_once('\n') {
        Some((rest, last)) if last.starts_with(TILE_KEY) => {
            let tile: TileIndex = last[TILE_KEY.len()..].parse().map_err(&bad)?;
            (rest.to_string(), Some(tile))
        }
        _ => (note, None),
    };
    if let Some(t) = tile {
        let expected = Region::tile(t.index, t.count, width, height).map_err(&bad)?;
        if expected != region {
            return Err(bad(format!(
                "it says it is tile {t} but covers rows {}..{}, columns {}..{}",
                region.y0, region.y1, region.x0, region.x1
            )));
        }
    }
    let pixels = read_pixels(bytes, region.width(), region.height()).map_err(&bad)?;
    Ok(Part {
        name: name.to_string(),
        identity,
        tile,
        image: (width, height),
        region,
        pixels,
    })
}

/// The frame being assembled, one part at a time (a part's pixels can be dropped once
/// laid).
#[derive(Clone, Debug)]
pub struct Canvas {
    /// What every part said (the note without tile lines).
    pub identity: String,
    pub film: Film,
    /// Which pixels a part has covered, top row first.
    covered: Vec<bool>,
    /// Which part set each covered pixel (an index into `names`), to name both sides of a
    /// disagreement.
    owner: Vec<u32>,
    names: Vec<String>,
    /// Each part's tile count, `None` for a crop.
    tile_counts: Vec<Option<u32>>,
}

impl Canvas {
    /// An empty canvas for the frame `first` belongs to; [`Canvas::add`] lays the parts.
    pub fn new(first: &Part) -> Canvas {
        let (width, height) = first.image;
        let pixels = width as usize * height as usize;
        Canvas {
            identity: first.identity.clone(),
            film: Film::new(width, height),
            covered: vec![false; pixels],
            owner: vec![0; pixels],
            names: Vec::new(),
            tile_counts: Vec::new(),
        }
    }

    /// Lays `part` on the canvas. Refuses a part of another render (naming the first line
    /// where the notes differ) and an overlap whose pixels are not bit for bit equal.
    pub fn add(&mut self, part: &Part) -> Result<(), String> {
        let first = self
            .names
            .first()
            .map_or(part.name.as_str(), String::as_str);
        if part.identity != self.identity {
            let cost = |identity: &str| CostMap::from_note(identity).ok().flatten().is_some();
            if cost(&part.identity) != cost(&self.identity) {
                let (cost, colour) = match cost(&part.identity) {
                    true => (part.name.as_str(), first),
                    false => (first, part.name.as_str()),
                };
                return Err(format!(
                    "{cost} is a part of a cost image (render --cost) and {colour} of a colour \
                     image: they are parts of different renders"
                ));
            }
            let (mine, theirs) = (self.identity.lines(), part.identity.lines());
            let blank = std::iter::repeat("");
            let (a, b) = mine
                .chain(blank.clone())
                .zip(theirs.chain(blank))
                .take_while(|(a, b)| !a.is_empty() || !b.is_empty())
                .find(|(a, b)| a != b)
                .unwrap_or(("", ""));
            return Err(format!(
                "{first} and {} are parts of different renders: '{a}' against '{b}'",
                part.name
            ));
        }
        let (width, height) = (self.film.width, self.film.height);
        if part.image != (width, height) {
            return Err(format!(
                "{first} and {} are parts of different images: {width}x{height} against {}x{}",
                part.name, part.image.0, part.image.1
            ));
        }
        let k = self.names.len() as u32;
        let r = part.region;
        for (i, &colour) in part.pixels.iter().enumerate() {
            let (x, y) = (r.x0 + i as u32 % r.width(), r.y0 + i as u32 / r.width());
            let at = (y * width + x) as usize;
            if !self.covered[at] {
                self.covered[at] = true;
                self.film.pixels[at] = colour;
                self.owner[at] = k;
                continue;
            }
            let before = self.film.pixels[at];
            if before.to_array().map(f32::to_bits) != colour.to_array().map(f32::to_bits) {
                return Err(format!(
                    "{} and {} overlap and disagree at pixel ({x}, {y}): {before} against {colour}",
                    self.names[self.owner[at] as usize], part.name
                ));
            }
        }
        self.names.push(part.name.clone());
        self.tile_counts.push(part.tile.map(|t| t.count));
        Ok(())
    }

    /// The tile count every part laid shares, if they are all tiles of one count.
    pub fn tile_count(&self) -> Option<u32> {
        let first = (*self.tile_counts.first()?)?;
        self.tile_counts
            .iter()
            .all(|&c| c == Some(first))
            .then_some(first)
    }

    /// The tiles of `count` with a pixel no part covers: the ones to render again.
    pub fn missing_tiles(&self, count: u32) -> Result<Vec<TileIndex>, String> {
        let (width, height) = (self.film.width, self.film.height);
        let mut missing = Vec::new();
        for index in 0..count {
            let r = Region::tile(index, count, width, height)?;
            let rows = (r.y0 as usize * width as usize)..(r.y1 as usize * width as usize);
            if self.covered[rows].contains(&false) {
                missing.push(TileIndex { index, count });
            }
        }
        Ok(missing)
    }

    /// The pixels no part covers: how many, and the rectangle around them.
    pub fn gaps(&self) -> Option<(u64, Region)> {
        let width = self.film.width;
        let mut count = 0;
        let mut bounds: Option<Region> = None;
        for (i, _) in self.covered.iter().enumerate().filter(|(_, &c)| !c) {
            let (x, y) = (i as u32 % width, i as u32 / width);
            count += 1;
            let b = bounds.get_or_insert(Region {
                x0: x,
                x1: x + 1,
                y0: y,
                y1: y + 1,
            });
            (b.x0, b.x1) = (b.x0.min(x), b.x1.max(x + 1));
            (b.y0, b.y1) = (b.y0.min(y), b.y1.max(y + 1));
        }
        bounds.map(|b| (count, b))
    }

    /// Where the merged film goes: the whole image, with the parts' note.
    pub fn placement(&self) -> Placement {
        Placement {
            note: Some(self.identity.clone()),
            ..Placement::whole(&self.film)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_of_known_strings() {
        assert_eq!(scene_hash(b""), 0xcbf29ce484222325);
        assert_eq!(scene_hash(b"a"), 0xaf63dc4c8601ec8c);
    }
}
