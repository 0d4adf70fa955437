//! An 8-wide BVH collapsed from a binary one: each node holds the boxes of up to eight
//! children side by side (one array per coordinate), so that one ray tests all of them at
//! once. Leaves are the binary tree's leaves, pointing into the same primitive order.
//!
//! Collapsing: a node starts with its binary node's two children, and the child with the
//! largest surface area is replaced by its own two children while fewer than eight remain
//! and some child is interior (Wald et al., "Getting Rid of Packets", 2008).
//!
//! Traversal visits the hit children nearest first, with their entry distances on the
//! stack; popped entries beyond the closest hit are skipped (ties are visited, as in the
//! binary BVH, so the answer is brute force's).

use std::mem::MaybeUninit;

use glam::Vec3;

use super::bvh::Node;
use super::ClosestHit;
use crate::ray::{PrimId, Ray};
use crate::scene::Geometry;

/// Children per node.
pub const WIDTH: usize = 8;

/// A child reference: a node index, or a leaf (the top bit) with its primitive count less
/// one in bits 27..30 and its first primitive below.
type ChildRef = u32;
const LEAF: u32 = 1 << 31;
const COUNT_SHIFT: u32 = 27;
const FIRST_MASK: u32 = (1 << COUNT_SHIFT) - 1;
/// The most primitives a leaf may hold, and the most a tree may hold, to be encoded.
const MAX_LEAF_PRIMS: usize = 1 << (31 - COUNT_SHIFT);
const MAX_PRIMS: usize = FIRST_MASK as usize + 1;

/// Eight children's boxes, one array per bound and axis, then their references.
/// 224 bytes of data padded to four cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node8 {
    min: [[f32; WIDTH]; 3],
    max: [[f32; WIDTH]; 3],
    child: [ChildRef; WIDTH],
    /// Children in use: slots `0..count`.
    count: u32,
}

const _: () = assert!(std::mem::size_of::<Node8>() == 256);

impl Node8 {
    /// Each used child's entry distance within `(t_min, t_max]`, or `None`: the binary
    /// node's slab test, child by child.
    #[inline]
    fn entries(&self, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> [Option<f32>; WIDTH] {
        let mut out = [None; WIDTH];
        for (k, entry) in out.iter_mut().enumerate().take(self.count as usize) {
            let mut near = t_min;
            let mut far = t_max;
            for axis in 0..3 {
                let t1 = (self.min[axis][k] - origin[axis]) * inv_dir[axis];
                let t2 = (self.max[axis][k] - origin[axis]) * inv_dir[axis];
                near = near.max(t1.min(t2));
                far = far.min(t1.max(t2));
            }
            *entry = (near <= far).then_some(near);
        }
        out
    }
}

/// The collapsed tree: `nodes[0]` is the root; leaves index `prims`.
#[derive(Clone, Debug)]
pub struct Bvh8 {
    nodes: Vec<Node8>,
    prims: Vec<PrimId>,
    /// The longest path from the root to a leaf, in nodes; bounds the traversal stack.
    depth: usize,
}

/// Entries on the traversal stack: each level pushes at most `WIDTH - 1`, and the binary
/// trees stay under `bvh::MAX_DEPTH` levels, which bounds the collapsed ones too.
const STACK_SIZE: usize = (WIDTH - 1) * super::bvh::MAX_DEPTH + 1;

impl Bvh8 {
    /// Collapses the binary tree `nodes` over `prims`, or returns `None` when it has more
    /// primitives, or larger leaves, than the child references can encode.
    pub fn collapse(nodes: &[Node], prims: &[PrimId]) -> Option<Bvh8> {
        let leaves_fit = nodes
            .iter()
            .all(|n| !n.is_leaf() || n.prim_range().len() <= MAX_LEAF_PRIMS);
        if prims.len() > MAX_PRIMS || !leaves_fit {
            return None;
        }
        let mut tree = Bvh8 {
            nodes: Vec::with_capacity(nodes.len() / 4 + 1),
            prims: prims.to_vec(),
            depth: 0,
        };
        if !nodes.is_empty() {
            let root_children = if nodes[0].is_leaf() {
                vec![0]
            } else {
                children_of(nodes, 0)
            };
            tree.depth = tree.emit(nodes, root_children);
        }
        Some(tree)
    }

    /// Appends the node over the binary nodes `start` (expanded as the header says) and
    /// its subtrees; returns the subtree's depth.
    fn emit(&mut self, binary: &[Node], start: Vec<usize>) -> usize {
        let mut kids = start;
        while kids.len() < WIDTH {
            let widest = kids
                .iter()
                .enumerate()
                .filter(|(_, &i)| !binary[i].is_leaf())
                .max_by(|(_, &a), (_, &b)| binary[a].area().total_cmp(&binary[b].area()));
            let Some((k, _)) = widest else {
                break;
            };
            let i = kids.swap_remove(k);
            kids.extend(children_of(binary, i));
        }
        let index = self.nodes.len();
        self.nodes.push(Node8 {
            min: [[0.0; WIDTH]; 3],
            max: [[0.0; WIDTH]; 3],
            child: [0; WIDTH],
            count: kids.len() as u32,
        });
        let mut depth = 1;
        for (k, &i) in kids.iter().enumerate() {
            let node = &binary[i];
            let child = if node.is_leaf() {
                let range = node.prim_range();
                LEAF | ((range.len() as u32 - 1) << COUNT_SHIFT) | range.start as u32
            } else {
                let child = self.nodes.len() as u32;
                depth = depth.max(1 + self.emit(binary, children_of(binary, i)));
                child
            };
            let bounds = node.bounds();
            let slot = &mut self.nodes[index];
            for axis in 0..3 {
                slot.min[axis][k] = bounds.min[axis];
                slot.max[axis][k] = bounds.max[axis];
            }
            slot.child[k] = child;
        }
        depth
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    pub fn depth(&self) -> usize {
        self.depth
    }

    pub fn memory(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..]) + std::mem::size_of_val(&self.prims[..])
    }

