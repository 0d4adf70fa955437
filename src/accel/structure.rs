//! [`Structure`], the queries every acceleration structure answers over the bounded
//! primitives of a [`Geometry`] (planes are [`Tracer`](super::Tracer)'s).

use super::count::{Count, CountLanes};
use super::hit::ClosestHit;
use crate::intersect::{PacketQuery, RayQuery};
use crate::ray::lane_mask;
use crate::scene::Geometry;
use crate::simd::{for_lanes, Bits, LaneBits, PACKET};

/// An acceleration structure's queries, each answered as brute force answers it
/// (`accel::ClosestHit`'s tie rule), each counting its work into a [`Count`] (nothing, for
/// [`NoCount`](super::count::NoCount)). A structure without a packet walk of its own
/// answers packets lane by lane, by the defaults.
pub trait Structure {
    /// Offers `closest` the hit of `query` that wins within `(query.t_min, closest.limit())`.
    fn closest<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        closest: &mut ClosestHit,
        count: &mut C,
    );

    /// Whether a primitive blocks `query` within `(query.t_min, t_max)`.
    fn occluded<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
    ) -> bool;

    /// [`Structure::closest`] for each active lane `k` of `query`'s packet, into
    /// `closest[k]`.
    fn closest_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        closest: &mut [ClosestHit; PACKET],
        count: &mut C::Lanes,
    ) {
        for_lanes(query.packet.active, |k| {
            let mut lane = C::default();
            self.closest(geometry, &query.lane(k), &mut closest[k], &mut lane);
            count.add_lane(k, &lane);
        });
    }

    /// The active lanes of `query`'s packet that a primitive blocks within their interval
    /// (`packet.t_max`), as a bit mask.
    fn occluded_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        count: &mut C::Lanes,
    ) -> LaneBits {
        let packet = query.packet;
        lane_mask(|k| {
            packet.active.has(k) && {
                let mut lane = C::default();
                let blocked = self.occluded(geometry, &query.lane(k), packet.t_max[k], &mut lane);
                count.add_lane(k, &lane);
                blocked
            }
        })
    }
}
