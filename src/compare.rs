//! How two images differ: PSNR, SSIM, the largest channel difference, the share of pixels
//! whose every channel is within a tolerance, and a heat map of where they differ.
//! Differences are in 8-bit levels (1/255).

use std::path::Path;

use crate::imaging::false_colour::heat;
use crate::imaging::Film;
use crate::plural::noun;

#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub width: u32,
    pub height: u32,
    /// Peak signal-to-noise ratio in dB over all channels; infinite for equal images.
    pub psnr: f64,
    /// Mean structural similarity (SSIM, Wang et al. 2004) of the three channels: 1 for
    /// equal images.
    pub ssim: f64,
    /// Largest difference of any channel of any pixel, in levels.
    pub max_difference: f32,
    /// Share of pixels (0 to 1) whose channels all differ by at most the tolerance.
    pub within_tolerance: f64,
    /// Each pixel's largest channel difference, in levels, row by row.
    pub pixel_differences: Vec<f32>,
}

/// Channel values of an image in levels (0 to 255 for 8-bit images), row by row.
pub struct Levels {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<f32>,
}

/// A difference in levels, with its noun: `1 level`, `2.5 levels`.
pub fn levels(n: f32) -> String {
    format!("{n} {}", noun(n.into(), "level", "levels"))
}

/// Reads a PNG, PPM, JPEG, HDR or OpenEXR image. An EXR file's linear floats become the
/// bytes a PNG of the same render holds (`floor(255.99 x)`, clamped: [`Film::to_rgb8`]),
/// so that a render compares equal to itself in either format; an HDR file's floats are
/// taken as they are, times 255.
pub fn load(path: &Path) -> Result<Levels, String> {
    let cannot = |e: &dyn std::fmt::Display| format!("cannot read {}: {e}", path.display());
    let exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if exr {
        let bytes = std::fs::read(path).map_err(|e| cannot(&e))?;
        let film = Film::read_exr(&bytes).map_err(|e| cannot(&e))?;
        return Ok(Levels {
            width: film.width,
            height: film.height,
            rgb: film.to_rgb8().into_iter().map(f32::from).collect(),
        });
    }
    let image = image::open(path).map_err(|e| cannot(&e))?;
    let rgb = image.to_rgb32f();
    Ok(Levels {
        width: rgb.width(),
        height: rgb.height(),
        rgb: rgb.into_raw().into_iter().map(|x| x * 255.0).collect(),
    })
}

/// How two cost images (`render --cost`) of one counter compare: their totals, means,
/// largest counts, the ratio of the second's total to the first's, and the share of
/// pixels where the second counts more.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostRatio {
    pub totals: [f64; 2],
    pub means: [f64; 2],
    pub largest: [f32; 2],
    /// The second's total over the first's (infinite where the first counts nothing).
    pub ratio: f64,
    /// The share of pixels (0 to 1) whose count is larger in the second.
    pub larger: f64,
}

/// Compares the cost images `a` and `b` (their counts in each pixel's first channel),
/// which must be of one size.
pub fn cost_ratio(a: &Film, b: &Film) -> Result<CostRatio, String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "the images differ in size: {}x{} and {}x{}",
            a.width, a.height, b.width, b.height
        ));
    }
    let total = |f: &Film| f.pixels.iter().map(|p| f64::from(p.x)).sum::<f64>();
    let largest = |f: &Film| f.pixels.iter().map(|p| p.x).fold(0.0, f32::max);
    let (ta, tb) = (total(a), total(b));
    let n = a.pixels.len().max(1) as f64;
    let larger = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(p, q)| q.x > p.x)
        .count();
    Ok(CostRatio {
        totals: [ta, tb],
        means: [ta / n, tb / n],
        largest: [largest(a), largest(b)],
        ratio: if ta > 0.0 { tb / ta } else { f64::INFINITY },
        larger: larger as f64 / n,
    })
}

/// Compares two images of the same size; `tolerance` is in levels.
pub fn compare(a: &Levels, b: &Levels, tolerance: f32) -> Result<Comparison, String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "the images differ in size: {}x{} and {}x{}",
            a.width, a.height, b.width, b.height
        ));
    }
    let mut squared_error = 0.0f64;
    let mut max_difference = 0.0f32;
    let mut within = 0usize;
    let mut pixel_differences = Vec::with_capacity(a.rgb.len() / 3);
    for (pa, pb) in a.rgb.chunks_exact(3).zip(b.rgb.chunks_exact(3)) {
        let mut pixel_max = 0.0f32;
        for (x, y) in pa.iter().zip(pb) {
            let d = (x - y).abs();
            squared_error += (d as f64) * (d as f64);
            pixel_max = pixel_max.max(d);
        }
        max_difference = max_difference.max(pixel_max);
        within += usize::from(pixel_max <= tolerance);
        pixel_differences.push(pixel_max);
    }
    let pixels = (a.width as usize * a.height as usize).max(1);
    let mse = squared_error / (3 * pixels) as f64;
    Ok(Comparison {
        width: a.width,
        height: a.height,
        psnr: 10.0 * (255.0f64 * 255.0 / mse).log10(),
        ssim: ssim(a, b),
        max_difference,
        within_tolerance: within as f64 / pixels as f64,
        pixel_differences,
    })
}

