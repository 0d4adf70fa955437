//! The 8-wide BVH, converted from a binary one (`collapse.rs`): each node holds the boxes
//! of up to eight children side by side (one array per coordinate), so that one ray tests
//! all of them at once (`node.rs`). A subtree of at most eight triangles, or eight
//! spheres, becomes one leaf whose primitives are stored side by side too
//! ([`TrianglePack8`], [`SpherePack8`]) and tested together; other leaves are the binary
//! tree's, tested one primitive at a time.
//!
//! Traversal (`traverse.rs` for single rays, `packet.rs` for eight rays together) visits
//! the hit children nearest first, with their entry distances on the stack; popped
//! entries beyond the closest hit are skipped (ties are visited, as in the binary BVH, so
//! the answer is brute force's).

mod collapse;
mod node;
mod packet;
mod traverse;

use super::bvh2::{Bvh2Stats, BvhBuild};
use crate::intersect::{SpherePack8, SphereRoots, TrianglePack8};
use crate::plural::count;
use crate::prim::PrimId;
use node::{Node8, WIDTH};

/// The collapsed tree: `nodes[0]` is the root; leaves index `prims` or the packs.
#[derive(Clone, Debug)]
pub struct Bvh8 {
    nodes: Vec<Node8>,
    prims: Vec<PrimId>,
    triangles: Vec<TrianglePack8>,
    spheres: Vec<SpherePack8>,
    /// How the sphere packs are tested: the scene's spheres' form of the quadratic.
    sphere_roots: SphereRoots,
    /// The primitives of each pack, lane by lane (`triangles`, then `spheres`).
    triangle_ids: Vec<[PrimId; 8]>,
    sphere_ids: Vec<[PrimId; 8]>,
    /// The longest path from the root to a leaf, in nodes (statistics).
    depth: usize,
    build: BvhBuild,
    /// The statistics of the binary tree it was collapsed from.
    binary: Bvh2Stats,
}

/// Entries on the traversal stack: each level pushes at most `WIDTH - 1`, and the binary
/// trees stay under `bvh2::MAX_DEPTH` levels, which bounds the collapsed ones too.
const STACK_SIZE: usize = (WIDTH - 1) * super::bvh2::MAX_DEPTH + 1;

impl Bvh8 {
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
            + std::mem::size_of_val(&self.triangles[..])
            + std::mem::size_of_val(&self.spheres[..])
            + std::mem::size_of_val(&self.triangle_ids[..])
            + std::mem::size_of_val(&self.sphere_ids[..])
    }
}
