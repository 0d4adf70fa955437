//! Packet traversal of the 8-wide tree: each node's children tested against all the
//! packet's rays at once, a subtree left with few lanes finished one ray at a time by
//! `traverse.rs`, so each lane's answer is the single ray's bit for bit.

use super::node::{ChildRef, LEAF, WIDTH};
use super::{Bvh8, STACK_SIZE};
use crate::accel::hit::{for_lanes, ClosestHit};
use crate::accel::stack::Stack;
use crate::intersect::{beyond, BoxRay8};
use crate::ray::RayPacket;
use crate::scene::Geometry;
use crate::simd::F32x8;

/// A packet whose lanes in a subtree drop to this many finishes it one ray at a time.
const SINGLE_RAY_LANES: u32 = 2;

impl Bvh8 {
    /// The closest hits of the active lanes of `packet`, traced together: each node's children are tested against all the packet's rays at once,
    /// visited nearest first (by the nearest lane's entry) with their lanes and that
    /// entry on the stack. An entry is skipped when it lies beyond every lane's closest
    /// hit; a subtree left with few lanes is finished one ray at a time. Each lane's
    /// answer is the one [`Bvh8::closest`] gives.
    pub fn closest_packet(
        &self,
        geometry: &Geometry,
        packet: &RayPacket,
        closest: &mut [ClosestHit; 8],
    ) {
        let (rays, active, t_min) = (packet.rays, packet.active, packet.t_min);
        if self.nodes.is_empty() || active == 0 {
            return;
        }
        let inv_dir = packet.inv_dir_lanes();
        let box_rays = BoxRay8::new(packet);
        let lanes_t_min = F32x8::splat(t_min);
        let limits =
            |closest: &[ClosestHit; 8]| F32x8::from_array(closest.each_ref().map(|c| c.limit()));
        let mut limit = limits(closest);
        let mut stack = Stack::<(ChildRef, u8, f32), STACK_SIZE>::new();
        stack.push((0, active, t_min));
        while let Some((child, lanes, t_entry)) = stack.pop() {
            // Beyond every lane's closest hit: nothing closer inside (ties are visited).
            let farthest = limit.to_array();
            if (0..8).all(|k| lanes & (1 << k) == 0 || beyond(t_entry, farthest[k])) {
                continue;
            }
            if child & LEAF != 0 || lanes.count_ones() <= SINGLE_RAY_LANES {
                for_lanes(lanes, |k| {
                    if child & LEAF != 0 {
                        self.closest_in_leaf(
                            geometry,
                            child,
                            &rays[k],
                            inv_dir[k],
                            t_min,
                            &mut closest[k],
                        );
                    } else {
                        self.closest_from(
                            child,
                            geometry,
                            &rays[k],
                            inv_dir[k],
                            t_min,
                            &mut closest[k],
                        );
                    }
                });
                limit = limits(closest);
                continue;
            }
            let node = &self.nodes[child as usize];
            let boxes = node.boxes.corners();
            // (child, its lanes, the nearest lane's entry), for the children entered.
            let mut entered = [(0u32, 0u8, 0f32); WIDTH];
            let mut count = 0;
            for (c, &(min, max)) in boxes.iter().enumerate().take(node.count as usize) {
                let intervals = box_rays.interval(min, max, lanes_t_min, limit);
                let hit = intervals.hit.bitmask() & lanes;
                if hit != 0 {
                    let t = intervals.entry.to_array();
                    let mut nearest = f32::INFINITY;
                    for_lanes(hit, |k| nearest = nearest.min(t[k]));
                    entered[count] = (node.child[c], hit, nearest);
                    count += 1;
                }
            }
            let entered = &mut entered[..count];
            // Farthest first on the stack, so the nearest is popped next.
            entered.sort_unstable_by(|a, b| b.2.total_cmp(&a.2));
            entered.iter().for_each(|&e| stack.push(e));
        }
    }

    /// The active lanes of `packet` whose ray is blocked within its interval, as a bit
    /// mask, the rays traced together as in [`Bvh8::closest_packet`].
    pub fn occluded_packet(&self, geometry: &Geometry, packet: &RayPacket) -> u8 {
        let (rays, active) = (packet.rays, packet.active);
        let (t_min, t_max) = (packet.t_min, &packet.t_max);
        if self.nodes.is_empty() || active == 0 {
            return 0;
        }
        let inv_dir = packet.inv_dir_lanes();
        let box_rays = BoxRay8::new(packet);
        let (lanes_t_min, lanes_t_max) = (F32x8::splat(t_min), F32x8::from_array(*t_max));
        let mut blocked = 0u8;
        let mut stack = Stack::<(ChildRef, u8), STACK_SIZE>::new();
        stack.push((0, active));
        while let Some((child, lanes)) = stack.pop() {
            let lanes = lanes & !blocked;
            if lanes == 0 {
                continue;
            }
            if child & LEAF != 0 || lanes.count_ones() <= SINGLE_RAY_LANES {
                for_lanes(lanes, |k| {
                    let hit = if child & LEAF != 0 {
                        self.blocks(geometry, child, &rays[k], inv_dir[k], t_min, t_max[k])
                    } else {
                        self.occluded_from(child, geometry, &rays[k], inv_dir[k], t_min, t_max[k])
                    };
                    if hit {
                        blocked |= 1 << k;
                    }
                });
                if blocked == active {
                    break;
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let boxes = node.boxes.corners();
            for (c, &(min, max)) in boxes.iter().enumerate().take(node.count as usize) {
                let intervals = box_rays.interval(min, max, lanes_t_min, lanes_t_max);
                let hit = intervals.hit.bitmask() & lanes;
                if hit != 0 {
                    stack.push((node.child[c], hit));
                }
            }
        }
        blocked
    }
}
