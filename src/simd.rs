//! Eight-lane SIMD types for the intersection kernels and the shading of eight hits at a
//! time. This is the only module that imports `wide`: kernels see [`F32x8`], [`Mask8`]
//! and [`Vec3x8`] and nothing else, so the backing crate (or a hand-written fallback)
//! can change here alone.
//!
//! Every operation is IEEE-exact lane by lane (`+ - * /` and `sqrt` are correctly
//! rounded, as their scalar counterparts are) and nothing here fuses a multiply with an
//! add: the kernels must equal their scalar twins bit for bit, and `mul_add` rounds once
//! where the scalar code rounds twice. Where the scalar code calls glam (`dot`, `cross`,
//! `min`, `max`, `recip`), the operations here take glam's order, which is why glam's
//! version is pinned (`=0.34.2`, in `fuzz/` too): a release that reorders one would part
//! the twins.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::Vec3;
use wide::{f32x8, u32x8};

/// Eight `f32` lanes.
#[derive(Clone, Copy, Debug)]
pub struct F32x8(f32x8);

/// Eight lane flags (each lane all ones or all zeros), from comparisons.
#[derive(Clone, Copy, Debug)]
pub struct Mask8(f32x8);

/// Eight 3-vectors as structure of arrays: lane `i` is `(x[i], y[i], z[i])`.
#[derive(Clone, Copy, Debug)]
pub struct Vec3x8 {
    pub x: F32x8,
    pub y: F32x8,
    pub z: F32x8,
}

impl F32x8 {
    pub const ZERO: F32x8 = F32x8::splat(0.0);

    #[inline]
    pub const fn splat(value: f32) -> Self {
        F32x8(f32x8::splat(value))
    }

    #[inline]
    pub const fn from_array(lanes: [f32; 8]) -> Self {
        F32x8(f32x8::new(lanes))
    }

    #[inline]
    pub const fn to_array(self) -> [f32; 8] {
        self.0.to_array()
    }

    /// Lane `i`, read in place.
    #[inline]
    pub fn lane(&self, i: usize) -> f32 {
        self.0.as_array()[i]
    }

    /// Sets lane `i` in place (lanes written one by one cost no transposition after).
    #[inline]
    pub fn set_lane(&mut self, i: usize, value: f32) {
        self.0.as_mut_array()[i] = value;
    }

    /// Lane-wise `if self < rhs { self } else { rhs }`: the x86 `minps` rule, and glam's
    /// `Vec3::min`. NaN in either operand, or a tie such as `-0.0` against `0.0`, gives
    /// `rhs`.
    #[inline]
    pub fn min(self, rhs: Self) -> Self {
        // `minps` is exactly this rule (the unit tests pin it).
        F32x8(self.0.fast_min(rhs.0))
    }

    /// Lane-wise `if self > rhs { self } else { rhs }` (`maxps`, glam's `Vec3::max`).
    /// NaN in either operand, or a tie, gives `rhs`.
    #[inline]
    pub fn max(self, rhs: Self) -> Self {
        F32x8(self.0.fast_max(rhs.0))
    }

    /// The larger operand, ignoring a NaN one as `f32::max` does; a tie (`-0.0` against
    /// `0.0`) gives `rhs`, a rule `f32::max` leaves open. Scalar twin: `intersect::max_num`.
    #[inline]
    pub fn max_num(self, rhs: Self) -> Self {
        (self.gt(rhs) | rhs.is_nan()).select(self, rhs)
    }

    /// Correctly rounded square root (NaN for negative lanes), as `f32::sqrt`.
    #[inline]
    pub fn sqrt(self) -> Self {
        F32x8(self.0.sqrt())
    }

    /// Clears the sign bit, as `f32::abs`.
    #[inline]
    pub fn abs(self) -> Self {
        F32x8(self.0.abs())
    }

    /// The magnitude of `self` with the sign bit of `sign`, as `f32::copysign` (NaN
    /// operands included: only bits move).
    #[inline]
    pub fn copysign(self, sign: Self) -> Self {
        F32x8(self.0.copysign(sign.0))
    }

