//! The lights as the shader samples them (P3F.md 6.3): each scene light becomes an
//! [`Emitter`], a fixed point or a rectangle sampled at one jittered point of the
//! sample's cell; without antialiasing rectangles become grids of points. Given the
//! point it lights ([`Receiver`]), an emitter says where its light comes from, how far,
//! and with what colour ([`Emitter::sample`], as pbrt-v4's `SampleLi`): the shader
//! (`shade.rs`) and the bench's shadow rays (`bench.rs`) work out nothing more.
//!
//! A soft point light's square lies in the plane perpendicular to the camera's up, its
//! sides along `up x X` (`up x Z` when up is close to X) and the third axis. An `al` light
//! faces its target, its width horizontal (perpendicular to world Y), or along X when it
//! faces straight up or down. A jittered point is drawn anew at every hit along a
//! sample's path, from that ray's own random numbers, in the cell of the sample's grid
//! that its primary sample took.

use std::ops::Sub;

use glam::{DVec3, Vec3};

use super::sampler::{dim, Sample, SampleGrid};
use crate::scene::Light;
use crate::simd::{F32x8, Mask8, Vec3x8};

/// Lights sampled over an area become this grid of points when a pixel has one sample
/// (P3F.md 6.3), unless the options say otherwise.
pub const DEFAULT_LIGHT_GRID: SampleGrid = SampleGrid::square(4);

/// The side of the square a point light becomes with soft shadows (P3F.md 6.3).
pub const DEFAULT_LIGHT_SIZE: f32 = 0.5;

/// A point that light comes from, with its share of its light's colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    pub position: Vec3,
    pub colour: Vec3,
}

/// A light as the shader samples it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Emitter {
    /// The same point for every sample.
    Point(LightSample),
    /// Sample `(p, q)` of a pixel's a x b grid of samples takes one point of the
    /// rectangle, jittered in cell `(p, q)` of an a x b grid over it, with the full colour.
    Rectangle(Rectangle),
}

/// A rectangular light centred at `centre`, with sides the full-length vectors `across`
/// and `up`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rectangle {
    pub centre: Vec3,
    pub across: Vec3,
    pub up: Vec3,
    pub colour: Vec3,
}

impl Rectangle {
    /// The point at `(s, t)` in `[-0.5, 0.5]^2`.
    fn at(&self, s: f32, t: f32) -> Vec3 {
        self.centre + self.across * s + self.up * t
    }

    /// The centres of the cells of `grid` over it (columns across, rows up), each with
    /// an equal share of the colour.
    fn grid(self, grid: SampleGrid) -> impl Iterator<Item = LightSample> {
        let (columns, rows) = (grid.columns.max(1), grid.rows.max(1));
        let centre = |i: u32, n: u32| (i as f32 + 0.5) / n as f32 - 0.5;
        (0..columns * rows).map(move |i| LightSample {
            position: self.at(centre(i / rows, columns), centre(i % rows, rows)),
            colour: self.colour / (columns * rows) as f32,
        })
    }
}

/// Where light arrives: a point of a surface, the surface's unit normal turned to face
/// the ray that found it, and the origin of shadow rays from there, off the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver<V> {
    pub point: V,
    pub normal: V,
    pub origin: V,
}

/// The light that one point of a light sends a receiver: the unit direction from the
/// receiver's origin towards it, its distance along that direction, and the colour that
/// arrives when nothing is in the way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incident<V> {
    pub dir: V,
    pub distance: f32,
    pub colour: Vec3,
}

/// Where one point of a light lies from each of eight receivers, as [`Incident`] lane by
/// lane; its colour is the light's ([`Emitter::colour`]).
#[derive(Clone, Copy, Debug)]
pub struct Incident8 {
    pub dir: Vec3x8,
    pub distance: F32x8,
}

/// The vectors lights are sampled in: `Vec3`, the renderer's, and `DVec3`, in which the
/// bench makes the protocol's rays as the Embree harness does. Each rounds as its caller's
/// rays always have: images and checksums are made of those bits.
pub trait Vector: Copy + From<Vec3> + Sub<Output = Self> {
    /// `self` points along or below the plane of `normal`: `normal . self <= 0`.
    fn below(self, normal: Self) -> bool;
    /// The unit vector along `self`, and its length.
    fn unit(self) -> (Self, f32);
}

