//! The triangle kind: its storage ([`Triangles`]: a vertex and two edges, optional vertex
//! normals), Möller-Trumbore and its SIMD twins (a packet's rays against one triangle; one
//! ray against a [`TrianglePack8`] of a BVH leaf).
//!
//! **Precision.** A hit stands only inside the triangle's trusted box (the box the
//! structures hold it in, `intersect::trusted_box`), by the structures' own box test
//! ([`RayQuery::holds`]): then every structure finds it (`accel::bounds`). Single-precision
//! Möller-Trumbore's hit almost always lies there. It fails in two ways: a sliver's
//! determinant (edges parallel to within rounding) is noise, so `u`, `v` and `t` are too
//! (a hit 0.09 off the plane); and from 1e9 away `t` keeps only the digits that
//! `e2 . ((o - p0) x e1)` leaves (15,200 short of the plane). Such a hit is computed again
//! in double precision from the same inputs ([`refined`]) and stands if that one lies in
//! the box. The products of single-precision numbers are exact in double precision, so
//! the determinant, `u`, `v` and `t` are those of the triangle as stored, to a few
//! roundings of doubles. Whether a hit is recomputed depends on the ray and the triangle
//! alone, never on `t_max`, so the answer does not depend on the order a structure tests
//! primitives in. The box test runs eight lanes at a time on the packs that single
//! precision hits, against boxes each pack keeps (made once: making them at each such
//! test cost 5% of the protocol's traversal instructions), and the recomputation in scalar
//! code shared by every twin, so each lane stays the scalar answer bit for bit. A watertight test (Woop, Benthin and Wald
//! 2013) would also close the cracks along shared edges, but wants the three vertices
//! stored and its shear per ray, and from 1e9 away its `t` loses the same digits; cracks
//! are not what the findings are, and the storage stays Möller-Trumbore's.

use glam::Vec3;

use super::{
    gamma, trusted_box, Aabb, BoxPack8, BoxRays, Hits8, IntersectOptions, LeafPack, PacketHits,
    PacketQuery, RayQuery, Shapes, SurfacePoint, SurfacePoint8,
};
use crate::ray::{lane_mask, Ray, RayPacket};
use crate::simd::{
    for_lanes, Bits, F32x8, F32xP, Floats, LaneBits, LaneMask, Mask8, MaskP, Vec3Lanes, Vec3x8,
    Vec3xP, PACKET,
};

/// Distance and barycentric coordinates of a ray-triangle hit: the point is
/// `(1 - u - v) p0 + u p1 + v p2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl TriangleHit {
    /// A hit at `t` with no barycentrics: the hits of the other kinds.
    pub fn at(t: f32) -> Self {
        TriangleHit { t, u: 0.0, v: 0.0 }
    }
}

