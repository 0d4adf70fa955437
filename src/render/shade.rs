//! Whitted shading exactly as P3F.md section 4: Blinn-Phong with `Katt`, shadows, mirror
//! reflection, refraction with Fresnel (or Schlick), total internal reflection, and a
//! clamp of every returned colour; and fuzzy reflections (P3F.md 6.4). The `course`
//! [`Profile`] is section 11's model of the course's own renderer instead. What light
//! each light sends a hit, from where, is for [`super::light`] to say.
//!
//! A hit is shaded in two steps, so that the scalar recursion ([`Shader::trace`]) and the
//! stream renderer (`stream/`) compute the same colours: Blinn-Phong over the lights
//! given each one's shadow ray and answer ([`Phong::light`], which the stream renderer
//! computes for eight hits at a time with its twin [`Phong8::light`]), and `spawn`, which
//! hands on the reflected ray and then the transmitted one with their weights (their
//! directions and weights from [`Bounce`], eight hits at a time [`Bounce8`]). Spawned
//! rays start from the hit recomputed on the surface, offset by its error bound
//! ([`crate::intersect::SurfacePoint`]); the `course` profile offsets by [`EPS`] instead.
//! Fuzzy reflection tilts every mirror direction, glass's Fresnel reflection and total
//! internal reflection included; a roughness of 0 draws no random number, so its image
//! is the mirror one byte for byte.

use glam::Vec3;

use super::light::{emitters, Emitter, Receiver, DEFAULT_LIGHT_GRID};
use super::sampler::{dim, Sample, SampleGrid, SampleRng};
use super::skybox::{Skybox, Texel};
use crate::accel::count::{Count, RayCounts, RayKind, Work};
use crate::accel::{InsideAnswers, Tracer};
use crate::intersect::{spawn_origin, Hits8, Rays8, Roots, SurfacePoint, SurfacePoint8};
use crate::prim::PrimKind;
use crate::ray::{Hit, Ray};
use crate::scene::{Frame, Material, Scene};
use crate::simd::{F32x8, Mask8, Vec3x8};

/// The `course` profile's offset of secondary ray origins along the normal against
/// self-intersection, in scene units (the course scenes span a few units). The standard
/// profile offsets by each hit point's error bound instead ([`SurfacePoint`]), which
/// follows the scene's scale and position (P3F.md 4).
pub const EPS: f32 = 1e-4;

/// Which model of shading: P3F.md section 4, or the course renderer's of section 11.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Profile {
    /// P3F.md section 4, with a maximum depth of 6.
    #[default]
    Standard,
    /// P3F.md section 11, which reproduces the course's reference images: the background
    /// seen by a ray of depth d that misses is dimmed by `min(1, 1 / (0.7 (d - 1)))`,
    /// the maximum depth is 8, and spheres are tested with the textbook quadratic.
    Course,
}

impl Profile {
    /// The depth at which rays stop spawning others, unless the options say otherwise.
    pub fn max_depth(self) -> u32 {
        match self {
            Profile::Standard => 6,
            Profile::Course => 8,
        }
    }

    /// The frame to read a scene in for this profile: the camera's, where precision does
    /// not depend on where the scene stands, or for the course's model the file's own,
    /// whose rounding its images carry (reading balls_high relative to the camera takes
    /// the course profile from 99.7% to 96.2% of its reference's pixels).
    pub fn frame(self) -> Frame {
        match self {
            Profile::Standard => Frame::Camera,
            Profile::Course => Frame::File,
        }
    }

    /// How spheres are tested: the course's renderer solved the textbook quadratic in
    /// single precision, whose error on the smallest spheres its images show.
    pub fn roots(self) -> Roots {
        match self {
            Profile::Standard => Roots::Precise,
            Profile::Course => Roots::Textbook,
        }
    }

