//! The P3F camera (P3F.md section 3): a pinhole, or a thin lens when `aperture > 0`. The
//! stream renderer makes its primary rays eight at a time ([`Camera::rays8`]), each the
//! scalar [`Camera::ray`]'s bits (`tests/integration/simd.rs`).

use glam::{Vec2, Vec3};

use crate::ray::Ray;
use crate::scene::CameraSpec;
use crate::simd::{F32x8, Vec3x8};

/// Where a primary ray starts from: the film point `(sx, sy)` in pixels, the point of
/// the unit disk `lens` (for a thin lens), and the time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmSample {
    pub sx: f32,
    pub sy: f32,
    pub lens: Vec2,
    pub time: f32,
}

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    eye: Vec3,
    /// The camera frame: `u` right, `v` up, `n` backwards (the camera looks along `-n`).
    u: Vec3,
    v: Vec3,
    n: Vec3,
    /// Distance from the eye to the view plane, which passes through `at`.
    plane_distance: f32,
    /// Size of the view plane in world units.
    plane_width: f32,
    plane_height: f32,
    width: f32,
    height: f32,
    lens_radius: f32,
    focal: f32,
}

impl Camera {
    /// A camera for an image of `width` x `height` pixels. `spec` must have passed
    /// [`CameraSpec::validate`].
    pub fn new(spec: &CameraSpec, width: u32, height: u32) -> Self {
        let n = (spec.from - spec.at).normalize();
        let plane_distance = (spec.from - spec.at).length();
        let u = spec.up.cross(n).normalize();
        let v = n.cross(u);
        let plane_height = 2.0 * plane_distance * (spec.angle.to_radians() / 2.0).tan();
        let plane_width = plane_height * width as f32 / height as f32;
        // The aperture counts pixel widths of the file's resolution, so that a preview at
        // any size shows the same blur (P3F.md section 3).
        let file_plane_width = plane_height * spec.width as f32 / spec.height as f32;
        Camera {
            eye: spec.from,
            u,
            v,
            n,
            plane_distance,
            plane_width,
            plane_height,
            width: width as f32,
            height: height as f32,
            lens_radius: spec.aperture * file_plane_width / spec.width as f32,
            focal: spec.focal,
        }
    }

    pub fn is_thin_lens(&self) -> bool {
        self.lens_radius > 0.0
    }

    /// The primary ray through film position `(sx, sy)` in pixel units, `(0, 0)` being the
    /// bottom-left corner. `lens` is a point of the unit disk, used only by a thin lens.
    pub fn ray(&self, film: &FilmSample) -> Ray {
        let FilmSample { sx, sy, lens, time } = *film;
        let x = self.plane_width * (sx / self.width - 0.5);
        let y = self.plane_height * (sy / self.height - 0.5);
        let mut ray = if self.is_thin_lens() {
            let l = lens * self.lens_radius;
            let (px, py) = (x * self.focal, y * self.focal);
            let dir = self.u * (px - l.x) + self.v * (py - l.y)
                - self.n * (self.focal * self.plane_distance);
            Ray::new(self.eye + self.u * l.x + self.v * l.y, dir.normalize())
        } else {
            let dir = self.u * x + self.v * y - self.n * self.plane_distance;
            Ray::new(self.eye, dir.normalize())
        };
        ray.time = time;
        ray
    }

    /// [`Camera::ray`] of the eight film samples `sample(0..8)`, computed eight lanes at a
    /// time in its order of operations: each ray is the scalar one bit for bit. The
    /// samples are read where they lie and the rays taken lane by lane: arrays of either
    /// built on the stack are read back before their stores can forward.
    #[inline]
    pub fn rays8<'s>(&self, sample: impl Fn(usize) -> &'s FilmSample) -> CameraRays8 {
        let lanes =
            |f: fn(&FilmSample) -> f32| F32x8::from_array(std::array::from_fn(|k| f(sample(k))));
        let (sx, sy) = (lanes(|s| s.sx), lanes(|s| s.sy));
        let splat = F32x8::splat;
        let half = splat(0.5);
        let x = splat(self.plane_width) * (sx / splat(self.width) - half);
        let y = splat(self.plane_height) * (sy / splat(self.height) - half);
        let (u, v) = (Vec3x8::splat(self.u), Vec3x8::splat(self.v));
        let (origin, dir) = if self.is_thin_lens() {
            let radius = splat(self.lens_radius);
            let (lx, ly) = (lanes(|s| s.lens.x) * radius, lanes(|s| s.lens.y) * radius);
            let focal = splat(self.focal);
            let (px, py) = (x * focal, y * focal);
            let depth = Vec3x8::splat(self.n * (self.focal * self.plane_distance));
            let dir = u.scale(px - lx) + v.scale(py - ly) - depth;
            (Vec3x8::splat(self.eye) + u.scale(lx) + v.scale(ly), dir)
        } else {
            let depth = Vec3x8::splat(self.n * self.plane_distance);
            (Vec3x8::splat(self.eye), u.scale(x) + v.scale(y) - depth)
        };
        CameraRays8 {
            origin,
            dir: dir.normalize(),
            time: lanes(|s| s.time),
        }
    }
}

