//! The padded boxes that the grid and the BVHs are built from.

use crate::intersect::Aabb;
use crate::prim::PrimId;
use crate::scene::Geometry;

/// The box of a bounded primitive, over the whole `shutter` for moving spheres, grown by
/// a relative margin so that rounding in the intersection routines never puts a hit
/// outside it. Non-finite primitives get the empty box (they are never hit).
pub fn prim_bounds(geometry: &Geometry, prim: PrimId, shutter: [f32; 2]) -> Aabb {
    let tight = geometry.bounds(prim, shutter);
    if !(tight.min.is_finite() && tight.max.is_finite()) {
        return Aabb::EMPTY;
    }
    let scale = tight.min.abs().max(tight.max.abs()).max_element();
    tight.padded(scale * 1e-6 + f32::MIN_POSITIVE)
}
