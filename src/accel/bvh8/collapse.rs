//! The conversion of a binary BVH into the 8-wide one. A node starts with its binary
//! node's two children, and the child with the largest surface area is replaced by its
//! own two children while fewer than eight remain and some child is interior (Wald et
//! al., "Getting Rid of Packets", 2008). The binary tree is consumed: its primitive order
//! is kept, and its nodes are freed once the 8-wide nodes are made, before the packs are
//! filled, so that the two largest arrays are never held at once. A first pass counts the
//! 8-wide tree's nodes and packs, so that its arrays are allocated once at their size.

use std::ops::Range;

use glam::Vec3;

use super::leaves::{count_index, Leaves, PackCounts};
use super::node::{leaf_ref, Node8, MAX_LEAF_PRIMS, MAX_PRIMS, RUN, WIDTH};
use super::Bvh8;
use crate::accel::bvh2::{Bvh2, BvhBuild, Node};
use crate::intersect::BoxPack8;
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;

impl Bvh8 {
    /// The tree over `geometry` as [`Bvh2::build`] takes it, built binary as far as the
    /// packs and collapsed; the binary tree when it does not fit ([`Bvh8::collapse`]).
    pub fn build(
        geometry: &Geometry,
        build: BvhBuild,
        shutter: [f32; 2],
        roots_margin: f32,
    ) -> Result<Bvh8, Bvh2> {
        let bvh2 = Bvh2::build_for_packs(geometry, build, shutter, roots_margin, PACK);
        Self::collapse(bvh2, geometry)
    }

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
        let (stats, build) = (bvh2.stats(), bvh2.build_kind());
        let (nodes, prims) = bvh2.into_parts();
        let binary = Binary {
            nodes: &nodes,
            prims: &prims,
        };
        let root = Kid {
            node: 0,
            range: 0..prims.len(),
        };
        let root_kids = if nodes.is_empty() {
            vec![]
        } else if binary.is_terminal(&root) {
            vec![root]
        } else {
            binary.children(&root)
        };
        // Counted first and allocated at their size: growing them held up to twice that,
        // and copied them, beside the binary tree at its largest
        // (`tests/memory/huge_mesh.rs`).
        let mut size = Size::default();
        if !root_kids.is_empty() {
            binary.size(root_kids.clone(), &mut size);
        }
        let mut tree = Bvh8 {
            nodes: Vec::with_capacity(size.nodes),
            prims: Vec::new(),
            leaves: Leaves::with_capacity(&PackCounts::default()),
            depth: 0,
            build,
            binary: stats,
        };
        let mut packs = Vec::with_capacity(size.packs.iter().sum());
        if !root_kids.is_empty() {
            tree.depth = tree.emit(&binary, root_kids, &mut packs);
        }
        drop(nodes);
        tree.leaves = Leaves::with_capacity(&size.packs);
        for pack in packs {
            let ids = &prims[pack.start as usize..][..pack.len as usize];
            tree.nodes[pack.node as usize].child[pack.slot as usize] =
                tree.leaves.push(geometry, ids);
        }
        tree.prims = prims;
        Ok(tree)
    }

    /// Appends the node over the binary nodes `start` (expanded by [`Binary::expand`])
    /// and its subtrees, and to `packs` the packs its leaves will hold, in the order they
    /// are to be stored; returns the subtree's depth.
    fn emit(&mut self, binary: &Binary, start: Vec<Kid>, packs: &mut Vec<PackToFill>) -> usize {
        let kids = binary.expand(start);
        let index = self.nodes.len();
        let boxes: Vec<(Vec3, Vec3)> = kids
            .iter()
            .map(|kid| {
                let b = binary.nodes[kid.node].bounds();
                (b.min, b.max)
            })
            .collect();
        self.nodes.push(Node8 {
            boxes: BoxPack8::new(&boxes),
            child: [0; WIDTH],
            count: kids.len() as u32,
        });
        let mut depth = 1;
        for (k, kid) in kids.iter().enumerate() {
            let child = match binary.pack_kind(kid) {
                Some(_) => {
                    packs.push(PackToFill {
                        node: index as u32,
                        slot: k as u8,
                        len: kid.range.len() as u8,
                        start: kid.range.start as u32,
                    });
                    // Until the packs are filled.
                    0
                }
                None if binary.nodes[kid.node].is_leaf() => {
                    leaf_ref(RUN, kid.range.len(), kid.range.start)
                }
                None => {
                    let child = self.nodes.len() as u32;
                    depth = depth.max(1 + self.emit(binary, binary.children(kid), packs));
                    child
                }
            };
            self.nodes[index].child[k] = child;
        }
        depth
    }
}

