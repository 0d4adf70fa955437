//! The course report's uniform grid (P3F.md section 9): `floor(m w_i s) + 1` cells along
//! each axis with `s = (N / V)^(1/3)`, every object listed in each cell its box overlaps,
//! and the 3D-DDA traversal of Amanatides and Woo.
//!
//! The report accepts a hit only when it lies before the current cell's exit and finds it
//! again in a later cell otherwise. Here a hit beyond the exit is kept as a candidate and
//! the walk stops once a cell's exit passes it: the same answer, and it lets mailboxing
//! (`--mailbox`) test an object that spans several cells only once per ray.

use std::cell::RefCell;

use glam::{IVec3, UVec3, Vec3};

use super::bounds::prim_bounds;
use super::hit::{for_lanes, ClosestHit};
use crate::intersect::{widen_entry, Aabb, BoxRay};
use crate::prim::{PrimId, PrimKind};
use crate::ray::{lane_mask, Hit, Ray, RayPacket};
use crate::scene::Geometry;

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
    /// Cell `c`'s objects are `refs[cell_start[c]..cell_start[c + 1]]` (cells x fastest).
    cell_start: Vec<u32>,
    /// Indices into `prims`.
    refs: Vec<u32>,
    prims: Vec<PrimId>,
    density: f32,
    mailbox: bool,
}

