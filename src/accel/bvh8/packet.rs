//! Packet traversal of the 8-wide tree: each node's children culled for the whole packet
//! by its [`RayRange`] (one test of the eight boxes), those left tested against all the
//! packet's rays at once, a subtree left with few lanes finished one ray at a time by
//! `traverse.rs` (the lanes grouped by their ray's frame, which those walks take as a
//! constant), so each lane's answer is the single ray's bit for bit. A leaf of packed
//! primitives holding few of them against the lanes the packet brings (SAH leaves hold
//! two on average; `leaves.rs` weighs the two tests) tests each primitive against all the
//! lanes at once, by the primitives' packet kernels, rather than each lane against all
//! eight slots of the pack.

use super::node::{ChildRef, Node8, LEAF, WIDTH};
use super::Bvh8;
use crate::accel::count::{Count, CountLanes};
use crate::accel::hit::ClosestHit;
use crate::accel::stack::Stack;
use crate::intersect::{beyond_lanes, with_frame, BoxRays, PacketQuery, RayRange};
use crate::scene::Geometry;
use crate::simd::{for_lanes, F32xP, LaneBits, MaskP, PACKET};

/// A packet whose lanes in a subtree drop to this many finishes it one ray at a time.
const SINGLE_RAY_LANES: u32 = 2;

