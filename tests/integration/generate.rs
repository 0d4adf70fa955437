//! The project's scene library: the generators against the course files and against
//! their own geometry, the files in `scenes/` against their generators, and every scene
//! in `scenes/` through the renderer.

use crate::common;

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use glam::{DVec3, Vec3};
use p3trace::generate::dragon::dragon_scene;
use p3trace::generate::mountain::{mount_scene, mountain};
use p3trace::generate::random::random_scene;
use p3trace::generate::skybox::{face_image, sky_colour, Up};
use p3trace::generate::sphereflake::{balls_scene, sphere_count, sphereflake};
use p3trace::imaging::to_byte;
use p3trace::render::skybox::{Face, Skybox};
use p3trace::render::{render, RenderOptions};
use p3trace::scene::p3f::parse_text;
use p3trace::scene::parse_file;
use p3trace::scene::ply::{read_ply, Mesh};

#[test]
fn sphereflake_matches_the_course_files_sphere_for_sphere() {
    let Some(shared) = common::shared() else {
        return;
    };
    for (depth, name) in [(1, "balls_low"), (2, "balls_medium"), (4, "balls_high")] {
        let course = parse_file(&shared.join(format!("scenes/{name}.p3f"))).unwrap();
        let ours = parse_text(&balls_scene(depth, None)).unwrap();
        let (a, b) = (&course.geometry.spheres, &ours.geometry.spheres);
        assert_eq!(a.records.len(), b.records.len(), "{name}");
        for i in 0..a.records.len() {
            let centre = (a.records[i].centre - b.records[i].centre)
                .abs()
                .max_element();
            let radius = (a.records[i].radius - b.records[i].radius).abs();
            assert!(
                centre <= 1e-5 && radius <= 1e-5,
                "{name} sphere {i}: course {} r {}, ours {} r {}",
                a.records[i].centre,
                a.records[i].radius,
                b.records[i].centre,
                b.records[i].radius
            );
        }
    }
}

#[test]
fn sphereflake_is_self_similar() {
    for (depth, count) in [(1, 10), (2, 91), (4, 7381)] {
        assert_eq!(sphereflake(depth).len(), count);
        assert_eq!(sphere_count(depth), count);
    }
    let balls = sphereflake(3);
    assert_eq!(balls[0].centre, DVec3::ZERO);
    assert_eq!(balls[0].radius, 0.5);
    // Every sphere but the root touches a parent three times its size, and every sphere
    // above the smallest size has nine children.
    let mut children = vec![0; balls.len()];
    for (i, child) in balls.iter().enumerate().skip(1) {
        let parents: Vec<usize> = (0..i)
            .filter(|&j| {
                let p = &balls[j];
                (p.radius - 3.0 * child.radius).abs() < 1e-12
                    && (p.centre.distance(child.centre) - (p.radius + child.radius)).abs() < 1e-9
            })
            .collect();
        assert_eq!(parents.len(), 1, "sphere {i} touches {parents:?}");
        children[parents[0]] += 1;
    }
    let smallest = balls.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min);
    for (ball, n) in balls.iter().zip(children) {
        let expected = if ball.radius > smallest { 9 } else { 0 };
        assert_eq!(n, expected, "{ball:?}");
    }
    // No two spheres overlap: they touch at most.
    for (i, a) in balls.iter().enumerate() {
        for b in &balls[i + 1..] {
            let gap = a.centre.distance(b.centre) - (a.radius + b.radius);
            assert!(gap > -1e-9, "{a:?} and {b:?} overlap by {}", -gap);
        }
    }
}

/// Heights of a mountain by position, to compare levels.
fn heights(level: u32, seed: u64) -> HashMap<(i64, i64), f64> {
    let key = |v: f64| (v * 1024.0).round() as i64;
    mountain(level, seed)
        .vertices
        .iter()
        .map(|v| ((key(v.x), key(v.y)), v.z))
        .collect()
}

#[test]
fn mountain_levels_refine_one_reproducible_shape() {
    let coarse = heights(1, 0);
    let fine = heights(5, 0);
    assert_eq!(coarse.len(), 9);
    for (at, h) in &coarse {
        assert_eq!(fine[at], *h, "level 5 moved the level-1 vertex {at:?}");
    }
    assert_eq!(heights(5, 0), fine, "the same seed gives the same mountain");
    let other = heights(5, 1);
    let moved = fine.iter().filter(|(at, h)| other[*at] != **h).count();
    assert!(moved > fine.len() / 2, "another seed moves most vertices");
    // The corners stay at height 0, as in the course's files.
    for corner in [(-1024, -1024), (1024, -1024), (-1024, 1024), (1024, 1024)] {
        assert_eq!(fine[&corner], 0.0);
    }
}

