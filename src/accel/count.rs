//! What a walk counts of its work: nodes visited, child boxes tested, leaves entered,
//! primitives tested and grid cells visited, per ray ([`Tally`]) or per lane of a packet
//! ([`LaneTallies`]). The statistics of `bench --stats`, `render --stats` and the cost
//! images of `render --cost` come from here.
//!
//! **Free when off.** Every walk is generic over its [`Count`]: [`NoCount`] is a type of
//! no size whose methods do nothing, so the walks the renderer and `bench` run without
//! statistics compile to the code they had before counting existed, with no branch in
//! their loops; [`Tally`] is a second instantiation of the same walks, never a flag
//! tested inside them. Counting never changes what a walk finds (`tests/integration/
//! accel.rs`), and the counts are pinned to what can be known without them
//! (`tests/integration/counts.rs`).
//!
//! **What is counted.** A single ray's walk counts, at each interior node it visits, the
//! node and the child boxes it tests against the ray (all the node's children); at each
//! leaf, the leaf and its primitives. A packet counts in every lane that takes part: at a
//! node, the lanes it brings there (its range cull is the visit, its candidates the boxes
//! tested against its rays); at a leaf, the lanes tested and the primitives each meets;
//! lanes finished one ray at a time count as single rays. The grid counts each cell its
//! walk enters, the box of the grid itself, a cell whose objects it tests as a leaf, and
//! each object tested (once per ray with mailboxing). Planes, tested beside every
//! structure, count as primitives tested.
//!
//! **Lane shares.** A visit by `n` lanes of a packet adds `SHARE / n` to each of them
//! ([`Tally::node_share`], [`Tally::leaf_share`]; a single ray adds `SHARE`), so that the
//! shares of a set's rays add up to its visits: [`SHARE`] divides by every lane count of a
//! packet, and the sums stay whole. The lanes active at a visit, on average, are then the
//! nodes counted over the visits.
//!
//! **By kind.** The renderer sums counts by what their rays are for ([`RayKind`]) in a
//! [`Work`], and the rays it traces in the same shape ([`RayCounts`]).

use std::ops::AddAssign;

use crate::scene::AccelKind;
use crate::simd::{for_lanes, LaneBits, PACKET};

/// The share of a visit made by one ray alone, in [`Tally::node_share`] and
/// [`Tally::leaf_share`]: divisible by every lane count from 1 to [`PACKET`] (840 for 8
/// lanes, 720720 for 16).
pub const SHARE: u64 = if PACKET > 8 { 720_720 } else { 840 };

/// How a walk counts: [`NoCount`] (nothing, the walks as they run) or [`Tally`] (one ray's
/// work). A packet's walk counts into [`Count::Lanes`], lane by lane.
pub trait Count: Copy + Default + std::fmt::Debug + Send + Sync + AddAssign {
    /// Whether anything is counted: callers skip the work of handing counts on without it.
    const ON: bool;
    /// A packet's counts, lane by lane.
    type Lanes: CountLanes<Self>;
    /// A ray asked of the tracer (traceable or not).
    fn ray(&mut self);
    /// An interior node visited.
    fn node(&mut self);
    /// `n` child boxes tested against the ray.
    fn boxes(&mut self, n: u32);
    /// A leaf entered (in the grid, a cell whose objects are tested).
    fn leaf(&mut self);
    /// `n` primitives tested.
    fn prims(&mut self, n: u32);
    /// A grid cell visited.
    fn cell(&mut self);
}

/// A packet's counts, lane by lane: the same events as [`Count`], each for the lanes
/// `lanes` that take part.
pub trait CountLanes<C>: Default {
    fn rays(&mut self, lanes: LaneBits);
    fn node(&mut self, lanes: LaneBits);
    fn boxes(&mut self, lanes: LaneBits, n: u32);
    fn leaf(&mut self, lanes: LaneBits);
    fn prims(&mut self, lanes: LaneBits, n: u32);
    fn cell(&mut self, lanes: LaneBits);
    /// Adds the counts of lane `k`'s walk made as a single ray.
    fn add_lane(&mut self, k: usize, count: &C);
    /// Lane `k`'s counts.
    fn lane(&self, k: usize) -> C;
}

/// Counts nothing: the walks as the renderer and `bench` run them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoCount;

impl Count for NoCount {
    const ON: bool = false;
    type Lanes = NoCount;
    #[inline(always)]
    fn ray(&mut self) {}
    #[inline(always)]
    fn node(&mut self) {}
    #[inline(always)]
    fn boxes(&mut self, _: u32) {}
    #[inline(always)]
    fn leaf(&mut self) {}
    #[inline(always)]
    fn prims(&mut self, _: u32) {}
    #[inline(always)]
    fn cell(&mut self) {}
}

