//! The traversal counts pinned to what can be known without them: brute force tests
//! every primitive once per ray, a BVH walks no further than its root for a ray through
//! empty space, the grid visits the cells a ray crosses, and a packet of one ray counts
//! what that ray alone does. That counting changes no answer is checked beside the
//! structures' answers (`accel.rs`).

use crate::common;
use glam::Vec3;
use p3trace::accel::count::{CountLanes, LaneTallies, Tally};
use p3trace::accel::{AccelKind, AccelOptions, BvhBuild, BvhWidth, Tracer};
use p3trace::ray::{Ray, RayPacket};
use p3trace::scene::p3f::parse_text;
use p3trace::scene::Scene;
use p3trace::simd::PACKET;

const MATERIAL: &str = "f 1 1 1 1 1 1 1 0 10 0 1\n";

fn scene(objects: &str) -> Scene {
    parse_text(&format!("{MATERIAL}{objects}")).expect("the scene parses")
}

/// Eight small spheres at the corners of the cube from 0 to 10, and a triangle and a box
/// inside it.
fn corners() -> Scene {
    let mut text = String::new();
    for k in 0..8 {
        let at = |bit: usize| if k & bit != 0 { 10.0 } else { 0.0 };
        text += &format!("s {} {} {} 0.1\n", at(1), at(2), at(4));
    }
    text += "p 3\n4 4 4\n6 4 4\n4 6 4\nbox 3 7 3 3.5 7.5 3.5\n";
    scene(&text)
}

/// `scene` with a plane below it: every structure tests it beside its own walk.
fn with_plane(scene: &Scene) -> Scene {
    let mut with = scene.clone();
    with.geometry.planes = self::scene("pl 0 -1 0 1 -1 0 0 -1 1\n").geometry.planes;
    with
}

fn bvh(build: BvhBuild, width: BvhWidth) -> AccelOptions {
    AccelOptions {
        kind: AccelKind::Bvh,
        bvh: build,
        bvh_width: Some(width),
        ..AccelOptions::default()
    }
}

fn closest_count(tracer: &Tracer, ray: &Ray) -> Tally {
    let mut count = Tally::default();
    tracer.closest_counting(ray, 0.0, f32::INFINITY, &mut count);
    count
}

#[test]
fn brute_force_tests_every_primitive_once_per_ray() {
    let scene = corners();
    let planes = with_plane(&scene);
    for (scene, primitives) in [(&scene, 10), (&planes, 11)] {
        let tracer = Tracer::new(&scene.geometry, &AccelOptions::brute_force());
        for dir in [Vec3::X, Vec3::NEG_Y, Vec3::new(1.0, 2.0, 3.0).normalize()] {
            let ray = Ray::new(Vec3::new(5.0, 5.0, -3.0), dir);
            let count = closest_count(&tracer, &ray);
            assert_eq!(
                count,
                Tally {
                    rays: 1,
                    prims: primitives,
                    ..Tally::default()
                },
                "{dir}"
            );
        }
    }
}

#[test]
fn a_ray_through_empty_space_goes_no_further_than_the_root() {
    let scene = corners();
    // Beside the scene, heading away from it.
    let away = Ray::new(Vec3::new(20.0, 5.0, 5.0), Vec3::X);
    let eight = Tracer::new(&scene.geometry, &bvh(BvhBuild::Sah, BvhWidth::Eight));
    let count = closest_count(&eight, &away);
    assert_eq!(
        (count.nodes, count.leaves, count.prims),
        (1, 0, 0),
        "{count:?}"
    );
    assert!(count.boxes > 0 && count.boxes <= 8, "{count:?}");
    for build in [BvhBuild::Sah, BvhBuild::Midpoint] {
        let binary = Tracer::new(&scene.geometry, &bvh(build, BvhWidth::Two));
        let count = closest_count(&binary, &away);
        assert_eq!(
            count,
            Tally {
                rays: 1,
                boxes: 1,
                ..Tally::default()
            },
            "{build:?}"
        );
    }
}

