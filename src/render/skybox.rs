//! The cube-map skybox of `env DIR` (P3F.md section 10): six faces, nearest texel.
//!
//! A JPEG face's data is checked as it is decoded ([`jpeg_scan`]): a damaged one (cut
//! short, or a copy whose bytes a line-ending conversion changed, as some course
//! repositories' faces are) decodes in silence to bands of pink and purple. It is drawn
//! as it decodes, and [`Skybox::damaged`] names it.

use std::path::{Path, PathBuf};

use glam::Vec3;
use rayon::prelude::*;

use crate::imaging::jpeg_scan;

/// Face files in the order of [`Face`].
pub const FACE_NAMES: [&str; 6] = ["right", "left", "top", "bottom", "front", "back"];

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Face {
    #[default]
    Right = 0,
    Left = 1,
    Top = 2,
    Bottom = 3,
    Front = 4,
    Back = 5,
}

#[derive(Clone, Debug)]
struct FaceImage {
    width: u32,
    height: u32,
    /// RGB bytes, top row first (as stored in the file).
    rgb: Vec<u8>,
}

#[derive(Clone, Debug)]
pub struct Skybox {
    faces: Vec<FaceImage>,
    /// A line per damaged face: its path and what the strict decoder found.
    damaged: Vec<String>,
}

/// A skybox's six face files, read and checked but not decoded: what `info` says of a
/// skybox, and what [`Skybox::load`] decodes.
pub struct FaceFiles {
    /// In the order of [`Face`].
    files: Vec<FaceFile>,
    damaged: Vec<String>,
}

struct FaceFile {
    path: PathBuf,
    bytes: Vec<u8>,
}

/// The first failure of `results` in their order (rayon's `collect` into a `Result`
/// gives any one), or every value.
fn in_order<T>(results: Vec<Result<T, String>>) -> Result<Vec<T>, String> {
    results.into_iter().collect()
}

impl FaceFiles {
    /// Reads `DIR/{right,left,top,bottom,front,back}.jpg` (or `.png`) and checks each JPEG
    /// face's data, the faces on rayon's threads. Of several failures, the first face's is
    /// reported.
    pub fn read(dir: &Path) -> Result<FaceFiles, String> {
        let files = in_order(
            FACE_NAMES
                .par_iter()
                .map(|name| {
                    let path = ["jpg", "jpeg", "png"]
                        .iter()
                        .map(|ext| dir.join(format!("{name}.{ext}")))
                        .find(|p| p.is_file())
                        .ok_or_else(|| {
                            format!("no {name}.jpg or {name}.png in {}", dir.display())
                        })?;
                    let bytes = std::fs::read(&path)
                        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                    Ok(FaceFile { path, bytes })
                })
                .collect(),
        )?;
        let damaged = files
            .par_iter()
            .filter_map(|f| damage(&f.bytes).map(|e| format!("{} ({e})", f.path.display())))
            .collect();
        Ok(FaceFiles { files, damaged })
    }

    /// The faces that decode only forgivingly, a line each: the path and, in brackets,
    /// the damage.
    pub fn damaged(&self) -> &[String] {
        &self.damaged
    }
}

impl Skybox {
    /// Loads the faces [`FaceFiles::read`] reads and decodes them on rayon's threads: the
    /// course's six 2048 x 2048 faces take about as long to decode as the dragon takes to
    /// render at one sample a pixel. Of several failures, the first face's is reported.
    pub fn load(dir: &Path) -> Result<Skybox, String> {
        let FaceFiles { files, damaged } = FaceFiles::read(dir)?;
        let faces = in_order(
            files
                .par_iter()
                .map(|FaceFile { path, bytes }| {
                    let image = image::load_from_memory(bytes)
                        .map_err(|e| format!("cannot read {}: {e}", path.display()))?
                        .into_rgb8();
                    if image.width() == 0 || image.height() == 0 {
                        return Err(format!("{} is empty", path.display()));
                    }
                    Ok(FaceImage {
                        width: image.width(),
                        height: image.height(),
                        rgb: image.into_raw(),
                    })
                })
                .collect(),
        )?;
        Ok(Skybox { faces, damaged })
    }

