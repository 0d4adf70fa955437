//! Every SIMD kernel against its scalar twin, lane for lane and bit for bit: the same hit
//! or miss and the same `t` (and `u`, `v`) bits, and the shading's light samples and
//! Blinn-Phong terms, on random primitives and rays that
//! include NaN, infinite and zero directions, origins inside primitives and in slab
//! planes, degenerate triangles, zero radii and random active masks. Inactive lanes and
//! padding slots must miss.

use std::cell::OnceCell;

use glam::{Vec2, Vec3};
use p3trace::intersect::{
    self, Aabb, BoxPack8, BoxRay, BoxRays, Boxes, Hits8, IntersectOptions, Intervals, MeshPack8,
    PackOf, PacketQuery, RayQuery, Rays8, Roots, ShapeHit, ShapeHit8, ShapeHits, Shapes, Shear,
    ShearLanes, SpherePack8, Spheres, SurfacePoint, SurfacePoint8, TrianglePack8, Triangles,
};
use p3trace::ray::{Ray, RayPacket};
use p3trace::render::camera::{Camera, FilmSample};
use p3trace::render::light::{Emitter, LightSample, Receiver, Rectangle};
use p3trace::render::sampler::{Sample, SampleGrid, SampleRng};
use p3trace::render::shade::{Bounce, Bounce8, Optics8, Phong, Phong8};
use p3trace::scene::{CameraSpec, Material};
use p3trace::simd::{
    table_code, table_halves, Bits, Codes8, F32x16, F32x8, F32xP, Floats, LaneBits, LaneMask,
    Mask8, Vec3x8, PACKET,
};
use proptest::prelude::*;

const NAN: f32 = f32::NAN;
const INF: f32 = f32::INFINITY;

/// Mostly ordinary values, often small integers (so that origins fall on the planes of
/// integer boxes), sometimes zeros of both signs, infinities and NaN.
fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => -6.0f32..6.0,
        3 => (-3i32..=3).prop_map(|i| i as f32),
        1 => prop::sample::select(vec![0.0, -0.0, NAN, INF, -INF, 1e-30, 1e30]),
    ]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Unit directions, axis-aligned ones (zero components: rays in slab planes), and the
/// degenerate ones: zero, NaN, infinite, not normalised.
fn direction() -> impl Strategy<Value = Vec3> {
    let unit = (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0)
        .prop_map(|(x, y, z)| Vec3::new(x, y, z).normalize_or(Vec3::X));
    let axis = prop::sample::select(vec![
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::new(1.0, 1.0, 0.0).normalize(),
        Vec3::new(0.0, -1.0, 1.0).normalize(),
        Vec3::new(-0.0, 0.0, -1.0),
    ]);
    let odd = prop::sample::select(vec![
        Vec3::ZERO,
        Vec3::NAN,
        Vec3::new(NAN, 0.0, 1.0),
        Vec3::new(INF, 0.0, 0.0),
        Vec3::new(3.0, -4.0, 0.5),
    ]);
    prop_oneof![6 => unit, 3 => axis, 1 => odd]
}

fn ray() -> impl Strategy<Value = Ray> {
    (point(), direction(), prop_oneof![Just(0.0f32), 0.0f32..1.0])
        .prop_map(|(origin, dir, time)| Ray { origin, dir, time })
}

/// A ray from up to 1e9 away aimed at a point near the origin: the triangle test's hits
/// from there often fall outside the box and are computed again in double precision.
fn far_ray() -> impl Strategy<Value = Ray> {
    (direction(), 1e3f32..1e9, point()).prop_map(|(from, distance, at)| {
        let origin = from * distance;
        Ray::new(origin, (at - origin).normalize_or_zero())
    })
}

/// The rays of the triangle tests: [`ray`], and [`far_ray`] now and then.
fn triangle_ray() -> impl Strategy<Value = Ray> {
    prop_oneof![3 => ray(), 1 => far_ray()]
}

/// An interval `(t_min, t_max)`, occasionally empty, infinite at both ends or NaN.
fn interval() -> impl Strategy<Value = (f32, f32)> {
    let lo = prop::sample::select(vec![0.0, 1e-4, -0.0, 2.0, -INF, -3.0, NAN]);
    let hi = prop::sample::select(vec![INF, 5.0, 100.0, 1e-4, 0.0, NAN]);
    (lo, hi)
}

fn radius() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => 0.0f32..4.0,
        1 => prop::sample::select(vec![0.0, -1.0, 1.0, 1000.0, NAN, INF]),
    ]
}

/// A box: usually ordered corners (often on integer planes), sometimes flat or inverted.
fn aabb() -> impl Strategy<Value = (Vec3, Vec3)> {
    (point(), point(), 0u8..4).prop_map(|(a, b, shape)| match shape {
        0 => (a, a),
        1 => (b, a),
        _ => (a.min(b), a.max(b)),
    })
}

/// Three vertices, degenerate now and then (all one point, on one line, or NaN, as
/// `Triangles` stores a degenerate one).
fn triangle() -> impl Strategy<Value = [Vec3; 3]> {
    (point(), point(), point(), 0u8..8).prop_map(|(p0, p1, p2, shape)| match shape {
        0 => [p0; 3],
        1 => [p0, p1, p1 + (p1 - p0)],
        2 => [Vec3::NAN; 3],
        _ => [p0, p1, p2],
    })
}

/// Up to eight triangles that fit in a mesh pack ([`MeshPack8::new`]): up to four of any
/// shape, or up to eight over at most eleven vertices, shared as a mesh's are. The storage
/// gives a degenerate triangle NaN corners (`Triangles::push`), a twelfth vertex.
fn pack_triangles() -> impl Strategy<Value = Vec<[Vec3; 3]>> {
    let vertex = prop_oneof![8 => point(), 1 => Just(Vec3::NAN)];
    let shared = (
        prop::collection::vec(vertex, 1..=11),
        prop::collection::vec(prop::array::uniform3(0usize..12), 0..=8),
    )
        .prop_map(|(pool, corners)| {
            (corners.iter())
                .map(|c| c.map(|i| pool[i % pool.len()]))
                .collect()
        });
    prop_oneof![prop::collection::vec(triangle(), 0..=4), shared]
}

