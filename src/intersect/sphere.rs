//! The sphere kind: its storage ([`Spheres`]), the ray-sphere test and its SIMD twins (a
//! packet's rays against one sphere; one ray against a [`SpherePack8`] of a BVH leaf),
//! each in two forms of the quadratic ([`Roots`]).

use glam::{DVec3, Vec3};

use super::{first_root_in, first_root_in_lanes, gather8, holds_lanes8};
use super::{
    gamma, trusted_box, Aabb, BoxPack8, Hits8, IntersectOptions, LeafPack, PackOf, PacketHits,
    PacketQuery, RayQuery, Rays8, ShapeHit, ShapeHit8, Shapes, SurfacePoint, SurfacePoint8,
};

use crate::ray::{Ray, RayPacket};
use crate::simd::{
    for_lanes, F32x8, F32xP, Floats, LaneBits, LaneMask, Mask8, MaskP, Vec3Lanes, Vec3x8, Vec3xP,
};

/// How the sphere test solves its quadratic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Roots {
    /// The discriminant from the perpendicular distance and the near root as `c / q`
    /// ([`sphere`]): precise for small spheres seen from afar and large ones from close by.
    #[default]
    Precise,
    /// The textbook form `b -+ sqrt(b^2 - c)` ([`sphere_textbook`]), as the course's
    /// renderer solved it in single precision; the `course` profile (P3F.md 11) uses it.
    Textbook,
}

/// The smallest radius a sphere is hit with, 2^-63 (about 1.08e-19): the square of a
/// smaller one is not a normal float, and the tests' squares underflow to zero, so that
/// a ray passing far off such a sphere would find `disc = 0 - 0` and hit it.
pub const MIN_RADIUS: f32 = f32::from_bits(0x2000_0000);

/// Ray-sphere test. The report's early exit comes first: an origin outside the sphere with
/// the centre behind it is a miss before the discriminant is computed. The discriminant is
/// taken as `r^2 - |perpendicular offset|^2` and the near root as `c / q`, which keeps
/// precision for large spheres seen from close by (the random scene's ground has radius
/// 1000). A sphere of radius below [`MIN_RADIUS`] (zero, negative or NaN included) is
/// never hit.
pub fn sphere(ray: &Ray, centre: Vec3, radius: f32, t_min: f32, t_max: f32) -> Option<f32> {
    let oc = centre - ray.origin;
    let b = oc.dot(ray.dir);
    let c = oc.dot(oc) - radius * radius;
    if c > 0.0 && b < 0.0 {
        return None;
    }
    let perpendicular = oc - b * ray.dir;
    let disc = radius * radius - perpendicular.dot(perpendicular);
    if !(disc >= 0.0 && radius >= MIN_RADIUS) {
        return None;
    }
    let q = b + disc.sqrt().copysign(b);
    let (r0, r1) = (c / q, q);
    let (near, far) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
    first_root_in(near, far, t_min, t_max)
}

/// [`sphere`] with the textbook quadratic: `disc = b^2 - c` and the roots `b -+ sqrt(disc)`.
/// For a sphere of radius r at distance D, `b^2` and `c` are about D^2 and their
/// difference about r^2, so single precision loses most of it: for the sphereflake's
/// smallest spheres (r = 0.0062, D about 3) the hit lands about 1e-4 off the surface,
/// as far as the ray offset, and some hits shadow themselves. The course's reference
/// images carry exactly that (P3F.md 11; `docs/course-profile.md`).
pub fn sphere_textbook(
    ray: &Ray,
    centre: Vec3,
    radius: f32,
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    let oc = centre - ray.origin;
    let b = oc.dot(ray.dir);
    let c = oc.dot(oc) - radius * radius;
    if c > 0.0 && b < 0.0 {
        return None;
    }
    let disc = b * b - c;
    if !(disc >= 0.0 && radius >= MIN_RADIUS) {
        return None;
    }
    let root = disc.sqrt();
    first_root_in(b - root, b + root, t_min, t_max)
}