    /// The smallest lane, by [`F32x8::min`] between halves, then quarters, then pairs:
    /// where no lane is NaN, the least value (either zero where `-0.0` and `0.0` tie), as
    /// a fold of `f32::min` over the lanes gives.
    #[inline]
    pub fn min_lane(self) -> f32 {
        self.reduce(F32x8::min)
    }

    /// The largest lane, as [`F32x8::min_lane`] with [`F32x8::max`].
    #[inline]
    pub fn max_lane(self) -> f32 {
        self.reduce(F32x8::max)
    }

    /// `combine` of the lanes pairwise, by halves, quarters and pairs (shuffles).
    #[inline(always)]
    fn reduce(self, combine: impl Fn(F32x8, F32x8) -> F32x8) -> f32 {
        let a = self.to_array();
        let halves = combine(
            self,
            F32x8::from_array([a[4], a[5], a[6], a[7], a[0], a[1], a[2], a[3]]),
        );
        let b = halves.to_array();
        let quarters = combine(
            halves,
            F32x8::from_array([b[2], b[3], b[0], b[1], b[6], b[7], b[4], b[5]]),
        );
        let c = quarters.to_array();
        combine(
            quarters,
            F32x8::from_array([c[1], c[0], c[3], c[2], c[5], c[4], c[7], c[6]]),
        )
        .to_array()[0]
    }

    /// Ordered comparisons: a NaN lane compares false, as in scalar Rust.
    #[inline]
    pub fn lt(self, rhs: Self) -> Mask8 {
        Mask8(self.0.simd_lt(rhs.0))
    }

    #[inline]
    pub fn le(self, rhs: Self) -> Mask8 {
        Mask8(self.0.simd_le(rhs.0))
    }

    #[inline]
    pub fn gt(self, rhs: Self) -> Mask8 {
        Mask8(self.0.simd_gt(rhs.0))
    }

    #[inline]
    pub fn ge(self, rhs: Self) -> Mask8 {
        Mask8(self.0.simd_ge(rhs.0))
    }

    /// Equality (`-0.0 == 0.0`; NaN equals nothing).
    #[inline]
    pub fn eq(self, rhs: Self) -> Mask8 {
        Mask8(self.0.simd_eq(rhs.0))
    }

    #[inline]
    pub fn is_nan(self) -> Mask8 {
        Mask8(self.0.is_nan())
    }

    /// `self` raised to `exponent` lane by lane with `f32::powf` (the C library's
    /// `powf`, whose exact bits no vector form here reproduces) in the lanes of `lanes`,
    /// zero in the others.
    #[inline]
    pub fn powf(self, exponent: Self, lanes: Mask8) -> Self {
        let (base, exponent) = (self.to_array(), exponent.to_array());
        let mut power = [0.0; 8];
        for_lanes(lanes.bitmask(), |k| power[k] = base[k].powf(exponent[k]));
        F32x8::from_array(power)
    }

    /// The next float above each lane, as `f32::next_up` (NaN and infinity stay): one
    /// step of the lane's bits, away from zero for positive lanes, towards it for negative.
    #[inline]
    pub fn next_up(self) -> Self {
        let bits = self.0.to_bits();
        let magnitude = bits & u32x8::splat(0x7fff_ffff);
        let one = u32x8::splat(1);
        let positive = bits.simd_eq(magnitude);
        let step = positive.select(bits + one, bits - one);
        let next = magnitude.simd_eq(u32x8::ZERO).select(one, step);
        let keep = self.is_nan() | self.eq(F32x8::splat(f32::INFINITY));
        keep.select(self, F32x8(f32x8::from_bits(next)))
    }

    /// The next float below each lane, as `f32::next_down`: `-(-x).next_up()`, bit for bit.
    #[inline]
    pub fn next_down(self) -> Self {
        -(-self).next_up()
    }