/// Each slot of a leaf's `hits` against the scalar test of its triangle, the padding
/// slots against a miss.
fn leaf_equals_scalar(
    what: &str,
    triangles: &[[Vec3; 3]],
    ray: &Ray,
    (t_min, t_max): (f32, f32),
    hits: ShapeHit8,
) {
    for i in 0..8 {
        let scalar =
            (triangles.get(i)).and_then(|&tri| intersect::triangle(ray, tri, t_min, t_max));
        same(
            &format!("{what} t"),
            i,
            scalar.map(|h| h.t),
            hits.hit,
            hits.t,
        );
        same(
            &format!("{what} u"),
            i,
            scalar.map(|h| h.u),
            hits.hit,
            hits.u,
        );
        same(
            &format!("{what} v"),
            i,
            scalar.map(|h| h.v),
            hits.hit,
            hits.v,
        );
    }
}

#[derive(Clone, Debug)]
struct Packet {
    rays: [Ray; PACKET],
    t_min: [f32; PACKET],
    t_max: [f32; PACKET],
    active: LaneBits,
}

fn packet() -> impl Strategy<Value = Packet> {
    (
        prop::array::uniform(ray()),
        prop::array::uniform(interval()),
        any::<LaneBits>(),
    )
        .prop_map(|(rays, limits, active)| Packet {
            rays,
            t_min: limits.map(|l| l.0),
            t_max: limits.map(|l| l.1),
            active,
        })
}

/// Packets whose directions share lane 0's signs, as a tile's primary rays or one
/// light's shadow rays mostly do: the packets a `RayRange` is made for.
fn coherent_packet() -> impl Strategy<Value = Packet> {
    packet().prop_map(|mut p| {
        let signs = p.rays[0].dir;
        for ray in &mut p.rays {
            ray.dir = ray.dir.abs().copysign(signs);
        }
        p
    })
}

/// The packets of the triangle tests: [`packet`]s; or with every direction turned
/// cyclically to be longest along lane 0's longest axis, so that every lane takes one frame
/// in the watertight test; or moved back along their directions by up to 1e9 (as
/// [`far_ray`]s), every lane over `(0, inf)`. One strategy drawing one packet, not a union
/// of three: the union's value tree, three packets' worth, overflows a test thread's stack
/// at sixteen lanes.
fn triangle_packet() -> impl Strategy<Value = Packet> {
    (packet(), 0u8..4, 1e3f32..1e9).prop_map(|(mut p, kind, distance)| {
        match kind {
            0 => {
                let axis = p.rays[0].dir.abs().max_position();
                for ray in &mut p.rays {
                    let d = ray.dir.to_array();
                    let longest = ray.dir.abs().max_position();
                    ray.dir =
                        Vec3::from_array(std::array::from_fn(|k| d[(k + 3 + longest - axis) % 3]));
                }
            }
            1 => {
                for (k, ray) in p.rays.iter_mut().enumerate() {
                    ray.dir = ray.dir.normalize_or(Vec3::X);
                    ray.origin -= ray.dir * (distance / (k + 1) as f32);
                }
                (p.t_min, p.t_max) = ([0.0; PACKET], [INF; PACKET]);
            }
            _ => {}
        }
        p
    })
}

/// Whether the directions of the lanes `lanes` agree in sign on every axis.
fn same_signs(p: &Packet, lanes: LaneBits) -> bool {
    let mut signs = (0..PACKET)
        .filter(|&k| lanes.has(k))
        .map(|k| p.rays[k].dir.recip().cmpgt(Vec3::ZERO).bitmask());
    let first = signs.next();
    signs.all(|s| Some(s) == first)
}

impl Packet {
    fn soa(&self) -> (RayPacket<'_>, F32xP, F32xP, LaneBits) {
        (
            RayPacket::new(&self.rays),
            F32xP::from_array(self.t_min),
            F32xP::from_array(self.t_max),
            self.active,
        )
    }

    fn active(&self, lane: usize) -> bool {
        self.active.has(lane)
    }
}

/// Lane `lane` of a kernel's answer (of eight lanes or a packet's) equals the scalar
/// `expected` bit for bit.
fn same<F: Floats>(what: &str, lane: usize, expected: Option<f32>, hit: F::Mask, t: F) {
    let got = hit.bitmask().has(lane).then(|| t.lane(lane));
    assert_eq!(
        got.map(f32::to_bits),
        expected.map(f32::to_bits),
        "{what}, lane {lane}: kernel {got:?}, scalar {expected:?}"
    );
}

/// [`same`] for the entry and the exit of a box interval.
fn same_interval<F: Floats>(
    what: &str,
    lane: usize,
    expected: Option<(f32, f32)>,
    lanes: Intervals<F>,
) {
    same(
        &format!("{what} entry"),
        lane,
        expected.map(|i| i.0),
        lanes.hit,
        lanes.entry,
    );
    same(
        &format!("{what} exit"),
        lane,
        expected.map(|i| i.1),
        lanes.hit,
        lanes.exit,
    );
}

/// The lanes of `active` of an answer of the box tests, which answer every lane (their
/// callers keep the lanes they ask about).
fn within<F: Floats>(lanes: Intervals<F>, active: <F::Mask as LaneMask>::Bits) -> Intervals<F> {
    Intervals {
        hit: lanes.hit & F::Mask::from_bitmask(active),
        ..lanes
    }
}

/// The scalar answer, or a miss for a lane outside the active mask.
fn when(active: bool, answer: Option<f32>) -> Option<f32> {
    answer.filter(|_| active)
}

const CASES: u32 = 2000;

/// A storage of `triangles`, in their order.
fn triangle_storage(triangles: Vec<[Vec3; 3]>) -> Triangles {
    let mut storage = Triangles::default();
    for tri in triangles {
        storage.push(tri, None, 0);
    }
    storage
}

/// A packed kind's [`LeafPack`] against its scalar test (`Shapes::intersect`), bit for
/// bit: the leaf kernel, one ray within `(t_min, t_max)` against the pack of all of
/// `storage` (padding slots miss) in the ray's frame (as the walks call it), and each
/// slot against the lanes of `p` from `t_min`, as the pack holds it and as `storage` does
/// (`Shapes::intersect_packet`).
fn pack_equals_scalar<K: Shapes, P: PackOf<K>>(
    what: &str,
    storage: &K,
    ray: &Ray,
    (t_min, t_max): (f32, f32),
    p: &Packet,
    options: IntersectOptions,
) {
    let n = storage.len();
    let pack = P::pack(storage, 0..n).expect("the primitives fit in a pack");
    let query = RayQuery::new(ray, t_min, options);
    let hits = match intersect::frame_of(ray.dir) {
        0 => P::leaf::<0>(&pack, &query, t_max),
        1 => P::leaf::<1>(&pack, &query, t_max),
        _ => P::leaf::<2>(&pack, &query, t_max),
    };
    for slot in 0..8 {
        let scalar = (slot < n)
            .then(|| storage.intersect(slot, &query, t_max))
            .flatten();
        same_hit(&format!("{what} leaf"), slot, scalar, hits);
    }
    let (rays, _, hi, active) = p.soa();
    let rays = RayPacket { t_min, ..rays };
    let shear = OnceCell::new();
    let query = PacketQuery::new(&rays, options, &shear);
    for slot in 0..n {
        let in_pack = P::slot_packet(P::slots(&pack), slot, &query, hi, active);
        let in_storage = storage.intersect_packet(slot, &query, hi, active);
        for (k, ray) in p.rays.iter().enumerate() {
            let lane = RayQuery::new(ray, t_min, options);
            let scalar = storage
                .intersect(slot, &lane, p.t_max[k])
                .filter(|_| p.active(k));
            same_hit(&format!("{what} slot {slot}"), k, scalar, in_pack);
            same_hit(
                &format!("{what} {slot}, intersect_packet"),
                k,
                scalar,
                in_storage,
            );
        }
    }
}

