//! Axis-aligned bounding boxes of primitives, for the grid and the BVHs.

use glam::Vec3;

use crate::ray::{PrimId, PrimKind};
use crate::scene::Geometry;

/// The bounded primitive kinds, in [`PrimId`] order: every kind but planes, which no
/// structure holds.
pub const BOUNDED: [PrimKind; 5] = [
    PrimKind::Sphere,
    PrimKind::MovingSphere,
    PrimKind::Triangle,
    PrimKind::Box,
    PrimKind::Cone,
];

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

/// The box of a bounded primitive, over the whole `shutter` for moving spheres, grown by
/// a relative margin so that rounding in the intersection routines never puts a hit
/// outside it. Non-finite primitives get the empty box (they are never hit).
pub fn prim_bounds(geometry: &Geometry, prim: PrimId, shutter: [f32; 2]) -> Aabb {
    let i = prim.index();
    let sphere = |c: Vec3, r: f32| Aabb {
        min: c - r.abs(),
        max: c + r.abs(),
    };
    let tight = match prim.kind() {
        PrimKind::Sphere => sphere(geometry.spheres.centre.get(i), geometry.spheres.radius[i]),
        PrimKind::MovingSphere => {
            let s = &geometry.moving_spheres;
            // The centre moves on a line, so the boxes at the two ends cover the path.
            let r = s.radius[i];
            sphere(s.centre_at(i, shutter[0]), r).union(sphere(s.centre_at(i, shutter[1]), r))
        }
        PrimKind::Triangle => {
            let t = &geometry.triangles;
            let p0 = t.p0.get(i);
            Aabb::EMPTY
                .grow(p0)
                .grow(p0 + t.e1.get(i))
                .grow(p0 + t.e2.get(i))
        }
        PrimKind::Box => Aabb {
            min: geometry.boxes.min.get(i),
            max: geometry.boxes.max.get(i),
        },
        PrimKind::Cone => {
            let c = &geometry.cones;
            let (base, axis) = (c.base.get(i), c.axis.get(i));
            let apex = base + axis * c.height[i];
            // A disc of radius r about `axis` reaches r * sqrt(1 - axis_k^2) along axis k.
            let reach = (Vec3::ONE - axis * axis).max(Vec3::ZERO).powf(0.5);
            let disc = |centre: Vec3, r: f32| Aabb {
                min: centre - reach * r.abs(),
                max: centre + reach * r.abs(),
            };
            disc(base, c.r_base[i]).union(disc(apex, c.r_apex[i]))
        }
        PrimKind::Plane => unreachable!("planes are unbounded and never enter a structure"),
    };
    if !(tight.min.is_finite() && tight.max.is_finite()) {
        return Aabb::EMPTY;
    }
    let scale = tight.min.abs().max(tight.max.abs()).max_element();
    tight.padded(scale * 1e-6 + f32::MIN_POSITIVE)
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
