//! The output formats and their encoders (P3F.md section 7): PNG, PPM, JPEG, Radiance
//! HDR or OpenEXR ([`super::openexr`]), to a file through
//! [`crate::output::write_atomically`] or to standard output once whole ([`ImageOutput`]).

use std::io::{Cursor, Seek, Write};
use std::path::{Path, PathBuf};

use super::openexr::Placement;
use super::Film;

/// Output formats, chosen by the file extension or by name (`--format`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    Png,
    /// Binary PPM (P6).
    Ppm,
    /// JPEG, lossy, at a quality from 1 to 100 ([`ImageOutput::quality`]).
    Jpeg,
    /// Radiance HDR: linear floating-point colour.
    Hdr,
    /// OpenEXR: linear 32-bit float RGB, exact; a region keeps its place in the image.
    Exr,
}

/// The extensions of each format, the first the one p3trace gives its files.
const EXTENSIONS: [(OutputFormat, &[&str]); 5] = [
    (OutputFormat::Png, &["png"]),
    (OutputFormat::Ppm, &["ppm"]),
    (OutputFormat::Jpeg, &["jpg", "jpeg"]),
    (OutputFormat::Hdr, &["hdr"]),
    (OutputFormat::Exr, &["exr"]),
];

/// The JPEG quality when none is asked for: the `image` crate's and libjpeg's 75 shows
/// blocks around a render's sharp edges.
pub const DEFAULT_JPEG_QUALITY: u8 = 90;

impl OutputFormat {
    /// The format of `path`'s extension, whatever its case; an unknown one is refused
    /// with every extension known.
    pub fn from_path(path: &Path) -> Result<Self, String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        EXTENSIONS
            .iter()
            .find(|(_, names)| names.contains(&ext.as_str()))
            .map(|&(format, _)| format)
            .ok_or_else(|| {
                let all: Vec<String> = EXTENSIONS
                    .iter()
                    .flat_map(|(_, names)| names.iter().map(|n| format!(".{n}")))
                    .collect();
                let (last, others) = all.split_last().expect("formats are known");
                format!(
                    "cannot tell the image format of '{}': use {} or {last}",
                    path.display(),
                    others.join(", ")
                )
            })
    }

    /// The extension of the files p3trace writes in this format.
    pub fn extension(self) -> &'static str {
        let (_, names) = EXTENSIONS.iter().find(|(f, _)| *f == self).expect("known");
        names[0]
    }
}

/// Where an image goes and how it is encoded.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageOutput {
    /// The file, or `None` for standard output.
    pub path: Option<PathBuf>,
    pub format: OutputFormat,
    /// JPEG's quality, from 1 to 100; other formats have none.
    pub quality: u8,
}

impl ImageOutput {
    /// The file `path`, in the format of its extension.
    pub fn file(path: &Path) -> Result<Self, String> {
        Ok(ImageOutput {
            path: Some(path.to_path_buf()),
            format: OutputFormat::from_path(path)?,
            quality: DEFAULT_JPEG_QUALITY,
        })
    }

    /// What `-o TARGET --format FORMAT --quality N` ask for. `-` is standard output, as
    /// PNG unless `format` names another. A file takes its extension's format: `format`
    /// must agree with it, and names the format of a file whose extension names none.
    /// `quality` is refused for any format but JPEG.
    pub fn new(
        target: &Path,
        format: Option<OutputFormat>,
        quality: Option<u8>,
    ) -> Result<Self, String> {
        let named = (target != Path::new("-")).then(|| OutputFormat::from_path(target));
        let format = match (named, format) {
            (None, asked) => asked.unwrap_or(OutputFormat::Png),
            (Some(Ok(named)), Some(asked)) if named != asked => {
                return Err(format!(
                    "--format {} and the extension of '{}' disagree: drop one of them",
                    asked.extension(),
                    target.display()
                ))
            }
            (Some(Ok(named)), _) => named,
            (Some(Err(_)), Some(asked)) => asked,
            (Some(Err(e)), None) => return Err(format!("{e}, or give --format")),
        };
        if quality.is_some() && format != OutputFormat::Jpeg {
            return Err(format!(
                "--quality is for JPEG output (.jpg, .jpeg or --format jpg), not {}",
                format.extension().to_uppercase()
            ));
        }
        Ok(ImageOutput {
            path: (target != Path::new("-")).then(|| target.to_path_buf()),
            format,
            quality: quality.unwrap_or(DEFAULT_JPEG_QUALITY),
        })
    }

    /// The file's name, or `standard output`.
    pub fn name(&self) -> String {
        self.path
            .as_ref()
            .map_or("standard output".into(), |p| p.display().to_string())
    }

    /// Refuses an image that the format cannot hold: JPEG's sides end at 65,535 pixels.
    pub fn check_size(&self, width: u32, height: u32) -> Result<(), String> {
        const JPEG_SIDE: u32 = u16::MAX as u32;
        if self.format == OutputFormat::Jpeg && width.max(height) > JPEG_SIDE {
            return Err(format!(
                "a JPEG image is at most {JPEG_SIDE} pixels a side, not {width}x{height}: \
                 write it as .png or .exr"
            ));
        }
        Ok(())
    }

