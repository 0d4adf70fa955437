use glam::Vec3;

use super::first_root_in;
use crate::ray::Ray;

/// Slab test against the axis-aligned box `[min, max]`, with `inv_dir = 1 / ray.dir`
/// computed once per ray. Returns the entry distance, or the exit distance when the
/// origin is inside (or the entry is before `t_min`). `f32::min`/`max` drop the NaN that
/// `0 * inf` gives for a ray lying in a slab's plane.
pub fn aabb(ray: &Ray, inv_dir: Vec3, min: Vec3, max: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
    let t1 = (min - ray.origin) * inv_dir;
    let t2 = (max - ray.origin) * inv_dir;
    let near = t1.min(t2).max_element();
    let far = t1.max(t2).min_element();
    if !(near <= far) {
        return None;
    }
    first_root_in(near, far, t_min, t_max)
}

/// Outward normal of the face of `[min, max]` nearest to the point `p` (a hit point).
pub fn aabb_normal(min: Vec3, max: Vec3, p: Vec3) -> Vec3 {
    let mut best = (f32::INFINITY, Vec3::X);
    for axis in 0..3 {
        let mut normal = Vec3::ZERO;
        normal[axis] = -1.0;
        let to_min = (p[axis] - min[axis]).abs();
        if to_min < best.0 {
            best = (to_min, normal);
        }
        normal[axis] = 1.0;
        let to_max = (max[axis] - p[axis]).abs();
        if to_max < best.0 {
            best = (to_max, normal);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test(o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let ray = Ray::new(o, d.normalize());
        aabb(
            &ray,
            ray.dir.recip(),
            Vec3::splat(-1.0),
            Vec3::splat(1.0),
            t_min,
            t_max,
        )
    }

    #[test]
    fn from_outside_returns_entry() {
        let t = test(Vec3::new(0., 0., -5.), Vec3::Z, 0.0, f32::INFINITY);
        assert_eq!(t, Some(4.0));
    }

    #[test]
    fn from_inside_returns_exit() {
        let t = test(Vec3::new(0., 0.5, 0.), Vec3::Y, 0.0, f32::INFINITY);
        assert_eq!(t, Some(0.5));
    }

    #[test]
    fn misses_and_behind() {
        assert_eq!(
            test(Vec3::new(0., 2., -5.), Vec3::Z, 0.0, f32::INFINITY),
            None
        );
        assert_eq!(
            test(Vec3::new(0., 0., 5.), Vec3::Z, 0.0, f32::INFINITY),
            None
        );
        assert_eq!(test(Vec3::new(0., 0., -5.), Vec3::Z, 0.0, 3.0), None);
    }

    #[test]
    fn axis_parallel_ray_on_a_face_plane_does_not_panic() {
        // Origin on the plane y = 1 with dir.y = 0: 0 * inf is NaN in that slab.
        let t = test(Vec3::new(0., 1., -5.), Vec3::Z, 0.0, f32::INFINITY);
        assert!(t.is_none() || t == Some(4.0));
    }

    #[test]
    fn diagonal_ray_hits_corner_region() {
        let t = test(Vec3::splat(-3.0), Vec3::ONE, 0.0, f32::INFINITY).unwrap();
        assert!((t - 2.0 * 3f32.sqrt()).abs() < 1e-5);
    }

    #[test]
    fn normal_is_the_face_hit() {
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(aabb_normal(lo, hi, Vec3::new(0.1, 0.2, -1.0)), Vec3::NEG_Z);
        assert_eq!(aabb_normal(lo, hi, Vec3::new(0.1, 2.0, 0.3)), Vec3::Y);
        assert_eq!(aabb_normal(lo, hi, Vec3::new(1.0, 0.0, 0.3)), Vec3::X);
    }
}
