//! The course report's uniform grid (P3F.md section 9): `floor(m w_i s) + 1` cells along
//! each axis with `s = (N / V)^(1/3)`, every object listed in each cell its box overlaps,
//! and the 3D-DDA traversal of Amanatides and Woo.
//!
//! The report accepts a hit only when it lies before the current cell's exit and finds it
//! again in a later cell otherwise. Here a hit beyond the exit is kept as a candidate and
//! the walk stops once a cell's exit passes it: the same answer, and it lets mailboxing
//! (`--mailbox`, per-thread stamps) test an object that spans several cells only once per
//! ray.
//!
//! The walk (`Dda`) allows for the rounding of its plane crossings and of the cells'
//! boundaries, so a ray from far away, or one passing within rounding of an edge, visits
//! every cell it may be in. A packet's lanes walk their own DDAs in lockstep, and the
//! lanes standing in one cell test its objects together by the packet kernels. Each axis
//! has at most [`MAX_AXIS_CELLS`] cells: a flat scene's padded box would otherwise ask
//! for millions.

use std::cell::RefCell;

use glam::{IVec3, UVec3, Vec3};

use super::bounds::prim_bounds;
use super::count::{Count, CountLanes};
use super::hit::{test_packet, ClosestHit};
use super::structure::Structure;
use crate::intersect::{beyond, widen_entry, widen_exit, Aabb, BoxRay, PacketQuery, RayQuery};
use crate::prim::{PrimId, PrimKind};
use crate::ray::{lane_mask, Ray, RayPacket};
use crate::scene::Geometry;
use crate::simd::{for_lanes, Bits, F32xP, LaneBits, PACKET};

/// The report's `m`.
pub const DEFAULT_DENSITY: f32 = 2.0;

/// At most this many cells along an axis: flat scenes would otherwise ask for millions.
pub const MAX_AXIS_CELLS: u32 = 512;

#[derive(Clone, Debug)]
pub struct Grid {
    bounds: Aabb,
    resolution: UVec3,
    cell_size: Vec3,
    inv_cell_size: Vec3,
    /// How far a plane the walk computes (`min + i * cell_size`) may lie from where
    /// `cell_of`, which places the objects, puts that boundary: a few roundings of the
    /// grid's coordinates.
    plane_error: Vec3,
    /// Cell `c`'s objects are `refs[cell_start[c]..cell_start[c + 1]]` (cells x fastest).
    cell_start: Vec<u32>,
    /// Indices into `prims`.
    refs: Vec<u32>,
    prims: Vec<PrimId>,
    density: f32,
    mailbox: bool,
}

/// Roundings of a coordinate that a plane of the walk and a boundary of `cell_of` may
/// differ by: each takes three or four roundings of numbers no larger than the grid's
/// coordinates, so eight is ample.
const PLANE_ROUNDING: f32 = 8.0 * f32::EPSILON;

impl Grid {
    /// The report's grid over the bounded primitives of `geometry`, `density` its `m`,
    /// moving spheres bounded over `shutter`; with `mailbox`, an object spanning several
    /// cells is tested once per ray.
    /// Spheres' boxes are grown by `roots_margin` (`bounds::prim_bounds`).
    pub fn build(
        geometry: &Geometry,
        density: f32,
        mailbox: bool,
        shutter: [f32; 2],
        roots_margin: f32,
    ) -> Grid {
        let mut prims = Vec::with_capacity(geometry.bounded_count());
        let mut boxes = Vec::with_capacity(geometry.bounded_count());
        for kind in PrimKind::BOUNDED {
            for prim in geometry.ids(kind) {
                let b = prim_bounds(geometry, prim, shutter, roots_margin);
                if !b.is_empty() {
                    prims.push(prim);
                    boxes.push(b);
                }
            }
        }
        let tight = boxes.iter().fold(Aabb::EMPTY, |a, &b| a.union(b));
        let (bounds, resolution) = if tight.is_empty() {
            (Aabb::EMPTY, UVec3::ONE)
        } else {
            // Padding keeps a flat scene's box from having zero volume.
            let scale = tight.extent().max_element().max(1e-6);
            let bounds = tight.padded(scale * 1e-4);
            let resolution = cells_per_axis(bounds.extent(), prims.len(), density);
            (bounds, resolution)
        };
        let cell_size = bounds.extent() / resolution.as_vec3();
        let inv_cell_size = cell_size.recip();
        let mut grid = Grid {
            bounds,
            resolution,
            cell_size,
            inv_cell_size,
            plane_error: PLANE_ROUNDING * (bounds.min.abs() + bounds.max.abs()),
            cell_start: Vec::new(),
            refs: Vec::new(),
            prims,
            density,
            mailbox,
        };
        grid.fill(&boxes);
        grid
    }

