//! The stream renderer: a batch of a tile's samples traced breadth first, one depth at a
//! time. Each depth is a [`Queue`] (arrays in the worker's arena): its rays, then their
//! hits' shadow rays light by light, are traced as packets of eight by the stream
//! scheduler ([`crate::accel::stream`], which `bench` measures), the hits are shaded,
//! and the rays they spawn make the next depth's queue. A depth's hits are gathered eight
//! to a [`HitBlock`] (structure of arrays), whose points are recomputed on the surfaces
//! ([`Shader::hit_points8`]) and offset off them ([`spawn_origin8`]), whose shadow rays
//! are set up ([`crate::render::light::Emitter::sample8`]; one that leaves a primitive
//! from inside is answered by that primitive's test alone, as the walk would answer it:
//! [`crate::accel::Tracer::occluded_by_own8`]), whose Blinn-Phong sums are
//! taken ([`super::shade::Phong8`]) and whose reflected and transmitted rays are made
//! ([`Bounce8`]) eight lanes at a time, light by light in the scalar order, bit for bit
//! as the scalar path. A depth queues its reflected rays, then its transmitted ones; those
//! made inside a primitive (refracted into it, reflected within it) that it and the
//! primitives near it answer as they are made ([`crate::accel::Tracer::closest_inside8`])
//! go between the two, with their hits, and are not walked: they stay the lanes of the
//! block that made them, which become a hit block at the next depth without a gathering.
//! Each of the three is a part of the queue of its own, filled where its rays are made.
//! A block that no light reaches (inside glass, most) skips its Blinn-Phong sums. Once
//! the deepest queue is shaded, colours flow back up: each ray's colour, clamped if it
//! hit something, is added to its parent's with its weight, in the order the scalar
//! [`Shader::trace`] adds them, so the image is the scalar one byte for byte. Where the
//! render counts (`C` of [`crate::accel::count`]), each ray's work flows up with its
//! colour, so that a pixel's cost is what its samples' rays took.

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::Vec3;

use super::light::Receiver;
use super::sampler::Sample;
use super::shade::{Bounce8, Optics8, Phong8, Profile, RayCounts, RayKind, Shader, Work, EPS};
use crate::accel::count::{Count, CountLanes};
use crate::accel::stream::{self, Answers};
use crate::accel::InsideAnswers;
use crate::intersect::{spawn_origin8, Rays8, SurfacePoint8};
use crate::prim::{PrimId, PrimKind};
use crate::ray::{Hit, Ray};
use crate::scene::Geometry;
use crate::simd::{bits_where, for_lanes, F32x8, Mask8, Vec3x8};

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
pub(super) struct Queue<'a, C> {
    rays: Parts<'a, Ray>,
    answered: ArenaVec<'a, AnsweredRays>,
    lineage: Parts<'a, Lineage>,
    seen: Parts<'a, Seen>,
    /// Where the render counts, each ray's work by kind: its own, its shadow rays' and
    /// its children's, added as they are traced; empty otherwise.
    work: Parts<'a, Work<C>>,
}

/// The parts of a queue, in the queue's order.
const WALKED_REFLECTED: usize = 0;
const ANSWERED: usize = 1;
const WALKED_TRANSMITTED: usize = 2;

/// One array per part of a queue.
type Parts<'a, T> = [ArenaVec<'a, T>; 3];

/// Parts with room for `capacity[p]` elements in part `p`.
fn parts_in<T>(capacity: [usize; 3], arena: &Bump) -> Parts<'_, T> {
    std::array::from_fn(|p| ArenaVec::with_capacity_in(capacity[p], arena))
}

/// The bits of a [`slot`] that hold the place in the part.
const PLACE_BITS: u32 = 30;

/// Where ray `place` of part `part` lies in its queue: both in one number.
fn slot(part: usize, place: usize) -> u32 {
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
fn at<'v, T>(parts: &'v Parts<T>, slot: u32) -> &'v T {
    let (part, place) = split(slot);
    &parts[part][place]
}

fn at_mut<'v, T>(parts: &'v mut Parts<T>, slot: u32) -> &'v mut T {
    let (part, place) = split(slot);
    &mut parts[part][place]
}

