//! Rays that start inside the box of a glass primitive of a kind with an interior
//! ([`Geometry::has_interior`]: spheres), refracted into it or reflected inside it: where
//! no primitive but a few of such kinds comes near that box, the primitive and those few
//! alone give the ray's closest hit, so the stream renderer answers such rays without a
//! walk ([`super::Tracer::closest_inside8`]; the rooms are made for it alone,
//! [`super::Tracer::with_rooms`]).
//!
//! **Why it is exact.** Every primitive reports a hit at `t` only inside the ray's
//! interval of its trusted box, as the structures' box test computes it
//! (`accel::bounds`); that test's slab distances `(corner - origin) * inv_dir` are off by
//! at most `GAMMA_3` of themselves, and it allows `2 GAMMA_3` more. Let a ray start in
//! primitive S's trusted box B, and let Q be a primitive whose trusted box lies beyond the
//! plane `x_a = B.max_a + m` on some axis `a` (or below `B.min_a - m`). A ray heading
//! away from that plane never enters Q's box. One heading for it (`d_a > 0`) leaves B by
//! `(B.max_a - o_a) / d_a` and meets Q no sooner than `(B.max_a - o_a + m) / d_a`, each
//! known to a few `GAMMA_3` of itself; with `m` a ten-thousandth ([`MARGIN`]) of B's
//! longest side, some eighty times those errors, a hit inside B (its `t` held by B's
//! interval, which [`super::Tracer::closest_inside8`] checks) comes strictly before
//! any hit of Q. So the closest hit that S and the primitives within `m` of B (at most
//! [`NEAR`], by the tie rule of [`super::ClosestHit`]) find inside B is brute force's
//! answer, and every structure's. A near primitive is tested only in the lanes whose
//! interval of its box begins by the best hit so far: in the others it reports no hit that
//! soon. A primitive with one of a kind without an interior within `m`, or more near ones,
//! is left to the walks, and so are all of a scene with planes, which no box holds.

use super::bounds::prim_bounds;
use crate::intersect::{Aabb, IntersectOptions};
use crate::prim::{PrimId, PrimKind};
use crate::scene::Geometry;

/// The most primitives near one that its rays are tested against beside it.
pub const NEAR: usize = 3;

/// How far, as a fraction of a room's longest side, another primitive's box must keep
/// from it on some axis.
pub const MARGIN: f64 = 1e-4;

/// The most rooms looked at while the rooms are made (a few per primitive where the
/// rooms are spread out): beyond it, a few milliseconds, no ray is answered.
const LOOKS: usize = 1 << 22;

/// Each room, the trusted box of a primitive of a kind with an interior: whether its rays
/// may be answered, and the primitives near it. Four bytes a primitive, and the lists of
/// the few that have near ones.
#[derive(Clone, Debug)]
pub struct Rooms {
    /// By kind, then by primitive: [`ALONE`], [`CROWDED`], or 1 + the index of its list
    /// in `near`; empty for the kinds without an interior.
    rooms: [Vec<u32>; PrimKind::ALL.len()],
    near: Vec<Near>,
    /// The shutter and the primitives' tests, whose boxes the rooms are ([`prim_bounds`]).
    shutter: [f32; 2],
    options: IntersectOptions,
}

/// A room with no primitive near it.
const ALONE: u32 = 0;
/// A room whose rays are left to the walks: a primitive of a kind without an interior
/// comes near it, or too many others, or it is not glass, or its box vanishes.
const CROWDED: u32 = u32::MAX;

/// The primitives near one room, and their boxes: the first `count`.
#[derive(Clone, Copy, Debug)]
struct Near {
    prims: [PrimId; NEAR],
    boxes: [Aabb; NEAR],
    count: u8,
}