    /// Lists every object in the cells its box overlaps: count, prefix sums, then place.
    fn fill(&mut self, boxes: &[Aabb]) {
        let cells = (self.resolution.x * self.resolution.y * self.resolution.z) as usize;
        let mut start = vec![0u32; cells + 1];
        let ranges: Vec<(UVec3, UVec3)> = boxes
            .iter()
            .map(|b| (self.cell_of(b.min), self.cell_of(b.max)))
            .collect();
        for &(lo, hi) in &ranges {
            self.for_cells(lo, hi, |c| start[c + 1] += 1);
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut next = start.clone();
        let mut refs = vec![0u32; start[cells] as usize];
        for (i, &(lo, hi)) in ranges.iter().enumerate() {
            self.for_cells(lo, hi, |c| {
                refs[next[c] as usize] = i as u32;
                next[c] += 1;
            });
        }
        self.cell_start = start;
        self.refs = refs;
    }

    fn for_cells(&self, lo: UVec3, hi: UVec3, mut visit: impl FnMut(usize)) {
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    visit(self.cell_index(UVec3::new(x, y, z)));
                }
            }
        }
    }

    /// The cell holding point `p`, clamped into the grid.
    fn cell_of(&self, p: Vec3) -> UVec3 {
        let c = ((p - self.bounds.min) * self.inv_cell_size).floor();
        let max = (self.resolution - 1).as_vec3();
        // `max(ZERO)` also turns NaN into 0.
        c.max(Vec3::ZERO).min(max).as_uvec3()
    }

    /// Whether slab `i` along axis `k` is one of the grid's.
    fn holds(&self, k: usize, i: i32) -> bool {
        // Through its array: a glam vector's index is a `match`.
        0 <= i && (i as u32) < self.resolution.as_ref()[k]
    }

    fn cell_index(&self, c: UVec3) -> usize {
        ((c.z * self.resolution.y + c.y) * self.resolution.x + c.x) as usize
    }

    pub fn name(&self) -> String {
        if self.mailbox {
            "grid+mailbox".into()
        } else {
            "grid".into()
        }
    }
}

