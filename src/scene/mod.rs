//! The scene model: geometry (a storage per primitive kind), materials, lights and camera,
//! read from P3F files by [`p3f`].

pub mod geometry;
pub mod p3f;
pub mod ply;

use std::path::PathBuf;

use glam::{DVec3, Vec3};

pub use geometry::Geometry;
pub use p3f::{parse_file, parse_file_in, parse_str, parse_str_in, FileError, ParseError};

/// `f Rd Gd Bd Kd Rs Gs Bs Ks Shine T ior` (P3F.md section 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub diffuse: Vec3,
    pub kd: f32,
    pub specular: Vec3,
    pub ks: f32,
    pub shine: f32,
    pub transmittance: f32,
    pub ior: f32,
}

impl Material {
    /// The course code's default, given to objects that come before any `f`.
    pub const DEFAULT: Material = Material {
        diffuse: Vec3::splat(0.2),
        kd: 0.2,
        specular: Vec3::ONE,
        ks: 0.8,
        shine: 20.0,
        transmittance: 0.0,
        ior: 1.0,
    };
}

/// A light source. Area lights are sampled as a grid of point lights (P3F.md 6.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    Point {
        position: Vec3,
        colour: Vec3,
    },
    /// `al`: a `width` x `height` rectangle centred at `centre`, facing the point `target`.
    Area {
        centre: Vec3,
        target: Vec3,
        width: f32,
        height: f32,
        colour: Vec3,
    },
}

impl Light {
    /// The kinds of light, in the order `info` counts them.
    pub const KINDS: [&'static str; 2] = ["point", "area"];

    /// This light's kind, one of [`Light::KINDS`].
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Point { .. } => "point",
            Light::Area { .. } => "area",
        }
    }
}

/// The camera block `v` as written in the file (P3F.md section 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    pub from: Vec3,
    pub at: Vec3,
    pub up: Vec3,
    /// Full vertical field of view in degrees.
    pub angle: f32,
    pub hither: f32,
    pub width: u32,
    pub height: u32,
    /// Lens radius in pixel widths of the file's `resolution`; 0 is a pinhole.
    pub aperture: f32,
    /// Distance of the focal plane as a multiple of `|from - at|`.
    pub focal: f32,
}

impl Default for CameraSpec {
    fn default() -> Self {
        CameraSpec {
            from: Vec3::new(0.0, 0.0, 1.0),
            at: Vec3::ZERO,
            up: Vec3::Y,
            angle: 45.0,
            hither: 0.01,
            width: 512,
            height: 512,
            aperture: 0.0,
            focal: 1.0,
        }
    }
}

/// An acceleration structure, as a file asks for it with `accel N` (0, 1, 2) or the
/// command line with `--accel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelKind {
    None,
    Grid,
    Bvh,
}

/// A non-fatal remark about a scene file, with its position.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    pub line: u32,
    pub column: u32,
    pub message: String,
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// The file the scene came from (for messages), or a name for built-in scenes.
    pub name: String,
    pub geometry: Geometry,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: CameraSpec,
    /// `bclr`: the colour of rays that leave the scene when there is no skybox.
    pub background: Vec3,
    /// `env DIR`, resolved against the scene file's folder.
    pub skybox: Option<PathBuf>,
    pub accel: Option<AccelKind>,
    /// `spp k`: k x k jittered samples per pixel; 0 is one sample at the pixel centre.
    pub spp: u32,
    /// How many `mesh` directives there were, and the triangles they made.
    pub meshes: usize,
    pub mesh_triangles: usize,
    /// Whether a `v` block was read.
    pub has_camera: bool,
    pub warnings: Vec<Warning>,
    /// Where the stored coordinates start, in the file's ([`Frame`]): zero, or the
    /// camera's `from`.
    pub origin: DVec3,
}

/// The frame the reader stores positions in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Frame {
    /// The file's own coordinates, as written (the course's renderer's, the protocol's).
    #[default]
    File,
    /// Relative to the camera's `from`, subtracted in double precision: a scene far from
    /// the file's origin keeps the precision it has at the origin, so moving a whole
    /// scene (camera and lights too) leaves its image as it is (P3F.md 4). Directions and
    /// lengths are the file's; [`Scene::origin`] holds the `from`.
    Camera,
}
