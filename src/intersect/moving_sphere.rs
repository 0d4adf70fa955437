//! Spheres in linear motion (P3F.md 6.5): the sphere's routines at the centre of the
//! ray's time. No packet kernel: they are rare, and tested lane by lane.

use glam::{DVec3, Vec3};

use super::sphere::{sphere, sphere_bounds, sphere_surface_point, trusted_sphere_box};
use super::{Aabb, RayQuery, ShapeHit, Shapes, SurfacePoint, Vec3s};
use crate::ray::Ray;

/// Spheres whose centre moves linearly from `centre0` at `time0` to `centre1` at `time1`.
#[derive(Clone, Debug, Default)]
pub struct MovingSpheres {
    pub centre0: Vec3s,
    pub centre1: Vec3s,
    pub radius: Vec<f32>,
    pub time0: Vec<f32>,
    pub time1: Vec<f32>,
    pub material: Vec<u32>,
}

impl MovingSpheres {
    /// Centre of sphere `i` at `time` (P3F.md 6.5); a sphere with `time0 == time1` stands
    /// at `centre0`.
    pub fn centre_at(&self, i: usize, time: f32) -> Vec3 {
        let (c0, c1) = (self.centre0.get(i), self.centre1.get(i));
        let span = self.time1[i] - self.time0[i];
        if span == 0.0 {
            return c0;
        }
        c0 + (c1 - c0) * ((time - self.time0[i]) / span)
    }
}

impl Shapes for MovingSpheres {
    fn len(&self) -> usize {
        self.material.len()
    }

    fn shrink_to_fit(&mut self) {
        self.centre0.shrink_to_fit();
        self.centre1.shrink_to_fit();
        self.radius.shrink_to_fit();
        self.time0.shrink_to_fit();
        self.time1.shrink_to_fit();
        self.material.shrink_to_fit();
    }

    fn material(&self, i: usize) -> u32 {
        self.material[i]
    }

    /// The centre moves on a line, so the boxes at the shutter's two ends cover the path.
    fn bounds(&self, i: usize, shutter: [f32; 2]) -> Aabb {
        let r = self.radius[i];
        sphere_bounds(self.centre_at(i, shutter[0]), r)
            .union(sphere_bounds(self.centre_at(i, shutter[1]), r))
    }

    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<ShapeHit> {
        let (ray, radius) = (&query.ray, self.radius[i]);
        let centre = self.centre_at(i, ray.time);
        // The box at the ray's time lies in the structures' box over any shutter that
        // holds the time: the centre moves monotonically, and the margin grows with it.
        sphere(ray, centre, radius, query.t_min, t_max)
            .filter(|&t| query.holds(trusted_sphere_box(centre, radius, query.options), t))
            .map(ShapeHit::at)
    }

    fn normal(&self, i: usize, p: Vec3, _u: f32, _v: f32, time: f32) -> Vec3 {
        ((p - self.centre_at(i, time)) / self.radius[i]).normalize_or_zero()
    }

    /// The sphere's, about the centre the test used at the ray's `time`.
    fn surface_point(&self, i: usize, ray: &Ray, t: f32, _u: f32, _v: f32) -> SurfacePoint {
        sphere_surface_point(self.centre_at(i, ray.time), self.radius[i], ray, t)
    }

    const ROOTS_MARGIN: bool = true;

    const MOVING: bool = true;

    fn geometric_normal64(&self, i: usize, p: DVec3, _u: f32, _v: f32) -> DVec3 {
        (p - self.centre_at(i, 0.0).as_dvec3()) / f64::from(self.radius[i])
    }
}
