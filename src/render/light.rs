//! The lights as the shader samples them (P3F.md 6.3): each scene light becomes an
//! [`Emitter`], a fixed point or a rectangle sampled at one jittered point of the
//! sample's cell; without antialiasing rectangles become grids of points. The shader
//! (`shade.rs`) asks only for the point of a light that a sample sees.

use glam::Vec3;

use super::sampler::{dim, Sample};
use crate::scene::Light;

/// Lights sampled over an area become this many points a side when a pixel has one
/// sample (P3F.md 6.3), unless the options say otherwise.
pub const DEFAULT_LIGHT_GRID: u32 = 4;

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
    /// Sample `(p, q)` of a pixel with k x k samples takes one point of the rectangle,
    /// jittered in cell `(p, q)` of a k x k grid over it, with the full colour.
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

    /// The centres of its n x n cells, each with 1 / n^2 of the colour.
    fn grid(self, n: u32) -> impl Iterator<Item = LightSample> {
        let n = n.max(1);
        let cell = move |i: u32| (i as f32 + 0.5) / n as f32 - 0.5;
        (0..n * n).map(move |i| LightSample {
            position: self.at(cell(i / n), cell(i % n)),
            colour: self.colour / (n * n) as f32,
        })
    }
}

impl Emitter {
    /// The point of this light (the `index`-th of the shader's) that `sample` sees.
    pub fn point(&self, index: usize, sample: &Sample) -> LightSample {
        match self {
            Emitter::Point(light) => *light,
            Emitter::Rectangle(rectangle) => {
                let dim = dim::LIGHT + 2 * index as u32;
                let k = sample.cells as f32;
                let s = (sample.cell[0] as f32 + sample.rng.uniform(dim)) / k - 0.5;
                let t = (sample.cell[1] as f32 + sample.rng.uniform(dim + 1)) / k - 0.5;
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
/// sampling they stay rectangles, sampled once per sample; otherwise each becomes an
/// n x n grid of points (n = `light_grid`), each with 1 / n^2 of the colour.
pub fn emitters(
    lights: &[Light],
    camera_up: Vec3,
    soft_light_size: Option<f32>,
    light_grid: u32,
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

    #[test]
    fn area_light_grid_covers_the_rectangle_with_the_full_colour() {
        let light = Light::Area {
            centre: Vec3::new(0., 5., 0.),
            target: Vec3::ZERO,
            width: 2.0,
            height: 1.0,
            colour: Vec3::ONE,
        };
        let samples = emitters(&[light], Vec3::Z, None, DEFAULT_LIGHT_GRID, false);
        assert_eq!(
            samples.len(),
            (DEFAULT_LIGHT_GRID * DEFAULT_LIGHT_GRID) as usize
        );
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

    fn sample(cell: [u32; 2], cells: u32, index: u32) -> Sample {
        Sample {
            rng: SampleRng::new(index, 0, 7),
            cell,
            cells,
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
        let grid = emitters(&[light], up, Some(0.5), 3, false);
        assert_eq!(grid.len(), 9);
        let mut total = Vec3::ZERO;
        for emitter in &grid {
            let point = emitter.point(0, &sample([0, 0], 1, 0));
            let offset = point.position - Vec3::new(1.0, 2.0, 3.0);
            assert!(offset.dot(up).abs() < 1e-6, "{offset} leaves the plane");
            assert!(offset.length() <= 0.5 * 2f32.sqrt() / 2.0 * 1.001);
            total += point.colour;
        }
        assert!((total - Vec3::ONE).length() < 1e-6);

        // With 4 x 4 antialiasing: sample (p, q) takes a point of cell (p, q), with the
        // light's full colour, and fills that cell.
        let [square] = emitters(&[light], up, Some(0.5), 3, true)[..] else {
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
            let point = square.point(0, &sample([1, 2], 4, i));
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
}
