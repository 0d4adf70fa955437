//! Closest-hit and occlusion queries over a scene's geometry (P3F.md section 9).
//!
//! Every accelerator answers the queries of [`Structure`] and sits behind [`Accel`], so
//! the renderer does not care which one runs; [`Tracer::new`] builds it from
//! [`AccelOptions`], which also say how the primitives are tested (the profile's
//! [`IntersectOptions`], carried by every query).
//! Planes are unbounded and never go into a structure: [`Tracer`] tests them on their own
//! beside whatever the accelerator returns.
//!
//! All structures return exactly the hit of brute force: the smallest `t`, and at equal
//! `t` the smallest [`PrimId`] ([`ClosestHit`] keeps that rule), so
//! the images of every structure are the same byte for byte.
//!
//! [`Tracer`] answers a ray whose origin is not finite, or whose direction is zero or not
//! finite, with a miss before any structure sees it: the structures would disagree on it.
//! It takes one ray at a time or a [`RayPacket`]: the 8-wide BVH and the grid trace a
//! packet together, brute force and the binary BVH lane by lane ([`Structure`]'s
//! defaults), and every lane's answer is its single ray's.

pub mod bounds;
pub mod bvh2;
pub mod bvh8;
pub mod count;
pub mod grid;
mod hit;
pub mod interior;
mod none;
mod stack;
pub mod stream;
mod structure;

use std::cell::OnceCell;
use std::time::{Duration, Instant};

use crate::intersect::{
    beyond_lanes, holds_lanes8, intervals_lanes8, BoxPack8, IntersectOptions, PackLayout,
    PacketQuery, RayQuery, Rays8,
};
use crate::prim::{PrimId, PrimKind};
use crate::ray::{traceable_lanes, Hit, Ray, RayPacket};
pub use crate::scene::AccelKind;
use crate::scene::Geometry;
use crate::simd::{for_lanes, Bits, F32x8, F32xP, LaneBits, Mask8, Vec3x8, PACKET};
use bvh2::Bvh2;
pub use bvh2::BvhBuild;
use bvh8::Bvh8;
use count::{Count, CountLanes, NoCount};
use grid::Grid;
use hit::test_packet;
pub use hit::ClosestHit;
use none::BruteForce;
pub use structure::Structure;

/// The acceleration structure over a scene's bounded primitives: one variant per
/// traversal engine. Unboxed though the 8-wide tree is the largest variant (its packs of
/// both layouts): there is one per tracer, and every query reads the tree in place.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum Accel {
    /// Every ray is tested against every primitive: the reference the others are checked
    /// against.
    None,
    Grid(Grid),
    /// The binary BVH, traversed as built.
    Bvh2(Bvh2),
    /// The binary BVH collapsed to 8-wide nodes; packets traverse it together.
    Bvh8(Bvh8),
}

/// Children per node that BVH traversal sees: the binary tree as built, or the tree
/// collapsed to 8-wide nodes ([`Bvh8`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhWidth {
    Two,
    Eight,
}

/// The SAH tree is collapsed to 8-wide nodes; the report's BVH stays binary, as the
/// report traverses it.
fn default_width(build: BvhBuild) -> BvhWidth {
    match build {
        BvhBuild::Midpoint => BvhWidth::Two,
        BvhBuild::Sah => BvhWidth::Eight,
    }
}

/// `bvh midpoint` or `bvh sah`, with the width when it is not the build's default
/// (`bvh sah binary`, `bvh midpoint 8-wide`).
fn bvh_name(build: BvhBuild, width: BvhWidth) -> String {
    let name = match build {
        BvhBuild::Midpoint => "bvh midpoint",
        BvhBuild::Sah => "bvh sah",
    };
    match width {
        _ if width == default_width(build) => name.into(),
        BvhWidth::Two => format!("{name} binary"),
        BvhWidth::Eight => format!("{name} 8-wide"),
    }
}

