//! The boxes that the grid and the BVHs are built from, and why every structure sees each
//! hit that brute force keeps.
//!
//! **The hit rule.** Every primitive routine reports a hit at `t` only if `t` lies in the
//! ray's interval of the primitive's trusted box (`intersect::trusted_box`: its tight box,
//! grown by a margin of its own and then by one relative to its coordinates), as the
//! structures' one box test computes it (`RayQuery::holds`, with `BoxRay::interval`, its
//! entry not `beyond` `t`). [`prim_bounds`] is that box. A node's box holds its primitives'
//! boxes, and the slab arithmetic is monotone in the corners (`(corner - origin) *
//! inv_dir`, then min and max, then the same widening), so such a hit lies in the interval
//! of every box above it: a node holding it is entered, never skipped as beyond it, and
//! brute force and both BVH widths find the same hits bit for bit, whatever error a
//! routine's `t` has. The grid walks every cell the ray may be in by the same allowance
//! (`accel::grid`), so it finds them too. A hit outside the rule is a routine's rounding
//! (a thin cone or a small sphere seen from 1e9 away, the textbook sphere roots) and no
//! structure reports it; a triangle computes such a hit again in double precision
//! (`intersect::triangle`), which puts it back inside.
//!
//! The rule costs a box test per hit a routine finds, not per primitive tested, computed
//! eight at a time in the leaf kernels. A padding derived from each routine's error bound
//! alone cannot hold where that bound grows with the ray's distance (the textbook roots'
//! does with `|origin - centre|`); so the textbook spheres get the bound for the rays of a
//! render ([`textbook_margin`]), which keeps the course renderer's images, and the rule for
//! every other ray.

use crate::intersect::{gamma, trusted_box, Aabb, IntersectOptions, Roots};
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;

/// The trusted box of a bounded primitive, over the whole `shutter` for moving ones,
/// grown first by `roots_margin` ([`textbook_margin`]) where its kind takes the margin of
/// the sphere roots ([`Geometry::takes_roots_margin`]). Non-finite primitives get the
/// empty box (they are never hit).
pub fn prim_bounds(
    geometry: &Geometry,
    prim: PrimId,
    shutter: [f32; 2],
    roots_margin: f32,
) -> Aabb {
    let margin = match Geometry::takes_roots_margin(prim.kind()) {
        true => roots_margin,
        false => 0.0,
    };
    trusted_box(geometry.bounds(prim, shutter), margin).unwrap_or(Aabb::EMPTY)
}

/// `options` with the padding of the boxes its tests need over `geometry`: the textbook
/// roots' spheres are padded further ([`textbook_margin`]).
pub fn with_margins(options: IntersectOptions, geometry: &Geometry) -> IntersectOptions {
    IntersectOptions {
        roots_margin: match options.roots {
            Roots::Precise => 0.0,
            Roots::Textbook => textbook_margin(geometry),
        },
        ..options
    }
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
