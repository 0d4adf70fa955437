//! Scalar intersection routines, one ray against one primitive, hitting and missing; then
//! the SIMD kernels against the eight scalar calls they replace: packet kernels (eight
//! rays, one primitive) and leaf kernels (one ray, a pack of eight primitives).

use std::cell::OnceCell;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use p3trace::intersect::{
    self, BoxPack8, BoxRay, BoxRays, IntersectOptions, MeshPack8, PacketQuery, Roots, SpherePack8,
    TrianglePack8,
};
use p3trace::ray::{Ray, RayPacket};
use p3trace::simd::{F32xP, LaneBits, PACKET};

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
                    [
                        Vec3::new(-1., -1., 0.),
                        Vec3::new(1., -1., 0.),
                        Vec3::new(-1., 1., 0.),
                    ],
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

/// A packet's rays fanning over the unit sphere at the origin: some hit, some miss.
fn fan() -> [Ray; PACKET] {
    std::array::from_fn(|i| {
        let x = -1.4 + 2.8 * i as f32 / (PACKET - 1) as f32;
        Ray::new(
            Vec3::new(x, 0.2, -5.0),
            Vec3::new(-0.02 * x, 0.0, 1.0).normalize(),
        )
    })
}

fn packets(c: &mut Criterion) {
    let rays = fan();
    let packet = RayPacket::new(&rays);
    let (lo, hi) = (F32xP::ZERO, F32xP::splat(f32::INFINITY));
    let all = LaneBits::MAX;
    let shear = OnceCell::new();
    let query = PacketQuery::new(&packet, IntersectOptions::default(), &shear);
    let triangle = [
        Vec3::new(-1., -1., 0.),
        Vec3::new(1., -1., 0.),
        Vec3::new(-1., 1., 0.),
    ];
    let (bmin, bmax) = (Vec3::splat(-1.0), Vec3::ONE);

    c.bench_function("packet/sphere/simd", |b| {
        b.iter(|| {
            intersect::sphere_packet(
                black_box(&packet),
                Vec3::ZERO,
                1.0,
                Roots::Precise,
                lo,
                hi,
                all,
            )
        })
    });
    c.bench_function("packet/sphere/scalar", |b| {
        b.iter(|| {
            black_box(&rays).map(|r| intersect::sphere(&r, Vec3::ZERO, 1.0, 0.0, f32::INFINITY))
        })
    });
    c.bench_function("packet/triangle/simd", |b| {
        b.iter(|| intersect::triangle_packet(black_box(&query), triangle, lo, hi, all))
    });
    c.bench_function("packet/triangle/scalar", |b| {
        b.iter(|| black_box(&rays).map(|r| intersect::triangle(&r, triangle, 0.0, f32::INFINITY)))
    });
    let box_rays = BoxRays::new(&packet);
    c.bench_function("packet/box interval/simd", |b| {
        b.iter(|| black_box(&box_rays).interval(bmin, bmax, lo, hi))
    });
    // The packet holds its inv_dir; the scalar rays get theirs computed outside the loop.
    let scalar_rays: [BoxRay; PACKET] = rays.map(|r| BoxRay::new(r.origin, r.dir.recip()));
    c.bench_function("packet/box interval/scalar", |b| {
        b.iter(|| black_box(&scalar_rays).map(|r| r.interval(bmin, bmax, 0.0, f32::INFINITY)))
    });
}

