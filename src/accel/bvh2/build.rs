//! The two builds of the binary BVH: the course report's midpoint split and the binned
//! SAH. Both write nodes depth first, a large subtree's halves on two threads, and reorder
//! the primitives so that each leaf's are contiguous.

use glam::Vec3A;

use super::{BvhBuild, Node, TRAVERSAL_COST};
use crate::accel::bounds::prim_bounds;
use crate::intersect::Aabb;
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;
use rayon::prelude::*;

/// The most primitives in an SAH leaf (a leaf can later be tested 8 at a time).
pub const MAX_LEAF: usize = 8;
/// Leaves of the report's BVH hold at most this many objects.
const MIDPOINT_LEAF: usize = 2;
/// Bins per axis of the SAH sweep: a power of two, for [`bin_of`]'s mask.
const BINS: usize = 16;
const _: () = assert!(BINS.is_power_of_two());
/// Below this depth a build may split as it likes; deeper, it splits at the median so
/// the depth stays under [`super::MAX_DEPTH`] whatever the input.
const FREE_DEPTH: usize = 64;
/// Subtrees over more primitives than this are built on two threads.
const PARALLEL_BUILD: usize = 4096;

/// Whether the passes over many items are split among rayon's threads: on one thread
/// the splitting cost the build of `gen balls --depth 6` about 7%.
pub(in crate::accel) fn several_threads() -> bool {
    rayon::current_num_threads() > 1
}

/// How a build splits: its kind, and the most primitives of one packed kind
/// ([`PrimKind::is_packed`]) that it leaves unsplit, 0 for none. A tree to be collapsed
/// into the 8-wide one stops there, as the collapse makes such a subtree one pack whatever
/// lies below it: the same packs and 8-wide nodes, for fewer binary nodes and splits.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rules {
    pub build: BvhBuild,
    pub pack_leaves: usize,
    /// The pack size by which the SAH counts a side's primitives, 0 to count them one by
    /// one ([`PACKS_COUNTED_FROM`]); set by [`build`].
    pub sah_pack: usize,
}

/// Trees for packs over at least this many primitives are split by the packs their sides
/// fill: fuller packs (7.3 primitives a pack at `gen mount --level 10`, against 6.1) and a
/// sixth fewer bytes, which pay where the tree outgrows the caches. `bench`, best paths,
/// against counting primitives (Xeon, native, 2026-12-06): level 10 1.02-1.04, level 9
/// 0.99-1.03; below, level 8 0.98-1.00, and the three benchmark scenes lost (dragon
/// 0.96-0.98, balls_high 0.92-0.94): a pack read from the cache costs its primitives' tests.
const PACKS_COUNTED_FROM: usize = 1 << 19;

impl Rules {
    /// Whether `items` are left a leaf for a pack.
    fn is_pack_leaf(&self, items: &[Item]) -> bool {
        let Some(first) = items.first() else {
            return false;
        };
        let kind = first.prim.kind();
        items.len() <= self.pack_leaves
            && kind.is_packed()
            && items.iter().all(|it| it.prim.kind() == kind)
    }
}

/// A primitive during the build: 28 bytes, for the items and the nodes are the build's
/// largest arrays. The centroid is the box's centre, recomputed where it is needed.
#[derive(Clone, Copy)]
struct Item {
    bounds: Aabb,
    prim: PrimId,
}

impl Item {
    /// The centroid, as a vector (its lanes as [`Item::centroid`] computes them).
    #[inline(always)]
    fn centre(&self) -> Vec3A {
        0.5 * (Vec3A::from(self.bounds.min) + Vec3A::from(self.bounds.max))
    }

    /// The centroid's coordinate on `axis` (as `Aabb::centre` computes it).
    fn centroid(&self, axis: usize) -> f32 {
        0.5 * (self.bounds.min[axis] + self.bounds.max[axis])
    }
}

const _: () = assert!(std::mem::size_of::<Item>() == 28);