/// Eight spheres side by side for [`sphere_leaf`]. Unused slots hold
/// [`SpherePack8::PAD_RADIUS`] (0), which the test rejects for every ray, NaN included.
#[derive(Clone, Copy, Debug)]
pub struct SpherePack8 {
    pub centre: Vec3x8,
    pub radius: F32x8,
}

impl SpherePack8 {
    /// The radius of a padding slot (its centre is the origin): never hit.
    pub const PAD_RADIUS: f32 = 0.0;

    /// Packs up to eight `(centre, radius)` pairs, padding the rest.
    ///
    /// # Panics
    /// If given more than eight spheres.
    pub fn new(spheres: &[(Vec3, f32)]) -> Self {
        assert!(spheres.len() <= 8, "a pack holds at most 8 spheres");
        let slot = |i: usize| spheres.get(i).copied();
        SpherePack8 {
            centre: Vec3x8::from_lanes(std::array::from_fn(|i| {
                slot(i).map_or(Vec3::ZERO, |s| s.0)
            })),
            radius: F32x8::from_array(std::array::from_fn(|i| {
                slot(i).map_or(Self::PAD_RADIUS, |s| s.1)
            })),
        }
    }
}

/// [`sphere`], or [`sphere_textbook`] as `roots` says, for a packet's rays against one
/// sphere; lanes outside `active` miss.
pub fn sphere_packet(
    rays: &RayPacket,
    centre: Vec3,
    radius: f32,
    roots: Roots,
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> (MaskP, F32xP) {
    let (centre, radius) = (Vec3xP::splat(centre), F32xP::splat(radius));
    let (hit, t) = match roots {
        Roots::Precise => {
            sphere_lanes::<_, false>(rays.origin, rays.dir, centre, radius, t_min, t_max)
        }
        Roots::Textbook => {
            sphere_lanes::<_, true>(rays.origin, rays.dir, centre, radius, t_min, t_max)
        }
    };
    (hit & MaskP::from_bitmask(active), t)
}

/// [`sphere`], or [`sphere_textbook`] as `roots` says, for one ray against the eight
/// spheres of a pack. The form belongs to all of a scene's spheres, so the tree keeps it
/// once rather than each pack (which it would grow from 128 bytes to 160).
#[inline]
pub fn sphere_leaf(
    ray: &Ray,
    pack: &SpherePack8,
    roots: Roots,
    t_min: f32,
    t_max: f32,
) -> (Mask8, F32x8) {
    let (origin, dir) = (Vec3x8::splat(ray.origin), Vec3x8::splat(ray.dir));
    let (t_min, t_max) = (F32x8::splat(t_min), F32x8::splat(t_max));
    match roots {
        Roots::Precise => {
            sphere_lanes::<_, false>(origin, dir, pack.centre, pack.radius, t_min, t_max)
        }
        Roots::Textbook => {
            sphere_lanes::<_, true>(origin, dir, pack.centre, pack.radius, t_min, t_max)
        }
    }
}

/// The body of [`sphere`] (or, with `TEXTBOOK`, of [`sphere_textbook`]), lane by lane:
/// both branches are computed and the early exits become masks.
#[inline(always)]
fn sphere_lanes<F: Floats, const TEXTBOOK: bool>(
    origin: Vec3Lanes<F>,
    dir: Vec3Lanes<F>,
    centre: Vec3Lanes<F>,
    radius: F,
    t_min: F,
    t_max: F,
) -> (F::Mask, F) {
    let zero = F::splat(0.0);
    let oc = centre - origin;
    let b = oc.dot(dir);
    let c = oc.dot(oc) - radius * radius;
    let behind = c.gt(zero) & b.lt(zero);
    let (disc, near, far) = if TEXTBOOK {
        let disc = b * b - c;
        let root = disc.sqrt();
        (disc, b - root, b + root)
    } else {
        let perpendicular = oc - dir.scale(b);
        let disc = radius * radius - perpendicular.dot(perpendicular);
        let q = b + disc.sqrt().copysign(b);
        let (r0, r1) = (c / q, q);
        let ordered = r0.le(r1);
        (disc, ordered.select(r0, r1), ordered.select(r1, r0))
    };
    let real = (disc.ge(zero) & radius.ge(F::splat(MIN_RADIUS))).and_not(behind);
    let (hit, t) = first_root_in_lanes(near, far, t_min, t_max);
    (hit & real, t)
}

/// Spheres, one [`Sphere`] record each: the SIMD tests read the leaf packs
/// ([`SpherePack8`], structure of arrays), so this storage is read one sphere at a time,
/// by a hit's surface point above all, where a record is one cache line or two and an
/// array per field five.
#[derive(Clone, Debug, Default)]
pub struct Spheres {
    pub records: Vec<Sphere>,
}

/// One sphere of [`Spheres`]: 20 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Sphere {
    pub centre: Vec3,
    pub radius: f32,
    pub material: u32,
}

