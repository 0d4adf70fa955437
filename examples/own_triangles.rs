//! Uses p3trace's BVH over triangles of your own, with no scene file: a rolling terrain
//! of 2 x 256 x 256 triangles, and a million rays dropped on it from above, on every core.
//!
//! ```sh
//! cargo run --release --example own_triangles
//! ```

use std::time::Instant;

use glam::Vec3;
use p3trace::accel::{AccelOptions, Tracer};
use p3trace::ray::Ray;
use p3trace::scene::Geometry;
use rayon::prelude::*;

const CELLS: usize = 256;

fn height(x: f32, z: f32) -> f32 {
    0.3 * (3.0 * x).sin() * (2.0 * z).cos()
}

fn main() {
    // Two triangles a cell of a grid over [-1, 1] x [-1, 1], all of material 0: the
    // grid's vertices stored once, each triangle as three of them.
    let mut geometry = Geometry::default();
    let rows = CELLS + 1;
    let point = |k: usize| {
        let (i, j) = (k / rows, k % rows);
        let (x, z) = (
            i as f32 / CELLS as f32 * 2.0 - 1.0,
            j as f32 / CELLS as f32 * 2.0 - 1.0,
        );
        Vec3::new(x, height(x, z), z)
    };
    let first = geometry.triangles.add_vertices((0..rows * rows).map(point));
    let vertex = |i: usize, j: usize| first + (i * rows + j) as u32;
    for i in 0..CELLS {
        for j in 0..CELLS {
            let [a, b, c, d] = [
                vertex(i, j),
                vertex(i + 1, j),
                vertex(i + 1, j + 1),
                vertex(i, j + 1),
            ];
            geometry.triangles.push_indexed([a, b, c], 0);
            geometry.triangles.push_indexed([a, c, d], 0);
        }
    }
    let start = Instant::now();
    let tracer = Tracer::new(&geometry, &AccelOptions::default());
    println!(
        "{} triangles, BVH built in {:.3} s",
        2 * CELLS * CELLS,
        start.elapsed().as_secs_f64()
    );

    // Rays straight down over the terrain: each hit lies on the surface, at its height.
    let side = 1000;
    let start = Instant::now();
    let worst = (0..side * side)
        .into_par_iter()
        .map(|k| {
            let (x, z) = (
                (k % side) as f32 / side as f32 * 1.8 - 0.9,
                (k / side) as f32 / side as f32 * 1.8 - 0.9,
            );
            let ray = Ray::new(Vec3::new(x, 2.0, z), Vec3::NEG_Y);
            let hit = tracer
                .closest(&ray, 0.0, f32::INFINITY)
                .expect("the terrain is below");
            (ray.at(hit.t).y - height(x, z)).abs()
        })
        .reduce(|| 0.0, f32::max);
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{} rays in {seconds:.3} s ({:.1} Mrays/s); every hit within {worst:.1e} of the surface",
        side * side,
        (side * side) as f64 / seconds / 1e6
    );
    // The flat triangles lie within a cell's curvature of the surface.
    assert!(worst < 0.01);
}
