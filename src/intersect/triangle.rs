use glam::Vec3;

use crate::ray::Ray;

/// Distance and barycentric coordinates of a ray-triangle hit: the point is
/// `(1 - u - v) p0 + u p1 + v p2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// Möller-Trumbore test against the triangle `p0, p0 + e1, p0 + e2`. Two-sided; edges and
/// vertices count as inside. A triangle with zero edges (how the scene stores degenerate
/// ones) has a zero determinant and is never hit.
pub fn triangle(
    ray: &Ray,
    p0: Vec3,
    e1: Vec3,
    e2: Vec3,
    t_min: f32,
    t_max: f32,
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
    (t > t_min && t < t_max).then_some(TriangleHit { t, u, v })
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