impl Spheres {
    pub fn push(&mut self, centre: Vec3, radius: f32, material: u32) {
        self.records.push(Sphere {
            centre,
            radius,
            material,
        });
    }
}

/// The body of the spheres' [`Shapes::hits8`]: sphere `k` (its centre and radius)
/// against ray `k`, `inv_dir` giving the rays' `1 / dir` where a hit needs its trusted
/// box's test.
#[inline(always)]
fn spheres_lanes8(
    (centre, radius): (Vec3x8, F32x8),
    &Rays8 { origin, dir, .. }: &Rays8,
    inv_dir: impl FnOnce() -> Vec3x8,
    (t_min, t_max): (f32, F32x8),
    options: IntersectOptions,
) -> (Mask8, F32x8) {
    let lanes_min = F32x8::splat(t_min);
    let (hit, t) = match options.roots {
        Roots::Precise => sphere_lanes::<_, false>(origin, dir, centre, radius, lanes_min, t_max),
        Roots::Textbook => sphere_lanes::<_, true>(origin, dir, centre, radius, lanes_min, t_max),
    };
    if hit.none() {
        return (hit, t);
    }
    let (trusted, some) = trusted_sphere_boxes8(centre, radius, options);
    (
        hit & some & holds_lanes8(origin, inv_dir(), &trusted, t_min, t),
        t,
    )
}

impl LeafPack for Spheres {
    type Pack = SpherePack8;
    type Compact = SpherePack8;
}

impl PackOf<Spheres> for SpherePack8 {
    fn pack(storage: &Spheres, indices: impl Iterator<Item = usize>) -> Option<SpherePack8> {
        let record = |i: usize| (storage.records[i].centre, storage.records[i].radius);
        let (spheres, n) = gather8(indices.map(record));
        Some(SpherePack8::new(&spheres[..n]))
    }

    #[inline(always)]
    fn leaf<const FRAME: usize>(pack: &SpherePack8, query: &RayQuery, t_max: f32) -> ShapeHit8 {
        let roots = query.options.roots;
        let (hit, t) = sphere_leaf(&query.ray, pack, roots, query.t_min, t_max);
        if hit.none() {
            return ShapeHit8::at((hit, t));
        }
        let trusted = trusted_sphere_boxes8(pack.centre, pack.radius, query.options);
        ShapeHit8::at((hit & query.holds8(trusted, t), t))
    }

    type Slots<'a> = &'a SpherePack8;

    #[inline(always)]
    fn slots(pack: &SpherePack8) -> &SpherePack8 {
        pack
    }

    #[inline(always)]
    fn slot_packet(
        pack: &SpherePack8,
        slot: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let (centre, radius) = (pack.centre.lane(slot), pack.radius.to_array()[slot]);
        sphere_in_packet(query, centre, radius, t_max, active)
    }
}