    /// Neither NaN nor infinite, as `f32::is_finite`.
    #[inline]
    pub fn is_finite(self) -> Mask8 {
        self.abs().lt(F32x8::splat(f32::INFINITY))
    }
}

impl Add for F32x8 {
    type Output = F32x8;
    #[inline]
    fn add(self, rhs: Self) -> Self {
        F32x8(self.0 + rhs.0)
    }
}

impl Sub for F32x8 {
    type Output = F32x8;
    #[inline]
    fn sub(self, rhs: Self) -> Self {
        F32x8(self.0 - rhs.0)
    }
}

impl Mul for F32x8 {
    type Output = F32x8;
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        F32x8(self.0 * rhs.0)
    }
}

impl Div for F32x8 {
    type Output = F32x8;
    #[inline]
    fn div(self, rhs: Self) -> Self {
        F32x8(self.0 / rhs.0)
    }
}

impl Neg for F32x8 {
    type Output = F32x8;
    /// Flips the sign bit, as scalar negation does (also for NaN and zero).
    #[inline]
    fn neg(self) -> Self {
        F32x8(-self.0)
    }
}

impl Mask8 {
    pub const ALL: Mask8 = Mask8(f32x8::splat(f32::from_bits(u32::MAX)));
    pub const NONE: Mask8 = Mask8(f32x8::splat(0.0));

    /// The mask whose lane `i` is set when bit `i` of `bits` is: one load from a table
    /// (building the lanes one by one showed up in profiles of the traversal).
    #[inline]
    pub fn from_bitmask(bits: u8) -> Self {
        Mask8(f32x8::new(MASKS[bits as usize]))
    }

    /// Bit `i` set when lane `i` is.
    #[inline]
    pub fn bitmask(self) -> u8 {
        self.0.to_bitmask() as u8
    }

    #[inline]
    pub fn any(self) -> bool {
        self.0.any()
    }

    #[inline]
    pub fn all(self) -> bool {
        self.0.all()
    }

    #[inline]
    pub fn none(self) -> bool {
        !self.0.any()
    }

    /// `self & !rhs`: the lanes of `self` that `rhs` does not have.
    #[inline]
    pub fn and_not(self, rhs: Mask8) -> Mask8 {
        self & !rhs
    }

    /// Lane-wise `if self { if_true } else { if_false }`.
    #[inline]
    pub fn select(self, if_true: F32x8, if_false: F32x8) -> F32x8 {
        F32x8(self.0.select(if_true.0, if_false.0))
    }

    /// [`Mask8::select`] on each component.
    #[inline]
    pub fn select_vec(self, if_true: Vec3x8, if_false: Vec3x8) -> Vec3x8 {
        Vec3x8 {
            x: self.select(if_true.x, if_false.x),
            y: self.select(if_true.y, if_false.y),
            z: self.select(if_true.z, if_false.z),
        }
    }
}

/// Calls `f` with the index of each set bit of `mask` (a [`Mask8::bitmask`]), lowest
/// first.
#[inline]
pub fn for_lanes(mut mask: u8, mut f: impl FnMut(usize)) {
    while mask != 0 {
        f(mask.trailing_zeros() as usize);
        mask &= mask - 1;
    }
}

/// Asks the cache for the lines holding `value` (its first and last bytes: a record of up
/// to a line's size), to be read soon: a hint, which changes no result.
#[inline]
pub fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch only hints the cache; it reads nothing and cannot fault, and
    // both addresses lie within `value`.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let first = (value as *const T).cast::<i8>();
        _mm_prefetch::<_MM_HINT_T0>(first);
        _mm_prefetch::<_MM_HINT_T0>(first.add(std::mem::size_of::<T>().max(1) - 1));
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

/// Every mask, by its bit mask.
static MASKS: [[f32; 8]; 256] = {
    let mut table = [[0.0; 8]; 256];
    let mut bits = 0;
    while bits < 256 {
        let mut lane = 0;
        while lane < 8 {
            if bits >> lane & 1 == 1 {
                table[bits][lane] = f32::from_bits(u32::MAX);
            }
            lane += 1;
        }
        bits += 1;
    }
    table
};