    /// Writes what `encode` makes: to the file atomically, or to standard output once it
    /// is whole (an EXR encoder seeks; and a failure then writes nothing).
    pub(super) fn write(
        &self,
        encode: impl FnOnce(&mut dyn WriteSeek) -> std::io::Result<()>,
    ) -> Result<(), String> {
        match &self.path {
            Some(path) => crate::output::write_atomically(path, |out| encode(out)),
            None => {
                let mut bytes = Cursor::new(Vec::new());
                encode(&mut bytes)
                    .and_then(|()| {
                        let mut out = std::io::stdout().lock();
                        out.write_all(bytes.get_ref())?;
                        out.flush()
                    })
                    .map_err(|e| format!("cannot write the image to standard output: {e}"))
            }
        }
    }
}

/// What the encoders write to: a file or a buffer.
pub(super) trait WriteSeek: Write + Seek {}

impl<T: Write + Seek> WriteSeek for T {}

impl Film {
    /// Writes the image in the format of `path`'s extension, atomically
    /// ([`crate::output::write_atomically`]): a failure never leaves a truncated image.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        self.write_placed(&ImageOutput::file(path)?, &Placement::whole(self))
    }

    /// Writes the image as `output` says, as [`Film::write`] does a file; an EXR image
    /// also gets `placement`'s windows and note.
    pub fn write_placed(&self, output: &ImageOutput, placement: &Placement) -> Result<(), String> {
        output.write(|out| self.encode(out, output, placement))
    }

    fn encode(
        &self,
        out: &mut dyn WriteSeek,
        output: &ImageOutput,
        placement: &Placement,
    ) -> std::io::Result<()> {
        match output.format {
            OutputFormat::Png => self.write_rgb8(image::codecs::png::PngEncoder::new(out)),
            OutputFormat::Jpeg => self.write_rgb8(
                image::codecs::jpeg::JpegEncoder::new_with_quality(out, output.quality),
            ),
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
            OutputFormat::Exr => self.encode_exr(out, placement),
        }
    }

    /// The image's bytes ([`Film::to_rgb8`]) through `encoder`.
    fn write_rgb8(&self, encoder: impl image::ImageEncoder) -> std::io::Result<()> {
        let (width, height) = (self.width, self.height);
        let rgb = self.to_rgb8();
        (encoder.write_image(&rgb, width, height, image::ExtendedColorType::Rgb8))
            .map_err(std::io::Error::other)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(
            OutputFormat::from_path(Path::new("a.exr")),
            Ok(OutputFormat::Exr)
        );
        for name in ["a.jpg", "a.JPEG"] {
            assert_eq!(
                OutputFormat::from_path(Path::new(name)),
                Ok(OutputFormat::Jpeg)
            );
        }
        assert_eq!(
            OutputFormat::from_path(Path::new("a.gif")),
            Err(
                "cannot tell the image format of 'a.gif': use .png, .ppm, .jpg, .jpeg, .hdr \
                 or .exr"
                    .into()
            )
        );
        assert!(OutputFormat::from_path(Path::new("noext")).is_err());
    }

    /// `-o`, `--format` and `--quality` together: `-` is standard output, PNG by default;
    /// a file's extension and `--format` agree or are refused; JPEG alone has a quality.
    #[test]
    fn image_outputs() {
        let new =
            |target: &str, format, quality| ImageOutput::new(Path::new(target), format, quality);
        let output = |path: Option<&str>, format, quality| {
            let path = path.map(PathBuf::from);
            Ok(ImageOutput {
                path,
                format,
                quality,
            })
        };
        let default = DEFAULT_JPEG_QUALITY;
        assert_eq!(
            new("-", None, None),
            output(None, OutputFormat::Png, default)
        );
        let exr = Some(OutputFormat::Exr);
        assert_eq!(
            new("-", exr, None),
            output(None, OutputFormat::Exr, default)
        );
        let jpeg = Some(OutputFormat::Jpeg);
        assert_eq!(
            new("a.jpg", jpeg, Some(40)),
            output(Some("a.jpg"), OutputFormat::Jpeg, 40)
        );
        assert_eq!(
            new("-", jpeg, Some(40)),
            output(None, OutputFormat::Jpeg, 40)
        );
        assert_eq!(
            new("a.img", exr, None),
            output(Some("a.img"), OutputFormat::Exr, default)
        );
        let disagree = new("a.png", jpeg, None).unwrap_err();
        assert!(
            disagree.contains("--format jpg and the extension of 'a.png'"),
            "{disagree}"
        );
        let unknown = new("a.img", None, None).unwrap_err();
        assert!(
            unknown.ends_with(".hdr or .exr, or give --format"),
            "{unknown}"
        );
        let quality = new("a.png", None, Some(40)).unwrap_err();
        assert!(
            quality.starts_with("--quality is for JPEG output"),
            "{quality}"
        );
        assert!(new("-", None, Some(40)).is_err());
    }

    #[test]
    fn jpeg_sides_end_at_65535() {
        let jpeg = ImageOutput::new(Path::new("a.jpg"), None, None).unwrap();
        assert!(jpeg.check_size(65535, 4).is_ok());
        assert!(jpeg.check_size(4, 65536).is_err());
        let png = ImageOutput::new(Path::new("a.png"), None, None).unwrap();
        assert!(png.check_size(65536, 4).is_ok());
    }
}
