//! Eric Haines' SPD sphereflake ("balls"), as in the course's `balls_*` scenes: a sphere
//! of radius 0.5 at the origin, and around every sphere nine children a third its size,
//! touching it, three above its equator and six on it, recursively.
//!
//! The floor is the SPD's 24 x 24 square (`p 4`), which the course's reference images
//! show, where the course files say `pl` (the infinite plane).

use glam::{DMat3, DVec3};

use super::{Camera, Finish, Header, P3fWriter};
use crate::plural::count;

/// Sphereflake depths give `(9^(depth + 1) - 1) / 8` spheres; beyond this the count
/// would pass 50 million.
pub const MAX_DEPTH: u32 = 7;

/// The child radius over the parent radius.
const CHILD_SCALE: f64 = 1.0 / 3.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    pub centre: DVec3,
    pub radius: f64,
}

/// Number of spheres of a sphereflake of `depth` levels below the root.
pub fn sphere_count(depth: u32) -> usize {
    (9usize.pow(depth + 1) - 1) / 8
}

/// The nine child directions of a sphere whose axis is +Z. They come in three trios
/// turned by 120 degrees about the axis; each trio holds one direction 54.7 degrees above
/// the equator (azimuth 45) and two on it (azimuths 15 and 75), in the SPD order.
fn child_directions() -> [DVec3; 9] {
    let elevation_sin = 2.0 / 6f64.sqrt();
    let elevation_cos = (1.0 - elevation_sin * elevation_sin).sqrt();
    let on_circle = |azimuth_deg: f64, cos_el: f64, sin_el: f64| {
        let (s, c) = azimuth_deg.to_radians().sin_cos();
        DVec3::new(c * cos_el, s * cos_el, sin_el)
    };
    let mut dirs = [DVec3::ZERO; 9];
    for trio in 0..3 {
        let turn = 120.0 * trio as f64;
        dirs[3 * trio] = on_circle(45.0 + turn, elevation_cos, elevation_sin);
        dirs[3 * trio + 1] = on_circle(15.0 + turn, 1.0, 0.0);
        dirs[3 * trio + 2] = on_circle(75.0 + turn, 1.0, 0.0);
    }
    dirs
}

/// The rotation about `Z x axis` that takes +Z onto the unit vector `axis`.
fn rotation_from_z(axis: DVec3) -> DMat3 {
    if axis.z >= 1.0 {
        DMat3::IDENTITY
    } else if axis.z <= -1.0 {
        DMat3::from_rotation_y(std::f64::consts::PI)
    } else {
        let about = DVec3::Z.cross(axis).normalize();
        DMat3::from_axis_angle(about, axis.z.clamp(-1.0, 1.0).acos())
    }
}

/// The spheres of a sphereflake, each parent before its children (depth first), the
/// order of the SPD program and of the course files.
pub fn sphereflake(depth: u32) -> Vec<Ball> {
    let mut balls = Vec::with_capacity(sphere_count(depth));
    let dirs = child_directions();
    let root = Ball {
        centre: DVec3::ZERO,
        radius: 0.5,
    };
    grow(&mut balls, &dirs, root, DVec3::Z, depth);
    balls
}

fn grow(balls: &mut Vec<Ball>, dirs: &[DVec3; 9], ball: Ball, axis: DVec3, depth: u32) {
    balls.push(ball);
    if depth == 0 {
        return;
    }
    let rotation = rotation_from_z(axis);
    // Children touch their parent: centres at parent radius + child radius.
    let distance = ball.radius * (1.0 + CHILD_SCALE);
    for &dir in dirs {
        let child_axis = rotation * dir;
        let child = Ball {
            centre: ball.centre + child_axis * distance,
            radius: ball.radius * CHILD_SCALE,
        };
        grow(balls, dirs, child, child_axis, depth - 1);
    }
}

/// The `balls` scene: the sphereflake over a floor square, with the camera, lights and
/// materials of the course's `balls_*` files.
pub fn balls_scene(depth: u32, env: Option<&str>) -> String {
    let balls = sphereflake(depth);
    let mut w = P3fWriter::new(&Header {
        comment: &format!(
            "Sphereflake of depth {depth} ({}) after Eric Haines' SPD 'balls',\n\
             made by: p3trace gen balls --depth {depth}",
            count(balls.len() as u64, "sphere", "spheres")
        ),
        background: DVec3::new(0.078, 0.361, 0.753),
        env,
        camera: Camera {
            from: DVec3::new(2.1, 1.3, 1.7),
            at: DVec3::ZERO,
            up: DVec3::Z,
            angle: 45.0,
            resolution: (512, 512),
            aperture: 0.0,
            focal: 1.0,
        },
    });
    for light in [[4.0, 3.0, 2.0], [1.0, -4.0, 4.0], [-3.0, 1.0, 5.0]] {
        w.light(DVec3::from_array(light));
    }
    w.line("# floor: the SPD's 24 x 24 square (the course files say 'pl', the infinite plane)");
    w.finish(&Finish {
        diffuse: DVec3::new(1.0, 0.75, 0.33),
        kd: 1.0,
        specular: DVec3::new(1.0, 1.0, 0.8),
        ks: 0.0,
        shine: 10.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    w.line("p 4");
    for [x, y] in [[12.0, 12.0], [-12.0, 12.0], [-12.0, -12.0], [12.0, -12.0]] {
        w.directive("", &[x, y, -0.5]);
    }
    w.finish(&Finish {
        diffuse: DVec3::new(1.0, 0.9, 0.7),
        kd: 0.5,
        specular: DVec3::ONE,
        ks: 0.5,
        shine: 30.0827,
        transmittance: 0.0,
        ior: 1.0,
    });
    for ball in &balls {
        w.sphere(ball.centre, ball.radius);
    }
    w.into_text()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_follow_nine_children_per_sphere() {
        for (depth, count) in [(0, 1), (1, 10), (2, 91), (4, 7381)] {
            assert_eq!(sphere_count(depth), count);
            assert_eq!(sphereflake(depth).len(), count);
        }
    }

    #[test]
    fn child_directions_are_unit_and_distinct() {
        let dirs = child_directions();
        for (i, a) in dirs.iter().enumerate() {
            assert!((a.length() - 1.0).abs() < 1e-12);
            assert!(
                a.z >= -1e-12,
                "children never point below the parent's equator"
            );
            for b in &dirs[i + 1..] {
                assert!(a.dot(*b) < 0.9, "{a} and {b} too close");
            }
        }
    }

    #[test]
    fn rotation_takes_z_to_the_axis() {
        for axis in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(1.0, -2.0, 0.5).normalize(),
        ] {
            let r = rotation_from_z(axis);
            assert!((r * DVec3::Z - axis).length() < 1e-12, "{axis}");
            assert!((r.determinant() - 1.0).abs() < 1e-12);
        }
    }
}