impl BitAnd for Mask8 {
    type Output = Mask8;
    #[inline]
    fn bitand(self, rhs: Self) -> Self {
        Mask8(self.0 & rhs.0)
    }
}

impl BitOr for Mask8 {
    type Output = Mask8;
    #[inline]
    fn bitor(self, rhs: Self) -> Self {
        Mask8(self.0 | rhs.0)
    }
}

impl Not for Mask8 {
    type Output = Mask8;
    #[inline]
    fn not(self) -> Self {
        Mask8(!self.0)
    }
}

impl Vec3x8 {
    pub const ZERO: Vec3x8 = Vec3x8 {
        x: F32x8::ZERO,
        y: F32x8::ZERO,
        z: F32x8::ZERO,
    };

    /// `v` in each component, lane by lane (glam's `Vec3::splat` of each lane's `v`).
    #[inline]
    pub fn from_components(v: F32x8) -> Self {
        Vec3x8 { x: v, y: v, z: v }
    }

    /// The same vector in every lane.
    #[inline]
    pub fn splat(v: Vec3) -> Self {
        Vec3x8 {
            x: F32x8::splat(v.x),
            y: F32x8::splat(v.y),
            z: F32x8::splat(v.z),
        }
    }

    /// Lane `i` from `lanes[i]`.
    #[inline]
    pub fn from_lanes(lanes: [Vec3; 8]) -> Self {
        Vec3x8 {
            x: F32x8::from_array(lanes.map(|v| v.x)),
            y: F32x8::from_array(lanes.map(|v| v.y)),
            z: F32x8::from_array(lanes.map(|v| v.z)),
        }
    }

    /// Lane `i` as a `Vec3`, read in place: a copy of the vectors first costs a store of
    /// each to the stack (packets read a node's child boxes this way).
    #[inline]
    pub fn lane(&self, i: usize) -> Vec3 {
        Vec3::new(self.x.lane(i), self.y.lane(i), self.z.lane(i))
    }

    /// Sets lane `i` to `v` in place.
    #[inline]
    pub fn set_lane(&mut self, i: usize, v: Vec3) {
        self.x.set_lane(i, v.x);
        self.y.set_lane(i, v.y);
        self.z.set_lane(i, v.z);
    }

    /// `x x' + y y' + z z'`, summed left to right as glam's `Vec3::dot`.
    #[inline]
    pub fn dot(self, rhs: Self) -> F32x8 {
        self.x * rhs.x + self.y * rhs.y + self.z * rhs.z
    }

    /// The cross product, each component computed as glam's `Vec3::cross` does.
    #[inline]
    pub fn cross(self, rhs: Self) -> Self {
        Vec3x8 {
            x: self.y * rhs.z - rhs.y * self.z,
            y: self.z * rhs.x - rhs.z * self.x,
            z: self.x * rhs.y - rhs.x * self.y,
        }
    }

    /// Each component times the lane's scalar `s` (glam's `f32 * Vec3`).
    #[inline]
    pub fn scale(self, s: F32x8) -> Self {
        Vec3x8 {
            x: s * self.x,
            y: s * self.y,
            z: s * self.z,
        }
    }

    /// [`F32x8::min`] per component, as glam's `Vec3::min`.
    #[inline]
    pub fn min(self, rhs: Self) -> Self {
        Vec3x8 {
            x: self.x.min(rhs.x),
            y: self.y.min(rhs.y),
            z: self.z.min(rhs.z),
        }
    }

    /// [`F32x8::max`] per component, as glam's `Vec3::max`.
    #[inline]
    pub fn max(self, rhs: Self) -> Self {
        Vec3x8 {
            x: self.x.max(rhs.x),
            y: self.y.max(rhs.y),
            z: self.z.max(rhs.z),
        }
    }

