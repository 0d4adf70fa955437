//! Ray-primitive intersection routines and the storage of each primitive kind, one file
//! per kind (`moving_sphere.rs` reuses the sphere's routines).
//!
//! Each kind's storage implements [`Shapes`]: count, material, bounds, the scalar and
//! packet tests, the normal, the surface point. It is structure of arrays ([`Vec3s`] and
//! plain `Vec`s, one array per field), except for the kinds that fill BVH leaves: their
//! SIMD tests read the leaves' packs (eight primitives side by side), so their storage
//! is read a primitive at a time, by each hit's surface point: a record per sphere
//! ([`Sphere`]) that one or two cache lines bring, a triangle's corners in its mesh's
//! vertices ([`Triangles`]).
//! [`crate::scene::Geometry`] holds one storage per kind of the list in [`crate::prim`]
//! and dispatches to them.
//!
//! Every routine has the same contract: given a ray with a unit direction and an open
//! interval `(t_min, t_max)`, return the smallest `t` in the interval at which the ray
//! meets the primitive, or `None`. NaN inputs give `None`, never a panic. These scalar
//! versions are the reference that faster (SIMD) versions are tested against.
//!
//! Beside each scalar routine live its SIMD twins over [`crate::simd`]: a packet kernel
//! (`*_packet`: the rays of a [`crate::ray::RayPacket`] against one primitive, with an
//! `active` mask) and, for the kinds that fill BVH leaves, a leaf kernel (`*_leaf`: one
//! ray against a pack of eight primitives side by side, padded with inert entries). Both
//! run one lane-wise body that repeats the scalar arithmetic operation for operation, in
//! the same order and without fused multiply-adds, so every lane equals the scalar answer
//! bit for bit (`tests/integration/simd.rs`). They return a hit mask and `t` lanes; the
//! `t` of a lane that misses is unspecified, and lanes outside `active` always miss.

/// `$body` with `$frame` (a ray's frame, [`frame_of`]: 0, 1 or 2) as the constant
/// `$name`, which the walks and leaf tests take as a generic parameter: one branch here
/// rather than one per leaf.
macro_rules! with_frame {
    ($frame:expr, $name:ident => $body:expr) => {
        match $frame {
            0 => {
                const $name: usize = 0;
                $body
            }
            1 => {
                const $name: usize = 1;
                $body
            }
            _ => {
                const $name: usize = 2;
                $body
            }
        }
    };
}
pub(crate) use with_frame;

mod aabb;
mod bounds;
mod cone;
mod interval;
mod mesh_pack;
mod moving_sphere;
mod plane;
mod sphere;
mod triangle;

pub use aabb::{aabb, aabb_leaf, aabb_normal, aabb_packet, BoxPack8, Boxes};
pub use bounds::{trusted_box, Aabb};
pub use cone::{cone, cone_normal, cone_packet, Cones};
pub use interval::{
    beyond, beyond_lanes, holds_lanes8, intervals_lanes8, widen_entry, widen_exit, BoxRay, BoxRays,
    Intervals, Intervals8, RayRange,
};
pub use mesh_pack::{mesh_leaf, MeshPack8};
pub use moving_sphere::MovingSpheres;
pub use plane::{plane, plane_packet, Planes};
pub use sphere::{
    sphere, sphere_leaf, sphere_packet, sphere_textbook, Roots, Sphere, SpherePack8, Spheres,
    MIN_RADIUS,
};
pub use triangle::{
    frame_of, triangle, triangle_leaf, triangle_packet, Axis, Shear, ShearLanes, TrianglePack8,
    Triangles,
};

/// A packet's lanes of [`ShapeHit`], as its kernels give them.
pub type PacketHits = ShapeHits<F32xP>;

use std::cell::OnceCell;

use glam::{DVec3, Vec3};

use crate::ray::{lane_mask, Ray, RayPacket};
use crate::simd::{
    bits_where, Bits, F32x8, F32xP, Floats, LaneBits, LaneMask, Mask8, MaskP, Vec3x8, PACKET,
};

