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
use crate::intersect::{PacketQuery, RayQuery};
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
    /// The longest path from the root to a leaf, in nodes (statistics).
    depth: usize,
    build: BvhBuild,
    /// The statistics of the binary tree it was collapsed from.
    binary: Bvh2Stats,
}

/// Entries on the traversal stack: each level pushes at most `WIDTH - 1`, and the binary
/// trees stay under `bvh2::MAX_DEPTH` levels, which bounds the collapsed ones too.
const STACK_SIZE: usize = (WIDTH - 1) * super::bvh2::MAX_DEPTH + 1;

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
            self.closest_from(0, geometry, query, closest, count);
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
        !self.nodes.is_empty() && self.occluded_from(0, geometry, query, t_max, count)
    }

    #[inline]
    fn closest_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        closest: &mut [ClosestHit; PACKET],
        count: &mut C::Lanes,
    ) {
        self.packet_closest::<C>(geometry, query, closest, count);
    }

    #[inline]
    fn occluded_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        count: &mut C::Lanes,
    ) -> LaneBits {
        self.packet_occluded::<C>(geometry, query, count)
    }
}

impl Bvh8 {
    /// Asks the cache for the pack of `child` if it is a pack leaf, and for the ids of its
    /// primitives where a walk looks for the closest hit (whose id it reads). The walks
    /// ask as they push a child: a pack (eight lines) read cold stalls the test that reads
    /// it, and one pushed is most often entered. The single-ray occlusion walk does not
    /// ask: it gained nothing measurable there.
    #[inline(always)]
    fn prefetch_pack(&self, child: ChildRef, closest: bool) {
        if child & LEAF != 0 {
            self.leaves.prefetch(child, closest);
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