/// The box of a node's items and the box of their centroids: a split finds its children's
/// as it splits (from its bins and as it moves the items), so that no node passes over
/// its items again to find them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Boxes {
    bounds: Aabb,
    centroids: Aabb,
}

impl Boxes {
    const EMPTY: Boxes = Boxes {
        bounds: Aabb::EMPTY,
        centroids: Aabb::EMPTY,
    };

    fn of(items: &[Item]) -> Boxes {
        items.iter().fold(Boxes::EMPTY, |b, it| Boxes {
            bounds: b.bounds.union(it.bounds),
            centroids: b.centroids.grow(it.bounds.centre()),
        })
    }

    /// [`Boxes::of`] on rayon's threads, a chunk each: unions of boxes are exact, so in
    /// any order they are the same.
    fn of_many(items: &[Item]) -> Boxes {
        items.par_chunks(PARALLEL_BUILD).map(Boxes::of).reduce(
            || Boxes::EMPTY,
            |a, b| Boxes {
                bounds: a.bounds.union(b.bounds),
                centroids: a.centroids.union(b.centroids),
            },
        )
    }
}

/// Where a node's items split: the first `k` go left; each side's boxes.
struct Split {
    k: usize,
    left: Boxes,
    right: Boxes,
}

impl Split {
    /// The split at `k` of items already in their order, its boxes found by a pass.
    fn at(items: &[Item], k: usize) -> Split {
        Split {
            k,
            left: Boxes::of(&items[..k]),
            right: Boxes::of(&items[k..]),
        }
    }
}

/// What the node array holds until the build writes it.
const UNUSED: Node = Node {
    min: [0.0; 3],
    offset: 0,
    max: [0.0; 3],
    count: 0,
};

/// The nodes, depth first, and the primitives in leaf order, over every bounded
/// primitive of `geometry` whose box (moving spheres over `shutter`, spheres grown by
/// `roots_margin`) is not empty.
pub(super) fn build(
    geometry: &Geometry,
    rules: Rules,
    shutter: [f32; 2],
    roots_margin: f32,
) -> (Vec<Node>, Vec<PrimId>) {
    // Made on rayon's threads into their places where there are several, and those with
    // an empty box dropped after: no more than the items are held.
    let mut items = Vec::with_capacity(geometry.bounded_count());
    for kind in PrimKind::BOUNDED {
        let item = |index| {
            let prim = PrimId::new(kind, index);
            let bounds = prim_bounds(geometry, prim, shutter, roots_margin);
            Item { bounds, prim }
        };
        let count = geometry.count(kind) as u32;
        match several_threads() {
            true => items.par_extend((0..count).into_par_iter().map(item)),
            false => items.extend((0..count).map(item)),
        }
    }
    items.retain(|it| !it.bounds.is_empty());
    let rules = Rules {
        sah_pack: match items.len() >= PACKS_COUNTED_FROM {
            true => rules.pack_leaves,
            false => 0,
        },
        ..rules
    };
    let mut nodes = match items.is_empty() {
        true => Vec::new(),
        false => {
            let boxes = Boxes::of_many(&items);
            grow(&mut items, boxes, 0, 0, rules)
        }
    };
    let prims = items.iter().map(|it| it.prim).collect();
    // A small tree's array was allocated at the most it could take; a large one's, at
    // its size already.
    drop(items);
    nodes.shrink_to_fit();
    (nodes, prims)
}

/// A node over `bounds` that is a leaf of `count` primitives from `offset`, until a split
/// makes it interior.
fn leaf(bounds: &Aabb, offset: usize, count: usize) -> Node {
    Node {
        min: bounds.min.to_array(),
        offset: offset as u32,
        max: bounds.max.to_array(),
        count: count as u32,
    }
}

