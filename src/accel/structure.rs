//! [`Structure`], the queries every acceleration structure answers over the bounded
//! primitives of a [`Geometry`] (planes are [`Tracer`](super::Tracer)'s).

use super::hit::ClosestHit;
use crate::intersect::{RayQuery, RayQuery8};
use crate::ray::lane_mask;
use crate::scene::Geometry;
use crate::simd::for_lanes;

/// An acceleration structure's queries, each answered as brute force answers it
/// (`accel::ClosestHit`'s tie rule). A structure without a packet walk of its own
/// answers packets lane by lane, by the defaults.
pub trait Structure {
    /// Offers `closest` the hit of `query` that wins within `(query.t_min, closest.limit())`.
    fn closest(&self, geometry: &Geometry, query: &RayQuery, closest: &mut ClosestHit);

    /// Whether a primitive blocks `query` within `(query.t_min, t_max)`.
    fn occluded(&self, geometry: &Geometry, query: &RayQuery, t_max: f32) -> bool;

    /// [`Structure::closest`] for each active lane `k` of `query`'s packet, into
    /// `closest[k]`.
    fn closest_packet(
        &self,
        geometry: &Geometry,
        query: &RayQuery8,
        closest: &mut [ClosestHit; 8],
    ) {
        for_lanes(query.packet.active, |k| {
            self.closest(geometry, &query.lane(k), &mut closest[k]);
        });
    }

    /// The active lanes of `query`'s packet that a primitive blocks within their interval
    /// (`packet.t_max`), as a bit mask.
    fn occluded_packet(&self, geometry: &Geometry, query: &RayQuery8) -> u8 {
        let packet = query.packet;
        lane_mask(|k| {
            packet.active & (1 << k) != 0
                && self.occluded(geometry, &query.lane(k), packet.t_max[k])
        })
    }
}
