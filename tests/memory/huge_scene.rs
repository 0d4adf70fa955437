//! Ten million spheres: stored, built into the default BVH and rendered at a small size
//! within the memory `docs/limits.md` states. A counting allocator measures the peak of the
//! heap.

use crate::counting;
use glam::Vec3;
use p3trace::accel::{AccelOptions, Tracer};
use p3trace::scene::{CameraSpec, Material, Scene};

/// The lattice: 250 x 200 x 200 spheres of radius 0.25, one unit apart.
const SIDES: [u32; 3] = [250, 200, 200];
const SPHERES: usize = 10_000_000;

/// The most heap a sphere may take at the peak of storing, building the default BVH and
/// rendering, as `docs/limits.md` states it (64.4 measured, at the end of the binary build:
/// 20 for the sphere records, 28 for the build's items and 16 for the binary nodes, built
/// down to the packs, twice as the root's halves are copied; once built, 47.5, the 8-wide
/// tree taking 28).
const MAX_BYTES_PER_SPHERE: f64 = 70.0;

pub fn ten_million_spheres_render_within_the_stated_memory() {
    let before = counting::start();

    let scene = sphere_lattice(
        "10M spheres",
        SIDES,
        Vec3::new(124.6, 99.6, 400.0),
        [64, 48],
    );
    assert_eq!(scene.geometry.spheres.records.len(), SPHERES);

    let limits = (MAX_BYTES_PER_SPHERE, None);
    let report = counting::render_within(&scene, before, SPHERES, "sphere", limits);

    // The lattice fills the middle of the image; rays between its rows leave it.
    let background = report.film.pixels[0];
    let hits = report
        .film
        .pixels
        .iter()
        .filter(|&&p| p != background)
        .count();
    assert!(
        hits > 0 && hits < report.film.pixels.len(),
        "{hits} pixels hit"
    );

    // A ray into the lattice meets the same sphere in the BVH as by brute force.
    let g = &scene.geometry;
    let ray = p3trace::ray::Ray::new(
        scene.camera.from,
        Vec3::new(0.013, -0.007, -1.0).normalize(),
    );
    let brute = Tracer::new(g, &AccelOptions::brute_force()).closest(&ray, 0.0, f32::INFINITY);
    let bvh = Tracer::new(g, &AccelOptions::default());
    assert!(brute.is_some());
    assert_eq!(bvh.closest(&ray, 0.0, f32::INFINITY), brute);
}

/// A lattice of `sides` spheres of radius 0.25, one unit apart from the origin, pushed one
/// by one and then shrunk to fit as the reader does, seen from `from` straight down the z
/// axis at `[width, height]`.
pub fn sphere_lattice(name: &str, sides: [u32; 3], from: Vec3, [width, height]: [u32; 2]) -> Scene {
    let mut scene = Scene {
        name: name.into(),
        background: Vec3::new(0.2, 0.4, 0.6),
        has_camera: true,
        ..Scene::default()
    };
    scene.materials.push(Material::DEFAULT);
    let spheres = &mut scene.geometry.spheres;
    for x in 0..sides[0] {
        for y in 0..sides[1] {
            for z in 0..sides[2] {
                spheres.push(Vec3::new(x as f32, y as f32, z as f32), 0.25, 0);
            }
        }
    }
    scene.geometry.shrink_to_fit();
    scene.camera = CameraSpec {
        from,
        at: Vec3::new(from.x, from.y, 0.0),
        up: Vec3::Y,
        angle: 50.0,
        width,
        height,
        ..CameraSpec::default()
    };
    scene
}
