//! Brute force: every bounded primitive is tested against every ray.

use glam::Vec3;

use crate::ray::{Hit, PrimKind, Ray};
use crate::scene::Geometry;

const BOUNDED: [PrimKind; 5] = [
    PrimKind::Sphere,
    PrimKind::MovingSphere,
    PrimKind::Triangle,
    PrimKind::Box,
    PrimKind::Cone,
];

/// The closest hit among the primitives of one kind.
pub fn closest_of_kind(
    geometry: &Geometry,
    kind: PrimKind,
    ray: &Ray,
    inv_dir: Vec3,
    t_min: f32,
    mut t_max: f32,
) -> Option<Hit> {
    let mut closest = None;
    for prim in geometry.ids(kind) {
        if let Some(h) = geometry.intersect(prim, ray, inv_dir, t_min, t_max) {
            t_max = h.t;
            closest = Some(Hit {
                t: h.t,
                prim,
                u: h.u,
                v: h.v,
            });
        }
    }
    closest
}

pub fn closest(
    geometry: &Geometry,
    ray: &Ray,
    inv_dir: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<Hit> {
    BOUNDED.iter().fold(None, |best: Option<Hit>, &kind| {
        let t_max = best.map_or(t_max, |h| h.t);
        closest_of_kind(geometry, kind, ray, inv_dir, t_min, t_max).or(best)
    })
}

pub fn occluded(geometry: &Geometry, ray: &Ray, inv_dir: Vec3, t_min: f32, t_max: f32) -> bool {
    BOUNDED.iter().any(|&kind| {
        geometry.ids(kind).any(|prim| {
            geometry
                .intersect(prim, ray, inv_dir, t_min, t_max)
                .is_some()
        })
    })
}