/// Eight camera rays as structure of arrays ([`Camera::rays8`]).
pub struct CameraRays8 {
    origin: Vec3x8,
    dir: Vec3x8,
    time: F32x8,
}

impl CameraRays8 {
    /// Lane `k`'s ray.
    #[inline]
    pub fn ray(&self, k: usize) -> Ray {
        Ray {
            origin: self.origin.lane(k),
            dir: self.dir.lane(k),
            time: self.time.lane(k),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film(sx: f32, sy: f32, lens: Vec2) -> FilmSample {
        FilmSample {
            sx,
            sy,
            lens,
            time: 0.0,
        }
    }

    fn spec() -> CameraSpec {
        CameraSpec {
            from: Vec3::new(0., 0., 10.),
            at: Vec3::ZERO,
            up: Vec3::Y,
            angle: 90.0,
            width: 200,
            height: 100,
            ..CameraSpec::default()
        }
    }

    #[test]
    fn centre_ray_looks_at_the_target() {
        let cam = Camera::new(&spec(), 200, 100);
        let r = cam.ray(&film(100.0, 50.0, Vec2::ZERO));
        assert!((r.dir - Vec3::NEG_Z).length() < 1e-6);
        assert_eq!(r.origin, Vec3::new(0., 0., 10.));
    }

    #[test]
    fn corners_span_the_field_of_view() {
        // 90 degrees vertically at distance 10: the view plane is 20 high and 40 wide.
        let cam = Camera::new(&spec(), 200, 100);
        let top_right = cam.ray(&film(200.0, 100.0, Vec2::ZERO));
        let expected = Vec3::new(20., 10., -10.).normalize();
        assert!((top_right.dir - expected).length() < 1e-6);
        let bottom_left = cam.ray(&film(0.0, 0.0, Vec2::ZERO));
        assert!((bottom_left.dir - Vec3::new(-20., -10., -10.).normalize()).length() < 1e-6);
    }

    #[test]
    fn thin_lens_rays_meet_on_the_focal_plane() {
        let s = CameraSpec {
            aperture: 4.0,
            focal: 1.5,
            ..spec()
        };
        let cam = Camera::new(&s, 200, 100);
        assert!(cam.is_thin_lens());
        let (sx, sy) = (37.0, 81.0);
        let points: Vec<Vec3> = [Vec2::ZERO, Vec2::new(1., 0.), Vec2::new(-0.3, 0.8)]
            .iter()
            .map(|&l| {
                let r = cam.ray(&film(sx, sy, l));
                // The focal plane is z = 10 - 1.5 * 10.
                r.at((-5.0 - r.origin.z) / r.dir.z)
            })
            .collect();
        assert!((points[0] - points[1]).length() < 1e-4);
        assert!((points[0] - points[2]).length() < 1e-4);
        // The lens is aperture pixel widths wide: 4 * 40 / 200 = 0.8.
        let edge = cam.ray(&film(sx, sy, Vec2::new(1., 0.)));
        assert!((edge.origin - Vec3::new(0.8, 0., 10.)).length() < 1e-5);
    }

    #[test]
    fn the_lens_keeps_its_size_at_any_image_size() {
        // The pixel widths are the file's (200 x 100): the same lens at every size.
        let s = CameraSpec {
            aperture: 4.0,
            ..spec()
        };
        for (width, height) in [(200, 100), (25, 13), (1600, 800), (100, 100)] {
            let edge = Camera::new(&s, width, height).ray(&film(3.0, 2.0, Vec2::new(1., 0.)));
            assert!(
                (edge.origin - Vec3::new(0.8, 0., 10.)).length() < 1e-5,
                "{width}x{height}"
            );
        }
    }
}
