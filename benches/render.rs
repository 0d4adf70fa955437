//! Whole renders of small scenes from the project's `scenes/`, at 128 x 128, one thread,
//! with the default structure (the SAH BVH).

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use p3trace::render::{render, RenderOptions};
use p3trace::scene::parse_file;

fn renders(c: &mut Criterion) {
    let mut group = c.benchmark_group("render");
    group.sample_size(10);
    for name in ["balls_low", "balls_medium", "mount_high", "showcase"] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.p3f"));
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

criterion_group!(benches, renders);
criterion_main!(benches);
