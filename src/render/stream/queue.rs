//! A depth's [`Queue`]: its rays in three parts (the walked reflected rays, the rays
//! answered inside primitives as they were made, the walked transmitted rays), each
//! ray's lineage (its sample, its parent and its weight there), what it sees, and where
//! the render counts, its work; a ray's [`slot`] names its part and place.

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::Vec3;

use super::super::sampler::Sample;
use crate::accel::count::Count;
use crate::accel::count::{RayKind, Work};
use crate::accel::InsideAnswers;
use crate::intersect::Rays8;
use crate::ray::Ray;
use crate::simd::for_lanes;

/// The rays of one depth, and what they bring back, in three parts, each filled where its
/// rays are made (no part is copied after another): the reflected rays that are walked
/// ([`WALKED_REFLECTED`], at depth 1 the primary rays), then the reflected and the
/// transmitted rays that start inside primitives, which gave their hits as the rays were
/// made ([`ANSWERED`], kept eight lanes to an [`AnsweredRays`] as their hit block made
/// them), then the transmitted rays that are walked. The queue's order is the parts' in
/// turn; a ray's [`slot`] names its part and its place there (in the answered part, its
/// record's times eight plus its lane: the lanes a record does not hold pad that part's
/// arrays). In the walked parts the rays lie side by side, where the scheduler reads them;
/// all else a ray carries is in two records, a push each (a push per field was a twentieth
/// of a render's instructions).
pub(in crate::render) struct Queue<'a, C> {
    pub(super) rays: Parts<'a, Ray>,
    pub(super) answered: ArenaVec<'a, AnsweredRays>,
    pub(super) lineage: Parts<'a, Lineage>,
    pub(super) seen: Parts<'a, Seen>,
    /// Where the render counts, each ray's work by kind: its own, its shadow rays' and
    /// its children's, added as they are traced; empty otherwise.
    pub(super) work: Parts<'a, Work<C>>,
}

/// The parts of a queue, in the queue's order.
pub(super) const WALKED_REFLECTED: usize = 0;
pub(super) const ANSWERED: usize = 1;
pub(super) const WALKED_TRANSMITTED: usize = 2;

/// One array per part of a queue.
pub(super) type Parts<'a, T> = [ArenaVec<'a, T>; 3];

/// Parts with room for `capacity[p]` elements in part `p`.
fn parts_in<T>(capacity: [usize; 3], arena: &Bump) -> Parts<'_, T> {
    std::array::from_fn(|p| ArenaVec::with_capacity_in(capacity[p], arena))
}

/// The bits of a [`slot`] that hold the place in the part.
const PLACE_BITS: u32 = 30;

/// Where ray `place` of part `part` lies in its queue: both in one number.
pub(super) fn slot(part: usize, place: usize) -> u32 {
    (part as u32) << PLACE_BITS | place as u32
}

/// The part and the place in it that `slot` names.
fn split(slot: u32) -> (usize, usize) {
    (
        (slot >> PLACE_BITS) as usize,
        (slot & ((1 << PLACE_BITS) - 1)) as usize,
    )
}

/// The element at `slot` of a queue's parts.
pub(super) fn at<'v, T>(parts: &'v Parts<T>, slot: u32) -> &'v T {
    let (part, place) = split(slot);
    &parts[part][place]
}

pub(super) fn at_mut<'v, T>(parts: &'v mut Parts<T>, slot: u32) -> &'v mut T {
    let (part, place) = split(slot);
    &mut parts[part][place]
}

/// The rays that one hit block made inside one primitive, in the block's lanes, with the
/// hits that primitive and its near ones gave them
/// ([`crate::accel::Tracer::closest_inside8`]): they stay lanes from the block that made
/// them to the block of their hits, never single rays queued and gathered again.
#[derive(Clone, Copy)]
pub(super) struct AnsweredRays {
    /// The lanes held (`answers.answered`), each one's closest hit and primitives tested.
    pub(super) answers: InsideAnswers,
    /// The lanes that hold reflected rays; the others held are transmitted.
    pub(super) reflected: u8,
    pub(super) rays: Rays8,
}

impl AnsweredRays {
    /// The kind of the ray of lane `k`.
    pub(super) fn kind(&self, k: usize) -> RayKind {
        if self.reflected >> k & 1 != 0 {
            RayKind::Reflection
        } else {
            RayKind::Refraction
        }
    }
}

/// Where a queued ray comes from, and how its colour counts there.
#[derive(Clone, Copy)]
pub(super) struct Lineage {
    pub(super) sample: Sample,
    /// The index of the medium the ray travels in.
    pub(super) ior: f32,
    /// At depth 1 the tile's pixel of the sample; deeper, the [`slot`] in the previous
    /// depth's queue of the hit that spawned the ray.
    pub(super) parent: u32,
    /// The factor of the ray's colour in its parent's (one at depth 1).
    pub(super) weight: Vec3,
}

