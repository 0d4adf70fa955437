//! Brute force: every bounded primitive is tested against every ray.

use super::count::Count;
use super::hit::ClosestHit;
use super::structure::Structure;
use crate::intersect::RayQuery;
use crate::prim::PrimKind;
use crate::scene::Geometry;

/// No structure at all: the reference every other one answers as.
#[derive(Clone, Copy, Debug)]
pub struct BruteForce;

impl Structure for BruteForce {
    fn closest<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        closest: &mut ClosestHit,
        count: &mut C,
    ) {
        for kind in PrimKind::BOUNDED {
            count.prims(geometry.count(kind) as u32);
            for prim in geometry.ids(kind) {
                closest.test(geometry, prim, query);
            }
        }
    }

    fn occluded<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
    ) -> bool {
        PrimKind::BOUNDED.iter().any(|&kind| {
            geometry.ids(kind).any(|prim| {
                count.prims(1);
                geometry.intersect(prim, query, t_max).is_some()
            })
        })
    }
}
