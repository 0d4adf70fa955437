//! The fractal mountain ("mount") after Eric Haines' SPD, as in the course's `mount_*`
//! scenes: the square [-1, 1]^2 split into two triangles, each split `level` times into
//! four by its edge midpoints, every new midpoint raised or lowered at random; four glass
//! spheres float above it.
//!
//! A midpoint's height is the mean of its edge's ends plus a Gaussian displacement whose
//! spread is a fixed fraction of the edge length (a fractal of dimension 2). The random
//! number comes from a hash of the seed and the point's position, so every level refines
//! the one below it: `mount --level 5` has the same outline as `--level 1`, only finer.
//!
//! The rock is written as one `mesh` with shared vertices, where the course files have
//! separate `p 3` triangles; once read they are the same triangles.

use glam::{DVec2, DVec3};

use super::{Camera, Finish, Header, P3fWriter};

/// The largest level: 2 * 4^12, about 33.5 million triangles (the scale curve,
/// `scripts/scale-curve.py`, reaches it where memory allows).
pub const MAX_LEVEL: u32 = 12;

/// Standard deviation of a midpoint's displacement over the length of its edge. The
/// course's `mount_very_high` measures 0.23 to 0.26 at every level.
const ROUGHNESS: f64 = 0.25;

/// Triangles of a mountain of `level` subdivisions.
pub fn triangle_count(level: u32) -> usize {
    2 * 4usize.pow(level)
}

/// A height field on the `(2^level + 1)^2` lattice over [-1, 1]^2, and its triangles as
/// lattice indices, counter-clockwise seen from above.
pub struct Mountain {
    pub side: usize,
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Builds the mountain of `level` (at most [`MAX_LEVEL`]) for `seed`.
pub fn mountain(level: u32, seed: u64) -> Mountain {
    assert!(
        level <= MAX_LEVEL,
        "mountain level {level} above {MAX_LEVEL}"
    );
    let cells = 1usize << level;
    let side = cells + 1;
    let mut builder = Builder {
        seed,
        cells,
        side,
        heights: vec![f64::NAN; side * side],
        triangles: Vec::with_capacity(triangle_count(level)),
    };
    for corner in [[0, 0], [cells, 0], [0, cells], [cells, cells]] {
        builder.heights[corner[1] * side + corner[0]] = 0.0;
    }
    let (a, b, c, d) = ([0, 0], [cells, 0], [cells, cells], [0, cells]);
    builder.split([a, b, c], level);
    builder.split([c, d, a], level);
    let vertices = (0..side * side)
        .map(|k| {
            let p = builder.world([k % side, k / side]);
            DVec3::new(p.x, p.y, builder.heights[k])
        })
        .collect();
    Mountain {
        side,
        vertices,
        triangles: builder.triangles,
    }
}

type Lattice = [usize; 2];

struct Builder {
    seed: u64,
    cells: usize,
    side: usize,
    heights: Vec<f64>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    fn world(&self, p: Lattice) -> DVec2 {
        DVec2::new(p[0] as f64, p[1] as f64) * (2.0 / self.cells as f64) - 1.0
    }

    fn index(&self, p: Lattice) -> usize {
        p[1] * self.side + p[0]
    }

    fn split(&mut self, [a, b, c]: [Lattice; 3], level: u32) {
        if level == 0 {
            self.triangles.push([a, b, c].map(|p| self.index(p) as u32));
            return;
        }
        let ab = self.midpoint(a, b);
        let bc = self.midpoint(b, c);
        let ca = self.midpoint(c, a);
        self.split([a, ab, ca], level - 1);
        self.split([ab, b, bc], level - 1);
        self.split([ca, bc, c], level - 1);
        self.split([ab, bc, ca], level - 1);
    }