/// The rays that one hit block made inside one primitive, in the block's lanes, with the
/// hits that primitive and its near ones gave them
/// ([`crate::accel::Tracer::closest_inside8`]): they stay lanes from the block that made
/// them to the block of their hits, never single rays queued and gathered again.
#[derive(Clone, Copy)]
struct AnsweredRays {
    /// The lanes held (`answers.answered`), each one's closest hit and primitives tested.
    answers: InsideAnswers,
    /// The lanes that hold reflected rays; the others held are transmitted.
    reflected: u8,
    rays: Rays8,
}

impl AnsweredRays {
    /// The kind of the ray of lane `k`.
    fn kind(&self, k: usize) -> RayKind {
        if self.reflected >> k & 1 != 0 {
            RayKind::Reflection
        } else {
            RayKind::Refraction
        }
    }
}

/// Where a queued ray comes from, and how its colour counts there.
#[derive(Clone, Copy)]
struct Lineage {
    sample: Sample,
    /// The index of the medium the ray travels in.
    ior: f32,
    /// At depth 1 the tile's pixel of the sample; deeper, the [`slot`] in the previous
    /// depth's queue of the hit that spawned the ray.
    parent: u32,
    /// The factor of the ray's colour in its parent's (one at depth 1).
    weight: Vec3,
}

/// What a traced ray sees: the background if it missed; else its hit's local colour, to
/// which its children's colours are added before it is clamped.
#[derive(Clone, Copy)]
struct Seen {
    colour: Vec3,
    /// Whether the ray hit something (only hits clamp their colour).
    hit: bool,
}

