//! The padded boxes that the grid and the BVHs are built from, and the hit rule that makes
//! every structure see each hit that brute force keeps.
//!
//! **The hit rule** ([`admits`]): a hit of a bounded primitive at `t` counts only if `t`
//! lies in the ray's interval of the primitive's own padded box, as the structures' one
//! box test computes it ([`BoxRay::interval`], its entry not [`beyond`] `t`). A node's
//! box holds its primitives' boxes, and the slab arithmetic is monotone in the corners
//! (`(corner - origin) * inv_dir`, then min and max, then the same widening), so such a
//! hit lies in the interval of every box above it: a node holding it is entered, never
//! skipped as beyond it, and brute force and both BVH widths find the same hits bit for
//! bit, whatever error a routine's `t` has. The grid walks every cell the ray may be in
//! by the same allowance (`accel::grid`), so it finds them too. A hit outside the rule is
//! a routine's rounding (a thin cone or a small sphere seen from 1e9 away, the textbook
//! sphere roots) and is dropped by every structure alike.
//!
//! The rule costs a box per hit a routine reports, not per primitive tested, and is
//! applied to the kinds whose routines keep single precision's error (`needs_rule`):
//! a box's hit lies in its padded box by construction, and a triangle's, recomputed in
//! double precision (`intersect::triangle`), within ulps of a point of the triangle.
//! A padding derived from each routine's error bound alone cannot hold where that bound
//! grows with the ray's distance (the textbook roots' does with `|origin - centre|`); so
//! the textbook spheres get the bound for the rays of a render ([`textbook_margin`]),
//! which keeps the course renderer's images, and the rule for every other ray.

use crate::intersect::{beyond, gamma, Aabb, BoxRay, RayQuery, TriangleHit, TriangleHit8};
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;
use crate::simd::{F32x8, Mask8};

/// The box of a bounded primitive, over the whole `shutter` for moving spheres, grown by
/// a relative margin so that rounding in the intersection routines seldom puts a hit
/// outside it, and a sphere's (moving or not) first by `sphere_margin`
/// ([`textbook_margin`]). Non-finite primitives get the empty box (they are never hit).
pub fn prim_bounds(
    geometry: &Geometry,
    prim: PrimId,
    shutter: [f32; 2],
    sphere_margin: f32,
) -> Aabb {
    let mut tight = geometry.bounds(prim, shutter);
    if matches!(prim.kind(), PrimKind::Sphere | PrimKind::MovingSphere) && sphere_margin > 0.0 {
        tight = tight.padded(sphere_margin);
    }
    if !(tight.min.is_finite() && tight.max.is_finite()) {
        return Aabb::EMPTY;
    }
    let scale = tight.min.abs().max(tight.max.abs()).max_element();
    tight.padded(scale * 1e-6 + f32::MIN_POSITIVE)
}

/// Whether the hit of `prim` at `t` along `query` counts (the module's rule). A moving
/// sphere is bounded at the ray's time: that box lies in its box over any shutter that
/// holds the time (its centre moves monotonically, and the padding grows with the
/// coordinates). Unbounded kinds, which no structure holds, always count.
#[inline(always)]
pub fn admits(geometry: &Geometry, prim: PrimId, query: &RayQuery, t: f32) -> bool {
    !needs_rule(prim.kind()) || in_padded_box(geometry, prim, query, t)
}

/// Whether `t` lies in `query`'s interval of `prim`'s padded box, as [`admits`] asks:
/// apart, so that the kinds that skip the rule pay only for the test of their kind.
#[inline(never)]
fn in_padded_box(geometry: &Geometry, prim: PrimId, query: &RayQuery, t: f32) -> bool {
    let time = query.ray.time;
    let bounds = prim_bounds(geometry, prim, [time, time], query.options.sphere_margin);
    let ray = BoxRay::new(query.ray.origin, query.inv_dir);
    ray.interval(bounds.min, bounds.max, query.t_min, f32::INFINITY)
        .is_some_and(|(entry, exit)| !beyond(entry, t) && t <= exit)
}

