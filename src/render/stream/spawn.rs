//! A depth's spawning: the reflected and transmitted rays of each hit block, made eight
//! hits at a time ([`Bounce8`]), queued in the next depth's [`Queue`]: the walked ones
//! in their parts, those made inside a primitive that it answers with their hits.

use bumpalo::Bump;

use super::super::shade::{Bounce8, Optics8, Shader};
use super::blocks::HitBlock;
use super::queue::{at, ray_kind, Lineage, Parts, Queue, WALKED_REFLECTED, WALKED_TRANSMITTED};
use crate::accel::count::Count;
use crate::accel::count::{RayCounts, RayKind};
use crate::ray::Ray;
use crate::simd::{for_lanes, F32x8, Mask8};

/// The queue of the rays that the hit blocks `blocks` of `queue` spawn, which are of
/// depth `depth + 1` (`rays` counts them); empty at the deepest depth.
#[inline(always)]
pub(super) fn spawn<'a, C: Count>(
    shader: &Shader,
    arena: &'a Bump,
    queue: &Queue<'a, C>,
    blocks: &[HitBlock],
    (depth, rays): (u32, &mut RayCounts),
) -> Queue<'a, C> {
    // A hit spawns a reflected and a transmitted ray at most. The reflected rays come
    // first and the transmitted ones after them, as Embree's stream renderer orders them:
    // a packet then holds rays that leave a surface on one side (a glass ball's
    // reflections outside it, its refractions inside), and each parent still receives its
    // reflected colour before its transmitted one, the scalar order of its sum.
    // The rays that start inside primitives and that the primitives answer, reflected and
    // transmitted, are queued between the other reflected rays and transmitted ones: a
    // parent has one of them at most (its reflected ray if it arrived from inside, else
    // its transmitted one), so each parent's reflected ray still comes before its
    // transmitted one.
    let room = if depth < shader.options.max_depth {
        queue.len()
    } else {
        0
    };
    let answered_room = if room > 0 { 8 * blocks.len() } else { 0 };
    let mut next = Queue::with_capacities_in([room, answered_room, room], arena);
    if room == 0 {
        return next;
    }
    for block in blocks {
        spawn_from(shader, &queue.lineage, block, &mut next);
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
    next
}

/// Queues in `next` the rays that the hits of `block` spawn, whose rays' lineages are in
/// `lineage`.
#[inline(always)]
fn spawn_from<C: Count>(
    shader: &Shader,
    lineage: &Parts<Lineage>,
    block: &HitBlock,
    next: &mut Queue<C>,
) {
    let optics = Optics8::new(block.material.map(|m| &shader.scene.materials[m as usize]));
    if optics.spawns_none() {
        return;
    }
    let ior_here = F32x8::from_array(block.ray.map(|i| at(lineage, i).ior));
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
    // A lane's ray inside its primitive is its reflected one if it arrived from inside.
    let (inner_reflected, inner_through) = match &answered {
        Some(rays) => (rays.reflected, rays.answers.answered & !rays.reflected),
        None => (0, 0),
    };
    let reflected_lineage = |k: usize| {
        let i = block.ray[k];
        let Lineage { sample, ior, .. } = *at(lineage, i);
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
            sample: at(lineage, i).sample.spawn(1),
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
        next.push_answered(rays, |k| match inner_reflected >> k & 1 != 0 {
            true => reflected_lineage(k),
            false => transmitted_lineage(k),
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
