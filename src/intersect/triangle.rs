//! The triangle kind: its storage ([`Triangles`]: three vertices, optional vertex normals),
//! the watertight ray-triangle test of Woop, Benthin and Wald ("Watertight Ray/Triangle
//! Intersection", JCGT 2013) and its SIMD twins (a packet's rays against one triangle; one
//! ray against a [`TrianglePack8`] of a BVH leaf).
//!
//! **Watertight.** A ray is set up for the test ([`Shear`]): the axis its direction is
//! longest along becomes `z`, the other two follow it cyclically, and a shear of `x` and
//! `y` along `z` turns the ray into the `z` axis. Each vertex, relative
//! to the origin and sheared, becomes a point of the plane `z = 0` that depends on the
//! vertex and the ray alone; an edge's function is the 2-by-2 determinant of its two ends
//! ([`edge`]), and reversing the edge negates it exactly (products commute and rounding
//! to nearest is symmetric). So two triangles that share an edge decide it alike, and a ray
//! passes on one side of it, the other, or on it, never between. A rounded difference of
//! two rounded products has the sign of the exact difference or is zero (rounding is
//! monotone), and a zero is computed again in double precision, where those products are
//! exact ([`exact_edges`]): every edge function has the exact sign for the sheared
//! vertices, as if they had been moved a little, each one the same way in every triangle
//! it belongs to. A ray that enters a closed mesh therefore meets one of its triangles, and
//! a ray through an edge or a vertex meets every triangle that shares it (zero counts as
//! inside). The vertices must be the stored ones, which is why [`Triangles`] keeps three
//! vertices and not a vertex and two edges: `p0 + (p1 - p0)` is not always `p1`.
//!
//! **Setup.** The walks of the 8-wide BVH take their ray's frame ([`frame_of`]) once, as a
//! constant (`FRAME`, by `with_frame!`: at a walk's start, and for a packet's lanes group
//! by group), so that a leaf pack's test reads the vertices on the frame's axes at fixed
//! places and makes no choice: choosing in each leaf, by a branch or by coordinates read
//! at computed places, cost the packet walks 7-19% (they test leaves for one lane after
//! another). A pack's eight triangles share one setup of the ray ([`Shear`]), made there
//! from its query; a packet's lanes share one ([`ShearLanes`]), made by its query at the
//! first triangle it meets. The scalar test, one triangle at a time (the grid, the binary
//! BVH, brute force), makes it for each.
//!
//! **Precision.** A hit stands only inside the triangle's trusted box (the box the
//! structures hold it in, `intersect::trusted_box`), by the structures' own box test
//! ([`RayQuery::holds`]): then every structure finds it (`accel::bounds`). The watertight
//! test's `t` is a weighted mean of the vertices' distances with weights of one sign, so no
//! sliver makes it noise, and its hit lies in the box but for a ray from very far away
//! (from 1e9, where floats are 64 apart, the vertices relative to the origin keep only
//! those digits). Such a hit is computed again by the same test in double precision from
//! the same inputs ([`refined`]) and stands if that one lies in the box. Whether a hit is
//! recomputed depends on the ray and the triangle alone, never on `t_max`, so the answer
//! does not depend on the order a structure tests primitives in. The box test runs eight
//! lanes at a time on the packs that single precision hits, against boxes each pack keeps
//! (made once: making them at each such test cost 5% of the protocol's traversal
//! instructions), and the recomputations in scalar code shared by every twin, so each lane
//! stays the scalar answer bit for bit.

use std::ops::{Mul, Sub};

use glam::{DVec3, Vec3};

use super::{
    gamma, gather8, trusted_box, Aabb, BoxPack8, BoxRays, Hits8, IntersectOptions, LeafPack,
    MeshPack8, PackOf, PacketHits, PacketQuery, RayQuery, ShapeHit, ShapeHit8, ShapeHits, Shapes,
    SurfacePoint, SurfacePoint8,
};
use crate::ray::{Ray, RayPacket};
use crate::simd::{
    for_lanes, Bits, F32x8, F32xP, Floats, LaneBits, LaneMask, Mask8, MaskP, Vec3Lanes, Vec3x8,
    Vec3xP,
};

/// An axis of space, as a ray's frame ([`Shear`]) takes them: an index that needs no
/// bounds check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Axis {
    X,
    Y,
    Z,
}

/// The frames a ray may take, by the axis its direction is longest along: that axis is the
/// frame's `z`, and the next two, cyclically, its `x` and `y`.
pub(super) const FRAMES: [[Axis; 3]; 3] = [
    [Axis::Y, Axis::Z, Axis::X],
    [Axis::Z, Axis::X, Axis::Y],
    [Axis::X, Axis::Y, Axis::Z],
];

/// `v` on the axes of `frame`.
#[inline(always)]
fn on_axes(v: Vec3, [x, y, z]: [Axis; 3]) -> Vec3 {
    let v = v.to_array();
    Vec3::new(v[x as usize], v[y as usize], v[z as usize])
}

/// The frame a ray with direction `dir` takes in the watertight test: the axis its
/// direction is longest along (0, 1, 2: `x`, `y`, `z`), ties to the later axis (NaN: `z`),
/// which becomes the frame's `z`. The walks take it as a constant (`FRAME`), so that a
/// leaf's test reads the vertices on the frame's axes at fixed places.
#[inline(always)]
pub fn frame_of(dir: Vec3) -> usize {
    let (x, y, z) = (dir.x.abs(), dir.y.abs(), dir.z.abs());
    let x_over_y = x > y;
    let by_x = x_over_y & (x > z);
    let by_y = !x_over_y & (y > z);
    2 - 2 * usize::from(by_x) - usize::from(by_y)
}

/// One ray set up for the watertight test: its frame's axes (`z` the one its direction is
/// longest along), its origin on them, and the shear `(sx, sy, sz)`, which takes a point
/// `p` relative to the origin on those axes to `(p.x - sx p.z, p.y - sy p.z)` in the plane
/// across the ray, at distance `p.z sz` along it. Made from the query where a test needs
/// it (the module's comment).
#[derive(Clone, Copy, Debug)]
pub struct Shear {
    axes: [Axis; 3],
    origin: Vec3,
    factors: Vec3,
}

impl Shear {
    /// The setup of `query`'s ray: its numbers read where they lie, by the axes' indices.
    #[inline(always)]
    pub fn of(query: &RayQuery) -> Self {
        Self::on(query, FRAMES[frame_of(query.ray.dir)])
    }

