//! Structure-of-arrays storage for the primitives of a scene: one array per field, so that
//! SIMD kernels can load eight primitives' `x` coordinates at once. Each kind keeps the
//! material index of every primitive beside its geometry. Planes are unbounded and kept
//! apart from the rest: accelerators never hold them.

use glam::Vec3;

use crate::intersect;
use crate::intersect::TriangleHit;
use crate::ray::{PrimId, PrimKind, Ray, RayPacket};
use crate::simd::{F32x8, Mask8};

/// Three parallel arrays of coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Vec3s {
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub z: Vec<f32>,
}

impl Vec3s {
    pub fn push(&mut self, v: Vec3) {
        self.x.push(v.x);
        self.y.push(v.y);
        self.z.push(v.z);
    }

    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}

#[derive(Clone, Debug, Default)]
pub struct Spheres {
    pub centre: Vec3s,
    pub radius: Vec<f32>,
    pub material: Vec<u32>,
}

/// Spheres whose centre moves linearly from `centre0` at `time0` to `centre1` at `time1`.
#[derive(Clone, Debug, Default)]
pub struct MovingSpheres {
    pub centre0: Vec3s,
    pub centre1: Vec3s,
    pub radius: Vec<f32>,
    pub time0: Vec<f32>,
    pub time1: Vec<f32>,
    pub material: Vec<u32>,
}

impl MovingSpheres {
    /// Centre of sphere `i` at `time` (P3F.md 6.5); a sphere with `time0 == time1` stands
    /// at `centre0`.
    pub fn centre_at(&self, i: usize, time: f32) -> Vec3 {
        let (c0, c1) = (self.centre0.get(i), self.centre1.get(i));
        let span = self.time1[i] - self.time0[i];
        if span == 0.0 {
            return c0;
        }
        c0 + (c1 - c0) * ((time - self.time0[i]) / span)
    }
}

/// Triangles stored as a vertex and two edges (what Möller-Trumbore reads). Degenerate
/// triangles are stored with zero edges, which the test never hits.
#[derive(Clone, Debug, Default)]
pub struct Triangles {
    pub p0: Vec3s,
    pub e1: Vec3s,
    pub e2: Vec3s,
    pub material: Vec<u32>,
    /// Index into `vertex_normals` for smooth (`pp`) triangles, `FLAT` otherwise.
    pub shading: Vec<u32>,
    pub vertex_normals: Vec<[Vec3; 3]>,
}

impl Triangles {
    pub const FLAT: u32 = u32::MAX;

    pub fn push(&mut self, p: [Vec3; 3], normals: Option<[Vec3; 3]>, material: u32) {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let degenerate = !(e1.cross(e2).length_squared() > 0.0);
        let (e1, e2) = if degenerate {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (e1, e2)
        };
        self.p0.push(p[0]);
        self.e1.push(e1);
        self.e2.push(e2);
        self.material.push(material);
        match normals {
            Some(n) => {
                self.shading.push(self.vertex_normals.len() as u32);
                self.vertex_normals.push(n);
            }
            None => self.shading.push(Self::FLAT),
        }
    }

    pub fn len(&self) -> usize {
        self.material.len()
    }

    pub fn is_empty(&self) -> bool {
        self.material.is_empty()
    }

    /// Unit geometric normal `normalize(e1 x e2)`.
    pub fn geometric_normal(&self, i: usize) -> Vec3 {
        self.e1.get(i).cross(self.e2.get(i)).normalize_or_zero()
    }
}

#[derive(Clone, Debug, Default)]
pub struct Boxes {
    pub min: Vec3s,
    pub max: Vec3s,
    pub material: Vec<u32>,
}

/// Open cones and cylinders: `base`, unit `axis`, `height`, and the radius at each end.
#[derive(Clone, Debug, Default)]
pub struct Cones {
    pub base: Vec3s,
    pub axis: Vec3s,
    pub height: Vec<f32>,
    pub r_base: Vec<f32>,
    pub r_apex: Vec<f32>,
    pub material: Vec<u32>,
}

