//! All primitives of a scene: one storage per kind of the list in [`crate::prim`]
//! (structure of arrays, or records for the kinds of the BVH's leaf packs), and the
//! dispatch from a [`PrimId`] to its kind's [`Shapes`], both generated from that list.
//! Planes are unbounded and kept apart from the rest: accelerators never hold them.

use glam::{DVec3, Vec3};

use crate::intersect::{
    Aabb, Hits8, IntersectOptions, PacketHits, PacketQuery, RayQuery, Rays8, ShapeHit, Shapes,
    SurfacePoint, SurfacePoint8,
};
use crate::prim::{prim_kinds, PrimId, PrimKind};
use crate::ray::Ray;
use crate::simd::{F32x8, F32xP, LaneBits, Mask8, Vec3x8};

macro_rules! define_geometry {
    ($($kind:ident, $field:ident, $storage:ident, $name:literal, $bound:ident, $pack:ident;)*) => {
        /// All primitives of a scene, by kind.
        #[derive(Clone, Debug, Default)]
        pub struct Geometry {
            // The storage named by its path, so that a new kind needs no import here.
            $(pub $field: crate::intersect::$storage,)*
        }

        impl Geometry {
            /// Gives back what every storage grew beyond its primitives ([`Shapes::shrink_to_fit`]).
            pub fn shrink_to_fit(&mut self) {
                $(self.$field.shrink_to_fit();)*
            }

            /// How many primitives of `kind` there are.
            pub fn count(&self, kind: PrimKind) -> usize {
                match kind {
                    $(PrimKind::$kind => self.$field.len(),)*
                }
            }

            pub fn material(&self, prim: PrimId) -> u32 {
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.material(prim.index()),)*
                }
            }

            /// The materials of eight primitives, through one dispatch where they share the
            /// kind `kind` ([`PrimId::shared_kind`]; a hit block's, most often).
            pub fn materials8(&self, kind: Option<PrimKind>, prims: [PrimId; 8]) -> [u32; 8] {
                match kind {
                    $(Some(PrimKind::$kind) => prims.map(|p| self.$field.material(p.index())),)*
                    None => prims.map(|p| self.material(p)),
                }
            }

            /// The tight box of `prim` ([`Shapes::bounds`]).
            pub fn bounds(&self, prim: PrimId, shutter: [f32; 2]) -> Aabb {
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.bounds(prim.index(), shutter),)*
                }
            }

            /// The scalar test of one primitive: the closest hit of `query` in
            /// `(query.t_min, t_max)`, with barycentrics for triangles.
            #[inline]
            pub fn intersect(&self, prim: PrimId, query: &RayQuery, t_max: f32) -> Option<ShapeHit> {
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.intersect(prim.index(), query, t_max),)*
                }
            }

            /// [`Geometry::intersect`] for the lanes `active` of `query`'s packet, each
            /// within `(packet.t_min, t_max)` lane by lane, by the kind's packet kernel:
            /// each lane's answer is bit for bit the scalar one.
            pub fn intersect_packet(
                &self,
                prim: PrimId,
                query: &PacketQuery,
                t_max: F32xP,
                active: LaneBits,
            ) -> PacketHits {
                let i = prim.index();
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.intersect_packet(i, query, t_max, active),)*
                }
            }

            /// Outward unit normal at the hit point `p` of `prim` (interpolated for smooth
            /// triangles, whose barycentrics are `u`, `v`). Triangles and planes have no
            /// inside: their normal is the geometric one of P3F.md section 2.
            pub fn normal(&self, prim: PrimId, p: Vec3, u: f32, v: f32, time: f32) -> Vec3 {
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.normal(prim.index(), p, u, v, time),)*
                }
            }

            /// The hit of `prim` at `t` along `ray` (barycentrics `u`, `v`) recomputed on its
            /// surface, with its error bound and normal: where spawned rays start from
            /// ([`crate::intersect::spawn_origin`]).
            #[inline(always)]
            pub fn surface_point(
                &self,
                prim: PrimId,
                ray: &Ray,
                t: f32,
                u: f32,
                v: f32,
            ) -> SurfacePoint {
                let i = prim.index();
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.surface_point(i, ray, t, u, v),)*
                }
            }

            /// [`Geometry::surface_point`] for eight hits on primitives of one kind `kind`
            /// (lane `k` on the primitive of index `indices[k]`), by the kind's eight-lane
            /// twin where it has one ([`Shapes::surface_points8`]).
            #[inline]
            pub fn surface_points8(
                &self,
                kind: PrimKind,
                indices: [usize; 8],
                rays: &[Ray; 8],
                hits: &Hits8,
            ) -> SurfacePoint8 {
                match kind {
                    $(PrimKind::$kind => self.$field.surface_points8(indices, rays, hits),)*
                }
            }

            /// Whether some primitive moves over the shutter ([`Shapes::MOVING`]).
            pub fn has_moving(&self) -> bool {
                $((<crate::intersect::$storage as Shapes>::MOVING && !self.$field.is_empty()) ||)*
                false
            }

            /// Whether the structures grow the boxes of `kind` by the margin of the
            /// profile's sphere roots ([`Shapes::ROOTS_MARGIN`]).
            pub fn takes_roots_margin(kind: PrimKind) -> bool {
                match kind {
                    $(PrimKind::$kind => <crate::intersect::$storage as Shapes>::ROOTS_MARGIN,)*
                }
            }

            /// Whether the rays inside the primitives of `kind` are answered by their own
            /// tests, without a walk ([`Shapes::INTERIOR`]).
            #[inline]
            pub fn has_interior(kind: PrimKind) -> bool {
                match kind {
                    $(PrimKind::$kind => <crate::intersect::$storage as Shapes>::INTERIOR,)*
                }
            }

            /// Eight rays against eight primitives of `kind`, lane `k` against the one of
            /// index `indices[k]` ([`Shapes::hits8`]).
            #[inline]
            pub fn hits8(
                &self,
                kind: PrimKind,
                indices: [usize; 8],
                rays: &Rays8,
                (t_min, t_max): (f32, F32x8),
                options: IntersectOptions,
            ) -> (Mask8, F32x8) {
                match kind {
                    $(PrimKind::$kind => self.$field.hits8(indices, rays, t_min, t_max, options),)*
                }
            }

            /// Eight rays, whose `1 / dir` is `inv_dir`, against `prim`
            /// ([`Shapes::hits_one8`]).
            #[inline(always)]
            pub fn hits_one8(
                &self,
                prim: PrimId,
                rays: (&Rays8, Vec3x8),
                (t_min, t_max): (f32, F32x8),
                options: IntersectOptions,
            ) -> (Mask8, F32x8) {
                let i = prim.index();
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.hits_one8(i, rays, t_min, t_max, options),)*
                }
            }

            /// The surface points of eight hits on primitives of `kind` given as lanes
            /// ([`Shapes::surface_points_along8`]).
            #[inline]
            pub fn surface_points_along8(
                &self,
                kind: PrimKind,
                indices: [usize; 8],
                rays: &Rays8,
                t: F32x8,
            ) -> SurfacePoint8 {
                match kind {
                    $(PrimKind::$kind => self.$field.surface_points_along8(indices, rays, t),)*
                }
            }

            /// The geometric normal of `prim` at `p`, in double precision where its kind
            /// computes it so ([`Shapes::geometric_normal64`]).
            pub fn geometric_normal64(&self, prim: PrimId, p: DVec3, u: f32, v: f32) -> DVec3 {
                match prim.kind() {
                    $(PrimKind::$kind => self.$field.geometric_normal64(prim.index(), p, u, v),)*
                }
            }
        }
    };
}
prim_kinds!(define_geometry);