    /// The setup of `query`'s ray on the frame `axes`: with the axes constants (a walk's
    /// `FRAME`), its numbers and a pack's coordinates are read at fixed places.
    #[inline(always)]
    pub(super) fn on(query: &RayQuery, axes: [Axis; 3]) -> Self {
        let [x, y, z] = [axes[0] as usize, axes[1] as usize, axes[2] as usize];
        let (o, d): (&[f32; 3], &[f32; 3]) = (query.ray.origin.as_ref(), query.ray.dir.as_ref());
        let sz = query.inv_dir.as_ref()[z];
        Shear {
            axes,
            origin: Vec3::new(o[x], o[y], o[z]),
            factors: Vec3::new(d[x] * sz, d[y] * sz, sz),
        }
    }

    /// The frame's axes.
    pub fn axes(&self) -> [Axis; 3] {
        self.axes
    }

    /// The origin on the frame's axes, then the shear `(sx, sy, sz)`.
    pub fn parts(&self) -> [Vec3; 2] {
        [self.origin, self.factors]
    }

    /// `p` relative to the origin, on the frame's axes.
    #[inline(always)]
    fn relative(&self, p: Vec3) -> Vec3 {
        on_axes(p, self.axes) - self.origin
    }

    /// [`Shear::relative`] for eight points given per axis (`[x, y, z]`), read by the
    /// frame's axes.
    #[inline(always)]
    pub(super) fn relative8(&self, p: &[F32x8; 3]) -> Vec3x8 {
        let [x, y, z] = self.axes;
        let o = self.origin;
        Vec3x8 {
            x: p[x as usize] - F32x8::splat(o.x),
            y: p[y as usize] - F32x8::splat(o.y),
            z: p[z as usize] - F32x8::splat(o.z),
        }
    }

    /// The shear's factors in every lane.
    #[inline(always)]
    pub(super) fn factors8(&self) -> [F32x8; 3] {
        let f = self.factors;
        [F32x8::splat(f.x), F32x8::splat(f.y), F32x8::splat(f.z)]
    }
}

/// [`Shear`] for each lane of a packet, made once per packet query
/// ([`PacketQuery::shear`]): each lane's frame, as masks, and the frame that every lane
/// the packet asks shares, if they do (most packets: a tile's primary rays, one light's
/// shadow rays), so that a triangle's vertices are taken on its axes by three broadcasts
/// rather than six blends per vertex.
#[derive(Clone, Copy, Debug)]
pub struct ShearLanes {
    /// The lanes whose frame's `z` is `x`, and those whose `z` is `y` (the others: `z`).
    z_is_x: MaskP,
    z_is_y: MaskP,
    /// The `z` of the frame the lanes share, if they do.
    shared: Option<Axis>,
    origin: Vec3xP,
    factors: [F32xP; 3],
}

impl ShearLanes {
    /// The setup of the packet's rays, lane by lane [`Shear::of`] the lane's query. Out of
    /// line: a packet query makes it once, and inlined it grew every packet walk.
    #[inline(never)]
    pub fn new(packet: &RayPacket) -> Self {
        let d = packet.dir.abs();
        let x_over_y = d.x.gt(d.y);
        let z_is_x = x_over_y & d.x.gt(d.z);
        let z_is_y = d.y.gt(d.z).and_not(x_over_y);
        let asked = packet.active;
        let (by_x, by_y) = (z_is_x.bitmask(), z_is_y.bitmask());
        let shared = if by_x & asked == asked {
            Some(Axis::X)
        } else if by_y & asked == asked {
            Some(Axis::Y)
        } else if (by_x | by_y) & asked == 0 {
            Some(Axis::Z)
        } else {
            None
        };
        // Each lane's vectors on its frame's axes: where the lanes share one, its fields
        // in turn, else a blend of the three.
        let on_axes = |v: &Vec3xP| match shared {
            Some(Axis::X) => Vec3xP {
                x: v.y,
                y: v.z,
                z: v.x,
            },
            Some(Axis::Y) => Vec3xP {
                x: v.z,
                y: v.x,
                z: v.y,
            },
            Some(Axis::Z) => *v,
            None => {
                let pick = |x: F32xP, y: F32xP, z: F32xP| z_is_x.select(x, z_is_y.select(y, z));
                Vec3xP {
                    x: pick(v.y, v.z, v.x),
                    y: pick(v.z, v.x, v.y),
                    z: pick(v.x, v.y, v.z),
                }
            }
        };
        let dir = on_axes(&packet.dir);
        let sz = on_axes(&packet.inv_dir).z;
        ShearLanes {
            z_is_x,
            z_is_y,
            shared,
            origin: on_axes(&packet.origin),
            factors: [dir.x * sz, dir.y * sz, sz],
        }
    }

    /// The packet's lanes by their frame ([`frame_of`]): `[x, y, z]`.
    #[inline(always)]
    pub fn lanes_by_frame(&self) -> [LaneBits; 3] {
        let (x, y) = (self.z_is_x.bitmask(), self.z_is_y.bitmask());
        [x, y, !(x | y)]
    }

    /// Lane `k`, one the packet asks, as a [`Shear`]: bit for bit [`Shear::of`] the lane's
    /// query.
    pub fn lane(&self, k: usize) -> Shear {
        let [sx, sy, sz] = &self.factors;
        let (x, y) = (self.z_is_x.bitmask().has(k), self.z_is_y.bitmask().has(k));
        Shear {
            axes: FRAMES[if x {
                0
            } else if y {
                1
            } else {
                2
            }],
            origin: self.origin.lane(k),
            factors: Vec3::new(sx.lane(k), sy.lane(k), sz.lane(k)),
        }
    }

    /// [`Shear::relative`] for each lane of the point whose coordinate on `axis` is
    /// `coordinate(axis)`. Right for the lanes of the packet it was made for (their frame
    /// is `shared` where that is set). The shared frame's axes are written out, one arm
    /// each, so that the coordinates' addresses wait for no load of the axes (a packet's
    /// test of one triangle, timed alone: 12.9 ns with the axes loaded, 10.5 written out).
    #[inline(always)]
    fn relative(&self, coordinate: impl Fn(usize) -> f32) -> Vec3xP {
        let splat = |axis: usize| F32xP::splat(coordinate(axis));
        let on_axes = match self.shared {
            Some(Axis::X) => Vec3xP {
                x: splat(1),
                y: splat(2),
                z: splat(0),
            },
            Some(Axis::Y) => Vec3xP {
                x: splat(2),
                y: splat(0),
                z: splat(1),
            },
            Some(Axis::Z) => Vec3xP {
                x: splat(0),
                y: splat(1),
                z: splat(2),
            },
            None => {
                let (x, y, z) = (splat(0), splat(1), splat(2));
                let pick =
                    |x: F32xP, y: F32xP, z: F32xP| self.z_is_x.select(x, self.z_is_y.select(y, z));
                Vec3xP {
                    x: pick(y, z, x),
                    y: pick(z, x, y),
                    z: pick(x, y, z),
                }
            }
        };
        on_axes - self.origin
    }
}