impl Seen {
    /// The colour as the ray's parent takes it.
    fn taken(&self) -> Vec3 {
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
    fn with_capacities_in(capacity: [usize; 3], arena: &'a Bump) -> Self {
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
    pub(super) fn primary_in(capacity: usize, arena: &'a Bump) -> Self {
        Self::with_capacities_in([capacity, 0, 0], arena)
    }

    /// Queues a primary sample of the tile's pixel `pixel`.
    pub(super) fn push_primary(&mut self, ray: Ray, sample: Sample, pixel: u32) {
        let lineage = Lineage {
            sample,
            ior: 1.0,
            parent: pixel,
            weight: Vec3::ONE,
        };
        self.push(WALKED_REFLECTED, ray, lineage);
    }

    /// Queues a ray in the walked part `part`.
    fn push(&mut self, part: usize, ray: Ray, lineage: Lineage) {
        push_reserved(&mut self.rays[part], ray);
        push_reserved(&mut self.lineage[part], lineage);
    }

    /// Queues rays answered as they were made, with each lane's lineage (`lineage(k)`
    /// for lane `k`; the lanes not held are padding).
    fn push_answered(&mut self, rays: AnsweredRays, lineage: impl Fn(usize) -> Lineage) {
        push_reserved(&mut self.answered, rays);
        for k in 0..8 {
            push_reserved(&mut self.lineage[ANSWERED], lineage(k));
        }
    }

    /// The rays of the walked parts.
    fn walked(&self) -> usize {
        self.rays[WALKED_REFLECTED].len() + self.rays[WALKED_TRANSMITTED].len()
    }

    fn len(&self) -> usize {
        let answered = self.answered.iter();
        self.walked()
            + answered
                .map(|r| r.answers.answered.count_ones() as usize)
                .sum::<usize>()
    }

    /// Calls `f` with the place, the lineage and what it saw of each ray of part `part`,
    /// in order.
    #[inline(always)]
    fn for_each_ray(&self, part: usize, mut f: impl FnMut(usize, &Lineage, &Seen)) {
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
fn push_reserved<T>(vec: &mut ArenaVec<T>, value: T) {
    assert!(vec.len() < vec.capacity(), "a queue outgrew its room");
    vec.push(value);
}

/// Traces the primary samples of `primary` and every ray they spawn, and adds each
/// sample's colour to `sums` and its rays' work to `work` at its pixel, in queue order;
/// `rays` counts the rays traced.
pub(super) fn trace<'a, C: Count>(
    shader: &Shader,
    arena: &'a Bump,
    primary: Queue<'a, C>,
    (sums, work): (&mut [Vec3], &mut [Work<C>]),
    rays: &mut RayCounts,
) {
    rays.add(RayKind::Primary, primary.len() as u64);
    let mut depths = ArenaVec::with_capacity_in(shader.options.max_depth as usize, arena);
    let mut queue = primary;
    for depth in 1.. {
        let next = shade_depth(shader, arena, &mut queue, depth, rays);
        depths.push(queue);
        if next.len() == 0 {
            break;
        }
        queue = next;
    }
    // Children add to their parents, deepest first, in queue order: a parent's reflected
    // child comes before its transmitted one.
    while let Some(queue) = depths.pop() {
        for p in 0..3 {
            match depths.last_mut() {
                Some(parents) => queue.for_each_ray(p, |j, lineage, seen| {
                    let Lineage { parent, weight, .. } = *lineage;
                    at_mut(&mut parents.seen, parent).colour += weight * seen.taken();
                    if C::ON {
                        at_mut(&mut parents.work, parent).merge(&queue.work[p][j]);
                    }
                }),
                None => queue.for_each_ray(p, |j, lineage, seen| {
                    let pixel = lineage.parent as usize;
                    sums[pixel] += seen.taken();
                    if C::ON {
                        work[pixel].merge(&queue.work[p][j]);
                    }
                }),
            }
        }
    }
}

/// Traces the rays of `queue`, which are of `depth`, and their shadow rays, sets each
/// one's local colour, and returns the queue of the rays their hits spawn. Kept out of
/// line: inlined, it spread into the tile loop, whose primary samples then took longer.
#[inline(never)]
fn shade_depth<'a, C: Count>(
    shader: &Shader,
    arena: &'a Bump,
    queue: &mut Queue<'a, C>,
    depth: u32,
    rays: &mut RayCounts,
) -> Queue<'a, C> {
    let n = queue.len();
    // The walked parts' hits, a part at a time.
    let longest = queue.rays[WALKED_REFLECTED]
        .len()
        .max(queue.rays[WALKED_TRANSMITTED].len());
    let mut hits = ArenaVec::with_capacity_in(longest, arena);
    let room = queue.walked().div_ceil(8) + queue.answered.len();
    let mut blocks = HitBlocks::with_capacity_in(room, arena);
    for p in 0..3 {
        let (rays, seen, work) = (&queue.rays[p], &mut queue.seen[p], &mut queue.work[p]);
        if p == ANSWERED {
            for (r, answered) in queue.answered.iter().enumerate() {
                // Every lane hit (those not held are padding, never read).
                for _ in 0..8 {
                    push_reserved(
                        seen,
                        Seen {
                            colour: Vec3::ZERO,
                            hit: true,
                        },
                    );
                }
                if C::ON {
                    for k in 0..8 {
                        let mut own = Work::default();
                        if answered.answers.answered >> k & 1 != 0 {
                            let tested = answered.answers.tested[k];
                            own.add(answered.kind(k), &answered_work::<C>(tested));
                        }
                        work.push(own);
                    }
                }
                blocks.push_answered(shader, answered, r);
            }
            continue;
        }
        let kind = ray_kind(depth, p);
        hits.clear();
        stream::closest_rays_counting::<C>(shader.tracer, rays, |found, lanes| {
            if C::ON {
                for k in 0..found.len() {
                    let mut own = Work::default();
                    own.add(kind, &lanes.lane(k));
                    work.push(own);
                }
            }
            hits.extend_from_slice(found);
        });
        blocks.take(
            shader,
            (depth, p),
            rays.iter().zip(hits.iter().copied()),
            seen,
        );
    }
    let blocks = blocks.finish(shader);
    let shadows = ShadowQueue::trace(shader, arena, queue, &blocks);
    rays.shadow += shadows.traced;
    for (b, block) in blocks.iter().enumerate() {
        // The lanes some light reaches; the others keep the black their hits were taken
        // with (inside glass, most blocks).
        let lit_by_any = (0..shadows.lights).fold(0, |lanes, light| {
            lanes | shadows.lit[light * blocks.len() + b]
        });
        if lit_by_any == 0 {
            continue;
        }
        let phong = Phong8::new(block.material.map(|m| &shader.phong[m as usize]));
        let mut colour = Vec3x8::ZERO;
        for light in 0..shadows.lights {
            let entry = light * blocks.len() + b;
            let lit = Mask8::from_bitmask(shadows.lit[entry]);
            if lit.none() {
                continue;
            }
            let l = shadows.dir[entry];
            let added = phong.light(block.nf, block.dir, l, shadows.colour[light], lit);
            // The scalar sum skips an unlit light: its lanes keep their bits.
            colour = lit.select_vec(colour + added, colour);
        }
        for_lanes(lit_by_any, |k| {
            at_mut(&mut queue.seen, block.ray[k]).colour = colour.lane(k)
        });
    }

    // A hit spawns a reflected and a transmitted ray at most, computed eight hits at a
    // time ([`Bounce8`]). The reflected rays come first and the transmitted ones after
    // them, as Embree's stream renderer orders them: a packet then holds rays that leave
    // a surface on one side (a glass ball's reflections outside it, its refractions
    // inside), and each parent still receives its reflected colour before its
    // transmitted one, the scalar order of its sum.
    // The rays that start inside primitives and that the primitives answer, reflected and
    // transmitted, are queued between the other reflected rays and transmitted ones: a
    // parent has one of them at most (its reflected ray if it arrived from inside, else
    // its transmitted one), so each parent's reflected ray still comes before its
    // transmitted one.
    let room = if depth < shader.options.max_depth {
        n
    } else {
        0
    };
    let answered_room = if room > 0 { 8 * blocks.len() } else { 0 };
    let mut next = Queue::with_capacities_in([room, answered_room, room], arena);
    if room > 0 {
        for block in &blocks {
            let optics = Optics8::new(block.material.map(|m| &shader.scene.materials[m as usize]));
            if optics.spawns_none() {
                continue;
            }
            let ior_here = F32x8::from_array(block.ray.map(|i| at(&queue.lineage, i).ior));
            let inside = Mask8::from_bitmask(block.inside);
            let schlick = shader.options.schlick;
            let bounce = Bounce8::new(block.dir, block.nf, inside, ior_here, &optics, schlick);
            let reflected = bounce.reflected.bitmask() & block.lanes;
            let through = bounce.transmitted.bitmask() & block.lanes;
            // Where transmitted rays start (any point where none is).
            let inward = if through != 0 {
                block.offset(-block.nf)
            } else {
                block.origin
            };
            let answered = block.inner_answers(shader, &bounce, inward, (reflected, through));
            // A lane's ray inside its primitive is its reflected one if it arrived from
            // inside.
            let (inner_reflected, inner_through) = match &answered {
                Some(rays) => (rays.reflected, rays.answers.answered & !rays.reflected),
                None => (0, 0),
            };
            let reflected_lineage = |k: usize| {
                let i = block.ray[k];
                let Lineage { sample, ior, .. } = *at(&queue.lineage, i);
                Lineage {
                    sample: sample.spawn(0),
                    ior,
                    parent: i,
                    weight: bounce.reflected_weight.lane(k),
                }
            };
            let transmitted_lineage = |k: usize| {
                let i = block.ray[k];
                Lineage {
                    sample: at(&queue.lineage, i).sample.spawn(1),
                    ior: bounce.ior_next.lane(k),
                    parent: i,
                    weight: bounce.transmitted_weight.lane(k),
                }
            };
            for_lanes(reflected & !inner_reflected, |k| {
                let lineage = reflected_lineage(k);
                let mirror = bounce.mirror.lane(k);
                let ray = Ray {
                    origin: block.origin.lane(k),
                    dir: shader.fuzz(mirror, block.nf.lane(k), lineage.sample.rng),
                    time: block.time.lane(k),
                };
                next.push(WALKED_REFLECTED, ray, lineage);
            });
            if let Some(rays) = answered {
                next.push_answered(rays, |k| {
                    if inner_reflected >> k & 1 != 0 {
                        reflected_lineage(k)
                    } else {
                        transmitted_lineage(k)
                    }
                });
            }
            for_lanes(through & !inner_through, |k| {
                let ray = Ray {
                    origin: inward.lane(k),
                    dir: bounce.refracted.lane(k),
                    time: block.time.lane(k),
                };
                next.push(WALKED_TRANSMITTED, ray, transmitted_lineage(k));
            });
        }
        for p in [WALKED_REFLECTED, WALKED_TRANSMITTED] {
            rays.add(ray_kind(depth + 1, p), next.rays[p].len() as u64);
        }
        for answered in &next.answered {
            let (lanes, reflected) = (answered.answers.answered, answered.reflected);
            rays.add(RayKind::Reflection, u64::from(reflected.count_ones()));
            rays.add(
                RayKind::Refraction,
                u64::from((lanes & !reflected).count_ones()),
            );
        }
    }
    next
}

/// The kind of the rays of the walked part `part` of a queue of depth `depth`.
fn ray_kind(depth: u32, part: usize) -> RayKind {
    match part {
        _ if depth == 1 => RayKind::Primary,
        WALKED_REFLECTED => RayKind::Reflection,
        _ => RayKind::Refraction,
    }
}

/// Eight hits of a depth as structure of arrays, for the shading of eight at a time.
#[derive(Clone, Copy, Debug)]
struct HitBlock {
    /// The lanes that hold a hit; the others repeat the first that does.
    lanes: u8,
    /// The lanes whose ray arrived from inside the surface.
    inside: u8,
    /// The kind of every lane's primitive, where they share one with an interior
    /// ([`Geometry::has_interior`]: the shadow rays of the lanes that arrived from inside
    /// meet their primitive again, [`crate::accel::Tracer::occluded_by_own8`]; the rays
    /// they spawn inside it may meet it alone, [`HitBlock::inner_answers`]), and each
    /// lane's primitive.
    interior: Option<PrimKind>,
    prim: [PrimId; 8],
    /// Whether the points have error bounds (all but with the `course` profile).
    bounded: bool,
    /// Each lane's [`slot`] in the depth's queue.
    ray: [u32; 8],
    material: [u32; 8],
    point: Vec3x8,
    /// The normal facing the ray.
    nf: Vec3x8,
    /// The bound of the point's error on each axis, where `bounded`.
    error: Vec3x8,
    /// Where shadow and reflected rays start ([`HitBlock::offset`]).
    origin: Vec3x8,
    /// The direction of the ray that hit.
    dir: Vec3x8,
    /// The shutter time of the ray that hit, which its shadow and spawned rays keep.
    time: F32x8,
}

impl HitBlock {
    /// The block of the hits `hits` of the rays `rays` (at the [`slot`]s `ray`), whose
    /// first `count` lanes are hits and whose others repeat lane 0: the points recomputed
    /// on the surfaces ([`Shader::hit_points8`]).
    fn new(
        shader: &Shader,
        rays: &[Ray; 8],
        ray: &[u32; 8],
        hits: &[Hit; 8],
        count: usize,
    ) -> Self {
        let prims = hits.map(|h| h.prim);
        let kind = PrimId::shared_kind(&prims);
        let surface = shader.hit_points8(rays, hits, kind);
        let dir = Vec3x8::from_fn(|k| rays[k].dir);
        let time = F32x8::from_array(rays.map(|r| r.time));
        let lanes = ((1u16 << count) - 1) as u8;
        Self::on_surface(shader, &surface, (dir, time), (prims, kind), (*ray, lanes))
    }

