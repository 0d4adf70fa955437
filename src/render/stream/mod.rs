//! The stream renderer: a batch of a tile's samples traced breadth first, one depth at a
//! time, each depth in three stages, bit for bit as the scalar path ([`Shader::trace`]):
//!
//! - [`queue`]: a depth's [`Queue`] (arrays in the worker's arena), its rays in three
//!   parts: the reflected rays that are walked, those made inside a primitive that it
//!   and the primitives near it answered as they were made, the transmitted rays that
//!   are walked; each ray's lineage, what it sees and its work.
//! - [`blocks`]: the walked rays traced as packets by the stream scheduler
//!   ([`crate::accel::stream`], which `bench` measures) and their hits gathered eight to
//!   a [`blocks::HitBlock`] (structure of arrays), whose points are recomputed on the
//!   surfaces and offset off them; the answered rays stay the lanes of the block that
//!   made them, which become a hit block without a gathering.
//! - [`shadows`]: each block's shadow rays, light by light, those that leave a primitive
//!   from inside answered by its own test; the Blinn-Phong sums of the lanes a light
//!   reaches (a block that none reaches, inside glass most, skips them).
//! - [`spawn`]: each block's reflected and transmitted rays, eight lanes at a time, the
//!   next depth's queue.
//!
//! Once the deepest queue is shaded, colours flow back up ([`trace`]): each ray's colour,
//! clamped if it hit something, is added to its parent's with its weight, in the order
//! the scalar path adds them, so the image is the scalar one byte for byte. Where the
//! render counts (`C` of [`crate::accel::count`]), each ray's work flows up with its
//! colour, so that a pixel's cost is what its samples' rays took.

mod blocks;
mod queue;
mod shadows;
mod spawn;

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::Vec3;

use super::shade::Shader;
use crate::accel::count::Count;
use crate::accel::count::{RayCounts, RayKind, Work};
pub(super) use queue::Queue;
use queue::{at_mut, Lineage};

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
    let blocks = blocks::trace_hits(shader, arena, queue, depth);
    shadows::shade_lit(shader, arena, queue, &blocks, rays);
    spawn::spawn(shader, arena, queue, &blocks, (depth, rays))
}

/// The work of a ray that primitives' own tests answered, `tested` of them, without a walk:
/// it counts as traced, with those tests.
fn answered_work<C: Count>(tested: u32) -> C {
    let mut count = C::default();
    count.ray();
    count.prims(tested);
    count
}