#[test]
fn mountain_mesh_is_watertight_over_the_square() {
    let m = mountain(4, 9);
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let on_border = |i: u32| {
        let v = m.vertices[i as usize];
        v.x.abs() == 1.0 || v.y.abs() == 1.0
    };
    for ((a, b), n) in edges {
        let border = on_border(a) && on_border(b) && {
            let (p, q) = (m.vertices[a as usize], m.vertices[b as usize]);
            p.x == q.x || p.y == q.y
        };
        assert_eq!(n, if border { 1 } else { 2 }, "edge {a}-{b}");
    }
}

#[test]
fn mount_scenes_have_the_course_counts_and_spheres_clear_of_the_rock() {
    for (level, triangles) in [(1, 8), (5, 2048), (7, 32768)] {
        let scene = parse_text(&mount_scene(level, 0, None)).unwrap();
        let g = &scene.geometry;
        assert_eq!(g.triangles.corners.len(), triangles, "level {level}");
        assert_eq!(g.spheres.records.len(), 4);
        // The glass spheres float: every vertex below a sphere lies beneath its bottom.
        for s in 0..4 {
            let (c, r) = (g.spheres.records[s].centre, g.spheres.records[s].radius);
            for t in 0..triangles {
                let v = g.triangles.vertices(t)[0];
                if v.truncate().distance(c.truncate()) <= r {
                    assert!(
                        v.z < c.z - r,
                        "level {level}: rock at {v} inside sphere {s}"
                    );
                }
            }
        }
    }
}

#[test]
fn random_scene_follows_section_8() {
    let scene = parse_text(&random_scene(3, None)).unwrap();
    let s = &scene.geometry.spheres;
    let n = s.records.len();
    assert!(n > 60 && n <= 1 + 81 + 3, "{n} spheres");
    assert_eq!(
        (s.records[0].centre, s.records[0].radius),
        (Vec3::new(0., -1000., 0.), 1000.)
    );
    for i in 1..n - 3 {
        let c = s.records[i].centre;
        assert_eq!((c.y, s.records[i].radius), (0.2, 0.2));
        assert!(c.distance(Vec3::new(4.0, 0.2, 0.0)) > 0.9);
        let m = scene.materials[s.records[i].material as usize];
        let diffuse = m.kd == 1.0 && m.ks == 0.0;
        let metal = m.kd == 0.0 && m.ks == 1.0 && m.specular.min_element() >= 0.5;
        let glass = m.transmittance == 1.0 && m.ior == 1.5 && m.ks == 0.7;
        assert!(diffuse || metal || glass, "sphere {i}: {m:?}");
    }
    let big: Vec<Vec3> = (n - 3..n).map(|i| s.records[i].centre).collect();
    assert_eq!(
        big,
        [
            Vec3::new(0., 1., 0.),
            Vec3::new(-4., 1., 0.),
            Vec3::new(4., 1., 0.)
        ]
    );
    assert_eq!(scene.lights.len(), 3);
    assert_eq!((scene.camera.width, scene.camera.height), (800, 600));
    assert!(scene.skybox.is_none());
    assert_ne!(random_scene(3, None), random_scene(4, None));
}

#[test]
fn generated_files_in_scenes_match_their_generators() {
    let env = Some("sky_zup");
    let cases = [
        ("balls_low", balls_scene(1, env)),
        ("balls_medium", balls_scene(2, env)),
        ("balls_high", balls_scene(4, env)),
        ("mount_low", mount_scene(1, 0, env)),
        ("mount_high", mount_scene(5, 0, env)),
        ("random", random_scene(0, None)),
    ];
    for (name, text) in cases {
        let path = common::project_file(&format!("scenes/{name}.p3f"));
        let file = std::fs::read_to_string(&path).unwrap();
        assert!(
            file == text,
            "scenes/{name}.p3f differs from its generator: regenerate it with the command \
             in its first lines, from the project's folder with -o scenes/{name}.p3f"
        );
    }
}