/// [`sphere_packet`] for the lanes `active` of `query`'s packet, in the form of the
/// storage's and the pack's packet tests, with the form of the roots the query chose.
#[inline(always)]
fn sphere_in_packet(
    query: &PacketQuery,
    centre: Vec3,
    radius: f32,
    t_max: F32xP,
    active: LaneBits,
) -> PacketHits {
    let (rays, roots, t_min) = (query.packet, query.options.roots, query.t_min_lanes());
    let (hit, t) = sphere_packet(rays, centre, radius, roots, t_min, t_max, active);
    if hit.none() {
        return PacketHits::at((hit, t));
    }
    let trusted = trusted_sphere_box(centre, radius, query.options);
    PacketHits::at((hit & query.holds(trusted, t), t))
}

/// The box the structures hold a sphere in ([`trusted_box`], with the margin of the
/// profile's roots): its hits count only inside it.
#[inline]
pub(super) fn trusted_sphere_box(
    centre: Vec3,
    radius: f32,
    options: IntersectOptions,
) -> Option<Aabb> {
    trusted_box(sphere_bounds(centre, radius), options.roots_margin)
}

/// [`trusted_sphere_box`] of eight spheres, with the lanes where it is `Some`.
#[inline(always)]
fn trusted_sphere_boxes8(
    centre: Vec3x8,
    radius: F32x8,
    options: IntersectOptions,
) -> (BoxPack8, Mask8) {
    let reach = Vec3x8::splat(Vec3::ONE).scale(radius.abs());
    let tight = BoxPack8 {
        min: centre - reach,
        max: centre + reach,
    };
    tight.trusted(options.roots_margin)
}

/// [`Shapes::surface_point`] of a sphere. The hit's offset from the centre is taken as
/// `(origin - centre) + t dir`, which keeps the digits that the point's own coordinates
/// lose far from the origin, and scaled to the radius: its error is a few ulps of the
/// radius (pbrt-v4 bounds its sphere's point by `gamma(5)` of it in object space), the
/// normal is that offset over the radius, and the centre's addition rounds once more.
/// The test of a ray from near the surface decides the side by `|origin - centre|^2 -
/// r^2`, off by `gamma(3)` of `r^2`, which that bound clears. An offset too small to
/// resolve (a sphere below the ulps of `t`) leaves the point along the ray, bounded by
/// the radius.
pub(super) fn sphere_surface_point(centre: Vec3, radius: f32, ray: &Ray, t: f32) -> SurfacePoint {
    let from_centre = (ray.origin - centre) + t * ray.dir;
    let length = from_centre.length();
    if !(length > 0.0 && length.is_finite()) {
        let point = ray.at(t);
        return SurfacePoint {
            point,
            error: gamma(2) * point.abs() + Vec3::splat(radius.abs()),
            normal: Vec3::ZERO,
        };
    }
    let normal = from_centre / length;
    let radial = normal * radius;
    let point = centre + radial;
    SurfacePoint {
        point,
        error: gamma(2) * point.abs() + gamma(6) * radial.abs(),
        normal,
    }
}

/// The box of a sphere (a negative radius bounds as its magnitude).
pub(super) fn sphere_bounds(centre: Vec3, radius: f32) -> Aabb {
    Aabb {
        min: centre - radius.abs(),
        max: centre + radius.abs(),
    }
}

impl Shapes for Spheres {
    fn len(&self) -> usize {
        self.records.len()
    }

    fn shrink_to_fit(&mut self) {
        self.records.shrink_to_fit();
    }

    fn material(&self, i: usize) -> u32 {
        self.records[i].material
    }

    fn bounds(&self, i: usize, _shutter: [f32; 2]) -> Aabb {
        let Sphere { centre, radius, .. } = self.records[i];
        sphere_bounds(centre, radius)
    }