/// The edge function of the edge from `p` to `q` (sheared, the ray through the origin):
/// twice the signed area of the triangle `(0, p, q)`. `edge(q, p)` is exactly `-edge(p,
/// q)`.
#[inline(always)]
fn edge<F: Copy + Mul<Output = F> + Sub<Output = F>>([px, py]: [F; 2], [qx, qy]: [F; 2]) -> F {
    qx * py - qy * px
}

/// [`edge`] of the three edges of `a, b, c` in double precision, where the products of
/// single-precision numbers are exact: the exact sign of each, for an edge function that
/// single precision rounded to zero.
#[cold]
#[inline(never)]
fn exact_edges([a, b, c]: [[f32; 2]; 3]) -> [f32; 3] {
    let edge = |p: [f32; 2], q: [f32; 2]| {
        let [px, py, qx, qy] = [p[0], p[1], q[0], q[1]].map(f64::from);
        (qx * py - qy * px) as f32
    };
    [edge(b, c), edge(c, a), edge(a, b)]
}

/// Whether edge functions of both signs rule the ray out.
#[inline(always)]
fn straddles([u, v, w]: [f32; 3]) -> bool {
    (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)
}

/// The watertight test against the triangle `vertices` for the ray set up as `shear`:
/// the hit in `(t_min, inf)`, before the trusted box and `t_max` settle it.
#[inline(always)]
fn watertight(shear: &Shear, vertices: [Vec3; 3], t_min: f32) -> Option<ShapeHit> {
    let [p0, p1, p2] = vertices;
    let (a, b, c) = (shear.relative(p0), shear.relative(p1), shear.relative(p2));
    let Vec3 {
        x: sx,
        y: sy,
        z: sz,
    } = shear.factors;
    // The vertices sheared into the plane across the ray, which passes through (0, 0).
    let sheared = |p: Vec3| [p.x - sx * p.z, p.y - sy * p.z];
    let sheared = [sheared(a), sheared(b), sheared(c)];
    let [a2, b2, c2] = sheared;
    let edges = [edge(b2, c2), edge(c2, a2), edge(a2, b2)];
    if straddles(edges) {
        return None;
    }
    let edges = if edges.contains(&0.0) {
        // Signs that single precision could not give may straddle zero too.
        let exact = exact_edges(sheared);
        if straddles(exact) {
            return None;
        }
        exact
    } else {
        edges
    };
    hit_of(edges, [a.z, b.z, c.z], sz, t_min)
}

/// The hit of a ray whose edge functions, of one sign or zero, are `edges` and whose
/// frame's `z` puts the vertices at `depths`, in `(t_min, inf)`: none where the
/// determinant, their sum, is zero or not finite.
#[inline(always)]
fn hit_of(edges: [f32; 3], depths: [f32; 3], sz: f32, t_min: f32) -> Option<ShapeHit> {
    let [u, v, w] = edges;
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = (u * depths[0] + v * depths[1] + w * depths[2]) * sz * inv_det;
    (t > t_min).then_some(ShapeHit {
        t,
        u: v * inv_det,
        v: w * inv_det,
    })
}

/// [`watertight`] lane by lane, on the vertices relative to each lane's origin on its
/// frame's axes (`vertices`) with each lane's shear (`factors`); lanes outside `asked`
/// miss. Its early exits turned into a mask: the candidates that [`settle`] settles, and
/// the lanes where an edge function is zero, which it leaves to the scalar test.
#[inline(always)]
fn watertight_lanes<F: Floats>(
    [a, b, c]: [Vec3Lanes<F>; 3],
    [sx, sy, sz]: [F; 3],
    t_min: F,
    asked: F::Mask,
) -> (ShapeHits<F>, F::Mask) {
    let sheared = |p: Vec3Lanes<F>| [p.x - sx * p.z, p.y - sy * p.z];
    let corners = [sheared(a), sheared(b), sheared(c)];
    watertight_sheared(corners, [a.z, b.z, c.z], sz, t_min, asked)
}

/// [`watertight_lanes`] from the vertices already sheared (`(x - sx z, y - sy z)` of each
/// vertex relative to the origin on the frame's axes), their `z` and the factor `sz`.
#[inline(always)]
pub(super) fn watertight_sheared<F: Floats>(
    [a2, b2, c2]: [[F; 2]; 3],
    [az, bz, cz]: [F; 3],
    sz: F,
    t_min: F,
    asked: F::Mask,
) -> (ShapeHits<F>, F::Mask) {
    let [u, v, w] = [edge(b2, c2), edge(c2, a2), edge(a2, b2)];
    let zero = F::splat(0.0);
    // [`straddles`] by the least and the largest: `minps` and `maxps` keep the second
    // operand against NaN, so a NaN lane may fall either way here, and its determinant
    // then rules it out (or the scalar test, which the lane goes to).
    let (least, largest) = (u.min(v).min(w), u.max(v).max(w));
    let inside = asked.and_not(least.lt(zero) & largest.gt(zero));
    let exact = inside & (least.eq(zero) | largest.eq(zero));
    let det = u + v + w;
    let inv_det = F::splat(1.0) / det;
    let t = (u * az + v * bz + w * cz) * sz * inv_det;
    // The edge functions of a lane inside and not exact are all of one sign and none zero,
    // so the determinant is zero in none: finite is what is left to ask.
    let hits = ShapeHits {
        hit: inside.and_not(exact) & (det.is_finite() & t.gt(t_min)),
        t,
        u: v * inv_det,
        v: w * inv_det,
    };
    (hits, exact)
}

/// The watertight test against `vertices` for one ray within `(t_min, t_max)`. Two-sided;
/// edges and vertices count as inside. NaN vertices (how [`Triangles`] stores a triangle
/// of zero area) are never hit. A hit lies in the triangle's box as the structures hold
/// it, single precision's where it does, else double precision's (the module's comment).
pub fn triangle(ray: &Ray, vertices: [Vec3; 3], t_min: f32, t_max: f32) -> Option<ShapeHit> {
    let query = RayQuery::new(ray, t_min, IntersectOptions::default());
    triangle_hit(&query, vertices, t_max)
}

/// The body of [`triangle`] for a query. Out of line, as [`triangle`] was: inlined, it
/// grows `Geometry::intersect` for every kind (+0.4% on `bench balls_high`).
#[inline(never)]
pub(super) fn triangle_hit(query: &RayQuery, vertices: [Vec3; 3], t_max: f32) -> Option<ShapeHit> {
    let hit = watertight(&Shear::of(query), vertices, query.t_min)?;
    if in_trusted_box(query, vertices, hit.t) {
        return (hit.t < t_max).then_some(hit);
    }
    refined(&query.ray, vertices, query.t_min, t_max)
        .filter(|hit| in_trusted_box(query, vertices, hit.t))
}

