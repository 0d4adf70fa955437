//! The cone and cylinder kind: its storage ([`Cones`]), the ray test of an open frustum
//! and its packet twin (a packet's rays against one cone), and the normal.
//!
//! Cones have no BVH leaf pack. One (a `ConePack8` and a leaf kernel over the packet
//! kernel's body) cut the instructions of `bench` by 13% and of a render by 11% on a
//! scene of 20,000 random cones, but cones are rare, and as a fourth packed kind it cost
//! the course's scenes up to 0.5% (`bench mount_very_high`) and would halve the
//! primitives an 8-wide tree can encode, to 2^25.

use glam::Vec3;

use super::{
    gamma, max_num, trusted_box, Aabb, PacketHits, PacketQuery, RayQuery, ShapeHit, Shapes,
    SurfacePoint, Vec3s,
};
use crate::ray::{Ray, RayPacket};
use crate::simd::{F32xP, LaneBits, MaskP, Vec3xP};

/// Ray test against the open (uncapped) cone frustum or cylinder from `base` along the unit
/// `axis` for `height`, with radius `r_base` at the base and `r_apex` at the far end.
///
/// A point `P` lies on it when its distance from the axis equals
/// `r(s) = r_base + k s`, `k = (r_apex - r_base) / height`, with `s = dot(P - base, axis)`
/// in `[0, height]`: a quadratic in `t`, solved for both roots in order.
///
/// The quadratic is taken in the cone's own frame, as the sphere's is about its centre:
/// from the ray's point nearest the middle of the axis, `t0` along it. From the ray's
/// origin its coefficients would be about `t^2` (1e18 from 1e9 away), and their
/// difference, the discriminant, rounding noise: a thin cone was hit by rays passing 2.5
/// units off it. From there they are about the squares of the distances near the cone.
#[allow(clippy::too_many_arguments)] // the cone's five fields, the ray and its interval
pub fn cone(
    ray: &Ray,
    base: Vec3,
    axis: Vec3,
    height: f32,
    r_base: f32,
    r_apex: f32,
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    let slope = (r_apex - r_base) / height;
    let from_base = ray.origin - base;
    let t0 = (axis * (0.5 * height) - from_base).dot(ray.dir);
    let offset = from_base + t0 * ray.dir;
    let d_axial = ray.dir.dot(axis);
    let o_axial = offset.dot(axis);
    let d_perp = ray.dir - d_axial * axis;
    let o_perp = offset - o_axial * axis;
    let r_origin = r_base + slope * o_axial;
    let a = d_perp.dot(d_perp) - slope * slope * d_axial * d_axial;
    let half_b = o_perp.dot(d_perp) - slope * d_axial * r_origin;
    let c = o_perp.dot(o_perp) - r_origin * r_origin;

    // `t0 + dt` for a root `dt`, if the ray is then on the frustum and in the interval.
    let on_surface = |dt: f32| {
        let (s, t) = (o_axial + dt * d_axial, t0 + dt);
        (t > t_min && t < t_max && (0.0..=height).contains(&s)).then_some(t)
    };
    // A ray parallel to the cone's side (or a cylinder's axis) leaves a linear equation.
    if a.abs() <= 1e-12 * max_num(d_perp.dot(d_perp), d_axial * d_axial) {
        if half_b == 0.0 {
            return None;
        }
        return on_surface(-c / (2.0 * half_b));
    }
    let disc = half_b * half_b - a * c;
    if !(disc >= 0.0) {
        return None;
    }
    let root = disc.sqrt();
    let (dt0, dt1) = ((-half_b - root) / a, (-half_b + root) / a);
    let (near, far) = if dt0 <= dt1 { (dt0, dt1) } else { (dt1, dt0) };
    on_surface(near).or_else(|| on_surface(far))
}