/// How the node over `items` (with boxes `boxes`, at `depth`) splits, or `None` for a leaf.
fn split_of(items: &mut [Item], boxes: &Boxes, depth: usize, rules: Rules) -> Option<Split> {
    let leaf_size = match rules.build {
        BvhBuild::Midpoint => MIDPOINT_LEAF,
        BvhBuild::Sah => MAX_LEAF,
    };
    if rules.is_pack_leaf(items) {
        None
    } else if depth >= FREE_DEPTH {
        median_split(items, &boxes.centroids, leaf_size).map(|k| Split::at(items, k))
    } else {
        match rules.build {
            BvhBuild::Midpoint => midpoint_split(items, &boxes.bounds).map(|k| Split::at(items, k)),
            BvhBuild::Sah => sah_split(items, boxes, rules.sah_pack),
        }
    }
}

/// The subtree over `items` (which start at `offset` in the final primitive order, and
/// whose boxes are `boxes`), depth first, its root first, its interior nodes' children
/// counted from its root. A large subtree's two halves are built on two threads, each
/// into an array of its own, and copied after their root: the nodes are held at most
/// twice, at the nodes used, not at the most a tree can take (2n - 1).
fn grow(items: &mut [Item], boxes: Boxes, offset: usize, depth: usize, rules: Rules) -> Vec<Node> {
    if items.len() <= PARALLEL_BUILD {
        // At most 2n - 1 nodes, for a small n.
        let mut nodes = vec![UNUSED; 2 * items.len() - 1];
        let used = grow_in(&mut nodes, 0, items, boxes, offset, depth, rules);
        nodes.truncate(used);
        return nodes;
    }
    let root = leaf(&boxes.bounds, offset, items.len());
    let Some(split) = split_of(items, &boxes, depth, rules) else {
        return vec![root];
    };
    let k = split.k;
    let (left, right) = items.split_at_mut(k);
    let (left, right) = rayon::join(
        || grow(left, split.left, offset, depth + 1, rules),
        || grow(right, split.right, offset + k, depth + 1, rules),
    );
    let right_start = 1 + left.len();
    let mut nodes = Vec::with_capacity(right_start + right.len());
    nodes.push(Node {
        offset: right_start as u32,
        count: 0,
        ..root
    });
    for (subtree, shift) in [(left, 1), (right, right_start)] {
        nodes.extend(subtree.into_iter().map(|node| match node.count {
            0 => Node {
                offset: node.offset + shift as u32,
                ..node
            },
            _ => node,
        }));
    }
    nodes
}

/// [`grow`] on one thread, into `nodes`, whose first node is `base` in the subtree's
/// array: returns the number of nodes it took. `nodes` holds at least `2 items.len() - 1`.
fn grow_in(
    nodes: &mut [Node],
    base: usize,
    items: &mut [Item],
    boxes: Boxes,
    offset: usize,
    depth: usize,
    rules: Rules,
) -> usize {
    nodes[0] = leaf(&boxes.bounds, offset, items.len());
    let Some(split) = split_of(items, &boxes, depth, rules) else {
        return 1;
    };
    let k = split.k;
    let (left, right) = items.split_at_mut(k);
    let left_used = grow_in(
        &mut nodes[1..],
        base + 1,
        left,
        split.left,
        offset,
        depth + 1,
        rules,
    );
    let right_base = base + 1 + left_used;
    let right_nodes = &mut nodes[1 + left_used..];
    let right_used = grow_in(
        right_nodes,
        right_base,
        right,
        split.right,
        offset + k,
        depth + 1,
        rules,
    );
    nodes[0].offset = right_base as u32;
    nodes[0].count = 0;
    1 + left_used + right_used
}

/// Splits at the median centroid along the longest axis of `centroids` (the items'),
/// or makes a leaf when `items` fit in one.
fn median_split(items: &mut [Item], centroids: &Aabb, leaf_size: usize) -> Option<usize> {
    if items.len() <= leaf_size {
        return None;
    }
    let axis = centroids.longest_axis();
    let k = items.len() / 2;
    items.select_nth_unstable_by(k, |a, b| a.centroid(axis).total_cmp(&b.centroid(axis)));
    Some(k)
}

