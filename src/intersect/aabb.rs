//! The Box primitive's test and its SIMD twins (a packet's rays against one box; one ray
//! against a [`BoxPack8`] of a BVH leaf). It is exact: it returns where the ray meets the
//! box's surface (the entry, or the exit from inside) in the open interval
//! `(t_min, t_max)`, as every primitive test does, so a ray passing beside the box misses
//! it. The acceleration structures' box test is another routine with another contract
//! (`interval.rs`: where the ray may be inside, allowing for rounding, erring towards
//! visiting); sharing code would change this test's bits, and so the images of scenes
//! with boxes.

use glam::Vec3;

use super::{first_root_in, first_root_in_lanes, gather8};
use super::{
    Aabb, LeafPack, PackOf, PacketHits, PacketQuery, RayQuery, ShapeHit, ShapeHit8, Shapes,
    SurfacePoint, Vec3s,
};
use crate::ray::{Ray, RayPacket};
use crate::simd::{F32x8, F32xP, Floats, LaneBits, Mask8, MaskP, Vec3Lanes, Vec3x8, Vec3xP};

/// Slab test against the axis-aligned box `[min, max]`, with `inv_dir = 1 / ray.dir`
/// computed once per ray. Returns the entry distance, or the exit distance when the
/// origin is inside (or the entry is before `t_min`). glam's `min`/`max` are
/// `if a < b { a } else { b }` (and `>`): they drop the NaN that `0 * inf` gives for a
/// ray lying in a slab's plane when it is `t1` and keep it when it is `t2`, and a NaN
/// entry or exit is a miss; the SIMD twins follow the same rule.
pub fn aabb(ray: &Ray, inv_dir: Vec3, min: Vec3, max: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
    let t1 = (min - ray.origin) * inv_dir;
    let t2 = (max - ray.origin) * inv_dir;
    let near = largest(t1.min(t2));
    let far = smallest(t1.max(t2));
    if !(near <= far) {
        return None;
    }
    first_root_in(near, far, t_min, t_max)
}

/// `max(x, max(y, z))` by the `a > b ? a : b` rule, as the SIMD twins take it. Not glam's
/// `max_element`: glam 0.34.3 changed its order to `max(max(x, y), z)`, which lets the
/// NaN slab of a ray lying in a `y` face hide the `x` slab, so the box was hit outside.
fn largest(t: Vec3) -> f32 {
    let max = |a: f32, b: f32| if a > b { a } else { b };
    max(t.x, max(t.y, t.z))
}

/// `min(x, min(y, z))` by the `a < b ? a : b` rule; see [`largest`].
fn smallest(t: Vec3) -> f32 {
    let min = |a: f32, b: f32| if a < b { a } else { b };
    min(t.x, min(t.y, t.z))
}

/// Eight boxes side by side: the primitive boxes of a leaf for [`aabb_leaf`], or the
/// children of an eight-wide BVH node for [`super::BoxRay::intervals8`].
///
/// Unused slots hold [`BoxPack8::PAD`] (NaN corners), which [`aabb_leaf`] never hits:
/// every slab distance is NaN and so is the entry. No corner values can make a slot
/// inert for [`super::BoxRay::intervals8`], whose clipping starts from `[t_min, t_max]`
/// (NaN slabs are ignored, an inverted or infinite box spans everything, a box at
/// infinity is entered at `t = inf` when `t_max` is infinite); leave its padding out of
/// the `active` mask instead.
#[derive(Clone, Copy, Debug)]
pub struct BoxPack8 {
    pub min: Vec3x8,
    pub max: Vec3x8,
}

impl BoxPack8 {
    /// Both corners of a padding slot.
    pub const PAD: Vec3 = Vec3::NAN;

    /// Packs up to eight `(min, max)` boxes, padding the rest with [`BoxPack8::PAD`].
    ///
    /// # Panics
    /// If given more than eight boxes.
    pub fn new(boxes: &[(Vec3, Vec3)]) -> Self {
        assert!(boxes.len() <= 8, "a pack holds at most 8 boxes");
        let corner = |pick: fn(&(Vec3, Vec3)) -> Vec3| {
            Vec3x8::from_lanes(std::array::from_fn(|i| {
                boxes.get(i).map_or(Self::PAD, pick)
            }))
        };
        BoxPack8 {
            min: corner(|b| b.0),
            max: corner(|b| b.1),
        }
    }

    /// Slot `k`'s `(min, max)` corners.
    #[inline]
    pub fn corners(&self, k: usize) -> (Vec3, Vec3) {
        (self.min.lane(k), self.max.lane(k))
    }
}