    /// The faces that decoded only forgivingly, a line each: the path and, in brackets,
    /// the damage.
    pub fn damaged(&self) -> &[String] {
        &self.damaged
    }

    /// The colour seen in direction `d` (need not be unit length).
    pub fn lookup(&self, d: Vec3) -> Vec3 {
        self.colour(self.texel(d))
    }

    /// The texel seen in direction `d` (need not be unit length), as [`Skybox::lookup`]
    /// finds it.
    pub fn texel(&self, d: Vec3) -> Texel {
        let (face, sc, tc, m) = face_coordinates(d);
        let image = &self.faces[face as usize];
        let s = (sc / m + 1.0) / 2.0;
        let t = (tc / m + 1.0) / 2.0;
        let column = nearest(s, image.width);
        let row_from_bottom = nearest(t, image.height);
        let row = (image.height - 1 - row_from_bottom) as usize;
        Texel {
            face,
            at: 3 * (row * image.width as usize + column as usize),
        }
    }

    /// Asks the cache for `texel`'s bytes, to be read soon ([`Skybox::colour`]).
    pub fn prefetch(&self, texel: Texel) {
        let rgb = &self.faces[texel.face as usize].rgb;
        // Its first and last byte, which may lie on two lines.
        crate::simd::prefetch(&rgb[texel.at]);
        crate::simd::prefetch(&rgb[texel.at + 2]);
    }

    /// The colour of `texel`.
    pub fn colour(&self, texel: Texel) -> Vec3 {
        let (rgb, i) = (&self.faces[texel.face as usize].rgb, texel.at);
        Vec3::new(rgb[i] as f32, rgb[i + 1] as f32, rgb[i + 2] as f32) / 255.99
    }
}

/// A texel of a skybox: its face, and the place of its first byte there.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Texel {
    face: Face,
    at: usize,
}

/// Why a face's bytes are damaged, for a JPEG whose data [`jpeg_scan`] finds so.
fn damage(bytes: &[u8]) -> Option<String> {
    match image::guess_format(bytes) {
        Ok(image::ImageFormat::Jpeg) => jpeg_scan::damage(bytes),
        _ => None,
    }
}

/// What `render` and `info` say of a damaged face, a line of [`FaceFiles::damaged`].
pub fn damage_warning(face: &str) -> String {
    format!(
        "damaged skybox face {face}: it is drawn as far as it decodes (a copy whose line \
         endings were converted has lost bytes)"
    )
}

/// What `render` and `info` say of a skybox that does not load, and why.
pub fn not_loaded_warning(why: &str) -> String {
    format!("skybox not loaded ({why}); the background colour is used instead")
}

/// Index of the texel nearest to `s` in `[0, 1]` along a side of `size` texels.
fn nearest(s: f32, size: u32) -> u32 {
    let x = ((size - 1) as f32 * s).round();
    (x.max(0.0) as u32).min(size - 1)
}

/// The face a direction falls on, its `(sc, tc)` and the magnitude of its largest component
/// (the table of P3F.md section 10: between x and y a tie goes to y, z only wins strictly).
fn face_coordinates(d: Vec3) -> (Face, f32, f32, f32) {
    let a = d.abs();
    if a.z > a.x && a.z > a.y {
        if d.z > 0.0 {
            (Face::Front, -d.x, d.y, a.z)
        } else {
            (Face::Back, d.x, d.y, a.z)
        }
    } else if a.y >= a.x {
        if d.y > 0.0 {
            (Face::Top, -d.x, -d.z, a.y)
        } else {
            (Face::Bottom, -d.x, d.z, a.y)
        }
    } else if d.x > 0.0 {
        (Face::Left, d.z, d.y, a.x)
    } else {
        (Face::Right, -d.z, d.y, a.x)
    }
}

