//! Whitted shading exactly as P3F.md section 4: Blinn-Phong with `Katt`, hard shadows,
//! mirror reflection, refraction with Fresnel (or Schlick), total internal reflection,
//! and a clamp of every returned colour.

use glam::Vec3;

use super::skybox::Skybox;
use crate::accel::Tracer;
use crate::ray::{Hit, Ray};
use crate::scene::{Light, Material, Scene};

/// Offset of secondary ray origins along the normal against self-intersection, in scene
/// units (the course's value; the course scenes span a few units).
pub const EPS: f32 = 1e-4;

/// Point samples standing for area lights: an n x n grid over the rectangle (P3F.md 6.3).
pub const AREA_LIGHT_GRID: u32 = 4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadeOptions {
    /// Rays at this depth return their local colour only (primary rays have depth 1).
    pub max_depth: u32,
    /// Schlick's approximation instead of the exact Fresnel equations.
    pub schlick: bool,
}

impl Default for ShadeOptions {
    fn default() -> Self {
        ShadeOptions {
            max_depth: 6,
            schlick: false,
        }
    }
}

/// A point that light comes from, with its share of its light's colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    pub position: Vec3,
    pub colour: Vec3,
}

/// The point samples of every light of a scene: one per point light, a grid per area light.
pub fn light_samples(lights: &[Light]) -> Vec<LightSample> {
    let mut samples = Vec::new();
    for light in lights {
        match *light {
            Light::Point { position, colour } => samples.push(LightSample { position, colour }),
            Light::Area {
                centre,
                target,
                width,
                height,
                colour,
            } => {
                let (across, up) = area_light_axes(target - centre);
                let n = AREA_LIGHT_GRID;
                let share = colour / (n * n) as f32;
                for i in 0..n {
                    for j in 0..n {
                        let s = (i as f32 + 0.5) / n as f32 - 0.5;
                        let t = (j as f32 + 0.5) / n as f32 - 0.5;
                        samples.push(LightSample {
                            position: centre + across * (s * width) + up * (t * height),
                            colour: share,
                        });
                    }
                }
            }
        }
    }
    samples
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

/// Everything a trace needs that stays fixed during a render.
pub struct Shader<'a> {
    pub scene: &'a Scene,
    pub tracer: &'a Tracer<'a>,
    pub skybox: Option<&'a Skybox>,
    pub lights: Vec<LightSample>,
    /// `1 / (1.25 * number of lights in the file)`, the weight of the specular highlight.
    pub katt: f32,
    pub options: ShadeOptions,
}

impl<'a> Shader<'a> {
    pub fn new(
        scene: &'a Scene,
        tracer: &'a Tracer<'a>,
        skybox: Option<&'a Skybox>,
        options: ShadeOptions,
    ) -> Self {
        let light_count = scene.lights.len().max(1) as f32;
        Shader {
            scene,
            tracer,
            skybox,
            lights: light_samples(&scene.lights),
            katt: 1.0 / (1.25 * light_count),
            options,
        }
    }

    /// The colour seen along `ray`, which travels in a medium of index `ior_here`.
    /// `rays` counts every ray traced, this one included.
    pub fn trace(&self, ray: &Ray, depth: u32, ior_here: f32, rays: &mut u64) -> Vec3 {
        *rays += 1;
        let hit = self.tracer.closest(ray, 0.0, f32::INFINITY);
        let hit = hit.map(|h| (h, self.surface(ray, &h)));
        self.shade(
            ray,
            hit,
            depth,
            ior_here,
            rays,
            &mut |shadow, distance, _| self.tracer.occluded(shadow, 0.0, distance),
        )
    }

