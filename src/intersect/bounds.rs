//! Axis-aligned boxes: each kind's bounds, and the margin the grid and the BVHs grow
//! them by ([`trusted_box`], with its SIMD twin for eight boxes).

use glam::Vec3;

use super::BoxPack8;
use crate::simd::{F32x8, Mask8, Vec3x8};

/// The box `[min, max]`; empty when some `min` exceeds its `max` (or is NaN).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: the union with it changes nothing.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.cmple(self.max).all())
    }

    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    pub fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Surface area (0 for an empty box).
    pub fn area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// The box grown on every side by `margin`.
    pub fn padded(self, margin: f32) -> Aabb {
        Aabb {
            min: self.min - margin,
            max: self.max + margin,
        }
    }

    /// The box grown by a margin relative to its coordinates (`1e-6` of the largest
    /// magnitude, and the least normal float), so that rounding in the intersection
    /// routines seldom puts a hit outside it: the last step of [`trusted_box`].
    #[inline]
    fn with_rounding_margin(self) -> Aabb {
        let scale = self.min.abs().max(self.max.abs()).max_element();
        self.padded(scale * 1e-6 + f32::MIN_POSITIVE)
    }

    /// Index of the longest axis.
    pub fn longest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }
}

/// The box the structures hold a primitive of tight box `tight` in: grown by `margin` (a
/// routine's own allowance, the textbook sphere roots', or 0), then by the rounding
/// margin; `None` unless finite. Every routine reports only hits inside it, by the
/// structures' box test ([`super::RayQuery::holds`]).
#[inline]
pub fn trusted_box(tight: Aabb, margin: f32) -> Option<Aabb> {
    let grown = tight.padded(margin);
    (grown.min.is_finite() && grown.max.is_finite()).then(|| grown.with_rounding_margin())
}

impl BoxPack8 {
    /// [`trusted_box`] of each of the eight boxes, with the lanes where it is `Some`; bit
    /// for bit on lanes whose corners are not NaN (the corners of a routine's hits).
    #[inline(always)]
    pub fn trusted(self, margin: f32) -> (BoxPack8, Mask8) {
        let margin = Vec3x8::splat(Vec3::splat(margin));
        let (min, max) = (self.min - margin, self.max + margin);
        let (low, high) = (min.abs(), max.abs());
        let infinity = F32x8::splat(f32::INFINITY);
        let finite = low.x.max(high.x).lt(infinity)
            & low.y.max(high.y).lt(infinity)
            & low.z.max(high.z).lt(infinity);
        // The largest magnitude, as `Aabb::with_rounding_margin` takes it (maxima are
        // exact, in any order).
        let scale = low
            .x
            .max(high.x)
            .max(low.y.max(high.y))
            .max(low.z.max(high.z));
        let margin = scale * F32x8::splat(1e-6) + F32x8::splat(f32::MIN_POSITIVE);
        let margin = Vec3x8 {
            x: margin,
            y: margin,
            z: margin,
        };
        let trusted = BoxPack8 {
            min: min - margin,
            max: max + margin,
        };
        (trusted, finite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_area_and_axes() {
        let a = Aabb::EMPTY.grow(Vec3::ZERO).grow(Vec3::new(2.0, 1.0, 3.0));
        assert_eq!(a.area(), 2.0 * (2.0 + 3.0 + 6.0));
        assert_eq!(a.longest_axis(), 2);
        assert!(Aabb::EMPTY.is_empty() && !a.is_empty());
        assert_eq!(Aabb::EMPTY.union(a), a);
        assert_eq!(Aabb::EMPTY.area(), 0.0);
    }
}