    /// The midpoint of edge `pq`, given its height the first time it is reached.
    fn midpoint(&mut self, p: Lattice, q: Lattice) -> Lattice {
        let m = [(p[0] + q[0]) / 2, (p[1] + q[1]) / 2];
        let k = self.index(m);
        if self.heights[k].is_nan() {
            let mean = 0.5 * (self.heights[self.index(p)] + self.heights[self.index(q)]);
            let length = self.world(p).distance(self.world(q));
            let offset = ROUGHNESS * length * gaussian(self.seed, self.world(m));
            self.heights[k] = mean + offset;
        }
        m
    }
}

/// A standard normal number that depends only on the seed and the point (Box-Muller on
/// two hashed uniforms). Points are dyadic, so scaling by 2^24 keys them exactly.
fn gaussian(seed: u64, point: DVec2) -> f64 {
    let key = |v: f64| (v * (1u64 << 24) as f64).round() as i64 as u64;
    let mut rng = super::Rng::new(
        seed ^ key(point.x).wrapping_mul(0x9e37_79b9_7f4a_7c15)
            ^ key(point.y).wrapping_mul(0xc2b2_ae3d_27d4_eb4f),
    );
    rng.next_u64();
    let u1 = 1.0 - rng.uniform(); // in (0, 1]: the logarithm stays finite
    let u2 = rng.uniform();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The `mount` scene: the mountain with the camera, light, materials and four glass
/// spheres of the course's `mount_*` files.
pub fn mount_scene(level: u32, seed: u64, env: Option<&str>) -> String {
    let m = mountain(level, seed);
    let mut w = P3fWriter::new(&Header {
        comment: &format!(
            "Fractal mountain of {} triangles after Eric Haines' SPD 'mount',\n\
             made by: p3trace gen mount --level {level} --seed {seed}",
            m.triangles.len()
        ),
        background: DVec3::new(0.078, 0.361, 0.753),
        env,
        camera: Camera {
            from: DVec3::new(-1.6, 1.6, 1.7),
            at: DVec3::ZERO,
            up: DVec3::Z,
            angle: 45.0,
            resolution: (512, 512),
            aperture: 0.0,
            focal: 1.0,
        },
    });
    w.directive("l", &[-100.0, -100.0, 100.0, 1.0, 1.0, 1.0]);
    w.line("# glass");
    w.finish(&Finish {
        diffuse: DVec3::ONE,
        kd: 0.1,
        specular: DVec3::ONE,
        ks: 0.1,
        shine: 101.148,
        transmittance: 1.0,
        ior: 1.6,
    });
    for (centre, radius) in [
        ([-0.8, 0.8, 1.20821], 0.17),
        ([-0.661196, 0.661196, 0.930598], 0.169),
        ([-0.749194, 0.98961, 0.930598], 0.168),
        ([-0.98961, 0.749194, 0.930598], 0.167),
    ] {
        w.sphere(DVec3::from_array(centre), radius);
    }
    w.line("# rock");
    w.finish(&Finish {
        diffuse: DVec3::new(0.5, 0.45, 0.35),
        kd: 1.0,
        specular: DVec3::ONE,
        ks: 0.0,
        shine: 100.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    w.line(&format!("mesh {} {}", m.vertices.len(), m.triangles.len()));
    for v in &m.vertices {
        w.directive("", &v.to_array());
    }
    for t in &m.triangles {
        // P3F mesh indices start at 1.
        w.line(&format!("{} {} {}", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    w.into_text()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_two_times_four_to_the_level() {
        for (level, count) in [(0, 2), (1, 8), (5, 2048), (7, 32768)] {
            assert_eq!(triangle_count(level), count);
            let m = mountain(level, 1);
            assert_eq!(m.triangles.len(), count);
            assert_eq!(m.vertices.len(), m.side * m.side);
            assert!(m.vertices.iter().all(|v| v.z.is_finite()));
        }
    }

    #[test]
    fn triangles_face_up_and_tile_the_square() {
        let m = mountain(4, 3);
        let mut area = 0.0;
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.vertices[i as usize].truncate());
            let signed = (b - a).perp_dot(c - a) / 2.0;
            assert!(
                signed > 0.0,
                "triangle {t:?} is not counter-clockwise from above"
            );
            area += signed;
        }
        assert!((area - 4.0).abs() < 1e-9, "area {area}");
    }

    #[test]
    fn gaussian_has_unit_spread() {
        let n = 20_000;
        let samples: Vec<f64> = (0..n)
            .map(|i| gaussian(5, DVec2::new(i as f64 / 1024.0, 0.25)))
            .collect();
        let mean = samples.iter().sum::<f64>() / n as f64;
        let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "mean {mean}");
        assert!((var - 1.0).abs() < 0.05, "variance {var}");
    }
}
