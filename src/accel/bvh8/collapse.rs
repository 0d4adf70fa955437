//! The conversion of a binary BVH into the 8-wide one. Which binary nodes become 8-wide
//! nodes, and which are opened into their parent's child slots, is chosen by dynamic
//! programming over the binary tree so that the 8-wide nodes' summed surface areas, their
//! SAH cost, are least (Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on
//! GPUs Through Compressed Wide BVHs", 2017): the leaves are the binary tree's whatever is
//! chosen. The binary tree is consumed: its primitive order
//! is kept, and its nodes are freed once the 8-wide nodes are made, before the packs are
//! filled, so that the two largest arrays are never held at once. On several threads a
//! large node's subtrees are made side by side and the packs filled side by side: the
//! same tree as on one.

use std::ops::Range;

use glam::Vec3;

use super::leaves::Leaves;
use super::node::{
    leaf_parts, leaf_ref, ChildRef, Node8, LEAF, MAX_LEAF_PRIMS, MAX_PRIMS, RUN, WIDTH,
};
use super::Bvh8;
use crate::accel::bvh2::{several_threads, Bvh2, BvhBuild, Node};
use crate::intersect::{BoxPack8, PackLayout};
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;
use rayon::prelude::*;

impl Bvh8 {
    /// The tree over `geometry` as [`Bvh2::build`] takes it, built binary as far as the
    /// packs and collapsed, its packs in `layout`; the binary tree when it does not fit
    /// ([`Bvh8::collapse`]).
    pub fn build(
        geometry: &Geometry,
        build: BvhBuild,
        shutter: [f32; 2],
        roots_margin: f32,
        layout: PackLayout,
    ) -> Result<Bvh8, Bvh2> {
        let bvh2 = Bvh2::build_for_packs(geometry, build, shutter, roots_margin, PACK);
        Self::collapse(bvh2, geometry, layout)
    }