/// The box of the vertices, as [`Triangles`] bounds the triangle for the structures;
/// `None` unless they are finite.
#[inline]
fn corner_box([p0, p1, p2]: [Vec3; 3]) -> Option<Aabb> {
    (p0.is_finite() && p1.is_finite() && p2.is_finite()).then(|| Aabb {
        min: p0.min(p1).min(p2),
        max: p0.max(p1).max(p2),
    })
}

/// The box the structures hold the triangle `vertices` in ([`trusted_box`]).
#[inline]
fn trusted_triangle_box(vertices: [Vec3; 3]) -> Option<Aabb> {
    corner_box(vertices).and_then(|tight| trusted_box(tight, 0.0))
}

/// Whether the hit at `t` of the triangle `vertices` along `query` lies where the
/// structures look for it: in its trusted box, by their box test ([`RayQuery::holds`]).
#[inline(never)]
fn in_trusted_box(query: &RayQuery, vertices: [Vec3; 3], t: f32) -> bool {
    query.holds(trusted_triangle_box(vertices), t)
}

/// The watertight test in double precision from the single-precision inputs, in the frame
/// single precision takes: the hit of a candidate that single precision found outside the
/// box (see the module's comment). Zero counts as inside, as in single precision.
#[inline(never)]
fn refined(ray: &Ray, vertices: [Vec3; 3], t_min: f32, t_max: f32) -> Option<ShapeHit> {
    let [x, y, z] = FRAMES[frame_of(ray.dir)].map(|axis| axis as usize);
    let (origin, dir) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let sz = 1.0 / dir[z];
    let (sx, sy) = (dir[x] * sz, dir[y] * sz);
    let [a, b, c] = vertices.map(|p| {
        let p = p.as_dvec3() - origin;
        [p[x] - sx * p[z], p[y] - sy * p[z], p[z]]
    });
    let edge = |p: [f64; 3], q: [f64; 3]| q[0] * p[1] - q[1] * p[0];
    let [u, v, w] = [edge(b, c), edge(c, a), edge(a, b)];
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let t = ((u * a[2] + v * b[2] + w * c[2]) * sz / det) as f32;
    let (u, v) = ((v / det) as f32, (w / det) as f32);
    (t > t_min && t < t_max).then_some(ShapeHit { t, u, v })
}

/// The candidates of `hits` (single precision's, [`watertight_lanes`]) settled as
/// [`triangle`] settles them: the lanes of `trusted` (in the triangle's box) kept within
/// `t_max`; the others, and the lanes `exact` (an edge function of zero), answered by
/// `scalar(k)`, the scalar test of lane `k`.
#[inline(always)]
pub(super) fn settle<F: Floats>(
    hits: &mut ShapeHits<F>,
    trusted: F::Mask,
    exact: F::Mask,
    t_max: F,
    scalar: impl Fn(usize) -> Option<ShapeHit>,
) {
    let others = (hits.hit.and_not(trusted) | exact).bitmask();
    hits.hit = hits.hit & trusted & hits.t.lt(t_max);
    if others != Bits::EMPTY {
        *hits = scalar_lanes(*hits, others, scalar);
    }
}

/// `hits` with the lanes `lanes` as `scalar` answers them. By value: a reference would
/// keep the hits in memory on the way that does not call it.
#[cold]
#[inline(never)]
fn scalar_lanes<F: Floats>(
    mut hits: ShapeHits<F>,
    lanes: <F::Mask as LaneMask>::Bits,
    scalar: impl Fn(usize) -> Option<ShapeHit>,
) -> ShapeHits<F> {
    let mut mask = hits.hit.bitmask();
    for_lanes(lanes, |k| {
        if let Some(hit) = scalar(k) {
            hits.t.set_lane(k, hit.t);
            hits.u.set_lane(k, hit.u);
            hits.v.set_lane(k, hit.v);
            mask = mask.with(k);
        }
    });
    hits.hit = F::Mask::from_bitmask(mask);
    hits
}

/// Eight triangles side by side for [`triangle_leaf`]: their vertices per axis, 36 bytes
/// a triangle and nothing more. Unused slots hold NaN vertices, as degenerate triangles
/// do, so every edge function is NaN (never a zero that asks for double precision) and
/// they are never hit.
///
/// The slots' trusted boxes are made again from the vertices where a lane hits
/// (`trusted8`), not stored: stored, they took 24 more bytes a triangle
/// and three more cache lines a pack for a test that only hits ask for.
#[derive(Clone, Copy, Debug)]
pub struct TrianglePack8 {
    /// `vertices[i][axis]`: coordinate `axis` of vertex `i` of each slot.
    vertices: [[F32x8; 3]; 3],
}

impl TrianglePack8 {
    /// Packs up to eight triangles (their vertices), padding the rest with NaN.
    ///
    /// # Panics
    /// If given more than eight triangles.
    pub fn new(triangles: &[[Vec3; 3]]) -> Self {
        assert!(triangles.len() <= 8, "a pack holds at most 8 triangles");
        let vertices = [0, 1, 2].map(|i| {
            [0, 1, 2].map(|axis| {
                F32x8::from_fn(|slot| triangles.get(slot).map_or(f32::NAN, |t| t[i][axis]))
            })
        });
        TrianglePack8 { vertices }
    }

    /// The vertices of slot `slot`.
    #[inline(always)]
    fn slot(&self, slot: usize) -> [Vec3; 3] {
        let vertex = |[x, y, z]: &[F32x8; 3]| Vec3::new(x.lane(slot), y.lane(slot), z.lane(slot));
        let [p0, p1, p2] = &self.vertices;
        [vertex(p0), vertex(p1), vertex(p2)]
    }
}

/// Each slot's trusted box, bit for bit as [`trusted_triangle_box`] makes it, valid in the
/// slots of the mask that single precision can hit (a slot with a NaN or infinite vertex
/// is none: it makes an edge function or the determinant NaN or infinite).
#[inline(always)]
pub(super) fn trusted8(vertices: &[[F32x8; 3]; 3]) -> (BoxPack8, Mask8) {
    let [p0, p1, p2] = vertices.map(|[x, y, z]| Vec3x8 { x, y, z });
    let tight = BoxPack8 {
        min: p0.min(p1).min(p2),
        max: p0.max(p1).max(p2),
    };
    tight.trusted(0.0)
}