impl Structure for Grid {
    fn closest<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        closest: &mut ClosestHit,
        count: &mut C,
    ) {
        Mailbox::with(self.mailbox, self.prims.len(), |mailbox| {
            self.walk(query, closest.limit(), count, |cell_refs, t_exit, count| {
                for &r in cell_refs {
                    if mailbox.first_visit(r) {
                        count.prims(1);
                        closest.test(geometry, self.prims[r as usize], query);
                    }
                }
                // Stop once the closest hit lies inside the cells walked so far (by the
                // allowance: the cells ahead may start within rounding of `t_exit`).
                if beyond(t_exit, closest.limit()) {
                    return Walk::Stop;
                }
                Walk::Continue(closest.limit())
            })
        });
    }

    fn occluded<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
    ) -> bool {
        let mut blocked = false;
        Mailbox::with(self.mailbox, self.prims.len(), |mailbox| {
            self.walk(query, t_max, count, |cell_refs, _, count| {
                blocked = cell_refs.iter().any(|&r| {
                    mailbox.first_visit(r) && {
                        count.prims(1);
                        geometry
                            .intersect(self.prims[r as usize], query, t_max)
                            .is_some()
                    }
                });
                if blocked {
                    Walk::Stop
                } else {
                    Walk::Continue(t_max)
                }
            })
        });
        blocked
    }

    /// The closest hits of the active lanes of `query`'s packet, as one ray's walk finds
    /// each. Each lane walks its own 3D-DDA; at every step the lanes that stand in the
    /// same cell test its objects together, by the primitives' packet kernels (so a
    /// coherent packet tests each object once for all its rays). Mailboxing plays no
    /// part here: it changes how often an object is tested, never the answer.
    fn closest_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        closest: &mut [ClosestHit; PACKET],
        count: &mut C::Lanes,
    ) {
        let packet = query.packet;
        let packet_inv_dir = packet.inv_dir_lanes();
        let limits = closest.each_ref().map(|c| c.limit());
        let mut walks = self.start_walks(packet, &packet_inv_dir, &limits, count);
        loop {
            let walking = lanes_of(&walks, |_| true);
            if walking == 0 {
                return;
            }
            for_cell_groups(&walks, walking, |cell, lanes| {
                let refs = self.cell_refs(cell);
                count.leaf(lanes);
                count.prims(lanes, refs.len() as u32);
                if lanes.count_ones() <= SINGLE_RAY_LANES {
                    for_lanes(lanes, |k| {
                        let lane = query.lane(k);
                        for &r in refs {
                            closest[k].test(geometry, self.prims[r as usize], &lane);
                        }
                    });
                    return;
                }
                for &r in refs {
                    test_packet(closest, geometry, self.prims[r as usize], query, lanes);
                }
            });
            for (k, walk) in walks.iter_mut().enumerate() {
                let Some(dda) = walk else {
                    continue;
                };
                // As `closest`: stop once the closest hit lies in the cells walked.
                let limit = closest[k].limit();
                dda.t_end = dda.t_end.min(limit);
                let stop = beyond(dda.t_exit(), limit);
                self.step(walk, stop, &mut || count.cell(1 << k));
            }
        }
    }

    /// The active lanes of `query`'s packet whose ray is blocked within its interval,
    /// walked as the closest hits are.
    fn occluded_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        count: &mut C::Lanes,
    ) -> LaneBits {
        let (packet, t_max) = (query.packet, &query.packet.t_max);
        let packet_inv_dir = packet.inv_dir_lanes();
        let mut walks = self.start_walks(packet, &packet_inv_dir, t_max, count);
        let mut blocked: LaneBits = 0;
        loop {
            let walking = lanes_of(&walks, |_| true) & !blocked;
            if walking == 0 {
                return blocked;
            }
            for_cell_groups(&walks, walking, |cell, lanes| {
                count.leaf(lanes);
                if lanes.count_ones() <= SINGLE_RAY_LANES {
                    for_lanes(lanes, |k| {
                        let lane = query.lane(k);
                        let hit = self.cell_refs(cell).iter().any(|&r| {
                            count.prims(1 << k, 1);
                            let prim = self.prims[r as usize];
                            geometry.intersect(prim, &lane, t_max[k]).is_some()
                        });
                        if hit {
                            blocked |= 1 << k;
                        }
                    });
                    return;
                }
                for &r in self.cell_refs(cell) {
                    let open = lanes & !blocked;
                    if open == 0 {
                        break;
                    }
                    count.prims(open, 1);
                    let prim = self.prims[r as usize];
                    let hits =
                        geometry.intersect_packet(prim, query, F32xP::from_array(*t_max), open);
                    blocked |= hits.hit.bitmask() & open;
                }
            });
            for (k, walk) in walks.iter_mut().enumerate() {
                self.step(walk, blocked.has(k), &mut || count.cell(1 << k));
            }
        }
    }
}

impl Grid {
    /// The 3D-DDA: calls `visit` with each cell's objects, the distance at which the ray
    /// leaves that cell and `count`, in order along the ray, while `visit` says to
    /// continue and the ray is within `(query.t_min, t_max)` (which `visit` may shrink).
    /// Counts the grid's box and each cell entered.
    fn walk<C: Count>(
        &self,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
        mut visit: impl FnMut(&[u32], f32, &mut C) -> Walk,
    ) {
        let (ray, inv_dir, t_min) = (&query.ray, query.inv_dir, query.t_min);
        if !self.refs.is_empty() {
            count.boxes(1);
        }
        let Some(mut dda) = Dda::start(self, ray, inv_dir, t_min, t_max) else {
            return;
        };
        loop {
            count.cell();
            let cell_refs = self.cell_refs(dda.cell);
            if !cell_refs.is_empty() {
                count.leaf();
                match visit(cell_refs, dda.t_exit(), count) {
                    Walk::Stop => return,
                    Walk::Continue(limit) => dda.t_end = dda.t_end.min(limit),
                }
            }
            if !dda.advance(self) {
                return;
            }
        }
    }