    /// Each component's magnitude, as glam's `Vec3::abs`.
    #[inline]
    pub fn abs(self) -> Self {
        Vec3x8 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// `sqrt(v . v)`, as glam's `Vec3::length`.
    #[inline]
    pub fn length(self) -> F32x8 {
        self.dot(self).sqrt()
    }

    /// `v * (1 / |v|)`, as glam's `Vec3::normalize`.
    #[inline]
    pub fn normalize(self) -> Self {
        self.scale(F32x8::splat(1.0) / self.length())
    }

    /// `1 / v` per component, as glam's `Vec3::recip`.
    #[inline]
    pub fn recip(self) -> Self {
        let one = F32x8::splat(1.0);
        Vec3x8 {
            x: one / self.x,
            y: one / self.y,
            z: one / self.z,
        }
    }
}

impl Neg for Vec3x8 {
    type Output = Vec3x8;
    /// Flips each component's sign bit, as glam's `-v`.
    #[inline]
    fn neg(self) -> Self {
        Vec3x8 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl Add for Vec3x8 {
    type Output = Vec3x8;
    #[inline]
    fn add(self, rhs: Self) -> Self {
        Vec3x8 {
            x: self.x + rhs.x,
            y: self.y + rhs.y,
            z: self.z + rhs.z,
        }
    }
}

/// Each component divided by the lane's scalar (glam's `Vec3 / f32`).
impl Div<F32x8> for Vec3x8 {
    type Output = Vec3x8;
    #[inline]
    fn div(self, rhs: F32x8) -> Self {
        Vec3x8 {
            x: self.x / rhs,
            y: self.y / rhs,
            z: self.z / rhs,
        }
    }
}

impl Sub for Vec3x8 {
    type Output = Vec3x8;
    #[inline]
    fn sub(self, rhs: Self) -> Self {
        Vec3x8 {
            x: self.x - rhs.x,
            y: self.y - rhs.y,
            z: self.z - rhs.z,
        }
    }
}

impl Mul for Vec3x8 {
    type Output = Vec3x8;
    /// Component by component, as glam's `Vec3 * Vec3`.
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Vec3x8 {
            x: self.x * rhs.x,
            y: self.y * rhs.y,
            z: self.z * rhs.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bitmasks_round_trip() {
        for bits in 0..=255u8 {
            assert_eq!(Mask8::from_bitmask(bits).bitmask(), bits);
        }
    }

    const NAN: f32 = f32::NAN;

    fn bits(v: F32x8) -> [u32; 8] {
        v.to_array().map(f32::to_bits)
    }

    fn pairs() -> (F32x8, F32x8) {
        let a = [NAN, 1.0, NAN, -0.0, 0.0, 2.0, -1.0, f32::INFINITY];
        let b = [1.0, NAN, NAN, 0.0, -0.0, 3.0, -2.0, f32::NEG_INFINITY];
        (F32x8::from_array(a), F32x8::from_array(b))
    }

    /// Every min/max helper against the scalar rule it documents, bit for bit.
    #[test]
    fn min_max_follow_their_scalar_rules() {
        let (a, b) = pairs();
        let (sa, sb) = (a.to_array(), b.to_array());
        let lanes = |f: fn(f32, f32) -> f32| std::array::from_fn(|i| f(sa[i], sb[i]).to_bits());
        assert_eq!(bits(a.min(b)), lanes(|x, y| if x < y { x } else { y }));
        assert_eq!(bits(a.max(b)), lanes(|x, y| if x > y { x } else { y }));
        assert_eq!(
            bits(a.max_num(b)),
            lanes(|x, y| if x > y || y.is_nan() { x } else { y })
        );
    }

    #[test]
    fn nan_handling_of_min_max() {
        let (a, b) = pairs();
        // min/max: NaN on either side gives rhs.
        assert!(a.min(b).to_array()[0] == 1.0 && a.min(b).to_array()[1].is_nan());
        assert!(a.max(b).to_array()[0] == 1.0 && a.max(b).to_array()[1].is_nan());
        // max_num drops a single NaN from either side, like f32::max.
        for v in [a.max_num(b), b.max_num(a)] {
            let v = v.to_array();
            assert!(v[0] == 1.0 && v[1] == 1.0 && v[2].is_nan());
        }
        // Ties give rhs, so the sign of a zero result is defined.
        assert_eq!(a.min(b).to_array()[3].to_bits(), 0.0f32.to_bits());
        assert_eq!(a.max_num(b).to_array()[4].to_bits(), (-0.0f32).to_bits());
    }

    #[test]
    fn comparisons_and_masks() {
        let (a, b) = pairs();
        assert_eq!(a.lt(b).bitmask(), 1 << 5);
        assert_eq!(a.le(b).bitmask(), 1 << 3 | 1 << 4 | 1 << 5);
        assert_eq!(a.gt(b).bitmask(), 1 << 6 | 1 << 7);
        assert_eq!(a.ge(b).bitmask(), 1 << 3 | 1 << 4 | 1 << 6 | 1 << 7);
        assert_eq!(a.eq(b).bitmask(), 1 << 3 | 1 << 4);
        assert_eq!(a.is_nan().bitmask(), 0b101);
        assert_eq!(a.is_finite().bitmask(), 0b0111_1010);
        let m = Mask8::from_bitmask(0b1010_0110);
        assert_eq!(m.bitmask(), 0b1010_0110);
        assert_eq!((m & Mask8::from_bitmask(0b11)).bitmask(), 0b10);
        assert_eq!((m | Mask8::from_bitmask(0b1)).bitmask(), 0b1010_0111);
        assert_eq!(m.and_not(Mask8::from_bitmask(0b110)).bitmask(), 0b1010_0000);
        assert_eq!((!m).bitmask(), 0b0101_1001);
        assert!(m.any() && !m.all() && !m.none());
        assert!(Mask8::ALL.all() && Mask8::NONE.none());
        let picked = m.select(F32x8::splat(1.0), F32x8::splat(2.0)).to_array();
        assert_eq!(picked, [2.0, 1.0, 1.0, 2.0, 2.0, 1.0, 2.0, 1.0]);
    }

    #[test]
    fn sign_and_root_helpers_match_scalar() {
        let (a, b) = pairs();
        let (sa, sb) = (a.to_array(), b.to_array());
        let each = |f: &dyn Fn(f32, f32) -> f32| -> [u32; 8] {
            std::array::from_fn(|i| f(sa[i], sb[i]).to_bits())
        };
        assert_eq!(bits(a.copysign(b)), each(&|x, y| x.copysign(y)));
        assert_eq!(bits(a.abs()), each(&|x, _| x.abs()));
        assert_eq!(bits(b.sqrt()), each(&|_, y| y.sqrt()));
        assert_eq!(bits(-a), each(&|x, _| -x));
    }

    #[test]
    fn next_up_and_down_match_scalar() {
        let specials = [
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::from_bits(1),
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            NAN,
            -NAN,
            1.0,
            -1.0,
            1.5e-40,
            -3.25,
        ];
        for chunk in specials.chunks(8) {
            let mut lanes = [0.5; 8];
            lanes[..chunk.len()].copy_from_slice(chunk);
            let v = F32x8::from_array(lanes);
            assert_eq!(bits(v.next_up()), lanes.map(|x| x.next_up().to_bits()));
            assert_eq!(bits(v.next_down()), lanes.map(|x| x.next_down().to_bits()));
        }
    }

    #[test]
    fn dot_and_cross_match_glam() {
        let u = Vec3::new(1.5, -2.25, 1e-3);
        let v = Vec3::new(-0.7, 3.1, 7.9);
        let (a, b) = (Vec3x8::splat(u), Vec3x8::splat(v));
        assert_eq!(a.dot(b).to_array()[3].to_bits(), u.dot(v).to_bits());
        assert_eq!(a.cross(b).lane(5), u.cross(v));
        assert_eq!(a.recip().lane(0), u.recip());
    }
}
