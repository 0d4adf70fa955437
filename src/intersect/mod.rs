//! Ray-primitive intersection routines, one file per primitive.
//!
//! Every routine has the same contract: given a ray with a unit direction and an open
//! interval `(t_min, t_max)`, return the smallest `t` in the interval at which the ray
//! meets the primitive, or `None`. NaN inputs give `None`, never a panic. These scalar
//! versions are the reference that faster (SIMD) versions are tested against.

mod aabb;
mod cone;
mod plane;
mod sphere;
mod triangle;

pub use aabb::{aabb, aabb_normal};
pub use cone::{cone, cone_normal};
pub use plane::plane;
pub use sphere::sphere;
pub use triangle::{triangle, TriangleHit};

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
