//! An 8-wide BVH collapsed from a binary one: each node holds the boxes of up to eight
//! children side by side (one array per coordinate), so that one ray tests all of them at
//! once. A subtree of at most eight triangles, or eight spheres, becomes one leaf whose
//! primitives are stored side by side too ([`TrianglePack8`], [`SpherePack8`]) and tested
//! together; other leaves are the binary tree's, tested one primitive at a time.
//!
//! Collapsing: a node starts with its binary node's two children, and the child with the
//! largest surface area is replaced by its own two children while fewer than eight remain
//! and some child is interior (Wald et al., "Getting Rid of Packets", 2008).
//!
//! Traversal visits the hit children nearest first, with their entry distances on the
//! stack; popped entries beyond the closest hit are skipped (ties are visited, as in the
//! binary BVH, so the answer is brute force's).

use std::mem::MaybeUninit;
use std::ops::Range;

use glam::Vec3;

use super::bvh::Node;
use super::{for_lanes, ClosestHit};
use crate::intersect::{
    slab_entry8, slab_entry_packet, sphere_leaf, triangle_leaf, BoxPack8, SpherePack8,
    TrianglePack8, FAR_WIDENING,
};
use crate::ray::{Hit, PrimId, PrimKind, Ray, RayPacket};
use crate::scene::Geometry;
use crate::simd::{F32x8, Mask8};

/// Children per node.
pub const WIDTH: usize = 8;

/// A child reference: a node index, or a leaf (the top bit) with its kind in bits 29..31,
/// its primitive count less one in bits 26..29, and below, its first primitive (a run of
/// `prims`) or its pack.
type ChildRef = u32;
const LEAF: u32 = 1 << 31;
const KIND_SHIFT: u32 = 29;
const COUNT_SHIFT: u32 = 26;
const INDEX_MASK: u32 = (1 << COUNT_SHIFT) - 1;
/// The kinds of leaf.
const RUN: u32 = 0;
const TRIANGLES: u32 = 1;
const SPHERES: u32 = 2;
/// The most primitives a leaf may hold, and the most a tree may hold, to be encoded.
const MAX_LEAF_PRIMS: usize = 1 << (KIND_SHIFT - COUNT_SHIFT);
const MAX_PRIMS: usize = INDEX_MASK as usize + 1;

fn leaf_ref(kind: u32, count: usize, index: usize) -> ChildRef {
    LEAF | kind << KIND_SHIFT | ((count as u32 - 1) << COUNT_SHIFT) | index as u32
}

/// A leaf reference's kind, primitive count and index.
fn leaf_parts(child: ChildRef) -> (u32, usize, usize) {
    (
        (child & !LEAF) >> KIND_SHIFT,
        ((child >> COUNT_SHIFT) & (MAX_LEAF_PRIMS as u32 - 1)) as usize + 1,
        (child & INDEX_MASK) as usize,
    )
}

/// Eight children's boxes side by side, then their references: 228 bytes of data padded
/// to four cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node8 {
    boxes: BoxPack8,
    child: [ChildRef; WIDTH],
    /// Children in use: slots `0..count`. The others hold padding boxes, which no box
    /// value can make the slab test miss, so they are left out of its mask.
    count: u32,
}

const _: () = assert!(std::mem::size_of::<Node8>() == 256);

