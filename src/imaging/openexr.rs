//! OpenEXR files: written as float32 RGB (or one channel of counts), ZIP-compressed in
//! increasing scan lines, so equal pixels give equal bytes, with a [`Placement`]: the
//! display window, the data window's corner and one `p3trace` note attribute (one,
//! because the `exr` crate writes its attributes in hash-map order); and read back.

use std::io::Cursor;

use glam::Vec3;

use super::format::{ImageOutput, WriteSeek};
use super::Film;
use crate::limits::check_image_size;

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

impl Film {
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

    pub(super) fn encode_exr(
        &self,
        out: &mut dyn WriteSeek,
        placement: &Placement,
    ) -> std::io::Result<()> {
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
