//! Closest-hit and occlusion queries over a scene's geometry.
//!
//! Every accelerator sits behind [`Accel`], so the renderer does not care which one runs.
//! Planes are unbounded and never go into a structure: [`Tracer`] tests them on their own
//! beside whatever the accelerator returns.

mod none;

use glam::Vec3;

use crate::ray::{Hit, PrimKind, Ray};
use crate::scene::Geometry;

/// The acceleration structure over a scene's bounded primitives.
#[derive(Clone, Debug)]
pub enum Accel {
    /// Every ray is tested against every primitive: the reference the others are checked
    /// against.
    None,
}

/// Answers ray queries for one scene: the accelerator for bounded primitives, planes apart.
pub struct Tracer<'s> {
    pub geometry: &'s Geometry,
    pub accel: Accel,
}

impl<'s> Tracer<'s> {
    pub fn new(geometry: &'s Geometry, accel: Accel) -> Self {
        Tracer { geometry, accel }
    }

    /// The closest hit with `t` in `(t_min, t_max)`.
    pub fn closest(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let inv_dir = ray.dir.recip();
        let bounded = match &self.accel {
            Accel::None => none::closest(self.geometry, ray, inv_dir, t_min, t_max),
        };
        let t_max = bounded.map_or(t_max, |h| h.t);
        self.closest_plane(ray, inv_dir, t_min, t_max).or(bounded)
    }

    /// Whether anything blocks the ray within `(t_min, t_max)`.
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let inv_dir = ray.dir.recip();
        self.closest_plane(ray, inv_dir, t_min, t_max).is_some()
            || match &self.accel {
                Accel::None => none::occluded(self.geometry, ray, inv_dir, t_min, t_max),
            }
    }

    fn closest_plane(&self, ray: &Ray, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        none::closest_of_kind(self.geometry, PrimKind::Plane, ray, inv_dir, t_min, t_max)
    }
}