impl Grid {
    /// The report's grid over the bounded primitives of `geometry`, `density` its `m`,
    /// moving spheres bounded over `shutter`; with `mailbox`, an object spanning several
    /// cells is tested once per ray.
    pub fn build(geometry: &Geometry, density: f32, mailbox: bool, shutter: [f32; 2]) -> Grid {
        let mut prims = Vec::with_capacity(geometry.bounded_count());
        let mut boxes = Vec::with_capacity(geometry.bounded_count());
        for kind in PrimKind::BOUNDED {
            for prim in geometry.ids(kind) {
                let b = prim_bounds(geometry, prim, shutter);
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

    pub fn closest(
        &self,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        closest: &mut ClosestHit,
    ) {
        Mailbox::with(self.mailbox, self.prims.len(), |mailbox| {
            self.walk(ray, inv_dir, t_min, closest.limit(), |cell_refs, t_exit| {
                for &r in cell_refs {
                    if mailbox.first_visit(r) {
                        closest.test(geometry, self.prims[r as usize], ray, inv_dir, t_min);
                    }
                }
                // Stop once the closest hit lies inside the cells walked so far.
                if closest.limit() < t_exit {
                    return Walk::Stop;
                }
                Walk::Continue(closest.limit())
            })
        });
    }

    pub fn occluded(
        &self,
        geometry: &Geometry,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        let mut blocked = false;
        Mailbox::with(self.mailbox, self.prims.len(), |mailbox| {
            self.walk(ray, inv_dir, t_min, t_max, |cell_refs, _| {
                blocked = cell_refs.iter().any(|&r| {
                    mailbox.first_visit(r)
                        && geometry
                            .intersect(self.prims[r as usize], ray, inv_dir, t_min, t_max)
                            .is_some()
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

    /// The 3D-DDA: calls `visit` with each cell's objects and the distance at which the
    /// ray leaves that cell, in order along the ray, while `visit` says to continue and
    /// the ray is within `(t_min, t_max)` (which `visit` may shrink).
    fn walk(
        &self,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
        mut visit: impl FnMut(&[u32], f32) -> Walk,
    ) {
        let Some(mut dda) = Dda::start(self, ray, inv_dir, t_min, t_max) else {
            return;
        };
        loop {
            let cell_refs = self.cell_refs(dda.cell);
            if !cell_refs.is_empty() {
                match visit(cell_refs, dda.t_exit()) {
                    Walk::Stop => return,
                    Walk::Continue(limit) => dda.t_end = dda.t_end.min(limit),
                }
            }
            if !dda.advance(self) {
                return;
            }
        }
    }

    /// The closest hits of the active lanes of `packet`, as [`Grid::closest`] finds
    /// each. Each lane walks its own 3D-DDA; at every step the lanes that stand in the
    /// same cell test its objects together, by the primitives' packet kernels (so a
    /// coherent packet tests each object once for all its rays). Mailboxing plays no
    /// part here: it changes how often an object is tested, never the answer.
    pub fn closest_packet(
        &self,
        geometry: &Geometry,
        packet: &RayPacket,
        closest: &mut [ClosestHit; 8],
    ) {
        let (rays, t_min) = (packet.rays, packet.t_min);
        let packet_inv_dir = packet.inv_dir_lanes();
        let limits = closest.each_ref().map(|c| c.limit());
        let mut walks = self.start_walks(packet, &packet_inv_dir, &limits);
        loop {
            let walking = lanes_of(&walks, |_| true);
            if walking == 0 {
                return;
            }
            for_cell_groups(&walks, walking, |cell, lanes| {
                if lanes.count_ones() <= SINGLE_RAY_LANES {
                    for_lanes(lanes, |k| {
                        let ray = &rays[k];
                        for &r in self.cell_refs(cell) {
                            let prim = self.prims[r as usize];
                            closest[k].test(geometry, prim, ray, packet_inv_dir[k], t_min);
                        }
                    });
                    return;
                }
                // Each lane's bound changes only when it takes a hit.
                let mut t_max = closest.each_ref().map(|c| c.bound());
                for &r in self.cell_refs(cell) {
                    let prim = self.prims[r as usize];
                    let hits = geometry.intersect_packet(prim, packet, &t_max, lanes);
                    for (k, hit) in hits.into_iter().enumerate() {
                        if let Some(h) = hit {
                            let (t, u, v) = (h.t, h.u, h.v);
                            closest[k].offer(Hit { t, prim, u, v });
                            t_max[k] = closest[k].bound();
                        }
                    }
                }
            });
            for (k, walk) in walks.iter_mut().enumerate() {
                let Some(dda) = walk else {
                    continue;
                };
                // As `closest`: stop once the closest hit lies in the cells walked.
                let limit = closest[k].limit();
                dda.t_end = dda.t_end.min(limit);
                *walk = self.step(*dda, limit < dda.t_exit());
            }
        }
    }

    /// The active lanes of `packet` whose ray is blocked within its interval, walked as
    /// in [`Grid::closest_packet`].
    pub fn occluded_packet(&self, geometry: &Geometry, packet: &RayPacket) -> u8 {
        let (rays, t_min, t_max) = (packet.rays, packet.t_min, &packet.t_max);
        let packet_inv_dir = packet.inv_dir_lanes();
        let mut walks = self.start_walks(packet, &packet_inv_dir, t_max);
        let mut blocked = 0u8;
        loop {
            let walking = lanes_of(&walks, |_| true) & !blocked;
            if walking == 0 {
                return blocked;
            }
            for_cell_groups(&walks, walking, |cell, lanes| {
                if lanes.count_ones() <= SINGLE_RAY_LANES {
                    for_lanes(lanes, |k| {
                        let ray = &rays[k];
                        let hit = self.cell_refs(cell).iter().any(|&r| {
                            let prim = self.prims[r as usize];
                            geometry
                                .intersect(prim, ray, packet_inv_dir[k], t_min, t_max[k])
                                .is_some()
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
                    let prim = self.prims[r as usize];
                    let hits = geometry.intersect_packet(prim, packet, t_max, open);
                    for (k, hit) in hits.iter().enumerate() {
                        if hit.is_some() {
                            blocked |= 1 << k;
                        }
                    }
                }
            });
            for (k, walk) in walks.iter_mut().enumerate() {
                if let Some(dda) = walk {
                    *walk = self.step(*dda, blocked & (1 << k) != 0);
                }
            }
        }
    }

    /// The walks of the active lanes of `packet` within `(t_min, t_max[k])`, each in its
    /// first cell with objects (`None` for the others, and where there is no such cell).
    fn start_walks(
        &self,
        packet: &RayPacket,
        inv_dir: &[Vec3; 8],
        t_max: &[f32; 8],
    ) -> [Option<Dda>; 8] {
        let (rays, t_min) = (packet.rays, packet.t_min);
        std::array::from_fn(|k| {
            (packet.active & (1 << k) != 0)
                .then(|| Dda::start(self, &rays[k], inv_dir[k], t_min, t_max[k]))
                .flatten()
                .and_then(|dda| self.skip_empty(dda))
        })
    }

    /// The walk after `dda`'s cell, in the next cell with objects; `None` when `stop`
    /// says so or the walk ends.
    fn step(&self, mut dda: Dda, stop: bool) -> Option<Dda> {
        if stop || !dda.advance(self) {
            return None;
        }
        self.skip_empty(dda)
    }

    /// Walks `dda` on through empty cells; `None` when the walk ends before a cell with
    /// objects.
    fn skip_empty(&self, mut dda: Dda) -> Option<Dda> {
        while self.cell_refs(dda.cell).is_empty() {
            if !dda.advance(self) {
                return None;
            }
        }
        Some(dda)
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

/// One ray's 3D-DDA walk through the cells (Amanatides and Woo).
#[derive(Clone, Copy, Debug)]
struct Dda {
    cell: IVec3,
    step: IVec3,
    /// Distance to the next cell boundary along each axis, and between boundaries.
    t_next: Vec3,
    t_delta: Vec3,
    /// The walk ends past this distance.
    t_end: f32,
}

impl Dda {
    /// The walk of `ray` within `(t_min, t_max)`, in the cell where it enters the grid
    /// (or starts inside it); `None` when it misses the grid.
    fn start(grid: &Grid, ray: &Ray, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<Dda> {
        if grid.refs.is_empty() {
            return None;
        }
        let bounds = BoxRay::new(ray.origin, inv_dir);
        let (entry, exit) = bounds.interval(grid.bounds.min, grid.bounds.max, t_min, t_max)?;
        // The start cell is the one holding the entry point, so the entry must not be
        // late: a ray entering across the corner of a cell would skip it. Stepped back by
        // the allowance, the walk may start a cell early, which only costs a visit.
        let t_enter = t_min.max(widen_entry(entry));
        // The exit is widened already; the walk needs nothing beyond the ray's end.
        let t_leave = t_max.min(exit);
        let cell = grid.cell_of(ray.at(t_enter)).as_ivec3();
        let mut t_next = Vec3::INFINITY;
        let mut t_delta = Vec3::INFINITY;
        for k in 0..3 {
            if ray.dir[k] != 0.0 && inv_dir[k].is_finite() {
                let side = if ray.dir[k] > 0.0 { 1 } else { 0 };
                let boundary = grid.bounds.min[k] + (cell[k] + side) as f32 * grid.cell_size[k];
                t_next[k] = (boundary - ray.origin[k]) * inv_dir[k];
                t_delta[k] = grid.cell_size[k] * inv_dir[k].abs();
            }
        }
        Some(Dda {
            cell,
            step: ray.dir.signum().as_ivec3(),
            t_next,
            t_delta,
            t_end: t_leave,
        })
    }

    /// Where the ray leaves the current cell.
    fn t_exit(&self) -> f32 {
        self.t_next.min_element()
    }

    /// Steps into the next cell; `false` when the walk is over (past `t_end`, or out of
    /// the grid).
    fn advance(&mut self, grid: &Grid) -> bool {
        let t_next = self.t_next;
        if !(t_next.min_element() <= self.t_end) {
            return false;
        }
        let k = if t_next.x <= t_next.y && t_next.x <= t_next.z {
            0
        } else if t_next.y <= t_next.z {
            1
        } else {
            2
        };
        self.cell[k] += self.step[k];
        if self.cell[k] < 0 || self.cell[k] >= grid.resolution.as_ivec3()[k] {
            return false;
        }
        self.t_next[k] += self.t_delta[k];
        true
    }
}

/// Lanes sharing a cell test its objects one ray at a time when there are this few: the
/// packet kernels pay off only for more.
const SINGLE_RAY_LANES: u32 = 2;

/// The lanes whose walk goes on and satisfies `keep`, as a bit mask.
fn lanes_of(walks: &[Option<Dda>; 8], keep: impl Fn(&Dda) -> bool) -> u8 {
    lane_mask(|k| walks[k].as_ref().is_some_and(&keep))
}

/// Calls `visit` once per distinct cell among the walks of `lanes`, with the lanes that
/// stand in it.
fn for_cell_groups(walks: &[Option<Dda>; 8], lanes: u8, mut visit: impl FnMut(IVec3, u8)) {
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
