//! Images as data and as files, below the renderer (this module imports no other but
//! [`crate::limits`] and [`crate::output`]): a [`Film`] of linear RGB pixels and
//! [`to_byte`], the course's rule for a channel's byte; the output formats and their
//! encoders ([`mod@format`], P3F.md section 7); OpenEXR files, written with their placement
//! in a larger image and read back ([`openexr`]); the check of a JPEG's data
//! ([`jpeg_scan`]); and counts or differences drawn in false colour ([`false_colour`]),
//! labelled in a bitmap [`font`].

pub mod false_colour;
pub mod font;
pub mod format;
pub mod jpeg_scan;
pub mod openexr;

use glam::Vec3;

/// Linear RGB pixels, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// A channel value as a byte: `min(255, floor(255.99 x))`, no gamma.
pub fn to_byte(x: f32) -> u8 {
    (x * 255.99).clamp(0.0, 255.0) as u8
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// Colour of pixel `(x, row)` with row 0 at the top.
    pub fn get(&self, x: u32, row: u32) -> Vec3 {
        self.pixels[(row * self.width + x) as usize]
    }

    pub fn to_rgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.to_array().map(to_byte))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_follow_the_course_rule() {
        assert_eq!(to_byte(0.0), 0);
        assert_eq!(to_byte(1.0), 255);
        assert_eq!(to_byte(2.0), 255);
        assert_eq!(to_byte(-1.0), 0);
        // mount_low's background: floor(255.99 * (0.078, 0.361, 0.753)) = (19, 92, 192).
        assert_eq!([0.078, 0.361, 0.753].map(to_byte), [19, 92, 192]);
    }
}
