//! Bounding volume hierarchies, flattened into one array of 32-byte nodes.
//!
//! Two builds share the layout and the traversal:
//! - [`BvhBuild::Midpoint`], the course report's (P3F.md section 9): leaves of at most two
//!   objects; split on the longest axis of the node's box at its midpoint, objects sorted
//!   by centroid; if one side is empty, at the mean centroid; if that still separates
//!   nothing, at the median (the report's code could recurse forever on equal centroids).
//! - [`BvhBuild::Sah`], the default: binned surface area heuristic over all three axes,
//!   leaves of up to [`MAX_LEAF`] primitives.
//!
//! Nodes are stored depth first: an interior node's left child follows it, and it holds
//! the index of its right child. A leaf's primitives are contiguous in `prims`, in the
//! order the build left them. Traversal is near child first with the entry distance kept
//! on the stack, so popped entries beyond the closest hit are skipped; occlusion stops at
//! the first hit.

use glam::Vec3;

use super::bounds::{prim_bounds, Aabb};
use super::wide::Bvh8;
use super::{ClosestHit, BOUNDED};
use crate::intersect::{slab_entry, FAR_WIDENING};
use crate::ray::{PrimId, Ray};
use crate::scene::Geometry;

/// Which build to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhBuild {
    Midpoint,
    Sah,
}

/// Children per node that traversal sees: the binary tree as built, or the tree
/// collapsed to 8-wide nodes ([`Bvh8`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhWidth {
    Two,
    Eight,
}

impl BvhBuild {
    /// The SAH tree is collapsed to 8-wide nodes; the report's BVH stays binary, as the
    /// report traverses it.
    pub fn default_width(self) -> BvhWidth {
        match self {
            BvhBuild::Midpoint => BvhWidth::Two,
            BvhBuild::Sah => BvhWidth::Eight,
        }
    }
}

/// The most primitives in an SAH leaf (a leaf can later be tested 8 at a time).
pub const MAX_LEAF: usize = 8;
/// Leaves of the report's BVH hold at most this many objects.
const MIDPOINT_LEAF: usize = 2;
/// SAH cost of visiting a node, relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;
/// Bins per axis of the SAH sweep.
const BINS: usize = 16;
/// Below this depth a build may split as it likes; deeper, it splits at the median so
/// the depth stays under [`STACK_SIZE`] whatever the input.
const FREE_DEPTH: usize = 64;
/// No tree is deeper: past [`FREE_DEPTH`] median splits halve the primitives.
pub const MAX_DEPTH: usize = 128;
const STACK_SIZE: usize = MAX_DEPTH;

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
    pub(super) fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from_array(self.min),
            max: Vec3::from_array(self.max),
        }
    }

    pub(super) fn area(&self) -> f32 {
        self.bounds().area()
    }

    pub(super) fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// A leaf's primitives, as indices into the tree's primitive order.
    pub(super) fn prim_range(&self) -> std::ops::Range<usize> {
        self.offset as usize..(self.offset + self.count) as usize
    }

    /// An interior node's right child (its left child follows it).
    pub(super) fn right_child(&self) -> usize {
        self.offset as usize
    }

    /// The entry distance of the ray into the node's box within `[t_min, t_max]`
    /// ([`slab_entry`]: a ray in a slab's plane passes, erring towards visiting).
    #[inline]
    fn entry(&self, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        slab_entry(
            origin,
            inv_dir,
            Vec3::from_array(self.min),
            Vec3::from_array(self.max),
            t_min,
            t_max,
        )
    }
}

#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    prims: Vec<PrimId>,
    build: BvhBuild,
    /// The tree collapsed to 8-wide nodes, which traversal then uses.
    wide: Option<Bvh8>,
}

/// A primitive during the build.
#[derive(Clone, Copy)]
struct Item {
    bounds: Aabb,
    centroid: Vec3,
    prim: PrimId,
}

impl Bvh {
    pub fn build(geometry: &Geometry, build: BvhBuild, width: BvhWidth, shutter: [f32; 2]) -> Bvh {
        let mut items = Vec::with_capacity(geometry.bounded_count());
        for kind in BOUNDED {
            for prim in geometry.ids(kind) {
                let bounds = prim_bounds(geometry, prim, shutter);
                if !bounds.is_empty() {
                    items.push(Item {
                        bounds,
                        centroid: bounds.centre(),
                        prim,
                    });
                }
            }
        }
        let mut nodes = Vec::with_capacity(2 * items.len() / MIDPOINT_LEAF.max(1) + 1);
        if !items.is_empty() {
            grow(&mut nodes, &mut items, 0, 0, build);
        }
        let prims: Vec<PrimId> = items.iter().map(|it| it.prim).collect();
        let wide = match width {
            BvhWidth::Two => None,
            BvhWidth::Eight => Bvh8::collapse(geometry, &nodes, &prims),
        };
        Bvh {
            nodes,
            prims,
            build,
            wide,
        }
    }