/// What a traced ray sees: the background if it missed; else its hit's local colour, to
/// which its children's colours are added before it is clamped.
#[derive(Clone, Copy)]
pub(super) struct Seen {
    pub(super) colour: Vec3,
    /// Whether the ray hit something (only hits clamp their colour).
    pub(super) hit: bool,
}

impl Seen {
    /// The colour as the ray's parent takes it.
    pub(super) fn taken(&self) -> Vec3 {
        if self.hit {
            self.colour.clamp(Vec3::ZERO, Vec3::ONE)
        } else {
            self.colour
        }
    }
}

impl<'a, C: Count> Queue<'a, C> {
    /// A queue with room for `capacity[p]` rays in part `p` (in the answered part, a
    /// multiple of eight): growing a vector in an arena copies it and leaves the old one
    /// behind, so queues are made at the size they may reach.
    pub(super) fn with_capacities_in(capacity: [usize; 3], arena: &'a Bump) -> Self {
        assert!(
            capacity.iter().all(|&c| c < 1 << PLACE_BITS),
            "a queue too long for its slots"
        );
        let mut walked = capacity;
        walked[ANSWERED] = 0;
        Queue {
            rays: parts_in(walked, arena),
            answered: ArenaVec::with_capacity_in(capacity[ANSWERED] / 8, arena),
            lineage: parts_in(capacity, arena),
            seen: parts_in(capacity, arena),
            work: parts_in(if C::ON { capacity } else { [0; 3] }, arena),
        }
    }

    /// A queue with room for `capacity` primary samples.
    pub(in crate::render) fn primary_in(capacity: usize, arena: &'a Bump) -> Self {
        Self::with_capacities_in([capacity, 0, 0], arena)
    }

    /// Queues a primary sample of the tile's pixel `pixel`.
    pub(in crate::render) fn push_primary(&mut self, ray: Ray, sample: Sample, pixel: u32) {
        let lineage = Lineage {
            sample,
            ior: 1.0,
            parent: pixel,
            weight: Vec3::ONE,
        };
        self.push(WALKED_REFLECTED, ray, lineage);
    }

    /// Queues a ray in the walked part `part`.
    pub(super) fn push(&mut self, part: usize, ray: Ray, lineage: Lineage) {
        push_reserved(&mut self.rays[part], ray);
        push_reserved(&mut self.lineage[part], lineage);
    }

    /// Queues rays answered as they were made, with each lane's lineage (`lineage(k)`
    /// for lane `k`; the lanes not held are padding).
    pub(super) fn push_answered(&mut self, rays: AnsweredRays, lineage: impl Fn(usize) -> Lineage) {
        push_reserved(&mut self.answered, rays);
        for k in 0..8 {
            push_reserved(&mut self.lineage[ANSWERED], lineage(k));
        }
    }

    /// The rays of the walked parts.
    pub(super) fn walked(&self) -> usize {
        self.rays[WALKED_REFLECTED].len() + self.rays[WALKED_TRANSMITTED].len()
    }

    pub(super) fn len(&self) -> usize {
        let answered = self.answered.iter();
        self.walked()
            + answered
                .map(|r| r.answers.answered.count_ones() as usize)
                .sum::<usize>()
    }

    /// Calls `f` with the place, the lineage and what it saw of each ray of part `part`,
    /// in order.
    #[inline(always)]
    pub(super) fn for_each_ray(&self, part: usize, mut f: impl FnMut(usize, &Lineage, &Seen)) {
        let (lineage, seen) = (&self.lineage[part], &self.seen[part]);
        if part == ANSWERED {
            let lanes = lineage.chunks_exact(8).zip(seen.chunks_exact(8));
            for (r, (rays, (lineage, seen))) in self.answered.iter().zip(lanes).enumerate() {
                let (lineage, seen): (&[_; 8], &[_; 8]) =
                    (lineage.try_into().unwrap(), seen.try_into().unwrap());
                for_lanes(rays.answers.answered, |k| {
                    f(8 * r + k, &lineage[k], &seen[k])
                });
            }
        } else {
            for (j, (lineage, seen)) in lineage.iter().zip(seen).enumerate() {
                f(j, lineage, seen);
            }
        }
    }
}

/// Pushes `value` onto `vec`, made with room for it: a queue's vectors are made at the
/// size they may reach. A push that may grow its vector calls out, and around that call
/// the spawning loops kept every field of a ray on the stack; this one cannot call.
#[inline(always)]
pub(super) fn push_reserved<T>(vec: &mut ArenaVec<T>, value: T) {
    assert!(vec.len() < vec.capacity(), "a queue outgrew its room");
    vec.push(value);
}

/// The kind of the rays of the walked part `part` of a queue of depth `depth`.
pub(super) fn ray_kind(depth: u32, part: usize) -> RayKind {
    match part {
        _ if depth == 1 => RayKind::Primary,
        WALKED_REFLECTED => RayKind::Reflection,
        _ => RayKind::Refraction,
    }
}
