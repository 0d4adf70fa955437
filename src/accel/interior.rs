//! Rays that start inside a glass sphere's box (refracted into the sphere, or reflected
//! inside it): where no primitive but a few spheres comes near that box, the sphere and
//! those spheres alone give the ray's closest hit, so the stream renderer answers such
//! rays without a walk ([`super::Tracer::closest_in_sphere8`]; the rooms are made for it
//! alone, [`super::Tracer::with_rooms`]).
//!
//! **Why it is exact.** Every primitive reports a hit at `t` only inside the ray's
//! interval of its trusted box, as the structures' box test computes it
//! (`accel::bounds`); that test's slab distances `(corner - origin) * inv_dir` are off by
//! at most `GAMMA_3` of themselves, and it allows `2 GAMMA_3` more. Let a ray start in
//! sphere S's trusted box B, and let Q be a primitive whose trusted box lies beyond the
//! plane `x_a = B.max_a + m` on some axis `a` (or below `B.min_a - m`). A ray heading
//! away from that plane never enters Q's box. One heading for it (`d_a > 0`) leaves B by
//! `(B.max_a - o_a) / d_a` and meets Q no sooner than `(B.max_a - o_a + m) / d_a`, each
//! known to a few `GAMMA_3` of itself; with `m` a ten-thousandth ([`MARGIN`]) of B's
//! longest side, some eighty times those errors, a hit inside B (its `t` held by B's
//! interval, which [`super::Tracer::closest_in_sphere8`] checks) comes strictly before
//! any hit of Q. So the closest hit that S and the spheres within `m` of B (at most
//! [`NEAR`], by the tie rule of [`super::ClosestHit`]) find inside B is brute force's
//! answer, and every structure's. A near sphere is tested only in the lanes whose
//! interval of its box begins by the best hit so far: in the others it reports no hit that
//! soon. A sphere with any other primitive within `m`, or more spheres, is left to the
//! walks, and so are all the spheres of a scene with planes, which no box holds.

use super::bounds::prim_bounds;
use crate::intersect::{Aabb, IntersectOptions};
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;

/// The most spheres near a sphere that its rays are tested against beside it.
pub const NEAR: usize = 3;

/// How far, as a fraction of a sphere box's longest side, another primitive's box must
/// keep from it on some axis.
pub const MARGIN: f64 = 1e-4;

/// The most sphere boxes looked at while the rooms are made (a few per primitive where
/// the spheres are spread out): beyond it, a few milliseconds, no sphere is answered.
const LOOKS: usize = 1 << 22;

/// Each sphere's room: whether its rays may be answered, and the spheres near it. Four
/// bytes a sphere, and the lists of the few that have near spheres.
#[derive(Clone, Debug)]
pub struct Rooms {
    /// By sphere: [`ALONE`], [`CROWDED`], or 1 + the index of its list in `near`.
    rooms: Vec<u32>,
    near: Vec<Near>,
    /// The primitives' tests, whose margin the spheres' boxes take ([`prim_bounds`]).
    options: IntersectOptions,
}

/// A sphere with no primitive near it.
const ALONE: u32 = 0;
/// A sphere whose rays are left to the walks: a primitive other than a sphere comes near
/// it, or too many spheres, or it is not glass, or its box vanishes.
const CROWDED: u32 = u32::MAX;

/// The spheres near one sphere, and their boxes: the first `count`.
#[derive(Clone, Copy, Debug)]
struct Near {
    spheres: [u32; NEAR],
    boxes: [Aabb; NEAR],
    count: u8,
}

