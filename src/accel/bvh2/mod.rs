//! The binary BVH, flattened into one array of 32-byte nodes, and its two builds
//! (`build.rs`):
//! - [`BvhBuild::Midpoint`], the course report's (P3F.md section 9): leaves of at most two
//!   objects; split on the longest axis of the node's box at its midpoint, objects sorted
//!   by centroid; if one side is empty, at the mean centroid; if that still separates
//!   nothing, at the median (the report's code could recurse forever on equal centroids).
//! - [`BvhBuild::Sah`]: binned surface area heuristic over all three axes, leaves of up
//!   to [`MAX_LEAF`] primitives. The default structure collapses it into the 8-wide tree
//!   of [`crate::accel::bvh8`].
//!
//! Nodes are stored depth first: an interior node's left child follows it, and it holds
//! the index of its right child. A leaf's primitives are contiguous in `prims`, in the
//! order the build left them. Traversal is near child first with the entry distance kept
//! on the stack, so popped entries beyond the closest hit are skipped; occlusion stops at
//! the first hit.

mod build;

use glam::Vec3;

use super::count::Count;
use super::hit::ClosestHit;
use super::stack::Stack;
use super::structure::Structure;
use crate::intersect::{beyond, Aabb, BoxRay, RayQuery};
use crate::plural::count;
use crate::prim::PrimId;
use crate::scene::Geometry;
pub(super) use build::several_threads;
pub use build::MAX_LEAF;

/// Which build to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhBuild {
    Midpoint,
    Sah,
}

/// SAH cost of visiting a node, relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;
/// No tree is deeper: past a free depth, builds split at the median, halving the
/// primitives.
pub const MAX_DEPTH: usize = 128;

/// A node: its box, and either two children or a run of primitives.
/// Two nodes fill a 64-byte cache line.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct Node {
    min: [f32; 3],
    /// Interior: index of the right child. Leaf: index of the first primitive.
    offset: u32,
    max: [f32; 3],
    /// 0 for an interior node, else the number of primitives in the leaf.
    count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from_array(self.min),
            max: Vec3::from_array(self.max),
        }
    }

    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// A leaf's primitives, as indices into the tree's primitive order.
    pub fn prim_range(&self) -> std::ops::Range<usize> {
        self.offset as usize..(self.offset + self.count) as usize
    }

    /// An interior node's right child (its left child follows it).
    pub fn right_child(&self) -> usize {
        self.offset as usize
    }

    /// The entry distance of the ray into the node's box within `[t_min, t_max]`, by the
    /// structures' box test ([`BoxRay::interval`]: allowing for its rounding, a ray in a
    /// slab's plane passes, erring towards visiting).
    #[inline]
    fn entry(&self, ray: &BoxRay, t_min: f32, t_max: f32) -> Option<f32> {
        let (min, max) = (Vec3::from_array(self.min), Vec3::from_array(self.max));
        ray.interval(min, max, t_min, t_max).map(|(entry, _)| entry)
    }
}

#[derive(Clone, Debug)]
pub struct Bvh2 {
    nodes: Vec<Node>,
    prims: Vec<PrimId>,
    build: BvhBuild,
}

/// What `info` reports of a binary tree; an 8-wide tree keeps its binary tree's.
#[derive(Clone, Debug)]
pub struct Bvh2Stats {
    nodes: usize,
    leaves: usize,
    depth: usize,
    leaf_prims: usize,
    max_leaf: u32,
    prims: usize,
    sah_cost: f64,
    memory: usize,
}

impl Bvh2Stats {
    /// One `name: value` per line, the build named `build`.
    pub fn lines(&self, build: &str) -> Vec<String> {
        vec![
            format!("bvh build: {}", build.trim_start_matches("bvh ")),
            format!(
                "nodes: {} ({} interior, {}), depth {}",
                self.nodes,
                self.nodes - self.leaves,
                count(self.leaves as u64, "leaf", "leaves"),
                self.depth
            ),
            format!(
                "primitives per leaf: {:.2} mean, {} max ({})",
                self.leaf_prims as f64 / self.leaves.max(1) as f64,
                self.max_leaf,
                count(self.prims as u64, "primitive", "primitives")
            ),
            format!("sah cost: {:.2}", self.sah_cost),
            format!("memory: {:.2} MiB", self.memory as f64 / (1 << 20) as f64),
        ]
    }

    /// The number of nodes on the longest path from the root to a leaf.
    pub fn depth(&self) -> usize {
        self.depth
    }
}

impl Bvh2 {
    /// The tree over every bounded primitive of `geometry`, moving spheres bounded over
    /// `shutter`, spheres' boxes grown by `roots_margin` (`bounds::prim_bounds`).
    pub fn build(
        geometry: &Geometry,
        build: BvhBuild,
        shutter: [f32; 2],
        roots_margin: f32,
    ) -> Bvh2 {
        Self::build_for_packs(geometry, build, shutter, roots_margin, 0)
    }