/// Möller-Trumbore test against the triangle `p0, p0 + e1, p0 + e2`. Two-sided; edges and
/// vertices count as inside. A triangle with zero edges (how the scene stores degenerate
/// ones) has a zero determinant and is never hit. A hit lies in the triangle's box as the
/// structures hold it, single precision's where it does, else double precision's (the
/// module's comment).
pub fn triangle(
    ray: &Ray,
    p0: Vec3,
    e1: Vec3,
    e2: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<TriangleHit> {
    let query = || RayQuery::new(ray, t_min, IntersectOptions::default());
    triangle_hit(ray, [p0, e1, e2], t_min, t_max, query)
}

/// The body of [`triangle`], with `query` giving the ray's query for the box test, made
/// only for a candidate (a caller with one at hand passes it). Out of line, as
/// [`triangle`] was: inlined, it grows `Geometry::intersect` for every kind (+0.4% on
/// `bench balls_high`).
#[inline(never)]
fn triangle_hit(
    ray: &Ray,
    [p0, e1, e2]: [Vec3; 3],
    t_min: f32,
    t_max: f32,
    query: impl Fn() -> RayQuery,
) -> Option<TriangleHit> {
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - p0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    if !(t > t_min) {
        return None;
    }
    let query = query();
    if in_trusted_box(&query, [p0, e1, e2], t) {
        return (t < t_max).then_some(TriangleHit { t, u, v });
    }
    refined(ray, p0, e1, e2, t_min, t_max).filter(|hit| in_trusted_box(&query, [p0, e1, e2], hit.t))
}

/// The box of the corners of `p0, e1, e2`, as [`Triangles`] bounds it for the structures;
/// `None` unless the corners are finite.
#[inline]
fn corner_box([p0, e1, e2]: [Vec3; 3]) -> Option<Aabb> {
    let (a, b) = (p0 + e1, p0 + e2);
    (p0.is_finite() && a.is_finite() && b.is_finite()).then(|| Aabb {
        min: p0.min(a).min(b),
        max: p0.max(a).max(b),
    })
}

/// The box the structures hold the triangle `p0, e1, e2` in ([`trusted_box`]).
#[inline]
fn trusted_triangle_box(triangle: [Vec3; 3]) -> Option<Aabb> {
    corner_box(triangle).and_then(|tight| trusted_box(tight, 0.0))
}

/// Whether the hit at `t` of the triangle `p0, e1, e2` along `query` lies where the
/// structures look for it: in its trusted box, by their box test ([`RayQuery::holds`]).
#[inline(never)]
fn in_trusted_box(query: &RayQuery, triangle: [Vec3; 3], t: f32) -> bool {
    query.holds(trusted_triangle_box(triangle), t)
}

/// Möller-Trumbore in double precision from the single-precision inputs: the hit of a
/// candidate that the single-precision test found (see the module's comment).
#[inline(never)]
fn refined(ray: &Ray, p0: Vec3, e1: Vec3, e2: Vec3, t_min: f32, t_max: f32) -> Option<TriangleHit> {
    let (origin, dir) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (p0, e1, e2) = (p0.as_dvec3(), e1.as_dvec3(), e2.as_dvec3());
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = origin - p0;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    if !(u >= 0.0 && v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = (e2.dot(q) / det) as f32;
    let (u, v) = (u as f32, v as f32);
    (t > t_min && t < t_max).then_some(TriangleHit { t, u, v })
}

/// The candidates of `hits` (single precision's, `triangle_lanes`) settled as [`triangle`]
/// settles them: the lanes of `trusted` (in the triangle's box) kept within `t_max`, the
/// others computed again by [`refined`], lane `k` against the ray and the triangle that
/// `lane(k)` gives.
#[inline(always)]
fn settle<F: Floats>(
    hits: &mut TriangleHits<F>,
    trusted: F::Mask,
    lane: impl Fn(usize) -> (Ray, [Vec3; 3]),
    t_min: F,
    t_max: F,
) {
    let doubtful = hits.hit.and_not(trusted).bitmask();
    hits.hit = hits.hit & trusted & hits.t.lt(t_max);
    if doubtful != Bits::EMPTY {
        refine_lanes(hits, doubtful, lane, t_min, t_max);
    }
}

/// The lanes `doubtful` of `hits` as [`triangle`] computes them again.
#[cold]
#[inline(never)]
fn refine_lanes<F: Floats>(
    hits: &mut TriangleHits<F>,
    doubtful: <F::Mask as LaneMask>::Bits,
    lane: impl Fn(usize) -> (Ray, [Vec3; 3]),
    t_min: F,
    t_max: F,
) {
    let mut mask = hits.hit.bitmask();
    for_lanes(doubtful, |k| {
        let (ray, triangle) = lane(k);
        let [p0, e1, e2] = triangle;
        let (t_min, t_max) = (t_min.lane(k), t_max.lane(k));
        let hit = refined(&ray, p0, e1, e2, t_min, t_max).filter(|hit| {
            let query = RayQuery::new(&ray, t_min, IntersectOptions::default());
            in_trusted_box(&query, triangle, hit.t)
        });
        if let Some(hit) = hit {
            hits.t.set_lane(k, hit.t);
            hits.u.set_lane(k, hit.u);
            hits.v.set_lane(k, hit.v);
            mask = mask.with(k);
        }
    });
    hits.hit = F::Mask::from_bitmask(mask);
}

/// Lanes of [`TriangleHit`]: lane `i` hit when `hit` has it; `t`, `u` and `v` of a lane
/// that misses are unspecified.
#[derive(Clone, Copy, Debug)]
pub struct TriangleHits<F: Floats> {
    pub hit: F::Mask,
    pub t: F,
    pub u: F,
    pub v: F,
}

/// Eight lanes of [`TriangleHit`].
pub type TriangleHit8 = TriangleHits<F32x8>;

impl<F: Floats> TriangleHits<F> {
    /// Hits at `t` with no barycentrics: the hits of the other kinds.
    pub fn at((hit, t): (F::Mask, F)) -> Self {
        TriangleHits {
            hit,
            t,
            u: F::splat(0.0),
            v: F::splat(0.0),
        }
    }
}

impl PacketHits {
    /// The hit of each lane (a miss's lanes zero).
    pub fn from_lanes(hits: [Option<TriangleHit>; PACKET]) -> Self {
        let lane = |field: fn(&TriangleHit) -> f32| {
            F32xP::from_fn(|k| hits[k].as_ref().map_or(0.0, field))
        };
        TriangleHits {
            hit: MaskP::from_bitmask(lane_mask(|k| hits[k].is_some())),
            t: lane(|h| h.t),
            u: lane(|h| h.u),
            v: lane(|h| h.v),
        }
    }
}

/// Eight triangles side by side for [`triangle_leaf`], stored as the scene stores them
/// (a vertex and two edges), with their trusted boxes. Unused slots have zero edges, as
/// degenerate triangles do, so their determinant is 0 (or NaN for a NaN ray) and they
/// are never hit.
#[derive(Clone, Copy, Debug)]
pub struct TrianglePack8 {
    pub p0: Vec3x8,
    pub e1: Vec3x8,
    pub e2: Vec3x8,
    /// Each slot's [`trusted_triangle_box`], valid in the slots of `trusted_slots` that
    /// single precision can hit (a slot with a NaN corner is none: a NaN or infinite
    /// vertex or edge makes the determinant or `u` NaN).
    trusted: BoxPack8,
    trusted_slots: u8,
}

impl TrianglePack8 {
    /// Packs up to eight `[p0, e1, e2]` triangles, padding the rest with zeros.
    ///
    /// # Panics
    /// If given more than eight triangles.
    pub fn new(triangles: &[[Vec3; 3]]) -> Self {
        assert!(triangles.len() <= 8, "a pack holds at most 8 triangles");
        let field = |k: usize| {
            Vec3x8::from_lanes(std::array::from_fn(|i| {
                triangles.get(i).map_or(Vec3::ZERO, |tri| tri[k])
            }))
        };
        let (p0, e1, e2) = (field(0), field(1), field(2));
        let (a, b) = (p0 + e1, p0 + e2);
        let tight = BoxPack8 {
            min: p0.min(a).min(b),
            max: p0.max(a).max(b),
        };
        let (trusted, trusted_slots) = tight.trusted(0.0);
        TrianglePack8 {
            p0,
            e1,
            e2,
            trusted,
            trusted_slots: trusted_slots.bitmask(),
        }
    }

    /// The trusted box of slot `slot`, bit for bit as [`trusted_triangle_box`] makes it
    /// where its corners are not NaN.
    #[inline(always)]
    fn trusted_box(&self, slot: usize) -> Option<Aabb> {
        (self.trusted_slots & 1 << slot != 0).then(|| Aabb {
            min: self.trusted.min.lane(slot),
            max: self.trusted.max.lane(slot),
        })
    }
}

/// [`triangle`] for a packet's rays against one triangle; lanes outside `active` miss.
pub fn triangle_packet(
    rays: &RayPacket,
    p0: Vec3,
    e1: Vec3,
    e2: Vec3,
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> PacketHits {
    let triangle = [p0, e1, e2];
    packet_hits(
        rays,
        triangle,
        || trusted_triangle_box(triangle),
        t_min,
        t_max,
        active,
    )
}

/// [`triangle_packet`] with the triangle's trusted box made by `trusted`, only for a
/// packet with candidates.
#[inline(always)]
fn packet_hits(
    rays: &RayPacket,
    [p0, e1, e2]: [Vec3; 3],
    trusted: impl Fn() -> Option<Aabb>,
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> PacketHits {
    let mut hits = triangle_lanes(
        rays.origin,
        rays.dir,
        Vec3xP::splat(p0),
        Vec3xP::splat(e1),
        Vec3xP::splat(e2),
        t_min,
    );
    hits.hit = hits.hit & MaskP::from_bitmask(active);
    if hits.hit.any() {
        let trusted = trusted().map_or(MaskP::from_bitmask(0), |b| {
            BoxRays::new(rays).holds(b.min, b.max, t_min, hits.t)
        });
        settle(
            &mut hits,
            trusted,
            |k| (rays.rays[k], [p0, e1, e2]),
            t_min,
            t_max,
        );
    }
    hits
}

/// [`triangle`] for one ray against the eight triangles of a pack.
pub fn triangle_leaf(ray: &Ray, pack: &TrianglePack8, t_min: f32, t_max: f32) -> TriangleHit8 {
    let query = RayQuery::new(ray, t_min, IntersectOptions::default());
    leaf_hits(&query, pack, t_max)
}

/// [`triangle_leaf`] for a query (its `1 / dir` computed once per ray).
#[inline(always)]
fn leaf_hits(query: &RayQuery, pack: &TrianglePack8, t_max: f32) -> TriangleHit8 {
    let ray = &query.ray;
    let (t_min, t_max) = (F32x8::splat(query.t_min), F32x8::splat(t_max));
    let mut hits = triangle_lanes(
        Vec3x8::splat(ray.origin),
        Vec3x8::splat(ray.dir),
        pack.p0,
        pack.e1,
        pack.e2,
        t_min,
    );
    if hits.hit.any() {
        let trusted = query.holds8(
            (pack.trusted, Mask8::from_bitmask(pack.trusted_slots)),
            hits.t,
        );
        let triangle = |k| [pack.p0.lane(k), pack.e1.lane(k), pack.e2.lane(k)];
        settle(&mut hits, trusted, |k| (*ray, triangle(k)), t_min, t_max);
    }
    hits
}

/// The single-precision body of [`triangle`], lane by lane, its early exits turned into
/// a mask: the candidates that [`settle`] settles.
#[inline(always)]
fn triangle_lanes<F: Floats>(
    origin: Vec3Lanes<F>,
    dir: Vec3Lanes<F>,
    p0: Vec3Lanes<F>,
    e1: Vec3Lanes<F>,
    e2: Vec3Lanes<F>,
    t_min: F,
) -> TriangleHits<F> {
    let (zero, one) = (F::splat(0.0), F::splat(1.0));
    let p = dir.cross(e2);
    let det = e1.dot(p);
    let mut hit = det.is_finite().and_not(det.eq(zero));
    let inv_det = one / det;
    let s = origin - p0;
    let u = s.dot(p) * inv_det;
    hit = hit & zero.le(u) & u.le(one);
    let q = s.cross(e1);
    let v = dir.dot(q) * inv_det;
    hit = hit & v.ge(zero) & (u + v).le(one);
    let t = e2.dot(q) * inv_det;
    hit = hit & t.gt(t_min);
    TriangleHits { hit, t, u, v }
}

/// Triangles stored as a vertex and two edges (what Möller-Trumbore reads), one
/// [`Triangle`] record each. Degenerate triangles are stored with zero edges, which the
/// test never hits.
///
/// Records, not an array per coordinate: the SIMD tests read the leaf packs
/// ([`TrianglePack8`], structure of arrays), so this storage is read one triangle at a
/// time, by a hit's surface point above all, where nine coordinate arrays and two of
/// indices cost eleven cache lines and a record one or two.
#[derive(Clone, Debug, Default)]
pub struct Triangles {
    pub records: Vec<Triangle>,
    pub vertex_normals: Vec<[Vec3; 3]>,
}

/// One triangle of [`Triangles`]: 44 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Triangle {
    pub p0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    pub material: u32,
    /// Index into `vertex_normals` for smooth (`pp`) triangles, [`Triangles::FLAT`]
    /// otherwise.
    pub shading: u32,
}

impl Triangle {
    /// The vertex and the two edges.
    pub fn vertex_and_edges(&self) -> [Vec3; 3] {
        [self.p0, self.e1, self.e2]
    }
}

impl Triangles {
    pub const FLAT: u32 = u32::MAX;

    pub fn push(&mut self, p: [Vec3; 3], normals: Option<[Vec3; 3]>, material: u32) {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let degenerate = !(e1.cross(e2).length_squared() > 0.0);
        let (e1, e2) = if degenerate {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (e1, e2)
        };
        let shading = match normals {
            Some(n) => {
                self.vertex_normals.push(n);
                self.vertex_normals.len() as u32 - 1
            }
            None => Self::FLAT,
        };
        self.records.push(Triangle {
            p0: p[0],
            e1,
            e2,
            material,
            shading,
        });
    }

    /// Unit geometric normal `normalize(e1 x e2)`.
    pub fn geometric_normal(&self, i: usize) -> Vec3 {
        let triangle = &self.records[i];
        triangle.e1.cross(triangle.e2).normalize_or_zero()
    }

    /// [`Shapes::normal`] at `(u, v)`, with the geometric normal made by `geometric` only
    /// where it is needed, so that a caller holding `e1 x e2` need not take it again.
    fn shading_normal(&self, shading: u32, u: f32, v: f32, geometric: impl Fn() -> Vec3) -> Vec3 {
        match shading {
            Self::FLAT => geometric(),
            k => {
                let n = self.vertex_normals[k as usize];
                ((1.0 - u - v) * n[0] + u * n[1] + v * n[2])
                    .try_normalize()
                    .unwrap_or_else(geometric)
            }
        }
    }
}

impl LeafPack for Triangles {
    type Pack = TrianglePack8;

    fn pack(&self, indices: impl Iterator<Item = usize>) -> TrianglePack8 {
        let tris: Vec<[Vec3; 3]> = indices
            .map(|i| self.records[i].vertex_and_edges())
            .collect();
        TrianglePack8::new(&tris)
    }

    #[inline(always)]
    fn leaf(pack: &TrianglePack8, query: &RayQuery, t_max: f32) -> TriangleHit8 {
        leaf_hits(query, pack, t_max)
    }

    #[inline(always)]
    fn slot_packet(
        pack: &TrianglePack8,
        slot: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let triangle = [pack.p0.lane(slot), pack.e1.lane(slot), pack.e2.lane(slot)];
        let trusted = || pack.trusted_box(slot);
        packet_hits(
            query.packet,
            triangle,
            trusted,
            query.t_min_lanes(),
            t_max,
            active,
        )
    }
}

impl Shapes for Triangles {
    fn len(&self) -> usize {
        self.records.len()
    }

    fn material(&self, i: usize) -> u32 {
        self.records[i].material
    }

    fn bounds(&self, i: usize, _shutter: [f32; 2]) -> Aabb {
        corner_box(self.records[i].vertex_and_edges()).unwrap_or(Aabb::EMPTY)
    }

    #[inline]
    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<TriangleHit> {
        triangle_hit(
            &query.ray,
            self.records[i].vertex_and_edges(),
            query.t_min,
            t_max,
            || *query,
        )
    }

    fn intersect_packet(
        &self,
        i: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let [p0, e1, e2] = self.records[i].vertex_and_edges();
        triangle_packet(query.packet, p0, e1, e2, query.t_min_lanes(), t_max, active)
    }

    /// The geometric normal of P3F.md section 2 (triangles have no inside), or for smooth
    /// triangles the vertex normals interpolated at `(u, v)`.
    fn normal(&self, i: usize, _p: Vec3, u: f32, v: f32, _time: f32) -> Vec3 {
        self.shading_normal(self.records[i].shading, u, v, || self.geometric_normal(i))
    }

    /// `p0 + u e1 + v e2`, a point of the plane the test sees whatever `u` and `v` are. Its
    /// sum is off by `gamma(7)` of its terms, as pbrt-v4 bounds its triangles' points. A
    /// ray leaving it meets the plane again where Möller-Trumbore's triple product
    /// `e2 . ((o - p0) x e1)` has the wrong sign; that product is off by `gamma(5)` of
    /// `|o - p0| |e1| |e2|`, which is `|o - p0| / sin(angle between e1 and e2)` along the
    /// normal, so a sliver's bound grows with its skew.
    #[inline]
    fn surface_point(&self, i: usize, _ray: &Ray, _t: f32, u: f32, v: f32) -> SurfacePoint {
        let Triangle {
            p0,
            e1,
            e2,
            shading,
            ..
        } = self.records[i];
        let (along1, along2) = (u * e1, v * e2);
        let point = p0 + along1 + along2;
        // One cross product for the bound's area and the normal.
        let cross = e1.cross(e2);
        let area = cross.length();
        let skew = if area > 0.0 {
            e1.length() * e2.length() / area
        } else {
            1.0
        };
        let product = gamma(5) * skew * (along1 + along2).length();
        SurfacePoint {
            point,
            error: gamma(7) * (p0.abs() + along1.abs() + along2.abs()) + Vec3::splat(product),
            normal: self.shading_normal(shading, u, v, || cross.normalize_or_zero()),
        }
    }

    /// The flat triangles' points eight at a time; a smooth one's lane (vertex normals)
    /// is left to [`Shapes::surface_point`].
    fn surface_points8(&self, indices: [usize; 8], rays: &[Ray; 8], hits: &Hits8) -> SurfacePoint8 {
        let records = indices.map(|i| &self.records[i]);
        let field = |f: fn(&Triangle) -> Vec3| Vec3x8::from_lanes(records.map(f));
        let (p0, e1, e2) = (field(|r| r.p0), field(|r| r.e1), field(|r| r.e2));
        let (u, v) = (F32x8::from_array(hits.u), F32x8::from_array(hits.v));
        let (along1, along2) = (e1.scale(u), e2.scale(v));
        let point = p0 + along1 + along2;
        let cross = e1.cross(e2);
        let area = cross.length();
        let skew = area
            .gt(F32x8::ZERO)
            .select(e1.length() * e2.length() / area, F32x8::splat(1.0));
        let product = F32x8::splat(gamma(5)) * skew * (along1 + along2).length();
        let sum = p0.abs() + along1.abs() + along2.abs();
        let error = sum.scale(F32x8::splat(gamma(7))) + Vec3x8::from_components(product);
        // `normalize_or_zero`: the cross product over its length where that is a number.
        let rcp = F32x8::splat(1.0) / area;
        let normal =
            (rcp.is_finite() & rcp.gt(F32x8::ZERO)).select_vec(cross.scale(rcp), Vec3x8::ZERO);
        let mut points = SurfacePoint8 {
            point,
            error,
            normal,
        };
        for (k, record) in records.iter().enumerate() {
            if record.shading != Self::FLAT {
                let scalar =
                    self.surface_point(indices[k], &rays[k], hits.t[k], hits.u[k], hits.v[k]);
                points.set_lane(k, scalar);
            }
        }
        points
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P0: Vec3 = Vec3::new(0., 0., 0.);
    const E1: Vec3 = Vec3::new(1., 0., 0.);
    const E2: Vec3 = Vec3::new(0., 1., 0.);

    fn down_at(x: f32, y: f32) -> Ray {
        Ray::new(Vec3::new(x, y, 2.0), Vec3::new(0., 0., -1.))
    }

    #[test]
    fn a_pack_keeps_each_slots_trusted_box() {
        let max = Vec3::splat(f32::MAX);
        let triangles = [
            [P0, E1, E2],
            [
                Vec3::new(-3.0, 2.5, 1e-3),
                Vec3::new(1e-7, 0.0, 4.0),
                Vec3::new(-2.0, 1e-7, 0.0),
            ],
            [
                Vec3::splat(1e9),
                Vec3::new(-64.0, 128.0, 0.0),
                Vec3::new(0.0, 0.0, -1e3),
            ],
            [Vec3::new(0.0, -0.0, 5.0), Vec3::ZERO, Vec3::ZERO],
            // A corner beyond the floats (a vertex at `p0 + e1` of infinity): no box.
            [max, Vec3::new(f32::MAX, 0.0, 0.0), E2],
        ];
        let pack = TrianglePack8::new(&triangles);
        let bits =
            |b: Option<Aabb>| b.map(|b| [b.min, b.max].map(|c| c.to_array().map(f32::to_bits)));
        for (slot, &triangle) in triangles.iter().enumerate() {
            assert_eq!(
                bits(pack.trusted_box(slot)),
                bits(trusted_triangle_box(triangle))
            );
        }
        assert_eq!(pack.trusted_box(4), None);
        // The padding's slots hold the zero triangle, as an unused slot does.
        assert_eq!(
            bits(pack.trusted_box(7)),
            bits(trusted_triangle_box([Vec3::ZERO; 3]))
        );
    }

    #[test]
    fn hits_interior_with_barycentrics() {
        let h = triangle(&down_at(0.25, 0.5), P0, E1, E2, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
    }

    #[test]
    fn two_sided() {
        let up = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z);
        assert!((triangle(&up, P0, E1, E2, 0.0, 9.0).unwrap().t - 1.0).abs() < 1e-6);
    }

    #[test]
    fn edges_and_vertices_are_inside() {
        for (x, y) in [
            (0.5, 0.0),
            (0.0, 0.5),
            (0.5, 0.5),
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
        ] {
            assert!(
                triangle(&down_at(x, y), P0, E1, E2, 0.0, 9.0).is_some(),
                "({x}, {y}) should be on the triangle"
            );
        }
        for (x, y) in [(-1e-4, 0.5), (0.5, -1e-4), (0.5001, 0.5), (1.0001, 0.0)] {
            assert!(
                triangle(&down_at(x, y), P0, E1, E2, 0.0, 9.0).is_none(),
                "({x}, {y}) should be off the triangle"
            );
        }
    }

    #[test]
    fn parallel_ray_and_degenerate_triangle_miss() {
        let parallel = Ray::new(Vec3::new(-1., 0.2, 0.), Vec3::X);
        assert_eq!(triangle(&parallel, P0, E1, E2, 0.0, 9.0), None);
        assert_eq!(
            triangle(&down_at(0.0, 0.0), P0, Vec3::ZERO, Vec3::ZERO, 0.0, 9.0),
            None
        );
    }

    #[test]
    fn behind_and_beyond_are_misses() {
        let away = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::Z);
        assert_eq!(triangle(&away, P0, E1, E2, 0.0, 9.0), None);
        assert_eq!(triangle(&down_at(0.2, 0.2), P0, E1, E2, 0.0, 1.5), None);
    }
}
