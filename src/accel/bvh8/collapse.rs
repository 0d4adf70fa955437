//! The conversion of a binary BVH into the 8-wide one. A node starts with its binary
//! node's two children, and the child with the largest surface area is replaced by its
//! own two children while fewer than eight remain and some child is interior (Wald et
//! al., "Getting Rid of Packets", 2008). The binary tree is consumed: its primitive order
//! is kept, and its nodes are freed once the 8-wide nodes are made, before the packs are
//! filled, so that the two largest arrays are never held at once. On several threads a
//! large node's subtrees are made side by side and the packs filled side by side: the
//! same tree as on one.

use std::ops::Range;

use glam::Vec3;

use super::leaves::Leaves;
use super::node::{
    leaf_parts, leaf_ref, pack_code, ChildRef, Node8, LEAF, MAX_LEAF_PRIMS, MAX_PRIMS, RUN, WIDTH,
};
use super::Bvh8;
use crate::accel::bvh2::{several_threads, Bvh2, BvhBuild, Node};
use crate::intersect::BoxPack8;
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;
use rayon::prelude::*;

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
        let Subtree {
            nodes: mut wide,
            mut packs,
            depth,
        } = match root_kids.is_empty() {
            true => Subtree::default(),
            false => binary.subtree(root_kids),
        };
        drop(nodes);
        // Trimmed before the packs are allocated: trimmed beside them, the copy and the
        // grown array held with them made the peak of `tests/memory/huge_mesh.rs`. Each
        // kind's packs are then allocated at their number by `fill`.
        wide.shrink_to_fit();
        packs.shrink_to_fit();
        let mut tree = Bvh8 {
            nodes: wide,
            prims: Vec::new(),
            leaves: Leaves::new(),
            depth,
            build,
            binary: stats,
        };
        tree.fill(geometry, &prims, packs);
        // The packs hold their own ids: the order is kept only for runs to index.
        if tree.has_runs() {
            tree.prims = prims;
        }
        Ok(tree)
    }

    /// Whether a leaf is a run of the primitive order rather than a pack.
    fn has_runs(&self) -> bool {
        let run = |&child: &ChildRef| child & LEAF != 0 && leaf_parts(child).0 == RUN;
        (self.nodes.iter()).any(|node| node.child[..node.count as usize].iter().any(run))
    }

    /// Fills the packs `packs` over `prims`, each kind's in the order they come (on
    /// rayon's threads), and points their nodes' children at them.
    fn fill(&mut self, geometry: &Geometry, prims: &[PrimId], mut packs: Vec<PackToFill>) {
        let ids = |pack: &PackToFill| &prims[pack.start as usize..][..pack.len as usize];
        let kind_of = |pack: &PackToFill| prims[pack.start as usize].kind();
        // Each kind's packs side by side, in the order of `PrimKind::PACKED` (which their
        // codes follow), and still in their order within a kind (a scene of one packed
        // kind has them so: no sort's scratch beside them).
        if !packs.is_sorted_by_key(|pack| pack_code(kind_of(pack))) {
            packs.sort_by_key(|pack| pack_code(kind_of(pack)));
        }
        let mut rest = &packs[..];
        for kind in PrimKind::PACKED {
            let (these, after) = rest.split_at(rest.partition_point(|p| kind_of(p) == kind));
            let first = self
                .leaves
                .extend(geometry, kind, these.len(), |i| ids(&these[i]));
            for (i, pack) in these.iter().enumerate() {
                self.nodes[pack.node as usize].child[pack.slot as usize] =
                    leaf_ref(pack_code(kind), pack.len as usize, first + i);
            }
            rest = after;
        }
    }
}

/// The most primitives of one kind stored side by side in a leaf.
const PACK: usize = 8;

/// Nodes over more primitives than this make their children's subtrees on rayon's threads.
const PARALLEL_COLLAPSE: usize = 4096;

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

/// An 8-wide subtree: its nodes, depth first from its root, their children counted from
/// it; the packs its leaves will hold, in the order they are to be stored; its depth.
#[derive(Default)]
struct Subtree {
    nodes: Vec<Node8>,
    packs: Vec<PackToFill>,
    depth: usize,
}

impl Subtree {
    /// Appends `sub` after the nodes held, its children counted from here; returns its
    /// depth.
    fn append(&mut self, sub: Subtree) -> usize {
        let base = self.nodes.len() as u32;
        self.nodes.extend(sub.nodes.into_iter().map(|mut node| {
            for child in &mut node.child[..node.count as usize] {
                // Leaves keep their references, and a pack's slot its 0 until filled (no
                // node refers to a subtree's root).
                if *child & LEAF == 0 && *child != 0 {
                    *child += base;
                }
            }
            node
        }));
        self.packs
            .extend(sub.packs.into_iter().map(|pack| PackToFill {
                node: pack.node + base,
                ..pack
            }));
        sub.depth
    }
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