    /// The block of the hits of `rays`, record `record` of the answered part: the points
    /// recomputed on the surfaces from the lanes as they are ([`Shader::inside_points8`]),
    /// the lanes not held repeating the first held, as a gathered block's do.
    fn answered(shader: &Shader, rays: &AnsweredRays, record: usize) -> Self {
        let AnsweredRays {
            mut answers,
            rays:
                Rays8 {
                    mut origin,
                    mut dir,
                    mut time,
                },
            ..
        } = *rays;
        let lanes = answers.answered;
        let mut ray = std::array::from_fn(|k| slot(ANSWERED, 8 * record + k));
        if lanes != u8::MAX {
            let first = lanes.trailing_zeros() as usize;
            let held = Mask8::from_bitmask(lanes);
            origin = held.select_vec(origin, Vec3x8::splat(origin.lane(first)));
            dir = held.select_vec(dir, Vec3x8::splat(dir.lane(first)));
            time = held.select(time, F32x8::splat(time.lane(first)));
            answers.t = held.select(answers.t, F32x8::splat(answers.t.lane(first)));
            for_lanes(!lanes, |k| {
                (answers.prim[k], ray[k]) = (answers.prim[first], ray[first]);
            });
        }
        let prims = answers.prim;
        let kind = PrimId::shared_kind(&prims);
        let surface = shader.inside_points8(&answers, &Rays8 { origin, dir, time }, kind);
        Self::on_surface(shader, &surface, (dir, time), (prims, kind), (ray, lanes))
    }

