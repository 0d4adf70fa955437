//! A depth's shadow rays ([`ShadowQueue`]): each hit block's towards each light, set up
//! eight at a time and traced light by light, those that leave a primitive from inside
//! answered by its own test; then each lit hit's Blinn-Phong sum ([`shade_lit`]).

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::Vec3;

use super::super::light::{Incident8, Receiver};
use super::super::shade::{Phong8, Shader};
use super::answered_work;
use super::blocks::HitBlock;
use super::queue::{at, at_mut, Queue};
use crate::accel::count::Count;
use crate::accel::count::RayCounts;
use crate::accel::stream::{self, Answers};
use crate::intersect::Rays8;
use crate::ray::Ray;
use crate::simd::{for_lanes, Mask8, Vec3x8};

/// Traces the shadow rays of the hit blocks `blocks` of `queue` (`rays` counts them) and
/// sets the local colour of each hit some light reaches: its Blinn-Phong sum ([`Phong8`]),
/// light by light in the scalar order.
#[inline(always)]
pub(super) fn shade_lit<C: Count>(
    shader: &Shader,
    arena: &Bump,
    queue: &mut Queue<C>,
    blocks: &[HitBlock],
    rays: &mut RayCounts,
) {
    let shadows = ShadowQueue::trace(shader, arena, queue, blocks);
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
            at_mut(work, block.ray[(tag & 7) as usize]).shadow += count;
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
                let answered = blocked_by_own(shader, block, facing, &incident);
                let walked = facing & !answered;
                if C::ON {
                    for_lanes(answered, |k| {
                        counted(entry << 3 | k as u32, answered_work(1))
                    });
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

/// The lanes `facing` of `block` whose shadow rays along `incident` leave their primitive
/// from inside and meet it again, as the walk would find them: answered by that
/// primitive's own test ([`crate::accel::Tracer::occluded_by_own8`]), without the walk.
#[inline(always)]
fn blocked_by_own(shader: &Shader, block: &HitBlock, facing: u8, incident: &Incident8) -> u8 {
    let Some(kind) = block.interior else {
        return 0;
    };
    let enclosed = facing & block.inside;
    if enclosed == 0 {
        return 0;
    }
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
    enclosed & own.bitmask()
}

/// Takes the lane of a blocked shadow ray, tagged with its entry and lane, out of the lanes
/// its light reaches.
fn unlit(lit: &mut [u8], tag: u32) {
    lit[tag as usize >> 3] &= !(1 << (tag & 7));
}