/// How far the textbook sphere roots (the course profile's) may put a hit along the ray
/// from the sphere, for rays whose origin lies within the box of `geometry`'s bounded
/// primitives: `disc = b^2 - c` is off by about `gamma(5) |oc|^2`, and its root by up to
/// the root of that at a grazing ray, so the hit by `sqrt(2 gamma(5)) |oc|` (twice that
/// here, for the terms left out), `|oc|` at most the box's diagonal. The error grows
/// with the ray's distance, so no padding holds every ray: this one holds the rays of a
/// render (from a camera near the scene), which keep the course renderer's images (the
/// hits it finds off the surface); a ray from further away still agrees in every
/// structure, by the rule, but may lose such a hit.
pub fn textbook_margin(geometry: &Geometry) -> f32 {
    let scene = PrimKind::BOUNDED
        .iter()
        .flat_map(|&kind| geometry.ids(kind))
        .map(|prim| geometry.bounds(prim, [0.0, 0.0]))
        .filter(|b| b.min.is_finite() && b.max.is_finite())
        .fold(Aabb::EMPTY, Aabb::union);
    if scene.is_empty() {
        return 0.0;
    }
    let margin = 2.0 * (2.0 * f64::from(gamma(5))).sqrt() * f64::from(scene.extent().length());
    (margin as f32).min(f32::MAX)
}

/// Whether the hits of `kind` need the rule. A box's hit is a slab distance of its tight
/// box, computed as the structures' box test computes it, so it lies in the interval of
/// the padded box by construction; a triangle's is recomputed in double precision
/// (`intersect::triangle`), within a few ulps of the distance to a point of the triangle,
/// where the padding and the allowance hold it; planes are in no structure. Spheres
/// (either form of the roots), moving spheres and cones keep single precision's error.
#[inline(always)]
const fn needs_rule(kind: PrimKind) -> bool {
    matches!(
        kind,
        PrimKind::Sphere | PrimKind::MovingSphere | PrimKind::Cone
    )
}

/// The scalar test of `prim` under the hit rule.
#[inline]
pub fn counted_hit(
    geometry: &Geometry,
    prim: PrimId,
    query: &RayQuery,
    t_max: f32,
) -> Option<TriangleHit> {
    geometry
        .intersect(prim, query, t_max)
        .filter(|hit| admits(geometry, prim, query, hit.t))
}

/// The lanes of `hits` (lane `k` a hit of `prims[k]` along lane `k` of `query`) that the
/// hit rule keeps, each as the scalar rule decides it.
#[inline]
pub fn admitted8(
    geometry: &Geometry,
    prims: impl Fn(usize) -> PrimId,
    query: impl Fn(usize) -> RayQuery,
    hits: &TriangleHit8,
) -> Mask8 {
    let mask = hits.hit.bitmask();
    if mask == 0 || !needs_rule(prims(mask.trailing_zeros() as usize).kind()) {
        return hits.hit;
    }
    let t = hits.t.to_array();
    let mut kept = 0u8;
    crate::accel::hit::for_lanes(mask, |k| {
        if admits(geometry, prims(k), &query(k), t[k]) {
            kept |= 1 << k;
        }
    });
    Mask8::from_bitmask(kept)
}

/// [`Geometry::intersect8`] under the hit rule, lane by lane the scalar [`counted_hit`].
#[inline]
pub fn counted_hits8(
    geometry: &Geometry,
    prim: PrimId,
    query: &crate::intersect::RayQuery8,
    t_max: F32x8,
    active: u8,
) -> TriangleHit8 {
    let mut hits = geometry.intersect8(prim, query, t_max, active);
    hits.hit = admitted8(geometry, |_| prim, |k| query.lane(k), &hits);
    hits
}
