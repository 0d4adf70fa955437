//! Scenes at any scale and far from the origin (P3F.md 4, issue 17): every course scene of
//! `../shared/scenes` and every scene of `scenes/`, rewritten with every length multiplied
//! by 1000 or by 0.001, or every position moved by (1000, -1000, 1000), renders as the
//! scene itself does. The scenes are rewritten as text, as a user converting units would,
//! so the reader's handling of far positions is tested with the offsets of spawned rays.
//!
//! Scaling by 1024 or 1/1024 changes no digit of a float, so those images must be the
//! scene's own: that holds the offsets to their scale. Scaling by 1000 rounds every
//! number of the scene anew, and a scene of many small mirrors (balls_high) turns that
//! into visible differences whatever the renderer does: the same scene with every number
//! multiplied by 1 + 1e-7 differs as much. So the 99.9% floor of scaled scenes gives way,
//! for a scene that differs more than that from itself so perturbed, to that control's
//! share less half a point.

use crate::common;

use std::path::Path;

use glam::Vec3;
use p3trace::accel::AccelOptions;
use p3trace::compare::{compare, Levels};
use p3trace::imaging::to_byte;
use p3trace::intersect::{spawn_origin, IntersectOptions, RayQuery, Shapes, Spheres, Triangles};
use p3trace::ray::Ray;
use p3trace::render::{render, RenderOptions};
use p3trace::scene::{parse_str_in, Frame};
use proptest::prelude::*;

/// How a number of a directive changes: a coordinate of a position, a length, or not.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Position(usize),
    Length,
    Kept,
}

/// The roles of the numbers that follow `directive` (`count` of them), by P3F.md 2 and 3.
fn roles(directive: &str, numbers: &[f64]) -> Vec<Role> {
    use Role::*;
    let point = [Position(0), Position(1), Position(2)];
    let kept = |n: usize| vec![Kept; n];
    let mut roles: Vec<Role> = match directive {
        "from" | "at" | "l" => point.to_vec(),
        // `focal` is a multiple of the view distance, not a length (P3F.md 3).
        "hither" => vec![Length],
        "al" => [&point[..], &point[..], &[Length, Length]].concat(),
        "s" => [&point[..], &[Length]].concat(),
        "ms" | "sm" => [&point[..], &point[..], &[Length]].concat(),
        "pl" | "box" => point.repeat(if directive == "pl" { 3 } else { 2 }),
        "c" => [&point[..], &[Length], &point[..], &[Length]].concat(),
        "p" => [&[Kept][..], &point.repeat(numbers[0] as usize)].concat(),
        "pp" => {
            let vertex = [&point[..], &kept(3)].concat();
            [&[Kept][..], &vertex.repeat(numbers[0] as usize)].concat()
        }
        "mesh" => [&kept(2)[..], &point.repeat(numbers[0] as usize)].concat(),
        _ => Vec::new(),
    };
    roles.resize(numbers.len(), Kept);
    roles
}

/// `text` with every position `p` made `scale p + shift` and every length `scale l`.
fn transformed(text: &str, scale: f64, shift: [f64; 3]) -> String {
    let tokens: Vec<&str> = text
        .lines()
        .flat_map(|line| line.split('#').next().unwrap_or("").split_whitespace())
        .collect();
    let mut out = String::new();
    let mut i = 0;
    while i < tokens.len() {
        let directive = tokens[i];
        out.push('\n');
        out.push_str(directive);
        i += 1;
        let start = i;
        while i < tokens.len() && tokens[i].parse::<f64>().is_ok() {
            i += 1;
        }
        let numbers: Vec<f64> = tokens[start..i]
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        for ((number, role), token) in numbers
            .iter()
            .zip(roles(directive, &numbers))
            .zip(&tokens[start..i])
        {
            let written = match role {
                Role::Position(axis) => format!("{:?}", number * scale + shift[axis]),
                Role::Length => format!("{:?}", number * scale),
                Role::Kept => token.to_string(),
            };
            out.push(' ');
            out.push_str(&written);
        }
    }
    out
}