/// What a primitive's test answers: the distance along the ray and, for a triangle, the
/// barycentric coordinates of the point, `(1 - u - v) p0 + u p1 + v p2` (zero for the
/// other kinds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl ShapeHit {
    /// A hit at `t` with no barycentrics: the hits of the other kinds.
    pub fn at(t: f32) -> Self {
        ShapeHit { t, u: 0.0, v: 0.0 }
    }
}

/// Lanes of [`ShapeHit`]: lane `i` hit when `hit` has it; `t`, `u` and `v` of a lane
/// that misses are unspecified.
#[derive(Clone, Copy, Debug)]
pub struct ShapeHits<F: Floats> {
    pub hit: F::Mask,
    pub t: F,
    pub u: F,
    pub v: F,
}

/// Eight lanes of [`ShapeHit`].
pub type ShapeHit8 = ShapeHits<F32x8>;

impl<F: Floats> ShapeHits<F> {
    /// Hits at `t` with no barycentrics: the hits of the other kinds.
    pub fn at((hit, t): (F::Mask, F)) -> Self {
        ShapeHits {
            hit,
            t,
            u: F::splat(0.0),
            v: F::splat(0.0),
        }
    }
}

impl PacketHits {
    /// The hit of each lane (a miss's lanes zero).
    pub fn from_lanes(hits: [Option<ShapeHit>; PACKET]) -> Self {
        let lane =
            |field: fn(&ShapeHit) -> f32| F32xP::from_fn(|k| hits[k].as_ref().map_or(0.0, field));
        ShapeHits {
            hit: MaskP::from_bitmask(lane_mask(|k| hits[k].is_some())),
            t: lane(|h| h.t),
            u: lane(|h| h.u),
            v: lane(|h| h.v),
        }
    }
}

/// The storage of one primitive kind, and what the layers above ask of a primitive `i`
/// of it. Implemented in the kind's own file; [`crate::scene::Geometry`] dispatches to it.
pub trait Shapes {
    /// The number of primitives.
    fn len(&self) -> usize;

    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Gives back the room its arrays grew beyond what they hold: a reader calls it once
    /// a scene is read, so that the doubling of growth is not held while a scene renders.
    fn shrink_to_fit(&mut self);

    /// Primitive `i`'s material.
    fn material(&self, i: usize) -> u32;

    /// The tight box, over the whole `shutter` for moving primitives; all of space for an
    /// unbounded kind (which no structure holds).
    fn bounds(&self, i: usize, shutter: [f32; 2]) -> Aabb;

    /// The scalar test: the closest hit of `query` in `(query.t_min, t_max)`, with
    /// barycentrics for triangles (zero for other kinds).
    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<ShapeHit>;

    /// [`Shapes::intersect`] for the lanes `active` of `query`'s packet, each within
    /// `(packet.t_min, t_max)` lane by lane (the packet's own bounds, or tighter ones a
    /// traversal keeps), each lane bit for bit the scalar answer; the other lanes miss.
    /// By default lane by lane; a kind with a packet kernel (`*_packet`) calls it.
    fn intersect_packet(
        &self,
        i: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let t_max = t_max.to_array();
        PacketHits::from_lanes(std::array::from_fn(|k| {
            active
                .has(k)
                .then(|| self.intersect(i, &query.lane(k), t_max[k]))
                .flatten()
        }))
    }

    /// The outward unit normal at the hit point `p` (barycentrics `u`, `v` for
    /// triangles; `time` for moving primitives).
    fn normal(&self, i: usize, p: Vec3, u: f32, v: f32, time: f32) -> Vec3;

    /// The hit at `t` along `ray` (barycentrics `u`, `v` for triangles; the ray's time
    /// for moving primitives) recomputed on the surface, with its error bound and normal.
    fn surface_point(&self, i: usize, ray: &Ray, t: f32, u: f32, v: f32) -> SurfacePoint;