/// Infinite planes `dot(normal, p) = offset`.
#[derive(Clone, Debug, Default)]
pub struct Planes {
    pub normal: Vec3s,
    pub offset: Vec<f32>,
    pub material: Vec<u32>,
}

/// All primitives of a scene, by kind.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    pub spheres: Spheres,
    pub moving_spheres: MovingSpheres,
    pub triangles: Triangles,
    pub boxes: Boxes,
    pub cones: Cones,
    pub planes: Planes,
}

impl Geometry {
    /// How many primitives of `kind` there are.
    pub fn count(&self, kind: PrimKind) -> usize {
        match kind {
            PrimKind::Sphere => self.spheres.radius.len(),
            PrimKind::MovingSphere => self.moving_spheres.radius.len(),
            PrimKind::Triangle => self.triangles.len(),
            PrimKind::Box => self.boxes.material.len(),
            PrimKind::Cone => self.cones.material.len(),
            PrimKind::Plane => self.planes.material.len(),
        }
    }

    /// The ids of every primitive of `kind`.
    pub fn ids(&self, kind: PrimKind) -> impl Iterator<Item = PrimId> {
        (0..self.count(kind) as u32).map(move |i| PrimId::new(kind, i))
    }

    /// Number of bounded primitives (everything but planes).
    pub fn bounded_count(&self) -> usize {
        PrimKind::ALL
            .iter()
            .filter(|&&k| k != PrimKind::Plane)
            .map(|&k| self.count(k))
            .sum()
    }

    pub fn material(&self, prim: PrimId) -> u32 {
        let i = prim.index();
        match prim.kind() {
            PrimKind::Sphere => self.spheres.material[i],
            PrimKind::MovingSphere => self.moving_spheres.material[i],
            PrimKind::Triangle => self.triangles.material[i],
            PrimKind::Box => self.boxes.material[i],
            PrimKind::Cone => self.cones.material[i],
            PrimKind::Plane => self.planes.material[i],
        }
    }

