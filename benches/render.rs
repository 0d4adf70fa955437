//! Whole renders of small scenes from the project's `scenes/`, at 128 x 128, one thread,
//! with the default structure (the SAH BVH); and `balls_low` at 16 samples per pixel with
//! each distribution effect, to compare the cost of an effect as a ratio in one run.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use p3trace::render::sampler::SampleGrid;
use p3trace::render::{render, RenderOptions, Sampling};
use p3trace::scene::{parse_file, Scene};

fn renders(c: &mut Criterion) {
    let mut group = c.benchmark_group("render");
    group.sample_size(10);
    for name in ["balls_low", "balls_medium", "mount_high", "showcase"] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.p3f"));
        let scene = parse_file(&path).expect("the project's scene parses");
        let mut options = RenderOptions::from_scene(&scene);
        (options.width, options.height) = (128, 128);
        options.threads = Some(1);
        group.bench_function(name, |b| {
            b.iter(|| render(black_box(&scene), &options).expect("the render runs"))
        });
    }
    group.finish();
}

/// Turns one effect on.
type Effect = fn(&mut Scene, &mut RenderOptions);

fn effects(c: &mut Criterion) {
    let mut group = c.benchmark_group("effects");
    group.sample_size(10);
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/balls_low.p3f");
    let scene = parse_file(&path).expect("the project's scene parses");
    let mut base = RenderOptions::from_scene(&scene);
    (base.width, base.height) = (96, 96);
    base.threads = Some(1);
    base.sampling = Sampling::Jittered(SampleGrid::square(4));
    let variants: [(&str, Effect); 5] = [
        ("16spp", |_, _| {}),
        ("soft_shadows", |_, o| o.shade.soft_light_size = Some(0.5)),
        ("fuzzy", |_, o| o.shade.roughness = 0.2),
        // balls_low has no moving spheres: this times the shutter's draws alone.
        ("motion_blur", |_, o| o.shutter = [0.0, 0.3]),
        ("depth_of_field", |scene, _| scene.camera.aperture = 8.0),
    ];
    for (name, configure) in variants {
        let (mut scene, mut options) = (scene.clone(), base.clone());
        configure(&mut scene, &mut options);
        group.bench_function(name, |b| {
            b.iter(|| render(black_box(&scene), &options).expect("the render runs"))
        });
    }
    group.finish();
}

criterion_group!(benches, renders, effects);
criterion_main!(benches);