/// How to build the structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelOptions {
    pub kind: AccelKind,
    pub bvh: BvhBuild,
    /// The BVH's node width; `None` takes the build's default.
    pub bvh_width: Option<BvhWidth>,
    /// The grid's `m`: cells per axis grow as `m * w_i * (N / V)^(1/3)`.
    pub grid_density: f32,
    /// Test an object that spans several grid cells only once per ray.
    pub mailbox: bool,
    /// The shutter interval: moving primitives are bounded over all of it (`render` sets
    /// it from `RenderOptions::shutter`).
    pub shutter: [f32; 2],
    /// What the profile chooses in the primitives' tests, which every query carries
    /// (`render` sets it from the shading profile).
    pub intersect: IntersectOptions,
    /// The layout of the 8-wide BVH's leaf packs: compact (fewer bytes, more work) for
    /// large scenes by default.
    pub packs: PackLayout,
}

impl Default for AccelOptions {
    fn default() -> Self {
        AccelOptions {
            kind: AccelKind::Bvh,
            bvh: BvhBuild::Sah,
            bvh_width: None,
            grid_density: grid::DEFAULT_DENSITY,
            mailbox: false,
            shutter: [0.0, 0.0],
            intersect: IntersectOptions::default(),
            packs: PackLayout::Auto,
        }
    }
}

impl AccelOptions {
    /// Brute force, the reference every structure answers as.
    pub fn brute_force() -> Self {
        AccelOptions {
            kind: AccelKind::None,
            ..AccelOptions::default()
        }
    }
}

impl Accel {
    /// Builds the structure `options` asks for.
    fn build(geometry: &Geometry, options: &AccelOptions) -> Accel {
        match options.kind {
            AccelKind::None => Accel::None,
            AccelKind::Grid => Accel::Grid(Grid::build(
                geometry,
                options.grid_density,
                options.mailbox,
                options.shutter,
                options.intersect.roots_margin,
            )),
            AccelKind::Bvh => {
                let (build, shutter) = (options.bvh, options.shutter);
                let margin = options.intersect.roots_margin;
                match options.bvh_width.unwrap_or(default_width(options.bvh)) {
                    BvhWidth::Two => Accel::Bvh2(Bvh2::build(geometry, build, shutter, margin)),
                    // A tree too large for the 8-wide encoding stays binary.
                    BvhWidth::Eight => {
                        match Bvh8::build(geometry, build, shutter, margin, options.packs) {
                            Ok(bvh8) => Accel::Bvh8(bvh8),
                            Err(bvh2) => Accel::Bvh2(bvh2),
                        }
                    }
                }
            }
        }
    }

    /// A short name: `none`, `grid`, `grid+mailbox`, `bvh midpoint`, `bvh sah`, with the
    /// BVH's width when it is not the build's default (`bvh sah binary`).
    pub fn name(&self) -> String {
        match self {
            Accel::None => "none".into(),
            Accel::Grid(g) => g.name(),
            Accel::Bvh2(b) => bvh_name(b.build_kind(), BvhWidth::Two),
            Accel::Bvh8(b) => bvh_name(b.build_kind(), BvhWidth::Eight),
        }
    }

    /// The structure's statistics, one `name: value` per line.
    pub fn stats(&self) -> Vec<String> {
        match self {
            Accel::None => vec![],
            Accel::Grid(g) => g.stats(),
            Accel::Bvh2(b) => b.stats().lines(&self.name()),
            Accel::Bvh8(b) => b.stats(&self.name()),
        }
    }
}

/// `$call` with `$s` the structure `$accel` holds, as its own type (no dynamic dispatch
/// in the queries).
macro_rules! with_structure {
    ($accel:expr, |$s:ident| $call:expr) => {
        match $accel {
            Accel::None => {
                let $s = &BruteForce;
                $call
            }
            Accel::Grid($s) => $call,
            Accel::Bvh2($s) => $call,
            Accel::Bvh8($s) => $call,
        }
    };
}

/// Each query by the structure's own walk, or its lane-by-lane default.
impl Structure for Accel {
    #[inline]
    fn closest<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        closest: &mut ClosestHit,
        count: &mut C,
    ) {
        with_structure!(self, |s| s.closest(geometry, query, closest, count))
    }

    #[inline]
    fn occluded<C: Count>(
        &self,
        geometry: &Geometry,
        query: &RayQuery,
        t_max: f32,
        count: &mut C,
    ) -> bool {
        with_structure!(self, |s| s.occluded(geometry, query, t_max, count))
    }

    #[inline]
    fn closest_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        closest: &mut [ClosestHit; PACKET],
        count: &mut C::Lanes,
    ) {
        with_structure!(self, |s| s
            .closest_packet::<C>(geometry, query, closest, count))
    }

    #[inline]
    fn occluded_packet<C: Count>(
        &self,
        geometry: &Geometry,
        query: &PacketQuery,
        count: &mut C::Lanes,
    ) -> LaneBits {
        with_structure!(self, |s| s.occluded_packet::<C>(geometry, query, count))
    }
}