/// [`cone`] for a packet's rays against one cone; lanes outside `active` miss. Both the
/// linear and the quadratic case are computed and chosen per lane.
#[allow(clippy::too_many_arguments)] // as `cone`, with the lane mask
pub fn cone_packet(
    rays: &RayPacket,
    base: Vec3,
    axis: Vec3,
    height: f32,
    r_base: f32,
    r_apex: f32,
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> (MaskP, F32xP) {
    let zero = F32xP::ZERO;
    let slope_f = (r_apex - r_base) / height;
    let (slope, slope2) = (F32xP::splat(slope_f), F32xP::splat(slope_f * slope_f));
    let (axis, height) = (Vec3xP::splat(axis), F32xP::splat(height));
    let (origin, dir) = (rays.origin, rays.dir);
    let from_base = origin - Vec3xP::splat(base);
    let t0 = (axis.scale(F32xP::splat(0.5) * height) - from_base).dot(dir);
    let offset = from_base + dir.scale(t0);
    let d_axial = dir.dot(axis);
    let o_axial = offset.dot(axis);
    let d_perp = dir - axis.scale(d_axial);
    let o_perp = offset - axis.scale(o_axial);
    let r_origin = F32xP::splat(r_base) + slope * o_axial;
    let d_perp2 = d_perp.dot(d_perp);
    let a = d_perp2 - slope2 * d_axial * d_axial;
    let half_b = o_perp.dot(d_perp) - slope * d_axial * r_origin;
    let c = o_perp.dot(o_perp) - r_origin * r_origin;

    // As `cone`'s: whether `t0 + dt` is on the frustum and in the interval.
    let on_surface = |dt: F32xP| {
        let (s, t) = (o_axial + dt * d_axial, t0 + dt);
        t.gt(t_min) & t.lt(t_max) & zero.le(s) & s.le(height)
    };
    // Parallel to the side: the linear equation.
    let linear = a
        .abs()
        .le(F32xP::splat(1e-12) * d_perp2.max_num(d_axial * d_axial));
    let t_line = -c / (F32xP::splat(2.0) * half_b);
    let hit_line = on_surface(t_line).and_not(half_b.eq(zero));
    // Otherwise the quadratic, near root first.
    let disc = half_b * half_b - a * c;
    let root = disc.sqrt();
    let (dt0, dt1) = ((-half_b - root) / a, (-half_b + root) / a);
    let ordered = dt0.le(dt1);
    let (near, far) = (ordered.select(dt0, dt1), ordered.select(dt1, dt0));
    let near_on = on_surface(near);
    let hit_quad = disc.ge(zero) & (near_on | on_surface(far));
    let t_quad = near_on.select(near, far);

    let hit = (linear & hit_line) | hit_quad.and_not(linear);
    (
        hit & MaskP::from_bitmask(active),
        t0 + linear.select(t_line, t_quad),
    )
}

/// Outward normal of the cone surface at `p`, the gradient of `|P_perp|^2 - r(s)^2`. At the
/// apex of a pointed cone the gradient vanishes and the axis is returned.
pub fn cone_normal(base: Vec3, axis: Vec3, height: f32, r_base: f32, r_apex: f32, p: Vec3) -> Vec3 {
    let slope = (r_apex - r_base) / height;
    let offset = p - base;
    let s = offset.dot(axis);
    let perp = offset - s * axis;
    let gradient = perp - (r_base + slope * s) * slope * axis;
    gradient.try_normalize().unwrap_or(axis)
}

/// Open cones and cylinders: `base`, unit `axis`, `height`, and the radius at each end.
#[derive(Clone, Debug, Default)]
pub struct Cones {
    pub base: Vec3s,
    pub axis: Vec3s,
    pub height: Vec<f32>,
    pub r_base: Vec<f32>,
    pub r_apex: Vec<f32>,
    pub material: Vec<u32>,
}

impl Shapes for Cones {
    fn len(&self) -> usize {
        self.material.len()
    }

    fn shrink_to_fit(&mut self) {
        self.base.shrink_to_fit();
        self.axis.shrink_to_fit();
        self.height.shrink_to_fit();
        self.r_base.shrink_to_fit();
        self.r_apex.shrink_to_fit();
        self.material.shrink_to_fit();
    }

    fn material(&self, i: usize) -> u32 {
        self.material[i]
    }

    fn bounds(&self, i: usize, _shutter: [f32; 2]) -> Aabb {
        let (base, axis) = (self.base.get(i), self.axis.get(i));
        let apex = base + axis * self.height[i];
        // A disc of radius r about `axis` reaches r * sqrt(1 - axis_k^2) along axis k.
        let reach = (Vec3::ONE - axis * axis).max(Vec3::ZERO).powf(0.5);
        let disc = |centre: Vec3, r: f32| Aabb {
            min: centre - reach * r.abs(),
            max: centre + reach * r.abs(),
        };
        disc(base, self.r_base[i]).union(disc(apex, self.r_apex[i]))
    }

    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<ShapeHit> {
        let (base, axis, height) = (self.base.get(i), self.axis.get(i), self.height[i]);
        let (r_base, r_apex, t_min) = (self.r_base[i], self.r_apex[i], query.t_min);
        cone(&query.ray, base, axis, height, r_base, r_apex, t_min, t_max)
            .filter(|&t| query.holds(trusted_box(self.bounds(i, [0.0; 2]), 0.0), t))
            .map(ShapeHit::at)
    }

    fn intersect_packet(
        &self,
        i: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let (base, axis, height) = (self.base.get(i), self.axis.get(i), self.height[i]);
        let (r_base, r_apex, t_min) = (self.r_base[i], self.r_apex[i], query.t_min_lanes());
        let rays = query.packet;
        let (hit, t) = cone_packet(
            rays, base, axis, height, r_base, r_apex, t_min, t_max, active,
        );
        if hit.none() {
            return PacketHits::at((hit, t));
        }
        let trusted = trusted_box(self.bounds(i, [0.0; 2]), 0.0);
        PacketHits::at((hit & query.holds(trusted, t), t))
    }

    fn normal(&self, i: usize, p: Vec3, _u: f32, _v: f32, _time: f32) -> Vec3 {
        cone_normal(
            self.base.get(i),
            self.axis.get(i),
            self.height[i],
            self.r_base[i],
            self.r_apex[i],
            p,
        )
    }

    /// The hit moved across the axis to the radius at its height (kept on the axis, at a
    /// pointed apex), its offset from the base taken as `(origin - base) + t dir` as the
    /// sphere's is. The test's quadratic is off by `gamma` of the squares of the radius
    /// and the distance from the axis, so the bound holds the radius beside the point's
    /// terms.
    fn surface_point(&self, i: usize, ray: &Ray, t: f32, _u: f32, _v: f32) -> SurfacePoint {
        let (base, axis) = (self.base.get(i), self.axis.get(i));
        let slope = (self.r_apex[i] - self.r_base[i]) / self.height[i];
        let offset = (ray.origin - base) + t * ray.dir;
        let along = offset.dot(axis) * axis;
        let across = offset - along;
        let radius = self.r_base[i] + slope * offset.dot(axis);
        let distance = across.length();
        let radial = if distance > 0.0 && distance.is_finite() {
            across * (radius / distance)
        } else {
            across
        };
        let point = base + along + radial;
        SurfacePoint {
            point,
            error: gamma(8) * (base.abs() + along.abs() + radial.abs() + Vec3::splat(radius.abs())),
            normal: self.normal(i, point, 0.0, 0.0, ray.time),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_cylinder(ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        cone(ray, Vec3::ZERO, Vec3::Z, 2.0, 1.0, 1.0, t_min, t_max)
    }

    #[test]
    fn cylinder_from_outside_and_inside() {
        let outside = Ray::new(Vec3::new(-5., 0., 1.), Vec3::X);
        assert!((unit_cylinder(&outside, 0.0, 1e9).unwrap() - 4.0).abs() < 1e-5);
        let inside = Ray::new(Vec3::new(0., 0., 1.), Vec3::X);
        assert!((unit_cylinder(&inside, 0.0, 1e9).unwrap() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn cylinder_is_open_and_finite() {
        let along_axis = Ray::new(Vec3::new(0., 0., -5.), Vec3::Z);
        assert_eq!(unit_cylinder(&along_axis, 0.0, 1e9), None);
        let above = Ray::new(Vec3::new(-5., 0., 2.5), Vec3::X);
        assert_eq!(unit_cylinder(&above, 0.0, 1e9), None);
        // Through the open top and out of the side wall.
        let slanted = Ray::new(Vec3::new(0., 0., 3.), Vec3::new(1., 0., -1.).normalize());
        let t = unit_cylinder(&slanted, 0.0, 1e9).unwrap();
        let p = slanted.at(t);
        assert!((p.x - 1.0).abs() < 1e-5 && (p.z - 2.0).abs() < 1e-5);
    }

    #[test]
    fn cone_apex_and_side() {
        // Pointed cone: radius 1 at z = 0, apex at z = 1.
        let (base, axis) = (Vec3::ZERO, Vec3::Z);
        let through_apex = Ray::new(Vec3::new(-1., 0., 1.), Vec3::X);
        let t = cone(&through_apex, base, axis, 1.0, 1.0, 0.0, 0.0, 1e9).unwrap();
        assert!((t - 1.0).abs() < 1e-4);
        assert_eq!(
            cone_normal(base, axis, 1.0, 1.0, 0.0, through_apex.at(t)),
            axis
        );
        // Halfway up the side the radius is 0.5 and the normal leans up at 45 degrees.
        let side = Ray::new(Vec3::new(-5., 0., 0.5), Vec3::X);
        let t = cone(&side, base, axis, 1.0, 1.0, 0.0, 0.0, 1e9).unwrap();
        assert!((t - 4.5).abs() < 1e-5);
        let n = cone_normal(base, axis, 1.0, 1.0, 0.0, side.at(t));
        assert!((n - Vec3::new(-1., 0., 1.).normalize()).length() < 1e-5);
    }

    #[test]
    fn ray_parallel_to_the_side_hits_once() {
        // The side of this cone runs at 45 degrees; a ray along that slope crosses the
        // surface once, where the quadratic term vanishes.
        let ray = Ray::new(Vec3::new(-0.5, 0., 0.), Vec3::new(1., 0., 1.).normalize());
        let t = cone(&ray, Vec3::ZERO, Vec3::Z, 1.0, 1.0, 0.0, 0.0, 1e9).unwrap();
        let p = ray.at(t);
        assert!((p.x.hypot(p.y) - (1.0 - p.z)).abs() < 1e-5);
    }
}
