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

// Tests like `!(x > 0.0)` are deliberate: they must also reject NaN, which `x <= 0.0` lets
// through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod bench;
pub mod compare;
pub mod farm;
pub mod generate;
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