    /// The 8-wide tree that traversal uses, when the tree was collapsed.
    pub fn wide(&self) -> Option<&Bvh8> {
        self.wide.as_ref()
    }

    pub fn name(&self) -> String {
        let build = match self.build {
            BvhBuild::Midpoint => "bvh midpoint",
            BvhBuild::Sah => "bvh sah",
        };
        match (self.build.default_width(), &self.wide) {
            (BvhWidth::Two, None) | (BvhWidth::Eight, Some(_)) => build.into(),
            (_, Some(_)) => format!("{build} 8-wide"),
            (_, None) => format!("{build} binary"),
        }
    }

    pub fn closest(
        &self,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        closest: &mut ClosestHit,
    ) {
        if let Some(wide) = &self.wide {
            return wide.closest(geometry, ray, inv_dir, t_min, closest);
        }
        let Some(root) = self.nodes.first() else {
            return;
        };
        let Some(t_root) = root.entry(ray.origin, inv_dir, t_min, closest.limit()) else {
            return;
        };
        let mut stack = [(0u32, 0f32); STACK_SIZE];
        stack[0] = (0, t_root);
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let (mut index, t_entry) = stack[depth];
            // Entries beyond the closest hit cannot hold a closer one (ties may); by the
            // node test's own rounding allowance.
            if t_entry > closest.limit() * FAR_WIDENING {
                continue;
            }
            loop {
                let node = &self.nodes[index as usize];
                if node.count > 0 {
                    let first = node.offset as usize;
                    for &prim in &self.prims[first..first + node.count as usize] {
                        closest.test(geometry, prim, ray, inv_dir, t_min);
                    }
                    break;
                }
                let (left, right) = (index + 1, node.offset);
                let limit = closest.limit();
                let t_left = self.nodes[left as usize].entry(ray.origin, inv_dir, t_min, limit);
                let t_right = self.nodes[right as usize].entry(ray.origin, inv_dir, t_min, limit);
                index = match (t_left, t_right) {
                    (Some(tl), Some(tr)) => {
                        let (near, far, t_far) = if tl <= tr {
                            (left, right, tr)
                        } else {
                            (right, left, tl)
                        };
                        stack[depth] = (far, t_far);
                        depth += 1;
                        near
                    }
                    (Some(_), None) => left,
                    (None, Some(_)) => right,
                    (None, None) => break,
                };
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
        if let Some(wide) = &self.wide {
            return wide.occluded(geometry, ray, inv_dir, t_min, t_max);
        }
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = [0u32; STACK_SIZE];
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let index = stack[depth];
            let node = &self.nodes[index as usize];
            if node.entry(ray.origin, inv_dir, t_min, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                let first = node.offset as usize;
                let blocked = self.prims[first..first + node.count as usize]
                    .iter()
                    .any(|&prim| {
                        geometry
                            .intersect(prim, ray, inv_dir, t_min, t_max)
                            .is_some()
                    });
                if blocked {
                    return true;
                }
            } else {
                stack[depth] = node.offset;
                stack[depth + 1] = index + 1;
                depth += 2;
            }
        }
        false
    }

