//! Ten million triangles: a height field stored as the reader stores a mesh, built into
//! the default BVH and rendered at a small size within the memory `docs/limits.md` states. A
//! counting allocator measures the peak of the heap.

use crate::counting;
use glam::Vec3;
use p3trace::scene::{CameraSpec, Material, Scene};

/// 2500 x 2000 cells of two triangles each, one unit apart.
const CELLS: [u32; 2] = [2500, 2000];
const TRIANGLES: usize = 10_000_000;

/// The most heap a triangle may take at the peak of storing, building the default BVH and
/// rendering (64.1 measured, `docs/limits.md`).
const MAX_BYTES_PER_TRIANGLE: f64 = 100.0;

/// The most heap a triangle may hold once the BVH is built: the mesh (18) and the 8-wide
/// tree, whose compact packs share a leaf's vertices (51.5 measured; 65.8 with a triangle's
/// vertices in each pack).
const MAX_HELD_PER_TRIANGLE: f64 = 60.0;

/// A gentle landscape, so that the SAH has shapes to split.
fn height(x: u32, y: u32) -> f32 {
    let (x, y) = (x as f32, y as f32);
    2.0 * (x * 0.013).sin() * (y * 0.017).cos() + 0.5 * (x * 0.11 + y * 0.07).sin()
}

pub fn ten_million_triangles_render_within_the_stated_memory() {
    let before = counting::start();

    let mut scene = Scene {
        name: "10M triangles".into(),
        background: Vec3::new(0.2, 0.4, 0.6),
        has_camera: true,
        ..Scene::default()
    };
    scene.materials.push(Material::DEFAULT);
    // Stored as the reader stores a mesh: its vertices once, then its triangles' corners
    // one by one into room made for them.
    let point = |x: u32, y: u32| Vec3::new(x as f32, y as f32, height(x, y));
    let rows = CELLS[1] + 1;
    let triangles = &mut scene.geometry.triangles;
    let vertices = (0..(CELLS[0] + 1) * rows).map(|k| point(k / rows, k % rows));
    let first = triangles.add_vertices(vertices);
    triangles.reserve(TRIANGLES);
    let index = |x: u32, y: u32| first + x * rows + y;
    for x in 0..CELLS[0] {
        for y in 0..CELLS[1] {
            let [a, b, c, d] = [
                index(x, y),
                index(x + 1, y),
                index(x + 1, y + 1),
                index(x, y + 1),
            ];
            triangles.push_indexed([a, b, c], 0);
            triangles.push_indexed([a, c, d], 0);
        }
    }
    assert_eq!(triangles.corners.len(), TRIANGLES);
    // As the reader does once the file is read.
    scene.geometry.shrink_to_fit();

    scene.camera = CameraSpec {
        from: Vec3::new(1250.0, -600.0, 900.0),
        at: Vec3::new(1250.0, 1000.0, 0.0),
        up: Vec3::Z,
        angle: 50.0,
        width: 64,
        height: 48,
        ..CameraSpec::default()
    };
    scene.lights.push(p3trace::scene::Light::Point {
        position: Vec3::new(1250.0, 1000.0, 2000.0),
        colour: Vec3::ONE,
    });
    let report = counting::render_within(
        &scene,
        before,
        TRIANGLES,
        "triangle",
        (MAX_BYTES_PER_TRIANGLE, Some(MAX_HELD_PER_TRIANGLE)),
    );
    // The sky fills the top row (the film's first); the landscape below it is lit.
    let background = report.film.pixels[0];
    assert_eq!(background, scene.background);
    let lit = report
        .film
        .pixels
        .iter()
        .filter(|&&p| p != background && p != Vec3::ZERO)
        .count();
    assert!(lit > 0, "no pixel shows the landscape lit");
}