    /// The block of hits on the points `surface`, by the rays of directions `dir` at the
    /// shutter times `time`, on the primitives `prims` (of kind `kind` if they share one),
    /// at the slots `ray`, of which the lanes `lanes` hold hits: the normals turned to face
    /// the rays, as [`Shader::hit_point`] turns them, and the points offset off them.
    #[inline(always)]
    fn on_surface(
        shader: &Shader,
        surface: &SurfacePoint8,
        (dir, time): (Vec3x8, F32x8),
        (prims, kind): ([PrimId; 8], Option<PrimKind>),
        (ray, lanes): ([u32; 8], u8),
    ) -> Self {
        let inside = dir.dot(surface.normal).gt(F32x8::ZERO);
        let nf = inside.select_vec(-surface.normal, surface.normal);
        let geometry = &shader.tracer.geometry;
        let mut block = HitBlock {
            lanes,
            inside: inside.bitmask(),
            interior: kind.filter(|&kind| Geometry::has_interior(kind)),
            prim: prims,
            bounded: shader.options.profile == Profile::Standard,
            ray,
            material: geometry.materials8(kind, prims),
            point: surface.point,
            nf,
            error: surface.error,
            origin: Vec3x8::ZERO,
            dir,
            time,
        };
        block.origin = block.offset(nf);
        block
    }