impl Comparison {
    /// A picture of where the images differ: each pixel's largest channel difference on
    /// the heat ramp, black where the images are equal and white at `full` levels (and
    /// beyond), by default the largest difference found ([`Comparison::heat_map_scale`]
    /// says it in words). A full scale below the largest difference shows differences of
    /// a level or two that the largest would leave near black.
    pub fn heat_map(&self, full: Option<f32>) -> Film {
        let full = full.unwrap_or(self.max_difference);
        let mut film = Film::new(self.width, self.height);
        for (pixel, &difference) in film.pixels.iter_mut().zip(&self.pixel_differences) {
            *pixel = heat(difference / full);
        }
        film
    }

    /// What the colours of [`Comparison::heat_map`]`(full)` mean, in levels.
    pub fn heat_map_scale(&self, full: Option<f32>) -> String {
        let ramp = "black 0 levels, then blue, red, yellow, white";
        match full {
            _ if !(self.max_difference > 0.0) => "all black: no pixel differs".to_string(),
            None => format!("{ramp} {}", levels(self.max_difference)),
            Some(full) => format!("{ramp} {} or more", levels(full)),
        }
    }
}

/// SSIM's stabilising constants (Wang et al. 2004): (K1 L)^2 and (K2 L)^2, with K1 = 0.01,
/// K2 = 0.03 and the range L = 255 levels.
const SSIM_C1: f64 = (0.01 * 255.0) * (0.01 * 255.0);
const SSIM_C2: f64 = (0.03 * 255.0) * (0.03 * 255.0);

/// SSIM's window: a Gaussian of standard deviation 1.5 over 11 x 11 pixels.
const SSIM_RADIUS: usize = 5;
const SSIM_SIGMA: f64 = 1.5;

/// The structural similarity of two images of the same size (Wang, Bovik, Sheikh and
/// Simoncelli 2004): each channel's SSIM map over Gaussian windows centred on every pixel,
/// averaged over the pixels and the three channels. 1 for equal images, lower as local
/// means, contrasts and structure part. A window reaching past the border keeps its taps
/// inside the image, reweighted to sum to 1, so that images smaller than the window have
/// an SSIM too; elsewhere it is the paper's window, and the map's mean over the pixels
/// five or more from the border agrees with scikit-image's `structural_similarity`
/// (`gaussian_weights`, `sigma=1.5`, `use_sample_covariance=False`, `data_range=255`).
fn ssim(a: &Levels, b: &Levels) -> f64 {
    let (width, height) = (a.width as usize, a.height as usize);
    let mut sum = 0.0;
    for channel in 0..3 {
        let plane = |image: &Levels| -> Vec<f64> {
            image.rgb[channel..]
                .iter()
                .step_by(3)
                .map(|&v| v.into())
                .collect()
        };
        let (x, y) = (plane(a), plane(b));
        let product =
            |p: &[f64], q: &[f64]| -> Vec<f64> { p.iter().zip(q).map(|(p, q)| p * q).collect() };
        let mean = |plane: &[f64]| window_means(plane, width, height);
        let (mean_x, mean_y) = (mean(&x), mean(&y));
        let mean_xx = mean(&product(&x, &x));
        let mean_yy = mean(&product(&y, &y));
        let mean_xy = mean(&product(&x, &y));
        for i in 0..x.len() {
            let (mx, my) = (mean_x[i], mean_y[i]);
            let variance_x = mean_xx[i] - mx * mx;
            let variance_y = mean_yy[i] - my * my;
            let covariance = mean_xy[i] - mx * my;
            sum += (2.0 * mx * my + SSIM_C1) * (2.0 * covariance + SSIM_C2)
                / ((mx * mx + my * my + SSIM_C1) * (variance_x + variance_y + SSIM_C2));
        }
    }
    sum / (3 * width * height) as f64
}