/// [`aabb`] for a packet's rays (with their `inv_dir`) against one box; lanes outside
/// `active` miss.
pub fn aabb_packet(
    rays: &RayPacket,
    min: Vec3,
    max: Vec3,
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> (MaskP, F32xP) {
    let (hit, t) = aabb_lanes(
        rays.origin,
        rays.inv_dir,
        Vec3xP::splat(min),
        Vec3xP::splat(max),
        t_min,
        t_max,
    );
    (hit & MaskP::from_bitmask(active), t)
}

/// [`aabb`] for one ray against the eight boxes of a pack.
pub fn aabb_leaf(
    ray: &Ray,
    inv_dir: Vec3,
    pack: &BoxPack8,
    t_min: f32,
    t_max: f32,
) -> (Mask8, F32x8) {
    aabb_lanes(
        Vec3x8::splat(ray.origin),
        Vec3x8::splat(inv_dir),
        pack.min,
        pack.max,
        F32x8::splat(t_min),
        F32x8::splat(t_max),
    )
}

/// The body of [`aabb`], lane by lane, with glam's `min`/`max` rule ([`F32x8::min`]) and
/// the order of [`largest`] and [`smallest`].
#[inline(always)]
fn aabb_lanes<F: Floats>(
    origin: Vec3Lanes<F>,
    inv_dir: Vec3Lanes<F>,
    min: Vec3Lanes<F>,
    max: Vec3Lanes<F>,
    t_min: F,
    t_max: F,
) -> (F::Mask, F) {
    let t1 = (min - origin) * inv_dir;
    let t2 = (max - origin) * inv_dir;
    let (lo, hi) = (
        Vec3Lanes {
            x: t1.x.min(t2.x),
            y: t1.y.min(t2.y),
            z: t1.z.min(t2.z),
        },
        Vec3Lanes {
            x: t1.x.max(t2.x),
            y: t1.y.max(t2.y),
            z: t1.z.max(t2.z),
        },
    );
    let near = lo.x.max(lo.y.max(lo.z));
    let far = hi.x.min(hi.y.min(hi.z));
    let (hit, t) = first_root_in_lanes(near, far, t_min, t_max);
    (hit & near.le(far), t)
}

/// Outward normal of the face of `[min, max]` nearest to the point `p` (a hit point).
pub fn aabb_normal(min: Vec3, max: Vec3, p: Vec3) -> Vec3 {
    let mut best = (f32::INFINITY, Vec3::X);
    for axis in 0..3 {
        let mut normal = Vec3::ZERO;
        normal[axis] = -1.0;
        let to_min = (p[axis] - min[axis]).abs();
        if to_min < best.0 {
            best = (to_min, normal);
        }
        normal[axis] = 1.0;
        let to_max = (max[axis] - p[axis]).abs();
        if to_max < best.0 {
            best = (to_max, normal);
        }
    }
    best.1
}

#[derive(Clone, Debug, Default)]
pub struct Boxes {
    pub min: Vec3s,
    pub max: Vec3s,
    pub material: Vec<u32>,
}

impl LeafPack for Boxes {
    type Pack = BoxPack8;
    type Compact = BoxPack8;
}

impl PackOf<Boxes> for BoxPack8 {
    fn pack(storage: &Boxes, indices: impl Iterator<Item = usize>) -> Option<BoxPack8> {
        let (boxes, n) = gather8(indices.map(|i| (storage.min.get(i), storage.max.get(i))));
        Some(BoxPack8::new(&boxes[..n]))
    }

    #[inline]
    fn leaf<const FRAME: usize>(pack: &BoxPack8, query: &RayQuery, t_max: f32) -> ShapeHit8 {
        let (ray, inv_dir) = (&query.ray, query.inv_dir);
        ShapeHit8::at(aabb_leaf(ray, inv_dir, pack, query.t_min, t_max))
    }

    type Slots<'a> = &'a BoxPack8;

    #[inline(always)]
    fn slots(pack: &BoxPack8) -> &BoxPack8 {
        pack
    }

    #[inline(always)]
    fn slot_packet(
        pack: &BoxPack8,
        slot: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        aabb_in_packet(query, pack.corners(slot), t_max, active)
    }
}

/// [`aabb_packet`] for the lanes `active` of `query`'s packet, in the form of the
/// storage's and the pack's packet tests.
#[inline(always)]
fn aabb_in_packet(
    query: &PacketQuery,
    (min, max): (Vec3, Vec3),
    t_max: F32xP,
    active: LaneBits,
) -> PacketHits {
    PacketHits::at(aabb_packet(
        query.packet,
        min,
        max,
        query.t_min_lanes(),
        t_max,
        active,
    ))
}

impl Shapes for Boxes {
    fn len(&self) -> usize {
        self.material.len()
    }

    fn shrink_to_fit(&mut self) {
        self.min.shrink_to_fit();
        self.max.shrink_to_fit();
        self.material.shrink_to_fit();
    }

    fn material(&self, i: usize) -> u32 {
        self.material[i]
    }

    fn bounds(&self, i: usize, _shutter: [f32; 2]) -> Aabb {
        Aabb {
            min: self.min.get(i),
            max: self.max.get(i),
        }
    }

    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<ShapeHit> {
        let (ray, inv_dir, t_min) = (&query.ray, query.inv_dir, query.t_min);
        aabb(ray, inv_dir, self.min.get(i), self.max.get(i), t_min, t_max).map(ShapeHit::at)
    }

    fn intersect_packet(
        &self,
        i: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        aabb_in_packet(query, (self.min.get(i), self.max.get(i)), t_max, active)
    }

    fn normal(&self, i: usize, p: Vec3, _u: f32, _v: f32, _time: f32) -> Vec3 {
        aabb_normal(self.min.get(i), self.max.get(i), p)
    }

    /// `p` with the coordinate of the face hit set to the face's: exact, and the slab
    /// test's `(face - origin)` has the exact sign, so the one float
    /// [`super::spawn_origin`] adds is enough.
    fn surface_point(&self, i: usize, ray: &Ray, t: f32, _u: f32, _v: f32) -> SurfacePoint {
        let (min, max, p) = (self.min.get(i), self.max.get(i), ray.at(t));
        let normal = aabb_normal(min, max, p);
        let face = Vec3::select(normal.cmpgt(Vec3::ZERO), max, min);
        SurfacePoint {
            point: Vec3::select(normal.cmpne(Vec3::ZERO), face, p),
            error: Vec3::ZERO,
            normal,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test(o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let ray = Ray::new(o, d.normalize());
        aabb(
            &ray,
            ray.dir.recip(),
            Vec3::splat(-1.0),
            Vec3::splat(1.0),
            t_min,
            t_max,
        )
    }

    #[test]
    fn from_outside_returns_entry() {
        let t = test(Vec3::new(0., 0., -5.), Vec3::Z, 0.0, f32::INFINITY);
        assert_eq!(t, Some(4.0));
    }

    #[test]
    fn from_inside_returns_exit() {
        let t = test(Vec3::new(0., 0.5, 0.), Vec3::Y, 0.0, f32::INFINITY);
        assert_eq!(t, Some(0.5));
    }

    #[test]
    fn misses_and_behind() {
        assert_eq!(
            test(Vec3::new(0., 2., -5.), Vec3::Z, 0.0, f32::INFINITY),
            None
        );
        assert_eq!(
            test(Vec3::new(0., 0., 5.), Vec3::Z, 0.0, f32::INFINITY),
            None
        );
        assert_eq!(test(Vec3::new(0., 0., -5.), Vec3::Z, 0.0, 3.0), None);
    }

    #[test]
    fn axis_parallel_ray_on_a_face_plane_does_not_panic() {
        // Origin on the plane y = 1 with dir.y = 0: 0 * inf is NaN in that slab.
        let t = test(Vec3::new(0., 1., -5.), Vec3::Z, 0.0, f32::INFINITY);
        assert!(t.is_none() || t == Some(4.0));
    }

    #[test]
    fn a_ray_in_a_face_plane_never_hits_beside_the_box() {
        // The face's slab is NaN (0 * inf); the other two must still count, whichever
        // axis the NaN is on (fuzz finding: with glam 0.34.3's `min_element` a NaN `y`
        // slab hid the `x` one).
        for face in 0..3 {
            for away in (0..3).filter(|&k| k != face) {
                let across = 3 - face - away;
                let (mut o, mut d) = (Vec3::ZERO, Vec3::ZERO);
                (o[face], o[away]) = (1.0, 2.0);
                (d[away], d[across]) = (1.0, 1.0);
                assert_eq!(
                    test(o, d, 0.0, f32::INFINITY),
                    None,
                    "on face {face}, leaving along {away}"
                );
            }
        }
    }

    #[test]
    fn diagonal_ray_hits_corner_region() {
        let t = test(Vec3::splat(-3.0), Vec3::ONE, 0.0, f32::INFINITY).unwrap();
        assert!((t - 2.0 * 3f32.sqrt()).abs() < 1e-5);
    }

    #[test]
    fn normal_is_the_face_hit() {
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(aabb_normal(lo, hi, Vec3::new(0.1, 0.2, -1.0)), Vec3::NEG_Z);
        assert_eq!(aabb_normal(lo, hi, Vec3::new(0.1, 2.0, 0.3)), Vec3::Y);
        assert_eq!(aabb_normal(lo, hi, Vec3::new(1.0, 0.0, 0.3)), Vec3::X);
    }
}
