//! What `p3trace view` computes, apart from its window: the camera's orbit about its `at`
//! as the course program's mouse moves it, the `v` block that puts a camera back in a
//! file, and the image that converges, pass by pass, to `render`'s.
//!
//! The course program turns its camera by one degree per pixel of a left drag (across:
//! about the up vector; down: up towards it, stopping at 85 degrees) and moves it along
//! the view direction with the right button and the wheel. [`Orbit`] does the same about
//! any up vector, from the file's camera. A still camera's image adds one sample of the
//! pixel's grid per pass ([`Accumulator`]) in the order `render` adds them, so that the
//! last pass is `render`'s image bit for bit.

use glam::{DVec3, Vec3};

use crate::imaging::Film;
use crate::scene::CameraSpec;

/// How far a left drag turns the camera: degrees per pixel, as in the course program.
pub const DEGREES_PER_PIXEL: f32 = 1.0;

/// How high above or below the `at` point the orbit goes, in degrees, as in the course
/// program (an up vector parallel to the view leaves no image).
pub const HIGHEST: f32 = 85.0;

/// The factor a step of the wheel (or 20 pixels of a right drag) moves the eye towards
/// the `at` point by.
pub const DOLLY_STEP: f32 = 0.9;

/// The camera as the mouse has moved it about the file's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    file: CameraSpec,
    /// The up vector, unit length, and two directions that complete its frame: `front`
    /// points from `at` to the file's eye, `side` is `up x front`.
    up: Vec3,
    front: Vec3,
    side: Vec3,
    /// Degrees about `up` from `front` towards `side`; degrees above the `at` point; the
    /// eye's distance from it.
    around: f32,
    above: f32,
    distance: f32,
    moved: bool,
}

impl Orbit {
    /// The orbit of a valid camera (one whose up vector is not along its view).
    pub fn new(file: &CameraSpec) -> Self {
        let up = file.up.normalize();
        let eye = file.from - file.at;
        let distance = eye.length();
        let level = eye - up * eye.dot(up);
        let front = level.normalize();
        let above = (eye.dot(up) / distance)
            .clamp(-1.0, 1.0)
            .asin()
            .to_degrees();
        Orbit {
            file: *file,
            up,
            front,
            side: up.cross(front),
            around: 0.0,
            above,
            distance,
            moved: false,
        }
    }

    /// A left drag of `(dx, dy)` pixels (right and down positive): across turns the eye
    /// about the up vector, the other way from the mouse; down raises it. A camera that
    /// starts higher than [`HIGHEST`] may stay there, but goes no higher.
    pub fn turn(&mut self, dx: f32, dy: f32) {
        let limit = HIGHEST.max(self.above.abs());
        self.around -= dx * DEGREES_PER_PIXEL;
        self.above = (self.above + dy * DEGREES_PER_PIXEL).clamp(-limit, limit);
        self.moved = true;
    }

    /// Moves the eye along the view direction: `steps` > 0 towards the `at` point, each
    /// step by [`DOLLY_STEP`]; never onto it.
    pub fn dolly(&mut self, steps: f32) {
        let distance = self.distance * DOLLY_STEP.powf(steps);
        if distance.is_finite() && distance > self.file.hither.max(f32::MIN_POSITIVE) * 1e-3 {
            self.distance = distance;
            self.moved = true;
        }
    }

    /// Back to the file's camera.
    pub fn reset(&mut self) {
        *self = Orbit::new(&self.file);
    }

    /// The camera: the file's until the mouse moves it.
    pub fn camera(&self) -> CameraSpec {
        if !self.moved {
            return self.file;
        }
        let (around, above) = (self.around.to_radians(), self.above.to_radians());
        let level = self.front * around.cos() + self.side * around.sin();
        let eye = (level * above.cos() + self.up * above.sin()) * self.distance;
        CameraSpec {
            from: self.file.at + eye,
            ..self.file
        }
    }

    /// Whether the mouse has moved the camera away from the file's.
    pub fn moved(&self) -> bool {
        self.moved
    }
}

/// The camera block `v` of P3F.md section 3 for `camera`, whose points are stored
/// relative to `origin` (the scene's [`crate::scene::Scene::origin`]): the file's
/// coordinates, ready to paste into it. Points are written to a millionth of the eye's
/// distance from `at`, which hides the rounding of the stored frame (an `at` of 0 stays
/// 0, not 1e-7).
pub fn camera_block(camera: &CameraSpec, origin: DVec3) -> String {
    let distance = (camera.from - camera.at).length() as f64;
    let point = |p: Vec3| {
        let p = origin + p.as_dvec3();
        let scale = distance.max(p.abs().max_element());
        [p.x, p.y, p.z].map(|x| decimal(x, scale)).join(" ")
    };
    let mut block = format!(
        "v\nfrom {}\nat {}\nup {} {} {}\nangle {}\nhither {}\nresolution {} {}\n",
        point(camera.from),
        point(camera.at),
        camera.up.x,
        camera.up.y,
        camera.up.z,
        camera.angle,
        camera.hither,
        camera.width,
        camera.height
    );
    if camera.aperture > 0.0 {
        block += &format!("aperture {}\nfocal {}\n", camera.aperture, camera.focal);
    }
    block
}

