//! The stream renderer: a tile's samples traced breadth first, one depth at a time. Each
//! depth is a [`Queue`] (structure of arrays in the tile's arena): its rays, then their
//! hits' shadow rays light by light, are traced as packets of eight by the stream
//! scheduler ([`crate::accel::stream`], which `bench` measures), the hits are shaded,
//! and the rays they spawn make the next depth's queue. Once the deepest queue is
//! shaded, colours flow back up: each ray's colour, clamped if it hit something, is
//! added to its parent's with its weight, in the order the scalar [`Shader::trace`] adds
//! them, so the image is the scalar one byte for byte.

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::Vec3;

use super::sampler::Sample;
use super::shade::{RayCounts, RayKind, Shader, ShadowRay, Surface};
use crate::accel::stream::{self, Occlusions, Query};
use crate::ray::Ray;

/// The rays of one depth, and what they bring back.
pub(super) struct Queue<'a> {
    rays: ArenaVec<'a, Ray>,
    samples: ArenaVec<'a, Sample>,
    /// The index of the medium each ray travels in.
    ior: ArenaVec<'a, f32>,
    /// At depth 1 the tile's pixel of each sample; deeper, the index in the previous
    /// depth's queue of the hit that spawned the ray.
    parent: ArenaVec<'a, u32>,
    /// The factor of each ray's colour in its parent's (one at depth 1).
    weight: ArenaVec<'a, Vec3>,
    /// What each ray sees: the background if it missed; else its hit's local colour, to
    /// which its children's colours are added before it is clamped.
    colour: ArenaVec<'a, Vec3>,
    /// Whether each ray hit something (only hits clamp their colour).
    hit: ArenaVec<'a, bool>,
}

impl<'a> Queue<'a> {
    /// A queue with room for `capacity` rays: growing a vector in an arena copies it and
    /// leaves the old one behind, so queues are made at the size they may reach.
    pub(super) fn with_capacity_in(capacity: usize, arena: &'a Bump) -> Self {
        Queue {
            rays: ArenaVec::with_capacity_in(capacity, arena),
            samples: ArenaVec::with_capacity_in(capacity, arena),
            ior: ArenaVec::with_capacity_in(capacity, arena),
            parent: ArenaVec::with_capacity_in(capacity, arena),
            weight: ArenaVec::with_capacity_in(capacity, arena),
            colour: ArenaVec::with_capacity_in(capacity, arena),
            hit: ArenaVec::with_capacity_in(capacity, arena),
        }
    }

    /// Queues a primary sample of the tile's pixel `pixel`.
    pub(super) fn push_primary(&mut self, ray: Ray, sample: Sample, pixel: u32) {
        self.push(ray, sample, 1.0, pixel, Vec3::ONE);
    }

    fn push(&mut self, ray: Ray, sample: Sample, ior: f32, parent: u32, weight: Vec3) {
        self.rays.push(ray);
        self.samples.push(sample);
        self.ior.push(ior);
        self.parent.push(parent);
        self.weight.push(weight);
    }

    fn len(&self) -> usize {
        self.rays.len()
    }

    /// Ray `i`'s colour as its parent takes it.
    fn seen(&self, i: usize) -> Vec3 {
        if self.hit[i] {
            self.colour[i].clamp(Vec3::ZERO, Vec3::ONE)
        } else {
            self.colour[i]
        }
    }
}

/// Traces the primary samples of `primary` and every ray they spawn, and adds each
/// sample's colour to `sums` at its pixel, in queue order.
pub(super) fn trace<'a>(
    shader: &Shader,
    arena: &'a Bump,
    primary: Queue<'a>,
    sums: &mut [Vec3],
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
    // Children add to their parents, deepest first.
    while let Some(queue) = depths.pop() {
        match depths.last_mut() {
            Some(parents) => {
                for i in 0..queue.len() {
                    parents.colour[queue.parent[i] as usize] += queue.weight[i] * queue.seen(i);
                }
            }
            None => {
                for i in 0..queue.len() {
                    sums[queue.parent[i] as usize] += queue.seen(i);
                }
            }
        }
    }
}