/// [`triangle`] for the rays of `query`'s packet against one triangle, each lane within
/// `(t_min, t_max)`; lanes outside `active` (which the packet asks) miss.
pub fn triangle_packet(
    query: &PacketQuery,
    vertices: [Vec3; 3],
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> PacketHits {
    packet_hits(query, |i, axis| vertices[i][axis], t_min, t_max, active)
}

/// [`triangle_packet`] for the triangle whose vertex `i` has the coordinate
/// `coordinate(i, axis)` on `axis`, its trusted box made from those vertices where a
/// lane hits. A coordinate is read where it lies, on the axes the lanes take: from a
/// pack, one broadcast each.
#[inline(always)]
fn packet_hits(
    query: &PacketQuery,
    coordinate: impl Fn(usize, usize) -> f32,
    t_min: F32xP,
    t_max: F32xP,
    active: LaneBits,
) -> PacketHits {
    let shear = query.shear();
    let relative = |i: usize| shear.relative(|axis| coordinate(i, axis));
    let (mut hits, exact) = watertight_lanes(
        [relative(0), relative(1), relative(2)],
        shear.factors,
        t_min,
        MaskP::from_bitmask(active),
    );
    if (hits.hit | exact).any() {
        let rays = query.packet;
        let vertex = |i| Vec3::new(coordinate(i, 0), coordinate(i, 1), coordinate(i, 2));
        let vertices = [vertex(0), vertex(1), vertex(2)];
        let trusted = trusted_triangle_box(vertices).map_or(MaskP::from_bitmask(0), |b| {
            BoxRays::new(rays).holds(b.min, b.max, t_min, hits.t)
        });
        settle(&mut hits, trusted, exact, t_max, |k| {
            let lane = RayQuery::new(&rays.rays[k], t_min.lane(k), query.options);
            triangle_hit(&lane, vertices, t_max.lane(k))
        });
    }
    hits
}

/// [`triangle_packet`] for the triangle in slot `slot` of eight given by their vertices
/// per axis (`vertices[i][axis]`), the packet's lanes within `(t_min, t_max)`.
#[inline(always)]
pub(super) fn slot_hits(
    vertices: &[[F32x8; 3]; 3],
    slot: usize,
    query: &PacketQuery,
    t_max: F32xP,
    active: LaneBits,
) -> PacketHits {
    let coordinate = |i: usize, axis: usize| vertices[i][axis].lane(slot);
    packet_hits(query, coordinate, query.t_min_lanes(), t_max, active)
}

/// [`triangle`] for one ray against the eight triangles of a pack.
pub fn triangle_leaf(ray: &Ray, pack: &TrianglePack8, t_min: f32, t_max: f32) -> ShapeHit8 {
    let query = RayQuery::new(ray, t_min, IntersectOptions::default());
    with_frame!(frame_of(ray.dir), FRAME => leaf_hits::<FRAME>(&query, pack, t_max))
}

/// [`triangle_leaf`] for a query whose frame ([`frame_of`]) is `FRAME`: the frame's axes
/// are constants, so the vertices' coordinates are read where they lie, waiting for no
/// choice of frame, and the test makes no choice per leaf.
#[inline(always)]
fn leaf_hits<const FRAME: usize>(query: &RayQuery, pack: &TrianglePack8, t_max: f32) -> ShapeHit8 {
    let shear = &Shear::on(query, FRAMES[FRAME]);
    let (t_min, t_max) = (F32x8::splat(query.t_min), F32x8::splat(t_max));
    let [p0, p1, p2] = &pack.vertices;
    let (mut hits, exact) = watertight_lanes(
        [
            shear.relative8(p0),
            shear.relative8(p1),
            shear.relative8(p2),
        ],
        shear.factors8(),
        t_min,
        Mask8::ALL,
    );
    if (hits.hit | exact).any() {
        let trusted = query.holds8(trusted8(&pack.vertices), hits.t);
        let t_max_lane = t_max.lane(0);
        settle(&mut hits, trusted, exact, t_max, |k| {
            triangle_hit(query, pack.slot(k), t_max_lane)
        });
    }
    hits
}

/// How far a point of a triangle must be moved off its plane so that no ray leaving it
/// there meets the triangle again by the watertight test ([`Shapes::surface_point`] of
/// [`Triangles`]): `gamma(12) |a| |b| |c| / area + gamma(14) (w |a| + u |b| + v |c|)`,
/// with `distances` the point's distances to the three vertices, `weights` its
/// barycentrics and `area` the length of `e1 x e2` (the first term left out where that is
/// not positive). [`self_hit_margin8`] is its twin for eight points.
#[inline(always)]
fn self_hit_margin([a, b, c]: [f32; 3], [w, u, v]: [f32; 3], area: f32) -> f32 {
    let spread = if area > 0.0 { a * b * c / area } else { 0.0 };
    gamma(12) * spread + gamma(14) * (w.abs() * a + u.abs() * b + v.abs() * c)
}

/// [`self_hit_margin`] lane by lane.
#[inline(always)]
fn self_hit_margin8([a, b, c]: [F32x8; 3], [w, u, v]: [F32x8; 3], area: F32x8) -> F32x8 {
    let spread = area.gt(F32x8::ZERO).select(a * b * c / area, F32x8::ZERO);
    F32x8::splat(gamma(12)) * spread
        + F32x8::splat(gamma(14)) * (w.abs() * a + u.abs() * b + v.abs() * c)
}

/// Triangles as corners of shared vertices: a mesh's vertices are stored once, as the
/// file gives them. Degenerate triangles (of zero area in single precision) have a NaN
/// vertex at every corner, which the test never hits and the structures leave out (their
/// box is empty).
///
/// Read one triangle at a time, by a hit's surface point above all: the SIMD tests read
/// the leaf packs ([`TrianglePack8`], structure of arrays, where the vertices are laid out
/// for the test). Indexed, not three vertices a triangle: the packs hold each triangle's
/// vertices already, and a mesh's corners take 12 bytes and its vertices about 6 a
/// triangle, where three vertices took 36. Materials and vertex normals go by runs of
/// triangles, as files give them (a mesh is one run), not 8 bytes a triangle.
#[derive(Clone, Debug, Default)]
pub struct Triangles {
    /// The vertices that the corners index.
    pub positions: Vec<Vec3>,
    /// Each triangle's vertices, as indices in `positions`.
    pub corners: Vec<[u32; 3]>,
    /// The triangles' materials and shading, a run of consecutive triangles alike at a
    /// time, by their first triangle.
    runs: Vec<Run>,
    pub vertex_normals: Vec<[Vec3; 3]>,
}

/// The triangles from `first` up to the next run's first: of one material, and flat
/// (`normals` is [`Triangles::FLAT`]) or smooth, triangle `first + k` with the vertex
/// normals `normals + k`.
#[derive(Clone, Copy, Debug)]
struct Run {
    first: u32,
    material: u32,
    normals: u32,
}

impl Triangles {
    pub const FLAT: u32 = u32::MAX;

    /// Makes room for `additional` more triangles (their corners; a mesh's vertices are
    /// reserved by [`Triangles::add_vertices`]), so that a mesh of known size is read
    /// without growing them by doubling, which held a copy and a half of them at once.
    pub fn reserve(&mut self, additional: usize) {
        self.corners.reserve_exact(additional);
    }

    /// Stores `vertices` for triangles to share ([`Triangles::push_indexed`]); gives the
    /// index of the first.
    ///
    /// # Panics
    /// If the triangles would then have more than `u32::MAX` vertices.
    pub fn add_vertices(&mut self, vertices: impl ExactSizeIterator<Item = Vec3>) -> u32 {
        let first = self.first_free_vertex(vertices.len());
        self.positions.reserve_exact(vertices.len());
        self.positions.extend(vertices);
        first
    }

    /// Stores the triangle of the vertices `p` with its own copy of them, flat or with
    /// vertex `normals`.
    pub fn push(&mut self, p: [Vec3; 3], normals: Option<[Vec3; 3]>, material: u32) {
        let shading = match normals {
            Some(n) => {
                self.vertex_normals.push(n);
                self.vertex_normals.len() as u32 - 1
            }
            None => Self::FLAT,
        };
        let first = self.add_vertices(p.into_iter());
        self.push_corners([first, first + 1, first + 2], material, shading);
    }

    /// Stores the flat triangle whose vertices are `corners` of those stored.
    ///
    /// # Panics
    /// If a corner is not a stored vertex.
    pub fn push_indexed(&mut self, corners: [u32; 3], material: u32) {
        assert!(
            corners.iter().all(|&c| (c as usize) < self.positions.len()),
            "a corner beyond the {} vertices",
            self.positions.len()
        );
        self.push_corners(corners, material, Self::FLAT);
    }

    fn push_corners(&mut self, corners: [u32; 3], material: u32, shading: u32) {
        let [p0, p1, p2] = corners.map(|c| self.positions[c as usize]);
        let degenerate = !((p1 - p0).cross(p2 - p0).length_squared() > 0.0);
        let corners = if degenerate {
            // A vertex of its own, NaN, at every corner.
            let nan = self.first_free_vertex(1);
            self.positions.push(Vec3::NAN);
            [nan; 3]
        } else {
            corners
        };
        let index = self.corners.len() as u32;
        let continues = self.runs.last().is_some_and(|run| {
            run.material == material
                && match (run.normals, shading) {
                    (Self::FLAT, Self::FLAT) => true,
                    (Self::FLAT, _) | (_, Self::FLAT) => false,
                    (normals, shading) => shading == normals + (index - run.first),
                }
        });
        if !continues {
            self.runs.push(Run {
                first: index,
                material,
                normals: shading,
            });
        }
        self.corners.push(corners);
    }

    /// The run that holds triangle `i`.
    #[inline]
    fn run(&self, i: usize) -> &Run {
        let after = self.runs.partition_point(|run| run.first as usize <= i);
        &self.runs[after - 1]
    }

    /// Triangle `i`'s index into `vertex_normals` if it is smooth, [`Triangles::FLAT`]
    /// otherwise.
    #[inline]
    pub fn shading(&self, i: usize) -> u32 {
        // Without smooth triangles none is one: no run is searched.
        if self.vertex_normals.is_empty() {
            return Self::FLAT;
        }
        let run = self.run(i);
        match run.normals {
            Self::FLAT => Self::FLAT,
            normals => normals + (i as u32 - run.first),
        }
    }

    /// The index the next of `n` vertices will take.
    fn first_free_vertex(&self, n: usize) -> u32 {
        u32::try_from(self.positions.len() + n)
            .map(|_| self.positions.len() as u32)
            .expect("at most u32::MAX triangle vertices")
    }

    /// The vertices of triangle `i`.
    #[inline(always)]
    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        self.corners[i].map(|c| self.positions[c as usize])
    }

    /// The edges `p1 - p0` and `p2 - p0` of triangle `i`, and its vertex `p0`.
    #[inline(always)]
    fn edges(&self, i: usize) -> ([Vec3; 2], Vec3) {
        let [p0, p1, p2] = self.vertices(i);
        ([p1 - p0, p2 - p0], p0)
    }

    /// Unit geometric normal `normalize((p1 - p0) x (p2 - p0))`.
    pub fn geometric_normal(&self, i: usize) -> Vec3 {
        let ([e1, e2], _) = self.edges(i);
        e1.cross(e2).normalize_or_zero()
    }

    /// [`Shapes::normal`] at `(u, v)`, with the geometric normal made by `geometric` only
    /// where it is needed, so that a caller holding `e1 x e2` need not take it again.
    fn shading_normal(&self, shading: u32, u: f32, v: f32, geometric: impl Fn() -> Vec3) -> Vec3 {
        match shading {
            Self::FLAT => geometric(),
            k => {
                let n = self.vertex_normals[k as usize];
                ((1.0 - u - v) * n[0] + u * n[1] + v * n[2])
                    .try_normalize()
                    .unwrap_or_else(geometric)
            }
        }
    }
}

