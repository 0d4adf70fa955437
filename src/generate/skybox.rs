//! A procedural skybox for the project's scenes: a sky gradient from a pale horizon to a
//! deep zenith, a small sun with a glow, and a darker sea below the horizon, written as
//! the six faces that `env` reads (P3F.md section 10).
//!
//! The faces come from the renderer's own definitions, so that they read back as the sky
//! they were made from: each texel's direction is `render::skybox::Face::direction` (the
//! lookup's mapping run backwards), and its bytes come from `imaging::to_byte`, the
//! conversion every rendered image goes through. `generate` sits above `render`, so this
//! is no cycle.

use std::path::Path;

use glam::Vec3;
use image::RgbImage;

use crate::imaging::to_byte;
use crate::render::skybox::Face;

/// Which world axis points up: the course's scenes use Z (balls, mount) or Y.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Up {
    Y,
    Z,
}

impl Up {
    /// `(up, east, north)` for this up axis; the sun's position is given in this frame.
    fn frame(self) -> (Vec3, Vec3, Vec3) {
        match self {
            Up::Y => (Vec3::Y, Vec3::X, Vec3::Z),
            Up::Z => (Vec3::Z, Vec3::X, Vec3::Y),
        }
    }
}

const ZENITH: Vec3 = Vec3::new(0.16, 0.36, 0.78);
const HORIZON: Vec3 = Vec3::new(0.82, 0.88, 0.95);
/// Below the horizon a grey-blue sea, so that brown and yellow floors stand out on it.
const GROUND_NEAR: Vec3 = Vec3::new(0.52, 0.58, 0.64);
const GROUND_FAR: Vec3 = Vec3::new(0.2, 0.26, 0.34);
const SUN: Vec3 = Vec3::new(1.0, 0.95, 0.82);
/// The sun's elevation and azimuth (from east towards north), in degrees.
const SUN_ELEVATION: f32 = 35.0;
const SUN_AZIMUTH: f32 = 40.0;

/// The colour of the sky in direction `d` (any length).
pub fn sky_colour(d: Vec3, up: Up) -> Vec3 {
    let d = d.normalize();
    let (up_axis, east, north) = up.frame();
    let e = d.dot(up_axis);
    if e < 0.0 {
        return GROUND_NEAR.lerp(GROUND_FAR, (-e).sqrt());
    }
    let (sin_el, cos_el) = SUN_ELEVATION.to_radians().sin_cos();
    let (sin_az, cos_az) = SUN_AZIMUTH.to_radians().sin_cos();
    let sun = up_axis * sin_el + (east * cos_az + north * sin_az) * cos_el;
    let closeness = d.dot(sun).max(0.0);
    let sky = HORIZON.lerp(ZENITH, e.sqrt());
    let glow = 0.25 * closeness.powi(16) + closeness.powi(2000);
    (sky + SUN * glow).min(Vec3::ONE)
}

/// One face of `size` x `size` texels, top row first as image files store them.
pub fn face_image(face: Face, size: u32, up: Up) -> RgbImage {
    let size = size.max(2);
    let to_unit = |i: u32| 2.0 * i as f32 / (size - 1) as f32 - 1.0;
    RgbImage::from_fn(size, size, |column, row| {
        // The lookup reads t = 0 from the bottom row.
        let d = face.direction(to_unit(column), to_unit(size - 1 - row));
        image::Rgb(sky_colour(d, up).to_array().map(to_byte))
    })
}

/// Writes the six faces as PNG files into `dir`, creating it if needed.
pub fn write_skybox(dir: &Path, size: u32, up: Up) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    for face in Face::ALL {
        let image = face_image(face, size, up);
        let path = dir.join(format!("{}.png", face.name()));
        crate::output::write_atomically(&path, |out| {
            image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new_with_quality(
                    out,
                    image::codecs::png::CompressionType::Best,
                    image::codecs::png::FilterType::Adaptive,
                ),
                image.as_raw(),
                size,
                size,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(std::io::Error::other)
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_is_brighter_than_ground_and_bluer_upwards() {
        for up in [Up::Y, Up::Z] {
            let (axis, east, _) = up.frame();
            let zenith = sky_colour(axis, up);
            let horizon = sky_colour(east + 0.01 * axis, up);
            let ground = sky_colour(-axis, up);
            assert!(zenith.z > zenith.x && zenith.x < horizon.x);
            assert!(ground.element_sum() < horizon.element_sum());
        }
    }
}