    pub fn stats(&self) -> Vec<String> {
        let leaves: Vec<&Node> = self.nodes.iter().filter(|n| n.count > 0).collect();
        let leaf_prims: usize = leaves.iter().map(|n| n.count as usize).sum();
        let max_leaf = leaves.iter().map(|n| n.count).max().unwrap_or(0);
        let memory = std::mem::size_of_val(&self.nodes[..]) + 4 * self.prims.len();
        let mut lines = vec![
            format!("bvh build: {}", self.name().trim_start_matches("bvh ")),
            format!(
                "nodes: {} ({} interior, {} leaves), depth {}",
                self.nodes.len(),
                self.nodes.len() - leaves.len(),
                leaves.len(),
                self.depth()
            ),
            format!(
                "primitives per leaf: {:.2} mean, {max_leaf} max ({} primitives)",
                leaf_prims as f64 / leaves.len().max(1) as f64,
                self.prims.len()
            ),
            format!("sah cost: {:.2}", self.sah_cost()),
            format!("memory: {:.2} MiB", memory as f64 / (1 << 20) as f64),
        ];
        if let Some(wide) = &self.wide {
            lines.push(format!(
                "8-wide: {} nodes, depth {}, {:.2} MiB",
                wide.node_count(),
                wide.depth(),
                wide.memory() as f64 / (1 << 20) as f64
            ));
        }
        lines
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

/// Builds the subtree over `items` (which start at `offset` in the final primitive
/// order) at the end of `nodes`, depth first.
fn grow(nodes: &mut Vec<Node>, items: &mut [Item], offset: usize, depth: usize, build: BvhBuild) {
    let bounds = items.iter().fold(Aabb::EMPTY, |b, it| b.union(it.bounds));
    let index = nodes.len();
    nodes.push(Node {
        min: bounds.min.to_array(),
        offset: offset as u32,
        max: bounds.max.to_array(),
        count: items.len() as u32,
    });
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
        return;
    };
    let (left, right) = items.split_at_mut(k);
    if left.len() + right.len() > PARALLEL_BUILD {
        // The two subtrees on two threads, then the right one's nodes appended after
        // the left one's: the same array as one thread builds.
        let (_, mut right_nodes) = rayon::join(
            || grow(nodes, left, offset, depth + 1, build),
            || {
                let mut right_nodes = Vec::new();
                grow(&mut right_nodes, right, offset + k, depth + 1, build);
                right_nodes
            },
        );
        let right_index = nodes.len() as u32;
        for node in &mut right_nodes {
            if node.count == 0 {
                node.offset += right_index;
            }
        }
        nodes.append(&mut right_nodes);
        nodes[index].offset = right_index;
    } else {
        grow(nodes, left, offset, depth + 1, build);
        let right_index = nodes.len() as u32;
        grow(nodes, right, offset + k, depth + 1, build);
        nodes[index].offset = right_index;
    }
    nodes[index].count = 0;
}

/// Subtrees over more primitives than this are built on two threads.
const PARALLEL_BUILD: usize = 4096;

fn centroid_bounds(items: &[Item]) -> Aabb {
    items.iter().fold(Aabb::EMPTY, |b, it| b.grow(it.centroid))
}

/// Splits at the median centroid along the centroids' longest axis, or makes a leaf
/// when `items` fit in one.
fn median_split(items: &mut [Item], leaf_size: usize) -> Option<usize> {
    if items.len() <= leaf_size {
        return None;
    }
    let axis = centroid_bounds(items).longest_axis();
    let k = items.len() / 2;
    items.select_nth_unstable_by(k, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
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
    items.sort_unstable_by(|a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    let separates = |k: usize| k > 0 && k < n;
    let mid = bounds.centre()[axis];
    let k = items.partition_point(|it| it.centroid[axis] < mid);
    if separates(k) {
        return Some(k);
    }
    let mean = items.iter().map(|it| it.centroid[axis]).sum::<f32>() / n as f32;
    let k = items.partition_point(|it| it.centroid[axis] < mean);
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
    // (cost, axis, last bin on the left)
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if !(extent[axis] > 0.0) {
            continue;
        }
        let mut bins = [(Aabb::EMPTY, 0usize); BINS];
        for it in items.iter() {
            let b = &mut bins[bin_of(it.centroid[axis], axis)];
            b.0 = b.0.union(it.bounds);
            b.1 += 1;
        }
        // Areas and counts of everything right of each split, swept from the right.
        let mut right = [(0f32, 0usize); BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            acc = acc.union(bins[i].0);
            count += bins[i].1;
            right[i] = (acc.area(), count);
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in 0..BINS - 1 {
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
        if bin_of(items[i].centroid[axis], axis) <= last_left {
            items.swap(i, k);
            k += 1;
        }
    }
    Some(k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray::PrimKind;

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
                    centroid: c,
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
            pool.install(|| Bvh::build(&scene.geometry, BvhBuild::Sah, BvhWidth::Two, [0.0; 2]))
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
        assert!(a[..3].iter().all(|it| it.centroid.x < 1.0));
        let mut b = items(&[0.0, 0.01]);
        let bounds = b.iter().fold(Aabb::EMPTY, |b, i| b.union(i.bounds));
        assert_eq!(sah_split(&mut b, &bounds), None);
        let mut same = items(&[1.0; 20]);
        let bounds = same[0].bounds;
        assert_eq!(sah_split(&mut same, &bounds), Some(10));
    }
}