impl Bvh8 {
    /// The closest hits of the active lanes of `query`'s packet, traced together: each
    /// node's children are tested against all the packet's rays at once, visited nearest
    /// first (by an entry no lane's lies below) with their lanes and that entry on the
    /// stack. An entry is skipped when it lies beyond every lane's closest hit; a subtree
    /// left with few lanes is finished one ray at a time. Each lane's answer is the one
    /// single-ray walk ([`Bvh8::closest_from`]) gives.
    pub(super) fn packet_closest<C: Count, const STACK: usize, const COMPACT: bool>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        closest: &mut [ClosestHit; PACKET],
        count: &mut C::Lanes,
    ) {
        let packet = query.packet;
        let (active, t_min) = (packet.active, packet.t_min);
        if self.nodes.is_empty() || active == 0 {
            return;
        }
        let box_rays = BoxRays::new(packet);
        let lanes_t_min = F32xP::splat(t_min);
        let mut limit = lanes_of(closest, ClosestHit::limit);
        let range = box_rays.range(active);
        // The lanes' limits when the walk starts: as hits bring them closer, the lanes'
        // own box tests cull by distance.
        let range_limit = largest(limit, active);
        let mut stack = Stack::<(ChildRef, LaneBits, f32), STACK>::new();
        // The nearest child of the node just tested and its lanes, entered without the
        // stack: its lanes' closest hits have not moved since their box tests.
        let mut next = Some((0, active));
        loop {
            let (child, lanes) = match next.take() {
                Some(entered) => entered,
                None => match stack.pop() {
                    // Beyond every lane's closest hit: nothing closer inside (ties are
                    // visited).
                    Some((child, lanes, t_entry))
                        if lanes & !beyond_lanes(F32xP::splat(t_entry), limit).bitmask() != 0 =>
                    {
                        (child, lanes)
                    }
                    Some(_) => continue,
                    None => break,
                },
            };
            let leaf = child & LEAF != 0;
            if leaf
                && self
                    .leaves
                    .closest_packet::<_, COMPACT>(child, query, lanes, closest, count)
            {
                limit = lanes_of(closest, ClosestHit::limit);
                continue;
            }
            if leaf || lanes.count_ones() <= SINGLE_RAY_LANES {
                for (frame, lanes) in self.lanes_by_frame(query, lanes).into_iter().enumerate() {
                    with_frame!(frame, FRAME => for_lanes(lanes, |k| {
                        let (lane, mut counted) = (query.lane(k), C::default());
                        let closest = &mut closest[k];
                        if leaf {
                            self.closest_in_leaf::<C, FRAME, COMPACT>(
                                geometry,
                                child,
                                &lane,
                                closest,
                                &mut counted,
                            );
                        } else {
                            self.closest_from::<C, STACK, FRAME, COMPACT>(
                                child,
                                geometry,
                                &lane,
                                closest,
                                &mut counted,
                            );
                        }
                        count.add_lane(k, &counted);
                    }));
                }
                limit = lanes_of(closest, ClosestHit::limit);
                continue;
            }
            let node = &self.nodes[child as usize];
            let (candidates, range_entries) = candidates(node, range.as_ref(), t_min, range_limit);
            count.node(lanes);
            count.boxes(lanes, candidates.count_ones());
            let kept = MaskP::from_bitmask(lanes);
            // (child, its lanes, their entry) for the children entered but the nearest,
            // sorted on the stack with the nearest of them on top. The entry is the
            // range's bound, found for all eight children at once, where the packet has a
            // range; the nearest lane's, a reduction over the lanes for each child, where
            // it has none.
            let floor = stack.len();
            let mut nearest: Option<(ChildRef, LaneBits, f32)> = None;
            for_lanes(candidates, |c| {
                let (min, max) = node.boxes.corners(c);
                let intervals = box_rays.interval(min, max, lanes_t_min, limit);
                let hit = intervals.hit & kept;
                if hit.any() {
                    let entry = match &range_entries {
                        Some(entries) => entries[c],
                        None => hit
                            .select(intervals.entry, F32xP::splat(f32::INFINITY))
                            .min_lane(),
                    };
                    self.prefetch_child::<COMPACT>(node.child[c], true);
                    let entered = (node.child[c], hit.bitmask(), entry);
                    stack.push_sorted_but_nearest(floor, &mut nearest, entered, |e| e.2);
                }
            });
            next = nearest.map(|(child, lanes, _)| (child, lanes));
        }
    }

    /// The active lanes of `query`'s packet whose ray is blocked within its interval, as
    /// a bit mask, the rays traced together as in [`Bvh8::packet_closest`].
    pub(super) fn packet_occluded<C: Count, const STACK: usize, const COMPACT: bool>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        count: &mut C::Lanes,
    ) -> LaneBits {
        let packet = query.packet;
        let (active, t_min, t_max) = (packet.active, packet.t_min, &packet.t_max);
        if self.nodes.is_empty() || active == 0 {
            return 0;
        }
        let box_rays = BoxRays::new(packet);
        let (lanes_t_min, lanes_t_max) = (F32xP::splat(t_min), F32xP::from_array(*t_max));
        let range = box_rays.range(active);
        let range_limit = largest(lanes_t_max, active);
        let mut blocked: LaneBits = 0;
        let mut stack = Stack::<(ChildRef, LaneBits), STACK>::new();
        stack.push((0, active));
        while let Some((child, lanes)) = stack.pop() {
            let lanes = lanes & !blocked;
            if lanes == 0 {
                continue;
            }
            let leaf = child & LEAF != 0;
            let in_pack = if leaf {
                self.leaves
                    .blocks_packet::<_, COMPACT>(child, query, lanes, count)
            } else {
                None
            };
            if let Some(hit) = in_pack {
                blocked |= hit;
                if blocked == active {
                    break;
                }
                continue;
            }
            if leaf || lanes.count_ones() <= SINGLE_RAY_LANES {
                for (frame, lanes) in self.lanes_by_frame(query, lanes).into_iter().enumerate() {
                    with_frame!(frame, FRAME => for_lanes(lanes, |k| {
                        let (lane, mut counted) = (query.lane(k), C::default());
                        let hit = if leaf {
                            self.blocks::<C, FRAME, COMPACT>(geometry, child, &lane, t_max[k], &mut counted)
                        } else {
                            self.occluded_from::<C, STACK, FRAME, COMPACT>(
                                child,
                                geometry,
                                &lane,
                                t_max[k],
                                &mut counted,
                            )
                        };
                        count.add_lane(k, &counted);
                        if hit {
                            blocked |= 1 << k;
                        }
                    }));
                }
                if blocked == active {
                    break;
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let candidates = candidates(node, range.as_ref(), t_min, range_limit).0;
            count.node(lanes);
            count.boxes(lanes, candidates.count_ones());
            for_lanes(candidates, |c| {
                let (min, max) = node.boxes.corners(c);
                let intervals = box_rays.interval(min, max, lanes_t_min, lanes_t_max);
                let hit = intervals.hit.bitmask() & lanes;
                if hit != 0 {
                    self.prefetch_child::<COMPACT>(node.child[c], false);
                    stack.push((node.child[c], hit));
                }
            });
        }
        blocked
    }

    /// The lanes `lanes` of `query`'s packet by the frame their walks take
    /// ([`Leaves::frame`](super::leaves::Leaves::frame)): `[x, y, z]`, from the packet's
    /// triangle setup where the tree holds triangles.
    #[inline(always)]
    fn lanes_by_frame(&self, query: &PacketQuery, lanes: LaneBits) -> [LaneBits; 3] {
        if !self.leaves.framed() {
            return [0, 0, lanes];
        }
        query.shear().lanes_by_frame().map(|frame| frame & lanes)
    }
}

/// `distance` of each lane's closest hit so far, as a packet's lanes.
pub(super) fn lanes_of(
    closest: &[ClosestHit; PACKET],
    distance: impl Fn(&ClosestHit) -> f32,
) -> F32xP {
    F32xP::from_array(closest.each_ref().map(distance))
}

/// The largest of `t`'s lanes in `lanes` (at least one).
fn largest(t: F32xP, lanes: LaneBits) -> f32 {
    MaskP::from_bitmask(lanes)
        .select(t, F32xP::splat(f32::NEG_INFINITY))
        .max_lane()
}

/// The used children of `node` that some ray of `range` may enter (all of them without
/// a range), as a bit mask: the children left to test lane by lane; with a range, the
/// bounds below their lanes' entries ([`RayRange::entries8`]).
fn candidates(
    node: &Node8,
    range: Option<&RayRange>,
    t_min: f32,
    t_max: f32,
) -> (u8, Option<[f32; WIDTH]>) {
    let used = ((1u32 << node.count) - 1) as u8;
    match range {
        Some(range) => {
            let (entered, entries) = range.entries8(&node.boxes, t_min, t_max);
            (entered & used, Some(entries))
        }
        None => (used, None),
    }
}