impl CountLanes<NoCount> for NoCount {
    #[inline(always)]
    fn rays(&mut self, _: LaneBits) {}
    #[inline(always)]
    fn node(&mut self, _: LaneBits) {}
    #[inline(always)]
    fn boxes(&mut self, _: LaneBits, _: u32) {}
    #[inline(always)]
    fn leaf(&mut self, _: LaneBits) {}
    #[inline(always)]
    fn prims(&mut self, _: LaneBits, _: u32) {}
    #[inline(always)]
    fn cell(&mut self, _: LaneBits) {}
    #[inline(always)]
    fn add_lane(&mut self, _: usize, _: &NoCount) {}
    #[inline(always)]
    fn lane(&self, _: usize) -> NoCount {
        NoCount
    }
}

/// One ray's work (or, summed, a pixel's or a set's).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Rays asked of the tracer: one for a ray's own work.
    pub rays: u32,
    /// Interior nodes visited.
    pub nodes: u32,
    /// Child boxes tested against the ray (the grid: its own box).
    pub boxes: u32,
    /// Leaves entered (the grid: cells whose objects were tested).
    pub leaves: u32,
    /// Primitives tested, planes included.
    pub prims: u32,
    /// Grid cells visited.
    pub cells: u32,
    /// The ray's shares of the node visits it took part in, [`SHARE`] for a visit alone.
    pub node_share: u64,
    /// The ray's shares of the leaf tests it took part in.
    pub leaf_share: u64,
}

/// The counters a cost image can show, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Counter {
    Nodes,
    Boxes,
    Leaves,
    Prims,
    Cells,
}

impl Counter {
    pub const ALL: [Counter; 5] = [
        Counter::Nodes,
        Counter::Boxes,
        Counter::Leaves,
        Counter::Prims,
        Counter::Cells,
    ];

    /// Its name on the command line, in statistics and in cost images.
    pub fn name(self) -> &'static str {
        match self {
            Counter::Nodes => "nodes",
            Counter::Boxes => "boxes",
            Counter::Leaves => "leaves",
            Counter::Prims => "prims",
            Counter::Cells => "cells",
        }
    }

    /// What it counts, for help texts and legends.
    pub fn meaning(self) -> &'static str {
        match self {
            Counter::Nodes => "interior nodes visited",
            Counter::Boxes => "child boxes tested",
            Counter::Leaves => "leaves entered",
            Counter::Prims => "primitives tested",
            Counter::Cells => "grid cells visited",
        }
    }

    pub fn from_name(name: &str) -> Option<Counter> {
        Counter::ALL.into_iter().find(|c| c.name() == name)
    }
}

impl AccelKind {
    /// The counters its walks count, in [`Counter::ALL`]'s order: every other stays 0.
    pub fn counters(self) -> &'static [Counter] {
        match self {
            AccelKind::None => &[Counter::Prims],
            AccelKind::Grid => &[
                Counter::Boxes,
                Counter::Leaves,
                Counter::Prims,
                Counter::Cells,
            ],
            AccelKind::Bvh => &[
                Counter::Nodes,
                Counter::Boxes,
                Counter::Leaves,
                Counter::Prims,
            ],
        }
    }

    /// The counter of the step its walks are made of: a BVH's nodes, the grid's cells,
    /// brute force's primitives.
    pub fn step(self) -> Counter {
        match self {
            AccelKind::Bvh => Counter::Nodes,
            AccelKind::Grid => Counter::Cells,
            AccelKind::None => Counter::Prims,
        }
    }
}

impl Tally {
    /// The count of `counter`.
    pub fn get(&self, counter: Counter) -> u32 {
        match counter {
            Counter::Nodes => self.nodes,
            Counter::Boxes => self.boxes,
            Counter::Leaves => self.leaves,
            Counter::Prims => self.prims,
            Counter::Cells => self.cells,
        }
    }
}

impl Count for Tally {
    const ON: bool = true;
    type Lanes = LaneTallies;
    #[inline]
    fn ray(&mut self) {
        self.rays += 1;
    }
    #[inline]
    fn node(&mut self) {
        self.nodes += 1;
        self.node_share += SHARE;
    }
    #[inline]
    fn boxes(&mut self, n: u32) {
        self.boxes += n;
    }
    #[inline]
    fn leaf(&mut self) {
        self.leaves += 1;
        self.leaf_share += SHARE;
    }
    #[inline]
    fn prims(&mut self, n: u32) {
        self.prims += n;
    }
    #[inline]
    fn cell(&mut self) {
        self.cells += 1;
    }
}

impl AddAssign for Tally {
    #[inline]
    fn add_assign(&mut self, other: Tally) {
        self.rays += other.rays;
        self.nodes += other.nodes;
        self.boxes += other.boxes;
        self.leaves += other.leaves;
        self.prims += other.prims;
        self.cells += other.cells;
        self.node_share += other.node_share;
        self.leaf_share += other.leaf_share;
    }
}

impl AddAssign for NoCount {
    #[inline(always)]
    fn add_assign(&mut self, _: NoCount) {}
}

/// A packet's [`Tally`] per lane.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LaneTallies(pub [Tally; PACKET]);

impl LaneTallies {
    fn each(&mut self, lanes: LaneBits, mut count: impl FnMut(&mut Tally)) {
        for_lanes(lanes, |k| count(&mut self.0[k]));
    }
}