/// What [`Tracer::closest_inside8`] answers of eight rays.
#[derive(Clone, Copy, Debug)]
pub struct InsideAnswers {
    /// The lanes answered.
    pub answered: u8,
    /// In those lanes, the closest hit's `t` and primitive, and how many primitives were
    /// tested.
    pub t: F32x8,
    pub prim: [PrimId; 8],
    pub tested: [u32; 8],
}

impl InsideAnswers {
    /// No lane answered.
    pub const NONE: InsideAnswers = InsideAnswers {
        answered: 0,
        t: F32x8::ZERO,
        prim: [PrimId::new(PrimKind::ALL[0], 0); 8],
        tested: [0; 8],
    };

    /// Lane `k`'s hit (an answered lane): the kinds with an interior have no barycentrics.
    #[inline]
    pub fn hit(&self, k: usize) -> Hit {
        Hit {
            t: self.t.lane(k),
            prim: self.prim[k],
            u: 0.0,
            v: 0.0,
        }
    }
}

/// Answers ray queries for one scene: the accelerator for bounded primitives, planes apart.
///
/// ```
/// use glam::Vec3;
/// use p3trace::accel::{AccelKind, AccelOptions, Tracer};
/// use p3trace::ray::Ray;
/// use p3trace::scene::Geometry;
///
/// // Triangles of your own: one facing +z at z = 0, material 0.
/// let mut geometry = Geometry::default();
/// geometry.triangles.push([Vec3::ZERO, Vec3::X, Vec3::Y], None, 0);
/// let ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z);
/// // Every structure gives brute force's answer.
/// for kind in [AccelKind::Bvh, AccelKind::Grid, AccelKind::None] {
///     let tracer = Tracer::new(&geometry, &AccelOptions { kind, ..AccelOptions::default() });
///     assert_eq!(tracer.closest(&ray, 0.0, f32::INFINITY).map(|hit| hit.t), Some(1.0));
///     assert!(tracer.occluded(&ray, 0.0, 2.0) && !tracer.occluded(&ray, 0.0, 0.5));
/// }
/// ```
pub struct Tracer<'s> {
    pub geometry: &'s Geometry,
    accel: Accel,
    /// The rooms: the rays from inside a primitive that it and the primitives near it
    /// answer ([`interior`]); none unless asked for ([`Tracer::with_rooms`]).
    rooms: Option<interior::Rooms>,
    /// The shutter interval the structure bounds moving primitives over.
    shutter: [f32; 2],
    /// What the profile chose in the primitives' tests: every query carries it.
    options: IntersectOptions,
    build_time: Duration,
    build_threads: usize,
}

impl<'s> Tracer<'s> {
    /// Builds the structure `options` asks for over `geometry`, whose queries test the
    /// primitives as `options.intersect` says, on the threads of the rayon pool it is
    /// called in (every core's, outside one): the same structure on any number.
    pub fn new(geometry: &'s Geometry, options: &AccelOptions) -> Self {
        let start = Instant::now();
        let intersect = bounds::with_margins(options.intersect, geometry);
        let accel = Accel::build(
            geometry,
            &AccelOptions {
                intersect,
                ..*options
            },
        );
        Tracer {
            geometry,
            accel,
            rooms: None,
            shutter: options.shutter,
            options: intersect,
            build_time: start.elapsed(),
            build_threads: rayon::current_num_threads(),
        }
    }

    /// The tracer, with the rooms of the primitives (of kinds with an interior) whose
    /// material `glass` says rays travel in: [`Tracer::closest_inside8`] answers the rays
    /// made inside them ([`interior`]).
    /// Making the rooms counts in the build time.
    pub fn with_rooms(mut self, glass: impl Fn(u32) -> bool) -> Self {
        let start = Instant::now();
        self.rooms = interior::Rooms::new(self.geometry, self.shutter, self.options, glass);
        self.build_time += start.elapsed();
        self
    }

