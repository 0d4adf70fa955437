//! Rays and hit records shared by the intersection routines, accelerators and shader.

use glam::Vec3;

use crate::prim::PrimId;
use crate::simd::{bits_where, Bits, F32xP, Floats, LaneBits, Vec3Lanes, Vec3xP, PACKET};

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

/// [`Ray::is_traceable`] lane by lane, for the rays from `origin` along `dir`.
#[inline]
pub fn traceable_lanes<F: Floats>(origin: Vec3Lanes<F>, dir: Vec3Lanes<F>) -> F::Mask {
    let finite = |v: Vec3Lanes<F>| v.x.is_finite() & v.y.is_finite() & v.z.is_finite();
    let zero = F::splat(0.0);
    let dir_zero = dir.x.eq(zero) & dir.y.eq(zero) & dir.z.eq(zero);
    finite(origin) & finite(dir) & !dir_zero
}

/// [`PACKET`] rays traced together (Embree's `RayK`: 8, or 16 in an AVX-512 build), the
/// one packet type of every layer: the rays themselves (borrowed, for lanes that go on
/// alone), the same rays as structure of arrays for the packet kernels of
/// [`crate::intersect`] (lane `i` is ray `i`), each lane's interval `(t_min, t_max[i])`,
/// and the lanes that are asked (`active`, bit `i` for lane `i`). `inv_dir = 1 / dir` is
/// computed once, as the scalar callers do with `ray.dir.recip()`, so the slab tests see
/// the same bits.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket<'r> {
    pub rays: &'r [Ray; PACKET],
    pub origin: Vec3xP,
    pub dir: Vec3xP,
    pub inv_dir: Vec3xP,
    pub time: F32xP,
    /// One lower end for every lane: queries start at the origin.
    pub t_min: f32,
    pub t_max: [f32; PACKET],
    pub active: LaneBits,
}

/// The bit mask of a packet's lanes `0..PACKET` for which `pred` holds.
pub fn lane_mask(pred: impl FnMut(usize) -> bool) -> LaneBits {
    bits_where(pred)
}

impl<'r> RayPacket<'r> {
    /// The rays, every lane active over `(0, inf)`.
    pub fn new(rays: &'r [Ray; PACKET]) -> Self {
        let dir = Vec3xP::from_fn(|k| rays[k].dir);
        RayPacket {
            rays,
            origin: Vec3xP::from_fn(|k| rays[k].origin),
            dir,
            inv_dir: dir.recip(),
            time: F32xP::from_fn(|k| rays[k].time),
            t_min: 0.0,
            t_max: [f32::INFINITY; PACKET],
            active: LaneBits::first(PACKET),
        }
    }

    /// The packet with only the lanes `active` asked.
    #[inline(always)]
    pub fn with_active(mut self, active: LaneBits) -> Self {
        self.active = active;
        self
    }

    /// [`RayPacket::with_active`] made in `copy`, or the packet itself where `active` are
    /// the lanes it asks (a copy is hundreds of bytes, and most packets keep every lane).
    #[inline(always)]
    pub fn asking<'a>(&'a self, active: LaneBits, copy: &'a mut Option<Self>) -> &'a Self {
        if active == self.active {
            self
        } else {
            copy.insert(self.with_active(active))
        }
    }

    /// The packet with lane `i` asked within `(t_min, t_max[i])`.
    #[inline(always)]
    pub fn with_t_max(mut self, t_max: [f32; PACKET]) -> Self {
        self.t_max = t_max;
        self
    }

    /// The lanes whose ray [`Ray::is_traceable`] ([`traceable_lanes`]), as a bit mask.
    pub fn traceable(&self) -> LaneBits {
        traceable_lanes(self.origin, self.dir).bitmask()
    }

    /// Each lane's `1 / dir`, as the single-ray routines take it.
    pub fn inv_dir_lanes(&self) -> [Vec3; PACKET] {
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