    /// The scalar test of one primitive: the closest hit in `(t_min, t_max)`, with
    /// barycentrics for triangles.
    pub fn intersect(
        &self,
        prim: PrimId,
        ray: &Ray,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<TriangleHit> {
        let i = prim.index();
        let uv0 = |t| TriangleHit { t, u: 0.0, v: 0.0 };
        match prim.kind() {
            PrimKind::Sphere => {
                let s = &self.spheres;
                intersect::sphere(ray, s.centre.get(i), s.radius[i], t_min, t_max).map(uv0)
            }
            PrimKind::MovingSphere => {
                let s = &self.moving_spheres;
                intersect::sphere(ray, s.centre_at(i, ray.time), s.radius[i], t_min, t_max).map(uv0)
            }
            PrimKind::Triangle => {
                let tr = &self.triangles;
                intersect::triangle(ray, tr.p0.get(i), tr.e1.get(i), tr.e2.get(i), t_min, t_max)
            }
            PrimKind::Box => {
                let b = &self.boxes;
                intersect::aabb(ray, inv_dir, b.min.get(i), b.max.get(i), t_min, t_max).map(uv0)
            }
            PrimKind::Cone => {
                let c = &self.cones;
                intersect::cone(
                    ray,
                    c.base.get(i),
                    c.axis.get(i),
                    c.height[i],
                    c.r_base[i],
                    c.r_apex[i],
                    t_min,
                    t_max,
                )
                .map(uv0)
            }
            PrimKind::Plane => {
                let p = &self.planes;
                intersect::plane(ray, p.normal.get(i), p.offset[i], t_min, t_max).map(uv0)
            }
        }
    }

    /// [`Geometry::intersect`] for the rays of `packet` (lanes of `rays`) in `active`,
    /// each within `(t_min, t_max[k])`, by the primitive's packet kernel: each lane's
    /// answer is bit for bit the scalar one. Moving spheres are tested lane by lane.
    pub fn intersect_packet(
        &self,
        prim: PrimId,
        packet: &RayPacket,
        rays: &[Ray; 8],
        t_min: f32,
        t_max: &[f32; 8],
        active: u8,
    ) -> [Option<TriangleHit>; 8] {
        let i = prim.index();
        let (lo, hi, mask) = (
            F32x8::splat(t_min),
            F32x8::from_array(*t_max),
            Mask8::from_bitmask(active),
        );
        let lanes = |(hit, t): (Mask8, F32x8)| {
            let (hit, t) = (hit.bitmask(), t.to_array());
            std::array::from_fn(|k| {
                (hit & (1 << k) != 0).then(|| TriangleHit {
                    t: t[k],
                    u: 0.0,
                    v: 0.0,
                })
            })
        };
        match prim.kind() {
            PrimKind::Sphere => {
                let s = &self.spheres;
                lanes(intersect::sphere_packet(
                    packet,
                    s.centre.get(i),
                    s.radius[i],
                    lo,
                    hi,
                    mask,
                ))
            }
            PrimKind::Triangle => {
                let tr = &self.triangles;
                let h = intersect::triangle_packet(
                    packet,
                    tr.p0.get(i),
                    tr.e1.get(i),
                    tr.e2.get(i),
                    lo,
                    hi,
                    mask,
                );
                let (hit, t, u, v) = (
                    h.hit.bitmask(),
                    h.t.to_array(),
                    h.u.to_array(),
                    h.v.to_array(),
                );
                std::array::from_fn(|k| {
                    (hit & (1 << k) != 0).then(|| TriangleHit {
                        t: t[k],
                        u: u[k],
                        v: v[k],
                    })
                })
            }
            PrimKind::Box => {
                let b = &self.boxes;
                lanes(intersect::aabb_packet(
                    packet,
                    b.min.get(i),
                    b.max.get(i),
                    lo,
                    hi,
                    mask,
                ))
            }
            PrimKind::Cone => {
                let c = &self.cones;
                lanes(intersect::cone_packet(
                    packet,
                    c.base.get(i),
                    c.axis.get(i),
                    c.height[i],
                    c.r_base[i],
                    c.r_apex[i],
                    lo,
                    hi,
                    mask,
                ))
            }
            PrimKind::Plane => {
                let p = &self.planes;
                lanes(intersect::plane_packet(
                    packet,
                    p.normal.get(i),
                    p.offset[i],
                    lo,
                    hi,
                    mask,
                ))
            }
            PrimKind::MovingSphere => std::array::from_fn(|k| {
                let ray = &rays[k];
                (active & (1 << k) != 0)
                    .then(|| self.intersect(prim, ray, ray.dir.recip(), t_min, t_max[k]))
                    .flatten()
            }),
        }
    }

    /// Outward unit normal at the hit point `p` of `prim` (interpolated for smooth
    /// triangles, whose barycentrics are `u`, `v`). Triangles and planes have no inside:
    /// their normal is the geometric one of P3F.md section 2.
    pub fn normal(&self, prim: PrimId, p: Vec3, u: f32, v: f32, time: f32) -> Vec3 {
        let i = prim.index();
        match prim.kind() {
            PrimKind::Sphere => {
                ((p - self.spheres.centre.get(i)) / self.spheres.radius[i]).normalize_or_zero()
            }
            PrimKind::MovingSphere => {
                let s = &self.moving_spheres;
                ((p - s.centre_at(i, time)) / s.radius[i]).normalize_or_zero()
            }
            PrimKind::Triangle => {
                let tr = &self.triangles;
                match tr.shading[i] {
                    Triangles::FLAT => tr.geometric_normal(i),
                    k => {
                        let n = tr.vertex_normals[k as usize];
                        ((1.0 - u - v) * n[0] + u * n[1] + v * n[2])
                            .try_normalize()
                            .unwrap_or_else(|| tr.geometric_normal(i))
                    }
                }
            }
            PrimKind::Box => {
                intersect::aabb_normal(self.boxes.min.get(i), self.boxes.max.get(i), p)
            }
            PrimKind::Cone => {
                let c = &self.cones;
                intersect::cone_normal(
                    c.base.get(i),
                    c.axis.get(i),
                    c.height[i],
                    c.r_base[i],
                    c.r_apex[i],
                    p,
                )
            }
            PrimKind::Plane => self.planes.normal.get(i),
        }
    }
}
