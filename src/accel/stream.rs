//! The stream scheduler: many independent queries traced as packets of eight through
//! [`Tracer::closest_packet`] and [`Tracer::occluded_packet`], each answered as its single
//! ray. The renderer's queues (`render/stream.rs`) and the protocol's `p3trace-stream`
//! path (`bench.rs`) both trace through it.
//!
//! Closest-hit queries go in the order they come: the renderer's queues keep a tile's
//! rays together, the protocol's sets their pixel blocks. Occlusion queries are grouped by
//! the light they head for ([`Occlusions`]), in their order within each light, so that a
//! packet's rays share an end point; the last packet of one light takes the first rays of
//! the next. What the other groupings cost, by end point and by direction octant, is in
//! BENCHMARKS.md ("What did not pay").

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;

use super::Tracer;
use crate::ray::{Hit, Ray, RayPacket};

/// One query of a stream: a ray and the far end of its interval, which starts at 0.
pub trait Query: Copy {
    fn ray(&self) -> &Ray;
    fn t_max(&self) -> f32;
}

/// A closest-hit query over the whole ray.
impl Query for Ray {
    fn ray(&self) -> &Ray {
        self
    }

    fn t_max(&self) -> f32 {
        f32::INFINITY
    }
}

/// A query by reference.
impl<Q: Query> Query for &Q {
    fn ray(&self) -> &Ray {
        (*self).ray()
    }

    fn t_max(&self) -> f32 {
        (*self).t_max()
    }
}

/// Traces `queries` in their order as packets of eight, and gives `hits` each packet's
/// queries and their closest hits.
#[inline(never)]
pub fn closest<Q: Query>(
    tracer: &Tracer,
    queries: impl IntoIterator<Item = Q>,
    mut hits: impl FnMut(&[Q], &[Option<Hit>]),
) {
    packets(
        queries,
        |packet| tracer.closest_packet(packet),
        |lanes, found| hits(lanes, &found[..lanes.len()]),
    );
}

/// A stream of occlusion queries, each pushed with the light it heads for, traced grouped
/// by light.
pub struct Occlusions<'a, Q> {
    queries: ArenaVec<'a, Q>,
    light: ArenaVec<'a, u32>,
    /// Whether the queries came light by light, so that they are grouped already.
    grouped: bool,
}

impl<'a, Q: Query> Occlusions<'a, Q> {
    /// A stream with room for `capacity` queries: growing a vector in an arena copies it
    /// and leaves the old one behind, so streams are made at the size they may reach.
    pub fn with_capacity_in(capacity: usize, arena: &'a Bump) -> Self {
        Occlusions {
            queries: ArenaVec::with_capacity_in(capacity, arena),
            light: ArenaVec::with_capacity_in(capacity, arena),
            grouped: true,
        }
    }

    /// Adds `query`, which heads for light `light`, and returns its index.
    pub fn push(&mut self, light: u32, query: Q) -> u32 {
        self.grouped &= self.light.last().is_none_or(|&last| last <= light);
        self.light.push(light);
        self.queries.push(query);
        self.queries.len() as u32 - 1
    }

    /// The queries in the order they were pushed.
    pub fn queries(&self) -> &[Q] {
        &self.queries
    }

    /// Whether each query is blocked, by index: the queries light by light (as they came,
    /// or by a stable counting sort of their indices), as packets of eight.
    #[inline(never)]
    pub fn trace(&self, tracer: &Tracer, arena: &'a Bump) -> ArenaVec<'a, bool> {
        let n = self.queries.len();
        let occluded = |packet: &RayPacket| tracer.occluded_packet(packet);
        let lanes = |answer: u8, lanes: usize| (0..lanes).map(move |k| answer & (1 << k) != 0);
        if self.grouped {
            let mut blocked = ArenaVec::with_capacity_in(n, arena);
            packets(&self.queries, occluded, |queries, answer| {
                blocked.extend(lanes(answer, queries.len()))
            });
            return blocked;
        }
        // Each light's first place in the order, then its next free one.
        let lights = self.light.iter().max().map_or(0, |&l| l as usize + 1);
        let mut next = bumpalo::vec![in arena; 0u32; lights + 1];
        for &light in &self.light {
            next[light as usize + 1] += 1;
        }
        for light in 1..next.len() {
            next[light] += next[light - 1];
        }
        let mut order = bumpalo::vec![in arena; 0u32; n];
        for (i, &light) in self.light.iter().enumerate() {
            let place = &mut next[light as usize];
            order[*place as usize] = i as u32;
            *place += 1;
        }
        let mut blocked = bumpalo::vec![in arena; false; n];
        let mut traced = order.iter();
        let in_order = order.iter().map(|&i| &self.queries[i as usize]);
        packets(in_order, occluded, |queries, answer| {
            // The lanes first: `zip` then takes no index beyond the packet's.
            for (b, &i) in lanes(answer, queries.len()).zip(traced.by_ref()) {
                blocked[i as usize] = b;
            }
        });
        blocked
    }
}

/// Traces `queries` in their order as packets of eight by `trace`, and gives `answer`
/// each packet's queries and its answer. A packet's missing lanes repeat its first query
/// and are inactive.
fn packets<Q: Query, A>(
    queries: impl IntoIterator<Item = Q>,
    trace: impl Fn(&RayPacket) -> A,
    mut answer: impl FnMut(&[Q], A),
) {
    let mut queries = queries.into_iter();
    while let Some(first) = queries.next() {
        let mut lanes = [first; 8];
        let mut n = 1;
        // `zip` asks `queries` for no more than the free lanes.
        for (lane, query) in lanes[1..].iter_mut().zip(queries.by_ref()) {
            *lane = query;
            n += 1;
        }
        let rays = lanes.map(|q| *q.ray());
        let packet = RayPacket::new(&rays)
            .with_t_max(lanes.map(|q| q.t_max()))
            .with_active((1u16 << n).wrapping_sub(1) as u8);
        answer(&lanes[..n], trace(&packet));
    }
}