/// The report's split: at the midpoint of the node box's longest axis, objects sorted by
/// centroid; then at the mean centroid; then at the median.
fn midpoint_split(items: &mut [Item], bounds: &Aabb) -> Option<usize> {
    let n = items.len();
    if n <= MIDPOINT_LEAF {
        return None;
    }
    let axis = bounds.longest_axis();
    items.sort_unstable_by(|a, b| a.centroid(axis).total_cmp(&b.centroid(axis)));
    let separates = |k: usize| k > 0 && k < n;
    let mid = bounds.centre()[axis];
    let k = items.partition_point(|it| it.centroid(axis) < mid);
    if separates(k) {
        return Some(k);
    }
    let mean = items.iter().map(|it| it.centroid(axis)).sum::<f32>() / n as f32;
    let k = items.partition_point(|it| it.centroid(axis) < mean);
    Some(if separates(k) { k } else { n / 2 })
}

/// A bin of the SAH sweep: the box of its items, as lanes, and their count.
type Bin = (Vec3A, Vec3A, usize);

const EMPTY_BIN: Bin = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0);

/// The bin holding the items of both.
fn add((min, max, count): Bin, bin: Bin) -> Bin {
    (min.min(bin.0), max.max(bin.1), count + bin.2)
}

/// The surface area of a bin's box, as [`Aabb::area`] computes it.
#[inline(always)]
fn bin_area((min, max, _): &Bin) -> f32 {
    let e = (*max - *min).max(Vec3A::ZERO);
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

/// A bin's box.
fn boxed((min, max, _): Bin) -> Aabb {
    Aabb {
        min: min.into(),
        max: max.into(),
    }
}

/// Swaps items `k` and `i` (`k <= i`) field by field. `items.swap` copied an item through
/// the stack as two overlapping 16-byte moves and read it back across both stores, which
/// the store buffer cannot forward: perf put 12% of the split's samples on that stall.
#[inline(always)]
fn swap_items(items: &mut [Item], k: usize, i: usize) {
    if k == i {
        return;
    }
    let (low, high) = items.split_at_mut(i);
    let (a, b) = (&mut low[k], &mut high[0]);
    std::mem::swap(&mut a.bounds.min, &mut b.bounds.min);
    std::mem::swap(&mut a.bounds.max, &mut b.bounds.max);
    std::mem::swap(&mut a.prim, &mut b.prim);
}

/// Binned SAH over the three axes: the cheapest split, or a leaf when that is cheaper
/// and the items fit in one. Only the bins that items fall in are swept (most are empty
/// in the many small nodes), which gives the costs, and so the split, of a sweep over all.
/// A side's primitives count by the packs of `pack` they fill where the build is for
/// packs (`pack` above 0): a pack's test costs the same for one primitive as for eight.
fn sah_split(items: &mut [Item], boxes: &Boxes, pack: usize) -> Option<Split> {
    let tests = |count: usize| match pack {
        0 => count as f32,
        _ => count.div_ceil(pack) as f32,
    };
    let n = items.len();
    if n == 1 {
        return None;
    }
    let centroids = boxes.centroids;
    let extent = centroids.extent();
    let node_area = boxes.bounds.area().max(f32::MIN_POSITIVE);
    // An item's place on each axis, in bins, the three side by side in the lanes of a
    // vector: `(centre - low) * scale`. The partition below computes the lane of the
    // split's axis as this does, so that an item goes to the side of its bin.
    let low = Vec3A::from(centroids.min);
    let scale = BINS as f32 / Vec3A::from(extent);
    // Every axis's bins in one pass over the items; the boxes' unions are exact (an axis
    // without extent fills bins that are never read), so a large node's chunks are binned
    // on rayon's threads and their bins merged.
    let binned = |items: &[Item]| {
        let mut bins = [[EMPTY_BIN; BINS]; 3];
        for it in items {
            let (min, max) = (Vec3A::from(it.bounds.min), Vec3A::from(it.bounds.max));
            let place = (it.centre() - low) * scale;
            for (axis, axis_bins) in bins.iter_mut().enumerate() {
                let i = bin_of(place[axis]);
                axis_bins[i] = add(axis_bins[i], (min, max, 1));
            }
        }
        bins
    };
    let bins = match n > PARALLEL_BUILD && several_threads() {
        false => binned(items),
        true => items.par_chunks(PARALLEL_BUILD).map(binned).reduce(
            || [[EMPTY_BIN; BINS]; 3],
            |a, b| std::array::from_fn(|axis| std::array::from_fn(|i| add(a[axis][i], b[axis][i]))),
        ),
    };
    // The bins that hold items, left to right, an axis: (their places, how many). Each
    // place is written, and kept where its bin holds items.
    let full = bins.each_ref().map(|axis_bins| {
        let mut full = ([0usize; BINS], 0);
        for (i, bin) in axis_bins.iter().enumerate() {
            full.0[full.1] = i;
            full.1 += (bin.2 > 0) as usize;
        }
        full
    });
    // (cost, axis, place of the last bin on the left among the axis's full bins)
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if !(extent[axis] > 0.0) {
            continue;
        }
        // Everything right of each full bin, swept from the right: a split after an empty
        // bin costs what the one before it did, and only a cheaper one replaces the best.
        let (full, m) = (&full[axis].0, full[axis].1);
        // Each split's right side: its area times its tests.
        let mut right = [0.0f32; BINS];
        let mut acc = EMPTY_BIN;
        for j in (1..m).rev() {
            acc = add(acc, bins[full[j]]);
            right[j] = bin_area(&acc) * tests(acc.2);
        }
        let mut acc = EMPTY_BIN;
        for j in 0..m.saturating_sub(1) {
            acc = add(acc, bins[full[j]]);
            let cost = TRAVERSAL_COST + (bin_area(&acc) * tests(acc.2) + right[j + 1]) / node_area;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, j));
            }
        }
    }
    let Some((cost, axis, j)) = best else {
        // Every centroid in one place: no plane separates them.
        return median_split(items, &centroids, MAX_LEAF).map(|k| Split::at(items, k));
    };
    if n <= MAX_LEAF && cost >= n as f32 {
        return None;
    }
    // The two sides' boxes: the unions of their bins (minima and maxima are exact in any
    // order).
    let full = &full[axis].0[..full[axis].1];
    let side = |bins_of_side: &[usize]| {
        boxed(
            bins_of_side
                .iter()
                .fold(EMPTY_BIN, |acc, &i| add(acc, bins[axis][i])),
        )
    };
    let (last_left, left_bounds, right_bounds) = (full[j], side(&full[..=j]), side(&full[j + 1..]));
    let (k, left, right) = match axis {
        0 => partition::<0>(items, low[0], scale[0], last_left),
        1 => partition::<1>(items, low[1], scale[1], last_left),
        _ => partition::<2>(items, low[2], scale[2], last_left),
    };
    let (left_centroids, right_centroids) = (boxed(left), boxed(right));
    Some(Split {
        k,
        left: Boxes {
            bounds: left_bounds,
            centroids: left_centroids,
        },
        right: Boxes {
            bounds: right_bounds,
            centroids: right_centroids,
        },
    })
}

