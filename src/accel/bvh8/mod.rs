//! The 8-wide BVH, converted from a binary one (`collapse.rs`): each node holds the boxes
//! of up to eight children side by side (one array per coordinate), so that one ray tests
//! all of them at once (`node.rs`). A subtree of at most eight primitives of one `packed`
//! kind (`prim_kinds!`) becomes one leaf whose primitives are stored side by side too,
//! in the kind's [`LeafPack`](crate::intersect::LeafPack) (`leaves.rs`), and tested
//! together; other leaves are the binary tree's, tested one primitive at a time. No file
//! here names a kind: the packs and their dispatch are generated from the list.
//!
//! Traversal (`traverse.rs` for single rays, `packet.rs` for a packet's rays together)
//! visits the hit children nearest first, with their entry distances on the stack; popped
//! entries beyond the closest hit are skipped (ties are visited, as in the binary BVH, so
//! the answer is brute force's).

mod collapse;
mod leaves;
mod node;
mod packet;
mod traverse;

use super::bvh2::{Bvh2Stats, BvhBuild};
use super::count::Count;
use super::hit::ClosestHit;
use super::structure::Structure;
#[cfg(test)]
use crate::intersect::PackLayout;
use crate::intersect::{with_frame, PacketQuery, RayQuery};
use crate::plural::count;
use crate::prim::PrimId;
use crate::scene::Geometry;
use crate::simd::{LaneBits, PACKET};
use leaves::Leaves;
use node::{ChildRef, Node8, LEAF, WIDTH};

/// The collapsed tree: `nodes[0]` is the root; leaves index `prims` or `leaves`' packs.
#[derive(Clone, Debug)]
pub struct Bvh8 {
    nodes: Vec<Node8>,
    prims: Vec<PrimId>,
    leaves: Leaves,
    /// The longest path from the root to a leaf, in nodes: it sizes the walks' stacks.
    depth: usize,
    build: BvhBuild,
    /// The statistics of the binary tree it was collapsed from.
    binary: Bvh2Stats,
    /// Whether its leaves hold compact packs ([`Leaves::compact`]), which its walks are
    /// compiled for.
    compact: bool,
}

/// Entries on the traversal stack of a tree `depth` levels deep: each level pushes at most
/// `WIDTH - 1`.
const fn stack_size(depth: usize) -> usize {
    (WIDTH - 1) * depth + 1
}

/// Trees at most this deep (the course scenes' have 1 to 10 levels) walk with stacks sized
/// for them, a few KiB: a walk's frame with the deepest tree's stack was 9 KiB, and a
/// profiler's copy of the call stack (16 KiB in `render-profile`) then missed the render
/// loop above it.
const SHALLOW_DEPTH: usize = 32;
/// Deeper trees, which only contrived scenes make, walk with stacks sized for the deepest:
/// the binary trees stay under `bvh2::MAX_DEPTH` levels, which bounds the collapsed ones.
const DEEP_STACK: usize = stack_size(super::bvh2::MAX_DEPTH);
const SHALLOW_STACK: usize = stack_size(SHALLOW_DEPTH);

/// Calls the walk `$walk` of `$tree` with the stack its depth asks for; a deep walk out
/// of line, so that its stack is not in the frame of every caller.
macro_rules! walk {
    ($tree:ident.$walk:ident::<$count:ty $(, $frame:ident)?>($($arg:expr),*)) => {
        if $tree.depth <= SHALLOW_DEPTH && !$tree.compact {
            $tree.$walk::<$count, SHALLOW_STACK $(, $frame)?, false>($($arg),*)
        } else if !$tree.compact {
            out_of_line(|| $tree.$walk::<$count, DEEP_STACK $(, $frame)?, false>($($arg),*))
        } else {
            // Trees of compact packs are large: one walk for them, of the deep stack.
            out_of_line(|| $tree.$walk::<$count, DEEP_STACK $(, $frame)?, true>($($arg),*))
        }
    };
}

#[inline(never)]
fn out_of_line<R>(walk: impl FnOnce() -> R) -> R {
    walk()
}

/// Trees of more nodes than this (2 MiB of them, a core's second-level cache here) have
/// their nodes asked for as the walks push them: whole renders of half a million to 8
/// million triangles, or of 600,000 spheres, then took 4-12% less time, while in trees
/// that the caches hold the asking added work to the protocol's sets.
const PREFETCHED_NODES: usize = 8192;

/// The walks from the root: one ray's in `traverse.rs`, a packet's in `packet.rs`.
impl Structure for Bvh8 {
    #[inline]
    fn closest<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        closest: &mut ClosestHit,
        count: &mut C,
    ) {
        if !self.nodes.is_empty() {
            with_frame!(self.leaves.frame(query), FRAME => {
                walk!(self.closest_from::<C, FRAME>(0, geometry, query, closest, count))
            });
        }
    }

    #[inline]
    fn occluded<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
    ) -> bool {
        !self.nodes.is_empty()
            && with_frame!(self.leaves.frame(query), FRAME => {
                walk!(self.occluded_from::<C, FRAME>(0, geometry, query, t_max, count))
            })
    }

    #[inline]
    fn closest_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        closest: &mut [ClosestHit; PACKET],
        count: &mut C::Lanes,
    ) {
        walk!(self.packet_closest::<C>(geometry, query, closest, count));
    }

    #[inline]
    fn occluded_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        count: &mut C::Lanes,
    ) -> LaneBits {
        walk!(self.packet_occluded::<C>(geometry, query, count))
    }
}

