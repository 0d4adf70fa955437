//! Deterministic random numbers: every value is a hash of (pixel, sample, dimension, seed),
//! so an image does not depend on the number of threads or the order of work. A ray
//! carries its numbers, and its primary sample's cell, as a [`Sample`]; a reflected or
//! transmitted ray derives its own from its parent's ([`Sample::spawn`]).
//!
//! A pixel's samples lie on a [`SampleGrid`]: one through the centre (`--spp 1`, a file's
//! `spp 0`), the k x k jittered grid of a file's `spp k` (P3F.md 6.1), or for `--spp N`
//! the squarest a x b grid of N cells ([`SampleGrid::with_cells`]). Lights with an area
//! are sampled over the same a x b cells.

use glam::{Vec2, Vec3};

/// What each random dimension of a sample is used for.
pub mod dim {
    pub const FILM_X: u32 = 0;
    pub const FILM_Y: u32 = 1;
    pub const LENS_U: u32 = 2;
    pub const LENS_V: u32 = 3;
    /// The shutter time of a primary sample (motion blur).
    pub const TIME: u32 = 4;
    /// The point of the unit ball that tilts a fuzzy reflection.
    pub const FUZZ: [u32; 3] = [5, 6, 7];
    /// The jitter of the point of soft light `i` in its cell: dimensions `LIGHT + 2 i`
    /// and `LIGHT + 2 i + 1`.
    pub const LIGHT: u32 = 8;
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

    /// The numbers of a ray spawned at a hit (`branch` tells the reflected ray from the
    /// transmitted one): independent of this ray's and of every other branch's.
    pub fn spawn(&self, branch: u32) -> Self {
        SampleRng {
            key: mix64(self.key ^ u64::from(branch + 1).wrapping_mul(0xD6E8_FEB8_6659_FD93)),
        }
    }

    /// A point uniform in the unit ball, from the three dimensions `dims`: a uniform
    /// direction (z and azimuth) at a radius whose cube is uniform.
    pub fn unit_ball(&self, dims: [u32; 3]) -> Vec3 {
        let z = 1.0 - 2.0 * self.uniform(dims[0]);
        let (s, c) = (std::f32::consts::TAU * self.uniform(dims[1])).sin_cos();
        let ring = (1.0 - z * z).max(0.0).sqrt();
        let r = self.uniform(dims[2]).cbrt();
        Vec3::new(r * ring * c, r * ring * s, r * z)
    }

    /// A point uniform in the unit disk, from dimensions `du` and `dv`.
    pub fn unit_disk(&self, du: u32, dv: u32) -> Vec2 {
        let r = self.uniform(du).sqrt();
        let (s, c) = (std::f32::consts::TAU * self.uniform(dv)).sin_cos();
        Vec2::new(r * c, r * s)
    }
}

/// A grid of `columns` x `rows` cells over a pixel (one jittered sample in each) or
/// over a light (one point in each).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleGrid {
    pub columns: u32,
    pub rows: u32,
}

impl SampleGrid {
    /// The k x k grid of the file's `spp k` (P3F.md 6.1).
    pub const fn square(k: u32) -> Self {
        SampleGrid {
            columns: k,
            rows: k,
        }
    }

    /// `n` cells as an a x b grid with a >= b as close as possible: b is the largest
    /// divisor of n not above its square root (8 is 4 x 2, 7 is 7 x 1, 16 is 4 x 4).
    pub fn with_cells(n: u32) -> Self {
        let n = n.max(1);
        let rows = (1..=n.isqrt())
            .rev()
            .find(|b| n.is_multiple_of(*b))
            .unwrap_or(1);
        SampleGrid {
            columns: n / rows,
            rows,
        }
    }

    pub fn cells(self) -> u32 {
        self.columns * self.rows
    }

    /// The cells `(p, q)` whose places in the grid's order (row by row: `q * columns + p`)
    /// are in `places`, in that order. It is called for every pixel: a cell follows the
    /// one before it, and only a start past the first cell costs a division.
    pub fn cells_in(self, places: std::ops::Range<u32>) -> impl Iterator<Item = (u32, u32)> {
        let columns = self.columns;
        let mut cell = match places.start {
            0 => (0, 0),
            k => (k % columns, k / columns),
        };
        places.map(move |_| {
            let this = cell;
            cell = if this.0 + 1 == columns {
                (0, this.1 + 1)
            } else {
                (this.0 + 1, this.1)
            };
            this
        })
    }
}

/// The random state of one primary sample and of the rays it spawns.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// This ray's random numbers.
    pub rng: SampleRng,
    /// The sample's cell `(p, q)` in the pixel's grid, and that grid.
    pub cell: [u32; 2],
    pub grid: SampleGrid,
}

impl Sample {
    /// The sample of the ray spawned along `branch` (0 reflected, 1 transmitted).
    pub fn spawn(&self, branch: u32) -> Sample {
        Sample {
            rng: self.rng.spawn(branch),
            ..*self
        }
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
    fn ball_points_stay_inside_and_fill_it_evenly() {
        // A uniform ball has 1/8 of its points within half its radius, and as many in
        // each half-space.
        let (mut inner, mut upper, n) = (0, 0, 20_000);
        for sample in 0..n {
            let q = SampleRng::new(3, sample, 1).unit_ball(dim::FUZZ);
            assert!(q.length() <= 1.0 + 1e-6, "{q}");
            inner += u32::from(q.length() < 0.5);
            upper += u32::from(q.y > 0.0);
        }
        assert!((2300..2700).contains(&inner), "{inner} of {n} within r/2");
        assert!((9700..10300).contains(&upper), "{upper} of {n} above y = 0");
    }

    #[test]
    fn spawned_rays_get_their_own_numbers() {
        let rng = SampleRng::new(17, 3, 0);
        let (reflected, transmitted) = (rng.spawn(0), rng.spawn(1));
        let x = |r: SampleRng| r.uniform(dim::FUZZ[0]);
        assert_ne!(x(rng), x(reflected));
        assert_ne!(x(reflected), x(transmitted));
        assert_eq!(x(reflected), x(rng.spawn(0)));
    }

    #[test]
    fn any_cell_count_becomes_the_squarest_grid() {
        let shape = |n| {
            let g = SampleGrid::with_cells(n);
            (g.columns, g.rows)
        };
        assert_eq!(shape(1), (1, 1));
        assert_eq!(shape(2), (2, 1));
        assert_eq!(shape(7), (7, 1));
        assert_eq!(shape(8), (4, 2));
        assert_eq!(shape(12), (4, 3));
        assert_eq!(shape(16), (4, 4));
        assert_eq!(shape(1 << 20), (1024, 1024));
        for n in 1..=2000 {
            let g = SampleGrid::with_cells(n);
            assert_eq!(g.cells(), n);
            assert!(g.columns >= g.rows);
            // No divisor of n lies strictly between the rows and the square root.
            assert!(
                (g.rows + 1..=n.isqrt()).all(|b| !n.is_multiple_of(b)),
                "{n}"
            );
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
