//! How two images differ: PSNR, the largest channel difference, and the share of pixels
//! whose every channel is within a tolerance. Differences are in 8-bit levels (1/255).

use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub width: u32,
    pub height: u32,
    /// Peak signal-to-noise ratio in dB over all channels; infinite for equal images.
    pub psnr: f64,
    /// Largest difference of any channel of any pixel, in levels.
    pub max_difference: f32,
    /// Share of pixels (0 to 1) whose channels all differ by at most the tolerance.
    pub within_tolerance: f64,
}

/// Channel values of an image in levels (0 to 255 for 8-bit images), row by row.
pub struct Levels {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<f32>,
}

/// Reads a PNG, PPM, JPEG or HDR image.
pub fn load(path: &Path) -> Result<Levels, String> {
    let image = image::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let rgb = image.to_rgb32f();
    Ok(Levels {
        width: rgb.width(),
        height: rgb.height(),
        rgb: rgb.into_raw().into_iter().map(|x| x * 255.0).collect(),
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
    for (pa, pb) in a.rgb.chunks_exact(3).zip(b.rgb.chunks_exact(3)) {
        let mut pixel_max = 0.0f32;
        for (x, y) in pa.iter().zip(pb) {
            let d = (x - y).abs();
            squared_error += (d as f64) * (d as f64);
            pixel_max = pixel_max.max(d);
        }
        max_difference = max_difference.max(pixel_max);
        within += usize::from(pixel_max <= tolerance);
    }
    let pixels = (a.width as usize * a.height as usize).max(1);
    let mse = squared_error / (3 * pixels) as f64;
    Ok(Comparison {
        width: a.width,
        height: a.height,
        psnr: 10.0 * (255.0f64 * 255.0 / mse).log10(),
        max_difference,
        within_tolerance: within as f64 / pixels as f64,
    })
}

#[cfg(test)]
mod tests {
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

    #[test]
    fn size_mismatch_is_an_error() {
        assert!(compare(&image(vec![0.; 3]), &image(vec![0.; 6]), 0.0).is_err());
    }
}
