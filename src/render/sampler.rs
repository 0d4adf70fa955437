//! Deterministic random numbers: every value is a hash of (pixel, sample, dimension, seed),
//! so an image does not depend on the number of threads or the order of work.

use glam::Vec2;

/// What each random dimension of a sample is used for.
pub mod dim {
    pub const FILM_X: u32 = 0;
    pub const FILM_Y: u32 = 1;
    pub const LENS_U: u32 = 2;
    pub const LENS_V: u32 = 3;
}

/// The random numbers of one sample of one pixel.
#[derive(Clone, Copy, Debug)]
pub struct SampleRng {
    key: u64,
}

impl SampleRng {
    pub fn new(pixel: u32, sample: u32, seed: u64) -> Self {
        SampleRng {
            key: mix64(((pixel as u64) << 32 | sample as u64) ^ mix64(seed)),
        }
    }

    /// A number uniform in `[0, 1)` for dimension `dim`.
    pub fn uniform(&self, dim: u32) -> f32 {
        let bits = mix64(self.key ^ (dim as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        (bits >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// A point uniform in the unit disk, from dimensions `du` and `dv`.
    pub fn unit_disk(&self, du: u32, dv: u32) -> Vec2 {
        let r = self.uniform(du).sqrt();
        let (s, c) = (std::f32::consts::TAU * self.uniform(dv)).sin_cos();
        Vec2::new(r * c, r * s)
    }
}

/// The finaliser of SplitMix64: a bijection on u64 with full avalanche.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_inputs_same_numbers_and_seed_changes_them() {
        let a = SampleRng::new(17, 3, 0);
        assert_eq!(
            a.uniform(dim::FILM_X),
            SampleRng::new(17, 3, 0).uniform(dim::FILM_X)
        );
        assert_ne!(
            a.uniform(dim::FILM_X),
            SampleRng::new(17, 3, 1).uniform(dim::FILM_X)
        );
        assert_ne!(a.uniform(dim::FILM_X), a.uniform(dim::FILM_Y));
    }

    #[test]
    fn uniform_values_cover_the_unit_interval_evenly() {
        let mut buckets = [0u32; 10];
        for pixel in 0..10_000 {
            let x = SampleRng::new(pixel, 0, 42).uniform(dim::LENS_U);
            assert!((0.0..1.0).contains(&x));
            buckets[(x * 10.0) as usize] += 1;
        }
        for count in buckets {
            assert!((900..1100).contains(&count), "{buckets:?}");
        }
    }

    #[test]
    fn disk_points_stay_inside() {
        for sample in 0..1000 {
            let p = SampleRng::new(5, sample, 9).unit_disk(dim::LENS_U, dim::LENS_V);
            assert!(p.length() <= 1.0);
        }
    }
}