/// `x` with six significant digits of `scale`, without trailing zeros.
fn decimal(x: f64, scale: f64) -> String {
    let digits = if scale > 0.0 {
        (6.0 - scale.log10().floor()).clamp(0.0, 15.0) as usize
    } else {
        0
    };
    let text = format!("{x:.digits$}");
    let text = match text.contains('.') {
        true => text.trim_end_matches('0').trim_end_matches('.'),
        false => &text,
    };
    match text {
        "-0" => "0".into(),
        _ => text.into(),
    }
}

/// The sums of a frame's samples as passes bring them, one sample of every pixel a pass.
#[derive(Clone, Debug)]
pub struct Accumulator {
    sums: Film,
    passes: u32,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Self {
        Accumulator {
            sums: Film::new(width, height),
            passes: 0,
        }
    }

    /// Adds a pass: a film of one sample per pixel, the next in the grid's order.
    pub fn add(&mut self, pass: &Film) {
        assert_eq!(
            (pass.width, pass.height),
            (self.sums.width, self.sums.height),
            "a pass of another size"
        );
        for (sum, sample) in self.sums.pixels.iter_mut().zip(&pass.pixels) {
            *sum += *sample;
        }
        self.passes += 1;
    }

    /// The passes added so far.
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// The mean of the samples added so far: once every sample of the grid is in,
    /// `render`'s film bit for bit (each pixel's sum in the same order, divided alike).
    pub fn image(&self) -> Film {
        let n = self.passes.max(1) as f32;
        Film {
            pixels: self.sums.pixels.iter().map(|&sum| sum / n).collect(),
            ..self.sums
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file_camera() -> CameraSpec {
        CameraSpec {
            from: Vec3::new(2.1, 1.3, 1.7),
            at: Vec3::ZERO,
            up: Vec3::Z,
            ..CameraSpec::default()
        }
    }

    #[test]
    fn the_file_camera_stays_until_the_mouse_moves_it() {
        let mut orbit = Orbit::new(&file_camera());
        assert_eq!(orbit.camera(), file_camera());
        orbit.turn(30.0, 0.0);
        assert!(orbit.moved() && orbit.camera() != file_camera());
        orbit.reset();
        assert_eq!(orbit.camera(), file_camera());
    }

    #[test]
    fn a_drag_turns_about_up_keeping_the_distance_and_at() {
        let file = file_camera();
        let mut orbit = Orbit::new(&file);
        // A full turn across comes back; a drag down raises the eye.
        orbit.turn(360.0, 0.0);
        assert!(orbit.camera().from.distance(file.from) < 1e-5);
        orbit.turn(-90.0, 0.0);
        let turned = orbit.camera();
        assert!((turned.from.length() - file.from.length()).abs() < 1e-5);
        assert_eq!((turned.at, turned.up), (file.at, file.up));
        assert!((turned.from.z - file.from.z).abs() < 1e-5, "height kept");
        // 90 degrees about +z, the other way from the mouse: (x, y) becomes (-y, x).
        assert!((turned.from.x + file.from.y).abs() < 1e-5);
        assert!((turned.from.y - file.from.x).abs() < 1e-5);
        orbit.turn(0.0, 10.0);
        assert!(orbit.camera().from.z > turned.from.z);
    }

    #[test]
    fn the_eye_stops_at_85_degrees_above_and_below() {
        let mut orbit = Orbit::new(&file_camera());
        orbit.turn(0.0, 500.0);
        let eye = orbit.camera().from;
        let above = (eye.z / eye.length()).asin().to_degrees();
        assert!((above - HIGHEST).abs() < 1e-3, "{above}");
        orbit.turn(0.0, -1000.0);
        let eye = orbit.camera().from;
        assert!(((eye.z / eye.length()).asin().to_degrees() + HIGHEST).abs() < 1e-3);
    }

    #[test]
    fn the_wheel_moves_the_eye_along_the_view() {
        let file = file_camera();
        let mut orbit = Orbit::new(&file);
        orbit.dolly(2.0);
        let near = orbit.camera().from;
        assert!((near.length() - file.from.length() * 0.81).abs() < 1e-5);
        assert!(near.normalize().distance(file.from.normalize()) < 1e-5);
        orbit.dolly(f32::INFINITY);
        assert_eq!(orbit.camera().from, near, "never onto at");
    }

    #[test]
    fn the_camera_block_reads_back_as_the_camera() {
        let camera = CameraSpec {
            aperture: 2.0,
            focal: 1.5,
            ..file_camera()
        };
        let block = camera_block(&camera, DVec3::ZERO);
        assert_eq!(
            block,
            "v\nfrom 2.1 1.3 1.7\nat 0 0 0\nup 0 0 1\nangle 45\nhither 0.01\n\
             resolution 512 512\naperture 2\nfocal 1.5\n"
        );
        let scene = crate::scene::parse_str(&block, "v", std::path::Path::new("")).unwrap();
        assert_eq!(scene.camera, camera);
        // Stored relative to the eye, the points are the file's again.
        let moved = CameraSpec {
            from: Vec3::ZERO,
            at: -Vec3::new(2.1, 1.3, 1.7),
            ..camera
        };
        assert_eq!(camera_block(&moved, DVec3::new(2.1, 1.3, 1.7)), block);
    }
}