impl Rooms {
    /// The rooms of `geometry`'s spheres whose material `glass` says rays travel in, the
    /// others left to the walks, with the boxes the structures take (`shutter`, and
    /// `options`' margin for spheres: [`prim_bounds`]); `None` where no room can answer
    /// (no such spheres, or planes).
    pub fn new(
        geometry: &Geometry,
        shutter: [f32; 2],
        options: IntersectOptions,
        glass: impl Fn(u32) -> bool,
    ) -> Option<Rooms> {
        let spheres = geometry.count(PrimKind::Sphere);
        let unbounded = PrimKind::UNBOUNDED.iter().any(|&k| geometry.count(k) != 0);
        if spheres == 0 || unbounded {
            return None;
        }
        let mut rooms = Rooms {
            rooms: vec![ALONE; spheres],
            near: Vec::new(),
            options,
        };
        let margin = |b: &Aabb| MARGIN * f64::from(b.extent().max_element());
        // The spheres by the lower x of their boxes grown by the margin (rounded down), so
        // that the rooms a primitive's box may reach are one run of them. An empty or
        // vanishing box (a sphere never hit) answers nothing.
        let mut order: Vec<(f32, u32)> = Vec::new();
        let (mut widest, mut reach) = (0.0f64, Aabb::EMPTY);
        for i in 0..spheres {
            let b = rooms.bounds(geometry, i);
            let side = b.extent().max_element();
            let vanishing = b.is_empty() || !(side >= 1e-20);
            if vanishing || !glass(geometry.spheres.records[i].material) {
                rooms.rooms[i] = CROWDED;
                continue;
            }
            let start = ((f64::from(b.min.x) - margin(&b)) as f32).next_down();
            widest = widest.max(f64::from(b.max.x) + margin(&b) - f64::from(start));
            order.push((start, i as u32));
            reach = reach.union(b.padded((2.0 * margin(&b)) as f32));
        }
        if order.is_empty() {
            return None;
        }
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut looks = 0;
        for &kind in &PrimKind::BOUNDED {
            for prim in geometry.ids(kind) {
                // Most primitives are far from every glass sphere: told by their tight
                // boxes, grown by more than the trusted box grows them.
                let tight = geometry.bounds(prim, shutter);
                let scale = tight.min.abs().max(tight.max.abs()).max_element();
                let pad = options.sphere_margin + 1e-5 * scale + 1e-30;
                if !overlap(&tight.padded(pad), &reach) {
                    continue;
                }
                let b = prim_bounds(geometry, prim, shutter, options.sphere_margin);
                if b.is_empty() {
                    continue;
                }
                let (low, high) = (f64::from(b.min.x), f64::from(b.max.x));
                let first = order.partition_point(|&(start, _)| f64::from(start) < low - widest);
                for &(start, s) in &order[first..] {
                    if f64::from(start) > high {
                        break;
                    }
                    looks += 1;
                    if looks > LOOKS {
                        return None;
                    }
                    let own = prim == PrimId::new(PrimKind::Sphere, s);
                    if own || rooms.rooms[s as usize] == CROWDED {
                        continue;
                    }
                    let sphere = rooms.bounds(geometry, s as usize);
                    if comes_near(&sphere, &b, margin(&sphere)) {
                        let near = (kind == PrimKind::Sphere).then(|| (prim.index(), b));
                        rooms.add_near(s as usize, near);
                    }
                }
            }
        }
        Some(rooms)
    }

    /// Notes that `near` (a sphere's index and box, or `None` for another primitive)
    /// comes near sphere `sphere`.
    fn add_near(&mut self, sphere: usize, near: Option<(usize, Aabb)>) {
        let room = &mut self.rooms[sphere];
        match near {
            Some((near, b)) if *room == ALONE => {
                self.near.push(Near {
                    spheres: [near as u32; NEAR],
                    boxes: [b; NEAR],
                    count: 1,
                });
                *room = self.near.len() as u32;
            }
            Some((near, b)) if *room != CROWDED => {
                let list = &mut self.near[*room as usize - 1];
                let count = usize::from(list.count);
                if count < NEAR {
                    (list.spheres[count], list.boxes[count]) = (near as u32, b);
                    list.count += 1;
                } else {
                    *room = CROWDED;
                }
            }
            _ => *room = CROWDED,
        }
    }