fn levels(text: &str, name: &str, dir: &Path) -> Levels {
    let scene =
        parse_str_in(text, name, dir, Frame::Camera).unwrap_or_else(|e| panic!("{name}: {e}"));
    // The BVH whatever the file asks: several course files ask for brute force.
    let options = RenderOptions {
        width: 160,
        height: 120,
        accel: AccelOptions::default(),
        ..RenderOptions::from_scene(&scene)
    };
    let film = render(&scene, &options).unwrap().film;
    Levels {
        width: film.width,
        height: film.height,
        rgb: film
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(|x| to_byte(x) as f32))
            .collect(),
    }
}

/// Renders each of `files` as written, scaled and moved, and checks each variant's share
/// of pixels within 2 levels of the scene's own image (see the top of this file).
fn check(files: Vec<std::path::PathBuf>) {
    const SCALED: f64 = 0.999;
    let mut failures = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        let dir = file.parent().unwrap();
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        let own = levels(&text, &name, dir);
        let share = |scale: f64, shift: [f64; 3]| {
            let other = levels(&transformed(&text, scale, shift), &name, dir);
            compare(&own, &other, 2.0).unwrap().within_tolerance
        };
        let control = share(1.0 + 1e-7, [0.0; 3]);
        let rounded = if control >= SCALED {
            SCALED
        } else {
            control - 0.005
        };
        let variants = [
            ("x1024", share(1024.0, [0.0; 3]), SCALED),
            ("x1/1024", share(1.0 / 1024.0, [0.0; 3]), SCALED),
            ("x1000", share(1000.0, [0.0; 3]), rounded),
            ("x0.001", share(0.001, [0.0; 3]), rounded),
            ("moved", share(1.0, [1000.0, -1000.0, 1000.0]), 0.995),
        ];
        let mut line = format!("{name}: control x(1 + 1e-7) {:.3}%", 100.0 * control);
        for (variant, share, least) in variants {
            line += &format!(", {variant} {:.3}%", 100.0 * share);
            if share < least {
                failures.push(format!("{name} {variant}: {:.3}%", 100.0 * share));
            }
        }
        eprintln!("{line}");
    }
    assert!(failures.is_empty(), "{failures:?}");
}

fn p3f_files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "p3f"))
        .collect();
    files.sort();
    files
}

#[test]
fn course_scenes_render_alike_at_any_scale_and_place() {
    let Some(shared) = common::shared() else {
        return;
    };
    check(p3f_files(&shared.join("scenes")));
}

#[test]
fn project_scenes_render_alike_at_any_scale_and_place() {
    check(p3f_files(&common::project_file("scenes")));
}

#[test]
fn the_rewrite_scales_positions_and_lengths_only() {
    let text = "v from 1 2 3 at 0 0 0 up 0 0 1 angle 45 hither 0.5 resolution 8 8\n\
                l 1 1 1 0.5 0.5 0.5\nf 1 0 0 1 1 1 1 1 10 0 1\ns 1 2 3 0.5\n\
                p 3\n0 0 0\n1 0 0\n0 1 0\nc 0 0 0 1 0 0 2 0.5 # a cone\n";
    let moved = transformed(text, 2.0, [10.0, 0.0, 0.0]);
    assert_eq!(
        moved.split_whitespace().collect::<Vec<_>>().join(" "),
        "v from 12.0 4.0 6.0 at 10.0 0.0 0.0 up 0 0 1 angle 45 hither 1.0 resolution 8 8 \
         l 12.0 2.0 2.0 0.5 0.5 0.5 f 1 0 0 1 1 1 1 1 10 0 1 s 12.0 4.0 6.0 1.0 \
         p 3 10.0 0.0 0.0 12.0 0.0 0.0 10.0 2.0 0.0 c 10.0 0.0 0.0 2.0 10.0 0.0 4.0 1.0"
    );
}

/// `ray` as the standard profile's primitive tests take it, from `t = 0`.
fn query(ray: &Ray) -> RayQuery {
    RayQuery::new(ray, 0.0, IntersectOptions::default())
}