/// The most primitives of one kind stored side by side in a leaf.
const PACK: usize = 8;

/// A pack to fill once the binary nodes are freed: its primitives, `len` from `start` in
/// the primitive order, and the child `slot` of `node` that will refer to it.
struct PackToFill {
    node: u32,
    slot: u8,
    len: u8,
    start: u32,
}

/// A node of the binary tree and the run of primitives under it.
#[derive(Clone)]
struct Kid {
    node: usize,
    range: Range<usize>,
}

/// The binary tree and its primitive order.
struct Binary<'a> {
    nodes: &'a [Node],
    prims: &'a [PrimId],
}

/// What an 8-wide tree holds: its nodes, and its packs of each packed kind.
#[derive(Default)]
struct Size {
    nodes: usize,
    packs: PackCounts,
}

impl Binary<'_> {
    /// The two children of the interior node `kid`. The right one's primitives start at
    /// its leftmost leaf's, which its left children lead to: no range is stored per node.
    fn children(&self, kid: &Kid) -> Vec<Kid> {
        let right = self.nodes[kid.node].right_child();
        let mut first = right;
        while !self.nodes[first].is_leaf() {
            first += 1;
        }
        let split = self.nodes[first].prim_range().start;
        vec![
            Kid {
                node: kid.node + 1,
                range: kid.range.start..split,
            },
            Kid {
                node: right,
                range: split..kid.range.end,
            },
        ]
    }

    /// The children of the 8-wide node over `start`: the child with the largest surface
    /// area replaced by its own two children while fewer than eight remain and some child
    /// is interior.
    fn expand(&self, start: Vec<Kid>) -> Vec<Kid> {
        let mut kids = start;
        while kids.len() < WIDTH {
            let widest = kids
                .iter()
                .enumerate()
                .filter(|(_, kid)| !self.is_terminal(kid))
                .max_by(|(_, a), (_, b)| {
                    let area = |kid: &Kid| self.nodes[kid.node].bounds().area();
                    area(a).total_cmp(&area(b))
                });
            let Some((k, _)) = widest else {
                break;
            };
            let kid = kids.swap_remove(k);
            kids.extend(self.children(&kid));
        }
        kids
    }

    /// Adds to `size` what [`Bvh8::emit`] appends for the node over `start`.
    fn size(&self, start: Vec<Kid>, size: &mut Size) {
        size.nodes += 1;
        for kid in self.expand(start) {
            match self.pack_kind(&kid) {
                Some(kind) => size.packs[count_index(kind)] += 1,
                None if self.nodes[kid.node].is_leaf() => {}
                None => self.size(self.children(&kid), size),
            }
        }
    }

    /// The kind of a subtree that becomes one pack: at most [`PACK`] primitives of one
    /// packed kind.
    fn pack_kind(&self, kid: &Kid) -> Option<PrimKind> {
        let prims = &self.prims[kid.range.clone()];
        let kind = PrimId::shared_kind(prims)?;
        (kind.is_packed() && prims.len() <= PACK).then_some(kind)
    }

    /// Nodes that become leaves of the 8-wide tree.
    fn is_terminal(&self, kid: &Kid) -> bool {
        self.nodes[kid.node].is_leaf() || self.pack_kind(kid).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
                    let ids = match kind {
                        RUN => &self.prims[index..index + count],
                        _ => &self.leaves.ids(child)[..count],
                    };
                    for id in ids {
                        let k = self.prims.iter().position(|p| p == id).unwrap();
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
                let bvh2 = Bvh2::build(&scene.geometry, build, [0.0, 0.0], 0.0);
                let binary_depth = bvh2.depth();
                let wide = Bvh8::collapse(bvh2, &scene.geometry).expect("small trees collapse");
                wide.validate();
                assert!(wide.depth() <= binary_depth);
            }
        }
    }
}