#[test]
fn the_grid_visits_the_cells_a_ray_crosses_along_an_axis() {
    let scene = corners();
    let options = AccelOptions {
        kind: AccelKind::Grid,
        ..AccelOptions::default()
    };
    let tracer = Tracer::new(&scene.geometry, &options);
    let resolution: Vec<u32> = tracer
        .stats()
        .iter()
        .find_map(|line| line.strip_prefix("grid resolution: "))
        .expect("the grid's resolution")
        .split(" (")
        .next()
        .unwrap()
        .split(" x ")
        .map(|n| n.parse().unwrap())
        .collect();
    // The grid spans -0.1 to 10.1 on each axis; rays run through the middle of the
    // second slab of cells in the other two axes, far from any plane between cells.
    for axis in 0..3 {
        let cells = resolution[axis];
        let mut origin = Vec3::ZERO;
        for other in (0..3).filter(|&k| k != axis) {
            origin[other] = -0.1 + 1.5 * 10.2 / resolution[other] as f32;
        }
        origin[axis] = -5.0;
        let mut dir = Vec3::ZERO;
        dir[axis] = 1.0;
        let count = closest_count(&tracer, &Ray::new(origin, dir));
        assert_eq!(count.cells, cells, "axis {axis}: {count:?}");
        assert_eq!((count.nodes, count.boxes), (0, 1), "axis {axis}");
    }
}

#[test]
fn a_packet_of_one_ray_counts_what_the_ray_does_alone() {
    let scene = with_plane(&corners());
    let structures = [
        AccelOptions::brute_force(),
        AccelOptions {
            kind: AccelKind::Grid,
            ..AccelOptions::default()
        },
        bvh(BvhBuild::Sah, BvhWidth::Eight),
        bvh(BvhBuild::Sah, BvhWidth::Two),
        bvh(BvhBuild::Midpoint, BvhWidth::Two),
    ];
    let rays: [Ray; PACKET] = std::array::from_fn(|k| {
        let target = Vec3::new(k as f32 * 1.3, 5.0 + (k % 3) as f32, 4.0 + (k % 2) as f32);
        let origin = Vec3::new(5.0, 5.0, -20.0);
        Ray::new(origin, (target - origin).normalize())
    });
    for options in &structures {
        let tracer = Tracer::new(&scene.geometry, options);
        for (k, ray) in rays.iter().enumerate() {
            let packet = RayPacket::new(&rays).with_active(1 << k);
            let mut lanes = LaneTallies::default();
            tracer.closest_packet_counting::<Tally>(&packet, &mut lanes);
            assert_eq!(
                lanes.lane(k),
                closest_count(&tracer, ray),
                "{} closest",
                tracer.name()
            );
            let t_max = 30.0;
            let mut alone = Tally::default();
            tracer.occluded_counting(ray, 0.0, t_max, &mut alone);
            let packet = packet.with_t_max([t_max; PACKET]);
            let mut lanes = LaneTallies::default();
            tracer.occluded_packet_counting::<Tally>(&packet, &mut lanes);
            assert_eq!(lanes.lane(k), alone, "{} occluded", tracer.name());
            // The other lanes took no part.
            assert!((0..PACKET)
                .filter(|&j| j != k)
                .all(|j| lanes.lane(j) == Tally::default()));
        }
    }
}

/// `bench --stats --json -` on `scene` with `--accel ACCEL`: the work of its sets.
fn bench_work(scene: &str, accel: &str) -> Vec<serde_json::Value> {
    let scene = project_scene(scene);
    let args = [
        "bench",
        &scene,
        "--accel",
        accel,
        "--reps",
        "1",
        "--threads",
        "1",
        "--stats",
        "--json",
        "-",
    ];
    let run = common::succeeds(&args);
    let text = common::stderr(&run);
    assert!(text.contains("# work  primary"), "{text}");
    let value: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
    value["work"].as_array().expect("a work list").clone()
}

