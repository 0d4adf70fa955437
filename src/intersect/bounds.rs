//! Axis-aligned boxes: each kind's bounds, and the boxes the grid and the BVHs are
//! built from.

use glam::Vec3;

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
