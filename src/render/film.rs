//! The image being rendered and how it is written (P3F.md section 7).

use std::io::Write;
use std::path::Path;

use glam::Vec3;

/// Output formats, chosen by the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    Png,
    /// Binary PPM (P6).
    Ppm,
    /// Radiance HDR: linear floating-point colour.
    Hdr,
}

impl OutputFormat {
    pub fn from_path(path: &Path) -> Result<Self, String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(OutputFormat::Png),
            Some("ppm") => Ok(OutputFormat::Ppm),
            Some("hdr") => Ok(OutputFormat::Hdr),
            _ => Err(format!(
                "cannot tell the image format of '{}': use .png, .ppm or .hdr",
                path.display()
            )),
        }
    }
}

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

    /// Writes the image in the format of `path`'s extension, atomically
    /// ([`crate::output::write_atomically`]): a failure never leaves a truncated image.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let format = OutputFormat::from_path(path)?;
        crate::output::write_atomically(path, |out| self.encode(out, format))
    }

    fn encode(&self, out: &mut impl Write, format: OutputFormat) -> std::io::Result<()> {
        match format {
            OutputFormat::Png => image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new(out),
                &self.to_rgb8(),
                self.width,
                self.height,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(std::io::Error::other),
            OutputFormat::Ppm => {
                write!(out, "P6\n{} {}\n255\n", self.width, self.height)?;
                out.write_all(&self.to_rgb8())
            }
            OutputFormat::Hdr => {
                let pixels: Vec<image::Rgb<f32>> = self
                    .pixels
                    .iter()
                    .map(|p| image::Rgb(p.to_array()))
                    .collect();
                image::codecs::hdr::HdrEncoder::new(out)
                    .encode(&pixels, self.width as usize, self.height as usize)
                    .map_err(std::io::Error::other)
            }
        }
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

    #[test]
    fn format_from_extension() {
        assert_eq!(
            OutputFormat::from_path(Path::new("a.PNG")),
            Ok(OutputFormat::Png)
        );
        assert_eq!(
            OutputFormat::from_path(Path::new("a.ppm")),
            Ok(OutputFormat::Ppm)
        );
        assert_eq!(
            OutputFormat::from_path(Path::new("a.hdr")),
            Ok(OutputFormat::Hdr)
        );
        assert!(OutputFormat::from_path(Path::new("a.gif")).is_err());
        assert!(OutputFormat::from_path(Path::new("noext")).is_err());
    }
}
