//! The box test of every acceleration structure: where a ray may be inside an
//! axis-aligned box, as the interval `[entry, exit]`, allowing for its own rounding (pbrt-v4's
//! `Bounds3::IntersectP` with its `1 + 2 gamma(3)`). The BVH nodes (both widths, one ray
//! or a packet) and the grid's bounds all take it from here.
//!
//! It is not the Box primitive's test ([`aabb`](fn@super::aabb)), and the two must
//! differ. A primitive test answers where the ray meets the surface: exact, and a ray
//! passing beside the box misses. A node test answers whether a box may hold anything
//! the ray meets: it must never say no when the objects' own tests, with their own
//! rounding, would find a hit inside, so it errs towards visiting. A ray from far away
//! (1e9 units, where floats are 64 apart) shows the difference: the slab distances are
//! off by up to `GAMMA_3` of themselves, enough to pass beside a box the objects' tests
//! find the ray in (`tests/integration/fuzz_findings.rs`).
//!
//! **Per-ray setup.** [`BoxRay`] (one ray) and [`BoxRays`] (a packet) are built once per
//! ray, as Embree's `TravRay` is: the origin and a safe inverse direction, whose
//! infinite components (a ray parallel to an axis) are clamped to `±f32::MAX` (as
//! Embree's `rcp_safe` keeps them finite). So no slab distance is NaN: the `0 * inf` of a
//! ray lying in a slab's plane becomes `±0`, so that ray is in the slab on the side its
//! zero's sign points to (it passes where that points into the box, and leaves at
//! `t = 0` where it points out), and a parallel ray beside the slab gets two distances
//! of one sign and misses. No hit lies on a face of a structure's box (every primitive's
//! box is padded, `accel::bounds`), so either answer for such a ray finds every hit; a
//! branch-free NaN rule that lets it pass on both faces cost 1.4% more instructions on
//! the protocol (a second traversal loop per kind of ray). Finite inverse directions are
//! kept as they are, so every other ray's distances are the bare slab test's.
//!
//! **NaN convention.** Only NaN corners (the padding of a pack) or a NaN `t_min` or
//! `t_max` give NaN. The clipping, `if t > entry { t } else { entry }` and
//! `if t < exit { t } else { exit }` (`maxps`/`minps`), keeps the clipped end when `t` is
//! NaN, so padding boxes are entered and their callers leave them out of the lanes they
//! keep; a NaN `t_min` or `t_max` is a miss. The rule is one instruction per step in the
//! SIMD twins, where a NaN-dropping min or max takes four, and it gives one answer for
//! `-0.0` against `0.0`, which a bit-exact twin needs.
//!
//! **The allowance.** Each slab distance `(corner - origin) * inv_dir` is off by up to
//! `GAMMA_3` of itself, the entry one way and the exit the other, so the exit is widened
//! by `2 GAMMA_3` of itself ([`widen_exit`]) before it is compared with the entry. The
//! traversals skip a stacked box whose entry lies [`beyond`] the closest hit by the same
//! rule, and the grid, which walks from the entry, steps back by the same allowance
//! ([`widen_entry`]). The distances of a traversal are never negative (`t_min >= 0`), so
//! the widenings are plain products.
//!
//! The SIMD twins ([`BoxRay::intervals8`], one ray against eight boxes, and
//! [`BoxRays::interval`], a packet's rays against one box) repeat the scalar arithmetic in
//! the same order, so each lane equals [`BoxRay::interval`] bit for bit
//! (`tests/integration/simd.rs`).

use glam::Vec3;

use super::{BoxPack8, GAMMA_3};
use crate::ray::RayPacket;
use crate::simd::{
    F32x8, F32xP, Floats, LaneBits, LaneMask, Mask8, MaskP, Vec3Lanes, Vec3x8, Vec3xP,
};

/// The rounding a box test allows for: twice the error bound of a slab distance.
const ALLOWANCE: f32 = 2.0 * GAMMA_3;

