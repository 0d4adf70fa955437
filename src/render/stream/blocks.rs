//! A depth's hits gathered eight to a [`HitBlock`] (structure of arrays), in queue order:
//! the walked rays traced and their hits gathered ([`trace_hits`]), the rays answered
//! inside primitives made a block as they are; each block's points recomputed on the
//! surfaces and offset off them, and the rays it spawns inside its primitives answered
//! there ([`HitBlock::inner_answers`]).

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::Vec3;

use super::super::shade::{Bounce8, Profile, Shader, EPS};
use super::super::skybox::{Skybox, Texel};
use super::answered_work;
use super::queue::{push_reserved, ray_kind, slot, AnsweredRays, Queue, Seen};
use super::queue::{ANSWERED, WALKED_REFLECTED, WALKED_TRANSMITTED};
use crate::accel::count::Work;
use crate::accel::count::{Count, CountLanes};
use crate::accel::stream;
use crate::intersect::{spawn_origin8, Rays8, SurfacePoint8};
use crate::prim::{PrimId, PrimKind};
use crate::ray::{Hit, Ray};
use crate::scene::Geometry;
use crate::simd::{bits_where, for_lanes, F32x8, Mask8, Vec3x8};

/// Eight hits of a depth as structure of arrays, for the shading of eight at a time.
#[derive(Clone, Copy, Debug)]
pub(super) struct HitBlock {
    /// The lanes that hold a hit; the others repeat the first that does.
    pub(super) lanes: u8,
    /// The lanes whose ray arrived from inside the surface.
    pub(super) inside: u8,
    /// The kind of every lane's primitive, where they share one with an interior
    /// ([`Geometry::has_interior`]: the shadow rays of the lanes that arrived from inside
    /// meet their primitive again, [`crate::accel::Tracer::occluded_by_own8`]; the rays
    /// they spawn inside it may meet it alone, [`HitBlock::inner_answers`]), and each
    /// lane's primitive.
    pub(super) interior: Option<PrimKind>,
    pub(super) prim: [PrimId; 8],
    /// Whether the points have error bounds (all but with the `course` profile).
    bounded: bool,
    /// Each lane's [`slot`] in the depth's queue.
    pub(super) ray: [u32; 8],
    pub(super) material: [u32; 8],
    pub(super) point: Vec3x8,
    /// The normal facing the ray.
    pub(super) nf: Vec3x8,
    /// The bound of the point's error on each axis, where `bounded`.
    error: Vec3x8,
    /// Where shadow and reflected rays start ([`HitBlock::offset`]).
    pub(super) origin: Vec3x8,
    /// The direction of the ray that hit.
    pub(super) dir: Vec3x8,
    /// The shutter time of the ray that hit, which its shadow and spawned rays keep.
    pub(super) time: F32x8,
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
    pub(super) fn inner_answers(
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
    pub(super) fn offset(&self, side: Vec3x8) -> Vec3x8 {
        if self.bounded {
            spawn_origin8(self.point, self.error, side)
        } else {
            self.point + side.scale(F32x8::splat(EPS))
        }
    }
}

/// Missed rays' skybox texels are read this many at a time: each is asked of the cache
/// as its ray comes (the course's faces hold 12 MiB each, which rays leaving a glass read
/// at random), and the colours are read once this many have come, so that their cache
/// misses overlap rather than each stall the loop in turn.
const SKY_READS: usize = 16;

/// The texels of up to [`SKY_READS`] missed rays, and the places of their rays' colours.
struct SkyReads {
    seen: [usize; SKY_READS],
    texels: [Texel; SKY_READS],
    len: usize,
}

impl SkyReads {
    fn new() -> Self {
        SkyReads {
            seen: [0; SKY_READS],
            texels: [Texel::default(); SKY_READS],
            len: 0,
        }
    }

    /// Adds the ray whose colour is `seen[place]`, which sees `texel` of `sky`.
    fn push(&mut self, sky: &Skybox, place: usize, texel: Texel) {
        sky.prefetch(texel);
        (self.seen[self.len], self.texels[self.len]) = (place, texel);
        self.len += 1;
    }