#[test]
fn skybox_faces_in_scenes_are_the_generated_ones_and_read_back_as_the_sky() {
    for (dir, up) in [("scenes/sky_zup", Up::Z), ("scenes/sky_yup", Up::Y)] {
        let dir = common::project_file(dir);
        for face in Face::ALL {
            let file = image::open(dir.join(format!("{}.png", face.name())))
                .unwrap()
                .into_rgb8();
            assert!(file == face_image(face, 256, up), "{} differs", face.name());
        }
        // Through the renderer's lookup, a texel's own direction reads that texel.
        let sky = Skybox::load(&dir).unwrap();
        for face in Face::ALL {
            for (column, row) in [(0u32, 0u32), (17, 200), (128, 128), (255, 3)] {
                let sc = 2.0 * column as f32 / 255.0 - 1.0;
                let tc = 2.0 * (255 - row) as f32 / 255.0 - 1.0;
                let d = face.direction(sc, tc) * 0.999; // stay off the cube's edges
                let expected = sky_colour(face.direction(sc, tc), up)
                    .to_array()
                    .map(|x| to_byte(x) as f32 / 255.99);
                assert_eq!(
                    sky.lookup(d).to_array(),
                    expected,
                    "{face:?} {column},{row}"
                );
            }
        }
    }
}

fn write_gzipped_ply(path: &Path, mesh: &Mesh) {
    let mut text = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    );
    for [x, y, z] in &mesh.vertices {
        text += &format!("{x} {y} {z}\n");
    }
    for [a, b, c] in &mesh.triangles {
        text += &format!("3 {a} {b} {c}\n");
    }
    let file = std::fs::File::create(path).unwrap();
    let mut gz = flate2::write::GzEncoder::new(file, flate2::Compression::fast());
    gz.write_all(text.as_bytes()).unwrap();
    gz.finish().unwrap();
}

#[test]
fn dragon_scene_places_a_gzipped_ply_model_on_the_floor() {
    // A long tetrahedron in the Stanford scan's frame: its length along X.
    let model = Mesh {
        vertices: vec![
            [0.0, 0.1, 0.0],
            [0.2, 0.1, 0.0],
            [0.1, 0.2, 0.02],
            [0.1, 0.15, 0.05],
        ],
        triangles: vec![[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 2, 3]],
    };
    let dir = common::scratch("dragon_ply");
    let path = dir.join("model.ply.gz");
    write_gzipped_ply(&path, &model);
    let mesh = read_ply(&path).unwrap();
    assert_eq!(mesh, model);

    let scene = parse_text(&dragon_scene(&mesh, "model.ply.gz", None)).unwrap();
    let t = &scene.geometry.triangles;
    // The floor square (two triangles) and the model's four.
    assert_eq!(t.corners.len(), 2 + 4);
    assert_eq!(scene.mesh_triangles, 4);
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for i in 2..6 {
        for v in t.vertices(i) {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
    }
    assert!((lo.y + 0.6).abs() < 1e-5, "stands on the floor: {lo}");
    assert!(
        (hi.z - lo.z - 1.77).abs() < 1e-5,
        "1.77 long along Z: {lo} {hi}"
    );
    assert!(
        (lo.x + hi.x).abs() < 1e-5 && (lo.z + hi.z).abs() < 1e-5,
        "centred"
    );
    assert_eq!(scene.geometry.spheres.records.len(), 2);
    assert_eq!(scene.geometry.boxes.min.x.len(), 1);
}

#[test]
fn every_scene_in_scenes_renders() {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(common::project_file("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "p3f") {
            continue;
        }
        names.push(path.file_name().unwrap().to_string_lossy().into_owned());
        let scene = parse_file(&path).unwrap();
        assert!(
            scene.warnings.is_empty(),
            "{}: {:?}",
            scene.name,
            scene.warnings
        );
        let mut options = RenderOptions::from_scene(&scene);
        (options.width, options.height) = (32, 24);
        let report = render(&scene, &options).unwrap();
        assert!(
            report.warnings.is_empty(),
            "{}: {:?}",
            scene.name,
            report.warnings
        );
        let bytes = report.film.to_rgb8();
        let first = &bytes[..3];
        assert!(
            bytes.chunks(3).any(|p| p != first),
            "{}: a single colour",
            scene.name
        );
    }
    names.sort();
    assert!(names.len() >= 10, "scenes/ holds only {names:?}");
}