/// The latest distance a ray may still be in a box whose computed exit is `t` (or on the
/// closest hit found at `t`).
#[inline]
pub fn widen_exit(t: f32) -> f32 {
    t * (1.0 + ALLOWANCE)
}

/// The earliest distance a ray may already be in a box whose computed entry is `t >= 0`.
#[inline]
pub fn widen_entry(t: f32) -> f32 {
    t * (1.0 - ALLOWANCE)
}

/// Whether a stacked box entered at `entry` lies beyond the closest hit at `limit`, and
/// so cannot hold a closer hit or a tie: the skip rule of every traversal stack.
#[inline]
pub fn beyond(entry: f32, limit: f32) -> bool {
    entry > widen_exit(limit)
}

/// [`beyond`] lane by lane: the lanes whose `limit` the entry `entry` lies beyond.
#[inline]
pub fn beyond_lanes<F: Floats>(entry: F, limit: F) -> F::Mask {
    entry.gt(widen_exit_lanes(limit))
}

/// [`widen_exit`] lane by lane.
#[inline(always)]
fn widen_exit_lanes<F: Floats>(t: F) -> F {
    t * F::splat(1.0 + ALLOWANCE)
}

/// `if a > b { a } else { b }`: the `maxps` rule, so a NaN `a` keeps `b`.
#[inline(always)]
fn greater(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// `if a < b { a } else { b }`: the `minps` rule, so a NaN `a` keeps `b`.
#[inline(always)]
fn lesser(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// One ray set up for box tests.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    origin: Vec3,
    /// `1 / dir` with infinities clamped to `±f32::MAX`.
    inv_dir: Vec3,
}

/// `t` with `±inf` clamped to `±f32::MAX`: `0 * t` is then 0, never NaN.
#[inline(always)]
fn clamp_infinite(t: f32) -> f32 {
    lesser(greater(t, -f32::MAX), f32::MAX)
}

/// [`clamp_infinite`] on each lane of each component (`maxps` and `minps` take the same
/// branches as `greater` and `lesser`).
#[inline(always)]
fn clamp_infinite_lanes<F: Floats>(v: Vec3Lanes<F>) -> Vec3Lanes<F> {
    let clamp = |t: F| t.max(F::splat(-f32::MAX)).min(F::splat(f32::MAX));
    Vec3Lanes {
        x: clamp(v.x),
        y: clamp(v.y),
        z: clamp(v.z),
    }
}

impl BoxRay {
    /// The setup of the ray from `origin` with `inv_dir = 1 / dir`.
    #[inline]
    pub fn new(origin: Vec3, inv_dir: Vec3) -> Self {
        BoxRay {
            origin,
            inv_dir: Vec3::new(
                clamp_infinite(inv_dir.x),
                clamp_infinite(inv_dir.y),
                clamp_infinite(inv_dir.z),
            ),
        }
    }

    /// The interval `[entry, exit]` in which the ray may be inside the box `[min, max]`
    /// within `[t_min, t_max]`, its exit widened by the allowance; `None` if it is empty.
    #[inline]
    pub fn interval(&self, min: Vec3, max: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let mut entry = t_min;
        let mut exit = t_max;
        for k in 0..3 {
            let t1 = (min[k] - self.origin[k]) * self.inv_dir[k];
            let t2 = (max[k] - self.origin[k]) * self.inv_dir[k];
            entry = greater(lesser(t1, t2), entry);
            exit = lesser(greater(t1, t2), exit);
        }
        let exit = widen_exit(exit);
        (entry <= exit).then_some((entry, exit))
    }

    /// Whether a hit at `t` lies where the structures look for it in the box `[min,
    /// max]`: in its interval from `t_min` on, as [`BoxRay::interval`] computes it, and
    /// its entry not [`beyond`] `t`. Every box above it in a structure holds it, so a
    /// structure enters every such box before its closest hit (`accel::bounds`).
    #[inline]
    pub fn holds(&self, min: Vec3, max: Vec3, t_min: f32, t: f32) -> bool {
        self.interval(min, max, t_min, f32::INFINITY)
            .is_some_and(|(entry, exit)| !beyond(entry, t) && t <= exit)
    }

    /// [`BoxRay::holds`] for the eight boxes of `boxes`, lane `k` with the hit `t[k]`.
    #[inline]
    pub fn holds8(&self, boxes: &BoxPack8, t_min: f32, t: F32x8) -> Mask8 {
        self.intervals8(boxes, t_min, f32::INFINITY).holds(t)
    }

    /// [`BoxRay::interval`] against the eight boxes of a pack (the children of an
    /// eight-wide node), every lane. No box value is inert here (NaN corners are a slab
    /// ignored), so the caller masks out the padding with the lanes it asks about.
    #[inline]
    pub fn intervals8(&self, boxes: &BoxPack8, t_min: f32, t_max: f32) -> Intervals8 {
        let lanes = Lanes {
            origin: Vec3x8::splat(self.origin),
            inv_dir: Vec3x8::splat(self.inv_dir),
            min: boxes.min,
            max: boxes.max,
            t_min: F32x8::splat(t_min),
            t_max: F32x8::splat(t_max),
        };
        lanes.clip()
    }
}

/// [`BoxRay::holds`] for eight rays and eight boxes, lane by lane: ray `k` (from
/// `origin[k]`, with `inv_dir[k] = 1 / dir[k]`) against box `k` of `boxes`, with the hit
/// `t[k]`, from `t_min`.
#[inline]
pub fn holds_lanes8(
    origin: Vec3x8,
    inv_dir: Vec3x8,
    boxes: &BoxPack8,
    t_min: f32,
    t: F32x8,
) -> Mask8 {
    intervals_lanes8(origin, inv_dir, boxes, t_min).holds(t)
}

/// [`BoxRay::interval`] over `(t_min, inf)` for eight rays and eight boxes, paired lane by
/// lane as [`holds_lanes8`] pairs them.
#[inline]
pub fn intervals_lanes8(
    origin: Vec3x8,
    inv_dir: Vec3x8,
    boxes: &BoxPack8,
    t_min: f32,
) -> Intervals8 {
    let lanes = Lanes {
        origin,
        inv_dir: clamp_infinite_lanes(inv_dir),
        min: boxes.min,
        max: boxes.max,
        t_min: F32x8::splat(t_min),
        t_max: F32x8::splat(f32::INFINITY),
    };
    lanes.clip()
}

/// A packet's rays set up for box tests together: [`BoxRay`] lane by lane.
#[derive(Clone, Copy, Debug)]
pub struct BoxRays {
    origin: Vec3xP,
    /// `1 / dir` with infinities clamped to `±f32::MAX`, lane by lane.
    inv_dir: Vec3xP,
}

impl BoxRays {
    /// The setup of the packet's rays, with the `inv_dir` it holds.
    #[inline]
    pub fn new(rays: &RayPacket) -> Self {
        BoxRays {
            origin: rays.origin,
            inv_dir: clamp_infinite_lanes(rays.inv_dir),
        }
    }

    /// [`BoxRay::holds`] for each ray against the box `[min, max]`, lane `k` with its
    /// own `t_min` and hit `t`.
    #[inline]
    pub fn holds(&self, min: Vec3, max: Vec3, t_min: F32xP, t: F32xP) -> MaskP {
        self.interval(min, max, t_min, F32xP::splat(f32::INFINITY))
            .holds(t)
    }

    /// The lanes `lanes` as one [`RayRange`], if their directions agree in sign.
    #[inline]
    pub fn range(&self, lanes: LaneBits) -> Option<RayRange> {
        if lanes == 0 {
            return None;
        }
        let keep = MaskP::from_bitmask(lanes);
        // Per axis, `pick` of the kept lanes, the others filled with what it ignores.
        let reduce = |v: Vec3xP, fill: f32, pick: fn(F32xP) -> f32| {
            let fill = F32xP::splat(fill);
            Vec3::new(
                pick(keep.select(v.x, fill)),
                pick(keep.select(v.y, fill)),
                pick(keep.select(v.z, fill)),
            )
        };
        let least = |v| reduce(v, f32::INFINITY, F32xP::min_lane);
        let most = |v| reduce(v, f32::NEG_INFINITY, F32xP::max_lane);
        RayRange::from_bounds(
            [least(self.origin), most(self.origin)],
            [least(self.inv_dir), most(self.inv_dir)],
        )
    }

    /// [`BoxRay::interval`] for each ray against the box `[min, max]` (packet
    /// traversal), every lane: the caller keeps the lanes it asks about, so that a node's
    /// children share one mask operation (a bit `and` on the answer).
    #[inline]
    pub fn interval(&self, min: Vec3, max: Vec3, t_min: F32xP, t_max: F32xP) -> Intervals<F32xP> {
        let lanes = Lanes {
            origin: self.origin,
            inv_dir: self.inv_dir,
            min: Vec3xP::splat(min),
            max: Vec3xP::splat(max),
            t_min,
            t_max,
        };
        lanes.clip()
    }
}

/// The rays of a packet as one ray of intervals (interval arithmetic, as in Wald, Boulos
/// and Shirley's coherent BVH traversal): on each axis the range of the lanes' origins
/// and of their inverse directions, which must share a sign. Its box test says whether
/// any of those lanes may enter a box, never no where [`BoxRays::interval`] says yes for
/// one of them: on an axis where the directions are positive, every lane's entry slab
/// distance `(min - o) * inv` is at least `(min - o_hi) * inv` (rounding is monotone),
/// which is at least the smaller of its products with the two ends of the inverse
/// directions' range; the exit and negative axes likewise. So a traversal may skip the
/// boxes it rejects for every lane, and test the lanes of the rest one by one; and the
/// range's entry into a box, the largest of those bounds, lies below every lane's.
#[derive(Clone, Copy, Debug)]
pub struct RayRange {
    /// Per axis, the origin that gives the smallest entry distance (the largest origin
    /// where the directions are positive, the smallest where negative).
    entry_origin: Vec3,
    /// Per axis, the origin that gives the largest exit distance.
    exit_origin: Vec3,
    inv_lo: Vec3,
    inv_hi: Vec3,
    /// Bit `k` set where the directions are negative on axis `k`: rays enter through
    /// `max`. One byte, stored once: three flags stored apart and read as one word wait
    /// for their stores to reach the cache (no store forwarding).
    negative: u8,
}

impl RayRange {
    /// The range of rays whose origins lie within `[o_lo, o_hi]` and whose (clamped)
    /// inverse directions lie within `[inv_lo, inv_hi]`, or `None` when on some axis the
    /// directions differ in sign.
    fn from_bounds([o_lo, o_hi]: [Vec3; 2], [inv_lo, inv_hi]: [Vec3; 2]) -> Option<Self> {
        let (mut entry_origin, mut exit_origin, mut negative) = (o_hi, o_lo, 0);
        for k in 0..3 {
            // Clamped inverse directions are never zero, so each lies on one side.
            match (inv_lo[k] > 0.0, inv_hi[k] < 0.0) {
                (true, _) => {}
                (_, true) => {
                    negative |= 1 << k;
                    entry_origin[k] = o_lo[k];
                    exit_origin[k] = o_hi[k];
                }
                _ => return None,
            }
        }
        Some(RayRange {
            entry_origin,
            exit_origin,
            inv_lo,
            inv_hi,
            negative,
        })
    }

    /// A box's bounds on axis `k` as the rays meet them: the one they enter through,
    /// then the one they leave through.
    #[inline(always)]
    fn near_far<T>(&self, k: usize, min: T, max: T) -> (T, T) {
        if self.negative >> k & 1 != 0 {
            (max, min)
        } else {
            (min, max)
        }
    }

    /// Whether any of the rays may be inside the box `[min, max]` (with `min <= max`)
    /// within `[t_min, t_max]`, `t_max` the largest of the lanes': if so, a bound that
    /// no lane's entry ([`BoxRays::interval`]) lies below.
    #[inline]
    pub fn entry(&self, min: Vec3, max: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let mut entry = t_min;
        let mut exit = t_max;
        for k in 0..3 {
            let (near, far) = self.near_far(k, min[k], max[k]);
            let a = near - self.entry_origin[k];
            let b = far - self.exit_origin[k];
            entry = greater(lesser(a * self.inv_lo[k], a * self.inv_hi[k]), entry);
            exit = lesser(greater(b * self.inv_lo[k], b * self.inv_hi[k]), exit);
        }
        (entry <= widen_exit(exit)).then_some(entry)
    }

    /// [`RayRange::entry`] for the eight boxes of a pack: the boxes entered as a bit mask
    /// (padding slots may be set: the caller masks them out), and their entry bounds
    /// (unspecified in the other slots).
    #[inline]
    pub fn entries8(&self, boxes: &BoxPack8, t_min: f32, t_max: f32) -> (u8, [f32; 8]) {
        let mut entry = F32x8::splat(t_min);
        let mut exit = F32x8::splat(t_max);
        let axes = [
            (boxes.min.x, boxes.max.x),
            (boxes.min.y, boxes.max.y),
            (boxes.min.z, boxes.max.z),
        ];
        for (k, (min, max)) in axes.into_iter().enumerate() {
            let (near, far) = self.near_far(k, min, max);
            let a = near - F32x8::splat(self.entry_origin[k]);
            let b = far - F32x8::splat(self.exit_origin[k]);
            let (lo, hi) = (F32x8::splat(self.inv_lo[k]), F32x8::splat(self.inv_hi[k]));
            entry = (a * lo).min(a * hi).max(entry);
            exit = (b * lo).max(b * hi).min(exit);
        }
        (entry.le(widen_exit_lanes(exit)).bitmask(), entry.to_array())
    }
}

/// Intervals lane by lane: the lanes that hit, and their entries and widened exits
/// (unspecified in the other lanes).
#[derive(Clone, Copy, Debug)]
pub struct Intervals<F: Floats> {
    pub hit: F::Mask,
    pub entry: F,
    pub exit: F,
}

/// Eight intervals: a node's children, or a pack's boxes, against one ray.
pub type Intervals8 = Intervals<F32x8>;

impl<F: Floats> Intervals<F> {
    /// The rule of [`BoxRay::holds`] lane by lane: the hit `t[k]` lies in interval `k`.
    #[inline(always)]
    fn holds(&self, t: F) -> F::Mask {
        (self.hit & t.le(self.exit)).and_not(beyond_lanes(self.entry, t))
    }
}

/// The operands of [`BoxRay::interval`], lane by lane.
struct Lanes<F> {
    origin: Vec3Lanes<F>,
    inv_dir: Vec3Lanes<F>,
    min: Vec3Lanes<F>,
    max: Vec3Lanes<F>,
    t_min: F,
    t_max: F,
}

impl<F: Floats> Lanes<F> {
    /// The body of [`BoxRay::interval`], axes in the same order, `minps`/`maxps` as
    /// `lesser`/`greater`.
    #[inline(always)]
    fn clip(&self) -> Intervals<F> {
        let t1 = (self.min - self.origin) * self.inv_dir;
        let t2 = (self.max - self.origin) * self.inv_dir;
        let mut entry = self.t_min;
        let mut exit = self.t_max;
        for (t1, t2) in [(t1.x, t2.x), (t1.y, t2.y), (t1.z, t2.z)] {
            entry = t1.min(t2).max(entry);
            exit = t1.max(t2).min(exit);
        }
        let exit = widen_exit_lanes(exit);
        Intervals {
            hit: entry.le(exit),
            entry,
            exit,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const INF: f32 = f32::INFINITY;

    fn unit_box(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        BoxRay::new(origin, dir.recip()).interval(Vec3::ZERO, Vec3::ONE, t_min, t_max)
    }

    #[test]
    fn entry_and_widened_exit() {
        let (entry, exit) = unit_box(Vec3::new(0.5, 0.5, -2.0), Vec3::Z, 0.0, INF).unwrap();
        assert_eq!((entry, exit), (2.0, widen_exit(3.0)));
        assert!(exit > 3.0);
        // From inside, the entry is `t_min`; backwards through the `max` face.
        let inside = unit_box(Vec3::splat(0.5), Vec3::NEG_X, 0.0, INF).unwrap();
        assert_eq!(inside, (0.0, widen_exit(0.5)));
        assert_eq!(
            unit_box(Vec3::new(0.5, 0.5, 3.0), Vec3::NEG_Z, 0.0, INF)
                .unwrap()
                .0,
            2.0
        );
        // Behind, beside, and beyond `t_max`.
        assert_eq!(unit_box(Vec3::new(0.5, 0.5, 2.0), Vec3::Z, 0.0, INF), None);
        assert_eq!(unit_box(Vec3::new(2.0, 0.5, -2.0), Vec3::Z, 0.0, INF), None);
        assert_eq!(unit_box(Vec3::new(0.5, 0.5, -2.0), Vec3::Z, 0.0, 1.5), None);
        assert_eq!(unit_box(Vec3::new(0.5, 0.5, -2.0), Vec3::Z, 0.0, NAN), None);
    }

    const NAN: f32 = f32::NAN;

    /// A ray running in the plane of a face (zero direction component, origin on the
    /// face) gets no NaN: it is in the slab from `-inf` (or `t = 0`) to `t = 0` (or
    /// `inf`), by the sign of its zero. So it passes where that sign points into the
    /// box, and leaves at 0 where it points out; a ray beside the slab misses either way.
    #[test]
    fn a_ray_in_a_face_plane_takes_the_side_its_zero_points_to() {
        for (face, zero, passes) in [
            (0.0, 0.0, true),
            (0.0, -0.0, false),
            (1.0, -0.0, true),
            (1.0, 0.0, false),
        ] {
            let origin = Vec3::new(face, 0.5, -2.0);
            let dir = Vec3::new(zero, 0.0, 1.0);
            let entry = unit_box(origin, dir, 0.0, 10.0).map(|i| i.0);
            let expected = passes.then_some(2.0);
            assert_eq!(entry, expected, "face x = {face}, dir.x = {zero:?}");
            let beside = Vec3::new(face + if face == 0.0 { -0.5 } else { 0.5 }, 0.5, -2.0);
            assert_eq!(unit_box(beside, dir, 0.0, 10.0), None);
        }
    }

    /// The allowance: a box the computed distances put just beside the ray is still
    /// entered, and a stacked entry just past the closest hit is not skipped.
    #[test]
    fn the_allowance_keeps_a_grazing_box() {
        // Entry and exit computed one float apart the wrong way round.
        let t = 1e9f32;
        let (min, max) = (Vec3::new(t.next_up(), -1.0, -1.0), Vec3::new(2e9, 1.0, 1.0));
        let ray = BoxRay::new(Vec3::ZERO, Vec3::X.recip());
        assert!(ray.interval(min, max, 0.0, t).is_some());
        assert!(!beyond(t.next_up(), t));
        assert!(beyond(2.0 * t, t));
        assert!(widen_entry(t) < t && widen_exit(t) > t);
        assert_eq!((widen_entry(0.0), widen_exit(INF)), (0.0, INF));
    }
}