impl LeafPack for Triangles {
    type Pack = TrianglePack8;
    type Compact = MeshPack8;
    const HAS_COMPACT: bool = true;
    /// Where the full packs would pass 150 MB. Mesh packs hold 14 bytes a triangle less
    /// for more work: `bench`, EPYC-512, best paths, `gen mount --level 10` and `11`
    /// 0.94-0.99 of the full packs' speed (reflection at level 10: 0.995-1.02); the
    /// dragon 0.95-0.98; AVX2, `mount_very_high` and the dragon 0.90-0.95.
    const COMPACT_FROM: usize = 1 << 22;
}

impl PackOf<Triangles> for TrianglePack8 {
    fn pack(storage: &Triangles, indices: impl Iterator<Item = usize>) -> Option<TrianglePack8> {
        let (triangles, n) = gather8(indices.map(|i| storage.vertices(i)));
        Some(TrianglePack8::new(&triangles[..n]))
    }

    const FRAMED: bool = true;

    #[inline(always)]
    fn leaf<const FRAME: usize>(pack: &TrianglePack8, query: &RayQuery, t_max: f32) -> ShapeHit8 {
        leaf_hits::<FRAME>(query, pack, t_max)
    }

    type Slots<'a> = &'a TrianglePack8;

    #[inline(always)]
    fn slots(pack: &TrianglePack8) -> &TrianglePack8 {
        pack
    }

    #[inline(always)]
    fn slot_packet(
        pack: &TrianglePack8,
        slot: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        slot_hits(&pack.vertices, slot, query, t_max, active)
    }
}

impl Shapes for Triangles {
    fn len(&self) -> usize {
        self.corners.len()
    }

    fn shrink_to_fit(&mut self) {
        self.positions.shrink_to_fit();
        self.corners.shrink_to_fit();
        self.runs.shrink_to_fit();
        self.vertex_normals.shrink_to_fit();
    }

    fn material(&self, i: usize) -> u32 {
        self.run(i).material
    }