    /// The structure's short name ([`Accel::name`]).
    pub fn name(&self) -> String {
        self.accel.name()
    }

    /// The structure's statistics, one `name: value` per line.
    pub fn stats(&self) -> Vec<String> {
        self.accel.stats()
    }

    /// How long building the structure took.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The threads the structure was built on.
    pub fn build_threads(&self) -> usize {
        self.build_threads
    }

    /// The closest hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn closest(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.closest_counting(ray, t_min, t_max, &mut NoCount)
    }

    /// [`Tracer::closest`], its work counted into `count`.
    pub fn closest_counting<C: Count>(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        count: &mut C,
    ) -> Option<Hit> {
        count.ray();
        if !ray.is_traceable() {
            return None;
        }
        let query = RayQuery::new(ray, t_min, self.options);
        let mut closest = ClosestHit::new(t_max);
        self.accel
            .closest(self.geometry, &query, &mut closest, count);
        let bounded = closest.hit();
        // Planes come last in id order, so a plane at the same `t` loses the tie.
        let t_max = bounded.map_or(t_max, |h| h.t);
        self.closest_unbounded(&query, t_max, count).or(bounded)
    }

    /// Whether anything blocks the ray within `(t_min, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.occluded_counting(ray, t_min, t_max, &mut NoCount)
    }

    /// Whether `prim` alone blocks `ray` within `(t_min, t_max)`, by its own test: where it
    /// does, [`Tracer::occluded`] and [`Tracer::occluded_packet`] answer yes too, as every
    /// structure finds what testing each primitive finds. [`Tracer::occluded_by_own8`]
    /// is its eight-lane twin.
    pub fn occluded_by(&self, prim: PrimId, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let query = RayQuery::new(ray, t_min, self.options);
        ray.is_traceable() && self.geometry.intersect(prim, &query, t_max).is_some()
    }

    /// [`Tracer::occluded_by`] for eight rays, lane `k` ray `k` of `rays` within `(t_min,
    /// t_max[k])` against the primitive of kind `kind` and index `indices[k]`. A shadow
    /// ray that leaves a closed primitive from inside meets it again before any light
    /// outside it: the renderer answers those so, without a walk.
    #[inline]
    pub fn occluded_by_own8(
        &self,
        (kind, indices): (PrimKind, [usize; 8]),
        rays: &Rays8,
        t_min: f32,
        t_max: F32x8,
    ) -> Mask8 {
        let interval = (t_min, t_max);
        let (hit, _) = self
            .geometry
            .hits8(kind, indices, rays, interval, self.options);
        traceable_lanes(rays.origin, rays.dir) & hit
    }

    /// The closest hits of eight rays `rays` from inside the trusted box of `prim`, found
    /// by it and the primitives near it where they answer as every structure would
    /// ([`interior`]): of the lanes `lanes`, those answered, and each one's hit. The other
    /// lanes need a walk.
    pub fn closest_inside8(&self, prim: PrimId, rays: &Rays8, lanes: u8) -> InsideAnswers {
        let Some(rooms) = &self.rooms else {
            return InsideAnswers::NONE;
        };
        let Some((near_prims, near_boxes)) = rooms.near(prim) else {
            return InsideAnswers::NONE;
        };
        let room = rooms.bounds(self.geometry, prim);
        let (min, max) = (Vec3x8::splat(room.min), Vec3x8::splat(room.max));
        let Rays8 { origin, dir, .. } = *rays;
        let inside = origin.x.ge(min.x)
            & origin.y.ge(min.y)
            & origin.z.ge(min.z)
            & origin.x.le(max.x)
            & origin.y.le(max.y)
            & origin.z.le(max.z);
        let asked = (inside & traceable_lanes(origin, dir)).bitmask() & lanes;
        if asked == 0 {
            return InsideAnswers::NONE;
        }
        let infinity = F32x8::splat(f32::INFINITY);
        let inv_dir = dir.recip();
        let test = |p: PrimId| {
            let within = (0.0, infinity);
            self.geometry
                .hits_one8(p, (rays, inv_dir), within, self.options)
        };
        let (mut found, mut best) = test(prim);
        let mut best_prim = [prim; 8];
        let mut tested = [1; 8];
        for (&near, near_box) in near_prims.iter().zip(near_boxes) {
            // The lanes where the near primitive's box may hold a hit at or before the
            // best (any hit, where none was found): no routine reports one in the others.
            let near_box = BoxPack8 {
                min: Vec3x8::splat(near_box.min),
                max: Vec3x8::splat(near_box.max),
            };
            let interval = intervals_lanes8(origin, inv_dir, &near_box, 0.0);
            let limit = found.select(best, infinity);
            let reach = interval.hit.and_not(beyond_lanes(interval.entry, limit));
            if reach.bitmask() & asked == 0 {
                continue;
            }
            for_lanes(reach.bitmask(), |k| tested[k] += 1);
            let (hit, t) = test(near);
            let hit = hit & reach;
            // The tie rule of `ClosestHit`: the smaller `t`, at equal `t` the smaller id.
            let mut wins = (hit & (!found | t.lt(best))).bitmask();
            for_lanes((hit & found & t.eq(best)).bitmask(), |k| {
                wins |= u8::from(near < best_prim[k]) << k;
            });
            best = Mask8::from_bitmask(wins).select(t, best);
            for_lanes(wins, |k| best_prim[k] = near);
            found = found | hit;
        }
        // A near primitive's hit beyond the room may have a closer one outside it.
        let held = holds_lanes8(origin, inv_dir, &BoxPack8 { min, max }, 0.0, best);
        InsideAnswers {
            answered: (found & held).bitmask() & asked,
            t: best,
            prim: best_prim,
            tested,
        }
    }

    /// [`Tracer::occluded`], its work counted into `count`.
    pub fn occluded_counting<C: Count>(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        count: &mut C,
    ) -> bool {
        count.ray();
        if !ray.is_traceable() {
            return false;
        }
        let query = RayQuery::new(ray, t_min, self.options);
        self.blocking_unbounded(&query, t_max, count)
            || self.accel.occluded(self.geometry, &query, t_max, count)
    }

    /// The closest hit of each active lane of `packet` within its interval; `None` for
    /// the other lanes. The same hits as [`Tracer::closest`] gives each ray; the 8-wide
    /// BVH and the grid trace them as one packet, and the planes are tested a packet's rays
    /// at a time.
    #[inline]
    pub fn closest_packet(&self, packet: &RayPacket) -> [Option<Hit>; PACKET] {
        self.closest_packet_counting::<NoCount>(packet, &mut NoCount)
    }

    /// [`Tracer::closest_packet`], each lane's work counted into its lane of `count`.
    pub fn closest_packet_counting<C: Count>(
        &self,
        packet: &RayPacket,
        count: &mut C::Lanes,
    ) -> [Option<Hit>; PACKET] {
        count.rays(packet.active);
        let active = packet.active & packet.traceable();
        let mut traceable = None;
        let packet = packet.asking(active, &mut traceable);
        let mut closest = packet.t_max.map(ClosestHit::new);
        let shear = OnceCell::new();
        let query = PacketQuery::new(packet, self.options, &shear);
        self.accel
            .closest_packet::<C>(self.geometry, &query, &mut closest, count);
        let bounded = closest.map(|c| c.hit());
        if !self.has_unbounded() {
            return std::array::from_fn(|k| bounded[k].filter(|_| active.has(k)));
        }
        // As `closest` for each lane: a plane must be closer than the structure's hit.
        let unbounded =
            self.closest_unbounded_lanes(&query, active, closest.map(|c| c.limit()), count);
        std::array::from_fn(|k| active.has(k).then(|| unbounded[k].or(bounded[k])).flatten())
    }

    /// The active lanes of `packet` whose ray is blocked within its interval, as a bit
    /// mask: the answers of [`Tracer::occluded`], traced as one packet by the 8-wide BVH
    /// and the grid.
    #[inline]
    pub fn occluded_packet(&self, packet: &RayPacket) -> LaneBits {
        self.occluded_packet_counting::<NoCount>(packet, &mut NoCount)
    }

    /// [`Tracer::occluded_packet`], each lane's work counted into its lane of `count`.
    pub fn occluded_packet_counting<C: Count>(
        &self,
        packet: &RayPacket,
        count: &mut C::Lanes,
    ) -> LaneBits {
        count.rays(packet.active);
        let active = packet.active & packet.traceable();
        let options = self.options;
        let by_unbounded = if self.has_unbounded() {
            let shear = OnceCell::new();
            self.blocking_unbounded_lanes(&PacketQuery::new(packet, options, &shear), active, count)
        } else {
            0
        };
        let mut rest = None;
        let packet = packet.asking(active & !by_unbounded, &mut rest);
        let shear = OnceCell::new();
        let query = PacketQuery::new(packet, options, &shear);
        by_unbounded
            | self
                .accel
                .occluded_packet::<C>(self.geometry, &query, count)
    }

    /// [`Tracer::closest_unbounded`] for the lanes `lanes` of `query`'s packet, each within
    /// `(t_min, t_max[k])`: each plane against the packet's rays at once by its packet
    /// kernel, which answers each lane as the scalar test does
    /// (`tests/integration/simd.rs`).
    fn closest_unbounded_lanes<C>(
        &self,
        query: &PacketQuery,
        lanes: LaneBits,
        t_max: [f32; PACKET],
        count: &mut impl CountLanes<C>,
    ) -> [Option<Hit>; PACKET] {
        let mut closest = t_max.map(ClosestHit::new);
        for kind in PrimKind::UNBOUNDED {
            count.prims(lanes, self.geometry.count(kind) as u32);
            for prim in self.geometry.ids(kind) {
                test_packet(&mut closest, self.geometry, prim, query, lanes);
            }
        }
        closest.map(|c| c.hit())
    }

    /// The lanes `lanes` of `query`'s packet that an unbounded primitive (a plane) blocks
    /// within their interval: those in which [`Tracer::closest_unbounded_lanes`] finds a hit,
    /// found without keeping the closest (a lane is done at its first plane hit).
    fn blocking_unbounded_lanes<C>(
        &self,
        query: &PacketQuery,
        lanes: LaneBits,
        count: &mut impl CountLanes<C>,
    ) -> LaneBits {
        let t_max = F32xP::from_array(query.packet.t_max);
        let mut blocked: LaneBits = 0;
        for kind in PrimKind::UNBOUNDED {
            count.prims(lanes, self.geometry.count(kind) as u32);
            for prim in self.geometry.ids(kind) {
                let open = lanes & !blocked;
                if open != 0 {
                    let hits = self.geometry.intersect_packet(prim, query, t_max, open);
                    blocked |= hits.hit.bitmask() & open;
                }
            }
        }
        blocked
    }

    /// Whether an unbounded primitive (a plane) blocks `query` within `(t_min, t_max)`:
    /// whether [`Tracer::closest_unbounded`] finds a hit, found without keeping the closest.
    fn blocking_unbounded(&self, query: &RayQuery, t_max: f32, count: &mut impl Count) -> bool {
        let mut blocked = false;
        for kind in PrimKind::UNBOUNDED {
            count.prims(self.geometry.count(kind) as u32);
            let hits = |prim| self.geometry.intersect(prim, query, t_max).is_some();
            blocked = blocked || self.geometry.ids(kind).any(hits);
        }
        blocked
    }

    /// Whether the geometry holds unbounded primitives (planes), which no structure holds
    /// and every query tests beside it.
    #[inline]
    fn has_unbounded(&self) -> bool {
        PrimKind::UNBOUNDED
            .iter()
            .any(|&kind| self.geometry.count(kind) != 0)
    }

    /// The closest hit among the unbounded primitives (planes), which no structure holds.
    fn closest_unbounded(
        &self,
        query: &RayQuery,
        t_max: f32,
        count: &mut impl Count,
    ) -> Option<Hit> {
        let mut closest = ClosestHit::new(t_max);
        for kind in PrimKind::UNBOUNDED {
            count.prims(self.geometry.count(kind) as u32);
            for prim in self.geometry.ids(kind) {
                closest.test(self.geometry, prim, query);
            }
        }
        closest.hit()
    }
}