impl Vector for Vec3 {
    fn below(self, normal: Self) -> bool {
        normal.dot(self) <= 0.0
    }

    /// Divided by its length.
    fn unit(self) -> (Self, f32) {
        let length = self.length();
        (self / length, length)
    }
}

impl Vector for DVec3 {
    fn below(self, normal: Self) -> bool {
        normal.dot(self) <= 0.0
    }

    /// Scaled by the reciprocal of its length, as the harness normalises; the length
    /// rounded to `f32` last.
    fn unit(self) -> (Self, f32) {
        (self.normalize(), self.length() as f32)
    }
}

impl Emitter {
    /// The light that the point of this light (the `index`-th that [`emitters`] made)
    /// that `sample` sees sends `receiver`; `None` when that point is not above the
    /// tangent plane of the receiver's surface.
    // Inlined into the shader's two paths: see `Shader::shadow_ray`.
    #[inline(always)]
    pub fn sample<V: Vector>(
        &self,
        index: usize,
        receiver: &Receiver<V>,
        sample: &Sample,
    ) -> Option<Incident<V>> {
        let light = self.point(index, sample);
        let position = V::from(light.position);
        if (position - receiver.point).below(receiver.normal) {
            return None;
        }
        let (dir, distance) = (position - receiver.origin).unit();
        Some(Incident {
            dir,
            distance,
            colour: light.colour,
        })
    }

    /// [`Emitter::sample`] for eight receivers at once, lane `k` with the sample
    /// `sample(k)`, in the same operations: the lanes whose point is above the receiver's
    /// tangent plane, and their light (the other lanes' is meaningless).
    #[inline(always)]
    pub fn sample8(
        &self,
        index: usize,
        receiver: &Receiver<Vec3x8>,
        sample: impl Fn(usize) -> Sample,
    ) -> (Mask8, Incident8) {
        let position = match self {
            Emitter::Point(light) => Vec3x8::splat(light.position),
            Emitter::Rectangle(_) => Vec3x8::from_lanes(std::array::from_fn(|k| {
                self.point(index, &sample(k)).position
            })),
        };
        let facing = !receiver
            .normal
            .dot(position - receiver.point)
            .le(F32x8::ZERO);
        let towards = position - receiver.origin;
        let distance = towards.length();
        let incident = Incident8 {
            dir: towards / distance,
            distance,
        };
        (facing, incident)
    }

    /// The colour that every point of this light sends.
    pub fn colour(&self) -> Vec3 {
        match self {
            Emitter::Point(light) => light.colour,
            Emitter::Rectangle(rectangle) => rectangle.colour,
        }
    }

    /// The point of this light (the `index`-th of the shader's) that `sample` sees.
    fn point(&self, index: usize, sample: &Sample) -> LightSample {
        match self {
            Emitter::Point(light) => *light,
            Emitter::Rectangle(rectangle) => {
                let dim = dim::LIGHT + 2 * index as u32;
                let (columns, rows) = (sample.grid.columns as f32, sample.grid.rows as f32);
                let s = (sample.cell[0] as f32 + sample.rng.uniform(dim)) / columns - 0.5;
                let t = (sample.cell[1] as f32 + sample.rng.uniform(dim + 1)) / rows - 0.5;
                LightSample {
                    position: rectangle.at(s, t),
                    colour: rectangle.colour,
                }
            }
        }
    }
}

/// The lights of a scene as the shader samples them. Lights with an area are the
/// scene's `al` lights and, with soft shadows, its point lights as squares of side
/// `soft_light_size` in the plane perpendicular to `camera_up`. With `jittered`
/// sampling they stay rectangles, sampled once per sample; otherwise each becomes the
/// points of `light_grid`, each with an equal share of the colour.
pub fn emitters(
    lights: &[Light],
    camera_up: Vec3,
    soft_light_size: Option<f32>,
    light_grid: SampleGrid,
    jittered: bool,
) -> Vec<Emitter> {
    let mut emitters = Vec::new();
    for light in lights {
        let rectangle = match *light {
            Light::Point { position, colour } => {
                let Some(size) = soft_light_size else {
                    emitters.push(Emitter::Point(LightSample { position, colour }));
                    continue;
                };
                let (across, up) = square_axes(camera_up);
                Rectangle {
                    centre: position,
                    across: across * size,
                    up: up * size,
                    colour,
                }
            }
            Light::Area {
                centre,
                target,
                width,
                height,
                colour,
            } => {
                let (across, up) = area_light_axes(target - centre);
                Rectangle {
                    centre,
                    across: across * width,
                    up: up * height,
                    colour,
                }
            }
        };
        if jittered {
            emitters.push(Emitter::Rectangle(rectangle));
        } else {
            emitters.extend(rectangle.grid(light_grid).map(Emitter::Point));
        }
    }
    emitters
}