    /// The factor of the background (colour or skybox) seen by a ray of `depth` that
    /// hits nothing.
    pub fn background_factor(self, depth: u32) -> f32 {
        match self {
            Profile::Course if depth > 2 => 1.0 / (0.7 * (depth - 1) as f32),
            _ => 1.0,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadeOptions {
    /// The shading model; [`ShadeOptions::with_profile`] also takes its maximum depth.
    pub profile: Profile,
    /// Rays at this depth return their local colour only (primary rays have depth 1).
    pub max_depth: u32,
    /// Schlick's approximation instead of the exact Fresnel equations.
    pub schlick: bool,
    /// Soft shadows: each point light becomes a square of this side, perpendicular to
    /// the camera's up vector. `None`: point lights cast hard shadows.
    pub soft_light_size: Option<f32>,
    /// Without antialiasing, a light with an area becomes the points of this grid.
    pub light_grid: SampleGrid,
    /// Fuzzy reflections: how far a reflected direction strays (0 is a mirror).
    pub roughness: f32,
}

impl Default for ShadeOptions {
    fn default() -> Self {
        ShadeOptions {
            profile: Profile::Standard,
            max_depth: Profile::Standard.max_depth(),
            schlick: false,
            soft_light_size: None,
            light_grid: DEFAULT_LIGHT_GRID,
            roughness: 0.0,
        }
    }
}

impl ShadeOptions {
    /// These options with `profile` and its maximum depth.
    pub fn with_profile(self, profile: Profile) -> Self {
        ShadeOptions {
            profile,
            max_depth: profile.max_depth(),
            ..self
        }
    }
}

/// Everything a trace needs that stays fixed during a render.
pub struct Shader<'a> {
    pub scene: &'a Scene,
    pub tracer: &'a Tracer<'a>,
    pub skybox: Option<&'a Skybox>,
    pub lights: Vec<Emitter>,
    /// Each material's Blinn-Phong terms, by material index.
    pub phong: Vec<Phong>,
    pub options: ShadeOptions,
}

impl<'a> Shader<'a> {
    /// A shader for `scene`; `jittered` says whether pixels are sampled on a jittered
    /// grid, which decides how lights with an area are sampled.
    pub fn new(
        scene: &'a Scene,
        tracer: &'a Tracer<'a>,
        skybox: Option<&'a Skybox>,
        options: ShadeOptions,
        jittered: bool,
    ) -> Self {
        // Katt, the weight of the specular highlight: 1 / (1.25 * the file's lights).
        let katt = 1.0 / (1.25 * scene.lights.len().max(1) as f32);
        Shader {
            scene,
            tracer,
            skybox,
            lights: emitters(
                &scene.lights,
                scene.camera.up,
                options.soft_light_size,
                options.light_grid,
                jittered,
            ),
            phong: scene
                .materials
                .iter()
                .map(|m| Phong::new(m, katt))
                .collect(),
            options,
        }
    }

    /// The colour seen along `ray`, a ray of `kind` which travels in a medium of index
    /// `ior_here` and draws its random numbers from `sample`. `rays` counts every ray
    /// traced, this one included, and `work` takes their work, by kind.
    pub fn trace<C: Count>(
        &self,
        ray: &Ray,
        kind: RayKind,
        sample: &Sample,
        depth: u32,
        ior_here: f32,
        (rays, work): (&mut RayCounts, &mut Work<C>),
    ) -> Vec3 {
        rays.add(kind, 1);
        let mut own = C::default();
        let hit = self
            .tracer
            .closest_counting(ray, 0.0, f32::INFINITY, &mut own);
        work.add(kind, own);
        let Some(hit) = hit else {
            return self.background(ray.dir, depth);
        };
        let surface = self.surface(ray, &hit);
        // Each light's shadow ray, traced on the spot (a closure the lights' loop inlines).
        let shadow_of = &mut |light| {
            let shadow = self.shadow_ray(light, sample, &surface, ray.time)?;
            let mut count = C::default();
            let blocked =
                self.tracer
                    .occluded_counting(&shadow.ray, 0.0, shadow.distance, &mut count);
            work.shadow += count;
            Some((shadow, blocked))
        };
        let material_index = self.tracer.geometry.material(hit.prim) as usize;
        let material = &self.scene.materials[material_index];
        let phong = &self.phong[material_index];
        let mut colour = self.local(ray, surface.nf, phong, rays, shadow_of);
        if depth >= self.options.max_depth {
            return colour.clamp(Vec3::ZERO, Vec3::ONE);
        }
        self.spawn(ray, sample, &surface, material, ior_here, |child| {
            let seen = self.trace(
                &child.ray,
                child.kind,
                &child.sample,
                depth + 1,
                child.ior,
                (rays, work),
            );
            colour += child.weight * seen;
        });
        colour.clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// Gives `emit` the rays a hit on `surface` spawns, arrived along `ray` in a medium of
    /// index `ior_here`: the reflected one, then the transmitted one, the order in which
    /// their colours add to the hit's. A callback rather than a returned pair, which cost
    /// the scalar path's tiles 2% more instructions on the dragon (callgrind).
    #[inline(always)]
    pub(super) fn spawn(
        &self,
        ray: &Ray,
        sample: &Sample,
        surface: &Surface,
        material: &Material,
        ior_here: f32,
        mut emit: impl FnMut(Spawned),
    ) {
        let Surface { nf, inside, .. } = *surface;
        let bounce = Bounce::new(
            ray.dir,
            nf,
            inside,
            ior_here,
            material,
            self.options.schlick,
        );
        if let Some((mirror, weight)) = bounce.reflected {
            let sample = sample.spawn(0);
            emit(Spawned {
                ray: Ray {
                    origin: surface.outward,
                    dir: self.fuzz(mirror, nf, sample.rng),
                    time: ray.time,
                },
                kind: RayKind::Reflection,
                sample,
                ior: ior_here,
                weight,
            });
        }
        if let Some((dir, weight, ior_next)) = bounce.transmitted {
            emit(Spawned {
                ray: Ray {
                    origin: surface.origin(-nf),
                    dir,
                    time: ray.time,
                },
                kind: RayKind::Refraction,
                sample: sample.spawn(1),
                ior: ior_next,
                weight,
            });
        }
    }

    /// The hit point and the normal facing the ray: the point recomputed on the surface
    /// with its error bound, or with the `course` profile the point along the ray.
    /// Inlined into the recursion, which the count made generic: out of line, the scalar
    /// render ran 0.5% more instructions (callgrind, dragon).
    #[inline(always)]
    pub(super) fn surface(&self, ray: &Ray, hit: &Hit) -> Surface {
        let mut surface = self.hit_point(ray, hit);
        surface.outward = surface.origin(surface.nf);
        surface
    }

    /// [`Shader::surface`] but for `outward`, left at the point. The stream renderer takes
    /// eight hits at a time ([`Shader::hit_points8`]).
    #[inline(always)]
    pub(super) fn hit_point(&self, ray: &Ray, hit: &Hit) -> Surface {
        let geometry = &self.tracer.geometry;
        let (p, normal, error) = match self.options.profile {
            Profile::Standard => {
                let SurfacePoint {
                    point,
                    error,
                    normal,
                } = geometry.surface_point(hit.prim, ray, hit.t, hit.u, hit.v);
                (point, normal, Some(error))
            }
            Profile::Course => {
                let p = ray.at(hit.t);
                let normal = geometry.normal(hit.prim, p, hit.u, hit.v, ray.time);
                (p, normal, None)
            }
        };
        let inside = ray.dir.dot(normal) > 0.0;
        let nf = if inside { -normal } else { normal };
        Surface {
            p,
            nf,
            inside,
            error,
            outward: p,
        }
    }

    /// [`Shader::hit_point`] for eight hits (lane `k`: `hits[k]` along `rays[k]`): the
    /// points, their error bounds (zero with the `course` profile, which has none) and the
    /// outward normals, eight at a time where the hits share a kind (`kind`,
    /// [`crate::prim::PrimId::shared_kind`]) with a twin.
    pub(super) fn hit_points8(
        &self,
        rays: &[Ray; 8],
        hits: &[Hit; 8],
        kind: Option<PrimKind>,
    ) -> SurfacePoint8 {
        let geometry = &self.tracer.geometry;
        match self.options.profile {
            Profile::Standard => {
                if let Some(kind) = kind {
                    let indices = hits.map(|h| h.prim.index());
                    let lanes = Hits8 {
                        t: hits.map(|h| h.t),
                        u: hits.map(|h| h.u),
                        v: hits.map(|h| h.v),
                    };
                    return geometry.surface_points8(kind, indices, rays, &lanes);
                }
                SurfacePoint8::from_lanes(std::array::from_fn(|k| {
                    let Hit { prim, t, u, v } = hits[k];
                    geometry.surface_point(prim, &rays[k], t, u, v)
                }))
            }
            Profile::Course => SurfacePoint8::from_lanes(std::array::from_fn(|k| {
                let (ray, hit) = (&rays[k], &hits[k]);
                let point = ray.at(hit.t);
                SurfacePoint {
                    point,
                    error: Vec3::ZERO,
                    normal: geometry.normal(hit.prim, point, hit.u, hit.v, ray.time),
                }
            })),
        }
    }

    /// [`Shader::hit_points8`] for the hits `answers` of the rays `rays` from inside
    /// primitives, on primitives of kind `kind` if they share one, given as lanes: without
    /// the rays' transposition where the profile and the kind have the twin.
    pub(super) fn inside_points8(
        &self,
        answers: &InsideAnswers,
        rays: &Rays8,
        kind: Option<PrimKind>,
    ) -> SurfacePoint8 {
        if let (Profile::Standard, Some(kind)) = (self.options.profile, kind) {
            let indices = answers.prim.map(|p| p.index());
            let geometry = &self.tracer.geometry;
            return geometry.surface_points_along8(kind, indices, rays, answers.t);
        }
        let hits = std::array::from_fn(|k| answers.hit(k));
        self.hit_points8(&std::array::from_fn(|k| rays.lane(k)), &hits, kind)
    }

    /// Whether every reflected direction is the mirror direction ([`Shader::fuzz`]).
    pub(super) fn reflects_as_mirrors(&self) -> bool {
        self.options.roughness == 0.0
    }

    /// A reflected direction: the `mirror` direction, or with roughness g > 0 the
    /// direction of `mirror + g q` for `q` uniform in the unit ball, unless that one
    /// points below the surface of normal `nf` (P3F.md 6.4).
    ///
    /// Inline in the spawning loops but for the random offset, whose call takes neither
    /// a direction nor a reference: what a call is handed by reference lives on the stack,
    /// written in narrow stores, and the spawning loops' ray and lineage, copied whole
    /// from there into the queue, would wait for those stores (no store forwarding).
    #[inline(always)]
    pub(super) fn fuzz(&self, mirror: Vec3, nf: Vec3, rng: SampleRng) -> Vec3 {
        if self.reflects_as_mirrors() {
            return mirror;
        }
        let dir = (mirror + self.fuzz_offset(rng)).normalize();
        if dir.dot(nf) > 0.0 {
            dir
        } else {
            mirror
        }
    }

    /// [`Shader::fuzz`]'s offset from the mirror direction, g q.
    #[inline(never)]
    fn fuzz_offset(&self, rng: SampleRng) -> Vec3 {
        self.options.roughness * rng.unit_ball(dim::FUZZ)
    }

    /// Blinn-Phong over the lights that face the surface (normal `nf` facing the ray) and
    /// are not shadowed: `shadow_of` gives each light's shadow ray ([`Shader::shadow_ray`])
    /// and whether it is blocked, traced on the spot. The stream renderer computes the
    /// same sum eight hits at a time ([`Phong8`]).
    fn local(
        &self,
        ray: &Ray,
        nf: Vec3,
        phong: &Phong,
        rays: &mut RayCounts,
        shadow_of: &mut impl FnMut(usize) -> Option<(ShadowRay, bool)>,
    ) -> Vec3 {
        let mut colour = Vec3::ZERO;
        for light in 0..self.lights.len() {
            let Some((shadow, blocked)) = shadow_of(light) else {
                continue;
            };
            rays.shadow += 1;
            if blocked {
                continue;
            }
            colour += phong.light(nf, ray.dir, shadow.ray.dir, shadow.colour);
        }
        colour
    }

    /// The shadow ray from `surface` to the point of light `index` that `sample` sees, at
    /// shutter `time`; `None` when the light is behind the surface.
    // Inlined into both paths: out of line, the scalar render ran 0.7% more instructions
    // than with the ray built inside the lights' loop (callgrind, balls_low).
    #[inline(always)]
    fn shadow_ray(
        &self,
        index: usize,
        sample: &Sample,
        surface: &Surface,
        time: f32,
    ) -> Option<ShadowRay> {
        let receiver = Receiver {
            point: surface.p,
            normal: surface.nf,
            origin: surface.outward,
        };
        let light = self.lights[index].sample(index, &receiver, sample)?;
        Some(ShadowRay {
            ray: Ray {
                origin: receiver.origin,
                dir: light.dir,
                time,
            },
            distance: light.distance,
            colour: light.colour,
        })
    }

    /// What a ray of `depth` along `dir` that hits nothing sees.
    pub(super) fn background(&self, dir: Vec3, depth: u32) -> Vec3 {
        match self.skybox {
            Some(sky) => self.sky_background(sky, sky.texel(dir), depth),
            None => self.scene.background * self.options.profile.background_factor(depth),
        }
    }

    /// [`Shader::background`] of a ray of `depth` that sees `texel` of the skybox `sky`.
    pub(super) fn sky_background(&self, sky: &Skybox, texel: Texel, depth: u32) -> Vec3 {
        sky.colour(texel) * self.options.profile.background_factor(depth)
    }
}

/// Where a ray met a surface.
#[derive(Clone, Copy, Debug)]
pub(super) struct Surface {
    pub p: Vec3,
    /// The unit normal turned to face the ray.
    pub nf: Vec3,
    /// The ray arrived from inside the surface.
    pub inside: bool,
    /// The bound of `p`'s error on each axis; `None` with the `course` profile, whose rays
    /// start [`EPS`] off the surface.
    pub error: Option<Vec3>,
    /// `origin(nf)`, where reflected and shadow rays start: one hit's shadow rays to
    /// every light and its reflected ray share it.
    pub outward: Vec3,
}

impl Surface {
    /// The origin of a ray spawned here that leaves on the side of `side`, `nf` or `-nf`.
    fn origin(&self, side: Vec3) -> Vec3 {
        match self.error {
            Some(error) => spawn_origin(self.p, error, side),
            None => self.p + EPS * side,
        }
    }
}

/// A ray spawned at a hit, and how its colour adds to the hit's.
#[derive(Clone, Copy, Debug)]
pub(super) struct Spawned {
    pub ray: Ray,
    pub kind: RayKind,
    pub sample: Sample,
    /// The index of the medium the ray travels in.
    pub ior: f32,
    /// The factor of the colour it brings back in its hit's colour.
    pub weight: Vec3,
}

/// A shadow ray from a hit point to a point of a light, and the light that arrives along
/// it when nothing is in the way.
#[derive(Clone, Copy, Debug)]
struct ShadowRay {
    pub ray: Ray,
    /// The light's distance along `ray`.
    pub distance: f32,
    pub colour: Vec3,
}

/// A material's Blinn-Phong terms (P3F.md 4.2), the products of its constants taken
/// once, in the order the formula multiplies them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    /// `Cd Kd`.
    pub diffuse: Vec3,
    /// `Katt Cs Ks`.
    pub specular: Vec3,
    pub shine: f32,
}

impl Phong {
    pub fn new(m: &Material, katt: f32) -> Self {
        Phong {
            diffuse: m.diffuse * m.kd,
            specular: katt * m.specular * m.ks,
            shine: m.shine,
        }
    }

    /// The light of `colour` arriving from the unit direction `l` that a surface of unit
    /// normal `nf` reflects back along a ray of direction `dir`.
    #[inline(always)]
    pub fn light(&self, nf: Vec3, dir: Vec3, l: Vec3, colour: Vec3) -> Vec3 {
        let diffuse = self.diffuse * positive(nf.dot(l));
        let h = (l - dir).normalize();
        let specular = self.specular * positive(nf.dot(h)).powf(self.shine);
        colour * (diffuse + specular)
    }
}

/// `x` where it is above zero, else zero (NaN included): `x.max(0.0)` as it compiles on
/// x86, written out so that [`Phong8`] can take the same rule.
#[inline(always)]
fn positive(x: f32) -> f32 {
    if x > 0.0 {
        x
    } else {
        0.0
    }
}

/// Eight hits' [`Phong`] terms, lane `k` from the `k`-th material.
#[derive(Clone, Copy, Debug)]
pub struct Phong8 {
    diffuse: Vec3x8,
    specular: Vec3x8,
    shine: F32x8,
    /// The lanes whose highlight needs its power: all but those with no specular term and
    /// an exponent in `[0, inf)`, whose `0 x^shine` is `0 x 0` for every `x` in `[0, 1]`.
    powered: Mask8,
}

impl Phong8 {
    /// The terms of `lanes`, splat when every lane has the same (most blocks of a mesh).
    #[inline]
    pub fn new(lanes: [&Phong; 8]) -> Self {
        let (diffuse, specular, shine) = if lanes.iter().all(|&p| std::ptr::eq(p, lanes[0])) {
            let p = lanes[0];
            (
                Vec3x8::splat(p.diffuse),
                Vec3x8::splat(p.specular),
                F32x8::splat(p.shine),
            )
        } else {
            (
                Vec3x8::from_lanes(lanes.map(|p| p.diffuse)),
                Vec3x8::from_lanes(lanes.map(|p| p.specular)),
                F32x8::from_array(lanes.map(|p| p.shine)),
            )
        };
        let zero = F32x8::ZERO;
        let dark = specular.x.eq(zero) & specular.y.eq(zero) & specular.z.eq(zero);
        let finite_power = shine.ge(zero) & shine.lt(F32x8::splat(f32::INFINITY));
        Phong8 {
            diffuse,
            specular,
            shine,
            powered: !(dark & finite_power),
        }
    }

    /// [`Phong::light`] lane by lane, bit for bit in the lanes of `lit`, the only ones
    /// whose power is taken (the others' value is meaningless), and of those only where
    /// it shows (where the specular term is not zero, or the base is above 1).
    #[inline(always)]
    pub fn light(&self, nf: Vec3x8, dir: Vec3x8, l: Vec3x8, colour: Vec3, lit: Mask8) -> Vec3x8 {
        let diffuse = self.diffuse.scale(nf.dot(l).max(F32x8::ZERO));
        let h = (l - dir).normalize();
        let base = nf.dot(h).max(F32x8::ZERO);
        let shows = self.powered | base.gt(F32x8::splat(1.0));
        let specular = self.specular.scale(base.powf(self.shine, lit & shows));
        Vec3x8::splat(colour) * (diffuse + specular)
    }
}

/// The rays a hit spawns, as directions and weights before their origins and fuzz: the
/// mirror direction of a reflective material (weight `ks Cs`); for a transmissive one the
/// Fresnel (or Schlick) split into a reflected ray (`Kr Cs`, or `Cs` at total internal
/// reflection) and a transmitted one (`(1 - Kr) Cd`, into the medium of index `ior_next`),
/// each only where its weight is not zero. [`Bounce8`] is its eight-lane twin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounce {
    /// The mirror direction and the reflected ray's weight.
    pub reflected: Option<(Vec3, Vec3)>,
    /// The transmitted ray's direction, its weight and the index of its medium.
    pub transmitted: Option<(Vec3, Vec3, f32)>,
}

impl Bounce {
    /// The rays spawned where a ray of direction `dir`, in a medium of index `ior_here`,
    /// meets `material` with the normal `nf` facing it, from `inside` the surface or not.
    #[inline(always)]
    pub fn new(
        dir: Vec3,
        nf: Vec3,
        inside: bool,
        ior_here: f32,
        material: &Material,
        schlick: bool,
    ) -> Self {
        let mirror = || (dir - 2.0 * dir.dot(nf) * nf).normalize();
        let mut bounce = Bounce {
            reflected: None,
            transmitted: None,
        };
        if material.transmittance > 0.0 {
            let ior_next = if inside { 1.0 } else { material.ior };
            let eta = ior_here / ior_next;
            let cos_i = -dir.dot(nf);
            let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
            if sin2_t > 1.0 {
                // Total internal reflection: Kr = 1 and no transmitted ray.
                bounce.reflected = Some((mirror(), material.specular));
                return bounce;
            }
            let cos_t = (1.0 - sin2_t).sqrt();
            let kr = if schlick {
                self::schlick(ior_here, ior_next, cos_i, cos_t)
            } else {
                fresnel(ior_here, ior_next, cos_i, cos_t)
            };
            if kr > 0.0 {
                bounce.reflected = Some((mirror(), kr * material.specular));
            }
            if kr < 1.0 {
                let refracted = (eta * dir + (eta * cos_i - cos_t) * nf).normalize();
                bounce.transmitted = Some((refracted, (1.0 - kr) * material.diffuse, ior_next));
            }
        } else if material.ks > 0.0 {
            bounce.reflected = Some((mirror(), material.ks * material.specular));
        }
        bounce
    }
}

/// Eight hits' materials as [`Bounce8`] reads them, lane `k` from the `k`-th.
#[derive(Clone, Copy, Debug)]
pub struct Optics8 {
    transmissive: Mask8,
    reflective: Mask8,
    ior: F32x8,
    diffuse: Vec3x8,
    specular: Vec3x8,
    ks: F32x8,
}

impl Optics8 {
    /// The materials of `lanes`, splat when every lane has the same one.
    #[inline]
    pub fn new(lanes: [&Material; 8]) -> Self {
        let material = |m: &Material| Optics8 {
            transmissive: F32x8::splat(m.transmittance).gt(F32x8::ZERO),
            reflective: F32x8::splat(m.ks).gt(F32x8::ZERO),
            ior: F32x8::splat(m.ior),
            diffuse: Vec3x8::splat(m.diffuse),
            specular: Vec3x8::splat(m.specular),
            ks: F32x8::splat(m.ks),
        };
        if lanes.iter().all(|&m| std::ptr::eq(m, lanes[0])) {
            return material(lanes[0]);
        }
        let each = |f: fn(&Material) -> f32| F32x8::from_array(lanes.map(f));
        Optics8 {
            transmissive: each(|m| m.transmittance).gt(F32x8::ZERO),
            reflective: each(|m| m.ks).gt(F32x8::ZERO),
            ior: each(|m| m.ior),
            diffuse: Vec3x8::from_lanes(lanes.map(|m| m.diffuse)),
            specular: Vec3x8::from_lanes(lanes.map(|m| m.specular)),
            ks: each(|m| m.ks),
        }
    }