    /// The rays this block spawns inside its primitives with their closest hits, where the
    /// primitives answer them ([`crate::accel::Tracer::closest_inside8`]): of the lanes
    /// that reflect (`reflected`) those that arrived from inside, and of those that
    /// transmit (`through`, starting at `inward`) those that arrived from outside. Fuzzy
    /// reflections are left to the walks.
    fn inner_answers(
        &self,
        shader: &Shader,
        bounce: &Bounce8,
        inward: Vec3x8,
        (reflected, through): (u8, u8),
    ) -> Option<AnsweredRays> {
        let mirrors = if shader.reflects_as_mirrors() {
            reflected & self.inside
        } else {
            0
        };
        let lanes = mirrors | (through & !self.inside);
        if self.interior.is_none() || lanes == 0 {
            return None;
        }
        // The lanes in the primitive of the first: eight lanes of one are the rule.
        let prim = self.prim[lanes.trailing_zeros() as usize];
        let lanes = lanes & bits_where::<u8>(|k| self.prim[k] == prim);
        let inside = Mask8::from_bitmask(self.inside);
        let rays = Rays8 {
            origin: inside.select_vec(self.origin, inward),
            dir: inside.select_vec(bounce.mirror, bounce.refracted),
            time: self.time,
        };
        let answers = shader.tracer.closest_inside8(prim, &rays, lanes);
        (answers.answered != 0).then_some(AnsweredRays {
            answers,
            reflected: answers.answered & self.inside,
            rays,
        })
    }