    /// The walks of the active lanes of `packet` within `(t_min, t_max[k])`, each in its
    /// first cell with objects (`None` for the others, and where there is no such cell),
    /// counting each lane's box test and the cells it enters.
    fn start_walks<L: CountLanes<C>, C>(
        &self,
        packet: &RayPacket,
        inv_dir: &[Vec3; PACKET],
        t_max: &[f32; PACKET],
        count: &mut L,
    ) -> [Option<Dda>; PACKET] {
        let (rays, t_min) = (packet.rays, packet.t_min);
        if !self.refs.is_empty() {
            count.boxes(packet.active, 1);
        }
        std::array::from_fn(|k| {
            packet
                .active
                .has(k)
                .then(|| Dda::start(self, &rays[k], inv_dir[k], t_min, t_max[k]))
                .flatten()
                .and_then(|mut dda| {
                    let mut cell = || count.cell(1 << k);
                    cell();
                    self.skip_empty(&mut dda, &mut cell).then_some(dda)
                })
        })
    }

    /// Moves `walk` (in place: a walk is some 160 bytes) past its cell to the next cell
    /// with objects, calling `cell` for each cell it enters; ends it (`None`) when `stop`
    /// says so or the walk ends.
    fn step(&self, walk: &mut Option<Dda>, stop: bool, cell: &mut impl FnMut()) {
        if let Some(dda) = walk {
            if stop || !self.advance(dda, cell) || !self.skip_empty(dda, cell) {
                *walk = None;
            }
        }
    }

    /// [`Dda::advance`], calling `cell` when it enters a cell.
    #[inline]
    fn advance(&self, dda: &mut Dda, cell: &mut impl FnMut()) -> bool {
        let entered = dda.advance(self);
        if entered {
            cell();
        }
        entered
    }

    /// Walks `dda` on through empty cells, calling `cell` for each cell it enters;
    /// `false` when the walk ends before a cell with objects.
    fn skip_empty(&self, dda: &mut Dda, cell: &mut impl FnMut()) -> bool {
        while self.cell_refs(dda.cell).is_empty() {
            if !self.advance(dda, cell) {
                return false;
            }
        }
        true
    }

