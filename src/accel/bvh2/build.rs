//! The two builds of the binary BVH: the course report's midpoint split and the binned
//! SAH. Both write nodes depth first into one array, allocated once, and reorder the
//! primitives so that each leaf's are contiguous.

use super::{BvhBuild, Node, TRAVERSAL_COST};
use crate::accel::bounds::prim_bounds;
use crate::intersect::Aabb;
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;

/// The most primitives in an SAH leaf (a leaf can later be tested 8 at a time).
pub const MAX_LEAF: usize = 8;
/// Leaves of the report's BVH hold at most this many objects.
const MIDPOINT_LEAF: usize = 2;
/// Bins per axis of the SAH sweep.
const BINS: usize = 16;
/// Below this depth a build may split as it likes; deeper, it splits at the median so
/// the depth stays under [`super::MAX_DEPTH`] whatever the input.
const FREE_DEPTH: usize = 64;
/// Subtrees over more primitives than this are built on two threads.
const PARALLEL_BUILD: usize = 4096;

/// A primitive during the build: 28 bytes, for the items and the nodes are the build's
/// largest arrays. The centroid is the box's centre, recomputed where it is needed.
#[derive(Clone, Copy)]
struct Item {
    bounds: Aabb,
    prim: PrimId,
}

impl Item {
    /// The centroid's coordinate on `axis` (as `Aabb::centre` computes it).
    fn centroid(&self, axis: usize) -> f32 {
        0.5 * (self.bounds.min[axis] + self.bounds.max[axis])
    }
}

const _: () = assert!(std::mem::size_of::<Item>() == 28);

/// What the node array holds until the build writes it.
const UNUSED: Node = Node {
    min: [0.0; 3],
    offset: 0,
    max: [0.0; 3],
    count: 0,
};

/// The nodes, depth first, and the primitives in leaf order, over every bounded
/// primitive of `geometry` whose box (moving spheres over `shutter`, spheres grown by
/// `sphere_margin`) is not empty.
pub(super) fn build(
    geometry: &Geometry,
    build: BvhBuild,
    shutter: [f32; 2],
    sphere_margin: f32,
) -> (Vec<Node>, Vec<PrimId>) {
    let mut items = Vec::with_capacity(geometry.bounded_count());
    for kind in PrimKind::BOUNDED {
        for prim in geometry.ids(kind) {
            let bounds = prim_bounds(geometry, prim, shutter, sphere_margin);
            if !bounds.is_empty() {
                items.push(Item { bounds, prim });
            }
        }
    }
    // A tree of n primitives has at most 2n - 1 nodes: the array is allocated once, at
    // that size, and never grows (growing it copied it at twice its size, the peak of
    // `tests/memory/huge_scene.rs`).
    let mut nodes = vec![UNUSED; (2 * items.len()).saturating_sub(1)];
    if !items.is_empty() {
        let used = grow(&mut nodes, 0, &mut items, 0, 0, build);
        nodes.truncate(used);
    }
    let prims = items.iter().map(|it| it.prim).collect();
    // The items go before the nodes shrink to what is used, so both are never held at once.
    drop(items);
    nodes.shrink_to_fit();
    (nodes, prims)
}

/// Builds the subtree over `items` (which start at `offset` in the final primitive
/// order) at the start of `nodes`, whose first node is `base` in the whole array, depth
/// first; returns the number of nodes it took. `nodes` holds at least `2 items.len() - 1`.
fn grow(
    nodes: &mut [Node],
    base: usize,
    items: &mut [Item],
    offset: usize,
    depth: usize,
    build: BvhBuild,
) -> usize {
    let bounds = items.iter().fold(Aabb::EMPTY, |b, it| b.union(it.bounds));
    nodes[0] = Node {
        min: bounds.min.to_array(),
        offset: offset as u32,
        max: bounds.max.to_array(),
        count: items.len() as u32,
    };
    let leaf_size = match build {
        BvhBuild::Midpoint => MIDPOINT_LEAF,
        BvhBuild::Sah => MAX_LEAF,
    };
    let split = if depth >= FREE_DEPTH {
        median_split(items, leaf_size)
    } else {
        match build {
            BvhBuild::Midpoint => midpoint_split(items, &bounds),
            BvhBuild::Sah => sah_split(items, &bounds),
        }
    };
    let Some(k) = split else {
        return 1;
    };
    let (left, right) = items.split_at_mut(k);
    let (left_used, right_used) = if left.len() + right.len() > PARALLEL_BUILD {
        // The two subtrees on two threads, the right one after the most room the left
        // one can take (2k - 1 nodes), then moved down to follow it: the same array as
        // one thread builds.
        let room = 2 * k - 1;
        let (left_nodes, right_nodes) = nodes[1..].split_at_mut(room);
        let right_base = base + 1 + room;
        let (left_used, right_used) = rayon::join(
            || grow(left_nodes, base + 1, left, offset, depth + 1, build),
            || grow(right_nodes, right_base, right, offset + k, depth + 1, build),
        );
        let (from, shift) = (1 + room, room - left_used);
        for node in &mut nodes[from..from + right_used] {
            if node.count == 0 {
                node.offset -= shift as u32;
            }
        }
        nodes.copy_within(from..from + right_used, 1 + left_used);
        (left_used, right_used)
    } else {
        let left_used = grow(&mut nodes[1..], base + 1, left, offset, depth + 1, build);
        let right_nodes = &mut nodes[1 + left_used..];
        let right_base = base + 1 + left_used;
        let right_used = grow(right_nodes, right_base, right, offset + k, depth + 1, build);
        (left_used, right_used)
    };
    nodes[0].offset = (base + 1 + left_used) as u32;
    nodes[0].count = 0;
    1 + left_used + right_used
}