/// A unit vector from two numbers in [0, 1).
fn unit(a: f32, b: f32) -> Vec3 {
    let z = 2.0 * a - 1.0;
    let phi = std::f32::consts::TAU * b;
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// A direction on the side `side` of a surface, at least about 0.06 degrees off it.
fn leaving(side: Vec3, a: f32, b: f32) -> Vec3 {
    let d = unit(a, b);
    let d = if d.dot(side) < 0.0 {
        d - 2.0 * d.dot(side) * side
    } else {
        d
    };
    (d + 0.001 * side).normalize()
}

proptest! {
    #![proptest_config(ProptestConfig {
        max_global_rejects: 2000,
        ..ProptestConfig::with_cases(20000)
    })]

    /// A ray spawned at a sphere's hit never meets the sphere again on the way out, and
    /// going in it meets the far side, at any size and any distance from the origin.
    #[test]
    fn rays_spawned_off_a_sphere_clear_it(
        centre in prop::array::uniform3(-1e4f32..1e4),
        log_radius in -3.0f32..3.0,
        (a, b, c, d, e, f) in (0f32..1.0, 0f32..1.0, 0f32..1.0, 0f32..1.0, 0f32..1.0, 0f32..1.0),
        distance in 1.5f32..100.0,
    ) {
        // A sphere a few floats wide at its place is a point: keep it 1e4 times wider
        // than its centre's floats.
        let centre = Vec3::from(centre);
        let radius = 10f32.powf(log_radius).max(1e-4 * centre.abs().max_element());
        let mut spheres = Spheres::default();
        spheres.push(centre, radius, 0);
        let origin = centre + distance * radius * unit(a, b);
        let target = centre + 0.95 * radius * unit(c, d);
        let ray = Ray::new(origin, (target - origin).normalize());
        let hit = spheres.intersect(0, &query(&ray), f32::INFINITY);
        // Rejected, not passed: too many misses fail the test.
        prop_assume!(hit.is_some());
        let hit = hit.unwrap();
        let at = spheres.surface_point(0, &ray, hit.t, hit.u, hit.v);
        let out = leaving(at.normal, e, f);
        let away = Ray::new(spawn_origin(at.point, at.error, at.normal), out);
        prop_assert_eq!(spheres.intersect(0, &query(&away), f32::INFINITY), None);
        let inward = Ray::new(spawn_origin(at.point, at.error, -at.normal), -out);
        // The chord is 2 r cos, for the cosine with the inward normal.
        let chord = 2.0 * radius * out.dot(at.normal);
        let far = spheres.intersect(0, &query(&inward), f32::INFINITY);
        prop_assert!(far.is_some_and(|h| h.t > 0.5 * chord), "{far:?}, chord {chord}");
    }

    /// A ray spawned at a triangle's hit, on either side, never meets the triangle again,
    /// slivers included.
    #[test]
    fn rays_spawned_off_a_triangle_clear_it(
        at in prop::array::uniform3(-1e4f32..1e4),
        log_size in -3.0f32..3.0,
        corners in prop::array::uniform6(-1f32..1.0),
        (a, b, c, d, e) in (0f32..1.0, 0f32..1.0, 0f32..1.0, 0f32..1.0, 0f32..1.0),
    ) {
        let size = 10f32.powf(log_size);
        let p0 = Vec3::from(at);
        let p1 = p0 + size * Vec3::new(corners[0], corners[1], corners[2]);
        let p2 = p0 + size * Vec3::new(corners[3], corners[4], corners[5]);
        let mut triangles = Triangles::default();
        triangles.push([p0, p1, p2], None, 0);
        // Inside, away from the edges.
        let (u, v) = (0.05 + 0.85 * a * (1.0 - b), 0.05 + 0.85 * b * (1.0 - a));
        let target = p0 + u * (p1 - p0) + v * (p2 - p0);
        let origin = target + 10.0 * size * unit(c, d);
        let ray = Ray::new(origin, (target - origin).normalize());
        let hit = triangles.intersect(0, &query(&ray), f32::INFINITY);
        // Rejected, not passed: too many misses fail the test.
        prop_assume!(hit.is_some());
        let hit = hit.unwrap();
        let at = triangles.surface_point(0, &ray, hit.t, hit.u, hit.v);
        for side in [at.normal, -at.normal] {
            let away = Ray::new(spawn_origin(at.point, at.error, side), leaving(side, e, c));
            let again = triangles.intersect(0, &query(&away), f32::INFINITY);
            prop_assert_eq!(again, None);
        }
    }
}
