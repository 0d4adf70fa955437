//! Traces rays through a scene from your own code: the scene's camera makes one ray a
//! character of a text picture, the BVH finds what each meets (`O` a sphere, `#` anything
//! else), and a shadow ray towards the first point light says whether it is lit (in
//! shadow, `o` and `.`). Then the same rays as packets.
//!
//! ```sh
//! cargo run --release --example trace_rays -- scenes/balls_low.p3f
//! ```

use glam::Vec2;
use p3trace::accel::{AccelOptions, Tracer};
use p3trace::prim::PrimKind;
use p3trace::ray::{Ray, RayPacket};
use p3trace::render::camera::{Camera, FilmSample};
use p3trace::scene::{parse_file, Light};
use p3trace::simd::PACKET;

const COLUMNS: u32 = 64;
const ROWS: u32 = 24;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("scenes/balls_low.p3f".into());
    let scene = parse_file(std::path::Path::new(&path))?;
    let tracer = Tracer::new(&scene.geometry, &AccelOptions::default());
    // A character is two rows of pixels high, as a terminal's cells are.
    let camera = Camera::new(&scene.camera, COLUMNS, 2 * ROWS);
    let light = scene.lights.iter().find_map(|light| match light {
        Light::Point { position, .. } => Some(*position),
        _ => None,
    });
    let ray_through = |x: u32, y: u32| {
        camera.ray(&FilmSample {
            sx: x as f32 + 0.5,
            // Film rows count from the bottom.
            sy: (2 * ROWS - 1 - y) as f32 + 0.5,
            lens: Vec2::ZERO,
            time: 0.0,
        })
    };
    let mut rays = Vec::new();
    for row in 0..ROWS {
        let mut line = String::new();
        for x in 0..COLUMNS {
            let ray = ray_through(x, 2 * row);
            rays.push(ray);
            let Some(hit) = tracer.closest(&ray, 0.0, f32::INFINITY) else {
                line.push(' ');
                continue;
            };
            let point = ray.at(hit.t);
            let lit = light.is_none_or(|light| {
                let to_light = light - point;
                let shadow = Ray::new(point, to_light.normalize());
                !tracer.occluded(&shadow, 1e-3, to_light.length())
            });
            let sphere = hit.prim.kind() == PrimKind::Sphere;
            line.push(match (sphere, lit) {
                (true, true) => 'O',
                (true, false) => 'o',
                (false, true) => '#',
                (false, false) => '.',
            });
        }
        println!("{line}");
    }
    // The same rays, PACKET at a time: each lane finds its single ray's hit.
    let mut agree = 0;
    for chunk in rays.chunks_exact(PACKET) {
        let packet: &[Ray; PACKET] = chunk.try_into()?;
        let hits = tracer.closest_packet(&RayPacket::new(packet));
        for (ray, hit) in chunk.iter().zip(hits) {
            agree += usize::from(hit == tracer.closest(ray, 0.0, f32::INFINITY));
        }
    }
    println!(
        "{agree} of {} rays: the packets found the single rays' hits",
        rays.len()
    );
    assert_eq!(agree, rays.len());
    Ok(())
}