impl Rooms {
    /// The rooms of `geometry`'s primitives of kinds with an interior whose material
    /// `glass` says rays travel in, the others left to the walks, with the boxes the
    /// structures take (`shutter`, `options`: [`prim_bounds`]); `None` where no room can
    /// answer (no such primitives, or planes).
    pub fn new(
        geometry: &Geometry,
        shutter: [f32; 2],
        options: IntersectOptions,
        glass: impl Fn(u32) -> bool,
    ) -> Option<Rooms> {
        let unbounded = PrimKind::UNBOUNDED.iter().any(|&k| geometry.count(k) != 0);
        if unbounded {
            return None;
        }
        let count = |kind: PrimKind| match Geometry::has_interior(kind) {
            true => geometry.count(kind),
            false => 0,
        };
        let mut rooms = Rooms {
            rooms: PrimKind::ALL.map(|kind| vec![ALONE; count(kind)]),
            near: Vec::new(),
            shutter,
            options,
        };
        let margin = |b: &Aabb| MARGIN * f64::from(b.extent().max_element());
        // The rooms by the lower x of their boxes grown by the margin (rounded down), so
        // that the rooms a primitive's box may reach are one run of them. An empty or
        // vanishing box (a primitive never hit) answers nothing.
        let mut order: Vec<(f32, PrimId)> = Vec::new();
        let (mut widest, mut reach) = (0.0f64, Aabb::EMPTY);
        for kind in PrimKind::ALL {
            for prim in geometry.ids(kind).take(count(kind)) {
                let b = rooms.bounds(geometry, prim);
                let side = b.extent().max_element();
                let vanishing = b.is_empty() || !(side >= 1e-20);
                if vanishing || !glass(geometry.material(prim)) {
                    *rooms.room_mut(prim) = CROWDED;
                    continue;
                }
                let start = ((f64::from(b.min.x) - margin(&b)) as f32).next_down();
                widest = widest.max(f64::from(b.max.x) + margin(&b) - f64::from(start));
                order.push((start, prim));
                reach = reach.union(b.padded((2.0 * margin(&b)) as f32));
            }
        }
        if order.is_empty() {
            return None;
        }
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut looks = 0;
        for &kind in &PrimKind::BOUNDED {
            for prim in geometry.ids(kind) {
                // Most primitives are far from every room: told by their tight boxes,
                // grown by more than the trusted box grows them.
                let tight = geometry.bounds(prim, shutter);
                let scale = tight.min.abs().max(tight.max.abs()).max_element();
                let pad = options.roots_margin + 1e-5 * scale + 1e-30;
                if !overlap(&tight.padded(pad), &reach) {
                    continue;
                }
                let b = prim_bounds(geometry, prim, shutter, options.roots_margin);
                if b.is_empty() {
                    continue;
                }
                let (low, high) = (f64::from(b.min.x), f64::from(b.max.x));
                let first = order.partition_point(|&(start, _)| f64::from(start) < low - widest);
                for &(start, owner) in &order[first..] {
                    if f64::from(start) > high {
                        break;
                    }
                    looks += 1;
                    if looks > LOOKS {
                        return None;
                    }
                    if prim == owner || rooms.near(owner).is_none() {
                        continue;
                    }
                    let room = rooms.bounds(geometry, owner);
                    if comes_near(&room, &b, margin(&room)) {
                        let near = Geometry::has_interior(kind).then_some((prim, b));
                        rooms.add_near(owner, near);
                    }
                }
            }
        }
        Some(rooms)
    }

    /// Where the room of `prim` is noted (a primitive of a kind with an interior).
    fn room_mut(&mut self, prim: PrimId) -> &mut u32 {
        &mut self.rooms[prim.kind() as usize][prim.index()]
    }

    /// Notes that `near` (a primitive of a kind with an interior and its box, or `None`
    /// for one of another kind) comes near the room of `owner`.
    fn add_near(&mut self, owner: PrimId, near: Option<(PrimId, Aabb)>) {
        let room = &mut self.rooms[owner.kind() as usize][owner.index()];
        match near {
            Some((near, b)) if *room == ALONE => {
                self.near.push(Near {
                    prims: [near; NEAR],
                    boxes: [b; NEAR],
                    count: 1,
                });
                *room = self.near.len() as u32;
            }
            Some((near, b)) if *room != CROWDED => {
                let list = &mut self.near[*room as usize - 1];
                let count = usize::from(list.count);
                if count < NEAR {
                    (list.prims[count], list.boxes[count]) = (near, b);
                    list.count += 1;
                } else {
                    *room = CROWDED;
                }
            }
            _ => *room = CROWDED,
        }
    }

    /// The primitives near the room of `prim` and their boxes, or `None` if its rays are
    /// left to the walks (or it has no room).
    #[inline]
    pub fn near(&self, prim: PrimId) -> Option<(&[PrimId], &[Aabb])> {
        match *self.rooms[prim.kind() as usize].get(prim.index())? {
            ALONE => Some((&[], &[])),
            CROWDED => None,
            list => {
                let near = &self.near[list as usize - 1];
                let count = usize::from(near.count);
                Some((&near.prims[..count], &near.boxes[..count]))
            }
        }
    }

    /// The room of `prim`: its trusted box, as the structures take it (empty if not
    /// finite).
    #[inline]
    pub fn bounds(&self, geometry: &Geometry, prim: PrimId) -> Aabb {
        prim_bounds(geometry, prim, self.shutter, self.options.roots_margin)
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

    fn spheres_near(rooms: &Rooms, sphere: u32) -> Option<Vec<usize>> {
        let (near, _) = rooms.near(PrimId::new(PrimKind::Sphere, sphere))?;
        Some(near.iter().map(|p| p.index()).collect())
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
