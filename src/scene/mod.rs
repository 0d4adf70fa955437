//! The scene model: geometry (a storage per primitive kind), materials, lights and camera,
//! read from P3F files by [`p3f`].

pub mod geometry;
pub mod p3f;
pub mod ply;

use std::path::{Component, Path, PathBuf};

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
    /// `env DIR`: the skybox folder, and where to look for it.
    pub skybox: Option<SkyboxFolder>,
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

/// The skybox folder of `env DIR`. It is looked for in the scene file's folder, then in
/// the current folder, then in the scene folder's parent: students keep `skybox/` beside
/// their folder of scenes, where the course's program, run from there, found it.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyboxFolder {
    /// `DIR` as the file writes it.
    pub name: PathBuf,
    /// The folder of the scene file (empty for the current one).
    pub scene_folder: PathBuf,
}

impl SkyboxFolder {
    /// Where the folder is looked for, in order of preference, each place once: an
    /// absolute `DIR` is its own only place.
    pub fn places(&self) -> Vec<PathBuf> {
        let here = Path::new(".");
        let scene_folder = match self.scene_folder.as_os_str().is_empty() {
            true => here,
            false => self.scene_folder.as_path(),
        };
        let mut places: Vec<PathBuf> = Vec::new();
        for folder in [scene_folder, here, &parent_folder(scene_folder)] {
            let place = folder.join(&self.name);
            if !places.iter().any(|p| same_place(p, &place)) {
                places.push(place);
            }
        }
        places
    }

    /// The first of [`SkyboxFolder::places`] that is a folder, or why there is none: a
    /// sentence that names every place.
    pub fn find(&self) -> Result<PathBuf, String> {
        let places = self.places();
        if let Some(found) = places.iter().find(|place| place.is_dir()) {
            return Ok(found.clone());
        }
        let mut names: Vec<String> = places.iter().map(|p| p.display().to_string()).collect();
        let last = names.pop().unwrap_or_default();
        let listed = match names.is_empty() {
            true => last,
            false => format!("{} or {last}", names.join(", ")),
        };
        Err(format!("no skybox folder at {listed}"))
    }
}

/// The folder that holds `folder`, by its name where it can (`scenes` is in `.`, `a/b` in
/// `a`), else through `..`.
fn parent_folder(folder: &Path) -> PathBuf {
    match folder.components().next_back() {
        Some(Component::Normal(_)) => match folder.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
            _ => PathBuf::from("."),
        },
        Some(Component::CurDir) => PathBuf::from(".."),
        Some(Component::RootDir) => folder.to_path_buf(),
        _ => folder.join(".."),
    }
}

/// Whether `a` and `b` name one place from the current folder (`./sky` and `/cwd/sky`).
fn same_place(a: &Path, b: &Path) -> bool {
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    absolute(a) == absolute(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn places(name: &str, scene_folder: &str) -> Vec<PathBuf> {
        let sky = SkyboxFolder {
            name: name.into(),
            scene_folder: scene_folder.into(),
        };
        sky.places()
    }

    #[test]
    fn a_skybox_is_looked_for_beside_the_scene_then_here_then_above_the_scene() {
        let paths = |list: &[&str]| list.iter().map(PathBuf::from).collect::<Vec<_>>();
        assert_eq!(
            places("skybox", "../course/scenes"),
            paths(&["../course/scenes/skybox", "./skybox", "../course/skybox"])
        );
        // A scene in the current folder: its parent is `..`; in `scenes`, the current one.
        assert_eq!(places("skybox", ""), paths(&["./skybox", "../skybox"]));
        assert_eq!(places("sky", "scenes/"), paths(&["scenes/sky", "./sky"]));
        assert_eq!(
            places("sky", ".."),
            paths(&["../sky", "./sky", "../../sky"])
        );
        assert_eq!(places("/opt/sky", "scenes"), paths(&["/opt/sky"]));
        let here = std::env::current_dir().unwrap();
        assert_eq!(
            places("sky", here.to_str().unwrap()),
            vec![here.join("sky"), here.parent().unwrap().join("sky")]
        );
    }
}