    fn leaf_prims(&self, child: ChildRef) -> &[PrimId] {
        let first = (child & FIRST_MASK) as usize;
        let count = ((child & !LEAF) >> COUNT_SHIFT) as usize + 1;
        &self.prims[first..first + count]
    }

    pub fn closest(
        &self,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        closest: &mut ClosestHit,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [const { MaybeUninit::<(ChildRef, f32)>::uninit() }; STACK_SIZE];
        stack[0].write((0, t_min));
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            // SAFETY: every slot below `depth` was written before `depth` passed it.
            let (child, t_entry) = unsafe { stack[depth].assume_init() };
            // Entries beyond the closest hit cannot hold a closer one (ties may).
            if t_entry > closest.limit() {
                continue;
            }
            if child & LEAF != 0 {
                for &prim in self.leaf_prims(child) {
                    closest.test(geometry, prim, ray, inv_dir, t_min);
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let entries = node.entries(ray.origin, inv_dir, t_min, closest.limit());
            // Push the hit children farthest first, so the nearest is popped next.
            let first = depth;
            for (k, entry) in entries.iter().enumerate() {
                let Some(t) = *entry else {
                    continue;
                };
                let mut slot = depth;
                // SAFETY: slots `first..depth` were written in this loop.
                while slot > first && unsafe { stack[slot - 1].assume_init() }.1 < t {
                    let moved = unsafe { stack[slot - 1].assume_init() };
                    stack[slot].write(moved);
                    slot -= 1;
                }
                stack[slot].write((node.child[k], t));
                depth += 1;
            }
        }
    }

    pub fn occluded(
        &self,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = [const { MaybeUninit::<ChildRef>::uninit() }; STACK_SIZE];
        stack[0].write(0);
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            // SAFETY: every slot below `depth` was written before `depth` passed it.
            let child = unsafe { stack[depth].assume_init() };
            if child & LEAF != 0 {
                let blocked = self.leaf_prims(child).iter().any(|&prim| {
                    geometry
                        .intersect(prim, ray, inv_dir, t_min, t_max)
                        .is_some()
                });
                if blocked {
                    return true;
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            for (k, entry) in node
                .entries(ray.origin, inv_dir, t_min, t_max)
                .iter()
                .enumerate()
            {
                if entry.is_some() {
                    stack[depth].write(node.child[k]);
                    depth += 1;
                }
            }
        }
        false
    }
}

/// The two children of the interior binary node `i`.
fn children_of(nodes: &[Node], i: usize) -> Vec<usize> {
    vec![i + 1, nodes[i].right_child()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::{Bvh, BvhBuild, BvhWidth};
    use crate::scene::p3f::parse_text;

    impl Bvh8 {
        /// Every primitive in exactly one leaf, every child's box inside its parent's.
        fn validate(&self) {
            let mut seen = vec![0u32; self.prims.len()];
            let mut stack = vec![(0u32, [Vec3::NEG_INFINITY, Vec3::INFINITY])];
            while let Some((child, [lo, hi])) = stack.pop() {
                if child & LEAF != 0 {
                    let first = (child & FIRST_MASK) as usize;
                    for k in 0..self.leaf_prims(child).len() {
                        seen[first + k] += 1;
                    }
                    continue;
                }
                let node = &self.nodes[child as usize];
                assert!((1..=WIDTH as u32).contains(&node.count));
                for k in 0..node.count as usize {
                    let min = Vec3::new(node.min[0][k], node.min[1][k], node.min[2][k]);
                    let max = Vec3::new(node.max[0][k], node.max[1][k], node.max[2][k]);
                    assert!(
                        min.cmpge(lo).all() && max.cmple(hi).all(),
                        "child outside parent"
                    );
                    stack.push((node.child[k], [min, max]));
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
        }
    }

    #[test]
    fn collapse_keeps_every_primitive_once_inside_nested_boxes() {
        for n in [1, 2, 9, 100, 1000] {
            let text: String = (0..n)
                .map(|i| {
                    let x = (i * 37 % 101) as f32 * 0.3;
                    let y = (i * 53 % 89) as f32 * 0.2;
                    format!("s {x} {y} {} 0.1\n", i % 7)
                })
                .collect();
            let scene = parse_text(&text).unwrap();
            for build in [BvhBuild::Sah, BvhBuild::Midpoint] {
                let bvh = Bvh::build(&scene.geometry, build, BvhWidth::Eight, [0.0, 0.0]);
                let wide = bvh.wide().expect("small trees collapse");
                wide.validate();
                assert!(wide.depth() <= bvh.depth());
            }
        }
    }
}
