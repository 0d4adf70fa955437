//! The closest-hit rule every structure keeps: the smallest `t`, and at equal `t` the
//! smallest [`PrimId`], whatever order the primitives are tested in.

use crate::intersect::{PacketQuery, RayQuery};
use crate::prim::PrimId;
use crate::ray::Hit;
use crate::scene::Geometry;
use crate::simd::{for_lanes, F32xP, LaneBits, PACKET};

/// The closest hit found so far along a ray, with the tie rule of brute force: at equal
/// `t` the smaller [`PrimId`] wins, whatever order the primitives are tested in.
#[derive(Clone, Copy, Debug)]
pub struct ClosestHit {
    /// Private, so that only `offer` changes it, and `limit` with it.
    hit: Option<Hit>,
    /// The best hit's `t`, or the ray's end before any hit: kept apart from `hit` so
    /// that a packet reads its lanes' limits without a branch each.
    limit: f32,
}

impl ClosestHit {
    pub fn new(t_max: f32) -> Self {
        ClosestHit {
            hit: None,
            limit: t_max,
        }
    }

    /// The best hit so far.
    #[inline]
    pub fn hit(&self) -> Option<Hit> {
        self.hit
    }

    /// Hits at or beyond this distance cannot win; a hit exactly at it may (a tie).
    #[inline]
    pub fn limit(&self) -> f32 {
        self.limit
    }

    /// The upper end of the interval for the next test: the routines take an open
    /// interval, so a tie with the best hit needs the next float up.
    pub fn bound(&self) -> f32 {
        match self.hit {
            Some(_) => self.limit.next_up(),
            None => self.limit,
        }
    }

    /// Keeps `hit` if it is closer than the best, or as close with a smaller id.
    pub fn offer(&mut self, hit: Hit) {
        let wins = self
            .hit
            .is_none_or(|best| hit.t < best.t || (hit.t == best.t && hit.prim < best.prim));
        if wins {
            self.hit = Some(hit);
            self.limit = hit.t;
        }
    }

    /// Tests `prim` and keeps its hit if it wins.
    pub fn test(&mut self, geometry: &Geometry, prim: PrimId, query: &RayQuery) {
        if let Some(h) = geometry.intersect(prim, query, self.bound()) {
            self.offer(Hit {
                t: h.t,
                prim,
                u: h.u,
                v: h.v,
            });
        }
    }
}

/// [`ClosestHit::test`] for the lanes `lanes` of `query`'s packet: `prim` against all of
/// them at once by its packet kernel, each lane within its own bound, and each lane's hit
/// offered to its closest hit.
pub fn test_packet(
    closest: &mut [ClosestHit; PACKET],
    geometry: &Geometry,
    prim: PrimId,
    query: &PacketQuery,
    lanes: LaneBits,
) {
    let bounds = F32xP::from_array(closest.each_ref().map(ClosestHit::bound));
    let hits = geometry.intersect_packet(prim, query, bounds, lanes);
    let (t, u, v) = (hits.t.to_array(), hits.u.to_array(), hits.v.to_array());
    for_lanes(hits.hit.bitmask() & lanes, |k| {
        closest[k].offer(Hit {
            t: t[k],
            prim,
            u: u[k],
            v: v[k],
        });
    });
}
