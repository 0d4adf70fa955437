//! Brute force: every bounded primitive is tested against every ray.

use super::hit::ClosestHit;
use super::structure::Structure;
use crate::intersect::RayQuery;
use crate::prim::PrimKind;
use crate::scene::Geometry;

/// No structure at all: the reference every other one answers as.
#[derive(Clone, Copy, Debug)]
pub struct BruteForce;

impl Structure for BruteForce {
    fn closest(&self, geometry: &Geometry, query: &RayQuery, closest: &mut ClosestHit) {
        for kind in PrimKind::BOUNDED {
            for prim in geometry.ids(kind) {
                closest.test(geometry, prim, query);
            }
        }
    }

    fn occluded(&self, geometry: &Geometry, query: &RayQuery, t_max: f32) -> bool {
        PrimKind::BOUNDED.iter().any(|&kind| {
            geometry
                .ids(kind)
                .any(|prim| geometry.intersect(prim, query, t_max).is_some())
        })
    }
}