/// The Gaussian-weighted mean of `plane` in the window around each pixel. The window is
/// separable, and so is its cut at the border: a pass along the rows, one along the
/// columns, then a division by the weights of the taps that fell inside.
fn window_means(plane: &[f64], width: usize, height: usize) -> Vec<f64> {
    let taps: Vec<(isize, f64)> = (-(SSIM_RADIUS as isize)..=SSIM_RADIUS as isize)
        .map(|offset| {
            let d = offset as f64;
            (offset, (-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp())
        })
        .collect();
    let mut rows = vec![0.0; plane.len()];
    for (line, sums) in plane.chunks_exact(width).zip(rows.chunks_exact_mut(width)) {
        for &(offset, tap) in &taps {
            add_shifted(sums, line, tap, offset);
        }
    }
    // Moving the whole plane by whole rows moves each column along itself.
    let mut means = vec![0.0; plane.len()];
    for &(offset, tap) in &taps {
        add_shifted(&mut means, &rows, tap, offset * width as isize);
    }
    // The weights inside, along each axis: the same sums over a line of ones.
    let weights_inside = |len: usize| {
        let mut sums = vec![0.0; len];
        for &(offset, tap) in &taps {
            add_shifted(&mut sums, &vec![1.0; len], tap, offset);
        }
        sums
    };
    let (across, down) = (weights_inside(width), weights_inside(height));
    for (line, weight_down) in means.chunks_exact_mut(width).zip(down) {
        for (mean, weight_across) in line.iter_mut().zip(&across) {
            *mean /= weight_across * weight_down;
        }
    }
    means
}

/// Adds `tap` times the value `shift` places further on to each of `sums`, where there is
/// one.
fn add_shifted(sums: &mut [f64], values: &[f64], tap: f64, shift: isize) {
    let skip = shift.unsigned_abs().min(values.len());
    let kept = values.len() - skip;
    let (sums, values) = if shift >= 0 {
        (&mut sums[..kept], &values[skip..])
    } else {
        (&mut sums[skip..], &values[..kept])
    };
    for (sum, value) in sums.iter_mut().zip(values) {
        *sum += tap * value;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn image(rgb: Vec<f32>) -> Levels {
        Levels {
            width: rgb.len() as u32 / 3,
            height: 1,
            rgb,
        }
    }

    #[test]
    fn equal_images() {
        let a = image(vec![1., 2., 3., 4., 5., 6.]);
        let c = compare(&a, &a, 0.0).unwrap();
        assert_eq!(c.psnr, f64::INFINITY);
        assert_eq!(c.max_difference, 0.0);
        assert_eq!(c.within_tolerance, 1.0);
    }

    #[test]
    fn counts_pixels_within_tolerance() {
        let a = image(vec![0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0.]);
        let b = image(vec![1., 0., 0., 0., 3., 0., 0., 0., 0., 2., 2., 2.]);
        let c = compare(&a, &b, 2.0).unwrap();
        assert_eq!(c.max_difference, 3.0);
        assert_eq!(c.within_tolerance, 0.75);
        // MSE = (1 + 9 + 12) / 12.
        let expected = 10.0 * (255.0f64 * 255.0 / (22.0 / 12.0)).log10();
        assert!((c.psnr - expected).abs() < 1e-9);
    }

    /// A `width` x `height` image whose channels are `level(x, y, channel)`.
    fn image_of(width: u32, height: u32, level: impl Fn(u32, u32, u32) -> f32) -> Levels {
        let mut rgb = Vec::new();
        for y in 0..height {
            for x in 0..width {
                rgb.extend((0..3).map(|channel| level(x, y, channel)));
            }
        }
        Levels { width, height, rgb }
    }

    /// Levels that vary from pixel to pixel and channel to channel with no pattern.
    fn textured(x: u32, y: u32, channel: u32) -> f32 {
        ((x * 7919 + y * 104_729 + channel * 1_299_709) % 251) as f32
    }

    #[test]
    fn ssim_of_equal_images_is_one() {
        let a = image_of(13, 9, textured);
        assert_eq!(ssim(&a, &a), 1.0);
        assert_eq!(compare(&a, &a, 0.0).unwrap().ssim, 1.0);
    }

    #[test]
    fn ssim_of_a_constant_offset_is_the_luminance_term() {
        // Flat images have no contrast or structure: SSIM is (2 m n + C1) / (m^2 + n^2 + C1)
        // for means m and n, at every size, windows cut by the border or not.
        let expected =
            (2.0 * 100.0 * 110.0 + SSIM_C1) / (100.0f64.powi(2) + 110.0f64.powi(2) + SSIM_C1);
        for (width, height) in [(1, 1), (3, 2), (20, 13)] {
            let a = image_of(width, height, |_, _, _| 100.0);
            let b = image_of(width, height, |_, _, _| 110.0);
            let s = ssim(&a, &b);
            assert!(
                (s - expected).abs() < 1e-12,
                "{width}x{height}: {s} != {expected}"
            );
        }
    }

    #[test]
    fn ssim_is_symmetric_and_falls_with_noise() {
        let a = image_of(24, 16, |x, y, _| (8 * x + 4 * y) as f32);
        let noisy = |amount: f32| {
            image_of(24, 16, move |x, y, c| {
                (8 * x + 4 * y) as f32 + amount * (textured(x, y, c) - 125.0) / 125.0
            })
        };
        let (slightly, very) = (noisy(4.0), noisy(40.0));
        assert_eq!(ssim(&a, &very), ssim(&very, &a));
        let (s_slightly, s_very) = (ssim(&a, &slightly), ssim(&a, &very));
        assert!(1.0 > s_slightly && s_slightly > s_very && s_very > 0.0);
        // Inverting an image's contrast inverts its structure.
        let inverted = image_of(24, 16, |x, y, _| 255.0 - (8 * x + 4 * y) as f32);
        assert!(ssim(&a, &inverted) < 0.0);
    }

    #[test]
    fn heat_map_is_black_where_equal_and_white_at_the_largest_difference() {
        let a = image(vec![0.; 12]);
        let b = image(vec![0., 0., 0., 0., 0., 1., 0., 120., 0., 255., 0., 0.]);
        let c = compare(&a, &b, 0.0).unwrap();
        let map = c.heat_map(None);
        assert_eq!((map.width, map.height), (4, 1));
        let bytes = map.to_rgb8();
        assert_eq!(bytes[0..3], [0, 0, 0], "equal pixel");
        assert_ne!(bytes[3..6], [0, 0, 0], "one level of 255 still shows");
        assert_eq!(bytes[9..12], [255, 255, 255], "the largest difference");
        assert_eq!(
            c.heat_map_scale(None),
            "black 0 levels, then blue, red, yellow, white 255 levels"
        );

        let same = compare(&a, &a, 0.0).unwrap();
        for full in [None, Some(2.0)] {
            assert!(same.heat_map(full).pixels.iter().all(|p| *p == Vec3::ZERO));
            assert_eq!(same.heat_map_scale(full), "all black: no pixel differs");
        }
    }

    #[test]
    fn a_full_scale_shows_small_differences_and_saturates_larger_ones() {
        let a = image(vec![0.; 12]);
        let b = image(vec![0., 0., 0., 1., 0., 0., 0., 2., 0., 0., 0., 255.]);
        let c = compare(&a, &b, 0.0).unwrap();
        let bytes = c.heat_map(Some(2.0)).to_rgb8();
        assert_eq!(bytes[0..3], [0, 0, 0], "equal pixel");
        assert_eq!(bytes[3..6], [255, 0, 0], "half the scale is red");
        assert_eq!(bytes[6..9], [255, 255, 255], "the full scale is white");
        assert_eq!(bytes[9..12], [255, 255, 255], "beyond it, white too");
        assert_eq!(
            c.heat_map_scale(Some(2.0)),
            "black 0 levels, then blue, red, yellow, white 2 levels or more"
        );
        assert_eq!(
            c.heat_map_scale(Some(1.0)),
            "black 0 levels, then blue, red, yellow, white 1 level or more"
        );
    }

    #[test]
    fn cost_images_compare_by_their_totals() {
        let film = |counts: &[f32]| Film {
            width: counts.len() as u32,
            height: 1,
            pixels: counts.iter().map(|&c| Vec3::splat(c)).collect(),
        };
        let r = cost_ratio(&film(&[1.0, 2.0, 3.0, 2.0]), &film(&[2.0, 2.0, 9.0, 3.0])).unwrap();
        assert_eq!(r.totals, [8.0, 16.0]);
        assert_eq!(r.ratio, 2.0);
        assert_eq!(r.means, [2.0, 4.0]);
        assert_eq!(r.largest, [3.0, 9.0]);
        assert_eq!(r.larger, 0.75);
        assert!(cost_ratio(&film(&[1.0]), &film(&[1.0, 2.0])).is_err());
        assert_eq!(
            cost_ratio(&film(&[0.0]), &film(&[1.0])).unwrap().ratio,
            f64::INFINITY
        );
    }

    #[test]
    fn size_mismatch_is_an_error() {
        assert!(compare(&image(vec![0.; 3]), &image(vec![0.; 6]), 0.0).is_err());
    }
}