    /// [`Bvh2::build`] for a tree to be collapsed into packs of up to `pack_size`
    /// primitives: a subtree of that many or fewer of one packed kind is left a leaf,
    /// which is what the collapse makes of it.
    pub fn build_for_packs(
        geometry: &Geometry,
        build: BvhBuild,
        shutter: [f32; 2],
        roots_margin: f32,
        pack_size: usize,
    ) -> Bvh2 {
        let rules = build::Rules {
            build,
            pack_leaves: pack_size,
            sah_pack: 0,
        };
        let (nodes, prims) = build::build(geometry, rules, shutter, roots_margin);
        Bvh2 {
            nodes,
            prims,
            build,
        }
    }

    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    pub fn prims(&self) -> &[PrimId] {
        &self.prims
    }

    pub fn build_kind(&self) -> BvhBuild {
        self.build
    }

    /// The nodes and the primitive order, for a conversion that consumes the tree.
    pub fn into_parts(self) -> (Vec<Node>, Vec<PrimId>) {
        (self.nodes, self.prims)
    }
}

impl Structure for Bvh2 {
    fn closest<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        closest: &mut ClosestHit,
        count: &mut C,
    ) {
        let Some(root) = self.nodes.first() else {
            return;
        };
        let (t_min, box_ray) = (query.t_min, BoxRay::new(query.ray.origin, query.inv_dir));
        count.boxes(1);
        let Some(t_root) = root.entry(&box_ray, t_min, closest.limit()) else {
            return;
        };
        let mut stack = Stack::<(u32, f32), MAX_DEPTH>::new();
        stack.push((0, t_root));
        while let Some((mut index, t_entry)) = stack.pop() {
            // Entries beyond the closest hit cannot hold a closer one (ties may).
            if beyond(t_entry, closest.limit()) {
                continue;
            }
            loop {
                let node = &self.nodes[index as usize];
                if node.count > 0 {
                    count.leaf();
                    count.prims(node.count);
                    let first = node.offset as usize;
                    for &prim in &self.prims[first..first + node.count as usize] {
                        closest.test(geometry, prim, query);
                    }
                    break;
                }
                count.node();
                count.boxes(2);
                let (left, right) = (index + 1, node.offset);
                let limit = closest.limit();
                let t_left = self.nodes[left as usize].entry(&box_ray, t_min, limit);
                let t_right = self.nodes[right as usize].entry(&box_ray, t_min, limit);
                index = match (t_left, t_right) {
                    (Some(tl), Some(tr)) => {
                        let (near, far, t_far) = if tl <= tr {
                            (left, right, tr)
                        } else {
                            (right, left, tl)
                        };
                        stack.push((far, t_far));
                        near
                    }
                    (Some(_), None) => left,
                    (None, Some(_)) => right,
                    (None, None) => break,
                };
            }
        }
    }

    /// Each popped node's own box is tested: its children are pushed unsorted.
    fn occluded<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let (t_min, box_ray) = (query.t_min, BoxRay::new(query.ray.origin, query.inv_dir));
        let mut stack = Stack::<u32, MAX_DEPTH>::new();
        stack.push(0);
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index as usize];
            count.boxes(1);
            if node.entry(&box_ray, t_min, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                count.leaf();
                let first = node.offset as usize;
                let blocked = self.prims[first..first + node.count as usize]
                    .iter()
                    .any(|&prim| {
                        count.prims(1);
                        geometry.intersect(prim, query, t_max).is_some()
                    });
                if blocked {
                    return true;
                }
            } else {
                count.node();
                stack.push(node.offset);
                stack.push(index + 1);
            }
        }
        false
    }
}

impl Bvh2 {
    pub fn stats(&self) -> Bvh2Stats {
        // Counted in place: a list of the leaves took 8 bytes a primitive.
        let leaves = || self.nodes.iter().filter(|n| n.count > 0);
        Bvh2Stats {
            nodes: self.nodes.len(),
            leaves: leaves().count(),
            depth: self.depth(),
            leaf_prims: leaves().map(|n| n.count as usize).sum(),
            max_leaf: leaves().map(|n| n.count).max().unwrap_or(0),
            prims: self.prims.len(),
            sah_cost: self.sah_cost(),
            memory: std::mem::size_of_val(&self.nodes[..]) + 4 * self.prims.len(),
        }
    }

    /// The number of nodes on the longest path from the root to a leaf.
    pub fn depth(&self) -> usize {
        let mut deepest = 0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            let Some(node) = self.nodes.get(i) else {
                continue;
            };
            deepest = deepest.max(d);
            if node.count == 0 {
                stack.push((i + 1, d + 1));
                stack.push((node.offset as usize, d + 1));
            }
        }
        deepest
    }

    /// The SAH cost of the tree: node visits and primitive tests expected for a random
    /// ray through the root's box, with a primitive test costing 1.
    pub fn sah_cost(&self) -> f64 {
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        let root_area = root.bounds().area().max(f32::MIN_POSITIVE) as f64;
        self.nodes
            .iter()
            .map(|n| {
                let share = n.bounds().area() as f64 / root_area;
                if n.count > 0 {
                    share * n.count as f64
                } else {
                    share * TRAVERSAL_COST as f64
                }
            })
            .sum()
    }
}
