//! The project's own scenes, made in code: Eric Haines' SPD sphereflake ("balls") and
//! fractal mountain ("mount") as the course used them, the course's random scene
//! (P3F.md section 8), a dragon scene around a PLY model, and a procedural skybox.
//!
//! Every generator writes P3F text, so what it makes is exactly what `p3trace render`
//! reads back, and the files in `scenes/` can be checked against their generator.
//!
//! Generators sit above [`crate::scene`] and [`crate::render`], whose formats they write;
//! nothing in the library below them depends on them.

pub mod dragon;
pub mod mountain;
pub mod random;
pub mod skybox;
pub mod sphereflake;

use std::fmt::Write;

use glam::DVec3;

/// Builds P3F text one directive per line.
#[derive(Default)]
pub struct P3fWriter {
    text: String,
}

/// The camera block of a generated scene.
pub struct Camera {
    pub from: DVec3,
    pub at: DVec3,
    pub up: DVec3,
    pub angle: f64,
    pub resolution: (u32, u32),
    pub aperture: f64,
    pub focal: f64,
}

/// The header shared by every generated scene: accelerator, samples, background, skybox
/// and camera.
pub struct Header<'a> {
    pub comment: &'a str,
    pub background: DVec3,
    /// The skybox folder for `env`, relative to the scene file; `None` for no `env` line.
    pub env: Option<&'a str>,
    pub camera: Camera,
}

/// A material as the `f` directive spells it (P3F.md section 5).
#[derive(Clone, Copy)]
pub struct Finish {
    pub diffuse: DVec3,
    pub kd: f64,
    pub specular: DVec3,
    pub ks: f64,
    pub shine: f64,
    pub transmittance: f64,
    pub ior: f64,
}

impl P3fWriter {
    pub fn new(header: &Header) -> Self {
        let mut w = P3fWriter::default();
        for line in header.comment.lines() {
            w.line(&format!("# {line}"));
        }
        // Generated scenes leave the accelerator to the command line.
        w.line("spp 0");
        w.directive("bclr", &header.background.to_array());
        if let Some(env) = header.env {
            w.line(&format!("env {env}"));
        }
        let c = &header.camera;
        w.line("v");
        w.directive("from", &c.from.to_array());
        w.directive("at", &c.at.to_array());
        w.directive("up", &c.up.to_array());
        w.directive("angle", &[c.angle]);
        w.line("hither 0.01");
        w.line(&format!("resolution {} {}", c.resolution.0, c.resolution.1));
        w.directive("aperture", &[c.aperture]);
        w.directive("focal", &[c.focal]);
        w
    }

    pub fn line(&mut self, line: &str) {
        self.text.push_str(line);
        self.text.push('\n');
    }

    /// A keyword followed by numbers; an empty keyword writes just the numbers.
    pub fn directive(&mut self, keyword: &str, values: &[f64]) {
        self.text.push_str(keyword);
        for (i, &v) in values.iter().enumerate() {
            if i > 0 || !keyword.is_empty() {
                self.text.push(' ');
            }
            push_number(&mut self.text, v);
        }
        self.text.push('\n');
    }

    /// A white point light.
    pub fn light(&mut self, position: DVec3) {
        let p = position.to_array();
        self.directive("l", &[p[0], p[1], p[2], 1.0, 1.0, 1.0]);
    }

    pub fn finish(&mut self, f: &Finish) {
        let (d, s) = (f.diffuse, f.specular);
        self.directive(
            "f",
            &[
                d.x,
                d.y,
                d.z,
                f.kd,
                s.x,
                s.y,
                s.z,
                f.ks,
                f.shine,
                f.transmittance,
                f.ior,
            ],
        );
    }

    pub fn sphere(&mut self, centre: DVec3, radius: f64) {
        self.directive("s", &[centre.x, centre.y, centre.z, radius]);
    }

    pub fn triangle(&mut self, vertices: [DVec3; 3]) {
        self.line("p 3");
        for v in vertices {
            self.directive("", &v.to_array());
        }
    }

    pub fn into_text(self) -> String {
        self.text
    }
}

/// A number as short as it can be while still reading back as the same `f32` (the
/// precision the renderer keeps). Values within 1e-9 of zero are written as 0.
fn push_number(out: &mut String, value: f64) {
    let value = if value.abs() < 1e-9 { 0.0 } else { value };
    write!(out, "{}", value as f32).expect("writing to a String cannot fail");
}

/// A small seeded generator (SplitMix64): the generators' random choices are reproducible
/// from their seed on every platform.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_read_back_exactly_as_f32() {
        let mut s = String::new();
        for v in [0.5, 1.0 / 3.0, -2.0, 1.1102e-16, 123456.789] {
            s.clear();
            push_number(&mut s, v);
            let back: f32 = s.parse().unwrap();
            let expected = if v.abs() < 1e-9 { 0.0 } else { v as f32 };
            assert_eq!(back, expected, "{v} written as {s}");
        }
        s.clear();
        push_number(&mut s, 0.5);
        assert_eq!(s, "0.5");
    }

    #[test]
    fn rng_is_uniform_in_unit_interval_and_seeded() {
        let mut a = Rng::new(7);
        let draws: Vec<f64> = (0..10_000).map(|_| a.uniform()).collect();
        assert!(draws.iter().all(|&x| (0.0..1.0).contains(&x)));
        let mean = draws.iter().sum::<f64>() / draws.len() as f64;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
        let mut b = Rng::new(7);
        assert_eq!(b.uniform(), draws[0]);
        assert_ne!(Rng::new(8).uniform(), draws[0]);
    }
}
