//! Rays and hit records shared by the intersection routines, accelerators and shader.

use glam::Vec3;

use crate::prim::PrimId;
use crate::simd::{F32x8, Mask8, Vec3x8};

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

/// Eight rays as structure of arrays, for the packet kernels of [`crate::intersect`]:
/// lane `i` is ray `i`. `inv_dir = 1 / dir` is computed once, as the scalar callers do
/// with `ray.dir.recip()`, so the slab tests see the same bits.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket {
    pub origin: Vec3x8,
    pub dir: Vec3x8,
    pub inv_dir: Vec3x8,
    pub time: F32x8,
}

/// The bit mask of the lanes `0..8` for which `pred` holds.
pub fn lane_mask(mut pred: impl FnMut(usize) -> bool) -> u8 {
    (0..8).filter(|&k| pred(k)).fold(0, |mask, k| mask | 1 << k)
}

impl RayPacket {
    /// Each lane's `1 / dir`, as the single-ray routines take it.
    pub fn inv_dir_lanes(&self) -> [Vec3; 8] {
        std::array::from_fn(|k| self.inv_dir.lane(k))
    }

    pub fn new(rays: &[Ray; 8]) -> Self {
        let dir = Vec3x8::from_lanes(rays.map(|r| r.dir));
        RayPacket {
            origin: Vec3x8::from_lanes(rays.map(|r| r.origin)),
            dir,
            inv_dir: dir.recip(),
            time: F32x8::from_array(rays.map(|r| r.time)),
        }
    }

    /// Up to eight rays; the lanes past `rays.len()` hold NaN rays and are left out of
    /// the returned active mask, so a short tail needs no scalar loop.
    ///
    /// # Panics
    /// If `rays` holds more than eight rays.
    pub fn from_slice(rays: &[Ray]) -> (Self, Mask8) {
        assert!(rays.len() <= 8, "a packet holds at most 8 rays");
        let nan = Ray::new(Vec3::NAN, Vec3::NAN);
        let lanes = std::array::from_fn(|i| rays.get(i).copied().unwrap_or(nan));
        let active = Mask8::from_bitmask(((1u16 << rays.len()) - 1) as u8);
        (RayPacket::new(&lanes), active)
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