    /// [`Shapes::surface_point`] for eight hits, lane `k` on primitive `indices[k]` (the
    /// hit of `hits[k]` along `rays[k]`), each lane bit for bit the scalar answer. By
    /// default one lane at a time; a kind with an eight-lane twin overrides it.
    fn surface_points8(&self, indices: [usize; 8], rays: &[Ray; 8], hits: &Hits8) -> SurfacePoint8 {
        SurfacePoint8::from_lanes(std::array::from_fn(|k| {
            self.surface_point(indices[k], &rays[k], hits.t[k], hits.u[k], hits.v[k])
        }))
    }

    /// Whether the structures grow this kind's boxes by the margin of the profile's sphere
    /// roots ([`IntersectOptions::roots_margin`], `accel::bounds`).
    const ROOTS_MARGIN: bool = false;

    /// Whether the primitives move over the shutter (their boxes cover the whole of it).
    const MOVING: bool = false;

    /// Whether the rays inside this kind's primitives (refracted into them, reflected
    /// within them, their shadow rays) are answered by the primitives' own tests and those
    /// of the few near them, without a walk (`accel::interior`). For a closed kind whose
    /// hits have no barycentrics, with eight-lane twins of the three tests below: the
    /// defaults, one lane at a time, would cost more than the walks they save.
    const INTERIOR: bool = false;

    /// Eight rays against eight primitives, lane `k` against primitive `indices[k]` within
    /// `(t_min, t_max[k])`: the lanes that hit, and each hit's `t` (unspecified in the
    /// others), bit for bit as [`Shapes::intersect`]. By default one lane at a time.
    fn hits8(
        &self,
        indices: [usize; 8],
        rays: &Rays8,
        t_min: f32,
        t_max: F32x8,
        options: IntersectOptions,
    ) -> (Mask8, F32x8) {
        let mut t = [0.0; 8];
        let hit = bits_where(|k| {
            let query = RayQuery::new(&rays.lane(k), t_min, options);
            let found = self.intersect(indices[k], &query, t_max.lane(k));
            found.inspect(|h| t[k] = h.t).is_some()
        });
        (Mask8::from_bitmask(hit), F32x8::from_array(t))
    }

    /// [`Shapes::hits8`] with primitive `index` in every lane, for rays whose `1 / dir`
    /// the caller has (`inv_dir`).
    fn hits_one8(
        &self,
        index: usize,
        (rays, _inv_dir): (&Rays8, Vec3x8),
        t_min: f32,
        t_max: F32x8,
        options: IntersectOptions,
    ) -> (Mask8, F32x8) {
        self.hits8([index; 8], rays, t_min, t_max, options)
    }

    /// [`Shapes::surface_points8`] of eight hits without barycentrics given as lanes
    /// (lane `k`: primitive `indices[k]` at `t[k]` along ray `k` of `rays`), without the
    /// rays' transposition where the kind has the twin. By default the rays transposed.
    fn surface_points_along8(&self, indices: [usize; 8], rays: &Rays8, t: F32x8) -> SurfacePoint8 {
        let hits = Hits8 {
            t: t.to_array(),
            u: [0.0; 8],
            v: [0.0; 8],
        };
        self.surface_points8(indices, &std::array::from_fn(|k| rays.lane(k)), &hits)
    }

    /// The geometric normal (a smooth triangle's too) at the hit point `p` at time 0, in
    /// double precision where the kind computes it so: `bench` works in double, and a
    /// small sphere turns an error in its point into a large one in its normal. By
    /// default [`Shapes::normal`], widened.
    fn geometric_normal64(&self, i: usize, p: DVec3, u: f32, v: f32) -> DVec3 {
        self.normal(i, p.as_vec3(), u, v, 0.0).as_dvec3()
    }
}

/// Eight rays as lanes: origins, unit directions and shutter times.
#[derive(Clone, Copy, Debug)]
pub struct Rays8 {
    pub origin: Vec3x8,
    pub dir: Vec3x8,
    pub time: F32x8,
}

