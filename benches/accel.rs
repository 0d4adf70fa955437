//! Acceleration structures: the build of each on the large course scenes, and traversal
//! of the protocol's ray sets (PROTOCOL.md), one thread. The course scenes are read from
//! `../shared/scenes` (or `$P3TRACE_SHARED`); without them the project's own generated
//! equivalents in `scenes/` stand in.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use p3trace::accel::BvhBuild;
use p3trace::accel::{AccelKind, AccelOptions, Tracer};
use p3trace::bench::ray_sets;
use p3trace::scene::{parse_file, Scene};

/// Every `STRIDE`-th ray of a set is traced, so one iteration stays short.
const STRIDE: usize = 16;

fn scene(name: &str) -> Scene {
    let project = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let shared = std::env::var_os("P3TRACE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| project.join("../shared"));
    let course = shared.join("scenes").join(format!("{name}.p3f"));
    let path = if course.is_file() {
        course
    } else {
        eprintln!(
            "{} is absent: using the project's scenes/{name}.p3f",
            course.display()
        );
        project.join("scenes").join(format!("{name}.p3f"))
    };
    parse_file(&path).expect("the benchmark scene parses")
}

fn structures() -> [(&'static str, AccelOptions); 4] {
    let with = |kind, bvh, mailbox| AccelOptions {
        kind,
        bvh,
        mailbox,
        ..AccelOptions::default()
    };
    [
        ("grid", with(AccelKind::Grid, BvhBuild::Sah, false)),
        ("grid+mailbox", with(AccelKind::Grid, BvhBuild::Sah, true)),
        (
            "bvh-midpoint",
            with(AccelKind::Bvh, BvhBuild::Midpoint, false),
        ),
        ("bvh-sah", with(AccelKind::Bvh, BvhBuild::Sah, false)),
    ]
}

fn builds(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10);
    for name in ["balls_high", "mount_high"] {
        let scene = scene(name);
        for (label, options) in structures() {
            group.bench_function(format!("{name}/{label}"), |b| {
                b.iter(|| Tracer::new(black_box(&scene.geometry), &options))
            });
        }
    }
    group.finish();
}

fn traversal(c: &mut Criterion) {
    let mut group = c.benchmark_group("traverse");
    group.sample_size(10);
    for name in ["balls_high", "mount_high"] {
        let scene = scene(name);
        let g = &scene.geometry;
        let sets = ray_sets(&scene, &Tracer::new(g, &AccelOptions::default()));
        for (label, options) in structures() {
            let tracer = Tracer::new(g, &options);
            for set in &sets {
                group.bench_function(format!("{name}/{label}/{}", set.name), |b| {
                    b.iter(|| {
                        let mut hits = 0u32;
                        for (ray, &t_max) in set.rays.iter().zip(&set.t_max).step_by(STRIDE) {
                            let hit = if set.occlusion {
                                tracer.occluded(black_box(ray), 0.0, t_max)
                            } else {
                                tracer.closest(black_box(ray), 0.0, t_max).is_some()
                            };
                            hits += hit as u32;
                        }
                        hits
                    })
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, builds, traversal);
criterion_main!(benches);
