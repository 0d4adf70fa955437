//! The course's "random scene" (P3F.md section 8): a grid of small diffuse, metal and
//! glass spheres around three large ones, on a ground sphere.
//!
//! It is P3F text like every generator's: `p3trace render random` reads the text that
//! `gen random` writes, and its `--seed` lays out the scene as well as seeding the samples.

use glam::DVec3;

use super::{Camera, Finish, Header, P3fWriter, Rng};

/// The large metal sphere: small spheres keep 0.9 away from it.
const CLEAR_OF: DVec3 = DVec3::new(4.0, 0.2, 0.0);

const GLASS: Finish = Finish {
    diffuse: DVec3::ONE,
    kd: 0.0,
    specular: DVec3::ONE,
    ks: 0.7,
    shine: 20.0,
    transmittance: 1.0,
    ior: 1.5,
};

/// What a small sphere is made of; the draw follows section 8's probabilities.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Diffuse,
    Metal,
    Glass,
}

/// The random scene for `seed`, as P3F text; section 8 gives it no skybox (`env: None`).
pub fn random_scene(seed: u64, env: Option<&str>) -> String {
    let mut w = P3fWriter::new(&Header {
        comment: &format!(
            "The course's random scene (P3F.md section 8),\n\
             made by: p3trace gen random --seed {seed}"
        ),
        background: DVec3::new(0.5, 0.7, 1.0),
        env,
        camera: Camera {
            from: DVec3::new(-5.312192, 4.456562, 11.963158),
            at: DVec3::ZERO,
            up: DVec3::Y,
            angle: 45.0,
            resolution: (800, 600),
            aperture: 0.0,
            focal: 1.0,
        },
    });
    for light in [[7.0, 10.0, -5.0], [-7.0, 10.0, -5.0], [0.0, 10.0, 7.0]] {
        w.light(DVec3::from_array(light));
    }
    w.line("# ground");
    w.finish(&Finish {
        diffuse: DVec3::splat(0.5),
        kd: 1.0,
        specular: DVec3::ONE,
        ks: 0.0,
        shine: 10.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    w.sphere(DVec3::new(0.0, -1000.0, 0.0), 1000.0);

    let mut rng = Rng::new(seed);
    for (centre, kind) in small_spheres(&mut rng) {
        let finish = match kind {
            Kind::Diffuse => Finish {
                diffuse: DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()),
                kd: 1.0,
                specular: DVec3::ONE,
                ks: 0.0,
                shine: 10.0,
                transmittance: 0.0,
                ior: 1.0,
            },
            Kind::Metal => Finish {
                diffuse: DVec3::ZERO,
                kd: 0.0,
                specular: DVec3::new(
                    0.5 + 0.5 * rng.uniform(),
                    0.5 + 0.5 * rng.uniform(),
                    0.5 + 0.5 * rng.uniform(),
                ),
                ks: 1.0,
                shine: 220.0,
                transmittance: 0.0,
                ior: 1.0,
            },
            Kind::Glass => GLASS,
        };
        w.finish(&finish);
        w.sphere(centre, 0.2);
    }

    w.line("# the three large spheres: glass, diffuse brown, metal");
    w.finish(&GLASS);
    w.sphere(DVec3::new(0.0, 1.0, 0.0), 1.0);
    let brown = DVec3::new(0.4, 0.2, 0.1);
    w.finish(&Finish {
        diffuse: brown,
        kd: 0.9,
        specular: DVec3::ONE,
        ks: 0.1,
        shine: 10.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    w.sphere(DVec3::new(-4.0, 1.0, 0.0), 1.0);
    w.finish(&Finish {
        diffuse: brown,
        kd: 0.0,
        specular: DVec3::new(0.7, 0.6, 0.5),
        ks: 1.0,
        shine: 220.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    w.sphere(DVec3::new(4.0, 1.0, 0.0), 1.0);
    w.into_text()
}

/// The small spheres: for `a, b` in `-5..4` (4 excluded), a centre jittered in the cell,
/// skipped within 0.9 of the metal sphere, and its kind.
fn small_spheres(rng: &mut Rng) -> Vec<(DVec3, Kind)> {
    let cells = (-5..4).flat_map(|a| (-5..4).map(move |b| (a, b)));
    cells
        .filter_map(|(a, b)| {
            let choose = rng.uniform();
            let centre = DVec3::new(
                a as f64 + 0.9 * rng.uniform(),
                0.2,
                b as f64 + 0.9 * rng.uniform(),
            );
            if centre.distance(CLEAR_OF) <= 0.9 {
                return None;
            }
            let kind = if choose < 0.4 {
                Kind::Diffuse
            } else if choose < 0.9 {
                Kind::Metal
            } else {
                Kind::Glass
            };
            Some((centre, kind))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_spheres_stay_in_their_cells_and_clear_of_the_metal_sphere() {
        let mut counts = [0usize; 3];
        for seed in 0..50 {
            let spheres = small_spheres(&mut Rng::new(seed));
            assert!(spheres.len() <= 81);
            for (c, kind) in spheres {
                assert!(c.distance(CLEAR_OF) > 0.9);
                assert!((-5.0..3.9).contains(&c.x) && (-5.0..3.9).contains(&c.z));
                counts[kind as usize] += 1;
            }
        }
        let total: usize = counts.iter().sum();
        let share = counts.map(|c| c as f64 / total as f64);
        assert!((share[0] - 0.4).abs() < 0.04, "{share:?}");
        assert!((share[1] - 0.5).abs() < 0.04, "{share:?}");
        assert!((share[2] - 0.1).abs() < 0.03, "{share:?}");
    }
}
