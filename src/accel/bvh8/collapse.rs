//! The conversion of a binary BVH into the 8-wide one. A node starts with its binary
//! node's two children, and the child with the largest surface area is replaced by its
//! own two children while fewer than eight remain and some child is interior (Wald et
//! al., "Getting Rid of Packets", 2008). The binary tree is consumed: its primitive order
//! is kept, its nodes freed once converted.

use std::ops::Range;

use glam::Vec3;

use super::node::{
    leaf_ref, ChildRef, Node8, MAX_LEAF_PRIMS, MAX_PRIMS, RUN, SPHERES, TRIANGLES, WIDTH,
};
use super::Bvh8;
use crate::accel::bvh2::{Bvh2, Node};
use crate::intersect::BoxPack8;
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;

impl Bvh8 {
    /// Converts the binary tree `bvh2`, which it consumes, or gives it back when it has
    /// more primitives, or larger leaves, than the child references can encode.
    pub fn collapse(bvh2: Bvh2, geometry: &Geometry) -> Result<Bvh8, Bvh2> {
        let leaves_fit = bvh2
            .nodes()
            .iter()
            .all(|n| !n.is_leaf() || n.prim_range().len() <= MAX_LEAF_PRIMS);
        if bvh2.prims().len() > MAX_PRIMS || !leaves_fit {
            return Err(bvh2);
        }
        let (binary, build) = (bvh2.stats(), bvh2.build_kind());
        let (nodes, prims) = bvh2.into_parts();
        let mut tree = Bvh8 {
            // Grown as needed: an estimate from the binary tree's size reserved many times
            // what a tree of one-primitive leaves uses (`tests/huge_scene.rs`: 5 million
            // nodes reserved, 0.3 million used).
            nodes: Vec::new(),
            prims,
            triangles: Vec::new(),
            spheres: Vec::new(),
            sphere_roots: geometry.spheres.roots,
            triangle_ids: Vec::new(),
            sphere_ids: Vec::new(),
            depth: 0,
            build,
            binary,
        };
        if !nodes.is_empty() {
            let binary = Binary::new(&nodes);
            let root_children = if binary.is_terminal(0, &tree.prims) {
                vec![0]
            } else {
                binary.children(0)
            };
            tree.depth = tree.emit(geometry, &binary, root_children);
        }
        // The render holds the tree: none of the arrays' growing slack.
        tree.nodes.shrink_to_fit();
        tree.triangles.shrink_to_fit();
        tree.spheres.shrink_to_fit();
        tree.triangle_ids.shrink_to_fit();
        tree.sphere_ids.shrink_to_fit();
        Ok(tree)
    }

    /// Appends the node over the binary nodes `start` (expanded as the header says) and
    /// its subtrees; returns the subtree's depth.
    fn emit(&mut self, geometry: &Geometry, binary: &Binary, start: Vec<usize>) -> usize {
        let mut kids = start;
        while kids.len() < WIDTH {
            let widest = kids
                .iter()
                .enumerate()
                .filter(|(_, &i)| !binary.is_terminal(i, &self.prims))
                .max_by(|(_, &a), (_, &b)| {
                    binary.nodes[a]
                        .bounds()
                        .area()
                        .total_cmp(&binary.nodes[b].bounds().area())
                });
            let Some((k, _)) = widest else {
                break;
            };
            let i = kids.swap_remove(k);
            kids.extend(binary.children(i));
        }
        let index = self.nodes.len();
        let boxes: Vec<(Vec3, Vec3)> = kids
            .iter()
            .map(|&i| {
                let b = binary.nodes[i].bounds();
                (b.min, b.max)
            })
            .collect();
        self.nodes.push(Node8 {
            boxes: BoxPack8::new(&boxes),
            child: [0; WIDTH],
            count: kids.len() as u32,
        });
        let mut depth = 1;
        for (k, &i) in kids.iter().enumerate() {
            let child = match binary.pack_kind(i, &self.prims) {
                Some(kind) => self.pack(geometry, kind, binary.range[i].clone()),
                None if binary.nodes[i].is_leaf() => {
                    let range = binary.range[i].clone();
                    leaf_ref(RUN, range.len(), range.start)
                }
                None => {
                    let child = self.nodes.len() as u32;
                    depth = depth.max(1 + self.emit(geometry, binary, binary.children(i)));
                    child
                }
            };
            self.nodes[index].child[k] = child;
        }
        depth
    }