/// [`same`] for `t`, `u` and `v`.
fn same_hit<F: Floats>(what: &str, lane: usize, expected: Option<ShapeHit>, hits: ShapeHits<F>) {
    same(
        &format!("{what} t"),
        lane,
        expected.map(|h| h.t),
        hits.hit,
        hits.t,
    );
    same(
        &format!("{what} u"),
        lane,
        expected.map(|h| h.u),
        hits.hit,
        hits.u,
    );
    same(
        &format!("{what} v"),
        lane,
        expected.map(|h| h.v),
        hits.hit,
        hits.v,
    );
}

/// Both forms of the sphere's quadratic.
fn roots() -> impl Strategy<Value = Roots> {
    prop_oneof![Just(Roots::Precise), Just(Roots::Textbook)]
}

/// The scalar sphere test of `roots`: the twin of the kernels.
fn scalar_sphere(roots: Roots, ray: &Ray, c: Vec3, r: f32, lo: f32, hi: f32) -> Option<f32> {
    match roots {
        Roots::Precise => intersect::sphere(ray, c, r, lo, hi),
        Roots::Textbook => intersect::sphere_textbook(ray, c, r, lo, hi),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn sphere_packet_equals_scalar(
        p in packet(),
        centre in point(),
        r in radius(),
        roots in roots(),
    ) {
        let (rays, t_min, t_max, active) = p.soa();
        let (hit, t) = intersect::sphere_packet(&rays, centre, r, roots, t_min, t_max, active);
        for (i, ray) in p.rays.iter().enumerate() {
            let scalar = scalar_sphere(roots, ray, centre, r, p.t_min[i], p.t_max[i]);
            same("sphere", i, when(p.active(i), scalar), hit, t);
        }
    }

    /// The packet kernel against the scalar test, for packets whose lanes take one frame
    /// (the shared frame's path) and for any.
    #[test]
    fn triangle_packet_equals_scalar(
        p in triangle_packet(),
        tri in triangle(),
    ) {
        let (rays, t_min, t_max, active) = p.soa();
        let rays = rays.with_active(active);
        let shear = OnceCell::new();
        let query = PacketQuery::new(&rays, IntersectOptions::default(), &shear);
        let hits = intersect::triangle_packet(&query, tri, t_min, t_max, active);
        for (i, ray) in p.rays.iter().enumerate() {
            let scalar = intersect::triangle(ray, tri, p.t_min[i], p.t_max[i])
                .filter(|_| p.active(i));
            same("triangle t", i, scalar.map(|h| h.t), hits.hit, hits.t);
            same("triangle u", i, scalar.map(|h| h.u), hits.hit, hits.u);
            same("triangle v", i, scalar.map(|h| h.v), hits.hit, hits.v);
        }
    }

    /// A packet's shears, lane by lane, are the rays' own, bit for bit, in the lanes it asks,
    /// and its lanes grouped by frame are grouped by each ray's frame.
    #[test]
    fn shear_lanes_equal_scalar(p in triangle_packet()) {
        let (rays, ..) = p.soa();
        let lanes = ShearLanes::new(&rays.with_active(p.active));
        let by_frame = lanes.lanes_by_frame();
        for (k, ray) in p.rays.iter().enumerate().filter(|&(k, _)| p.active(k)) {
            let query = RayQuery::new(ray, 0.0, IntersectOptions::default());
            let (lane, scalar) = (lanes.lane(k), Shear::of(&query));
            let frames = by_frame.map(|group| group >> k & 1);
            let mut own = [0; 3];
            own[intersect::frame_of(ray.dir)] = 1;
            prop_assert_eq!(frames, own, "lane {}: {:?}", k, ray);
            prop_assert_eq!(lane.axes(), scalar.axes(), "lane {}: {:?}", k, ray);
            prop_assert_eq!(
                lane.parts().map(bits3),
                scalar.parts().map(bits3),
                "lane {}: {:?}",
                k,
                ray
            );
        }
    }

    #[test]
    fn aabb_packet_equals_scalar(p in packet(), (lo, hi) in aabb()) {
        let (rays, t_min, t_max, active) = p.soa();
        let (hit, t) = intersect::aabb_packet(&rays, lo, hi, t_min, t_max, active);
        for (i, ray) in p.rays.iter().enumerate() {
            let scalar =
                intersect::aabb(ray, ray.dir.recip(), lo, hi, p.t_min[i], p.t_max[i]);
            same("aabb", i, when(p.active(i), scalar), hit, t);
        }
    }

    #[test]
    fn plane_packet_equals_scalar(p in packet(), normal in direction(), offset in coord()) {
        let (rays, t_min, t_max, active) = p.soa();
        let (hit, t) = intersect::plane_packet(&rays, normal, offset, t_min, t_max, active);
        for (i, ray) in p.rays.iter().enumerate() {
            let scalar = intersect::plane(ray, normal, offset, p.t_min[i], p.t_max[i]);
            same("plane", i, when(p.active(i), scalar), hit, t);
        }
    }

    #[test]
    fn cone_packet_equals_scalar(
        p in packet(),
        base in point(),
        axis in direction(),
        height in prop_oneof![4 => 0.1f32..4.0, 1 => prop::sample::select(vec![0.0, NAN, INF])],
        r_base in radius(),
        r_apex in prop_oneof![2 => radius(), 1 => Just(0.0f32)],
        cylinder in any::<bool>(),
    ) {
        let r_apex = if cylinder { r_base } else { r_apex };
        let (rays, t_min, t_max, active) = p.soa();
        let (hit, t) = intersect::cone_packet(
            &rays, base, axis, height, r_base, r_apex, t_min, t_max, active,
        );
        for (i, ray) in p.rays.iter().enumerate() {
            let scalar = intersect::cone(
                ray, base, axis, height, r_base, r_apex, p.t_min[i], p.t_max[i],
            );
            same("cone", i, when(p.active(i), scalar), hit, t);
        }
    }

    #[test]
    fn box_interval_packet_equals_scalar(p in packet(), (lo, hi) in aabb()) {
        let (rays, t_min, t_max, active) = p.soa();
        let lanes = within(BoxRays::new(&rays).interval(lo, hi, t_min, t_max), active);
        for (i, ray) in p.rays.iter().enumerate() {
            let scalar = BoxRay::new(ray.origin, ray.dir.recip())
                .interval(lo, hi, p.t_min[i], p.t_max[i])
                .filter(|_| p.active(i));
            same_interval("box interval packet", i, scalar, lanes);
        }
    }

    #[test]
    fn sphere_leaf_equals_scalar(
        ray in ray(),
        (t_min, t_max) in interval(),
        spheres in prop::collection::vec((point(), radius()), 0..=8),
        roots in roots(),
    ) {
        let pack = SpherePack8::new(&spheres);
        let (hit, t) = intersect::sphere_leaf(&ray, &pack, roots, t_min, t_max);
        for i in 0..8 {
            let scalar = spheres
                .get(i)
                .and_then(|&(c, r)| scalar_sphere(roots, &ray, c, r, t_min, t_max));
            same("sphere leaf", i, scalar, hit, t);
        }
    }

    #[test]
    fn triangle_leaf_equals_scalar(
        ray in triangle_ray(),
        (t_min, t_max) in interval(),
        triangles in prop::collection::vec(triangle(), 0..=8),
    ) {
        let pack = TrianglePack8::new(&triangles);
        let hits = intersect::triangle_leaf(&ray, &pack, t_min, t_max);
        leaf_equals_scalar("triangle leaf", &triangles, &ray, (t_min, t_max), hits);
    }

    #[test]
    fn mesh_leaf_equals_scalar(
        ray in triangle_ray(),
        (t_min, t_max) in interval(),
        triangles in prop_oneof![prop::collection::vec(triangle(), 0..=8), pack_triangles()],
    ) {
        // A pack holds the triangles where they share at most twelve vertices.
        let mut distinct: Vec<[u32; 3]> = triangles
            .iter()
            .flatten()
            .map(|v| v.to_array().map(f32::to_bits))
            .collect();
        distinct.sort_unstable();
        distinct.dedup();
        let Some(pack) = MeshPack8::new(&triangles) else {
            prop_assert!(distinct.len() > 12, "{} vertices refused", distinct.len());
            return Ok(());
        };
        prop_assert!(distinct.len() <= 12);
        let hits = intersect::mesh_leaf(&ray, &pack, t_min, t_max);
        leaf_equals_scalar("mesh leaf", &triangles, &ray, (t_min, t_max), hits);
    }

    #[test]
    fn table_pick_equals_scalar(
        table in prop::array::uniform12(coord()),
        entries in prop::array::uniform8(0usize..12),
    ) {
        let codes = Codes8::new(&entries.map(table_code));
        let (low, high) = table_halves(&table);
        let (simd, scalar) = (codes.pick(low, high), codes.pick_lanes(low, high));
        for k in 0..8 {
            prop_assert_eq!(simd.lane(k).to_bits(), scalar.lane(k).to_bits(), "lane {}", k);
            prop_assert_eq!(scalar.lane(k).to_bits(), table[entries[k]].to_bits());
        }
    }

    #[test]
    fn sphere_pack_equals_scalar(
        ray in ray(),
        limits in interval(),
        p in packet(),
        spheres in prop::collection::vec((point(), radius()), 0..=8),
        roots in roots(),
        roots_margin in prop_oneof![Just(0.0f32), 0.0f32..4.0],
    ) {
        let mut storage = Spheres::default();
        for (centre, r) in spheres {
            storage.push(centre, r, 0);
        }
        let options = IntersectOptions {
            roots,
            roots_margin,
        };
        pack_equals_scalar::<_, SpherePack8>("sphere pack", &storage, &ray, limits, &p, options);
    }

    #[test]
    fn triangle_pack_equals_scalar(
        ray in triangle_ray(),
        limits in interval(),
        p in triangle_packet(),
        triangles in prop::collection::vec(triangle(), 0..=8),
    ) {
        let storage = triangle_storage(triangles);
        let options = IntersectOptions::default();
        pack_equals_scalar::<_, TrianglePack8>("triangle pack", &storage, &ray, limits, &p, options);
    }

    #[test]
    fn mesh_pack_equals_scalar(
        ray in triangle_ray(),
        limits in interval(),
        p in triangle_packet(),
        triangles in pack_triangles(),
    ) {
        let storage = triangle_storage(triangles);
        let options = IntersectOptions::default();
        pack_equals_scalar::<_, MeshPack8>("mesh pack", &storage, &ray, limits, &p, options);
    }

    #[test]
    fn box_pack_equals_scalar(
        ray in ray(),
        limits in interval(),
        p in packet(),
        boxes in prop::collection::vec(aabb(), 0..=8),
    ) {
        let mut storage = Boxes::default();
        for (lo, hi) in boxes {
            storage.min.push(lo);
            storage.max.push(hi);
            storage.material.push(0);
        }
        let options = IntersectOptions::default();
        pack_equals_scalar::<_, BoxPack8>("box pack", &storage, &ray, limits, &p, options);
    }

    #[test]
    fn aabb_leaf_equals_scalar(
        ray in ray(),
        (t_min, t_max) in interval(),
        boxes in prop::collection::vec(aabb(), 0..=8),
    ) {
        let inv_dir = ray.dir.recip();
        let pack = BoxPack8::new(&boxes);
        let (hit, t) = intersect::aabb_leaf(&ray, inv_dir, &pack, t_min, t_max);
        for i in 0..8 {
            let scalar = boxes
                .get(i)
                .and_then(|&(lo, hi)| intersect::aabb(&ray, inv_dir, lo, hi, t_min, t_max));
            same("aabb leaf", i, scalar, hit, t);
        }
    }

    #[test]
    fn box_intervals8_equal_scalar(
        ray in ray(),
        (t_min, t_max) in interval(),
        boxes in prop::collection::vec(aabb(), 0..=8),
        active in any::<u8>(),
    ) {
        let box_ray = BoxRay::new(ray.origin, ray.dir.recip());
        let pack = BoxPack8::new(&boxes);
        // Padding slots are left out of the mask, as a node with fewer children would.
        let present = ((1u16 << boxes.len()) - 1) as u8;
        let lanes = within(box_ray.intervals8(&pack, t_min, t_max), active & present);
        for i in 0..8 {
            let scalar = boxes
                .get(i)
                .filter(|_| active >> i & 1 == 1)
                .and_then(|&(lo, hi)| box_ray.interval(lo, hi, t_min, t_max));
            same_interval("box intervals8", i, scalar, lanes);
        }
    }

    /// The hit rule's box test, one ray against eight boxes, eight rays against one and
    /// eight rays against eight boxes, lane by lane `BoxRay::holds`; and the last's
    /// intervals, `BoxRay::interval`.
    #[test]
    fn box_holds_equal_scalar(
        p in packet(),
        boxes in prop::collection::vec(aabb(), 1..=8),
        hits in prop::array::uniform::<_, PACKET>(coord()),
    ) {
        let (rays, t_min, _, _) = p.soa();
        let ray = BoxRay::new(p.rays[0].origin, p.rays[0].dir.recip());
        let eight = F32x8::from_fn(|k| hits[k]);
        let one_ray = ray.holds8(&BoxPack8::new(&boxes), p.t_min[0], eight).bitmask();
        let (lo, hi) = boxes[0];
        let one_box = BoxRays::new(&rays).holds(lo, hi, t_min, F32xP::from_array(hits)).bitmask();
        for (k, &hit) in hits.iter().enumerate() {
            if let Some(&(lo, hi)) = boxes.get(k) {
                let scalar = ray.holds(lo, hi, p.t_min[0], hit);
                prop_assert_eq!(one_ray >> k & 1 == 1, scalar, "one ray, box {}", k);
            }
            let lane = BoxRay::new(p.rays[k].origin, p.rays[k].dir.recip());
            let scalar = lane.holds(lo, hi, p.t_min[k], hit);
            prop_assert_eq!(one_box >> k & 1 == 1, scalar, "one box, ray {}", k);
        }
        // Eight rays against eight boxes, ray k against box k.
        let eight_boxes: [(Vec3, Vec3); 8] = std::array::from_fn(|k| boxes[k % boxes.len()]);
        let origin = Vec3x8::from_fn(|k| p.rays[k].origin);
        let inv_dir = Vec3x8::from_fn(|k| p.rays[k].dir.recip());
        let lanes = intersect::holds_lanes8(
            origin, inv_dir, &BoxPack8::new(&eight_boxes), p.t_min[0], eight,
        ).bitmask();
        let pack = BoxPack8::new(&eight_boxes);
        let intervals = intersect::intervals_lanes8(origin, inv_dir, &pack, p.t_min[0]);
        for (k, &(lo, hi)) in eight_boxes.iter().enumerate() {
            let lane = BoxRay::new(p.rays[k].origin, p.rays[k].dir.recip());
            let scalar = lane.holds(lo, hi, p.t_min[0], hits[k]);
            prop_assert_eq!(lanes >> k & 1 == 1, scalar, "ray and box {}", k);
            // The interval itself, where it is not empty.
            let interval = lane.interval(lo, hi, p.t_min[0], f32::INFINITY);
            let hit = intervals.hit.bitmask() >> k & 1 == 1;
            prop_assert_eq!(hit, interval.is_some(), "interval of ray and box {}", k);
            if let Some((entry, exit)) = interval {
                let bits = (intervals.entry.lane(k).to_bits(), intervals.exit.lane(k).to_bits());
                prop_assert_eq!(bits, (entry.to_bits(), exit.to_bits()), "ray and box {}", k);
            }
        }
    }

    /// The spheres' `Shapes::hits8` (eight rays against eight spheres, lane by lane) and
    /// `Shapes::hits_one8` (against one) against `Shapes::intersect`: both root forms,
    /// with and without the margin.
    #[test]
    fn sphere_hits8_equal_scalar(
        rays in prop::array::uniform8(ray()),
        spheres in prop::collection::vec((point(), radius()), 1..=8),
        order in prop::array::uniform8(0usize..8),
        t_min in prop::sample::select(vec![0.0f32, 1e-4]),
        t_max in prop::array::uniform8(prop_oneof![Just(INF), 0.0f32..12.0, Just(NAN)]),
        roots in roots(),
        roots_margin in prop_oneof![Just(0.0f32), 0.0f32..4.0],
    ) {
        let mut storage = Spheres::default();
        for &(centre, r) in &spheres {
            storage.push(centre, r, 0);
        }
        let options = IntersectOptions { roots, roots_margin };
        let indices = order.map(|i| i % spheres.len());
        let lanes = Rays8 {
            origin: Vec3x8::from_fn(|k| rays[k].origin),
            dir: Vec3x8::from_fn(|k| rays[k].dir),
            time: F32x8::from_fn(|k| rays[k].time),
        };
        let (hit, t) =
            storage.hits8(indices, &lanes, t_min, F32x8::from_fn(|k| t_max[k]), options);
        // And sphere `indices[0]` against every lane.
        let (one_hit, one_t) =
            storage.hits_one8(indices[0], (&lanes, lanes.dir.recip()), t_min, F32x8::from_fn(|k| t_max[k]), options);
        for k in 0..8 {
            let query = RayQuery::new(&rays[k], t_min, options);
            let scalar = storage.intersect(indices[k], &query, t_max[k]).map(|h| h.t.to_bits());
            let lane = (hit.bitmask() >> k & 1 == 1).then(|| t.lane(k).to_bits());
            prop_assert_eq!(lane, scalar, "lane {}: {:?}", k, rays[k]);
            let scalar = storage.intersect(indices[0], &query, t_max[k]).map(|h| h.t.to_bits());
            let lane = (one_hit.bitmask() >> k & 1 == 1).then(|| one_t.lane(k).to_bits());
            prop_assert_eq!(lane, scalar, "one sphere, lane {}: {:?}", k, rays[k]);
        }
    }

    /// `BoxPack8::trusted` against `trusted_box`, box by box, on corners that are not
    /// NaN (a routine's hits have none).
    #[test]
    fn trusted_boxes_equal_scalar(
        boxes in prop::collection::vec(aabb(), 8..=8),
        margin in prop_oneof![Just(0.0f32), 0.0f32..4.0],
    ) {
        let (trusted, some) = BoxPack8::new(&boxes).trusted(margin);
        for (k, &(min, max)) in boxes.iter().enumerate() {
            if min.is_nan() || max.is_nan() {
                continue;
            }
            let scalar = intersect::trusted_box(Aabb { min, max }, margin);
            prop_assert_eq!(some.bitmask() >> k & 1 == 1, scalar.is_some(), "box {}", k);
            if let Some(b) = scalar {
                let lane = (trusted.min.lane(k), trusted.max.lane(k));
                prop_assert_eq!(bits3(lane.0), bits3(b.min), "min of box {}", k);
                prop_assert_eq!(bits3(lane.1), bits3(b.max), "max of box {}", k);
            }
        }
    }

    /// A packet's `RayRange` (its traceable active lanes, as a traversal makes it) never
    /// rejects a box that the box test lets one of those lanes into: the range may only
    /// cull boxes every lane misses. Its entry lies below every such lane's, so that a
    /// walk sorting and skipping by it keeps every box a lane needs.
    #[test]
    fn ray_range_keeps_every_box_a_lane_enters(
        p in coherent_packet(),
        (lo, hi) in aabb().prop_filter("ordered corners", |(lo, hi)| lo.cmple(*hi).all()),
    ) {
        let (rays, _, t_max, active) = p.soa();
        let lanes = active & rays.traceable();
        let t_min = F32xP::splat(p.t_min[0]);
        let box_rays = BoxRays::new(&rays);
        let intervals = box_rays.interval(lo, hi, t_min, t_max);
        let entered = intervals.hit.bitmask() & lanes;
        let Some(range) = box_rays.range(lanes) else {
            // Only lanes of mixed signs, or none, have no range.
            prop_assert!(lanes == 0 || !same_signs(&p, lanes));
            return Ok(());
        };
        let largest = (0..PACKET)
            .filter(|&k| lanes.has(k))
            .fold(f32::NEG_INFINITY, |m, k| m.max(p.t_max[k]));
        if entered != 0 {
            let entry = range.entry(lo, hi, p.t_min[0], largest);
            prop_assert!(entry.is_some(), "lanes {entered:b} enter");
            let entries = intervals.entry.to_array();
            for k in (0..PACKET).filter(|&k| entered.has(k)) {
                prop_assert!(entry.unwrap() <= entries[k], "lane {k} enters at {}", entries[k]);
            }
        }
    }

    /// `RayRange::entries8` answers each slot as `RayRange::entry`, bit for bit, padding
    /// and odd boxes included.
    #[test]
    fn ray_range_entries8_equals_scalar(
        p in coherent_packet(),
        boxes in prop::collection::vec(aabb(), 0..=8),
        (t_min, t_max) in interval(),
    ) {
        let (rays, .., active) = p.soa();
        let Some(range) = BoxRays::new(&rays).range(active & rays.traceable()) else {
            return Ok(());
        };
        let pack = BoxPack8::new(&boxes);
        let (lanes, entries) = range.entries8(&pack, t_min, t_max);
        for (k, lane_entry) in entries.into_iter().enumerate() {
            let (lo, hi) = boxes.get(k).copied().unwrap_or((BoxPack8::PAD, BoxPack8::PAD));
            let scalar = range.entry(lo, hi, t_min, t_max);
            prop_assert_eq!(lanes >> k & 1 == 1, scalar.is_some(), "slot {}", k);
            if let Some(entry) = scalar {
                prop_assert_eq!(lane_entry.to_bits(), entry.to_bits(), "slot {}", k);
            }
        }
    }

    /// `min_lane` and `max_lane` give what a fold of `f32::min` or `f32::max` over the
    /// lanes gives, wherever no lane is NaN (a zero of either sign where they tie).
    #[test]
    fn min_and_max_lane_equal_a_fold(
        lanes in prop::array::uniform16(coord().prop_filter("no NaN", |t| !t.is_nan())),
    ) {
        let sixteen = F32x16::from_array(lanes);
        prop_assert_eq!(sixteen.min_lane(), lanes.iter().copied().fold(INF, f32::min));
        prop_assert_eq!(sixteen.max_lane(), lanes.iter().copied().fold(-INF, f32::max));
        let eight = F32x8::from_fn(|k| lanes[k]);
        prop_assert_eq!(eight.min_lane(), lanes[..8].iter().copied().fold(INF, f32::min));
        prop_assert_eq!(eight.max_lane(), lanes[..8].iter().copied().fold(-INF, f32::max));
    }

    /// `beyond_lanes` answers each lane as `beyond`.
    #[test]
    fn beyond_lanes_equals_scalar(entry in coord(), limits in prop::array::uniform::<_, PACKET>(coord())) {
        let lanes = intersect::beyond_lanes(F32xP::splat(entry), F32xP::from_array(limits)).bitmask();
        for (k, &limit) in limits.iter().enumerate() {
            prop_assert_eq!(lanes.has(k), intersect::beyond(entry, limit), "lane {}", k);
        }
    }

    /// `Camera::rays8` makes each lane's primary ray as `Camera::ray` does, bit for bit
    /// (any NaN as any other: a degenerate camera's rays are untraceable either way), for
    /// pinholes and thin lenses, film points on and off the image, random times.
    #[test]
    fn camera_rays8_equal_scalar(
        (from, at, up) in (point(), point(), direction()),
        (angle, aperture, focal) in (1.0f32..179.0, prop_oneof![Just(0.0f32), 0.0f32..20.0], 0.1f32..10.0),
        (width, height) in (1u32..2000, 1u32..2000),
        films in prop::collection::vec(((-10.0f32..2010.0, -10.0f32..2010.0), (-1.0f32..1.0, -1.0f32..1.0), coord()), 8),
    ) {
        let spec = CameraSpec { from, at, up, angle, aperture, focal, width, height, ..CameraSpec::default() };
        let camera = Camera::new(&spec, width, height);
        let samples: [FilmSample; 8] = std::array::from_fn(|k| {
            let ((sx, sy), (lx, ly), time) = films[k];
            FilmSample { sx, sy, lens: Vec2::new(lx, ly), time }
        });
        let bits = |r: &Ray| {
            [r.origin.to_array(), r.dir.to_array(), [r.time; 3]]
                .map(|v| v.map(|x| if x.is_nan() { f32::NAN.to_bits() } else { x.to_bits() }))
        };
        let rays = camera.rays8(|k| &samples[k]);
        for (k, s) in samples.iter().enumerate() {
            let (ray, scalar) = (rays.ray(k), camera.ray(s));
            prop_assert_eq!(bits(&ray), bits(&scalar), "lane {}: {:?} against {:?}", k, ray, scalar);
        }
    }

    /// `RayPacket::traceable` answers each lane as `Ray::is_traceable`, odd rays included.
    #[test]
    fn traceable_lanes_equal_scalar(p in packet()) {
        let (packet, ..) = p.soa();
        let lanes = packet.traceable();
        for (k, ray) in p.rays.iter().enumerate() {
            prop_assert_eq!(lanes >> k & 1 == 1, ray.is_traceable(), "lane {}: {:?}", k, ray);
        }
    }

    /// The padding of each pack misses every ray: a pack with no real primitive never hits.
    #[test]
    fn padding_is_inert(ray in ray(), (t_min, t_max) in interval()) {
        let inv_dir = ray.dir.recip();
        let spheres = intersect::sphere_leaf(&ray, &SpherePack8::new(&[]), Roots::Precise, t_min, t_max).0;
        let triangles = intersect::triangle_leaf(&ray, &TrianglePack8::new(&[]), t_min, t_max);
        let empty_mesh = MeshPack8::new(&[]).expect("no triangle fits");
        let mesh = intersect::mesh_leaf(&ray, &empty_mesh, t_min, t_max);
        let boxes = intersect::aabb_leaf(&ray, inv_dir, &BoxPack8::new(&[]), t_min, t_max).0;
        prop_assert!(spheres.none() && triangles.hit.none() && mesh.hit.none() && boxes.none());
        // The same slots through the scalar routines.
        prop_assert!(intersect::sphere(&ray, Vec3::ZERO, SpherePack8::PAD_RADIUS, t_min, t_max).is_none());
        prop_assert!(intersect::triangle(&ray, [Vec3::NAN; 3], t_min, t_max).is_none());
        prop_assert!(intersect::aabb(&ray, inv_dir, BoxPack8::PAD, BoxPack8::PAD, t_min, t_max).is_none());
    }
}

/// Why a node's padding children stay out of its `active` mask: the NaN corners of
/// [`BoxPack8::PAD`], which the primitive test never hits, are slabs that the structures'
/// box test ignores, as it ignores the NaN slab of a ray lying in a face's plane.
#[test]
fn padding_is_inert_for_the_primitive_test_only() {
    let ray = Ray::new(Vec3::new(0.5, 0.5, 0.5), Vec3::new(1.0, 2.0, 2.0) / 3.0);
    let box_ray = BoxRay::new(ray.origin, ray.dir.recip());
    assert!(box_ray
        .interval(BoxPack8::PAD, BoxPack8::PAD, 0.0, INF)
        .is_some());
    let pack = BoxPack8::new(&[]);
    assert!(box_ray.intervals8(&pack, 0.0, INF).hit.all());
    let (hit, _) = intersect::aabb_leaf(&ray, ray.dir.recip(), &pack, 0.0, INF);
    assert!(hit.none());
}

/// The bits of a number, every NaN as one: comparisons tell `-0.0` from `0.0`, not one
/// NaN from another, whose sign and payload hang on the order in which the compiler puts
/// a commutative operation's operands (a NaN direction is untraceable, a NaN colour
/// clamps the same, whatever its bits).
fn bits(x: f32) -> u32 {
    if x.is_nan() {
        f32::NAN.to_bits()
    } else {
        x.to_bits()
    }
}

/// [`bits`] of each component.
fn bits3(v: Vec3) -> [u32; 3] {
    v.to_array().map(bits)
}

fn sample_of(seed: u64) -> Sample {
    Sample {
        rng: SampleRng::new(seed as u32, 3, seed),
        cell: [(seed % 3) as u32, (seed % 2) as u32],
        grid: SampleGrid {
            columns: 3,
            rows: 2,
        },
    }
}

/// A point light, or a rectangle sampled at each lane's own point.
fn emitter() -> impl Strategy<Value = Emitter> {
    let colour = (0.0f32..2.0, 0.0f32..2.0, 0.0f32..2.0).prop_map(|(r, g, b)| Vec3::new(r, g, b));
    prop_oneof![
        (point(), colour.clone())
            .prop_map(|(position, colour)| { Emitter::Point(LightSample { position, colour }) }),
        (point(), direction(), direction(), colour).prop_map(|(centre, across, up, colour)| {
            Emitter::Rectangle(Rectangle {
                centre,
                across,
                up,
                colour,
            })
        }),
    ]
}

/// Materials as the spawn step reads them: opaque or transmissive, with and without a
/// mirror term, indices of refraction around and below 1 (rays leaving a denser medium).
fn material() -> impl Strategy<Value = Material> {
    let colour = (0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0).prop_map(|(r, g, b)| Vec3::new(r, g, b));
    let ks = prop_oneof![Just(0.0f32), 0.0f32..1.0];
    let transmittance = prop_oneof![Just(0.0f32), Just(1.0f32), 0.0f32..1.0];
    let ior = prop_oneof![Just(1.0f32), 0.5f32..2.5];
    (colour.clone(), colour, ks, transmittance, ior).prop_map(
        |(diffuse, specular, ks, transmittance, ior)| Material {
            diffuse,
            kd: 0.5,
            specular,
            ks,
            shine: 20.0,
            transmittance,
            ior,
        },
    )
}

/// Blinn-Phong terms, with exponents that are integers, fractions, zero, large and
/// negative, and specular terms that are sometimes zero (a matte floor).
fn phong() -> impl Strategy<Value = Phong> {
    let colour = (0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0).prop_map(|(r, g, b)| Vec3::new(r, g, b));
    let shine = prop_oneof![
        3 => 0.0f32..200.0,
        1 => prop::sample::select(vec![0.0, 1.0, 20.0, 100.0, 1e4, 1e30, -2.0]),
    ];
    let specular = prop_oneof![3 => colour.clone(), 1 => Just(Vec3::ZERO), 1 => Just(Vec3::new(0.0, -0.0, 0.0))];
    (colour, specular, shine).prop_map(|(diffuse, specular, shine)| Phong {
        diffuse,
        specular,
        shine,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// `Emitter::sample8` against `Emitter::sample` on each lane's receiver.
    #[test]
    fn light_sample8_equals_scalar(
        emitter in emitter(),
        index in 0usize..3,
        points in prop::array::uniform8(point()),
        normals in prop::array::uniform8(direction()),
        origins in prop::array::uniform8(point()),
        seed in any::<u64>(),
    ) {
        let samples: [Sample; 8] = std::array::from_fn(|k| sample_of(seed.wrapping_add(k as u64)));
        let receiver8 = Receiver {
            point: Vec3x8::from_lanes(points),
            normal: Vec3x8::from_lanes(normals),
            origin: Vec3x8::from_lanes(origins),
        };
        let (facing, incident) = emitter.sample8(index, &receiver8, |k| samples[k]);
        for k in 0..8 {
            let receiver = Receiver { point: points[k], normal: normals[k], origin: origins[k] };
            let scalar = emitter.sample(index, &receiver, &samples[k]);
            prop_assert_eq!(facing.bitmask() >> k & 1 == 1, scalar.is_some(), "lane {}", k);
            if let Some(scalar) = scalar {
                prop_assert_eq!(bits3(incident.dir.lane(k)), bits3(scalar.dir), "lane {}", k);
                prop_assert_eq!(bits(incident.distance.lane(k)), bits(scalar.distance));
                prop_assert_eq!(emitter.colour(), scalar.colour);
            }
        }
    }

    /// `spawn_origin8` against `spawn_origin`, with sides that are unit normals, axes (zero
    /// components), NaN and infinite, and error bounds of zero.
    #[test]
    fn spawn_origin8_equals_scalar(
        points in prop::array::uniform8(point()),
        errors in prop::array::uniform8(prop_oneof![
            3 => (0.0f32..1e-3, 0.0f32..1e-3, 0.0f32..1e-3).prop_map(|(x, y, z)| Vec3::new(x, y, z)),
            1 => Just(Vec3::ZERO),
        ]),
        sides in prop::array::uniform8(direction()),
    ) {
        let got = intersect::spawn_origin8(
            Vec3x8::from_lanes(points),
            Vec3x8::from_lanes(errors),
            Vec3x8::from_lanes(sides),
        );
        for k in 0..8 {
            let scalar = intersect::spawn_origin(points[k], errors[k], sides[k]);
            prop_assert_eq!(bits3(got.lane(k)), bits3(scalar), "lane {}", k);
        }
    }

    /// `Phong8::light` against `Phong::light` in the lanes it is asked for, with each
    /// lane's own material or all lanes on one.
    #[test]
    fn phong8_equals_scalar(
        materials in prop::array::uniform8(phong()),
        shared in any::<bool>(),
        normals in prop::array::uniform8(direction()),
        dirs in prop::array::uniform8(direction()),
        lights in prop::array::uniform8(direction()),
        colour in point(),
        lit in any::<u8>(),
    ) {
        let lanes: [&Phong; 8] = std::array::from_fn(|k| &materials[if shared { 0 } else { k }]);
        let phong8 = Phong8::new(lanes);
        let (nf, dir, l) = (
            Vec3x8::from_lanes(normals),
            Vec3x8::from_lanes(dirs),
            Vec3x8::from_lanes(lights),
        );
        let got = phong8.light(nf, dir, l, colour, Mask8::from_bitmask(lit));
        for k in (0..8).filter(|k| lit >> k & 1 == 1) {
            let scalar = lanes[k].light(normals[k], dirs[k], lights[k], colour);
            prop_assert_eq!(bits3(got.lane(k)), bits3(scalar), "lane {}", k);
        }
    }

    /// `Bounce8::new` against `Bounce::new`, lane by lane and bit for bit, for each lane's
    /// own material or all lanes on one, both reflectance models, from either side.
    #[test]
    fn bounce8_equals_scalar(
        materials in prop::array::uniform8(material()),
        shared in any::<bool>(),
        dirs in prop::array::uniform8(direction()),
        normals in prop::array::uniform8(direction()),
        inside in any::<u8>(),
        ior_here in prop::array::uniform8(prop_oneof![Just(1.0f32), 0.5f32..2.5]),
        schlick in any::<bool>(),
    ) {
        let lanes: [&Material; 8] = std::array::from_fn(|k| &materials[if shared { 0 } else { k }]);
        let got = Bounce8::new(
            Vec3x8::from_lanes(dirs),
            Vec3x8::from_lanes(normals),
            Mask8::from_bitmask(inside),
            F32x8::from_array(ior_here),
            &Optics8::new(lanes),
            schlick,
        );
        for k in 0..8 {
            let scalar = Bounce::new(dirs[k], normals[k], inside >> k & 1 == 1, ior_here[k], lanes[k], schlick);
            let reflected = (got.reflected.bitmask() >> k & 1 == 1)
                .then(|| (bits3(got.mirror.lane(k)), bits3(got.reflected_weight.lane(k))));
            let expected = scalar.reflected.map(|(d, w)| (bits3(d), bits3(w)));
            prop_assert_eq!(reflected, expected, "reflected, lane {}", k);
            let transmitted = (got.transmitted.bitmask() >> k & 1 == 1).then(|| {
                let lane = |v: &Vec3x8| bits3(v.lane(k));
                (lane(&got.refracted), lane(&got.transmitted_weight), bits(got.ior_next.lane(k)))
            });
            let expected = scalar.transmitted.map(|(d, w, ior)| (bits3(d), bits3(w), bits(ior)));
            prop_assert_eq!(transmitted, expected, "transmitted, lane {}", k);
        }
    }

    /// Triangles' and spheres' `surface_points8` against `surface_point`, lane by lane and
    /// bit for bit: flat and smooth triangles, degenerate ones, barycentrics in and out of
    /// the triangle; spheres hit anywhere along random rays, at their centre too.
    #[test]
    fn surface_points8_equal_scalar(
        triangles in prop::array::uniform8(triangle()),
        smooth in any::<u8>(),
        normals in prop::array::uniform8(direction()),
        centres in prop::array::uniform8(point()),
        radii in prop::array::uniform8(radius()),
        rays in prop::array::uniform8(ray()),
        t in prop::array::uniform8(prop_oneof![3 => 0.0f32..10.0, 1 => Just(0.0f32)]),
        u in prop::array::uniform8(prop_oneof![3 => 0.0f32..1.0, 1 => -1.0f32..2.0]),
        v in prop::array::uniform8(prop_oneof![3 => 0.0f32..1.0, 1 => -1.0f32..2.0]),
        order in Just([3usize, 0, 7, 7, 1, 5, 2, 4]),
    ) {
        let mut tris = Triangles::default();
        let mut spheres = Spheres::default();
        for k in 0..8 {
            let smooth = (smooth >> k & 1 == 1).then(|| [normals[k], normals[(k + 1) % 8], normals[(k + 2) % 8]]);
            tris.push(triangles[k], smooth, 0);
            spheres.push(centres[k], radii[k], 0);
        }
        let hits = Hits8 { t, u, v };
        let check = |name: &str, got: SurfacePoint8, lane: &dyn Fn(usize) -> SurfacePoint| {
            for k in 0..8 {
                let (g, e) = (got.lane(k), lane(k));
                assert_eq!(
                    [bits3(g.point), bits3(g.error), bits3(g.normal)],
                    [bits3(e.point), bits3(e.error), bits3(e.normal)],
                    "{name}, lane {k}: {g:?} against {e:?}"
                );
            }
        };
        check("triangles", tris.surface_points8(order, &rays, &hits), &|k| {
            tris.surface_point(order[k], &rays[k], t[k], u[k], v[k])
        });
        check("spheres", spheres.surface_points8(order, &rays, &hits), &|k| {
            spheres.surface_point(order[k], &rays[k], t[k], u[k], v[k])
        });
    }
}