impl Node8 {
    /// The used children that the ray enters within `[t_min, t_max]`, as a bit mask, and
    /// their entry distances (lanes outside the mask are unspecified).
    #[inline]
    fn entries(&self, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> (u8, [f32; WIDTH]) {
        let used = Mask8::from_bitmask(((1u32 << self.count) - 1) as u8);
        let (hit, t) = slab_entry8(origin, inv_dir, &self.boxes, t_min, t_max, used);
        (hit.bitmask(), t.to_array())
    }
}

/// The collapsed tree: `nodes[0]` is the root; leaves index `prims` or the packs.
#[derive(Clone, Debug)]
pub struct Bvh8 {
    nodes: Vec<Node8>,
    prims: Vec<PrimId>,
    triangles: Vec<TrianglePack8>,
    spheres: Vec<SpherePack8>,
    /// The primitives of each pack, lane by lane (`triangles`, then `spheres`).
    triangle_ids: Vec<[PrimId; 8]>,
    sphere_ids: Vec<[PrimId; 8]>,
    /// The longest path from the root to a leaf, in nodes (statistics).
    depth: usize,
}

/// Entries on the traversal stack: each level pushes at most `WIDTH - 1`, and the binary
/// trees stay under `bvh::MAX_DEPTH` levels, which bounds the collapsed ones too.
const STACK_SIZE: usize = (WIDTH - 1) * super::bvh::MAX_DEPTH + 1;

impl Bvh8 {
    /// Collapses the binary tree `nodes` over `prims`, or returns `None` when it has more
    /// primitives, or larger leaves, than the child references can encode.
    pub fn collapse(geometry: &Geometry, nodes: &[Node], prims: &[PrimId]) -> Option<Bvh8> {
        let leaves_fit = nodes
            .iter()
            .all(|n| !n.is_leaf() || n.prim_range().len() <= MAX_LEAF_PRIMS);
        if prims.len() > MAX_PRIMS || !leaves_fit {
            return None;
        }
        let mut tree = Bvh8 {
            nodes: Vec::with_capacity(nodes.len() / 4 + 1),
            prims: prims.to_vec(),
            triangles: Vec::new(),
            spheres: Vec::new(),
            triangle_ids: Vec::new(),
            sphere_ids: Vec::new(),
            depth: 0,
        };
        if !nodes.is_empty() {
            let binary = Binary::new(nodes, prims);
            let root_children = if binary.is_terminal(0) {
                vec![0]
            } else {
                binary.children(0)
            };
            tree.depth = tree.emit(geometry, &binary, root_children);
        }
        Some(tree)
    }