    /// Stores the primitives `range` of `prims`, all of `kind`, as one pack.
    fn pack(&mut self, geometry: &Geometry, kind: PrimKind, range: Range<usize>) -> ChildRef {
        let ids = &self.prims[range];
        let mut lanes = [ids[0]; 8];
        lanes[..ids.len()].copy_from_slice(ids);
        let indices = ids.iter().map(|id| id.index());
        if kind == PrimKind::Triangle {
            self.triangles.push(geometry.triangles.pack(indices));
            self.triangle_ids.push(lanes);
            leaf_ref(TRIANGLES, ids.len(), self.triangles.len() - 1)
        } else {
            self.spheres.push(geometry.spheres.pack(indices));
            self.sphere_ids.push(lanes);
            leaf_ref(SPHERES, ids.len(), self.spheres.len() - 1)
        }
    }
}

/// The most primitives of one kind stored side by side in a leaf.
const PACK: usize = 8;

/// The binary tree with the run of primitives under each node.
struct Binary<'a> {
    nodes: &'a [Node],
    range: Vec<Range<usize>>,
}

impl<'a> Binary<'a> {
    fn new(nodes: &'a [Node]) -> Self {
        // Children follow their parent, so a backward sweep sees them first.
        let mut range = vec![0..0; nodes.len()];
        for i in (0..nodes.len()).rev() {
            range[i] = if nodes[i].is_leaf() {
                nodes[i].prim_range()
            } else {
                range[i + 1].start..range[nodes[i].right_child()].end
            };
        }
        Binary { nodes, range }
    }

    /// The two children of the interior node `i`.
    fn children(&self, i: usize) -> Vec<usize> {
        vec![i + 1, self.nodes[i].right_child()]
    }

    /// The kind of a subtree that becomes one pack: at most [`PACK`] triangles, or
    /// spheres (`prims` in the tree's order).
    fn pack_kind(&self, i: usize, prims: &[PrimId]) -> Option<PrimKind> {
        let prims = &prims[self.range[i].clone()];
        let kind = prims.first()?.kind();
        let packable = matches!(kind, PrimKind::Triangle | PrimKind::Sphere);
        (packable && prims.len() <= PACK && prims.iter().all(|p| p.kind() == kind)).then_some(kind)
    }

    /// Nodes that become leaves of the 8-wide tree.
    fn is_terminal(&self, i: usize, prims: &[PrimId]) -> bool {
        self.nodes[i].is_leaf() || self.pack_kind(i, prims).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh2::BvhBuild;
    use crate::accel::bvh8::node::{leaf_parts, LEAF};
    use crate::scene::p3f::parse_text;

    impl Bvh8 {
        /// Every primitive in exactly one leaf, every child's box inside its parent's.
        fn validate(&self) {
            let mut seen = vec![0u32; self.prims.len()];
            let mut stack = vec![(0u32, [Vec3::NEG_INFINITY, Vec3::INFINITY])];
            while let Some((child, [lo, hi])) = stack.pop() {
                if child & LEAF != 0 {
                    let (kind, count, index) = leaf_parts(child);
                    let ids: Vec<PrimId> = match kind {
                        TRIANGLES => self.triangle_ids[index][..count].to_vec(),
                        SPHERES => self.sphere_ids[index][..count].to_vec(),
                        _ => self.prims[index..index + count].to_vec(),
                    };
                    for id in ids {
                        let k = self.prims.iter().position(|&p| p == id).unwrap();
                        seen[k] += 1;
                    }
                    continue;
                }
                let node = &self.nodes[child as usize];
                assert!((1..=WIDTH as u32).contains(&node.count));
                for k in 0..node.count as usize {
                    let (min, max) = (node.boxes.min.lane(k), node.boxes.max.lane(k));
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
                let bvh2 = Bvh2::build(&scene.geometry, build, [0.0, 0.0]);
                let binary_depth = bvh2.depth();
                let wide = Bvh8::collapse(bvh2, &scene.geometry).expect("small trees collapse");
                wide.validate();
                assert!(wide.depth() <= binary_depth);
            }
        }
    }
}