fn leaves(c: &mut Criterion) {
    let ray = Ray::new(Vec3::new(0.1, 0.2, -5.0), Vec3::Z);
    let inv_dir = ray.dir.recip();
    let spheres: Vec<(Vec3, f32)> = (0..8)
        .map(|i| (Vec3::new(0.5 * i as f32 - 2.0, 0.0, 0.0), 0.3))
        .collect();
    let triangles: Vec<[Vec3; 3]> = (0..8)
        .map(|i| {
            let x = 0.5 * i as f32 - 2.0;
            let p0 = Vec3::new(x, -1.0, i as f32);
            [p0, p0 + Vec3::X, p0 + 2.0 * Vec3::Y]
        })
        .collect();
    let boxes: Vec<(Vec3, Vec3)> = spheres
        .iter()
        .map(|&(c, r)| (c - Vec3::splat(r), c + Vec3::splat(r)))
        .collect();
    let (sphere_pack, triangle_pack, box_pack) = (
        SpherePack8::new(&spheres),
        TrianglePack8::new(&triangles),
        BoxPack8::new(&boxes),
    );
    let inf = f32::INFINITY;

    c.bench_function("leaf/sphere/simd", |b| {
        b.iter(|| intersect::sphere_leaf(black_box(&ray), &sphere_pack, Roots::Precise, 0.0, inf))
    });
    c.bench_function("leaf/sphere/scalar x8", |b| {
        b.iter(|| {
            let ray = black_box(&ray);
            spheres
                .iter()
                .map(|&(c, r)| intersect::sphere(ray, c, r, 0.0, inf))
                .fold(inf, |best, t| t.map_or(best, |t| t.min(best)))
        })
    });
    c.bench_function("leaf/triangle/simd", |b| {
        b.iter(|| intersect::triangle_leaf(black_box(&ray), &triangle_pack, 0.0, inf))
    });
    c.bench_function("leaf/triangle/scalar x8", |b| {
        b.iter(|| {
            let ray = black_box(&ray);
            triangles
                .iter()
                .map(|&triangle| intersect::triangle(ray, triangle, 0.0, inf))
                .fold(inf, |best, h| h.map_or(best, |h| h.t.min(best)))
        })
    });
    // A strip of a mesh, as a mesh pack holds it: eight triangles over ten vertices.
    let vertex = |i: usize, top: bool| {
        Vec3::new(0.5 * i as f32 - 1.0, if top { 1.0 } else { -1.0 }, i as f32)
    };
    let strip: Vec<[Vec3; 3]> = (0..4)
        .flat_map(|i| {
            let (b0, b1) = (vertex(i, false), vertex(i + 1, false));
            let (t0, t1) = (vertex(i, true), vertex(i + 1, true));
            [[b0, b1, t0], [b1, t1, t0]]
        })
        .collect();
    let (strip_pack, mesh_pack) = (
        TrianglePack8::new(&strip),
        MeshPack8::new(&strip).expect("ten vertices fit a mesh pack"),
    );
    c.bench_function("leaf/triangle strip/simd", |b| {
        b.iter(|| intersect::triangle_leaf(black_box(&ray), &strip_pack, 0.0, inf))
    });
    c.bench_function("leaf/mesh strip/simd", |b| {
        b.iter(|| intersect::mesh_leaf(black_box(&ray), &mesh_pack, 0.0, inf))
    });
    c.bench_function("leaf/box/simd", |b| {
        b.iter(|| intersect::aabb_leaf(black_box(&ray), inv_dir, &box_pack, 0.0, inf))
    });
    c.bench_function("leaf/box/scalar x8", |b| {
        b.iter(|| {
            let ray = black_box(&ray);
            boxes
                .iter()
                .map(|&(lo, hi)| intersect::aabb(ray, inv_dir, lo, hi, 0.0, inf))
                .fold(inf, |best, t| t.map_or(best, |t| t.min(best)))
        })
    });
    let box_ray = BoxRay::new(ray.origin, inv_dir);
    c.bench_function("leaf/box interval/simd", |b| {
        // The ray runs along z, parallel to x and y.
        b.iter(|| black_box(&box_ray).intervals8(&box_pack, 0.0, inf))
    });
    c.bench_function("leaf/box interval/scalar x8", |b| {
        b.iter(|| {
            let box_ray = black_box(&box_ray);
            boxes
                .iter()
                .map(|&(lo, hi)| box_ray.interval(lo, hi, 0.0, inf))
                .enumerate()
                .fold(0u8, |bits, (i, t)| bits | u8::from(t.is_some()) << i)
        })
    });
}

criterion_group!(benches, routines, packets, leaves);
criterion_main!(benches);