    /// The 8-wide subtree over the binary nodes `start` (expanded by [`Binary::expand`]).
    fn subtree(&self, start: Vec<Kid>) -> Subtree {
        let mut tree = Subtree::default();
        tree.depth = self.emit(start, &mut tree);
        tree
    }

    /// Appends to `tree` the node over the binary nodes `start` and its subtrees, and the
    /// packs their leaves will hold; returns the depth of what it appended. A node over
    /// many primitives has its children's subtrees made on rayon's threads, each into
    /// its own, and appended in order: the nodes and packs of a walk on one thread.
    fn emit(&self, start: Vec<Kid>, tree: &mut Subtree) -> usize {
        let kids = self.expand(start);
        let index = tree.nodes.len();
        let boxes: Vec<(Vec3, Vec3)> = kids
            .iter()
            .map(|kid| {
                let b = self.nodes[kid.node].bounds();
                (b.min, b.max)
            })
            .collect();
        tree.nodes.push(Node8 {
            boxes: BoxPack8::new(&boxes),
            child: [0; WIDTH],
            count: kids.len() as u32,
        });
        let interior = |kid: &Kid| !self.is_terminal(kid);
        let mut made: Vec<Option<Subtree>> =
            match kids.iter().map(|kid| kid.range.len()).sum::<usize>() > PARALLEL_COLLAPSE
                && several_threads()
            {
                true => kids
                    .par_iter()
                    .map(|kid| interior(kid).then(|| self.subtree(self.children(kid))))
                    .collect(),
                false => Vec::new(),
            };
        let mut depth = 1;
        for (k, kid) in kids.iter().enumerate() {
            let child = match self.pack_kind(kid) {
                Some(_) => {
                    tree.packs.push(PackToFill {
                        node: index as u32,
                        slot: k as u8,
                        len: kid.range.len() as u8,
                        start: kid.range.start as u32,
                    });
                    // Until the packs are filled.
                    0
                }
                None if self.nodes[kid.node].is_leaf() => {
                    leaf_ref(RUN, kid.range.len(), kid.range.start)
                }
                None => {
                    let child = tree.nodes.len() as u32;
                    let below = match made.get_mut(k).and_then(Option::take) {
                        Some(sub) => tree.append(sub),
                        None => self.emit(self.children(kid), tree),
                    };
                    depth = depth.max(1 + below);
                    child
                }
            };
            tree.nodes[index].child[k] = child;
        }
        depth
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
        /// Every primitive of `all` in exactly one leaf, every child's box inside its
        /// parent's.
        fn validate(&self, all: &[PrimId]) {
            let mut seen = vec![0u32; all.len()];
            let mut stack = vec![(0u32, [Vec3::NEG_INFINITY, Vec3::INFINITY])];
            while let Some((child, [lo, hi])) = stack.pop() {
                if child & LEAF != 0 {
                    let (kind, count, index) = leaf_parts(child);
                    let ids = match kind {
                        RUN => &self.prims[index..index + count],
                        _ => &self.leaves.ids(child)[..count],
                    };
                    for id in ids {
                        let k = all.iter().position(|p| p == id).unwrap();
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
    fn several_threads_give_the_one_thread_tree() {
        // Spheres and triangles mixed, over enough for the parallel collapse.
        let text: String = (0..3 * PARALLEL_COLLAPSE)
            .map(|i| {
                let (x, y, z) = (i % 17, (i / 17) % 13, i / 221);
                match i % 3 {
                    0 => format!("p 3\n{x} {y} {z}\n{x}.5 {y} {z}\n{x} {y}.5 {z}\n"),
                    _ => format!("s {x} {y} {z} 0.05\n"),
                }
            })
            .collect();
        let scene = parse_text(&text).unwrap();
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| Bvh8::build(&scene.geometry, BvhBuild::Sah, [0.0; 2], 0.0))
                .expect("the tree fits")
        };
        let (one, two) = (build(1), build(2));
        // Packs of both kinds, filled each in its turn.
        let mut kinds: Vec<u32> = (one.nodes.iter())
            .flat_map(|node| node.child[..node.count as usize].to_vec())
            .filter(|&child| child & LEAF != 0)
            .map(|child| leaf_parts(child).0)
            .collect();
        kinds.sort();
        kinds.dedup();
        assert_eq!(kinds.len(), 2, "{kinds:?}");
        assert_eq!(format!("{one:?}"), format!("{two:?}"));
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
                let (binary_depth, all) = (bvh2.depth(), bvh2.prims().to_vec());
                let wide = Bvh8::collapse(bvh2, &scene.geometry).expect("small trees collapse");
                wide.validate(&all);
                assert!(wide.depth() <= binary_depth);
            }
        }
    }
}