impl Geometry {
    /// The ids of every primitive of `kind`.
    pub fn ids(&self, kind: PrimKind) -> impl Iterator<Item = PrimId> {
        (0..self.count(kind) as u32).map(move |i| PrimId::new(kind, i))
    }

    /// Number of bounded primitives (everything but planes).
    pub fn bounded_count(&self) -> usize {
        PrimKind::BOUNDED.iter().map(|&k| self.count(k)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn materials8_are_each_primitives_material() {
        let mut geometry = Geometry::default();
        for i in 0..8 {
            geometry.spheres.push(Vec3::splat(i as f32), 1.0, 10 + i);
            let p = Vec3::splat(i as f32);
            geometry
                .triangles
                .push([p, p + Vec3::X, p + Vec3::Y], None, 20 + i);
        }
        let sphere = |i| PrimId::new(PrimKind::Sphere, i);
        let triangle = |i| PrimId::new(PrimKind::Triangle, i);
        let one_kind = [5, 0, 7, 7, 1, 3, 2, 4].map(sphere);
        let mixed = [
            sphere(5),
            triangle(0),
            sphere(7),
            triangle(7),
            sphere(1),
            sphere(3),
            triangle(2),
            triangle(4),
        ];
        for prims in [
            one_kind,
            one_kind.map(|p| triangle(p.index() as u32)),
            mixed,
        ] {
            let kind = PrimId::shared_kind(&prims);
            assert_eq!(
                geometry.materials8(kind, prims),
                prims.map(|p| geometry.material(p))
            );
        }
        assert_eq!(
            geometry.materials8(Some(PrimKind::Sphere), one_kind),
            [15, 10, 17, 17, 11, 13, 12, 14]
        );
    }
}