#[test]
fn bench_stats_count_every_set_along_every_path() {
    // balls_low: ten spheres and a floor of two triangles, no plane.
    let brute = bench_work("balls_low", "none");
    assert_eq!(brute.len(), 3 * 3, "three sets, three paths");
    for work in &brute {
        let (set, api) = (
            work["ray_set"].as_str().unwrap(),
            work["api"].as_str().unwrap(),
        );
        let prims = &work["per_ray"]["prims"];
        if set != "shadow" {
            // Closest hits: brute force tests all twelve objects for every ray.
            for key in ["p50", "p90", "p99"] {
                assert_eq!(prims[key], 12, "{set} {api} {key}");
            }
            assert_eq!(prims["mean"], 12.0, "{set} {api}");
        }
        // No nodes, no leaves: no lanes at them either.
        assert_eq!(work["per_ray"]["nodes"]["total"], 0, "{set} {api}");
        assert!(work["lanes_at_nodes"].is_null() && work["lanes_at_leaves"].is_null());
    }
    for (accel, walks) in [("bvh", "nodes"), ("grid", "cells")] {
        for work in bench_work("balls_low", accel) {
            let name = format!("{accel} {} {}", work["ray_set"], work["api"]);
            let counted = &work["per_ray"][walks];
            assert!(counted["total"].as_u64().unwrap() > 0, "{name}");
            let p = |key: &str| counted[key].as_u64().unwrap();
            assert!(p("p50") <= p("p90") && p("p90") <= p("p99"), "{name}");
            let rays = work["rays"].as_f64().unwrap();
            let total = counted["total"].as_f64().unwrap();
            assert!((counted["mean"].as_f64().unwrap() * rays - total).abs() < 1e-6 * total);
            // Lanes are a packet's: none for single rays.
            let lanes = work["lanes_at_leaves"].as_f64();
            assert_eq!(lanes.is_none(), work["api"] == "p3trace-single", "{name}");
            assert!(
                lanes.is_none_or(|l| (1.0..=PACKET as f64).contains(&l)),
                "{name}: {lanes:?}"
            );
        }
    }
}

/// The project's scene `scenes/NAME.p3f`, as an argument.
fn project_scene(name: &str) -> String {
    common::project_file(&format!("scenes/{name}.p3f"))
        .display()
        .to_string()
}

/// The sum of the counts of a cost EXR (`render --cost`): its one channel, Y.
fn exr_sum(path: &std::path::Path) -> f64 {
    let bytes = std::fs::read(path).expect("the cost image");
    let part = p3trace::farm::read_part(&bytes, "cost").expect("a cost part");
    part.pixels.iter().map(|p| f64::from(p.x)).sum()
}

fn json_file(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).expect("JSON")
}

#[test]
fn a_cost_image_sums_to_the_frames_work_in_every_mode_and_effect() {
    let dir = common::scratch("counts_cost_sums");
    let showcase = project_scene("showcase");
    let dof = project_scene("dof");
    let effects: [(&str, &[&str]); 4] = [
        (&showcase, &[]),
        (
            &showcase,
            &["--spp", "4", "--soft-shadows", "--roughness", "0.2"],
        ),
        (&showcase, &["--mode", "scalar", "--accel", "grid"]),
        (&dof, &["--spp", "2", "--accel", "none"]),
    ];
    for (k, (scene, extra)) in effects.iter().enumerate() {
        for (rays, kind) in [("all", "all"), ("primary", "primary")] {
            let (exr, json) = (
                dir.join(format!("{k}{rays}.exr")),
                dir.join(format!("{k}{rays}.json")),
            );
            let mut args = vec![
                "render",
                scene,
                "--resolution",
                "40x30",
                "--no-skybox",
                "-q",
                "--cost",
                "prims",
                "--cost-rays",
                rays,
                "-o",
                exr.to_str().unwrap(),
                "--json",
                json.to_str().unwrap(),
            ];
            args.extend_from_slice(extra);
            common::succeeds(&args);
            let stats = json_file(&json);
            let work = &stats["work"];
            // Every ray traced is counted once, in the closing line's figures too.
            assert_eq!(
                work["by_kind"]["all"]["rays"], stats["rays"]["total"],
                "{extra:?}"
            );
            let total = work["by_kind"][kind]["prims"]["total"].as_f64().unwrap();
            assert!(total > 0.0, "{extra:?} {rays}");
            assert_eq!(exr_sum(&exr), total, "{extra:?} {rays}");
        }
    }
}

