//! The part of an image a render covers: the whole frame, or a rectangle of it for a
//! render farm (pbrt's `--cropwindow` and `--pixelbounds`, and `--tile I/N` for job
//! arrays). Coordinates are pixels with y from the top, as in pbrt and OpenEXR.

use crate::plural;

/// A rectangle of pixels `[x0, x1) x [y0, y1)`, rows counted from the top of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    pub x0: u32,
    pub x1: u32,
    pub y0: u32,
    pub y1: u32,
}

impl Region {
    /// The whole `width x height` image.
    pub fn full(width: u32, height: u32) -> Self {
        Region {
            x0: 0,
            x1: width,
            y0: 0,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    pub fn pixels(&self) -> u64 {
        u64::from(self.width()) * u64::from(self.height())
    }

    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// `--pixel-bounds x0,x1,y0,y1`: must be non-empty and inside the image.
    pub fn pixel_bounds(
        [x0, x1, y0, y1]: [u32; 4],
        width: u32,
        height: u32,
    ) -> Result<Self, String> {
        if x0 >= x1 || y0 >= y1 {
            return Err(format!(
                "--pixel-bounds {x0},{x1},{y0},{y1} is empty: it needs x0 < x1 and y0 < y1"
            ));
        }
        if x1 > width || y1 > height {
            return Err(format!(
                "--pixel-bounds {x0},{x1},{y0},{y1} reaches outside the {width}x{height} image"
            ));
        }
        Ok(Region { x0, x1, y0, y1 })
    }

    /// `--crop X0,X1,Y0,Y1`, fractions in [0, 1] with y from the top: the pixels from
    /// `ceil(X0 width)` to `ceil(X1 width)` (excluded), as pbrt's `--cropwindow`.
    pub fn crop([fx0, fx1, fy0, fy1]: [f64; 4], width: u32, height: u32) -> Result<Self, String> {
        if ![fx0, fx1, fy0, fy1].iter().all(|f| (0.0..=1.0).contains(f)) {
            return Err(format!(
                "--crop {fx0},{fx1},{fy0},{fy1}: the fractions lie between 0 and 1"
            ));
        }
        let at = |f: f64, side: u32| (f * f64::from(side)).ceil() as u32;
        let region = Region {
            x0: at(fx0, width),
            x1: at(fx1, width),
            y0: at(fy0, height),
            y1: at(fy1, height),
        };
        if region.x0 >= region.x1 || region.y0 >= region.y1 {
            return Err(format!(
                "--crop {fx0},{fx1},{fy0},{fy1} holds no pixel of the {width}x{height} image"
            ));
        }
        Ok(region)
    }

    /// `--tile I/N`: the I-th of N horizontal bands of rows (0-based, from the top), rows
    /// `floor(I H / N)` to `floor((I + 1) H / N)`, so that band heights differ by one row at
    /// most. Bands rather than blocks: every pixel of a row costs about the same setup,
    /// any N up to the height splits evenly, and a band is one EXR data window.
    pub fn tile(index: u32, count: u32, width: u32, height: u32) -> Result<Self, String> {
        if count == 0 || index >= count {
            return Err(format!(
                "--tile {index}/{count}: the tile I of N counts from 0 to N - 1"
            ));
        }
        if count > height {
            return Err(format!(
                "--tile {index}/{count}: the image has {}, so at most {}",
                plural::count(height.into(), "row", "rows"),
                plural::count(height.into(), "tile", "tiles")
            ));
        }
        let row = |i: u32| (u64::from(i) * u64::from(height) / u64::from(count)) as u32;
        Ok(Region {
            x0: 0,
            x1: width,
            y0: row(index),
            y1: row(index + 1),
        })
    }
}

/// Tile `I` of `N` as the command line writes it: `I/N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileIndex {
    pub index: u32,
    pub count: u32,
}

impl std::fmt::Display for TileIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for TileIndex {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let parsed = text
            .split_once('/')
            .and_then(|(i, n)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((index, count)) if index < count => Ok(TileIndex { index, count }),
            _ => Err(format!(
                "'{text}' is not a tile I/N with 0 <= I < N, such as 3/8"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_once_in_near_equal_bands() {
        for (height, count) in [(64, 64), (100, 7), (5, 2), (480, 8), (1, 1)] {
            let bands: Vec<Region> = (0..count)
                .map(|i| Region::tile(i, count, 10, height).unwrap())
                .collect();
            assert_eq!(bands[0].y0, 0);
            assert_eq!(bands.last().unwrap().y1, height);
            for pair in bands.windows(2) {
                assert_eq!(pair[0].y1, pair[1].y0);
            }
            let (lo, hi) = bands.iter().fold((u32::MAX, 0), |(lo, hi), b| {
                (lo.min(b.height()), hi.max(b.height()))
            });
            assert!(
                lo >= 1 && hi - lo <= 1,
                "{height} rows in {count}: {lo}..{hi}"
            );
        }
        assert!(Region::tile(8, 8, 10, 10).is_err());
        assert!(Region::tile(0, 11, 10, 10).is_err());
        assert!(Region::tile(0, 0, 10, 10).is_err());
    }

    #[test]
    fn crops_round_up_as_pbrt() {
        let r = Region::crop([0.0, 0.5, 0.25, 1.0], 101, 40).unwrap();
        assert_eq!(
            r,
            Region {
                x0: 0,
                x1: 51,
                y0: 10,
                y1: 40
            }
        );
        assert_eq!(
            Region::crop([0.0, 1.0, 0.0, 1.0], 7, 3).unwrap(),
            Region::full(7, 3)
        );
        assert!(Region::crop([0.5, 0.5, 0.0, 1.0], 10, 10).is_err());
        assert!(Region::crop([0.0, 0.01, 0.0, 1.0], 10, 10).is_ok());
        assert!(Region::crop([0.0, 1.5, 0.0, 1.0], 10, 10).is_err());
        assert!(Region::crop([f64::NAN, 1.0, 0.0, 1.0], 10, 10).is_err());
    }

    #[test]
    fn pixel_bounds_stay_inside() {
        assert!(Region::pixel_bounds([0, 10, 0, 10], 10, 10).is_ok());
        assert!(Region::pixel_bounds([0, 11, 0, 10], 10, 10).is_err());
        assert!(Region::pixel_bounds([3, 3, 0, 10], 10, 10).is_err());
    }

    #[test]
    fn tile_indices_parse() {
        assert_eq!("3/8".parse(), Ok(TileIndex { index: 3, count: 8 }));
        assert_eq!(TileIndex { index: 0, count: 1 }.to_string(), "0/1");
        for bad in ["8/8", "3", "a/8", "-1/8", "3/0", ""] {
            assert!(bad.parse::<TileIndex>().is_err(), "{bad}");
        }
    }
}