/// The bin of an item whose centroid lies `place` bins along an axis: NaN (an axis without
/// extent) in the first.
#[inline(always)]
fn bin_of(place: f32) -> usize {
    let clamped = place.max(0.0).min((BINS - 1) as f32);
    // SAFETY: `clamped` is a number in [0, BINS - 1], never NaN (`max` returns the number).
    // The mask changes nothing, but tells the compiler the bin is in range.
    (unsafe { clamped.to_int_unchecked::<u32>() }) as usize & (BINS - 1)
}

/// Moves the items whose bin on `AXIS` is at most `last_left` to the front, in one pass
/// (from both ends was slower: docs/did-not-pay.md), each item's side from its place on
/// `AXIS` alone, computed as the binning computed that lane. Returns how many went left
/// and each side's centroids, gathered on the way as a bin's box (in vectors: the boxes
/// of `Vec3` blend their fourth lane at each step).
fn partition<const AXIS: usize>(
    items: &mut [Item],
    axis_low: f32,
    axis_scale: f32,
    last_left: usize,
) -> (usize, Bin, Bin) {
    let (mut k, mut left, mut right) = (0, EMPTY_BIN, EMPTY_BIN);
    for i in 0..items.len() {
        let centre = items[i].centre();
        if bin_of((centre[AXIS] - axis_low) * axis_scale) <= last_left {
            left = add(left, (centre, centre, 1));
            swap_items(items, k, i);
            k += 1;
        } else {
            right = add(right, (centre, centre, 1));
        }
    }
    (k, left, right)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::bvh2::Bvh2;
    use crate::prim::PrimKind;

    fn items(centroids: &[f32]) -> Vec<Item> {
        centroids
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                let c = Vec3::new(x, 0.0, 0.0);
                Item {
                    bounds: Aabb {
                        min: c - 0.1,
                        max: c + 0.1,
                    },
                    prim: PrimId::new(PrimKind::Sphere, i as u32),
                }
            })
            .collect()
    }

    #[test]
    fn parallel_build_gives_the_single_thread_tree() {
        let text: String = (0..3 * PARALLEL_BUILD)
            .map(|i| format!("s {} {} {} 0.05\n", i % 17, (i / 17) % 13, i / 221))
            .collect();
        let scene = crate::scene::p3f::parse_text(&text).unwrap();
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| Bvh2::build(&scene.geometry, BvhBuild::Sah, [0.0; 2], 0.0))
        };
        let (one, two) = (build(1), build(2));
        assert_eq!(one.nodes, two.nodes);
        assert_eq!(one.prims, two.prims);
        // Every primitive in exactly one leaf, every interior node's children inside it.
        let mut seen = vec![0; one.prims.len()];
        for (i, node) in one.nodes.iter().enumerate() {
            if node.is_leaf() {
                node.prim_range().for_each(|p| seen[p] += 1);
            } else {
                for child in [i + 1, node.right_child()] {
                    let (outer, inner) = (node.bounds(), one.nodes[child].bounds());
                    assert!(
                        outer.union(inner) == outer,
                        "child {child} outside node {i}"
                    );
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1));
    }

    #[test]
    fn midpoint_split_falls_back_to_mean_then_median() {
        let bounds = |it: &[Item]| it.iter().fold(Aabb::EMPTY, |b, i| b.union(i.bounds));
        // The midpoint of [0, 10] separates.
        let mut a = items(&[0.0, 1.0, 9.0, 10.0]);
        let box_a = bounds(&a);
        assert_eq!(midpoint_split(&mut a, &box_a), Some(2));
        // Equal centroids: neither midpoint nor mean separates; the median does.
        let mut b = items(&[3.0; 5]);
        let box_b = bounds(&b);
        assert_eq!(midpoint_split(&mut b, &box_b), Some(2));
        // Two objects make a leaf.
        let mut c = items(&[0.0, 5.0]);
        let box_c = bounds(&c);
        assert_eq!(midpoint_split(&mut c, &box_c), None);
    }

    #[test]
    fn sah_separates_clusters_and_keeps_small_tight_groups_whole() {
        let split = |items: &mut [Item]| {
            let boxes = Boxes::of(items);
            sah_split(items, &boxes, 0).map(|s| {
                // The boxes found on the way are the boxes of the two sides.
                assert_eq!(s.left, Boxes::of(&items[..s.k]));
                assert_eq!(s.right, Boxes::of(&items[s.k..]));
                s.k
            })
        };
        let mut a = items(&[0.0, 0.1, 0.2, 50.0, 50.1]);
        assert_eq!(split(&mut a), Some(3));
        assert!(a[..3].iter().all(|it| it.centroid(0) < 1.0));
        let mut b = items(&[0.0, 0.01]);
        assert_eq!(split(&mut b), None);
        let mut same = items(&[1.0; 20]);
        assert_eq!(split(&mut same), Some(10));
    }
}
