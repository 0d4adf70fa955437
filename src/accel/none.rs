//! Brute force: every bounded primitive is tested against every ray.

use glam::Vec3;

use super::hit::ClosestHit;
use crate::prim::PrimKind;
use crate::ray::Ray;
use crate::scene::Geometry;

pub fn closest(
    geometry: &Geometry,
    ray: &Ray,
    inv_dir: Vec3,
    t_min: f32,
    closest: &mut ClosestHit,
) {
    for kind in PrimKind::BOUNDED {
        for prim in geometry.ids(kind) {
            closest.test(geometry, prim, ray, inv_dir, t_min);
        }
    }
}

pub fn occluded(geometry: &Geometry, ray: &Ray, inv_dir: Vec3, t_min: f32, t_max: f32) -> bool {
    PrimKind::BOUNDED.iter().any(|&kind| {
        geometry.ids(kind).any(|prim| {
            geometry
                .intersect(prim, ray, inv_dir, t_min, t_max)
                .is_some()
        })
    })
}
