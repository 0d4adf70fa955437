//! Cost images (`render --cost`): each pixel's count of one traversal counter
//! (`accel::count`), summed over its samples' rays, instead of its colour. A cost image is
//! a [`Film`] whose three channels hold the count, so that regions of one merge as colour
//! ones do (`farm`); what it shows is a line of its note ([`CostMap::note_line`]), which
//! keeps parts of cost and colour images apart. It is written as a false-colour picture
//! with its scale beside it (PNG, PPM, JPEG: viridis, a perceptual map, from 0 at the
//! bottom of the bar to the top of the scale: [`false_colour::picture`]) or as the raw
//! counts (OpenEXR, one float channel `Y`).

use glam::Vec3;

use super::{RenderMode, RenderWork};
use crate::accel::count::{CostRays, Counter};
use crate::imaging::false_colour::{self, Scale};
use crate::imaging::format::{ImageOutput, OutputFormat};
use crate::imaging::openexr::Placement;
use crate::imaging::Film;
use crate::simd::PACKET;

/// What a cost image shows: one counter, over the rays `rays` says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CostMap {
    pub counter: Counter,
    pub rays: CostRays,
}

/// The key of the note line that says a render is a cost image.
const NOTE_KEY: &str = "cost: ";

impl CostMap {
    /// The line of the note of a cost image made with the structure `structure` in ray
    /// mode `mode` and, for packets, the build's packet width, which change its counts
    /// (not its colours): `cost: prims per pixel, all rays (bvh sah, stream mode, packets
    /// of 8)`.
    pub fn note_line(&self, structure: &str, mode: RenderMode) -> String {
        let rays = match self.rays {
            CostRays::All => "all rays",
            CostRays::Primary => "primary rays",
        };
        let mode = match mode {
            RenderMode::Scalar => "scalar mode".to_string(),
            RenderMode::Stream => format!("stream mode, packets of {PACKET}"),
        };
        format!(
            "{NOTE_KEY}{} per pixel, {rays} ({structure}, {mode})",
            self.counter.name()
        )
    }

    /// What the note `note` says its image shows, if it is a cost image's (`Err` for a
    /// cost line this program cannot read).
    pub fn from_note(note: &str) -> Result<Option<CostMap>, String> {
        let Some(line) = note.lines().find_map(|l| l.strip_prefix(NOTE_KEY)) else {
            return Ok(None);
        };
        let unknown = || format!("an unknown cost line '{NOTE_KEY}{line}'");
        let (shown, _made_by) = line.split_once(" (").ok_or_else(unknown)?;
        let (counter, rays) = shown.split_once(" per pixel, ").ok_or_else(unknown)?;
        let counter = Counter::from_name(counter).ok_or_else(unknown)?;
        let rays = match rays {
            "all rays" => CostRays::All,
            "primary rays" => CostRays::Primary,
            _ => return Err(unknown()),
        };
        Ok(Some(CostMap { counter, rays }))
    }

    /// The cost image of `work` (a render of a `width` x `height` region): each pixel's
    /// count in all three channels.
    pub fn film(&self, work: &RenderWork, width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            pixels: work
                .pixels
                .iter()
                .map(|work| Vec3::splat(work.of(self.rays).get(self.counter) as f32))
                .collect(),
        }
    }
}

/// Writes the cost image `film` as `output` says: PNG, PPM and JPEG as the picture
/// ([`false_colour::picture`], on `scale`), EXR as the raw counts with `placement`. HDR is refused: a
/// cost image is a picture or counts.
pub fn write(
    film: &Film,
    output: &ImageOutput,
    placement: &Placement,
    map: &CostMap,
    scale: Scale,
) -> Result<(), String> {
    match output.format {
        OutputFormat::Exr => film.write_counts(output, placement),
        OutputFormat::Hdr => Err(refuse_hdr(output)),
        OutputFormat::Png | OutputFormat::Ppm | OutputFormat::Jpeg => {
            let picture = false_colour::picture(film, map.counter.name(), scale);
            picture.write_placed(output, &Placement::whole(&picture))
        }
    }
}

/// Why a cost image is not written as `output`, an HDR image.
pub fn refuse_hdr(output: &ImageOutput) -> String {
    format!(
        "a cost image cannot be written as HDR ({}): use .exr for the counts or .png for a picture",
        output.name()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::font::glyph;

    #[test]
    fn a_note_line_reads_back() {
        for counter in Counter::ALL {
            for rays in [CostRays::All, CostRays::Primary] {
                let map = CostMap { counter, rays };
                let line = map.note_line("bvh sah", RenderMode::Scalar);
                assert!(line.ends_with("(bvh sah, scalar mode)"), "{line}");
                let note = format!("p3trace\nscene: x\n{line}\ntile: 0/2");
                assert_eq!(CostMap::from_note(&note), Ok(Some(map)));
            }
        }
        assert_eq!(CostMap::from_note("p3trace\nskybox: no"), Ok(None));
        assert!(CostMap::from_note("cost: rays per pixel, all rays (grid, stream mode)").is_err());
    }

    /// A picture's title is its counter's name in capitals, drawn in the font.
    #[test]
    fn the_counters_names_are_in_the_font() {
        for c in Counter::ALL {
            let title = c.name().to_ascii_uppercase();
            assert!(title.chars().all(|c| glyph(c).is_some()), "{title}");
        }
    }
}
