//! Single-ray traversal of the 8-wide tree: one ray against a node's eight boxes at
//! once, nearest child first; a pack leaf's primitives tested eight at a time.

use super::node::{leaf_parts, ChildRef, LEAF};
use super::Bvh8;
use crate::accel::count::Count;
use crate::accel::hit::ClosestHit;
use crate::accel::stack::Stack;
use crate::intersect::{beyond, BoxRay, RayQuery};
use crate::scene::Geometry;
use crate::simd::for_lanes;

impl Bvh8 {
    /// Tests the primitives of leaf `child`, keeping the winner in `closest`.
    #[inline]
    pub(super) fn closest_in_leaf<C: Count, const FRAME: usize, const COMPACT: bool>(
        &self,
        geometry: &Geometry,
        child: ChildRef,
        query: &RayQuery,
        closest: &mut ClosestHit,
        counted: &mut C,
    ) {
        let (_, count, index) = leaf_parts(child);
        counted.leaf();
        counted.prims(count as u32);
        if !self.leaves.closest::<FRAME, COMPACT>(child, query, closest) {
            for &prim in &self.prims[index..index + count] {
                closest.test(geometry, prim, query);
            }
        }
    }

    /// Whether a primitive of leaf `child` blocks `query` within `(t_min, t_max)`.
    /// Inlined into the walks, as it was before they counted: out of line, the scalar
    /// render ran 0.9% more instructions (callgrind, dragon).
    #[inline(always)]
    pub(super) fn blocks<C: Count, const FRAME: usize, const COMPACT: bool>(
        &self,
        geometry: &Geometry,
        child: ChildRef,
        query: &RayQuery,
        t_max: f32,
        counted: &mut C,
    ) -> bool {
        counted.leaf();
        let in_pack = self.leaves.blocks::<FRAME, COMPACT>(child, query, t_max);
        if in_pack.is_some() {
            counted.prims(leaf_parts(child).1 as u32);
        }
        in_pack.unwrap_or_else(|| {
            let (_, count, index) = leaf_parts(child);
            let prims = &self.prims[index..index + count];
            prims.iter().any(|&prim| {
                counted.prims(1);
                geometry.intersect(prim, query, t_max).is_some()
            })
        })
    }

    /// The closest hit of `query` in the subtree under `start`, offered to `closest`.
    #[inline]
    pub(super) fn closest_from<
        C: Count,
        const STACK: usize,
        const FRAME: usize,
        const COMPACT: bool,
    >(
        &self,
        start: ChildRef,
        geometry: &Geometry,
        query: &RayQuery,
        closest: &mut ClosestHit,
        count: &mut C,
    ) {
        let (t_min, box_ray) = (query.t_min, BoxRay::new(query.ray.origin, query.inv_dir));
        let mut stack = Stack::<(ChildRef, f32), STACK>::new();
        // The nearest child of the node just tested, entered without the stack: it lies
        // within the closest hit, which has not moved since its box test.
        let mut next = Some(start);
        loop {
            let child = match next.take() {
                Some(child) => child,
                None => match stack.pop() {
                    // Entries beyond the closest hit cannot hold a closer one (ties may).
                    Some((child, t_entry)) if !beyond(t_entry, closest.limit()) => child,
                    Some(_) => continue,
                    None => break,
                },
            };
            if child & LEAF != 0 {
                self.closest_in_leaf::<C, FRAME, COMPACT>(geometry, child, query, closest, count);
                continue;
            }
            let node = &self.nodes[child as usize];
            count.node();
            count.boxes(node.count);
            let (hits, entries) = node.entries(&box_ray, t_min, closest.limit());
            if hits & hits.wrapping_sub(1) == 0 {
                // No child hit, or one, entered at once: nothing to sort or ask the cache
                // for ahead of its reading.
                next = (hits != 0).then(|| node.child[hits.trailing_zeros() as usize]);
                continue;
            }
            // The other hit children sorted on the stack, the nearest of them on top: the
            // order in which the stack gave them all when it held the nearest too.
            let floor = stack.len();
            let mut nearest: Option<(ChildRef, f32)> = None;
            for_lanes(hits, |k| {
                self.prefetch_child::<COMPACT>(node.child[k], true);
                let hit = (node.child[k], entries[k]);
                stack.push_sorted_but_nearest(floor, &mut nearest, hit, |e| e.1)
            });
            next = nearest.map(|near| near.0);
        }
    }

    /// Whether a primitive of the subtree under `start` blocks `query` within
    /// `(query.t_min, t_max)`.
    #[inline(always)]
    pub(super) fn occluded_from<
        C: Count,
        const STACK: usize,
        const FRAME: usize,
        const COMPACT: bool,
    >(
        &self,
        start: ChildRef,
        geometry: &Geometry,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
    ) -> bool {
        let (t_min, box_ray) = (query.t_min, BoxRay::new(query.ray.origin, query.inv_dir));
        let mut stack = Stack::<ChildRef, STACK>::new();
        let mut next = Some(start);
        while let Some(child) = next.take().or_else(|| stack.pop()) {
            if child & LEAF != 0 {
                if self.blocks::<C, FRAME, COMPACT>(geometry, child, query, t_max, count) {
                    return true;
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            count.node();
            count.boxes(node.count);
            let (hits, _) = node.entries(&box_ray, t_min, t_max);
            if hits != 0 {
                // The last child pushed is the one popped next: it skips the stack.
                let last = hits.ilog2() as usize;
                for_lanes(hits & !(1 << last), |k| {
                    self.prefetch_child::<COMPACT>(node.child[k], false);
                    stack.push(node.child[k])
                });
                next = Some(node.child[last]);
            }
        }
        false
    }
}