#[test]
fn cost_images_do_not_depend_on_threads_or_tiles_and_merge_exactly() {
    let dir = common::scratch("counts_cost_farm");
    let scene = project_scene("showcase");
    let render = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec![
            "render",
            &scene,
            "--resolution",
            "48x36",
            "--no-skybox",
            "-q",
            "--cost",
            "leaves",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        common::succeeds(&args);
        std::fs::read(out).unwrap()
    };
    let whole = render("whole.exr", &["--threads", "1"]);
    assert!(
        render("two.exr", &["--threads", "2"]) == whole,
        "two threads differ from one"
    );
    for t in 0..3 {
        render(
            &format!("tile{t}.exr"),
            &["--tile", &format!("{t}/3"), "--threads", "2"],
        );
    }
    let merged = dir.join("merged.exr");
    let parts: Vec<String> = (0..3)
        .map(|t| dir.join(format!("tile{t}.exr")).display().to_string())
        .collect();
    let mut args = vec!["merge", "-o", merged.to_str().unwrap()];
    args.extend(parts.iter().map(String::as_str));
    common::succeeds(&args);
    assert!(
        std::fs::read(&merged).unwrap() == whole,
        "the merged tiles differ from the frame"
    );
    // The merged parts also make the picture, on a fixed scale if asked.
    let picture = dir.join("merged.png");
    let mut args = vec!["merge", "-o", picture.to_str().unwrap(), "--cost-max", "10"];
    args.extend(parts.iter().map(String::as_str));
    common::succeeds(&args);
    let png = image::open(&picture).unwrap();
    assert_eq!(png.height(), 36);
    assert!(png.width() > 48, "the scale beside the image");

    // Colour parts and cost parts never mix, and a colour merge takes no scale.
    let colour = dir.join("colour.exr");
    common::succeeds(&[
        "render",
        &scene,
        "--resolution",
        "48x36",
        "--no-skybox",
        "-q",
        "--tile",
        "0/3",
        "-o",
        colour.to_str().unwrap(),
    ]);
    let mixed = common::p3trace(&[
        "merge",
        "-o",
        picture.to_str().unwrap(),
        colour.to_str().unwrap(),
        &parts[1],
        &parts[2],
    ]);
    assert_eq!(mixed.status.code(), Some(2), "{}", common::stderr(&mixed));
    assert!(
        common::stderr(&mixed).contains("different renders"),
        "{}",
        common::stderr(&mixed)
    );
    let scaled = common::p3trace(&[
        "merge",
        "--cost-max",
        "3",
        "-o",
        picture.to_str().unwrap(),
        colour.to_str().unwrap(),
    ]);
    assert_eq!(scaled.status.code(), Some(2));
    assert!(
        common::stderr(&scaled).contains("colour image"),
        "{}",
        common::stderr(&scaled)
    );
}

#[test]
fn a_cost_image_is_refused_where_it_cannot_apply() {
    let scene = project_scene("balls_low");
    let refused = |extra: &[&str], says: &str| {
        let mut args = vec!["render", &scene, "--resolution", "16x12", "-q"];
        args.extend_from_slice(extra);
        let run = common::p3trace(&args);
        assert_eq!(run.status.code(), Some(2), "{extra:?}");
        assert!(
            common::stderr(&run).contains(says),
            "{extra:?}: {}",
            common::stderr(&run)
        );
    };
    refused(&["--cost", "triangles", "-o", "x.png"], "invalid value");
    refused(&["--cost", "cells", "-o", "x.png"], "--accel grid");
    refused(
        &["--cost", "nodes", "--accel", "grid", "-o", "x.png"],
        "the grid counts no",
    );
    refused(
        &["--cost", "boxes", "--accel", "none", "-o", "x.png"],
        "only prims",
    );
    refused(
        &["--cost", "prims", "-o", "x.hdr"],
        "use .exr for the counts",
    );
    refused(&["--cost-max", "5", "-o", "x.png"], "--cost");
}

#[test]
fn compare_gives_the_ratio_of_two_cost_images() {
    let dir = common::scratch("counts_cost_compare");
    let scene = project_scene("balls_low");
    let cost = |name: &str, accel: &str| {
        let out = dir.join(name).display().to_string();
        common::succeeds(&[
            "render",
            &scene,
            "--resolution",
            "32x32",
            "-q",
            "--cost",
            "prims",
            "--accel",
            accel,
            "-o",
            &out,
        ]);
        out
    };
    let (bvh, brute) = (cost("bvh.exr", "bvh"), cost("none.exr", "none"));
    let run = common::succeeds(&["compare", &bvh, &brute]);
    let text = String::from_utf8_lossy(&run.stdout).into_owned();
    let ratio: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("ratio (second / first): "))
        .expect("a ratio")
        .parse()
        .unwrap();
    assert!(ratio > 1.0, "brute force tests more than the BVH: {text}");
    assert!(text.contains("(none, stream mode, packets of "), "{text}");
    let colour = dir.join("colour.png").display().to_string();
    common::succeeds(&[
        "render",
        &scene,
        "--resolution",
        "32x32",
        "-q",
        "-o",
        &colour,
    ]);
    let mixed = common::p3trace(&["compare", &bvh, &colour]);
    assert_eq!(mixed.status.code(), Some(2), "{}", common::stderr(&mixed));
}