    /// The colours seen along up to eight primary rays (lanes set in `active`): the same
    /// colours as [`Shader::trace`] gives each, with the primary rays and the first shadow
    /// rays to each light traced as packets. `visible` is scratch space, one byte per
    /// light sample.
    ///
    /// Reflected and transmitted rays go one by one. Tried: recording the rays each
    /// lane's shading spawns, tracing them as packets and shading again with the answers
    /// (identical images), which cost 9% more instructions on the dragon (callgrind,
    /// 2026-11-23): those rays diverge, and the second shading pass costs more than the
    /// packets save.
    pub fn trace_packet(
        &self,
        packet: &[Ray; 8],
        active: u8,
        visible: &mut [u8],
        rays: &mut u64,
    ) -> [Vec3; 8] {
        *rays += u64::from(active.count_ones());
        let hits = self.tracer.closest_packet(packet, active, f32::INFINITY);
        // Shadow rays of every lane to light `i`, as one packet; bit k of `visible[i]`
        // says whether lane k sees it.
        let surfaces: [Option<Surface>; 8] =
            std::array::from_fn(|k| hits[k].map(|hit| self.surface(&packet[k], &hit)));
        for (light, visible) in self.lights.iter().zip(visible.iter_mut()) {
            let mut shadows = [Ray::new(Vec3::ZERO, Vec3::Z); 8];
            let mut distances = [0.0; 8];
            let mut lanes = 0u8;
            for k in 0..8 {
                let Some(surface) = surfaces[k] else {
                    continue;
                };
                if let Some((ray, distance)) =
                    shadow_ray(surface.p, surface.nf, light, packet[k].time)
                {
                    (shadows[k], distances[k]) = (ray, distance);
                    lanes |= 1 << k;
                }
            }
            let blocked = self.tracer.occluded_packet(&shadows, &distances, lanes);
            *visible = lanes & !blocked;
        }
        std::array::from_fn(|k| {
            if active & (1 << k) == 0 {
                return Vec3::ZERO;
            }
            let hit = hits[k].zip(surfaces[k]);
            self.shade(&packet[k], hit, 1, 1.0, rays, &mut |_, _, light| {
                visible[light] & (1 << k) == 0
            })
        })
    }