    fn bounds(&self, i: usize, _shutter: [f32; 2]) -> Aabb {
        corner_box(self.vertices(i)).unwrap_or(Aabb::EMPTY)
    }

    #[inline]
    fn intersect(&self, i: usize, query: &RayQuery, t_max: f32) -> Option<ShapeHit> {
        triangle_hit(query, self.vertices(i), t_max)
    }

    fn intersect_packet(
        &self,
        i: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        let vertices = self.vertices(i);
        triangle_packet(query, vertices, query.t_min_lanes(), t_max, active)
    }

    /// The geometric normal of P3F.md section 2 (triangles have no inside), or for smooth
    /// triangles the vertex normals interpolated at `(u, v)`.
    fn normal(&self, i: usize, _p: Vec3, u: f32, v: f32, _time: f32) -> Vec3 {
        self.shading_normal(self.shading(i), u, v, || self.geometric_normal(i))
    }

    fn geometric_normal64(&self, i: usize, _p: DVec3, _u: f32, _v: f32) -> DVec3 {
        let ([e1, e2], _) = self.edges(i);
        e1.cross(e2).as_dvec3().normalize()
    }

    /// `p0 + u e1 + v e2` (`e1 = p1 - p0`, `e2 = p2 - p0`), a point of the triangle's plane
    /// whatever `u` and `v` are. Its sum is off by `gamma(7)` of its terms, as pbrt-v4
    /// bounds its triangles' points. A ray leaving it must not meet the triangle again. The
    /// watertight test's `t` has the sign of the triple product of the vertices relative to
    /// the ray's origin (`a`, `b`, `c`), which is `|e1 x e2|` times the origin's height over
    /// the plane; rounding the vertices into the ray's frame moves that product by up to
    /// `13.4 eps (w |a| + u |b| + v |c|) |e1 x e2|`, and rounding the edge functions by up
    /// to `12 eps |a| |b| |c|` (`eps` the unit roundoff, `w = 1 - u - v`). So the bound adds
    /// `self_hit_margin`, the height those come to (the second grows for a needle, a
    /// triangle with one short side). Random triangles, slivers and needles among them,
    /// met again from their own points in random directions, came to a third of it at
    /// most.
    #[inline]
    fn surface_point(&self, i: usize, _ray: &Ray, _t: f32, u: f32, v: f32) -> SurfacePoint {
        let ([e1, e2], p0) = self.edges(i);
        let (along1, along2) = (u * e1, v * e2);
        let point = p0 + along1 + along2;
        // One cross product for the bound's area and the normal.
        let cross = e1.cross(e2);
        let area = cross.length();
        let along = along1 + along2;
        let margin = self_hit_margin(
            [along, along - e1, along - e2].map(Vec3::length),
            [1.0 - u - v, u, v],
            area,
        );
        SurfacePoint {
            point,
            error: gamma(7) * (p0.abs() + along1.abs() + along2.abs()) + Vec3::splat(margin),
            normal: self.shading_normal(self.shading(i), u, v, || cross.normalize_or_zero()),
        }
    }

    /// The flat triangles' points eight at a time; a smooth one's lane (vertex normals)
    /// is left to [`Shapes::surface_point`].
    fn surface_points8(&self, indices: [usize; 8], rays: &[Ray; 8], hits: &Hits8) -> SurfacePoint8 {
        // Gathered corner by corner: the corners' loads first, then the vertices'.
        let corners = indices.map(|i| self.corners[i]);
        let mut lanes = [[Vec3::ZERO; 8]; 3];
        for (k, corner) in corners.iter().enumerate() {
            for (lane, &c) in lanes.iter_mut().zip(corner) {
                lane[k] = self.positions[c as usize];
            }
        }
        let [p0, p1, p2] = lanes.map(Vec3x8::from_lanes);
        let (e1, e2) = (p1 - p0, p2 - p0);
        let (u, v) = (F32x8::from_array(hits.u), F32x8::from_array(hits.v));
        let (along1, along2) = (e1.scale(u), e2.scale(v));
        let point = p0 + along1 + along2;
        let cross = e1.cross(e2);
        let area = cross.length();
        let along = along1 + along2;
        let margin = self_hit_margin8(
            [along, along - e1, along - e2].map(|d| d.length()),
            [F32x8::splat(1.0) - u - v, u, v],
            area,
        );
        let sum = p0.abs() + along1.abs() + along2.abs();
        let error = sum.scale(F32x8::splat(gamma(7))) + Vec3x8::from_components(margin);
        // `normalize_or_zero`: the cross product over its length where that is a number.
        let rcp = F32x8::splat(1.0) / area;
        let normal =
            (rcp.is_finite() & rcp.gt(F32x8::ZERO)).select_vec(cross.scale(rcp), Vec3x8::ZERO);
        let mut points = SurfacePoint8 {
            point,
            error,
            normal,
        };
        for (k, &i) in indices.iter().enumerate() {
            if self.shading(i) != Self::FLAT {
                let scalar = self.surface_point(i, &rays[k], hits.t[k], hits.u[k], hits.v[k]);
                points.set_lane(k, scalar);
            }
        }
        points
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triangle `(0, 0, 0), (1, 0, 0), (0, 1, 0)`.
    const UNIT: [Vec3; 3] = [Vec3::ZERO, Vec3::X, Vec3::Y];

    fn down_at(x: f32, y: f32) -> Ray {
        Ray::new(Vec3::new(x, y, 2.0), Vec3::new(0., 0., -1.))
    }

    #[test]
    fn a_packs_trusted_boxes_are_each_slots() {
        let max = Vec3::splat(f32::MAX);
        let triangles = [
            UNIT,
            [
                Vec3::new(-3.0, 2.5, 1e-3),
                Vec3::new(-3.0, 2.5, 4.0),
                Vec3::new(-5.0, 2.5, 1e-3),
            ],
            [
                Vec3::splat(1e9),
                Vec3::new(1e9 - 64.0, 1e9 + 128.0, 1e9),
                Vec3::new(1e9, 1e9, 1e9 - 1e3),
            ],
            [Vec3::NAN; 3],
            // A vertex beyond the floats: no box.
            [max, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::Y],
        ];
        let (boxes, slots) = trusted8(&TrianglePack8::new(&triangles).vertices);
        let trusted_box = |slot: usize| {
            (slots.bitmask() & 1 << slot != 0).then(|| Aabb {
                min: boxes.min.lane(slot),
                max: boxes.max.lane(slot),
            })
        };
        let bits =
            |b: Option<Aabb>| b.map(|b| [b.min, b.max].map(|c| c.to_array().map(f32::to_bits)));
        for (slot, &triangle) in triangles.iter().enumerate() {
            assert_eq!(
                bits(trusted_box(slot)),
                bits(trusted_triangle_box(triangle))
            );
        }
        assert_eq!(trusted_box(3), None);
        assert_eq!(trusted_box(4), None);
        assert_eq!(trusted_box(7), None);
    }

    #[test]
    fn hits_interior_with_barycentrics() {
        let h = triangle(&down_at(0.25, 0.5), UNIT, 0.0, f32::INFINITY).unwrap();
        assert_eq!(h.t, 2.0);
        assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
    }

    #[test]
    fn two_sided() {
        let up = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z);
        assert_eq!(triangle(&up, UNIT, 0.0, 9.0).unwrap().t, 1.0);
    }