impl Rays8 {
    /// The ray of lane `k`.
    #[inline]
    pub fn lane(&self, k: usize) -> Ray {
        Ray {
            origin: self.origin.lane(k),
            dir: self.dir.lane(k),
            time: self.time.lane(k),
        }
    }
}

/// Eight hits' distances and barycentrics, as [`Shapes::surface_points8`] reads them.
#[derive(Clone, Copy, Debug)]
pub struct Hits8 {
    pub t: [f32; 8],
    pub u: [f32; 8],
    pub v: [f32; 8],
}

/// What a profile chooses in an intersection: the form of the sphere test's quadratic.
/// Chosen where the tracer is built and handed to the kernels with each query (as
/// Embree's per-query context), never kept with the geometry. With it goes how much
/// further than rounding the structures pad the box of a kind whose roots it chooses
/// (`accel::bounds`, `Shapes::ROOTS_MARGIN`), which the tracer sets from the scene for
/// the textbook roots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IntersectOptions {
    pub roots: Roots,
    pub roots_margin: f32,
}

/// The primitives in the first pack of a leaf that takes two ([`PackOf::continues`]):
/// four triangles hold at most twelve vertices, which fit in a [`MeshPack8`].
pub const CHAIN_HEAD: usize = 4;

/// A kind whose primitives the 8-wide BVH stores side by side (`packed` in
/// `prim_kinds!`): up to eight of them in a leaf's pack ([`PackOf`]), tested against one
/// ray by the pack's leaf kernel, or slot by slot against a packet by its packet kernel.
/// Each slot's answer is the scalar test's ([`Shapes::intersect`]) bit for bit.
pub trait LeafPack: Shapes + Sized {
    /// The pack of the kind's leaves.
    type Pack: PackOf<Self>;
    /// A pack of fewer bytes, for more work, that large scenes take ([`LeafPack::Pack`]
    /// where the kind has none).
    type Compact: PackOf<Self>;
    /// Whether the kind has a compact pack: the trees of the others hold none, and their
    /// walks are compiled without it.
    const HAS_COMPACT: bool = false;
    /// The primitives of the kind from which a tree takes [`LeafPack::Compact`] packs
    /// ([`PackLayout::Auto`]).
    const COMPACT_FROM: usize = usize::MAX;
}

/// Which packs a tree's leaves take ([`LeafPack`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PackLayout {
    /// [`LeafPack::Compact`] for a kind of [`LeafPack::COMPACT_FROM`] primitives or more.
    #[default]
    Auto,
    /// [`LeafPack::Pack`] always.
    Full,
    /// [`LeafPack::Compact`] for every kind that has one.
    Compact,
}

impl PackLayout {
    /// Whether a tree over `count` primitives of the kind `K` takes compact packs (never
    /// where the kind has none).
    pub fn compact<K: LeafPack>(self, count: usize) -> bool {
        K::HAS_COMPACT
            && match self {
                PackLayout::Auto => count >= K::COMPACT_FROM,
                PackLayout::Full => false,
                PackLayout::Compact => true,
            }
    }
}

/// The (at most eight) values of `values` at the front of an array, and how many there
/// are: a pack's primitives gathered without a vector of their own.
///
/// # Panics
/// If given more than eight.
pub(crate) fn gather8<T: Copy + Default>(values: impl Iterator<Item = T>) -> ([T; 8], usize) {
    let mut gathered = [T::default(); 8];
    let mut n = 0;
    for value in values {
        assert!(n < 8, "a pack holds at most 8 primitives");
        gathered[n] = value;
        n += 1;
    }
    (gathered, n)
}

/// Up to eight primitives of the storage `K` side by side, and their kernels; unused
/// slots are padding that no ray hits.
pub trait PackOf<K>: Clone + Copy + std::fmt::Debug {
    /// The primitives `indices` (one to eight) of `storage` as a pack, or `None` where
    /// they do not fit in one (the triangles of a [`MeshPack8`] share at most twelve
    /// vertices).
    fn pack(storage: &K, indices: impl Iterator<Item = usize>) -> Option<Self>;

