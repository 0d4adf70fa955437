use glam::Vec3;

use super::first_root_in;
use crate::ray::Ray;

/// Ray-sphere test. The report's early exit comes first: an origin outside the sphere with
/// the centre behind it is a miss before the discriminant is computed. The discriminant is
/// taken as `r^2 - |perpendicular offset|^2` and the near root as `c / q`, which keeps
/// precision for large spheres seen from close by (the random scene's ground has radius
/// 1000). A sphere of radius zero or less is never hit.
pub fn sphere(ray: &Ray, centre: Vec3, radius: f32, t_min: f32, t_max: f32) -> Option<f32> {
    let oc = centre - ray.origin;
    let b = oc.dot(ray.dir);
    let c = oc.dot(oc) - radius * radius;
    if c > 0.0 && b < 0.0 {
        return None;
    }
    let perpendicular = oc - b * ray.dir;
    let disc = radius * radius - perpendicular.dot(perpendicular);
    if !(disc >= 0.0 && radius > 0.0) {
        return None;
    }
    let q = b + disc.sqrt().copysign(b);
    let (r0, r1) = (c / q, q);
    let (near, far) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
    first_root_in(near, far, t_min, t_max)
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