    #[test]
    fn edges_and_vertices_are_inside() {
        for (x, y) in [
            (0.5, 0.0),
            (0.0, 0.5),
            (0.5, 0.5),
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
        ] {
            assert!(
                triangle(&down_at(x, y), UNIT, 0.0, 9.0).is_some(),
                "({x}, {y}) should be on the triangle"
            );
        }
        for (x, y) in [(-1e-4, 0.5), (0.5, -1e-4), (0.5001, 0.5), (1.0001, 0.0)] {
            assert!(
                triangle(&down_at(x, y), UNIT, 0.0, 9.0).is_none(),
                "({x}, {y}) should be off the triangle"
            );
        }
    }

    /// An edge function that single precision rounds to zero is taken again in double
    /// precision, which gives its sign: the ray just beside the edge misses.
    #[test]
    fn a_zero_edge_function_gets_its_exact_sign() {
        // Sheared points whose products round alike in single precision.
        let (a, b) = ([1.0 + f32::EPSILON, 1.0], [1.0, 1.0 - f32::EPSILON]);
        assert_eq!(edge(a, b), 0.0);
        let exact = exact_edges([a, b, [0.0, -1.0]]);
        assert_eq!(exact[2], f32::EPSILON * f32::EPSILON, "{exact:?}");
        // The two triangles of a square share its diagonal; a ray down through a point of
        // the diagonal whose products round alike meets both, and one beside it just one.
        let square = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let (lower, upper) = (
            [square[0], square[1], square[2]],
            [square[0], square[2], square[3]],
        );
        for x in [1.0 / 3.0, 0.1, 0.7, 0.999_999_9] {
            let on = down_at(x, x);
            assert!(triangle(&on, lower, 0.0, 9.0).is_some(), "{x}");
            assert!(triangle(&on, upper, 0.0, 9.0).is_some(), "{x}");
            let beside = down_at(x, f32::from_bits(x.to_bits() + 1));
            let hits = [lower, upper].map(|t| triangle(&beside, t, 0.0, 9.0).is_some());
            assert_eq!(hits, [false, true], "{x}");
        }
    }

    /// Reversing an edge negates its function exactly, whatever the rounding (a zero
    /// stays `+0.0`).
    #[test]
    fn an_edge_reversed_is_negated_exactly() {
        let points = [
            [0.1f32, 0.7],
            [1e-3, -3.3],
            [1.0 / 3.0, 2.0 / 3.0],
            [-7.25e4, 1e-7],
        ];
        for p in points {
            for q in points {
                assert_eq!(edge(p, q), -edge(q, p), "{p:?} {q:?}");
            }
        }
    }

    #[test]
    fn parallel_ray_and_degenerate_triangle_miss() {
        let parallel = Ray::new(Vec3::new(-1., 0.2, 0.), Vec3::X);
        assert_eq!(triangle(&parallel, UNIT, 0.0, 9.0), None);
        let line = [Vec3::ZERO, Vec3::X, 2.0 * Vec3::X];
        assert_eq!(triangle(&down_at(0.5, 0.0), line, 0.0, 9.0), None);
        assert_eq!(
            triangle(&down_at(0.0, 0.0), [Vec3::ZERO; 3], 0.0, 9.0),
            None
        );
        assert_eq!(triangle(&down_at(0.0, 0.0), [Vec3::NAN; 3], 0.0, 9.0), None);
    }

    #[test]
    fn degenerate_triangles_are_stored_as_nan() {
        let mut triangles = Triangles::default();
        triangles.push([Vec3::ZERO, Vec3::X, 2.0 * Vec3::X], None, 0);
        triangles.push(UNIT, None, 0);
        assert!(triangles.vertices(0)[0].is_nan());
        assert_eq!(triangles.vertices(1), UNIT);
        assert_eq!(triangles.bounds(0, [0.0; 2]), Aabb::EMPTY);
    }

    #[test]
    fn each_triangle_keeps_its_material_and_normals_in_runs() {
        // (material, smooth) of each triangle pushed: runs begin and end at every change.
        let pushed = [
            (0, false),
            (0, false),
            (1, false),
            (1, true),
            (1, true),
            (2, true),
            (2, false),
            (2, true),
            (0, false),
        ];
        let mut triangles = Triangles::default();
        let mut smooth = 0;
        let mut expected = Vec::new();
        for (k, &(material, is_smooth)) in pushed.iter().enumerate() {
            let normals = is_smooth.then(|| [Vec3::splat(k as f32); 3]);
            triangles.push(UNIT, normals, material);
            if is_smooth {
                expected.push(smooth);
                smooth += 1;
            } else {
                expected.push(Triangles::FLAT);
            }
        }
        assert_eq!(triangles.runs.len(), 7);
        for (i, &(material, _)) in pushed.iter().enumerate() {
            assert_eq!(triangles.material(i), material, "triangle {i}");
            assert_eq!(triangles.shading(i), expected[i], "triangle {i}");
        }
        // The normals are each smooth triangle's own.
        let n = triangles.normal(4, Vec3::ZERO, 0.2, 0.3, 0.0);
        assert_eq!(n, Vec3::splat(1.0).normalize());
    }

    #[test]
    fn behind_and_beyond_are_misses() {
        let away = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::Z);
        assert_eq!(triangle(&away, UNIT, 0.0, 9.0), None);
        assert_eq!(triangle(&down_at(0.2, 0.2), UNIT, 0.0, 1.5), None);
    }

    /// Each axis can be a ray's `z`, and the test answers alike in every frame.
    #[test]
    fn every_frame_finds_the_hit() {
        let dirs = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z];
        for dir in dirs {
            let frame = FRAMES[frame_of(dir)];
            assert_eq!(frame[2] as usize, dir.abs().max_position());
            // A triangle across the ray, two units ahead.
            let centre = 2.0 * dir;
            let (s, r) = (
                dir.any_orthonormal_vector(),
                dir.cross(dir.any_orthonormal_vector()),
            );
            let tri = [centre - s - r, centre + 2.0 * s, centre + 2.0 * r];
            let hit = triangle(&Ray::new(Vec3::ZERO, dir), tri, 0.0, 9.0).unwrap();
            assert_eq!(hit.t, 2.0, "{dir}");
        }
    }
}