    /// Appends the node over the binary nodes `start` (expanded as the header says) and
    /// its subtrees; returns the subtree's depth.
    fn emit(&mut self, geometry: &Geometry, binary: &Binary, start: Vec<usize>) -> usize {
        let mut kids = start;
        while kids.len() < WIDTH {
            let widest = kids
                .iter()
                .enumerate()
                .filter(|(_, &i)| !binary.is_terminal(i))
                .max_by(|(_, &a), (_, &b)| {
                    binary.nodes[a].area().total_cmp(&binary.nodes[b].area())
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
            let child = match binary.pack_kind(i) {
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
        if kind == PrimKind::Triangle {
            let t = &geometry.triangles;
            let tris: Vec<[Vec3; 3]> = ids
                .iter()
                .map(|id| {
                    let i = id.index();
                    [t.p0.get(i), t.e1.get(i), t.e2.get(i)]
                })
                .collect();
            self.triangles.push(TrianglePack8::new(&tris));
            self.triangle_ids.push(lanes);
            leaf_ref(TRIANGLES, ids.len(), self.triangles.len() - 1)
        } else {
            let s = &geometry.spheres;
            let spheres: Vec<(Vec3, f32)> = ids
                .iter()
                .map(|id| (s.centre.get(id.index()), s.radius[id.index()]))
                .collect();
            self.spheres.push(SpherePack8::new(&spheres));
            self.sphere_ids.push(lanes);
            leaf_ref(SPHERES, ids.len(), self.spheres.len() - 1)
        }
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

    /// Tests the primitives of leaf `child`, keeping the winner in `closest`.
    #[inline]
    fn closest_in_leaf(
        &self,
        geometry: &Geometry,
        child: ChildRef,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        closest: &mut ClosestHit,
    ) {
        let (kind, count, index) = leaf_parts(child);
        match kind {
            TRIANGLES => {
                let hits = triangle_leaf(ray, &self.triangles[index], t_min, closest.bound());
                let (t, u, v) = (hits.t.to_array(), hits.u.to_array(), hits.v.to_array());
                let ids = &self.triangle_ids[index];
                for_lanes(hits.hit.bitmask(), |k| {
                    closest.offer(Hit {
                        t: t[k],
                        prim: ids[k],
                        u: u[k],
                        v: v[k],
                    })
                });
            }
            SPHERES => {
                let (hit, t) = sphere_leaf(ray, &self.spheres[index], t_min, closest.bound());
                let (t, ids) = (t.to_array(), &self.sphere_ids[index]);
                for_lanes(hit.bitmask(), |k| {
                    closest.offer(Hit {
                        t: t[k],
                        prim: ids[k],
                        u: 0.0,
                        v: 0.0,
                    })
                });
            }
            _ => {
                for &prim in &self.prims[index..index + count] {
                    closest.test(geometry, prim, ray, inv_dir, t_min);
                }
            }
        }
    }

    /// Whether a primitive of leaf `child` blocks the ray within `(t_min, t_max)`.
    #[inline]
    fn blocks(
        &self,
        geometry: &Geometry,
        child: ChildRef,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        let (kind, count, index) = leaf_parts(child);
        match kind {
            TRIANGLES => triangle_leaf(ray, &self.triangles[index], t_min, t_max)
                .hit
                .any(),
            SPHERES => sphere_leaf(ray, &self.spheres[index], t_min, t_max).0.any(),
            _ => self.prims[index..index + count].iter().any(|&prim| {
                geometry
                    .intersect(prim, ray, inv_dir, t_min, t_max)
                    .is_some()
            }),
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
        if !self.nodes.is_empty() {
            self.closest_from(0, geometry, ray, inv_dir, t_min, closest);
        }
    }

    /// [`Bvh8::closest`] over the subtree under `start`.
    fn closest_from(
        &self,
        start: ChildRef,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        closest: &mut ClosestHit,
    ) {
        let mut stack = [const { MaybeUninit::<(ChildRef, f32)>::uninit() }; STACK_SIZE];
        stack[0].write((start, t_min));
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            // SAFETY: every slot below `depth` was written before `depth` passed it.
            let (child, t_entry) = unsafe { stack[depth].assume_init() };
            // Entries beyond the closest hit cannot hold a closer one (ties may); by the
            // node test's own rounding allowance.
            if t_entry > closest.limit() * FAR_WIDENING {
                continue;
            }
            if child & LEAF != 0 {
                self.closest_in_leaf(geometry, child, ray, inv_dir, t_min, closest);
                continue;
            }
            let node = &self.nodes[child as usize];
            let (hits, entries) = node.entries(ray.origin, inv_dir, t_min, closest.limit());
            // Push the hit children farthest first, so the nearest is popped next.
            let first = depth;
            for_lanes(hits, |k| {
                let t = entries[k];
                let mut slot = depth;
                // SAFETY: slots `first..depth` were written in this loop.
                while slot > first && unsafe { stack[slot - 1].assume_init() }.1 < t {
                    let moved = unsafe { stack[slot - 1].assume_init() };
                    stack[slot].write(moved);
                    slot -= 1;
                }
                stack[slot].write((node.child[k], t));
                depth += 1;
            });
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
        !self.nodes.is_empty() && self.occluded_from(0, geometry, ray, inv_dir, t_min, t_max)
    }

    /// [`Bvh8::occluded`] over the subtree under `start`.
    fn occluded_from(
        &self,
        start: ChildRef,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        let mut stack = [const { MaybeUninit::<ChildRef>::uninit() }; STACK_SIZE];
        stack[0].write(start);
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            // SAFETY: every slot below `depth` was written before `depth` passed it.
            let child = unsafe { stack[depth].assume_init() };
            if child & LEAF != 0 {
                if self.blocks(geometry, child, ray, inv_dir, t_min, t_max) {
                    return true;
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let (hits, _) = node.entries(ray.origin, inv_dir, t_min, t_max);
            for_lanes(hits, |k| {
                stack[depth].write(node.child[k]);
                depth += 1;
            });
        }
        false
    }

    /// The closest hits of the rays of `rays` whose bit is set in `active`, traced
    /// together: each node's children are tested against all the packet's rays at once,
    /// visited nearest first (by the nearest lane's entry) with their lanes and that
    /// entry on the stack. An entry is skipped when it lies beyond every lane's closest
    /// hit; a subtree left with few lanes is finished one ray at a time. Each lane's
    /// answer is the one [`Bvh8::closest`] gives.
    pub fn closest_packet(
        &self,
        geometry: &Geometry,
        rays: &[Ray; 8],
        active: u8,
        t_min: f32,
        closest: &mut [ClosestHit; 8],
    ) {
        if self.nodes.is_empty() || active == 0 {
            return;
        }
        let packet = RayPacket::new(rays);
        let inv_dir = packet.inv_dir_lanes();
        let lanes_t_min = F32x8::splat(t_min);
        let limits =
            |closest: &[ClosestHit; 8]| F32x8::from_array(closest.each_ref().map(|c| c.limit()));
        let mut limit = limits(closest);
        let mut stack = [const { MaybeUninit::<(ChildRef, u8, f32)>::uninit() }; STACK_SIZE];
        stack[0].write((0, active, t_min));
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            // SAFETY: every slot below `depth` was written before `depth` passed it.
            let (child, lanes, t_entry) = unsafe { stack[depth].assume_init() };
            // Beyond every lane's closest hit: nothing closer inside (ties are visited).
            let farthest = limit.to_array();
            if (0..8).all(|k| lanes & (1 << k) == 0 || t_entry > farthest[k] * FAR_WIDENING) {
                continue;
            }
            if child & LEAF != 0 || lanes.count_ones() <= SINGLE_RAY_LANES {
                for_lanes(lanes, |k| {
                    if child & LEAF != 0 {
                        self.closest_in_leaf(
                            geometry,
                            child,
                            &rays[k],
                            inv_dir[k],
                            t_min,
                            &mut closest[k],
                        );
                    } else {
                        self.closest_from(
                            child,
                            geometry,
                            &rays[k],
                            inv_dir[k],
                            t_min,
                            &mut closest[k],
                        );
                    }
                });
                limit = limits(closest);
                continue;
            }
            let node = &self.nodes[child as usize];
            let mask = Mask8::from_bitmask(lanes);
            let boxes = node.boxes.corners();
            // (child, its lanes, the nearest lane's entry), for the children entered.
            let mut entered = [(0u32, 0u8, 0f32); WIDTH];
            let mut count = 0;
            for (c, &(min, max)) in boxes.iter().enumerate().take(node.count as usize) {
                let (hit, t) = slab_entry_packet(&packet, min, max, lanes_t_min, limit, mask);
                let hit = hit.bitmask();
                if hit != 0 {
                    let t = t.to_array();
                    let mut nearest = f32::INFINITY;
                    for_lanes(hit, |k| nearest = nearest.min(t[k]));
                    entered[count] = (node.child[c], hit, nearest);
                    count += 1;
                }
            }
            let entered = &mut entered[..count];
            // Farthest first on the stack, so the nearest is popped next.
            entered.sort_unstable_by(|a, b| b.2.total_cmp(&a.2));
            for &e in entered.iter() {
                stack[depth].write(e);
                depth += 1;
            }
        }
    }

    /// The lanes of `active` whose ray is blocked within `(t_min, t_max[k])`, as a bit
    /// mask, the rays traced together as in [`Bvh8::closest_packet`].
    pub fn occluded_packet(
        &self,
        geometry: &Geometry,
        rays: &[Ray; 8],
        active: u8,
        t_min: f32,
        t_max: &[f32; 8],
    ) -> u8 {
        if self.nodes.is_empty() || active == 0 {
            return 0;
        }
        let packet = RayPacket::new(rays);
        let inv_dir = packet.inv_dir_lanes();
        let (lanes_t_min, lanes_t_max) = (F32x8::splat(t_min), F32x8::from_array(*t_max));
        let mut blocked = 0u8;
        let mut stack = [const { MaybeUninit::<(ChildRef, u8)>::uninit() }; STACK_SIZE];
        stack[0].write((0, active));
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            // SAFETY: every slot below `depth` was written before `depth` passed it.
            let (child, lanes) = unsafe { stack[depth].assume_init() };
            let lanes = lanes & !blocked;
            if lanes == 0 {
                continue;
            }
            if child & LEAF != 0 || lanes.count_ones() <= SINGLE_RAY_LANES {
                for_lanes(lanes, |k| {
                    let hit = if child & LEAF != 0 {
                        self.blocks(geometry, child, &rays[k], inv_dir[k], t_min, t_max[k])
                    } else {
                        self.occluded_from(child, geometry, &rays[k], inv_dir[k], t_min, t_max[k])
                    };
                    if hit {
                        blocked |= 1 << k;
                    }
                });
                if blocked == active {
                    break;
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let mask = Mask8::from_bitmask(lanes);
            let boxes = node.boxes.corners();
            for (c, &(min, max)) in boxes.iter().enumerate().take(node.count as usize) {
                let (hit, _) = slab_entry_packet(&packet, min, max, lanes_t_min, lanes_t_max, mask);
                let hit = hit.bitmask();
                if hit != 0 {
                    stack[depth].write((node.child[c], hit));
                    depth += 1;
                }
            }
        }
        blocked
    }
}

/// A packet whose lanes in a subtree drop to this many finishes it one ray at a time.
const SINGLE_RAY_LANES: u32 = 2;

/// The most primitives of one kind stored side by side in a leaf.
const PACK: usize = 8;

/// The binary tree with the run of primitives under each node.
struct Binary<'a> {
    nodes: &'a [Node],
    prims: &'a [PrimId],
    range: Vec<Range<usize>>,
}

impl<'a> Binary<'a> {
    fn new(nodes: &'a [Node], prims: &'a [PrimId]) -> Self {
        // Children follow their parent, so a backward sweep sees them first.
        let mut range = vec![0..0; nodes.len()];
        for i in (0..nodes.len()).rev() {
            range[i] = if nodes[i].is_leaf() {
                nodes[i].prim_range()
            } else {
                range[i + 1].start..range[nodes[i].right_child()].end
            };
        }
        Binary {
            nodes,
            prims,
            range,
        }
    }

    /// The two children of the interior node `i`.
    fn children(&self, i: usize) -> Vec<usize> {
        vec![i + 1, self.nodes[i].right_child()]
    }

    /// The kind of a subtree that becomes one pack: at most [`PACK`] triangles, or
    /// spheres.
    fn pack_kind(&self, i: usize) -> Option<PrimKind> {
        let prims = &self.prims[self.range[i].clone()];
        let kind = prims.first()?.kind();
        let packable = matches!(kind, PrimKind::Triangle | PrimKind::Sphere);
        (packable && prims.len() <= PACK && prims.iter().all(|p| p.kind() == kind)).then_some(kind)
    }

    /// Nodes that become leaves of the 8-wide tree.
    fn is_terminal(&self, i: usize) -> bool {
        self.nodes[i].is_leaf() || self.pack_kind(i).is_some()
    }
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
                let bvh = Bvh::build(&scene.geometry, build, BvhWidth::Eight, [0.0, 0.0]);
                let wide = bvh.wide().expect("small trees collapse");
                wide.validate();
                assert!(wide.depth() <= bvh.depth());
            }
        }
    }
}