impl CountLanes<Tally> for LaneTallies {
    fn rays(&mut self, lanes: LaneBits) {
        self.each(lanes, |t| t.rays += 1);
    }
    fn node(&mut self, lanes: LaneBits) {
        let share = SHARE / u64::from(lanes.count_ones().max(1));
        self.each(lanes, |t| {
            t.nodes += 1;
            t.node_share += share;
        });
    }
    fn boxes(&mut self, lanes: LaneBits, n: u32) {
        self.each(lanes, |t| t.boxes += n);
    }
    fn leaf(&mut self, lanes: LaneBits) {
        let share = SHARE / u64::from(lanes.count_ones().max(1));
        self.each(lanes, |t| {
            t.leaves += 1;
            t.leaf_share += share;
        });
    }
    fn prims(&mut self, lanes: LaneBits, n: u32) {
        self.each(lanes, |t| t.prims += n);
    }
    fn cell(&mut self, lanes: LaneBits) {
        self.each(lanes, |t| t.cells += 1);
    }
    fn add_lane(&mut self, k: usize, count: &Tally) {
        self.0[k] += *count;
    }
    fn lane(&self, k: usize) -> Tally {
        self.0[k]
    }
}

/// What a traced ray is for, as the statistics count it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    Primary,
    Shadow,
    Reflection,
    Refraction,
}

/// A statistic of rays by kind ([`RayKind`]): with `C` a [`Count`], the traversal work of
/// a pixel's rays, of a ray and the rays it spawned, or of a render's; with `u64`, the
/// rays traced ([`RayCounts`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work<C> {
    pub primary: C,
    pub shadow: C,
    pub reflection: C,
    pub refraction: C,
}

/// The rays a render traced, by kind.
pub type RayCounts = Work<u64>;

impl<C: Copy + AddAssign> Work<C> {
    /// The statistic of the rays of the kind `kind`.
    #[inline]
    fn of_kind(&mut self, kind: RayKind) -> &mut C {
        match kind {
            RayKind::Primary => &mut self.primary,
            RayKind::Shadow => &mut self.shadow,
            RayKind::Reflection => &mut self.reflection,
            RayKind::Refraction => &mut self.refraction,
        }
    }

    /// Adds `count` to the kind `kind`'s statistic.
    #[inline]
    pub fn add(&mut self, kind: RayKind, count: C) {
        *self.of_kind(kind) += count;
    }

    pub fn merge(&mut self, other: &Work<C>) {
        self.primary += other.primary;
        self.shadow += other.shadow;
        self.reflection += other.reflection;
        self.refraction += other.refraction;
    }

    /// The work of the rays of `rays`: all of them, or the primary ones.
    pub fn of(&self, rays: CostRays) -> C {
        match rays {
            CostRays::All => self.total(),
            CostRays::Primary => self.primary,
        }
    }

    /// The work of each kind, then of all, with their names: `primary`, `shadow`,
    /// `reflection`, `refraction` and `all`.
    pub fn named(&self) -> [(&'static str, C); 5] {
        [
            ("primary", self.primary),
            ("shadow", self.shadow),
            ("reflection", self.reflection),
            ("refraction", self.refraction),
            ("all", self.total()),
        ]
    }

    /// The work of every kind together.
    pub fn total(&self) -> C {
        let mut total = self.primary;
        total += self.shadow;
        total += self.reflection;
        total += self.refraction;
        total
    }
}

/// Which rays a cost image (`render --cost`) counts: all that a pixel's samples trace,
/// or their primary rays alone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CostRays {
    #[default]
    All,
    Primary,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_of_a_packets_lanes_add_up_to_its_visits() {
        for lanes in 1..=LaneBits::MAX {
            let mut packet = LaneTallies::default();
            packet.node(lanes);
            packet.leaf(lanes);
            let nodes: u64 = packet.0.iter().map(|t| t.node_share).sum();
            let leaves: u64 = packet.0.iter().map(|t| t.leaf_share).sum();
            assert_eq!((nodes, leaves), (SHARE, SHARE), "lanes {lanes:b}");
            let visited: u32 = packet.0.iter().map(|t| t.nodes).sum();
            assert_eq!(visited, lanes.count_ones());
        }
    }

    #[test]
    fn a_structures_step_is_among_its_counters() {
        for kind in [AccelKind::None, AccelKind::Grid, AccelKind::Bvh] {
            assert!(kind.counters().contains(&kind.step()), "{kind:?}");
            let in_order: Vec<Counter> = (Counter::ALL.into_iter())
                .filter(|c| kind.counters().contains(c))
                .collect();
            assert_eq!(kind.counters(), in_order, "{kind:?}");
        }
    }

    #[test]
    fn counters_have_names_both_ways() {
        for c in Counter::ALL {
            assert_eq!(Counter::from_name(c.name()), Some(c));
        }
        assert_eq!(Counter::from_name("triangles"), None);
    }
}