    /// The objects of cell `cell`, as indices into `prims`.
    fn cell_refs(&self, cell: IVec3) -> &[u32] {
        let c = self.cell_index(cell.as_uvec3());
        &self.refs[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    pub fn stats(&self) -> Vec<String> {
        let cells = self.cell_start.len() - 1;
        let counts = self.cell_start.windows(2).map(|w| w[1] - w[0]);
        let empty = counts.clone().filter(|&n| n == 0).count();
        let max = counts.max().unwrap_or(0);
        let memory = 4 * (self.cell_start.len() + self.refs.len() + self.prims.len());
        vec![
            format!(
                "grid resolution: {} x {} x {} (m = {})",
                self.resolution.x, self.resolution.y, self.resolution.z, self.density
            ),
            format!("objects: {}", self.prims.len()),
            format!(
                "cells: {cells}, empty: {empty} ({:.1}%)",
                100.0 * empty as f64 / cells.max(1) as f64
            ),
            format!(
                "references: {} ({:.2} per object), per non-empty cell: {:.2} mean, {max} max",
                self.refs.len(),
                self.refs.len() as f64 / self.prims.len().max(1) as f64,
                self.refs.len() as f64 / (cells - empty).max(1) as f64
            ),
            format!("memory: {:.2} MiB", memory as f64 / (1 << 20) as f64),
        ]
    }
}

/// One ray's 3D-DDA walk through the cells (Amanatides and Woo), made robust to the
/// rounding of its plane crossings. A crossing distance `(plane - origin) * inv_dir` is
/// off by up to `GAMMA_3` of itself, so along each axis the ray may be in a slab of cells
/// from its computed entry less the allowance to its exit plus it. (A ray from 1e9 away,
/// where floats are 64 apart, may cross two planes 50 units apart in either order: fuzz
/// finding crash-b88a; and the point where it enters a small grid may be computed in
/// another cell altogether.) The walk sweeps the distance along the ray and keeps, per
/// axis, the range of slabs the ray may be in (`first..=last`, in the order the ray goes);
/// when a slab joins a range, the cells it adds, that slab against the other axes'
/// ranges, are visited. The ranges allow too for the walk's planes (`min + i *
/// cell_size`) lying a few roundings of the grid's coordinates from the boundaries that
/// `cell_of` placed the objects by (`Grid::plane_error`: 64 units in a grid 1e9 wide,
/// fuzz finding crash-fb93). Where rounding is far below the cells' size, each range
/// holds one slab, or two near a plane, and the walk is the classic one plus the cells
/// beside an edge that it passes within rounding of.
#[derive(Clone, Copy, Debug)]
struct Dda {
    /// The cell being visited.
    cell: IVec3,
    /// Per axis, the direction the slabs go in (0 where the ray runs along the axis).
    step: [i32; 3],
    /// Per axis, the grid's last slab in that direction.
    end: [i32; 3],
    origin: [f32; 3],
    inv_dir: [f32; 3],
    /// Per axis, how much later or earlier than computed the ray may cross a boundary
    /// of `cell_of` because the plane is not quite there (`plane_error * |inv_dir|`,
    /// finite; zero along an axis the ray creeps along, whose crossings are not timed).
    slack: [f32; 3],
    /// Per axis, the first and the last slab the ray may be in.
    first: [i32; 3],
    last: [i32; 3],
    /// Per axis, where the ray crosses the plane after `last` (infinite where there is
    /// none), where the slab after `last` may start (that crossing less the allowance),
    /// and where `first` may end if another follows it (infinite otherwise; the largest
    /// float along an axis the ray creeps along, whose crossings cannot be timed).
    t_plane: [f32; 3],
    t_join: [f32; 3],
    t_drop: [f32; 3],
    /// The cells being visited, `cell` among them: a box of cells from one corner to the
    /// other, in the order the ray goes, visited axis by axis.
    batch: Option<([i32; 3], [i32; 3])>,
    /// The distance from which the batch's cells may hold the ray.
    t_joined: f32,
    /// The walk ends past this distance.
    t_end: f32,
}

/// The cell after `cell` in the box from `from` to `to` (its corners in the order of
/// `step`), axis by axis; `None` after the last.
fn next_in_box(cell: IVec3, from: [i32; 3], to: [i32; 3], step: [i32; 3]) -> Option<IVec3> {
    let mut cell = cell.to_array();
    for k in 0..3 {
        if cell[k] != to[k] {
            cell[k] += step[k];
            return Some(IVec3::from_array(cell));
        }
        cell[k] = from[k];
    }
    None
}

/// The earliest distance within rounding of the computed `t`, of either sign (both
/// products taken, so that the choice is a blend rather than a branch).
fn lower(t: f32) -> f32 {
    let (shrunk, grown) = (widen_entry(t), widen_exit(t));
    if t >= 0.0 {
        shrunk
    } else {
        grown
    }
}

/// The latest distance within rounding of the computed `t`, of either sign.
fn upper(t: f32) -> f32 {
    let (shrunk, grown) = (widen_entry(t), widen_exit(t));
    if t >= 0.0 {
        grown
    } else {
        shrunk
    }
}

impl Dda {
    /// The walk of `ray` within `(t_min, t_max)`, at the first cell where it may enter
    /// the grid (or start inside it); `None` when it misses the grid.
    fn start(grid: &Grid, ray: &Ray, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<Dda> {
        if grid.refs.is_empty() {
            return None;
        }
        let bounds = BoxRay::new(ray.origin, inv_dir);
        let (entry, exit) = bounds.interval(grid.bounds.min, grid.bounds.max, t_min, t_max)?;
        let t_enter = t_min.max(widen_entry(entry));
        // The exit is widened already; the walk needs nothing beyond the ray's end.
        let t_leave = t_max.min(exit);
        // A first guess, which the ranges below correct: the cell of the entry point.
        let guess = grid.cell_of(ray.at(t_enter)).as_ivec3().to_array();
        let walks = |k: usize| ray.dir[k] != 0.0 && inv_dir[k].is_finite();
        // The planes' error as a distance along the ray. Along an axis the ray moves along
        // so slowly (a direction of 1e-38) that it overflows, the ray creeps: no crossing
        // of its planes can be timed.
        let slack = |k: usize| grid.plane_error[k] * inv_dir[k].abs();
        let creeps = |k: usize| walks(k) && !slack(k).is_finite();
        let timed = |k: usize| walks(k) && !creeps(k);
        let mut dda = Dda {
            cell: IVec3::from_array(guess),
            step: [0, 1, 2].map(|k| match walks(k) {
                true => ray.dir[k].signum() as i32,
                false => 0,
            }),
            end: [0, 1, 2].map(|k| match ray.dir[k] > 0.0 {
                true => grid.resolution.as_ref()[k] as i32 - 1,
                false => 0,
            }),
            origin: ray.origin.to_array(),
            inv_dir: inv_dir.to_array(),
            slack: [0, 1, 2].map(|k| match timed(k) {
                true => slack(k),
                false => 0.0,
            }),
            first: guess,
            last: guess,
            t_plane: [f32::INFINITY; 3],
            t_join: [f32::INFINITY; 3],
            t_drop: [f32::INFINITY; 3],
            batch: None,
            t_joined: t_enter,
            t_end: t_leave,
        };
        for k in (0..3).filter(|&k| timed(k)) {
            // The slabs the ray may be in at `t_enter`: from the first whose exit may
            // come after it to the last whose entry may come before it.
            let step = dda.step[k];
            let exit = |i: i32| dda.crossing_after(grid, k, i);
            let mut a = guess[k];
            while grid.holds(k, a - step) && dda.late(k, exit(a - step)) >= t_enter {
                a -= step;
            }
            let mut exit_a = exit(a);
            while dda.late(k, exit_a) < t_enter {
                a += step;
                exit_a = exit(a);
            }
            let (mut b, mut exit_b) = (a, exit_a);
            while dda.early(k, exit_b) <= t_enter {
                b += step;
                exit_b = exit(b);
            }
            (dda.first[k], dda.last[k]) = (a, b);
            (dda.t_plane[k], dda.t_join[k]) = (exit_b, dda.early(k, exit_b));
            if a != b {
                dda.t_drop[k] = dda.late(k, exit_a);
            }
        }
        for k in (0..3).filter(|&k| creeps(k)) {
            // The slabs of every point the ray passes, with the planes' error to spare,
            // all visited at every step, none joined or dropped (fuzz finding crash-99d9).
            let at = |t: f32| ray.origin[k] + ray.dir[k] * t;
            let (near, far) = (at(t_enter), at(t_leave));
            let slab = |x: f32| {
                let mut point = ray.origin;
                point[k] = x;
                grid.cell_of(point).as_ivec3()[k]
            };
            let error = grid.plane_error[k];
            let (low, high) = (slab(near.min(far) - error), slab(near.max(far) + error));
            (dda.first[k], dda.last[k]) = match dda.step[k] > 0 {
                true => (low, high),
                false => (high, low),
            };
            if low != high {
                dda.t_drop[k] = f32::MAX;
            }
        }
        dda.cell = IVec3::from_array(dda.first);
        dda.batch = (dda.first != dda.last).then_some((dda.first, dda.last));
        Some(dda)
    }

    /// Where the ray crosses the plane by which it leaves slab `i` along axis `k` for the
    /// next slab; infinite where the grid ends there.
    fn crossing_after(&self, grid: &Grid, k: usize, i: i32) -> f32 {
        if i == self.end[k] {
            return f32::INFINITY;
        }
        let plane_index = i + (self.step[k] > 0) as i32;
        let plane = grid.bounds.min.as_ref()[k] + plane_index as f32 * grid.cell_size.as_ref()[k];
        (plane - self.origin[k]) * self.inv_dir[k]
    }

    /// The earliest distance at which the ray may cross the boundary along axis `k` whose
    /// plane it crosses at the computed `t` (infinite for no plane).
    fn early(&self, k: usize, t: f32) -> f32 {
        lower(t) - self.slack[k]
    }

    /// The latest distance at which the ray may cross that boundary.
    fn late(&self, k: usize, t: f32) -> f32 {
        upper(t) + self.slack[k]
    }

    /// `t_plane` and `t_join` of axis `k`, for the plane after its `last` slab.
    fn next_plane(&mut self, grid: &Grid, k: usize) {
        self.t_plane[k] = self.crossing_after(grid, k, self.last[k]);
        self.t_join[k] = self.early(k, self.t_plane[k]);
    }

    /// Drops the first slab of axis `k`'s range.
    fn drop_first(&mut self, grid: &Grid, k: usize) {
        self.first[k] += self.step[k];
        self.t_drop[k] = match self.first[k] != self.last[k] {
            true => self.late(k, self.crossing_after(grid, k, self.first[k])),
            false => f32::INFINITY,
        };
    }

    /// From where the cells not yet visited may hold the ray: the rest of the batch, or
    /// the next slab to join.
    fn t_exit(&self) -> f32 {
        match self.batch {
            Some((from, to)) if next_in_box(self.cell, from, to, self.step).is_some() => {
                self.t_joined
            }
            _ => min3(self.t_join),
        }
    }

    /// Moves to the next cell to visit; `false` when the walk is over (no slab may join
    /// before `t_end`).
    #[inline]
    fn advance(&mut self, grid: &Grid) -> bool {
        if self.batch.is_some() || self.first != self.last {
            return self.advance_spread(grid);
        }
        // Every range holds one slab (the common case): the classic step to the one cell
        // of the slab that joins next.
        let k = argmin(self.t_join);
        let join = self.t_join[k];
        if !self.joins_in_time(join) {
            return false;
        }
        self.join_next(grid, k, join);
        self.cell = IVec3::from_array(self.last);
        true
    }

    /// [`Dda::advance`] where a batch of cells is being visited or a range holds several
    /// slabs.
    #[inline(never)]
    fn advance_spread(&mut self, grid: &Grid) -> bool {
        if let Some((from, to)) = self.batch {
            if let Some(next) = next_in_box(self.cell, from, to, self.step) {
                self.cell = next;
                return true;
            }
            self.batch = None;
        }
        loop {
            let k = argmin(self.t_join);
            let (join, drop) = (self.t_join[k], min3(self.t_drop));
            if drop < join {
                // A slab the ray has surely left: fewer cells for the slabs to come.
                self.drop_first(grid, argmin(self.t_drop));
                continue;
            }
            if !self.joins_in_time(join) {
                return false;
            }
            self.join_next(grid, k, join);
            if drop == f32::INFINITY {
                // Every range held one slab: the one cell of the slab that joined.
                self.cell = IVec3::from_array(self.last);
                return true;
            }
            let (mut from, mut to) = (self.first, self.last);
            (from[k], to[k]) = (self.last[k], self.last[k]);
            self.cell = IVec3::from_array(from);
            self.batch = (from != to).then_some((from, to));
            return true;
        }
    }

    /// Whether a slab joining at `join` may still hold the ray before the walk ends.
    fn joins_in_time(&self, join: f32) -> bool {
        join < f32::INFINITY && join <= widen_exit(self.t_end)
    }

    /// Adds the next slab of axis `k` to its range, the ray crossing into it from `join`.
    fn join_next(&mut self, grid: &Grid, k: usize, join: f32) {
        let crossed = self.t_plane[k];
        let single = self.first[k] == self.last[k];
        self.last[k] += self.step[k];
        self.next_plane(grid, k);
        self.t_joined = join;
        if single {
            // The slab left may last until the plane just crossed, plus rounding, but
            // adds cells only if another slab joins meanwhile: where none does, it
            // drops at once (the common case, one event a step).
            let left = self.late(k, crossed);
            if left < min3(self.t_join) {
                self.first[k] = self.last[k];
            } else {
                self.t_drop[k] = left;
            }
        }
    }
}

/// The smallest of `t`'s three.
fn min3(t: [f32; 3]) -> f32 {
    t[0].min(t[1]).min(t[2])
}

/// The axis of `t`'s smallest component, the first of equals.
fn argmin(t: [f32; 3]) -> usize {
    if t[0] <= t[1] && t[0] <= t[2] {
        0
    } else if t[1] <= t[2] {
        1
    } else {
        2
    }
}

/// Lanes sharing a cell test its objects one ray at a time when there are this few: the
/// packet kernels pay off only for more.
const SINGLE_RAY_LANES: u32 = 2;

/// The lanes whose walk goes on and satisfies `keep`, as a bit mask.
fn lanes_of(walks: &[Option<Dda>; PACKET], keep: impl Fn(&Dda) -> bool) -> LaneBits {
    lane_mask(|k| walks[k].as_ref().is_some_and(&keep))
}

/// Calls `visit` once per distinct cell among the walks of `lanes`, with the lanes that
/// stand in it.
fn for_cell_groups(
    walks: &[Option<Dda>; PACKET],
    lanes: LaneBits,
    mut visit: impl FnMut(IVec3, LaneBits),
) {
    let mut left = lanes;
    while left != 0 {
        let first = walks[left.trailing_zeros() as usize]
            .expect("a walking lane")
            .cell;
        let group = left & lanes_of(walks, |dda| dda.cell == first);
        visit(first, group);
        left &= !group;
    }
}

/// What the visitor of [`Grid::walk`] wants next.
enum Walk {
    Stop,
    /// Go on, but not beyond this distance.
    Continue(f32),
}

/// Cells per axis: `floor(m w_i (N / V)^(1/3)) + 1`, at most [`MAX_AXIS_CELLS`].
pub fn cells_per_axis(extent: Vec3, objects: usize, density: f32) -> UVec3 {
    let volume = extent.x as f64 * extent.y as f64 * extent.z as f64;
    let s = (objects as f64 / volume).cbrt();
    UVec3::from_array(extent.to_array().map(|w| {
        let n = (density as f64 * w as f64 * s).floor() + 1.0;
        if n.is_nan() {
            1
        } else {
            n.min(MAX_AXIS_CELLS as f64) as u32
        }
    }))
}

thread_local! {
    /// Per-thread mailboxes: `stamps[i]` is the last query that tested object `i`.
    static MAILBOX: RefCell<(Vec<u32>, u32)> = const { RefCell::new((Vec::new(), 0)) };
}

/// One query's view of the thread's mailbox; without mailboxing, every visit is a first.
struct Mailbox<'a> {
    stamps: Option<&'a mut [u32]>,
    stamp: u32,
}

impl Mailbox<'_> {
    /// Runs one query `f` with a fresh stamp in this thread's mailbox (when `enabled`).
    fn with<R>(enabled: bool, objects: usize, f: impl FnOnce(&mut Mailbox) -> R) -> R {
        if !enabled {
            return f(&mut Mailbox {
                stamps: None,
                stamp: 0,
            });
        }
        MAILBOX.with_borrow_mut(|(stamps, last)| {
            if stamps.len() < objects {
                stamps.resize(objects, 0);
            }
            *last = last.wrapping_add(1);
            if *last == 0 {
                // After 2^32 queries the stamps wrap: start again from clean boxes.
                stamps.fill(0);
                *last = 1;
            }
            f(&mut Mailbox {
                stamp: *last,
                stamps: Some(&mut stamps[..]),
            })
        })
    }

    /// Whether object `i` is met for the first time in this query.
    fn first_visit(&mut self, i: u32) -> bool {
        match &mut self.stamps {
            None => true,
            Some(stamps) => {
                let seen = stamps[i as usize] == self.stamp;
                stamps[i as usize] = self.stamp;
                !seen
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_follow_the_report_formula() {
        // 1000 objects in a 10 x 10 x 10 box: s = 1, so floor(2 * 10) + 1 = 21 cells.
        assert_eq!(
            cells_per_axis(Vec3::splat(10.0), 1000, 2.0),
            UVec3::splat(21)
        );
        // The same volume stretched: s stays 1.
        assert_eq!(
            cells_per_axis(Vec3::new(10.0, 5.0, 20.0), 1000, 2.0),
            UVec3::new(21, 11, 41)
        );
        // A flat box would ask for unbounded cells; each axis is capped.
        let flat = cells_per_axis(Vec3::new(10.0, 0.0, 10.0), 100, 2.0);
        assert_eq!(flat, UVec3::new(MAX_AXIS_CELLS, 1, MAX_AXIS_CELLS));
    }
}