    /// Whether no lane's material spawns a ray (opaque, with no mirror term).
    #[inline]
    pub fn spawns_none(&self) -> bool {
        (self.transmissive | self.reflective).none()
    }
}

/// [`Bounce`] for eight hits: lane `k` spawns a reflected ray where `reflected` has it,
/// along `mirror` with `reflected_weight`, and a transmitted one where `transmitted` has
/// it, along `refracted` with `transmitted_weight` into the medium `ior_next`; each bit for
/// bit as [`Bounce::new`] (the other lanes' values are meaningless).
#[derive(Clone, Copy, Debug)]
pub struct Bounce8 {
    pub reflected: Mask8,
    pub mirror: Vec3x8,
    pub reflected_weight: Vec3x8,
    pub transmitted: Mask8,
    pub refracted: Vec3x8,
    pub transmitted_weight: Vec3x8,
    pub ior_next: F32x8,
}

impl Bounce8 {
    /// [`Bounce::new`] lane by lane, in its operations and their order.
    #[inline(always)]
    pub fn new(
        dir: Vec3x8,
        nf: Vec3x8,
        inside: Mask8,
        ior_here: F32x8,
        optics: &Optics8,
        schlick: bool,
    ) -> Self {
        let (zero, one) = (F32x8::ZERO, F32x8::splat(1.0));
        let dir_nf = dir.dot(nf);
        let mirror = (dir - nf.scale(F32x8::splat(2.0) * dir_nf)).normalize();
        let opaque_weight = optics.specular.scale(optics.ks);
        let glass = optics.transmissive;
        if glass.none() {
            return Bounce8 {
                reflected: optics.reflective,
                mirror,
                reflected_weight: opaque_weight,
                transmitted: Mask8::NONE,
                refracted: Vec3x8::ZERO,
                transmitted_weight: Vec3x8::ZERO,
                ior_next: one,
            };
        }
        let ior_next = inside.select(one, optics.ior);
        let eta = ior_here / ior_next;
        let cos_i = -dir_nf;
        let sin2_t = eta * eta * (one - cos_i * cos_i);
        let total = sin2_t.gt(one);
        let cos_t = (one - sin2_t).sqrt();
        let kr = if schlick {
            schlick8(ior_here, ior_next, cos_i, cos_t)
        } else {
            fresnel8(ior_here, ior_next, cos_i, cos_t)
        };
        let split_weight = total.select_vec(optics.specular, optics.specular.scale(kr));
        let refracted = (dir.scale(eta) + nf.scale(eta * cos_i - cos_t)).normalize();
        Bounce8 {
            reflected: (glass & (total | kr.gt(zero))) | optics.reflective.and_not(glass),
            mirror,
            reflected_weight: glass.select_vec(split_weight, opaque_weight),
            transmitted: glass.and_not(total) & kr.lt(one),
            refracted,
            transmitted_weight: optics.diffuse.scale(one - kr),
            ior_next,
        }
    }
}

/// [`fresnel`] lane by lane.
#[inline(always)]
fn fresnel8(n1: F32x8, n2: F32x8, cos_i: F32x8, cos_t: F32x8) -> F32x8 {
    let r_perp = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let r_par = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    (r_perp * r_perp + r_par * r_par) / F32x8::splat(2.0)
}

/// [`schlick`] lane by lane (`powi(5)` as the compiler expands it: `x (x^2)^2`).
#[inline(always)]
fn schlick8(n1: F32x8, n2: F32x8, cos_i: F32x8, cos_t: F32x8) -> F32x8 {
    let one = F32x8::splat(1.0);
    let r = (n1 - n2) / (n1 + n2);
    let r0 = r * r;
    let c = n1.le(n2).select(cos_i, cos_t);
    let x = one - c;
    let x2 = x * x;
    r0 + (one - r0) * (x * (x2 * x2))
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
    use crate::accel::count::NoCount;

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
    fn trace_inside_glass(origin: Vec3, dir: Vec3) -> (Vec3, RayCounts) {
        let text = "bclr 0.2 0.4 0.6\nf 1 1 1 0 1 1 1 0 1 1 1.5\ns 0 0 0 1";
        let scene = crate::scene::p3f::parse_text(text).unwrap();
        let tracer = Tracer::new(&scene.geometry, &crate::accel::AccelOptions::brute_force());
        let options = ShadeOptions {
            max_depth: 2,
            ..ShadeOptions::default()
        };
        let shader = Shader::new(&scene, &tracer, None, options, false);
        let mut rays = RayCounts::default();
        let colour = shader.trace(
            &Ray::new(origin, dir),
            RayKind::Primary,
            &Sample {
                rng: SampleRng::new(0, 0, 7),
                cell: [0, 0],
                grid: SampleGrid::square(1),
            },
            1,
            1.5,
            (&mut rays, &mut Work::<NoCount>::default()),
        );
        (colour, rays)
    }

    #[test]
    fn refraction_spawns_a_reflected_and_a_transmitted_ray() {
        let (colour, rays) = trace_inside_glass(Vec3::ZERO, Vec3::X);
        let expected_rays = RayCounts {
            primary: 1,
            reflection: 1,
            refraction: 1,
            shadow: 0,
        };
        assert_eq!(rays, expected_rays);
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
        assert_eq!((rays.primary, rays.reflection, rays.refraction), (1, 1, 0));
        // The reflected ray stays inside and, at the depth limit, is black.
        assert_eq!(colour, Vec3::ZERO);
    }

    /// The course profile dims what a ray of depth d > 2 that misses sees, background
    /// colour or skybox alike, by 1 / (0.7 (d - 1)); the standard profile never does.
    #[test]
    fn the_course_profile_dims_the_background_of_deep_rays() {
        assert_eq!(Profile::Course.max_depth(), 8);
        let factors: Vec<f32> = (1..=7)
            .map(|d| Profile::Course.background_factor(d))
            .collect();
        let expected = [
            1.0,
            1.0,
            5.0 / 7.0,
            10.0 / 21.0,
            5.0 / 14.0,
            2.0 / 7.0,
            5.0 / 21.0,
        ];
        for (f, e) in factors.iter().zip(expected) {
            assert!((f - e).abs() < 1e-6, "{factors:?}");
        }
        let scene = crate::scene::p3f::parse_text("bclr 0.2 0.4 0.6").unwrap();
        let tracer = Tracer::new(&scene.geometry, &crate::accel::AccelOptions::brute_force());
        let sky_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sky_yup");
        let sky = Skybox::load(&sky_dir).unwrap();
        let dir = Vec3::new(0.3, 0.5, -0.8).normalize();
        let sample = Sample {
            rng: SampleRng::new(0, 0, 7),
            cell: [0, 0],
            grid: SampleGrid::square(1),
        };
        for skybox in [None, Some(&sky)] {
            let seen = skybox.map_or(scene.background, |sky| sky.lookup(dir));
            for profile in [Profile::Standard, Profile::Course] {
                let options = ShadeOptions::default().with_profile(profile);
                let shader = Shader::new(&scene, &tracer, skybox, options, false);
                for depth in 1..=7 {
                    let mut rays = RayCounts::default();
                    let ray = Ray::new(Vec3::ZERO, dir);
                    let counts = (&mut rays, &mut Work::<NoCount>::default());
                    let colour =
                        shader.trace(&ray, RayKind::Reflection, &sample, depth, 1.0, counts);
                    let expected = match profile {
                        Profile::Standard => seen,
                        Profile::Course => seen * Profile::Course.background_factor(depth),
                    };
                    assert_eq!(colour, expected, "{profile:?} at depth {depth}");
                }
            }
        }
    }

    /// A shader over an empty scene, for the direction helpers.
    fn with_shader(roughness: f32, check: impl FnOnce(&Shader)) {
        let scene = crate::scene::p3f::parse_text("bclr 0 0 0").unwrap();
        let tracer = Tracer::new(&scene.geometry, &crate::accel::AccelOptions::brute_force());
        let options = ShadeOptions {
            roughness,
            ..ShadeOptions::default()
        };
        check(&Shader::new(&scene, &tracer, None, options, false));
    }

    #[test]
    fn fuzzy_reflections_spread_with_roughness_and_stay_above_the_surface() {
        let nf = Vec3::Y;
        let mirror = Vec3::new(1.0, 0.2, 0.0).normalize();
        let mean_angle = |g: f32| {
            let mut sum = 0.0;
            with_shader(g, |shader| {
                for i in 0..4000 {
                    let dir = shader.fuzz(mirror, nf, SampleRng::new(i, 0, 3));
                    assert!(dir.dot(nf) > 0.0);
                    assert!((dir.length() - 1.0).abs() < 1e-5);
                    sum += dir.dot(mirror).clamp(-1.0, 1.0).acos();
                }
            });
            sum / 4000.0
        };
        assert_eq!(mean_angle(0.0), 0.0);
        let (small, large) = (mean_angle(0.1), mean_angle(0.4));
        // For g << 1 the mean angle is about g times the mean radius of the ball's
        // projection, 3 pi / 16 ~ 0.59.
        assert!((0.04..0.08).contains(&small), "g 0.1: {small}");
        assert!(large > 3.0 * small, "g 0.4: {large}, g 0.1: {small}");
    }
}
