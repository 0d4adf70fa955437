//! Ray-primitive intersection routines, one file per primitive.
//!
//! Every routine has the same contract: given a ray with a unit direction and an open
//! interval `(t_min, t_max)`, return the smallest `t` in the interval at which the ray
//! meets the primitive, or `None`. NaN inputs give `None`, never a panic. These scalar
//! versions are the reference that faster (SIMD) versions are tested against.
//!
//! Beside each scalar routine live its SIMD twins over [`crate::simd`]: a packet kernel
//! (`*_packet`: eight rays of a [`crate::ray::RayPacket`] against one primitive, with an
//! `active` mask) and, for the kinds that fill BVH leaves, a leaf kernel (`*_leaf`: one
//! ray against a pack of eight primitives side by side, padded with inert entries). Both
//! run one lane-wise body that repeats the scalar arithmetic operation for operation, in
//! the same order and without fused multiply-adds, so every lane equals the scalar answer
//! bit for bit (`tests/simd.rs`). They return a hit mask and `t` lanes; the `t` of a lane
//! that misses is unspecified, and lanes outside `active` always miss.

mod aabb;
mod cone;
mod interval;
mod plane;
mod sphere;
mod triangle;

pub use aabb::{aabb, aabb_leaf, aabb_normal, aabb_packet, BoxPack8};
pub use cone::{cone, cone_normal, cone_packet};
pub use interval::{beyond, widen_entry, widen_exit, BoxRay, BoxRay8, Intervals8};
pub use plane::{plane, plane_packet};
pub use sphere::{sphere, sphere_leaf, sphere_packet, SpherePack8};
pub use triangle::{
    triangle, triangle_leaf, triangle_packet, TriangleHit, TriangleHit8, TrianglePack8,
};

use crate::simd::{F32x8, Mask8};

/// The relative error bound of three rounded operations, `3 u / (1 - 3 u)` with `u` the
/// unit roundoff (PBRT's `gamma(3)`): a slab distance `(bound - origin) * inv_dir` is off
/// by at most this much of itself.
pub const GAMMA_3: f32 = 3.0 * (f32::EPSILON / 2.0) / (1.0 - 3.0 * (f32::EPSILON / 2.0));

/// The first of two roots `near <= far` that lies in `(t_min, t_max)`: the entry of a
/// convex shape, or its exit when the origin is inside.
fn first_root_in(near: f32, far: f32, t_min: f32, t_max: f32) -> Option<f32> {
    if near > t_min && near < t_max {
        Some(near)
    } else if far > t_min && far < t_max {
        Some(far)
    } else {
        None
    }
}

/// [`first_root_in`] lane by lane: the hit mask and the chosen root.
#[inline(always)]
fn first_root_in8(near: F32x8, far: F32x8, t_min: F32x8, t_max: F32x8) -> (Mask8, F32x8) {
    let near_in = near.gt(t_min) & near.lt(t_max);
    let far_in = far.gt(t_min) & far.lt(t_max);
    (near_in | far_in, near_in.select(near, far))
}

/// The larger of `a` and `b`, ignoring a NaN operand as `f32::max` does, and `b` on a
/// tie: `f32::max` may return either zero for `max(-0.0, 0.0)`, which would leave the
/// SIMD twin ([`F32x8::max_num`]) no fixed answer to equal.
#[inline]
pub fn max_num(a: f32, b: f32) -> f32 {
    if a > b || b.is_nan() {
        a
    } else {
        b
    }
}
