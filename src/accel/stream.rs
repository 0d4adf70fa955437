//! The stream scheduler: many independent queries traced as packets of [`PACKET`] rays
//! through [`Tracer::closest_packet`] and [`Tracer::occluded_packet`], each answered as its
//! single ray. The renderer's queues (`render/stream.rs`) and the protocol's `p3trace-stream`
//! path (`bench.rs`) both trace through it.
//!
//! Closest-hit queries go in the order they come: the renderer's queues keep a tile's
//! rays together (and side by side, read in place: [`closest_rays_counting`]), the
//! protocol's sets their pixel blocks. Occlusion queries are grouped by
//! the light they head for ([`Occlusions`]), in their order within each light, so that a
//! packet's rays share an end point. Both are packed a packet at a time by [`Packer`], which
//! traces a packet as soon as it is full: the renderer's shadow rays, made light by light,
//! go to one directly, and [`Occlusions`] keeps one for each light.
//! What the other groupings cost, by end point and by direction octant, is in
//! docs/did-not-pay.md. Each query's work comes back with its answer when
//! the stream is traced with a [`Count`] that counts ([`closest_counting`],
//! [`Occlusions::trace`]); [`NoCount`] hands back nothing.

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::Vec3;

use super::count::{Count, CountLanes, NoCount};
use super::Tracer;
use crate::ray::{Hit, Ray, RayPacket};
use crate::simd::{for_lanes, Bits, LaneBits, PACKET};

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

/// Traces `queries` in their order as packets, and gives `hits` each packet's
/// queries and their closest hits.
#[inline]
pub fn closest<Q: Query>(
    tracer: &Tracer,
    queries: impl IntoIterator<Item = Q>,
    mut hits: impl FnMut(&[Q], &[Option<Hit>]),
) {
    closest_counting::<Q, NoCount>(tracer, queries, |lanes, found, _| hits(lanes, found));
}

/// [`closest`], with each packet's work lane by lane.
#[inline(never)]
pub fn closest_counting<Q: Query, C: Count>(
    tracer: &Tracer,
    queries: impl IntoIterator<Item = Q>,
    mut hits: impl FnMut(&[Q], &[Option<Hit>], &C::Lanes),
) {
    packets(
        queries,
        |packet| {
            let mut count = C::Lanes::default();
            (
                tracer.closest_packet_counting::<C>(packet, &mut count),
                count,
            )
        },
        |lanes, (found, count)| hits(lanes, &found[..lanes.len()], &count),
    );
}

/// [`closest_counting`] for rays stored side by side, each over its whole length (the
/// renderer's queues): a full packet's rays are read where they lie, as a copy of them,
/// stored just before the packet reads them lane by lane, would wait on store forwarding.
#[inline(never)]
pub fn closest_rays_counting<C: Count>(
    tracer: &Tracer,
    rays: &[Ray],
    mut hits: impl FnMut(&[Option<Hit>], &C::Lanes),
) {
    for chunk in rays.chunks(PACKET) {
        // A partial packet's missing lanes repeat its first ray and are inactive.
        let padded: [Ray; PACKET];
        let lanes: &[Ray; PACKET] = match chunk.try_into() {
            Ok(full) => full,
            Err(_) => {
                padded = std::array::from_fn(|k| *chunk.get(k).unwrap_or(&chunk[0]));
                &padded
            }
        };
        let packet = RayPacket::new(lanes).with_active(LaneBits::first(chunk.len()));
        let mut count = C::Lanes::default();
        let found = tracer.closest_packet_counting::<C>(&packet, &mut count);
        hits(&found[..chunk.len()], &count);
    }
}

/// A stream of occlusion queries, each pushed with the light it heads for, traced grouped
/// by light.
pub struct Occlusions<'a, Q> {
    queries: ArenaVec<'a, Q>,
    light: ArenaVec<'a, u32>,
    /// One more than the largest light pushed.
    lights: usize,
}

impl<'a, Q: Query> Occlusions<'a, Q> {
    /// A stream with room for `capacity` queries: growing a vector in an arena copies it
    /// and leaves the old one behind, so streams are made at the size they may reach.
    pub fn with_capacity_in(capacity: usize, arena: &'a Bump) -> Self {
        Occlusions {
            queries: ArenaVec::with_capacity_in(capacity, arena),
            light: ArenaVec::with_capacity_in(capacity, arena),
            lights: 0,
        }
    }

    /// Adds `query`, which heads for light `light`, and returns its index.
    pub fn push(&mut self, light: u32, query: Q) -> u32 {
        self.lights = self.lights.max(light as usize + 1);
        self.light.push(light);
        self.queries.push(query);
        self.queries.len() as u32 - 1
    }

    /// The queries in the order they were pushed.
    pub fn queries(&self) -> &[Q] {
        &self.queries
    }