    /// The points offset towards `side` (a unit vector per lane), as `Surface::origin`
    /// offsets them: by the error bound ([`spawn_origin8`]), or with the `course` profile
    /// by [`EPS`]. Shadow and reflected rays start on the side of the facing normal
    /// (`origin`), transmitted rays on the other.
    fn offset(&self, side: Vec3x8) -> Vec3x8 {
        if self.bounded {
            spawn_origin8(self.point, self.error, side)
        } else {
            self.point + side.scale(F32x8::splat(EPS))
        }
    }
}

/// A depth's hits gathered into [`HitBlock`]s, in queue order.
struct HitBlocks<'a> {
    blocks: ArenaVec<'a, HitBlock>,
    /// The hits of the block being gathered, their rays' indices in the queue, and the
    /// rays, each stored in place as it comes: an array built whole and moved is copied
    /// in wide loads that wait on the narrow stores just made (no store forwarding).
    ray: [u32; 8],
    hits: [Hit; 8],
    rays: [Ray; 8],
    filled: usize,
}

impl<'a> HitBlocks<'a> {
    /// Room for `blocks` blocks.
    fn with_capacity_in(blocks: usize, arena: &'a Bump) -> Self {
        // What the lanes hold before their first hit: each is written before it is read.
        let none = Hit {
            t: 0.0,
            prim: PrimId::new(PrimKind::ALL[0], 0),
            u: 0.0,
            v: 0.0,
        };
        HitBlocks {
            blocks: ArenaVec::with_capacity_in(blocks, arena),
            ray: [0; 8],
            hits: [none; 8],
            rays: [Ray::new(Vec3::ZERO, Vec3::ZERO); 8],
            filled: 0,
        }
    }

    /// Takes the rays of the walked part `part` of a queue of depth `depth` with what each
    /// found: a hit into the blocks, each ray's colour so far into `seen`.
    #[inline(always)]
    fn take<'r>(
        &mut self,
        shader: &Shader,
        (depth, part): (u32, usize),
        found: impl Iterator<Item = (&'r Ray, Option<Hit>)>,
        seen: &mut ArenaVec<Seen>,
    ) {
        for (j, (ray, hit)) in found.enumerate() {
            match hit {
                Some(hit) => {
                    seen.push(Seen {
                        colour: Vec3::ZERO,
                        hit: true,
                    });
                    self.push(shader, slot(part, j), ray, hit);
                }
                None => {
                    seen.push(Seen {
                        colour: shader.background(ray.dir, depth),
                        hit: false,
                    });
                }
            }
        }
    }

    /// Adds the hit `hit` of `ray`, ray `index` of the depth's queue.
    fn push(&mut self, shader: &Shader, index: u32, ray: &Ray, hit: Hit) {
        self.ray[self.filled] = index;
        self.hits[self.filled] = hit;
        self.rays[self.filled] = *ray;
        self.filled += 1;
        if self.filled == 8 {
            self.close(shader);
        }
    }

    /// Makes the hits gathered a block, its free lanes repeating its lane 0.
    fn close(&mut self, shader: &Shader) {
        let count = self.filled;
        if count == 0 {
            return;
        }
        for k in count..8 {
            (self.ray[k], self.hits[k], self.rays[k]) = (self.ray[0], self.hits[0], self.rays[0]);
        }
        let block = HitBlock::new(shader, &self.rays, &self.ray, &self.hits, count);
        self.blocks.push(block);
        self.filled = 0;
    }

    /// Adds the block of the hits of `rays`, record `record` of the answered part, made
    /// whole, not gathered (out of line, so that the block is made in place, not copied).
    #[inline(never)]
    fn push_answered(&mut self, shader: &Shader, rays: &AnsweredRays, record: usize) {
        let block = HitBlock::answered(shader, rays, record);
        push_reserved(&mut self.blocks, block);
    }

    fn finish(mut self, shader: &Shader) -> ArenaVec<'a, HitBlock> {
        self.close(shader);
        self.blocks
    }
}

/// The shadow rays of one depth's hit blocks, and the lanes each light reaches.
struct ShadowQueue<'a> {
    lights: usize,
    /// Entry `light * blocks + block`: the unit directions from the block's hits towards
    /// the light's point.
    dir: ArenaVec<'a, Vec3x8>,
    /// Entry `light * blocks + block`: the lanes that face the light and whose shadow
    /// ray is not blocked.
    lit: ArenaVec<'a, u8>,
    /// Each light's colour.
    colour: ArenaVec<'a, Vec3>,
    /// The shadow rays traced.
    traced: u64,
}