/// Traces the rays of `queue`, which are of `depth`, and their shadow rays, sets each
/// one's local colour, and returns the queue of the rays their hits spawn.
fn shade_depth<'a>(
    shader: &Shader,
    arena: &'a Bump,
    queue: &mut Queue<'a>,
    depth: u32,
    rays: &mut RayCounts,
) -> Queue<'a> {
    let n = queue.len();
    let mut hits = ArenaVec::with_capacity_in(n, arena);
    stream::closest(shader.tracer, &queue.rays, |_, found| {
        hits.extend_from_slice(found)
    });
    let surfaces = ArenaVec::from_iter_in(
        hits.iter()
            .zip(&queue.rays)
            .map(|(hit, ray)| hit.map(|hit| shader.surface(ray, &hit))),
        arena,
    );
    let shadows = ShadowQueue::trace(shader, arena, queue, &surfaces);

    // A hit spawns a reflected and a transmitted ray at most.
    let mut next = Queue::with_capacity_in(2 * n, arena);
    for (i, (hit, surface)) in hits.iter().zip(&surfaces).enumerate() {
        let ray = &queue.rays[i];
        let (Some(hit), Some(surface)) = (hit, surface) else {
            queue.colour.push(shader.background(ray.dir, depth));
            queue.hit.push(false);
            continue;
        };
        let material = shader.material(hit);
        let shadow_of = &mut |light| shadows.of(i, light);
        queue
            .colour
            .push(shader.local(ray, surface.nf, material, rays, shadow_of));
        queue.hit.push(true);
        if depth < shader.options.max_depth {
            let sample = &queue.samples[i];
            shader.spawn(ray, sample, surface, material, queue.ior[i], |child| {
                rays.add(child.kind, 1);
                next.push(child.ray, child.sample, child.ior, i as u32, child.weight);
            });
        }
    }
    next
}

/// The shadow rays of one depth's hits and whether each is blocked.
struct ShadowQueue<'a> {
    lights: usize,
    /// Entry `i * lights + light`: the index in `rays` of hit `i`'s shadow ray to
    /// `light`, or [`ShadowQueue::NONE`] when it has none.
    slot: ArenaVec<'a, u32>,
    rays: Occlusions<'a, ShadowRay>,
    blocked: ArenaVec<'a, bool>,
}

impl<'a> ShadowQueue<'a> {
    const NONE: u32 = u32::MAX;

    /// Builds every hit's shadow ray to every light and traces them as a stream, which
    /// groups them by light.
    fn trace(
        shader: &Shader,
        arena: &'a Bump,
        queue: &Queue,
        surfaces: &[Option<Surface>],
    ) -> Self {
        let lights = shader.lights.len();
        let mut slot = ArenaVec::from_iter_in(
            std::iter::repeat_n(Self::NONE, surfaces.len() * lights),
            arena,
        );
        let mut rays = Occlusions::with_capacity_in(slot.len(), arena);
        for light in 0..lights {
            for (i, surface) in surfaces.iter().enumerate() {
                let Some(surface) = surface else { continue };
                let time = queue.rays[i].time;
                if let Some(shadow) = shader.shadow_ray(light, &queue.samples[i], surface, time) {
                    slot[i * lights + light] = rays.push(light as u32, shadow);
                }
            }
        }
        let blocked = rays.trace(shader.tracer, arena);
        ShadowQueue {
            lights,
            slot,
            rays,
            blocked,
        }
    }

    /// Hit `i`'s shadow ray to `light` and whether it is blocked, as
    /// [`Shader::local`] asks.
    fn of(&self, i: usize, light: usize) -> Option<(ShadowRay, bool)> {
        let slot = self.slot[i * self.lights + light];
        let rays = self.rays.queries();
        (slot != Self::NONE).then(|| (rays[slot as usize], self.blocked[slot as usize]))
    }
}

impl Query for ShadowRay {
    fn ray(&self) -> &Ray {
        &self.ray
    }

    fn t_max(&self) -> f32 {
        self.distance
    }
}