    /// Writes the colours of the rays added, of `depth`, into `seen`.
    fn read(&mut self, shader: &Shader, sky: &Skybox, depth: u32, seen: &mut ArenaVec<Seen>) {
        for (&place, &texel) in self.seen.iter().zip(&self.texels).take(self.len) {
            seen[place].colour = shader.sky_background(sky, texel, depth);
        }
        self.len = 0;
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
        let mut sky_reads = SkyReads::new();
        for (j, (ray, hit)) in found.enumerate() {
            match hit {
                Some(hit) => {
                    seen.push(Seen {
                        colour: Vec3::ZERO,
                        hit: true,
                    });
                    self.push(shader, slot(part, j), ray, hit);
                }
                None => match shader.skybox {
                    Some(sky) => {
                        seen.push(Seen {
                            colour: Vec3::ZERO,
                            hit: false,
                        });
                        sky_reads.push(sky, seen.len() - 1, sky.texel(ray.dir));
                        if sky_reads.len == SKY_READS {
                            sky_reads.read(shader, sky, depth, seen);
                        }
                    }
                    None => seen.push(Seen {
                        colour: shader.background(ray.dir, depth),
                        hit: false,
                    }),
                },
            }
        }
        if let Some(sky) = shader.skybox {
            sky_reads.read(shader, sky, depth, seen);
        }
    }

    /// Adds the hit `hit` of `ray`, ray `index` of the depth's queue.
    pub(super) fn push(&mut self, shader: &Shader, index: u32, ray: &Ray, hit: Hit) {
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

    /// Takes the answered part of a queue, its records `answered`: each record's block
    /// made whole, each lane a hit in `seen` (those not held are padding, never read), and
    /// where the render counts, each held lane's work in `work`.
    #[inline(always)]
    fn take_answered<C: Count>(
        &mut self,
        shader: &Shader,
        answered: &[AnsweredRays],
        seen: &mut ArenaVec<Seen>,
        work: &mut ArenaVec<Work<C>>,
    ) {
        for (r, rays) in answered.iter().enumerate() {
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
                    if rays.answers.answered >> k & 1 != 0 {
                        let tested = rays.answers.tested[k];
                        own.add(rays.kind(k), answered_work::<C>(tested));
                    }
                    work.push(own);
                }
            }
            self.push_answered(shader, rays, r);
        }
    }

    /// Adds the block of the hits of `rays`, record `record` of the answered part, made
    /// whole, not gathered (out of line, so that the block is made in place, not copied).
    #[inline(never)]
    pub(super) fn push_answered(&mut self, shader: &Shader, rays: &AnsweredRays, record: usize) {
        let block = HitBlock::answered(shader, rays, record);
        push_reserved(&mut self.blocks, block);
    }

    fn finish(mut self, shader: &Shader) -> ArenaVec<'a, HitBlock> {
        self.close(shader);
        self.blocks
    }
}

/// Traces the walked rays of `queue`, which are of `depth`, and gathers every ray's hit into hit blocks in queue order, those of
/// the answered part as their records hold them; each ray's colour so far (the
/// background where it missed) goes into the queue, and where the render counts, its
/// work.
#[inline(always)]
pub(super) fn trace_hits<'a, C: Count>(
    shader: &Shader,
    arena: &'a Bump,
    queue: &mut Queue<'a, C>,
    depth: u32,
) -> ArenaVec<'a, HitBlock> {
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
            blocks.take_answered(shader, &queue.answered, seen, work);
            continue;
        }
        let kind = ray_kind(depth, p);
        hits.clear();
        stream::closest_rays_counting::<C>(shader.tracer, rays, |found, lanes| {
            if C::ON {
                for k in 0..found.len() {
                    let mut own = Work::default();
                    own.add(kind, lanes.lane(k));
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
    blocks.finish(shader)
}
