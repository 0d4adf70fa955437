//! p3trace: a data-oriented ray tracer for the P3F scenes of the P3D course.
//!
//! The map of the crate is in `ARCHITECTURE.md`; the scene format and the shading it must
//! compute are specified in the course's `P3F.md`. In short:
//!
//! - [`scene`] reads P3F files into a [`scene::Scene`] whose primitives are stored
//!   structure-of-arrays ([`scene::geometry`]).
//! - [`intersect`] holds the scalar ray-primitive tests, the reference for everything faster,
//!   and beside each its SIMD twins over the eight-lane types of [`simd`].
//! - [`accel`] finds closest hits and answers occlusion queries over a scene.
//! - [`render`] turns a scene into an image: camera, Whitted shading, skybox, tiles, film.
//! - [`generate`] writes the project's own scenes as P3F text, and its skybox.
//! - [`limits`] holds the sizes accepted from files and the command line.
//! - [`compare`] measures how two images differ.
//! - [`farm`] writes, reads and merges the parts of a frame split over many machines.
//! - [`view`] orbits the camera and converges a still view to `render`'s image.
//! - [`mod@bench`] runs the trace-throughput protocol of `../shared/bench/PROTOCOL.md`.
//! - [`machine`] says what the binary was built for and what the CPU offers.
//! - [`plural`] writes counts with their noun, singular or plural.

//!
//! # An example
//!
//! Read a scene, build its BVH, trace a ray and a packet of rays through it, render it into
//! a buffer and compare two renders (`examples/` has whole programs):
//!
//! ```
//! use glam::Vec3;
//! use p3trace::accel::{AccelOptions, Tracer};
//! use p3trace::compare::{compare, Levels};
//! use p3trace::ray::{Ray, RayPacket};
//! use p3trace::render::{render, RenderOptions};
//! use p3trace::scene::parse_str;
//! use p3trace::simd::PACKET;
//!
//! let text = "v from 0 0 5 at 0 0 0 up 0 1 0 angle 40 hither 0.01 resolution 32 24
//!             l 3 4 5 1 1 1
//!             f 1 0.5 0.2 1 1 1 1 0.3 30 0 1
//!             s 0 0 0 1";
//! let scene = parse_str(text, "example", std::path::Path::new(".")).unwrap();
//!
//! // One ray from the eye down the view, and a packet of them side by side.
//! let tracer = Tracer::new(&scene.geometry, &AccelOptions::default());
//! let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z);
//! let hit = tracer.closest(&ray, 0.0, f32::INFINITY).unwrap();
//! assert!((hit.t - 4.0).abs() < 1e-5); // the sphere's near side, at z = 1
//! let rays: [Ray; PACKET] = std::array::from_fn(|k| {
//!     Ray::new(Vec3::new(0.1 * k as f32 - 0.5, 0.0, 5.0), Vec3::NEG_Z)
//! });
//! let hits = tracer.closest_packet(&RayPacket::new(&rays));
//! assert!(hits.iter().all(Option::is_some));
//!
//! // The image in linear RGB, top row first; the same with one thread.
//! let options = RenderOptions::from_scene(&scene);
//! let film = render(&scene, &options).unwrap().film;
//! assert_eq!((film.width, film.height), (32, 24));
//! let one_thread = RenderOptions { threads: Some(1), ..options };
//! let again = render(&scene, &one_thread).unwrap().film;
//! let levels = |f: &p3trace::imaging::Film| Levels {
//!     width: f.width,
//!     height: f.height,
//!     rgb: f.to_rgb8().into_iter().map(f32::from).collect(),
//! };
//! let diff = compare(&levels(&film), &levels(&again), 0.0).unwrap();
//! assert_eq!(diff.within_tolerance, 1.0); // every pixel equal
//! ```

// Tests like `!(x > 0.0)` are deliberate: they must also reject NaN, which `x <= 0.0` lets
// through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod bench;
pub mod compare;
pub mod farm;
pub mod generate;
pub mod imaging;
pub mod intersect;
pub mod limits;
pub mod machine;
pub mod output;
pub mod plural;
pub mod prim;
pub mod ray;
pub mod render;
pub mod scene;
pub mod simd;
pub mod view;