    /// The spheres near sphere `sphere` and their boxes, or `None` if its rays are left to
    /// the walks.
    #[inline]
    pub fn near_spheres(&self, sphere: usize) -> Option<(&[u32], &[Aabb])> {
        match self.rooms[sphere] {
            ALONE => Some((&[], &[])),
            CROWDED => None,
            list => {
                let near = &self.near[list as usize - 1];
                let count = usize::from(near.count);
                Some((&near.spheres[..count], &near.boxes[..count]))
            }
        }
    }

    /// Sphere `sphere`'s trusted box, as the structures take it (empty if not finite).
    #[inline]
    pub fn bounds(&self, geometry: &Geometry, sphere: usize) -> Aabb {
        let trusted = geometry.spheres.trusted_box(sphere, self.options);
        trusted.unwrap_or(Aabb::EMPTY)
    }
}

/// Whether boxes `a` and `b` share a point.
fn overlap(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// Whether box `b` comes within `margin` of box `room` on every axis (no axis keeps
/// them that far apart).
fn comes_near(room: &Aabb, b: &Aabb, margin: f64) -> bool {
    (0..3).all(|a| {
        let gap_above = f64::from(b.min[a]) - f64::from(room.max[a]);
        let gap_below = f64::from(room.min[a]) - f64::from(b.max[a]);
        gap_above < margin && gap_below < margin
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn rooms_of(spheres: &[(Vec3, f32)], triangles: &[[Vec3; 3]]) -> Option<Rooms> {
        let mut geometry = Geometry::default();
        for &(centre, radius) in spheres {
            geometry.spheres.push(centre, radius, 0);
        }
        for t in triangles {
            geometry.triangles.push(*t, None, 0);
        }
        Rooms::new(&geometry, [0.0, 0.0], IntersectOptions::default(), |_| true)
    }

    fn spheres_near(rooms: &Rooms, sphere: usize) -> Option<Vec<u32>> {
        rooms
            .near_spheres(sphere)
            .map(|(spheres, _)| spheres.to_vec())
    }

    #[test]
    fn spheres_far_apart_have_rooms_of_their_own() {
        let rooms = rooms_of(&[(Vec3::ZERO, 1.0), (Vec3::X * 3.0, 1.0)], &[]).unwrap();
        assert_eq!(spheres_near(&rooms, 0), Some(vec![]));
        assert_eq!(spheres_near(&rooms, 1), Some(vec![]));
    }

    #[test]
    fn touching_spheres_are_near_each_other_and_a_triangle_crowds_them() {
        let ground = [(-5.0, -5.0), (5.0, -5.0), (0.0, 5.0)].map(|(x, y)| Vec3::new(x, y, -1.5));
        let spheres = [
            (Vec3::ZERO, 1.0),
            (Vec3::X * 2.0, 1.0),
            (Vec3::Z * 9.0, 1.0),
        ];
        let rooms = rooms_of(&spheres, &[ground]).unwrap();
        assert_eq!(spheres_near(&rooms, 0), Some(vec![1]));
        assert_eq!(spheres_near(&rooms, 1), Some(vec![0]));
        assert_eq!(spheres_near(&rooms, 2), Some(vec![]));
        let touching = ground.map(|v| v + Vec3::Z * 0.5);
        let crowded = rooms_of(&spheres, &[touching]).unwrap();
        assert_eq!(spheres_near(&crowded, 0), None);
        assert_eq!(spheres_near(&crowded, 2), Some(vec![]));
    }

    #[test]
    fn a_sphere_with_too_many_near_spheres_is_crowded() {
        let row: Vec<(Vec3, f32)> = (0..6).map(|i| (Vec3::X * (2 * i) as f32, 1.0)).collect();
        let rooms = rooms_of(&row, &[]).unwrap();
        assert_eq!(spheres_near(&rooms, 0), Some(vec![1]));
        assert_eq!(spheres_near(&rooms, 2), Some(vec![1, 3]));
        let cluster = [(Vec3::ZERO, 1.0); 5];
        let rooms = rooms_of(&cluster, &[]).unwrap();
        assert_eq!(spheres_near(&rooms, 0), None);
    }

    #[test]
    fn no_rooms_without_spheres() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(rooms_of(&[], &[t]).is_none());
    }
}