impl<'a> ShadowQueue<'a> {
    /// Sets up every hit's shadow ray to every light, eight hits at a time, and traces
    /// them light by light, packed eight at a time as they are made
    /// ([`stream::Packer`]: the stream scheduler's packets of a stream grouped by light).
    /// Where the render counts, each shadow ray's work goes to the ray whose hit it leaves.
    fn trace<C: Count>(
        shader: &Shader,
        arena: &'a Bump,
        queue: &mut Queue<C>,
        blocks: &[HitBlock],
    ) -> Self {
        let lights = shader.lights.len();
        let mut dir = ArenaVec::with_capacity_in(lights * blocks.len(), arena);
        let mut lit = ArenaVec::with_capacity_in(lights * blocks.len(), arena);
        let mut colour = ArenaVec::with_capacity_in(lights, arena);
        let mut packer = stream::Packer::new(shader.tracer);
        let mut traced = 0;
        let (lineage, work) = (&queue.lineage, &mut queue.work);
        // The work of the shadow ray tagged `tag` (its entry and lane, below).
        let mut counted = |tag: u32, count: C| {
            let block = &blocks[(tag >> 3) as usize % blocks.len()];
            at_mut(work, block.ray[(tag & 7) as usize])
                .shadow
                .add(&count);
        };
        for (index, emitter) in shader.lights.iter().enumerate() {
            colour.push(emitter.colour());
            for block in blocks {
                let receiver = Receiver {
                    point: block.point,
                    normal: block.nf,
                    origin: block.origin,
                };
                let sample = |k: usize| at(lineage, block.ray[k]).sample;
                let (facing, incident) = emitter.sample8(index, &receiver, sample);
                let facing = facing.bitmask() & block.lanes;
                let entry = lit.len() as u32;
                let ray = |k: usize| Ray {
                    origin: block.origin.lane(k),
                    dir: incident.dir.lane(k),
                    time: block.time.lane(k),
                };
                // A ray that leaves a primitive from inside is answered by that
                // primitive's test, as the walk would answer it, without the walk.
                let mut walked = facing;
                let enclosed = match block.interior {
                    Some(_) => facing & block.inside,
                    None => 0,
                };
                if let (Some(kind), true) = (block.interior, enclosed != 0) {
                    let rays = Rays8 {
                        origin: block.origin,
                        dir: incident.dir,
                        time: block.time,
                    };
                    let own = shader.tracer.occluded_by_own8(
                        (kind, block.prim.map(|p| p.index())),
                        &rays,
                        0.0,
                        incident.distance,
                    );
                    let answered = enclosed & own.bitmask();
                    walked &= !answered;
                    if C::ON {
                        for_lanes(answered, |k| {
                            counted(entry << 3 | k as u32, answered_work(1))
                        });
                    }
                }
                dir.push(incident.dir);
                lit.push(walked);
                traced += u64::from(facing.count_ones());
                for_lanes(walked, |k| {
                    // The ray's entry (light and block) and lane, for `unlit`.
                    let tag = entry << 3 | k as u32;
                    let distance = incident.distance.lane(k);
                    let mut answer = Answers {
                        blocked: |tag| unlit(&mut lit, tag),
                        counted: &mut counted,
                    };
                    packer.push(&ray(k), distance, tag, &mut answer);
                });
            }
        }
        packer.flush(&mut Answers {
            blocked: |tag| unlit(&mut lit, tag),
            counted: &mut counted,
        });
        ShadowQueue {
            lights,
            dir,
            lit,
            colour,
            traced,
        }
    }
}

/// Takes the lane of a blocked shadow ray, tagged with its entry and lane, out of the lanes
/// its light reaches.
fn unlit(lit: &mut [u8], tag: u32) {
    lit[tag as usize >> 3] &= !(1 << (tag & 7));
}

/// The work of a ray that primitives' own tests answered, `tested` of them, without a walk:
/// it counts as traced, with those tests.
fn answered_work<C: Count>(tested: u32) -> C {
    let mut count = C::default();
    count.ray();
    count.prims(tested);
    count
}