impl Bvh8 {
    /// Asks the cache for `child`: its pack if it is a pack leaf, with the ids of its
    /// primitives where a walk looks for the closest hit (whose id it reads); its node in
    /// a tree of more than [`PREFETCHED_NODES`]. The walks ask as they push a child: a
    /// pack (up to eight lines) or a node (four) read cold stalls the test that reads it,
    /// and one pushed is most often entered.
    #[inline(always)]
    fn prefetch_child<const COMPACT: bool>(&self, child: ChildRef, closest: bool) {
        if child & LEAF != 0 {
            self.leaves.prefetch::<COMPACT>(child, closest);
        } else if self.nodes.len() > PREFETCHED_NODES {
            crate::simd::prefetch(self.nodes.as_ptr().wrapping_add(child as usize));
        }
    }

    /// The build the binary tree it was collapsed from ran.
    pub fn build_kind(&self) -> BvhBuild {
        self.build
    }

    /// The binary tree's statistics, then the 8-wide tree's, one `name: value` per line,
    /// the structure named `name`.
    pub fn stats(&self, name: &str) -> Vec<String> {
        let mut lines = self.binary.lines(name);
        lines.push(format!(
            "8-wide: {}, depth {}, {:.2} MiB",
            count(self.node_count() as u64, "node", "nodes"),
            self.depth(),
            self.memory() as f64 / (1 << 20) as f64
        ));
        lines
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    pub fn depth(&self) -> usize {
        self.depth
    }

    pub fn memory(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..])
            + std::mem::size_of_val(&self.prims[..])
            + self.leaves.memory()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh2::Bvh2;
    use crate::accel::count::NoCount;
    use crate::intersect::IntersectOptions;
    use crate::ray::{Ray, RayPacket};
    use crate::scene::p3f::parse_text;
    use glam::Vec3;
    use std::cell::OnceCell;

    /// The stacks sized for the deepest trees (which only contrived scenes reach) answer
    /// as the shallow ones: each walk, one ray and packets, closest and occlusion.
    #[test]
    fn deep_stacks_walk_as_shallow_ones() {
        let text: String = (0..300)
            .map(|i| {
                let (x, y, z) = ((i * 37 % 101) as f32, (i * 53 % 89) as f32, (i % 7) as f32);
                match i % 2 {
                    0 => format!("s {} {} {z} 0.4\n", x * 0.3, y * 0.2),
                    _ => format!("p 3 {x} {y} {z} {} {y} {z} {x} {} {z}\n", x + 0.5, y + 0.5),
                }
            })
            .collect();
        let scene = parse_text(&text).unwrap();
        let geometry = &scene.geometry;
        let bvh2 = Bvh2::build(geometry, BvhBuild::Sah, [0.0, 0.0], 0.0);
        let shallow =
            Bvh8::collapse(bvh2, geometry, PackLayout::Auto).expect("small trees collapse");
        assert!(shallow.depth <= SHALLOW_DEPTH);
        let deep = Bvh8 {
            depth: SHALLOW_DEPTH + 1,
            ..shallow.clone()
        };
        let options = IntersectOptions::default();
        let rays: Vec<Ray> = (0..64)
            .map(|i| {
                let origin = Vec3::new(-5.0, (i % 8) as f32 * 2.5, 3.0 + (i / 8) as f32 * 0.2);
                Ray::new(
                    origin,
                    Vec3::new(1.0, 0.05 * (i % 5) as f32, -0.1).normalize(),
                )
            })
            .collect();
        let mut hits = 0;
        for packet_rays in rays.chunks_exact(PACKET) {
            let packet_rays: &[Ray; PACKET] = packet_rays.try_into().unwrap();
            let packet = RayPacket::new(packet_rays).with_t_max([30.0; PACKET]);
            let shear = OnceCell::new();
            let query = PacketQuery::new(&packet, options, &shear);
            let [closest_shallow, closest_deep] = [&shallow, &deep].map(|tree| {
                let mut closest = [ClosestHit::new(f32::INFINITY); PACKET];
                tree.closest_packet::<NoCount>(geometry, &query, &mut closest, &mut NoCount);
                closest.map(|c| c.hit())
            });
            assert_eq!(closest_shallow, closest_deep);
            let [blocked_shallow, blocked_deep] = [&shallow, &deep]
                .map(|tree| tree.occluded_packet::<NoCount>(geometry, &query, &mut NoCount));
            assert_eq!(blocked_shallow, blocked_deep);
            for ray in packet_rays {
                let query = RayQuery::new(ray, 0.0, options);
                let [one_shallow, one_deep] = [&shallow, &deep].map(|tree| {
                    let mut closest = ClosestHit::new(f32::INFINITY);
                    tree.closest(geometry, &query, &mut closest, &mut NoCount);
                    let blocked = tree.occluded(geometry, &query, 30.0, &mut NoCount);
                    (closest.hit(), blocked)
                });
                assert_eq!(one_shallow, one_deep);
                hits += usize::from(one_shallow.0.is_some());
            }
        }
        assert!(hits > 8, "{hits} hits of {}", rays.len());
    }
}