/// Two unit axes spanning the plane perpendicular to `camera_up`.
fn square_axes(camera_up: Vec3) -> (Vec3, Vec3) {
    let normal = camera_up.normalize();
    let helper = if normal.x.abs() < 0.9 {
        Vec3::X
    } else {
        Vec3::Z
    };
    let across = normal.cross(helper).normalize();
    (across, normal.cross(across))
}

/// Two unit axes spanning the plane of an area light facing `facing`: the width runs
/// along the first, horizontal with respect to world Y unless the light faces along Y,
/// where it runs along X.
fn area_light_axes(facing: Vec3) -> (Vec3, Vec3) {
    let normal = facing.normalize();
    let helper = if normal.y.abs() < 0.999 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let across = helper.cross(normal).normalize();
    (across, normal.cross(across))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::SampleRng;

    /// A white area light 5 above the origin facing down: 2 wide along x, 1 high along z.
    const AREA: Light = Light::Area {
        centre: Vec3::new(0., 5., 0.),
        target: Vec3::ZERO,
        width: 2.0,
        height: 1.0,
        colour: Vec3::ONE,
    };

    #[test]
    fn area_light_grid_covers_the_rectangle_with_the_full_colour() {
        let light = AREA;
        let samples = emitters(&[light], Vec3::Z, None, DEFAULT_LIGHT_GRID, false);
        assert_eq!(samples.len(), DEFAULT_LIGHT_GRID.cells() as usize);
        let points = samples.iter().map(|e| match e {
            Emitter::Point(s) => *s,
            Emitter::Rectangle(_) => panic!("without antialiasing lights are points"),
        });
        let total: Vec3 = points.clone().map(|s| s.colour).sum();
        assert!((total - Vec3::ONE).length() < 1e-6);
        for s in points {
            assert!((s.position.y - 5.0).abs() < 1e-6);
            assert!(s.position.x.abs() < 1.0 && s.position.z.abs() < 0.5);
        }
    }

    /// A receiver at the origin facing up, its shadow rays starting 0.1 above it.
    fn receiver<V: Vector>() -> Receiver<V> {
        Receiver {
            point: V::from(Vec3::ZERO),
            normal: V::from(Vec3::Y),
            origin: V::from(Vec3::new(0.0, 0.1, 0.0)),
        }
    }

    #[test]
    fn a_light_above_the_surface_lights_it_from_the_receivers_origin() {
        let light = |position: Vec3| {
            Emitter::Point(LightSample {
                position,
                colour: Vec3::new(0.5, 0.25, 1.0),
            })
        };
        let one = sample([0, 0], SampleGrid::square(1), 0);
        // Above the tangent plane but below the origin: lit, from the origin downwards.
        let low = Vec3::new(4.0, 0.05, 3.0);
        let incident = light(low).sample(0, &receiver::<Vec3>(), &one).unwrap();
        let to_light = low - Vec3::new(0.0, 0.1, 0.0);
        assert_eq!(incident.dir, to_light / to_light.length());
        assert_eq!(incident.distance, to_light.length());
        assert_eq!(incident.colour, Vec3::new(0.5, 0.25, 1.0));
        assert!(incident.dir.y < 0.0);
        // In the tangent plane or below it: no light.
        for position in [Vec3::new(4.0, 0.0, 3.0), Vec3::new(0.0, -2.0, 0.0)] {
            assert_eq!(light(position).sample(0, &receiver::<Vec3>(), &one), None);
        }
        // In double precision, normalised as the Embree harness does: scaled by 1 / length.
        let incident = light(low).sample(0, &receiver::<DVec3>(), &one).unwrap();
        let to_light = low.as_dvec3() - DVec3::new(0.0, f64::from(0.1f32), 0.0);
        assert_eq!(incident.dir, to_light * (1.0 / to_light.length()));
        assert_eq!(incident.distance, to_light.length() as f32);
    }

    fn sample(cell: [u32; 2], grid: SampleGrid, index: u32) -> Sample {
        Sample {
            rng: SampleRng::new(index, 0, 7),
            cell,
            grid,
        }
    }

    #[test]
    fn soft_point_lights_become_squares_perpendicular_to_the_camera_up() {
        let light = Light::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            colour: Vec3::ONE,
        };
        let up = Vec3::new(0.0, 1.0, 1.0);
        // Without antialiasing: a 3 x 3 grid in the plane through the light.
        let grid = emitters(&[light], up, Some(0.5), SampleGrid::square(3), false);
        assert_eq!(grid.len(), 9);
        let mut total = Vec3::ZERO;
        for emitter in &grid {
            let point = emitter.point(0, &sample([0, 0], SampleGrid::square(1), 0));
            let offset = point.position - Vec3::new(1.0, 2.0, 3.0);
            assert!(offset.dot(up).abs() < 1e-6, "{offset} leaves the plane");
            assert!(offset.length() <= 0.5 * 2f32.sqrt() / 2.0 * 1.001);
            total += point.colour;
        }
        assert!((total - Vec3::ONE).length() < 1e-6);

        // With 4 x 4 antialiasing: sample (p, q) takes a point of cell (p, q), with the
        // light's full colour, and fills that cell.
        let [square] = emitters(&[light], up, Some(0.5), SampleGrid::square(3), true)[..] else {
            panic!("one rectangle per light")
        };
        let Emitter::Rectangle(r) = square else {
            panic!("a soft light is a rectangle")
        };
        let coordinates = |position: Vec3| {
            let offset = position - r.centre;
            let s = offset.dot(r.across) / r.across.length_squared() + 0.5;
            let t = offset.dot(r.up) / r.up.length_squared() + 0.5;
            (s * 4.0, t * 4.0)
        };
        let (mut low, mut high) = ((f32::MAX, f32::MAX), (f32::MIN, f32::MIN));
        for i in 0..2000 {
            let point = square.point(0, &sample([1, 2], SampleGrid::square(4), i));
            assert_eq!(point.colour, Vec3::ONE);
            let (s, t) = coordinates(point.position);
            assert!(
                (1.0..2.0).contains(&s) && (2.0..3.0).contains(&t),
                "{s} {t}"
            );
            (low, high) = ((low.0.min(s), low.1.min(t)), (high.0.max(s), high.1.max(t)));
        }
        assert!(low.0 < 1.01 && low.1 < 2.01 && high.0 > 1.99 && high.1 > 2.99);
    }

    #[test]
    fn rectangular_grids_run_columns_across_and_rows_up() {
        let light = AREA;
        let eight = SampleGrid::with_cells(8);
        let points: Vec<Vec3> = emitters(&[light], Vec3::Z, None, eight, false)
            .iter()
            .map(|e| {
                e.point(0, &sample([0, 0], SampleGrid::square(1), 0))
                    .position
            })
            .collect();
        let xs = [-0.75, -0.25, 0.25, 0.75];
        let zs = [-0.25, 0.25];
        let expected: Vec<Vec3> = xs
            .iter()
            .flat_map(|&x| zs.iter().map(move |&z| Vec3::new(x, 5.0, z)))
            .collect();
        assert_eq!(points.len(), expected.len());
        for (p, e) in points.iter().zip(&expected) {
            assert!((*p - *e).length() < 1e-6, "{p} instead of {e}");
        }

        // Sample (3, 1) of a 4 x 2 pixel grid takes a point of the light's cell (3, 1).
        let [rectangle] = emitters(&[light], Vec3::Z, None, eight, true)[..] else {
            panic!("one rectangle per light")
        };
        for i in 0..500 {
            let p = rectangle.point(0, &sample([3, 1], eight, i)).position;
            assert!(
                (0.5..1.0).contains(&p.x) && (0.0..0.5).contains(&p.z),
                "{p}"
            );
        }
    }
}