    /// Whether a pack may go on in the next one ([`PackOf::continues`]).
    const CHAINS: bool = false;

    /// Whether `pack` goes on in the next pack: the first [`CHAIN_HEAD`] primitives of a
    /// leaf that does not fit in one pack, the next pack holding the rest.
    #[inline(always)]
    fn continues(_pack: &Self) -> bool {
        false
    }

    /// `pack` marked as going on in the next one ([`PackOf::CHAINS`] packs alone).
    fn continued(pack: Self) -> Self {
        pack
    }

    /// Whether [`PackOf::leaf`]'s answer depends on `FRAME`.
    const FRAMED: bool = false;

    /// One ray against the eight slots of `pack`, within `(query.t_min, t_max)`. `FRAME`
    /// is the ray's frame ([`frame_of`]), which the triangle test specialises on and the
    /// other kinds ignore: a walk takes it once (`with_frame!`).
    fn leaf<const FRAME: usize>(pack: &Self, query: &RayQuery, t_max: f32) -> ShapeHit8;

    /// A pack as [`PackOf::slot_packet`] reads its slots: the pack itself, or what it
    /// holds unpacked once for all its slots.
    type Slots<'a>: Copy
    where
        Self: 'a;

    /// `pack` as its slots are read ([`PackOf::Slots`]).
    fn slots(pack: &Self) -> Self::Slots<'_>;

    /// The primitive in slot `slot` of a pack (its [`PackOf::slots`]) against the lanes
    /// `active` of `query`'s packet, as [`Shapes::intersect_packet`] tests a primitive of
    /// the storage.
    fn slot_packet(
        slots: Self::Slots<'_>,
        slot: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits;
}

/// One ray as a query's primitive tests take it, with what stays the same for all of
/// them: `1 / dir`, the start of the interval, and what the profile chose (`options`).
/// The end of the interval shrinks as hits are found, and goes with each test.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    pub ray: Ray,
    pub inv_dir: Vec3,
    pub t_min: f32,
    pub options: IntersectOptions,
}

impl RayQuery {
    pub fn new(ray: &Ray, t_min: f32, options: IntersectOptions) -> Self {
        RayQuery {
            ray: *ray,
            inv_dir: ray.dir.recip(),
            t_min,
            options,
        }
    }

    /// Whether the hit at `t` lies in the trusted box `bounds` ([`trusted_box`]), by the
    /// structures' box test ([`BoxRay::holds`]): the rule every routine's hits keep.
    #[inline]
    pub fn holds(&self, bounds: Option<Aabb>, t: f32) -> bool {
        bounds.is_some_and(|b| {
            BoxRay::new(self.ray.origin, self.inv_dir).holds(b.min, b.max, self.t_min, t)
        })
    }

    /// [`RayQuery::holds`] for the eight boxes of a pack (as [`BoxPack8::trusted`] gives
    /// them, with the lanes that have one), lane `k` with the hit `t[k]`.
    #[inline(always)]
    pub fn holds8(&self, (boxes, some): (BoxPack8, Mask8), t: F32x8) -> Mask8 {
        some & BoxRay::new(self.ray.origin, self.inv_dir).holds8(&boxes, self.t_min, t)
    }
}

/// [`RayQuery`] for a packet's rays: a packet (its lanes' `1 / dir`, the start of their
/// interval), the triangle test's setup of its lanes, made by the first triangle test
/// that needs it ([`PacketQuery::shear`]), and what the profile chose. A few words, passed
/// and copied freely: the setup, hundreds of bytes, lies in its maker's frame.
#[derive(Clone, Copy, Debug)]
pub struct PacketQuery<'p> {
    pub packet: &'p RayPacket<'p>,
    shear: &'p OnceCell<ShearLanes>,
    pub options: IntersectOptions,
}