    /// Converts the binary tree `bvh2`, which it consumes, its packs in `layout`, or gives
    /// it back when it has more primitives, or larger leaves, than the child references
    /// can encode.
    pub fn collapse(bvh2: Bvh2, geometry: &Geometry, layout: PackLayout) -> Result<Bvh8, Bvh2> {
        let leaves_fit = bvh2
            .nodes()
            .iter()
            .all(|n| !n.is_leaf() || n.prim_range().len() <= MAX_LEAF_PRIMS);
        if bvh2.prims().len() > MAX_PRIMS || !leaves_fit {
            return Err(bvh2);
        }
        let (stats, build) = (bvh2.stats(), bvh2.build_kind());
        let (nodes, prims) = bvh2.into_parts();
        let mut binary = Binary {
            nodes: &nodes,
            prims: &prims,
            costs: Vec::new(),
        };
        let root = Kid {
            node: 0,
            range: 0..prims.len(),
        };
        let Subtree {
            nodes: mut wide,
            mut packs,
            depth,
        } = match nodes.is_empty() {
            true => Subtree::default(),
            false => {
                let mut costs = vec![[0.0; WIDTH]; nodes.len()];
                binary.slot_costs(&root, &mut costs);
                binary.costs = costs;
                binary.subtree(root)
            }
        };
        drop(binary);
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
            compact: false,
        };
        tree.fill(geometry, &prims, packs, layout);
        tree.compact = tree.leaves.compact();
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
    fn fill(
        &mut self,
        geometry: &Geometry,
        prims: &[PrimId],
        mut packs: Vec<PackToFill>,
        layout: PackLayout,
    ) {
        let ids = |pack: &PackToFill| &prims[pack.start as usize..][..pack.len as usize];
        let kind_of = |pack: &PackToFill| prims[pack.start as usize].kind();
        // Each kind's packs side by side, in the order of `PrimKind::PACKED` (which their
        // codes follow), and still in their order within a kind (a scene of one packed
        // kind has them so: no sort's scratch beside them).
        if !packs.is_sorted_by_key(|pack| kind_of(pack) as u8) {
            packs.sort_by_key(|pack| kind_of(pack) as u8);
        }
        let mut rest = &packs[..];
        for kind in PrimKind::PACKED {
            let (these, after) = rest.split_at(rest.partition_point(|p| kind_of(p) == kind));
            let (code, first, moved) =
                (self.leaves).extend(geometry, kind, layout, these.len(), |i| ids(&these[i]));
            let place = |i: usize| moved.get(&i).copied().unwrap_or(first + i);
            for (i, pack) in these.iter().enumerate() {
                self.nodes[pack.node as usize].child[pack.slot as usize] =
                    leaf_ref(code, pack.len as usize, place(i));
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

/// What a binary subtree costs the 8-wide tree when it may take up to `k + 1` of its
/// 8-wide parent's child slots (at index `k`): the summed surface areas of the 8-wide
/// nodes it then needs.
type SlotCosts = [f32; WIDTH];

/// The binary tree, its primitive order, and its interior nodes' [`SlotCosts`] (indexed
/// as the nodes).
struct Binary<'a> {
    nodes: &'a [Node],
    prims: &'a [PrimId],
    costs: Vec<SlotCosts>,
}

/// The least cost of the subtrees `left` and `right` sharing `slots` child slots, and how
/// many of them go to `left` (the fewest, among equal costs).
fn shared_slots(left: &SlotCosts, right: &SlotCosts, slots: usize) -> (f32, usize) {
    (1..slots)
        .map(|a| (left[a - 1] + right[slots - a - 1], a))
        .fold((f32::INFINITY, 1), |best, next| match next.0 < best.0 {
            true => next,
            false => best,
        })
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
    fn children(&self, kid: &Kid) -> [Kid; 2] {
        let right = self.nodes[kid.node].right_child();
        let mut first = right;
        while !self.nodes[first].is_leaf() {
            first += 1;
        }
        let split = self.nodes[first].prim_range().start;
        [
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

    /// Writes the [`SlotCosts`] of `kid` and of every node below it into `costs`, whose
    /// first entry is `kid`'s (the nodes of a subtree follow its root), and returns
    /// `kid`'s. A terminal node takes one slot and costs nothing.
    fn slot_costs(&self, kid: &Kid, costs: &mut [SlotCosts]) -> SlotCosts {
        let mut own = [0.0; WIDTH];
        let (first, below) = costs.split_at_mut(1);
        if !self.is_terminal(kid) {
            let [left, right] = self.children(kid);
            let (left_costs, right_costs) = below.split_at_mut(right.node - left.node);
            let mut left_side = || self.slot_costs(&left, left_costs);
            let mut right_side = || self.slot_costs(&right, right_costs);
            let (l, r) = match kid.range.len() > PARALLEL_COLLAPSE && several_threads() {
                true => rayon::join(left_side, right_side),
                false => (left_side(), right_side()),
            };
            // One slot: an 8-wide node over the best use of all eight below it.
            own[0] = self.nodes[kid.node].bounds().area() + shared_slots(&l, &r, WIDTH).0;
            for slots in 2..=WIDTH {
                own[slots - 1] = own[slots - 2].min(shared_slots(&l, &r, slots).0);
            }
        }
        first[0] = own;
        own
    }

    /// The children of the 8-wide node over the binary node `over`, as
    /// [`Binary::slot_costs`] chose them: a terminal root is its own one child.
    fn expand(&self, over: Kid) -> Vec<Kid> {
        let mut kids = Vec::with_capacity(WIDTH);
        if self.is_terminal(&over) {
            kids.push(over);
            return kids;
        }
        let [left, right] = self.children(&over);
        let a = shared_slots(self.cost(&left), self.cost(&right), WIDTH).1;
        self.place(left, a, &mut kids);
        self.place(right, WIDTH - a, &mut kids);
        // Occlusion walks visit a node's last child first: the leaves before the nodes,
        // each the largest first, the likeliest to block a ray (a sixth fewer leaves
        // entered at level 10 of `gen mount`, and fewer nodes).
        let area = |kid: &Kid| self.nodes[kid.node].bounds().area();
        kids.sort_by(|a, b| {
            (self.is_terminal(a).cmp(&self.is_terminal(b))).then(area(a).total_cmp(&area(b)))
        });
        kids
    }

    /// Appends to `kids` the children that `kid` becomes given `slots` slots: itself, or
    /// its own children's where opening it costs less (or the same: fewer nodes).
    fn place(&self, kid: Kid, slots: usize, kids: &mut Vec<Kid>) {
        if slots > 1 && !self.is_terminal(&kid) {
            let best = self.cost(&kid)[slots - 1];
            let [left, right] = self.children(&kid);
            let (l, r) = (self.cost(&left), self.cost(&right));
            let opened = (2..=slots)
                .map(|s| (s, shared_slots(l, r, s)))
                .find(|&(_, (cost, _))| cost <= best);
            if let Some((s, (_, a))) = opened {
                self.place(left, a, kids);
                self.place(right, s - a, kids);
                return;
            }
        }
        kids.push(kid);
    }

    fn cost(&self, kid: &Kid) -> &SlotCosts {
        &self.costs[kid.node]
    }

    /// The 8-wide subtree whose root is over the binary node `over`.
    fn subtree(&self, over: Kid) -> Subtree {
        let mut tree = Subtree::default();
        tree.depth = self.emit(over, &mut tree);
        tree
    }

    /// Appends to `tree` the node over the binary node `over` and its subtrees, and the
    /// packs their leaves will hold; returns the depth of what it appended. A node over
    /// many primitives has its children's subtrees made on rayon's threads, each into
    /// its own, and appended in order: the nodes and packs of a walk on one thread.
    fn emit(&self, over: Kid, tree: &mut Subtree) -> usize {
        let kids = self.expand(over);
        let index = tree.nodes.len();
        // On the stack: one allocation a node fewer.
        let mut boxes = [(Vec3::ZERO, Vec3::ZERO); WIDTH];
        for (slot, kid) in boxes.iter_mut().zip(&kids) {
            let b = self.nodes[kid.node].bounds();
            *slot = (b.min, b.max);
        }
        tree.nodes.push(Node8 {
            boxes: BoxPack8::new(&boxes[..kids.len()]),
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
                    .map(|kid| interior(kid).then(|| self.subtree(kid.clone())))
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
                        None => self.emit(kid.clone(), tree),
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
        // The length first: the kinds of a large subtree are not read.
        if kid.range.len() > PACK {
            return None;
        }
        PrimId::shared_kind(&self.prims[kid.range.clone()]).filter(|kind| kind.is_packed())
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
    use crate::intersect::Aabb;
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
                        RUN => self.prims[index..index + count].to_vec(),
                        _ => self.leaves.prims(child),
                    };
                    for id in &ids {
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
            pool.install(|| {
                Bvh8::build(
                    &scene.geometry,
                    BvhBuild::Sah,
                    [0.0; 2],
                    0.0,
                    PackLayout::Auto,
                )
            })
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

    /// The summed surface areas of `tree`'s nodes (each the union of its children's boxes).
    fn node_areas(tree: &Bvh8) -> f64 {
        let area = |node: &Node8| {
            let child = |k| {
                let (min, max) = node.boxes.corners(k);
                Aabb { min, max }
            };
            let union = (0..node.count as usize)
                .map(child)
                .fold(Aabb::EMPTY, Aabb::union);
            union.area() as f64
        };
        tree.nodes.iter().map(area).sum()
    }

    /// The least summed area over every choice of the binary tree's interior nodes that
    /// become 8-wide nodes (the root always does), each with at most eight children.
    fn least_areas_by_enumeration(nodes: &[Node]) -> f64 {
        let interior: Vec<usize> = (0..nodes.len()).filter(|&i| !nodes[i].is_leaf()).collect();
        assert!(interior.len() <= 20, "too many to enumerate");
        let children = |i: usize| [i + 1, nodes[i].right_child()];
        let mut least = f64::INFINITY;
        for choice in 0u32..1 << (interior.len() - 1) {
            // Bit k - 1 says whether interior node k (after the root) is an 8-wide node.
            let wide = |i: usize| {
                let k = interior.iter().position(|&n| n == i).unwrap();
                k == 0 || choice >> (k - 1) & 1 != 0
            };
            let slots = |i: usize| {
                let mut open = children(i).to_vec();
                let mut count = 0;
                while let Some(n) = open.pop() {
                    match nodes[n].is_leaf() || wide(n) {
                        true => count += 1,
                        false => open.extend(children(n)),
                    }
                }
                count
            };
            let wides: Vec<usize> = interior.iter().copied().filter(|&i| wide(i)).collect();
            if wides.iter().all(|&i| slots(i) <= WIDTH) {
                let areas = wides.iter().map(|&i| nodes[i].bounds().area() as f64);
                least = least.min(areas.sum());
            }
        }
        least
    }

    #[test]
    fn collapse_chooses_the_nodes_of_least_summed_area() {
        let mut compared = 0;
        for (n, seed) in (20u32..200).step_by(5).zip(1u32..) {
            let text: String = (0..n)
                .map(|i| {
                    let h = |k: u32| {
                        ((i.wrapping_mul(2654435761) ^ (seed * k)).wrapping_mul(k) >> 8) % 997
                    };
                    let r = 0.05 + (h(7) % 40) as f32 * 0.02;
                    let (x, y, z) = (
                        h(11) as f32 * 0.01,
                        h(13) as f32 * 0.02,
                        h(17) as f32 * 0.005,
                    );
                    format!("s {x} {y} {z} {r}\n")
                })
                .collect();
            let scene = parse_text(&text).unwrap();
            let bvh2 = Bvh2::build_for_packs(&scene.geometry, BvhBuild::Sah, [0.0; 2], 0.0, PACK);
            // Enough interior nodes that some must stay closed, few enough to enumerate.
            let interior = bvh2.nodes().iter().filter(|node| !node.is_leaf()).count();
            if !(10..=18).contains(&interior) {
                continue;
            }
            compared += 1;
            let least = least_areas_by_enumeration(bvh2.nodes());
            let wide = Bvh8::collapse(bvh2, &scene.geometry, PackLayout::Auto)
                .expect("small trees collapse");
            let chosen = node_areas(&wide);
            assert!(
                (chosen - least).abs() <= 1e-5 * least,
                "{n}: {chosen} against {least}"
            );
        }
        assert!(compared >= 4, "{compared} trees compared");
    }

    /// Triangles of vertices of their own, close together: compact leaves of more than
    /// four take two packs, and every triangle is in one leaf.
    #[test]
    fn compact_leaves_of_a_soup_go_on_in_a_second_pack() {
        let text: String = (0..500)
            .map(|i| {
                let (x, y, z) = ((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32);
                let (x2, y2) = (x + 0.5, y + 0.5);
                format!("p 3 {x} {y} {z} {x2} {y} {z} {x} {y2} {z}\n")
            })
            .collect();
        let scene = parse_text(&text).unwrap();
        let wide = Bvh8::build(
            &scene.geometry,
            BvhBuild::Sah,
            [0.0; 2],
            0.0,
            PackLayout::Compact,
        )
        .expect("the tree fits");
        let all: Vec<PrimId> = scene.geometry.ids(PrimKind::Triangle).collect();
        wide.validate(&all);
        let leaves = wide
            .nodes
            .iter()
            .flat_map(|n| n.child[..n.count as usize].iter());
        let chained = leaves
            .filter(|&&c| c & LEAF != 0 && leaf_parts(c).1 > crate::intersect::CHAIN_HEAD)
            .count();
        assert!(chained > 0, "no leaf of more than four triangles");
    }

    /// Spheres, and triangles of vertices of their own (a compact leaf of more than four
    /// takes two packs), in both layouts.
    #[test]
    fn collapse_keeps_every_primitive_once_inside_nested_boxes() {
        for n in [1, 2, 9, 100, 1000] {
            let text: String = (0..n)
                .map(|i| {
                    let x = (i * 37 % 101) as f32 * 0.3;
                    let y = (i * 53 % 89) as f32 * 0.2;
                    let z = i % 7;
                    let (x2, z2) = (x + 0.5, z as f32 + 0.5);
                    format!("s {x} {y} {z} 0.1\np 3 {x} {y} {z} {x} {y} {z2} {x2} {y} {z}\n")
                })
                .collect();
            let scene = parse_text(&text).unwrap();
            for build in [BvhBuild::Sah, BvhBuild::Midpoint] {
                for layout in [PackLayout::Full, PackLayout::Compact] {
                    let bvh2 = Bvh2::build(&scene.geometry, build, [0.0, 0.0], 0.0);
                    let (binary_depth, all) = (bvh2.depth(), bvh2.prims().to_vec());
                    let wide = Bvh8::collapse(bvh2, &scene.geometry, layout)
                        .expect("small trees collapse");
                    wide.validate(&all);
                    assert!(wide.depth() <= binary_depth);
                    // (The midpoint build's leaves of a sphere and a triangle are runs.)
                    if n > 2 {
                        assert_eq!(wide.compact, layout == PackLayout::Compact);
                    }
                }
            }
        }
    }
}