    #[inline]
    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<ShapeHit> {
        let (ray, t_min) = (&query.ray, query.t_min);
        let Sphere { centre, radius, .. } = self.records[i];
        match query.options.roots {
            Roots::Precise => sphere(ray, centre, radius, t_min, t_max),
            Roots::Textbook => sphere_textbook(ray, centre, radius, t_min, t_max),
        }
        .filter(|&t| query.holds(trusted_sphere_box(centre, radius, query.options), t))
        .map(ShapeHit::at)
    }

    fn intersect_packet(
        &self,
        i: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let Sphere { centre, radius, .. } = self.records[i];
        sphere_in_packet(query, centre, radius, t_max, active)
    }

    fn normal(&self, i: usize, p: Vec3, _u: f32, _v: f32, _time: f32) -> Vec3 {
        let Sphere { centre, radius, .. } = self.records[i];
        ((p - centre) / radius).normalize_or_zero()
    }

    #[inline]
    fn surface_point(&self, i: usize, ray: &Ray, t: f32, _u: f32, _v: f32) -> SurfacePoint {
        let Sphere { centre, radius, .. } = self.records[i];
        sphere_surface_point(centre, radius, ray, t)
    }

    /// The scalar surface point (`sphere_surface_point`) eight at a time;
    /// [`Shapes::surface_points_along8`] of the rays' lanes.
    fn surface_points8(&self, indices: [usize; 8], rays: &[Ray; 8], hits: &Hits8) -> SurfacePoint8 {
        let lanes = Rays8 {
            origin: Vec3x8::from_lanes(rays.map(|r| r.origin)),
            dir: Vec3x8::from_lanes(rays.map(|r| r.dir)),
            time: F32x8::ZERO,
        };
        self.surface_points_along8(indices, &lanes, F32x8::from_array(hits.t))
    }

    const ROOTS_MARGIN: bool = true;

    /// Glass spheres hold most of the rays of the scenes that have them, and no other
    /// primitive comes near most of them.
    const INTERIOR: bool = true;

    /// The spheres' roots, then their trusted boxes, eight at a time.
    #[inline]
    fn hits8(
        &self,
        indices: [usize; 8],
        rays: &Rays8,
        t_min: f32,
        t_max: F32x8,
        options: IntersectOptions,
    ) -> (Mask8, F32x8) {
        let records = indices.map(|i| &self.records[i]);
        let centre = Vec3x8::from_lanes(records.map(|r| r.centre));
        let radius = F32x8::from_array(records.map(|r| r.radius));
        let inv_dir = || rays.dir.recip();
        spheres_lanes8((centre, radius), rays, inv_dir, (t_min, t_max), options)
    }

    #[inline(always)]
    fn hits_one8(
        &self,
        index: usize,
        (rays, inv_dir): (&Rays8, Vec3x8),
        t_min: f32,
        t_max: F32x8,
        options: IntersectOptions,
    ) -> (Mask8, F32x8) {
        let Sphere { centre, radius, .. } = self.records[index];
        let sphere = (Vec3x8::splat(centre), F32x8::splat(radius));
        spheres_lanes8(sphere, rays, || inv_dir, (t_min, t_max), options)
    }

    /// Each lane bit for bit the scalar `sphere_surface_point`; a lane whose offset from
    /// the centre has no direction (rare) is left to the scalar form.
    fn surface_points_along8(&self, indices: [usize; 8], rays: &Rays8, t: F32x8) -> SurfacePoint8 {
        let Rays8 { origin, dir, .. } = *rays;
        let records = indices.map(|i| &self.records[i]);
        let centre = Vec3x8::from_lanes(records.map(|r| r.centre));
        let radius = F32x8::from_array(records.map(|r| r.radius));
        let from_centre = (origin - centre) + dir.scale(t);
        let length = from_centre.length();
        let normal = from_centre / length;
        let radial = normal.scale(radius);
        let point = centre + radial;
        let error =
            point.abs().scale(F32x8::splat(gamma(2))) + radial.abs().scale(F32x8::splat(gamma(6)));
        let mut points = SurfacePoint8 {
            point,
            error,
            normal,
        };
        let directed = length.gt(F32x8::ZERO) & length.is_finite();
        for_lanes(!directed.bitmask(), |k| {
            let Sphere { centre, radius, .. } = *records[k];
            let ray = Ray::new(origin.lane(k), dir.lane(k));
            points.set_lane(k, sphere_surface_point(centre, radius, &ray, t.lane(k)));
        });
        points
    }