    /// The colour at `hit` and its surface (or the background when there is none) seen
    /// along `ray`. `occluded(shadow_ray, distance, light_index)` answers the shadow
    /// queries of this hit; deeper rays are traced one by one.
    fn shade(
        &self,
        ray: &Ray,
        hit: Option<(Hit, Surface)>,
        depth: u32,
        ior_here: f32,
        rays: &mut u64,
        occluded: &mut dyn FnMut(&Ray, f32, usize) -> bool,
    ) -> Vec3 {
        let Some((hit, Surface { p, nf, inside })) = hit else {
            return self.background(ray.dir);
        };
        let material = &self.scene.materials[self.tracer.geometry.material(hit.prim) as usize];

        let mut colour = self.local(ray, p, nf, material, rays, occluded);
        if depth >= self.options.max_depth {
            return colour.clamp(Vec3::ZERO, Vec3::ONE);
        }
        let reflect_ray = || Ray {
            origin: p + EPS * nf,
            dir: (ray.dir - 2.0 * ray.dir.dot(nf) * nf).normalize(),
            time: ray.time,
        };
        if material.transmittance > 0.0 {
            let ior_next = if inside { 1.0 } else { material.ior };
            let eta = ior_here / ior_next;
            let cos_i = -ray.dir.dot(nf);
            let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
            if sin2_t > 1.0 {
                // Total internal reflection: Kr = 1 and no transmitted ray.
                colour += material.specular * self.trace(&reflect_ray(), depth + 1, ior_here, rays);
            } else {
                let cos_t = (1.0 - sin2_t).sqrt();
                let kr = if self.options.schlick {
                    schlick(ior_here, ior_next, cos_i, cos_t)
                } else {
                    fresnel(ior_here, ior_next, cos_i, cos_t)
                };
                let transmitted = Ray {
                    origin: p - EPS * nf,
                    dir: (eta * ray.dir + (eta * cos_i - cos_t) * nf).normalize(),
                    time: ray.time,
                };
                if kr > 0.0 {
                    colour += kr
                        * material.specular
                        * self.trace(&reflect_ray(), depth + 1, ior_here, rays);
                }
                if kr < 1.0 {
                    colour += (1.0 - kr)
                        * material.diffuse
                        * self.trace(&transmitted, depth + 1, ior_next, rays);
                }
            }
        } else if material.ks > 0.0 {
            colour += material.ks
                * material.specular
                * self.trace(&reflect_ray(), depth + 1, ior_here, rays);
        }
        colour.clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// The hit point and the normal facing the ray.
    fn surface(&self, ray: &Ray, hit: &Hit) -> Surface {
        let p = ray.at(hit.t);
        let normal = self
            .tracer
            .geometry
            .normal(hit.prim, p, hit.u, hit.v, ray.time);
        let inside = ray.dir.dot(normal) > 0.0;
        let nf = if inside { -normal } else { normal };
        Surface { p, nf, inside }
    }

    /// Blinn-Phong over the lights that face the surface and are not shadowed.
    fn local(
        &self,
        ray: &Ray,
        p: Vec3,
        nf: Vec3,
        m: &Material,
        rays: &mut u64,
        occluded: &mut dyn FnMut(&Ray, f32, usize) -> bool,
    ) -> Vec3 {
        let mut colour = Vec3::ZERO;
        for (index, light) in self.lights.iter().enumerate() {
            let Some((shadow, distance)) = shadow_ray(p, nf, light, ray.time) else {
                continue;
            };
            *rays += 1;
            if occluded(&shadow, distance, index) {
                continue;
            }
            let l = shadow.dir;
            let diffuse = m.diffuse * m.kd * nf.dot(l).max(0.0);
            let h = (l - ray.dir).normalize();
            let specular = self.katt * m.specular * m.ks * nf.dot(h).max(0.0).powf(m.shine);
            colour += light.colour * (diffuse + specular);
        }
        colour
    }

    fn background(&self, dir: Vec3) -> Vec3 {
        match self.skybox {
            Some(sky) => sky.lookup(dir),
            None => self.scene.background,
        }
    }
}

/// Where a ray met a surface.
#[derive(Clone, Copy, Debug)]
struct Surface {
    p: Vec3,
    /// The unit normal turned to face the ray.
    nf: Vec3,
    /// The ray arrived from inside the surface.
    inside: bool,
}

/// The shadow ray from the hit point `p` (normal `nf` facing the viewer) to `light`, and
/// the light's distance along it; `None` when the light is behind the surface.
fn shadow_ray(p: Vec3, nf: Vec3, light: &LightSample, time: f32) -> Option<(Ray, f32)> {
    if nf.dot(light.position - p) <= 0.0 {
        return None;
    }
    let origin = p + EPS * nf;
    let to_light = light.position - origin;
    let distance = to_light.length();
    let dir = to_light / distance;
    Some((Ray { origin, dir, time }, distance))
}

/// Reflectance from the exact Fresnel equations: the mean of the two polarisations.
pub fn fresnel(n1: f32, n2: f32, cos_i: f32, cos_t: f32) -> f32 {
    let r_perp = ((n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)).powi(2);
    let r_par = ((n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)).powi(2);
    (r_perp + r_par) / 2.0
}

/// Schlick's approximation, with the cosine on the side of the less dense medium.
pub fn schlick(n1: f32, n2: f32, cos_i: f32, cos_t: f32) -> f32 {
    let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
    let c = if n1 <= n2 { cos_i } else { cos_t };
    r0 + (1.0 - r0) * (1.0 - c).powi(5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_limits() {
        // Normal incidence: ((n1 - n2) / (n1 + n2))^2 = 0.04 for glass.
        assert!((fresnel(1.0, 1.5, 1.0, 1.0) - 0.04).abs() < 1e-6);
        assert!((schlick(1.0, 1.5, 1.0, 1.0) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything.
        assert!((fresnel(1.0, 1.5, 0.0, 0.745).abs() - 1.0).abs() < 1e-6);
        assert!((schlick(1.0, 1.5, 0.0, 0.745) - 1.0).abs() < 1e-6);
        // Same medium: nothing is reflected.
        assert!(fresnel(1.3, 1.3, 0.6, 0.6).abs() < 1e-7);
    }

    #[test]
    fn schlick_is_close_to_fresnel() {
        for k in 0..=20 {
            let cos_i = k as f32 / 20.0;
            let eta = 1.0 / 1.5;
            let cos_t = (1.0 - eta * eta * (1.0 - cos_i * cos_i)).sqrt();
            let (f, s) = (
                fresnel(1.0, 1.5, cos_i, cos_t),
                schlick(1.0, 1.5, cos_i, cos_t),
            );
            assert!(
                (f - s).abs() < 0.05,
                "cos_i {cos_i}: fresnel {f}, schlick {s}"
            );
        }
    }

    /// Traces one ray from `origin` inside a glass sphere of radius 1 (ior 1.5, `Kd` 0,
    /// white `Cs`, no lights) with `max_depth` 2; returns its colour and the rays taken.
    fn trace_inside_glass(origin: Vec3, dir: Vec3) -> (Vec3, u64) {
        let text = "bclr 0.2 0.4 0.6\nf 1 1 1 0 1 1 1 0 1 1 1.5\ns 0 0 0 1";
        let scene = crate::scene::p3f::parse_text(text).unwrap();
        let tracer = Tracer::new(&scene.geometry, crate::accel::Accel::None);
        let options = ShadeOptions {
            max_depth: 2,
            schlick: false,
        };
        let shader = Shader::new(&scene, &tracer, None, options);
        let mut rays = 0;
        let colour = shader.trace(&Ray::new(origin, dir), 1, 1.5, &mut rays);
        (colour, rays)
    }

    #[test]
    fn refraction_spawns_a_reflected_and_a_transmitted_ray() {
        let (colour, rays) = trace_inside_glass(Vec3::ZERO, Vec3::X);
        assert_eq!(rays, 3);
        // The transmitted ray sees the background with weight 1 - Kr = 0.96 (normal
        // incidence); the reflected one stays inside and, at the depth limit, is black.
        let expected = 0.96 * Vec3::new(0.2, 0.4, 0.6);
        assert!((colour - expected).length() < 1e-6, "{colour}");
    }

    #[test]
    fn total_internal_reflection_spawns_one_ray_and_no_nan() {
        // From (0, 0.9, 0) along +x the ray meets the surface at about 64 degrees, beyond
        // the critical angle of 41.8 degrees (the course code had no guard here).
        let (colour, rays) = trace_inside_glass(Vec3::new(0.0, 0.9, 0.0), Vec3::X);
        assert_eq!(rays, 2);
        // The reflected ray stays inside and, at the depth limit, is black.
        assert_eq!(colour, Vec3::ZERO);
    }

    #[test]
    fn area_light_grid_covers_the_rectangle_with_the_full_colour() {
        let samples = light_samples(&[Light::Area {
            centre: Vec3::new(0., 5., 0.),
            target: Vec3::ZERO,
            width: 2.0,
            height: 1.0,
            colour: Vec3::ONE,
        }]);
        assert_eq!(samples.len(), (AREA_LIGHT_GRID * AREA_LIGHT_GRID) as usize);
        let total: Vec3 = samples.iter().map(|s| s.colour).sum();
        assert!((total - Vec3::ONE).length() < 1e-6);
        for s in &samples {
            assert!((s.position.y - 5.0).abs() < 1e-6);
            assert!(s.position.x.abs() < 1.0 && s.position.z.abs() < 0.5);
        }
    }
}
