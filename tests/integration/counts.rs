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
    let rays: [Ray; 8] = std::array::from_fn(|k| {
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
            let packet = packet.with_t_max([t_max; 8]);
            let mut lanes = LaneTallies::default();
            tracer.occluded_packet_counting::<Tally>(&packet, &mut lanes);
            assert_eq!(lanes.lane(k), alone, "{} occluded", tracer.name());
            // The other lanes took no part.
            assert!((0..8)
                .filter(|&j| j != k)
                .all(|j| lanes.lane(j) == Tally::default()));
        }
    }
}

/// `bench --stats --json -` on `scene` with `--accel ACCEL`: the work of its sets.
fn bench_work(scene: &str, accel: &str) -> Vec<serde_json::Value> {
    let scene = common::project_file(scene).display().to_string();
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
    let brute = bench_work("scenes/balls_low.p3f", "none");
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
        for work in bench_work("scenes/balls_low.p3f", accel) {
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
                lanes.is_none_or(|l| (1.0..=8.0).contains(&l)),
                "{name}: {lanes:?}"
            );
        }
    }
}
