//! Single-ray traversal of the 8-wide tree: one ray against a node's eight boxes at
//! once, nearest child first; leaves of packed triangles or spheres tested eight at a
//! time.

use glam::Vec3;

use super::node::{leaf_parts, ChildRef, LEAF, SPHERES, TRIANGLES};
use super::{Bvh8, STACK_SIZE};
use crate::accel::hit::{for_lanes, ClosestHit};
use crate::accel::stack::Stack;
use crate::intersect::{beyond, sphere_leaf, triangle_leaf, BoxRay};
use crate::ray::{Hit, Ray};
use crate::scene::Geometry;

impl Bvh8 {
    /// Tests the primitives of leaf `child`, keeping the winner in `closest`.
    #[inline]
    pub(super) fn closest_in_leaf(
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
                let (hit, t) = sphere_leaf(
                    ray,
                    &self.spheres[index],
                    self.sphere_roots,
                    t_min,
                    closest.bound(),
                );
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
    pub(super) fn blocks(
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
            SPHERES => sphere_leaf(ray, &self.spheres[index], self.sphere_roots, t_min, t_max)
                .0
                .any(),
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
    #[inline]
    pub(super) fn closest_from(
        &self,
        start: ChildRef,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        closest: &mut ClosestHit,
    ) {
        let box_ray = BoxRay::new(ray.origin, inv_dir);
        let mut stack = Stack::<(ChildRef, f32), STACK_SIZE>::new();
        stack.push((start, t_min));
        while let Some((child, t_entry)) = stack.pop() {
            // Entries beyond the closest hit cannot hold a closer one (ties may).
            if beyond(t_entry, closest.limit()) {
                continue;
            }
            if child & LEAF != 0 {
                self.closest_in_leaf(geometry, child, ray, inv_dir, t_min, closest);
                continue;
            }
            let node = &self.nodes[child as usize];
            let (hits, entries) = node.entries(&box_ray, t_min, closest.limit());
            // The hit children sorted on the stack, the nearest on top to be popped next.
            let floor = stack.len();
            for_lanes(hits, |k| {
                stack.push_sorted(floor, (node.child[k], entries[k]), |e| e.1)
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
    pub(super) fn occluded_from(
        &self,
        start: ChildRef,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        let box_ray = BoxRay::new(ray.origin, inv_dir);
        let mut stack = Stack::<ChildRef, STACK_SIZE>::new();
        stack.push(start);
        while let Some(child) = stack.pop() {
            if child & LEAF != 0 {
                if self.blocks(geometry, child, ray, inv_dir, t_min, t_max) {
                    return true;
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let (hits, _) = node.entries(&box_ray, t_min, t_max);
            for_lanes(hits, |k| stack.push(node.child[k]));
        }
        false
    }
}
