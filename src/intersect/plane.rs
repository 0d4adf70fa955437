//! The plane kind, the one unbounded kind: its storage ([`Planes`]), the ray-plane test
//! and its packet twin. No structure holds planes; `Tracer` tests them beside it.

use glam::Vec3;

use super::{
    gamma, Aabb, PacketHits, PacketQuery, RayQuery, ShapeHit, Shapes, SurfacePoint, Vec3s,
};
use crate::ray::{Ray, RayPacket};
use crate::simd::{F32xP, LaneBits, MaskP, Vec3xP};

/// Ray-plane test for the plane `dot(normal, p) = offset`. A ray parallel to the plane
/// (including one lying in it) misses.
pub fn plane(ray: &Ray, normal: Vec3, offset: f32, t_min: f32, t_max: f32) -> Option<f32> {
    let denom = normal.dot(ray.dir);
    if denom == 0.0 {
        return None;
    }
    let t = (offset - normal.dot(ray.origin)) / denom;
    (t > t_min && t < t_max).then_some(t)
}

/// [`plane`] for a packet's rays; lanes outside `active` miss. Planes never enter a BVH leaf,
/// so there is no leaf kernel.
pub fn plane_packet(
    rays: &RayPacket,
    normal: Vec3,
    offset: f32,
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> (MaskP, F32xP) {
    let normal = Vec3xP::splat(normal);
    let denom = normal.dot(rays.dir);
    let t = (F32xP::splat(offset) - normal.dot(rays.origin)) / denom;
    let hit = t.gt(t_min) & t.lt(t_max);
    let active = MaskP::from_bitmask(active);
    (active.and_not(denom.eq(F32xP::ZERO)) & hit, t)
}

/// Infinite planes `dot(normal, p) = offset`.
#[derive(Clone, Debug, Default)]
pub struct Planes {
    pub normal: Vec3s,
    pub offset: Vec<f32>,
    pub material: Vec<u32>,
}

impl Shapes for Planes {
    fn len(&self) -> usize {
        self.material.len()
    }

    fn shrink_to_fit(&mut self) {
        self.normal.shrink_to_fit();
        self.offset.shrink_to_fit();
        self.material.shrink_to_fit();
    }

    fn material(&self, i: usize) -> u32 {
        self.material[i]
    }

    /// All of space: planes are unbounded, and no structure holds them.
    fn bounds(&self, _i: usize, _shutter: [f32; 2]) -> Aabb {
        Aabb {
            min: Vec3::NEG_INFINITY,
            max: Vec3::INFINITY,
        }
    }

    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<ShapeHit> {
        let (normal, offset) = (self.normal.get(i), self.offset[i]);
        plane(&query.ray, normal, offset, query.t_min, t_max).map(ShapeHit::at)
    }

    fn intersect_packet(
        &self,
        i: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let (normal, offset) = (self.normal.get(i), self.offset[i]);
        PacketHits::at(plane_packet(
            query.packet,
            normal,
            offset,
            query.t_min_lanes(),
            t_max,
            active,
        ))
    }

    /// The geometric normal of P3F.md section 2: planes have no inside.
    fn normal(&self, i: usize, _p: Vec3, _u: f32, _v: f32, _time: f32) -> Vec3 {
        self.normal.get(i)
    }

    /// `p` moved along the normal by its distance from the plane. The test decides which
    /// side an origin is on by `offset - normal . origin`, off by `gamma(4)` of
    /// `|normal| . |origin| + |offset|`, and the projection rounds as much again.
    fn surface_point(&self, i: usize, ray: &Ray, t: f32, _u: f32, _v: f32) -> SurfacePoint {
        let (normal, offset) = (self.normal.get(i), self.offset[i]);
        let p = ray.at(t);
        let point = p - (normal.dot(p) - offset) * normal;
        let size = normal.abs().dot(point.abs()) + offset.abs();
        SurfacePoint {
            point,
            error: gamma(2) * point.abs() + gamma(5) * size * normal.abs(),
            normal,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_from_both_sides() {
        let down = Ray::new(Vec3::new(3., 2., 7.), Vec3::NEG_Z);
        assert_eq!(plane(&down, Vec3::Z, -0.5, 0.0, f32::INFINITY), Some(7.5));
        let up = Ray::new(Vec3::new(3., 2., -7.), Vec3::Z);
        assert_eq!(plane(&up, Vec3::Z, -0.5, 0.0, f32::INFINITY), Some(6.5));
    }

    #[test]
    fn parallel_and_in_plane_rays_miss() {
        let parallel = Ray::new(Vec3::new(0., 0., 1.), Vec3::X);
        assert_eq!(plane(&parallel, Vec3::Z, 0.0, 0.0, f32::INFINITY), None);
        let inside = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(plane(&inside, Vec3::Z, 0.0, 0.0, f32::INFINITY), None);
    }

    #[test]
    fn behind_and_beyond_miss() {
        let away = Ray::new(Vec3::new(0., 0., 1.), Vec3::Z);
        assert_eq!(plane(&away, Vec3::Z, 0.0, 0.0, f32::INFINITY), None);
        let down = Ray::new(Vec3::new(0., 0., 1.), Vec3::NEG_Z);
        assert_eq!(plane(&down, Vec3::Z, 0.0, 0.0, 0.5), None);
    }
}