impl Face {
    pub const ALL: [Face; 6] = [
        Face::Right,
        Face::Left,
        Face::Top,
        Face::Bottom,
        Face::Front,
        Face::Back,
    ];

    /// The file name of the face, without extension.
    pub fn name(self) -> &'static str {
        FACE_NAMES[self as usize]
    }

    /// The direction (largest component of magnitude 1) whose face coordinates are
    /// `(sc, tc)` in [-1, 1]: the inverse of the lookup's `face_coordinates`.
    pub fn direction(self, sc: f32, tc: f32) -> Vec3 {
        match self {
            Face::Left => Vec3::new(1.0, tc, sc),
            Face::Right => Vec3::new(-1.0, tc, -sc),
            Face::Top => Vec3::new(-sc, 1.0, -tc),
            Face::Bottom => Vec3::new(-sc, -1.0, tc),
            Face::Front => Vec3::new(-sc, tc, 1.0),
            Face::Back => Vec3::new(sc, tc, -1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_follow_the_table() {
        assert_eq!(face_coordinates(Vec3::X).0, Face::Left);
        assert_eq!(face_coordinates(Vec3::NEG_X).0, Face::Right);
        assert_eq!(face_coordinates(Vec3::Y).0, Face::Top);
        assert_eq!(face_coordinates(Vec3::NEG_Y).0, Face::Bottom);
        assert_eq!(face_coordinates(Vec3::Z).0, Face::Front);
        assert_eq!(face_coordinates(Vec3::NEG_Z).0, Face::Back);
        // Ties: y beats x; z must be strictly largest.
        assert_eq!(face_coordinates(Vec3::new(1., 1., 0.)).0, Face::Top);
        assert_eq!(face_coordinates(Vec3::new(1., 0., 1.)).0, Face::Left);
        assert_eq!(face_coordinates(Vec3::new(0., -1., 1.)).0, Face::Bottom);
    }

    #[test]
    fn face_direction_inverts_face_coordinates() {
        for face in Face::ALL {
            for (sc, tc) in [(0.0, 0.0), (0.5, -0.25), (-0.9, 0.9)] {
                let (f, s, t, m) = face_coordinates(face.direction(sc, tc));
                assert_eq!((f, s / m, t / m), (face, sc, tc));
            }
        }
    }

    /// A face as a JPEG, and the face damaged: cut short by 12 bytes.
    #[test]
    fn a_damaged_jpeg_face_says_so() {
        let face = image::RgbImage::from_fn(64, 48, |x, y| image::Rgb([x as u8, y as u8, 0]));
        let mut bytes = Vec::new();
        image::DynamicImage::from(face)
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Jpeg,
            )
            .unwrap();
        assert_eq!(damage(&bytes), None);
        let cut = &bytes[..bytes.len() - 12];
        assert_eq!(
            damage(cut).as_deref(),
            Some("premature end of data segment")
        );
    }

    #[test]
    fn lookup_reads_the_nearest_texel_bottom_row_first() {
        // A 2 x 2 face whose bottom-left texel is red and the rest black.
        let mut rgb = vec![0u8; 12];
        rgb[6] = 255; // row 1 (the bottom row), column 0
        let face = FaceImage {
            width: 2,
            height: 2,
            rgb,
        };
        let sky = Skybox {
            faces: vec![face; 6],
            damaged: Vec::new(),
        };
        // Back face: (sc, tc) = (x, y); s = t = 0 at the direction (-1, -1, -1).
        let c = sky.lookup(Vec3::new(-0.9, -0.9, -1.0));
        assert_eq!(c, Vec3::new(255.0 / 255.99, 0.0, 0.0));
        assert_eq!(sky.lookup(Vec3::new(0.9, 0.9, -1.0)), Vec3::ZERO);
    }
}