impl<'p> PacketQuery<'p> {
    /// The query of the lanes `packet` asks, its triangle setup to be made in `shear` (an
    /// empty cell of the caller's, as [`RayPacket::asking`] makes its copy).
    #[inline]
    pub fn new(
        packet: &'p RayPacket<'p>,
        options: IntersectOptions,
        shear: &'p OnceCell<ShearLanes>,
    ) -> Self {
        PacketQuery {
            packet,
            shear,
            options,
        }
    }

    /// The triangle test's setup of the lanes, made at the first call: a packet that
    /// meets no triangle (a scene of spheres, a packet whose lanes go on alone) never
    /// makes it.
    #[inline(always)]
    pub fn shear(&self) -> &ShearLanes {
        self.shear.get_or_init(|| ShearLanes::new(self.packet))
    }

    /// Lane `k`'s ray as a query of its own: the same `1 / dir`, bit for bit, as
    /// [`RayQuery::new`] makes. The ray is read from the packet's lanes, not copied from
    /// its array of rays: that copy (28 bytes, as two overlapping 16-byte moves) was read
    /// back across both stores, which the store buffer cannot forward, and that stall was
    /// 7% of a shadow packet walk's time at scale.
    #[inline]
    pub fn lane(&self, k: usize) -> RayQuery {
        let packet = self.packet;
        RayQuery {
            ray: Ray {
                origin: packet.origin.lane(k),
                dir: packet.dir.lane(k),
                time: packet.time.lane(k),
            },
            inv_dir: packet.inv_dir.lane(k),
            t_min: packet.t_min,
            options: self.options,
        }
    }

    /// [`RayQuery::holds`] for each lane, lane `k` with the hit `t[k]`.
    #[inline]
    pub fn holds(&self, bounds: Option<Aabb>, t: F32xP) -> MaskP {
        bounds.map_or(MaskP::from_bitmask(0), |b| {
            BoxRays::new(self.packet).holds(b.min, b.max, self.t_min_lanes(), t)
        })
    }

    /// The start of every lane's interval, as the packet kernels take it.
    #[inline]
    pub fn t_min_lanes(&self) -> F32xP {
        F32xP::splat(self.packet.t_min)
    }
}

/// Three parallel arrays of coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Vec3s {
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub z: Vec<f32>,
}

impl Vec3s {
    pub fn push(&mut self, v: Vec3) {
        self.x.push(v.x);
        self.y.push(v.y);
        self.z.push(v.z);
    }

    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    pub fn shrink_to_fit(&mut self) {
        self.x.shrink_to_fit();
        self.y.shrink_to_fit();
        self.z.shrink_to_fit();
    }
}

/// The relative error bound of `n` rounded operations, `n u / (1 - n u)` with `u` the unit
/// roundoff (pbrt's `gamma(n)`).
pub const fn gamma(n: u32) -> f32 {
    let nu = n as f32 * (f32::EPSILON / 2.0);
    nu / (1.0 - nu)
}

/// [`gamma`] of three: a slab distance `(bound - origin) * inv_dir` is off by at most this
/// much of itself.
pub const GAMMA_3: f32 = gamma(3);

/// A hit recomputed on the surface it hit ([`Shapes::surface_point`]): the point, a bound
/// of its remaining rounding error on each axis, and the outward unit normal there. Rays
/// spawned at a hit start from it ([`spawn_origin`]).
///
/// `ray.at(t)` is off the surface by the error of `t`, which cancellation can make
/// thousands of ulps (a small sphere seen from afar, a grazing hit), and a normal taken
/// from it as `p - centre` keeps only the digits that `p`'s magnitude leaves (a scene far
/// from the origin keeps few). Recomputed from the surface's own description, relative to
/// it (a sphere's centre and radius, a triangle's barycentrics), the point is off by a
/// few ulps of the coordinates involved, which is what `error` bounds; so the offset that
/// clears it follows the scene's scale and position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub point: Vec3,
    pub error: Vec3,
    pub normal: Vec3,
}