    fn geometric_normal64(&self, i: usize, p: DVec3, _u: f32, _v: f32) -> DVec3 {
        let Sphere { centre, radius, .. } = self.records[i];
        (p - centre.as_dvec3()) / f64::from(radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(Vec3::from(o), Vec3::from(d).normalize())
    }

    #[test]
    fn hits_front_from_outside() {
        let t = sphere(
            &ray([0., 0., -5.], [0., 0., 1.]),
            Vec3::ZERO,
            1.0,
            0.0,
            f32::INFINITY,
        );
        assert!((t.unwrap() - 4.0).abs() < 1e-6);
    }

    #[test]
    fn origin_inside_hits_far_side() {
        let t = sphere(
            &ray([0., 0.5, 0.], [0., 0., 1.]),
            Vec3::ZERO,
            1.0,
            0.0,
            f32::INFINITY,
        );
        let expected = (1.0f32 - 0.25).sqrt();
        assert!((t.unwrap() - expected).abs() < 1e-6);
    }

    #[test]
    fn sphere_behind_ray_is_missed() {
        assert_eq!(
            sphere(
                &ray([0., 0., 5.], [0., 0., 1.]),
                Vec3::ZERO,
                1.0,
                0.0,
                f32::INFINITY
            ),
            None
        );
    }

    #[test]
    fn respects_the_interval() {
        let r = ray([0., 0., -5.], [0., 0., 1.]);
        assert_eq!(sphere(&r, Vec3::ZERO, 1.0, 0.0, 3.9), None);
        // The near root is excluded by t_min, so the far one is returned.
        assert!((sphere(&r, Vec3::ZERO, 1.0, 4.5, 10.0).unwrap() - 6.0).abs() < 1e-5);
        assert_eq!(sphere(&r, Vec3::ZERO, 1.0, 6.5, 10.0), None);
    }

    #[test]
    fn tangent_and_near_miss() {
        let grazing = sphere(
            &ray([1.0001, 0., -5.], [0., 0., 1.]),
            Vec3::ZERO,
            1.0,
            0.0,
            1e9,
        );
        assert_eq!(grazing, None);
        let inside_edge = sphere(
            &ray([0.9999, 0., -5.], [0., 0., 1.]),
            Vec3::ZERO,
            1.0,
            0.0,
            1e9,
        );
        assert!(inside_edge.is_some());
    }

    #[test]
    fn zero_radius_and_nan_are_misses() {
        let r = ray([0., 0., -5.], [0., 0., 1.]);
        assert_eq!(sphere(&r, Vec3::ZERO, 0.0, 0.0, f32::INFINITY), None);
        let nan = Ray::new(Vec3::new(f32::NAN, 0., -5.), Vec3::Z);
        assert_eq!(sphere(&nan, Vec3::ZERO, 1.0, 0.0, f32::INFINITY), None);
    }

    #[test]
    fn large_sphere_from_close_by_is_precise() {
        // The random scene's ground: radius 1000, seen from 4.4 units above its top.
        let r = ray([0., 4.4, 0.], [0., -1., 0.]);
        let t = sphere(&r, Vec3::new(0., -1000., 0.), 1000.0, 0.0, f32::INFINITY).unwrap();
        assert!((t - 4.4).abs() < 1e-4, "t = {t}");
    }
}
