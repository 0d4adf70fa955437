//! The image being rendered and how it is written (P3F.md section 7): PNG, PPM, JPEG,
//! Radiance HDR or OpenEXR, to a file through [`crate::output::write_atomically`] or to
//! standard output once whole ([`ImageOutput`]). EXR files hold float32 RGB,
//! ZIP-compressed in increasing scan lines, so equal pixels give equal bytes, with a
//! [`Placement`]: the display window, the data window's corner and one `p3trace` note
//! attribute (one, because the `exr` crate writes its attributes in hash-map order).

use std::io::{Cursor, Seek, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::limits::check_image_size;

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
    fn write(
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
trait WriteSeek: Write + Seek {}

impl<T: Write + Seek> WriteSeek for T {}

/// Linear RGB pixels, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// The name of the EXR header attribute that says what render made the pixels.
pub const EXR_NOTE: &str = "p3trace";

/// Where a film lies in the image it is part of, and what an EXR file says of the render
/// that made it. PNG, PPM and HDR files hold the film's pixels alone.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// The whole image's width and height: the EXR display window.
    pub image: (u32, u32),
    /// The film's top-left pixel in the image: the corner of the EXR data window.
    pub origin: (u32, u32),
    /// The text of the [`EXR_NOTE`] attribute, if any.
    pub note: Option<String>,
}

impl Placement {
    /// A film that is the whole image, with no note.
    pub fn whole(film: &Film) -> Self {
        Placement {
            image: (film.width, film.height),
            origin: (0, 0),
            note: None,
        }
    }
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

    /// Reads the first layer of an OpenEXR file: its R, G and B channels, of any sample
    /// type, as linear floats; the data window alone, as a region's PNG holds it. The
    /// header's size is checked ([`check_image_size`]) before any pixel is read.
    pub fn read_exr(bytes: &[u8]) -> Result<Film, String> {
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
            .map_err(|e| format!("not a readable OpenEXR file ({e})"))?;
        let size = meta
            .headers
            .first()
            .ok_or("an OpenEXR file without a layer")?
            .layer_size;
        let side = |n: usize| u32::try_from(n).ok().filter(|&n| n > 0);
        let (Some(width), Some(height)) = (side(size.x()), side(size.y())) else {
            return Err("an empty data window".into());
        };
        check_image_size(width, height)?;
        let pixels = read_exr_pixels(bytes, width, height)?;
        Ok(Film {
            width,
            height,
            pixels,
        })
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

    fn encode_exr(&self, out: &mut dyn WriteSeek, placement: &Placement) -> std::io::Result<()> {
        use exr::prelude::{Encoding, Image, Layer, SpecificChannels, Vec2, WritableImage};
        let (attributes, display) = exr_layout(placement)?;
        let width = self.width as usize;
        let pixels = SpecificChannels::rgb(|at: Vec2<usize>| {
            let p = self.pixels[at.y() * width + at.x()];
            (p.x, p.y, p.z)
        });
        // Lossless, scan lines in increasing order: the same pixels give the same bytes.
        let size = (width, self.height as usize);
        let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, pixels);
        let image = Image::new(display, layer);
        image
            .write()
            .to_buffered(out)
            .map_err(std::io::Error::other)
    }

    /// Writes the film's first channel as an OpenEXR file of one 32-bit float channel,
    /// [`COUNT_CHANNEL`], with `placement` as [`Film::write_placed`] writes an EXR file:
    /// the raw counts of a cost image (`render::cost`).
    pub fn write_counts(&self, output: &ImageOutput, placement: &Placement) -> Result<(), String> {
        use exr::prelude::{Encoding, Image, Layer, SpecificChannels, Vec2, WritableImage};
        output.write(|out| {
            let (attributes, display) = exr_layout(placement)?;
            let width = self.width as usize;
            let counts = SpecificChannels::build()
                .with_channel(COUNT_CHANNEL)
                .with_pixel_fn(|at: Vec2<usize>| (self.pixels[at.y() * width + at.x()].x,));
            let size = (width, self.height as usize);
            let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, counts);
            let image = Image::new(display, layer);
            image
                .write()
                .to_buffered(out)
                .map_err(std::io::Error::other)
        })
    }
}

/// An EXR layer's attributes and the image's for `placement`: the data window's corner,
/// the display window, and the note.
fn exr_layout(
    placement: &Placement,
) -> std::io::Result<(exr::prelude::LayerAttributes, exr::prelude::ImageAttributes)> {
    use exr::meta::attribute::{AttributeValue, IntegerBounds, Text};
    use exr::prelude::{ImageAttributes, LayerAttributes, Vec2};
    let side = |n: u32| i32::try_from(n).map_err(std::io::Error::other);
    let mut layer = LayerAttributes {
        layer_position: Vec2(side(placement.origin.0)?, side(placement.origin.1)?),
        ..LayerAttributes::default()
    };
    // One attribute only: the crate keeps attributes in a hash map, so that two would be
    // written in an order that changes from run to run, and so would the file's bytes.
    if let Some(note) = &placement.note {
        layer.other.insert(
            Text::from(EXR_NOTE),
            AttributeValue::Text(Text::from_slice_unchecked(note.as_bytes())),
        );
    }
    let display = IntegerBounds::new(
        (0, 0),
        (placement.image.0 as usize, placement.image.1 as usize),
    );
    Ok((layer, ImageAttributes::new(display)))
}

/// The one channel of an EXR file of counts ([`Film::write_counts`]).
pub const COUNT_CHANNEL: &str = "Y";

/// The R, G and B pixels of the first layer of the OpenEXR file `bytes` that has them,
/// top row first, which must fill a `width` x `height` data window.
pub fn read_exr_pixels(bytes: &[u8], width: u32, height: u32) -> Result<Vec<Vec3>, String> {
    use exr::prelude::{ReadChannels, ReadLayers, ReadSpecificChannel};
    let row = width as usize;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required("R")
        .required("G")
        .required("B")
        .collect_pixels(
            move |size, _| vec![Vec3::ZERO; size.width() * size.height()],
            move |pixels: &mut Vec<Vec3>, at, (r, g, b): (f32, f32, f32)| {
                if let Some(p) = pixels.get_mut(at.y() * row + at.x()) {
                    *p = Vec3::new(r, g, b);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| format!("unreadable pixels ({e})"))?;
    filled(image.layer_data.channel_data.pixels, width, height)
}

/// The counts of an EXR file of counts ([`Film::write_counts`]) as pixels whose three
/// channels hold them, top row first, which must fill a `width` x `height` data window.
pub fn read_exr_counts(bytes: &[u8], width: u32, height: u32) -> Result<Vec<Vec3>, String> {
    use exr::prelude::{ReadChannels, ReadLayers, ReadSpecificChannel};
    let row = width as usize;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required(COUNT_CHANNEL)
        .collect_pixels(
            move |size, _| vec![Vec3::ZERO; size.width() * size.height()],
            move |pixels: &mut Vec<Vec3>, at, (count,): (f32,)| {
                if let Some(p) = pixels.get_mut(at.y() * row + at.x()) {
                    *p = Vec3::splat(count);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| format!("unreadable counts ({e})"))?;
    filled(image.layer_data.channel_data.pixels, width, height)
}

/// `pixels`, if they fill a `width` x `height` window.
fn filled(pixels: Vec<Vec3>, width: u32, height: u32) -> Result<Vec<Vec3>, String> {
    if pixels.len() as u64 != u64::from(width) * u64::from(height) {
        return Err("its pixels do not fill its data window".into());
    }
    Ok(pixels)
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