    /// Whether each query is blocked, and its work, by index: the queries in their
    /// order, each light's packed by a [`Packer`] of its own, so that nothing is sorted (a
    /// counting sort of their indices by light was 12% of the instructions of the
    /// dragon's shadow rays).
    #[inline(never)]
    pub fn trace<C: Count>(&self, tracer: &Tracer, arena: &'a Bump) -> (&'a [bool], &'a [C]) {
        let blocked = arena.alloc_slice_fill_copy(self.queries.len(), false);
        let counts = arena.alloc_slice_fill_copy(self.queries.len(), C::default());
        let mut answer = Answers {
            blocked: |i: u32| blocked[i as usize] = true,
            counted: |i: u32, count: C| counts[i as usize] = count,
        };
        let mut packers =
            ArenaVec::from_iter_in((0..self.lights).map(|_| Packer::new(tracer)), arena);
        for (i, (query, &light)) in self.queries.iter().zip(&self.light).enumerate() {
            packers[light as usize].push(query.ray(), query.t_max(), i as u32, &mut answer);
        }
        for packer in &mut packers {
            packer.flush(&mut answer);
        }
        (blocked, counts)
    }
}

/// What a [`Packer`] hands back of a traced packet: `blocked` takes the tag of each query
/// that is blocked, `counted` each query's tag and work (only where `C` counts).
pub struct Answers<B, K> {
    pub blocked: B,
    pub counted: K,
}

/// [`Answers`] that take the blocked queries alone.
impl<T, B: FnMut(T)> Answers<B, fn(T, NoCount)> {
    pub fn blocked(blocked: B) -> Self {
        Answers {
            blocked,
            counted: |_, _| {},
        }
    }
}

/// Occlusion queries packed [`PACKET`] at a time in the order they come, each packet
/// traced through [`Tracer::occluded_packet`] as soon as it is full (or flushed), the tags
/// of its blocked queries handed back. A stream grouped by light goes through it directly;
/// [`Occlusions`] keeps one for each light.
pub struct Packer<'t, T, C = NoCount> {
    tracer: &'t Tracer<'t>,
    rays: [Ray; PACKET],
    t_max: [f32; PACKET],
    tags: [T; PACKET],
    len: usize,
    count: std::marker::PhantomData<C>,
}

impl<'t, T: Copy + Default, C: Count> Packer<'t, T, C> {
    pub fn new(tracer: &'t Tracer<'t>) -> Self {
        Packer {
            tracer,
            rays: [Ray::new(Vec3::ZERO, Vec3::ZERO); PACKET],
            t_max: [0.0; PACKET],
            tags: [T::default(); PACKET],
            len: 0,
            count: std::marker::PhantomData,
        }
    }

    /// Adds the query along `ray` within `(0, t_max)`, tagged `tag`; when that fills a
    /// packet, traces it and gives `answer` what it found.
    #[inline(always)]
    pub fn push<B: FnMut(T), K: FnMut(T, C)>(
        &mut self,
        ray: &Ray,
        t_max: f32,
        tag: T,
        answer: &mut Answers<B, K>,
    ) {
        let k = self.len;
        (self.rays[k], self.t_max[k], self.tags[k]) = (*ray, t_max, tag);
        self.len += 1;
        if self.len == PACKET {
            self.flush(answer);
        }
    }

    /// Traces the queries added since the last packet; a partial packet's missing lanes
    /// repeat its first query and are inactive.
    pub fn flush<B: FnMut(T), K: FnMut(T, C)>(&mut self, answer: &mut Answers<B, K>) {
        let n = self.len;
        if n == 0 {
            return;
        }
        for k in n..PACKET {
            (self.rays[k], self.t_max[k]) = (self.rays[0], self.t_max[0]);
        }
        let active = LaneBits::first(n);
        let packet = RayPacket::new(&self.rays)
            .with_t_max(self.t_max)
            .with_active(active);
        let mut count = C::Lanes::default();
        for_lanes(
            self.tracer
                .occluded_packet_counting::<C>(&packet, &mut count),
            |k| (answer.blocked)(self.tags[k]),
        );
        if C::ON {
            for_lanes(active, |k| (answer.counted)(self.tags[k], count.lane(k)));
        }
        self.len = 0;
    }
}

/// Traces `queries` in their order as packets by `trace`, and gives `answer`
/// each packet's queries and its answer. A packet's missing lanes repeat its first query
/// and are inactive.
fn packets<Q: Query, A>(
    queries: impl IntoIterator<Item = Q>,
    trace: impl Fn(&RayPacket) -> A,
    mut answer: impl FnMut(&[Q], A),
) {
    let mut queries = queries.into_iter();
    while let Some(first) = queries.next() {
        let mut lanes = [first; PACKET];
        let mut n = 1;
        // `zip` asks `queries` for no more than the free lanes.
        for (lane, query) in lanes[1..].iter_mut().zip(queries.by_ref()) {
            *lane = query;
            n += 1;
        }
        let rays = lanes.map(|q| *q.ray());
        let packet = RayPacket::new(&rays)
            .with_t_max(lanes.map(|q| q.t_max()))
            .with_active(LaneBits::first(n));
        answer(&lanes[..n], trace(&packet));
    }
}
