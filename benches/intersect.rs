//! Scalar intersection routines, one ray against one primitive, hitting and missing.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use p3trace::intersect;
use p3trace::ray::Ray;

fn routines(c: &mut Criterion) {
    let hit = Ray::new(Vec3::new(0.1, 0.2, -5.0), Vec3::Z);
    let miss = Ray::new(Vec3::new(3.0, 0.2, -5.0), Vec3::Z);
    for (name, ray) in [("hit", hit), ("miss", miss)] {
        c.bench_function(&format!("sphere/{name}"), |b| {
            b.iter(|| intersect::sphere(black_box(&ray), Vec3::ZERO, 1.0, 0.0, f32::INFINITY))
        });
        c.bench_function(&format!("triangle/{name}"), |b| {
            b.iter(|| {
                intersect::triangle(
                    black_box(&ray),
                    Vec3::new(-1., -1., 0.),
                    Vec3::new(2., 0., 0.),
                    Vec3::new(0., 2., 0.),
                    0.0,
                    f32::INFINITY,
                )
            })
        });
        c.bench_function(&format!("box/{name}"), |b| {
            let inv = ray.dir.recip();
            b.iter(|| {
                intersect::aabb(
                    black_box(&ray),
                    inv,
                    Vec3::splat(-1.),
                    Vec3::ONE,
                    0.0,
                    f32::INFINITY,
                )
            })
        });
        c.bench_function(&format!("plane/{name}"), |b| {
            b.iter(|| intersect::plane(black_box(&ray), Vec3::NEG_Z, 1.0, 0.0, f32::INFINITY))
        });
        c.bench_function(&format!("cone/{name}"), |b| {
            b.iter(|| {
                intersect::cone(
                    black_box(&ray),
                    Vec3::new(0., -1., 0.),
                    Vec3::Y,
                    2.0,
                    1.0,
                    0.3,
                    0.0,
                    f32::INFINITY,
                )
            })
        });
    }
}

criterion_group!(benches, routines);
criterion_main!(benches);
