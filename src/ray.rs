//! Rays and hit records shared by the intersection routines, accelerators and shader.

use glam::Vec3;

use crate::prim::PrimId;
use crate::simd::{F32x8, Vec3x8};

/// A ray `origin + t * dir`. `dir` is unit length wherever the renderer makes rays: the
/// intersection routines rely on it (the sphere test skips the `dot(d, d)` term).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    /// Shutter time at which moving geometry is seen (0 without motion blur).
    pub time: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray {
            origin,
            dir,
            time: 0.0,
        }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }

    /// A finite origin and a finite, nonzero direction: rays without them meet nothing
    /// (the intersection routines are not asked to agree on NaN and infinite rays).
    pub fn is_traceable(&self) -> bool {
        self.origin.is_finite() && self.dir.is_finite() && self.dir != Vec3::ZERO
    }
}

/// Eight rays traced together (Embree's `RayK`), the one packet type of every layer: the
/// rays themselves (borrowed, for lanes that go on alone), the same rays as structure of arrays
/// for the packet kernels of [`crate::intersect`] (lane `i` is ray `i`), each lane's
/// interval `(t_min, t_max[i])`, and the lanes that are asked (`active`, bit `i` for
/// lane `i`). `inv_dir = 1 / dir` is computed once, as the scalar callers do with
/// `ray.dir.recip()`, so the slab tests see the same bits.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket<'r> {
    pub rays: &'r [Ray; 8],
    pub origin: Vec3x8,
    pub dir: Vec3x8,
    pub inv_dir: Vec3x8,
    pub time: F32x8,
    /// One lower end for every lane: queries start at the origin.
    pub t_min: f32,
    pub t_max: [f32; 8],
    pub active: u8,
}

/// The bit mask of the lanes `0..8` for which `pred` holds.
pub fn lane_mask(mut pred: impl FnMut(usize) -> bool) -> u8 {
    (0..8).filter(|&k| pred(k)).fold(0, |mask, k| mask | 1 << k)
}

impl<'r> RayPacket<'r> {
    /// The eight rays, every lane active over `(0, inf)`.
    pub fn new(rays: &'r [Ray; 8]) -> Self {
        let dir = Vec3x8::from_lanes(rays.map(|r| r.dir));
        RayPacket {
            rays,
            origin: Vec3x8::from_lanes(rays.map(|r| r.origin)),
            dir,
            inv_dir: dir.recip(),
            time: F32x8::from_array(rays.map(|r| r.time)),
            t_min: 0.0,
            t_max: [f32::INFINITY; 8],
            active: 0xFF,
        }
    }

    /// The packet with only the lanes `active` asked.
    pub fn with_active(self, active: u8) -> Self {
        RayPacket { active, ..self }
    }

    /// The packet with lane `i` asked within `(t_min, t_max[i])`.
    pub fn with_t_max(self, t_max: [f32; 8]) -> Self {
        RayPacket { t_max, ..self }
    }

    /// The lanes whose ray [`Ray::is_traceable`] (its 8-lane twin), as a bit mask.
    pub fn traceable(&self) -> u8 {
        let finite = |v: Vec3x8| v.x.is_finite() & v.y.is_finite() & v.z.is_finite();
        let zero = F32x8::splat(0.0);
        let dir_zero = self.dir.x.eq(zero) & self.dir.y.eq(zero) & self.dir.z.eq(zero);
        (finite(self.origin) & finite(self.dir) & !dir_zero).bitmask()
    }

    /// Each lane's `1 / dir`, as the single-ray routines take it.
    pub fn inv_dir_lanes(&self) -> [Vec3; 8] {
        std::array::from_fn(|k| self.inv_dir.lane(k))
    }
}

/// The closest hit found along a ray: its distance, the primitive, and the barycentric
/// coordinates `(u, v)` of the hit for triangles (zero for other kinds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: PrimId,
    pub u: f32,
    pub v: f32,
}