fn centroid_bounds(items: &[Item]) -> Aabb {
    items
        .iter()
        .fold(Aabb::EMPTY, |b, it| b.grow(it.bounds.centre()))
}

/// Splits at the median centroid along the centroids' longest axis, or makes a leaf
/// when `items` fit in one.
fn median_split(items: &mut [Item], leaf_size: usize) -> Option<usize> {
    if items.len() <= leaf_size {
        return None;
    }
    let axis = centroid_bounds(items).longest_axis();
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

/// Binned SAH over the three axes: the cheapest split, or a leaf when that is cheaper
/// and the items fit in one.
fn sah_split(items: &mut [Item], bounds: &Aabb) -> Option<usize> {
    let n = items.len();
    if n == 1 {
        return None;
    }
    let centroids = centroid_bounds(items);
    let extent = centroids.extent();
    let node_area = bounds.area().max(f32::MIN_POSITIVE);
    let bin_of = |c: f32, axis: usize| {
        let b = ((c - centroids.min[axis]) / extent[axis] * BINS as f32) as usize;
        b.min(BINS - 1)
    };
    // Every axis's bins in one pass over the items: each item's centroid is computed
    // once, and the axes' bins are filled from it as three passes filled them (an axis
    // without extent fills bins that are never read).
    let mut bins = [[(Aabb::EMPTY, 0usize); BINS]; 3];
    for it in items.iter() {
        let c = it.bounds.centre();
        for (axis, axis_bins) in bins.iter_mut().enumerate() {
            let b = &mut axis_bins[bin_of(c[axis], axis)];
            b.0 = b.0.union(it.bounds);
            b.1 += 1;
        }
    }
    // (cost, axis, last bin on the left)
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if !(extent[axis] > 0.0) {
            continue;
        }
        // Areas and counts of everything right of each split, swept from the right. An
        // empty bin changes neither (most are empty in the many small nodes).
        let mut right = [(0f32, 0usize); BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        let mut area = acc.area();
        for i in (1..BINS).rev() {
            if bins[i].1 > 0 {
                acc = acc.union(bins[i].0);
                count += bins[i].1;
                area = acc.area();
            }
            right[i] = (area, count);
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in 0..BINS - 1 {
            // After an empty bin a split costs what the one before it did, and only a
            // cheaper one replaces the best.
            if bins[i].1 == 0 {
                continue;
            }
            acc = acc.union(bins[i].0);
            count += bins[i].1;
            let (right_area, right_count) = right[i + 1];
            if count == 0 || right_count == 0 {
                continue;
            }
            let cost = TRAVERSAL_COST
                + (acc.area() * count as f32 + right_area * right_count as f32) / node_area;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, i));
            }
        }
    }
    let Some((cost, axis, last_left)) = best else {
        // Every centroid in one place: no plane separates them.
        return median_split(items, MAX_LEAF);
    };
    if n <= MAX_LEAF && cost >= n as f32 {
        return None;
    }
    let mut k = 0;
    for i in 0..n {
        if bin_of(items[i].centroid(axis), axis) <= last_left {
            items.swap(i, k);
            k += 1;
        }
    }
    Some(k)
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
        let mut a = items(&[0.0, 0.1, 0.2, 50.0, 50.1]);
        let bounds = a.iter().fold(Aabb::EMPTY, |b, i| b.union(i.bounds));
        assert_eq!(sah_split(&mut a, &bounds), Some(3));
        assert!(a[..3].iter().all(|it| it.centroid(0) < 1.0));
        let mut b = items(&[0.0, 0.01]);
        let bounds = b.iter().fold(Aabb::EMPTY, |b, i| b.union(i.bounds));
        assert_eq!(sah_split(&mut b, &bounds), None);
        let mut same = items(&[1.0; 20]);
        let bounds = same[0].bounds;
        assert_eq!(sah_split(&mut same, &bounds), Some(10));
    }
}
