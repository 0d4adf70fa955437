//! The P3F reader: every directive, the lexical rules, and errors with file:line:col.

use crate::common;

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use p3trace::prim::PrimKind;
use p3trace::scene::p3f::parse_text;
use p3trace::scene::{parse_file, AccelKind, Light, Material};

const CAMERA: &str = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 64 48\naperture 0\nfocal 1\n";

fn error_of(text: &str) -> String {
    parse_text(text)
        .expect_err("the text should not parse")
        .to_string()
}

#[test]
fn reads_every_directive() {
    let text = format!(
        "accel 2\nspp 3\nbclr 0.1 0.2 0.3\nenv sky\n{CAMERA}\
         l 1 2 3\nl 4 5 6 0.5 0.5 0.5\nal 0 5 0 0 0 0 2 1\nal 0 5 0 0 0 0 2 1 0.2 0.3 0.4\n\
         f 1 0.9 0.7 0.5 1 1 1 0.5 30 0 1\n\
         s 0 0 0 0.5\nms 0 0 0 1 0 0 0.25 0 1\nsm 0 1 0 1 1 0 0.25 0 2\n\
         pl 0 0 0 1 0 0 0 0 1\n\
         p 3 0 0 0 1 0 0 0 1 0\np 5 0 0 0 1 0 0 1 1 0 0.5 1.5 0 0 1 0\n\
         pp 3 0 0 0 0 0 1 1 0 0 0 0 1 0 1 0 0 0 1\n\
         mesh 4 2\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n1 2 3\n1 -2 -1\n\
         box 1 1 1 0 0 0\n\
         c 0 0 0 1 0 2 0 0.5\n"
    );
    let scene = parse_text(&text).unwrap();
    let g = &scene.geometry;
    assert_eq!(scene.accel, Some(AccelKind::Bvh));
    assert_eq!(scene.spp, 3);
    assert_eq!(scene.background, Vec3::new(0.1, 0.2, 0.3));
    let skybox = scene.skybox.as_ref().map(|sky| sky.name.as_path());
    assert_eq!(skybox, Some(Path::new("sky")));
    assert!(scene.has_camera);
    assert_eq!((scene.camera.width, scene.camera.height), (64, 48));
    assert_eq!(scene.lights.len(), 4);
    assert_eq!(
        scene.lights[0],
        Light::Point {
            position: Vec3::new(1., 2., 3.),
            colour: Vec3::ONE
        }
    );
    assert!(
        matches!(scene.lights[3], Light::Area { colour, .. } if colour == Vec3::new(0.2, 0.3, 0.4))
    );
    assert_eq!(scene.materials.len(), 1);
    assert_eq!(g.count(PrimKind::Sphere), 1);
    assert_eq!(g.count(PrimKind::MovingSphere), 2);
    assert_eq!(g.count(PrimKind::Plane), 1);
    // p 3 -> 1, p 5 -> 3 (fan), pp 3 -> 1, mesh -> 2.
    assert_eq!(g.count(PrimKind::Triangle), 7);
    assert_eq!(g.triangles.vertex_normals.len(), 1);
    assert_eq!((scene.meshes, scene.mesh_triangles), (1, 2));
    assert_eq!(g.count(PrimKind::Box), 1);
    assert_eq!(
        (g.boxes.min.get(0), g.boxes.max.get(0)),
        (Vec3::ZERO, Vec3::ONE)
    );
    assert_eq!(g.count(PrimKind::Cone), 1);
    assert_eq!(g.cones.height[0], 2.0);
    assert_eq!(g.cones.axis.get(0), Vec3::Y);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn mesh_negative_indices_count_from_the_end() {
    let scene =
        parse_text("f 1 1 1 1 0 0 0 0 1 0 1\nmesh 3 1\n0 0 0\n1 0 0\n0 1 0\n-3 -2 -1\n").unwrap();
    let t = &scene.geometry.triangles;
    assert_eq!(t.vertices(0), [Vec3::ZERO, Vec3::X, Vec3::Y]);
}

#[test]
fn a_mesh_stores_its_vertices_once() {
    let scene =
        parse_text("mesh 5 3\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n1 2 3\n1 3 4\n1 2 5\n").unwrap();
    let t = &scene.geometry.triangles;
    // The third triangle's corners are in a line: a NaN vertex of its own, never hit.
    assert_eq!(t.positions.len(), 5 + 1);
    assert_eq!(t.corners[1], [0, 2, 3]);
    assert_eq!(
        t.vertices(1),
        [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]
    );
    assert!(t.vertices(2).iter().all(|v| v.is_nan()));
}

#[test]
fn plane_normal_follows_the_triangle_rule() {
    // normalize((p3 - p2) x (p1 - p2)) for the balls' floor points is +z.
    let scene = parse_text("pl 12 12 -0.5 -12 12 -0.5 -12 -12 -0.5").unwrap();
    assert_eq!(scene.geometry.planes.normal.get(0), Vec3::Z);
    assert_eq!(scene.geometry.planes.offset[0], -0.5);
}

#[test]
fn lexical_rules_crlf_comments_and_no_final_newline() {
    let text = "# header comment\r\nf 1 1 1 1 0 0 0 0 1 0 1 #inline comment\r\ns 0 1.5 0 0.5 #main sphere\r\ns 1 2 3 4";
    let scene = parse_text(text).unwrap();
    assert_eq!(scene.geometry.count(PrimKind::Sphere), 2);
    assert_eq!(scene.geometry.spheres.records[1].radius, 4.0);
    assert_eq!(
        scene.geometry.spheres.records[0].centre,
        Vec3::new(0., 1.5, 0.)
    );
}

#[test]
fn numbers_as_printf_g_writes_them() {
    let scene = parse_text("s 1.11022e-16 -0.5 30.0827 1").unwrap();
    let c = scene.geometry.spheres.records[0].centre;
    assert_eq!((c.x, c.y, c.z), (1.11022e-16, -0.5, 30.0827));
}

#[test]
fn object_before_any_material_gets_the_default_with_a_warning() {
    let scene = parse_text("s 0 0 0 1\ns 1 0 0 1").unwrap();
    assert_eq!(scene.materials, vec![Material::DEFAULT]);
    assert_eq!(scene.warnings.len(), 1);
    assert_eq!((scene.warnings[0].line, scene.warnings[0].column), (1, 1));
}

/// A typo in a directive's name is answered with the name meant, where one is near
/// enough to be likely; a word that is no directive at all gets no guess.
#[test]
fn an_unknown_directive_suggests_the_nearest_known_one() {
    for (typo, meant) in [
        ("bclor", "bclr"),
        ("acel", "accel"),
        ("evn", "env"),
        ("msh", "mesh"),
        ("sppp", "spp"),
        ("boxx", "box"),
    ] {
        assert_eq!(
            error_of(&format!("{typo} 1 2 3\n")),
            format!("<text>:1:1: unknown directive '{typo}'; did you mean '{meant}'?")
        );
    }
    for word in ["sphere", "x", "xy", "camera", "light"] {
        assert_eq!(
            error_of(&format!("{word} 1\n")),
            format!("<text>:1:1: unknown directive '{word}'")
        );
    }
}

/// A value missing at the end of a line is reported there, where the directive's values
/// end, not at the next line's word (most often the next directive); a word on the
/// directive's own line is reported where it is.
#[test]
fn a_missing_value_is_reported_where_the_values_end() {
    assert_eq!(
        error_of("l 0 0 0 1 1\nl 1 1 1 1 1 1\n"),
        "<text>:1:12: in 'l': expected a light colour component (a number), \
         found the end of the line ('l' follows on line 2)"
    );
    // Values that run over lines (a triangle's vertices, as the course files write them).
    assert_eq!(
        error_of("p 3\n0 0 0\n1 0 0\n0 1\ns 0 0 0 1\n"),
        "<text>:4:4: in 'p': expected a vertex coordinate (a number), \
         found the end of the line ('s' follows on line 5)"
    );
    assert_eq!(
        error_of("accel\n\ns 0 0 0 1\n"),
        "<text>:1:6: in 'accel': expected the accelerator (0, 1 or 2) (a whole number), \
         found the end of the line ('s' follows on line 3)"
    );
    assert_eq!(
        error_of("l 0 0 0 1 x 1\n"),
        "<text>:1:11: in 'l': expected a light colour component (a number), found 'x'"
    );
}

#[test]
fn errors_name_file_line_column_and_directive() {
    assert_eq!(
        error_of("s 0 0 0 1\n  bogus 1 2"),
        "<text>:2:3: unknown directive 'bogus'"
    );
    assert_eq!(
        error_of("s 0 0 0 1\ns 0 x 0 1"),
        "<text>:2:5: in 's': expected the sphere's centre (a number), found 'x'"
    );
    assert_eq!(
        error_of("f 1 1 1\n"),
        "<text>:2:1: in 'f': expected Kd, found the end of the file"
    );
    assert!(error_of("s 0 0 0 nan")
        .starts_with("<text>:1:9: in 's': the radius must be a finite number"));
    assert!(error_of("s 0 0 0 inf").contains("finite"));
    assert!(error_of("s 0 0 0 -1").contains("must not be negative"));
    assert!(error_of("accel 7").starts_with("<text>:1:7: in 'accel'"));
    assert!(error_of("mesh 3 1 0 0 0 1 0 0 0 1 0 1 2 4").contains("vertex index 4 is out of range"));
    assert!(error_of("mesh 3 1 0 0 0 1 0 0 0 1 0 1 2 0").contains("vertex index 0"));
    assert!(error_of("mesh 3 1 0 0 0 1 0 0 0 1 0 1 2 -4").contains("vertex index -4"));
    assert!(error_of("p 2 0 0 0 1 1 1").contains("at least 3"));
    assert!(error_of("pl 0 0 0 1 1 1 2 2 2").contains("collinear"));
    assert!(error_of("c 0 0 0 1 0 0 0 1").contains("same point"));
    assert!(error_of("v from 1 1 1 at 1 1 1 up 0 1 0 angle 45").contains("same point"));
    assert!(error_of("v from 0 5 0 at 0 0 0 up 0 1 0 angle 45").contains("parallel"));
    assert!(error_of("v from 0 0 5 at 0 0 0 up 0 1 0 resolution 0 10").contains("between 1 and"));
    assert!(error_of("spp -1").contains("spp must be"));
    assert!(error_of("l 1 2").contains("end of the file"));
}

#[test]
fn counts_beyond_the_file_are_errors_not_allocations() {
    let e = error_of("mesh 2000000000 1\n0 0 0 1 1");
    assert!(e.starts_with("<text>:1:6: in 'mesh'"), "{e}");
    assert!(e.contains("bytes remain"), "{e}");
    let e = error_of("p 1000000000000 0 0");
    assert!(e.contains("bytes remain"), "{e}");
    let e = error_of("mesh 1 99999999999999999999");
    assert!(e.contains("whole number"), "{e}");
    let e = error_of("mesh 3 3\n0 0 0 1 0 0 0 1 0\n1 2 3");
    assert!(
        e.contains("more numbers than the rest of the file holds"),
        "{e}"
    );
}

#[test]
fn file_errors_carry_the_path() {
    let dir = common::scratch("reader_file_errors");
    let path = dir.join("bad.p3f");
    std::fs::write(&path, b"s 0 0 0 1\r\ns 1 \xff 0 1\n").unwrap();
    let e = parse_file(&path).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}:2:5:", path.display())), "{e}");
    assert!(e.contains("UTF-8"));
    let missing = parse_file(&dir.join("missing.p3f"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("cannot read"), "{missing}");
}

#[test]
fn env_is_relative_to_the_scene_folder() {
    let dir = common::scratch("reader_env");
    let path = dir.join("a.p3f");
    std::fs::write(&path, "env skybox\n").unwrap();
    let skybox = parse_file(&path).unwrap().skybox.unwrap();
    assert_eq!(skybox.places()[0], dir.join("skybox"));
}

#[test]
fn reads_every_course_scene_and_the_dragon_quickly() {
    let Some(shared) = common::shared() else {
        return;
    };
    for entry in std::fs::read_dir(shared.join("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "p3f") {
            let scene = parse_file(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.has_camera, "{}", path.display());
        }
    }
    let start = Instant::now();
    let dragon = parse_file(&shared.join("scenes/dragon.p3f")).unwrap();
    let elapsed = start.elapsed();
    // Measured, not asserted against a deadline: timings belong to benchmarks.
    eprintln!("dragon.p3f read in {elapsed:?}");
    assert_eq!(dragon.mesh_triangles, 100_000);
    assert_eq!(dragon.geometry.count(PrimKind::Triangle), 100_002);
}