/// [`SurfacePoint`] for eight hits, as structure of arrays.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint8 {
    pub point: Vec3x8,
    pub error: Vec3x8,
    pub normal: Vec3x8,
}

impl SurfacePoint8 {
    /// Lane `k` from `points[k]`.
    pub fn from_lanes(points: [SurfacePoint; 8]) -> Self {
        SurfacePoint8 {
            point: Vec3x8::from_lanes(points.map(|p| p.point)),
            error: Vec3x8::from_lanes(points.map(|p| p.error)),
            normal: Vec3x8::from_lanes(points.map(|p| p.normal)),
        }
    }

    pub fn lane(&self, k: usize) -> SurfacePoint {
        SurfacePoint {
            point: self.point.lane(k),
            error: self.error.lane(k),
            normal: self.normal.lane(k),
        }
    }

    /// Sets lane `k` to `point` (a lane a kind's twin leaves to its scalar form).
    pub fn set_lane(&mut self, k: usize, point: SurfacePoint) {
        self.point.set_lane(k, point.point);
        self.error.set_lane(k, point.error);
        self.normal.set_lane(k, point.normal);
    }
}

/// The origin of a ray leaving `point`, whose error is bounded by `error` on each axis,
/// on the side of the unit vector `side` (the normal facing where the ray goes): `point`
/// moved along `side` by the bound's extent along it, then each coordinate one float
/// further that way, so that a bound of zero still leaves the surface (pbrt-v4's
/// `OffsetRayOrigin`).
pub fn spawn_origin(point: Vec3, error: Vec3, side: Vec3) -> Vec3 {
    let moved = point + error.dot(side.abs()) * side;
    let away = |k: usize| {
        if side[k] > 0.0 {
            moved[k].next_up()
        } else if side[k] < 0.0 {
            moved[k].next_down()
        } else {
            moved[k]
        }
    };
    Vec3::new(away(0), away(1), away(2))
}

/// [`spawn_origin`] for eight points at once, lane by lane in the same operations.
pub fn spawn_origin8(point: Vec3x8, error: Vec3x8, side: Vec3x8) -> Vec3x8 {
    let moved = point + side.scale(error.dot(side.abs()));
    let away = |m: F32x8, s: F32x8| {
        let below = s.lt(F32x8::ZERO).select(m.next_down(), m);
        s.gt(F32x8::ZERO).select(m.next_up(), below)
    };
    Vec3x8 {
        x: away(moved.x, side.x),
        y: away(moved.y, side.y),
        z: away(moved.z, side.z),
    }
}

/// The first of two roots `near <= far` that lies in `(t_min, t_max)`: the entry of a
/// convex shape, or its exit when the origin is inside.
fn first_root_in(near: f32, far: f32, t_min: f32, t_max: f32) -> Option<f32> {
    if near > t_min && near < t_max {
        Some(near)
    } else if far > t_min && far < t_max {
        Some(far)
    } else {
        None
    }
}

/// [`first_root_in`] lane by lane: the hit mask and the chosen root.
#[inline(always)]
fn first_root_in_lanes<F: Floats>(near: F, far: F, t_min: F, t_max: F) -> (F::Mask, F) {
    let near_in = near.gt(t_min) & near.lt(t_max);
    let far_in = far.gt(t_min) & far.lt(t_max);
    (near_in | far_in, near_in.select(near, far))
}

/// The larger of `a` and `b`, ignoring a NaN operand as `f32::max` does, and `b` on a
/// tie: `f32::max` may return either zero for `max(-0.0, 0.0)`, which would leave the
/// SIMD twin ([`F32x8::max_num`]) no fixed answer to equal.
#[inline]
pub fn max_num(a: f32, b: f32) -> f32 {
    if a > b || b.is_nan() {
        a
    } else {
        b
    }
}
