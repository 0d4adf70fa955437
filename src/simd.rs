//! The SIMD lane types of the intersection kernels, the packets and the shading of eight
//! hits at a time: [`F32x8`], [`Mask8`] and [`Vec3x8`] (eight lanes) and [`F32x16`],
//! [`Mask16`] and [`Vec3x16`] (sixteen), generated from one definition. This is the only
//! module that imports `wide`, so the backing crate (or a hand-written fallback) can
//! change here alone. Kernels written once for any width take [`Floats`] (with its
//! [`LaneMask`] and [`Vec3Lanes`]); `wide` runs sixteen lanes as AVX-512 instructions where
//! the build enables `avx512f`, and as two halves of eight otherwise, lane for lane the
//! same values.
//!
//! **Packet width.** A packet holds [`PACKET`] rays, in the types [`F32xP`], [`MaskP`],
//! [`Vec3xP`] and [`LaneBits`] picked here: 16 lanes where the build targets AVX-512
//! (`avx512f`, as `-C target-cpu=x86-64-v4` enables), 8 elsewhere; the feature `packet16`
//! or `packet8` forces one (`build.rs` says which as the `cfg` `packet16`). A node's eight
//! children and a leaf's pack of eight stay eight lanes at every width.
//!
//! [`Codes8`] picks eight lanes from a table of twelve floats (a compact leaf pack's
//! shared vertices) by a permute.
//!
//! Every operation is IEEE-exact lane by lane (`+ - * /` and `sqrt` are correctly
//! rounded, as their scalar counterparts are) and nothing here fuses a multiply with an
//! add: the kernels must equal their scalar twins bit for bit, and `mul_add` rounds once
//! where the scalar code rounds twice. Where the scalar code calls glam (`dot`, `cross`,
//! `min`, `max`, `recip`), the operations here take glam's order, which is why glam's
//! version is pinned (`=0.34.2`, in `fuzz/` too): a release that reorders one would part
//! the twins.

use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::Vec3;
use wide::{f32x16, f32x8, u32x16, u32x8};

#[cfg(not(packet16))]
mod packet {
    pub use super::{F32x8 as F32xP, Mask8 as MaskP, Vec3x8 as Vec3xP};
    /// A packet's lanes as bits, bit `k` for lane `k`.
    pub type LaneBits = u8;
}
#[cfg(packet16)]
mod packet {
    pub use super::{F32x16 as F32xP, Mask16 as MaskP, Vec3x16 as Vec3xP};
    /// A packet's lanes as bits, bit `k` for lane `k`.
    pub type LaneBits = u16;
}
pub use packet::{F32xP, LaneBits, MaskP, Vec3xP};

/// Rays in a packet: the lanes of [`F32xP`].
pub const PACKET: usize = <F32xP as Floats>::LANES;

/// What a kernel written once for any width asks of its lanes: [`F32x8`] and [`F32x16`]
/// answer it with their own methods, the same operations in the same order.
pub trait Floats:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    const LANES: usize;
    type Mask: LaneMask<Floats = Self>;
    fn splat(value: f32) -> Self;
    /// Lane `i` is `lane(i)`.
    fn from_fn(lane: impl FnMut(usize) -> f32) -> Self;
    fn lane(&self, i: usize) -> f32;
    fn set_lane(&mut self, i: usize, value: f32);
    fn min(self, rhs: Self) -> Self;
    fn max(self, rhs: Self) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    fn copysign(self, sign: Self) -> Self;
    fn lt(self, rhs: Self) -> Self::Mask;
    fn le(self, rhs: Self) -> Self::Mask;
    fn gt(self, rhs: Self) -> Self::Mask;
    fn ge(self, rhs: Self) -> Self::Mask;
    fn eq(self, rhs: Self) -> Self::Mask;
    fn is_finite(self) -> Self::Mask;
}

/// The flags of a [`Floats`]' lanes, from its comparisons.
pub trait LaneMask:
    Copy + Debug + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self>
{
    type Floats: Floats<Mask = Self>;
    type Bits: Bits;
    fn from_bitmask(bits: Self::Bits) -> Self;
    fn bitmask(self) -> Self::Bits;
    fn and_not(self, rhs: Self) -> Self;
    fn select(self, if_true: Self::Floats, if_false: Self::Floats) -> Self::Floats;
}

/// Lanes as the bits of an integer, bit `k` for lane `k`: `u8` for eight, `u16` for
/// sixteen.
pub trait Bits:
    Copy + Eq + Debug + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self>
{
    const EMPTY: Self;
    /// How many lanes it holds.
    const LANES: usize;
    /// The lowest `n` lanes.
    fn first(n: usize) -> Self;
    fn has(self, lane: usize) -> bool;
    fn with(self, lane: usize) -> Self;
    fn count(self) -> u32;
    fn lowest(self) -> usize;
    fn highest(self) -> usize;
    /// Without its lowest set bit.
    fn drop_lowest(self) -> Self;
}

macro_rules! bits {
    ($($t:ty),*) => {$(
        impl Bits for $t {
            const EMPTY: $t = 0;
            const LANES: usize = <$t>::BITS as usize;
            #[inline(always)]
            fn first(n: usize) -> Self {
                ((1u32 << n) - 1) as $t
            }
            #[inline(always)]
            fn has(self, lane: usize) -> bool {
                self & (1 << lane) != 0
            }
            #[inline(always)]
            fn with(self, lane: usize) -> Self {
                self | (1 << lane)
            }
            #[inline(always)]
            fn count(self) -> u32 {
                self.count_ones()
            }
            #[inline(always)]
            fn lowest(self) -> usize {
                self.trailing_zeros() as usize
            }
            #[inline(always)]
            fn highest(self) -> usize {
                self.ilog2() as usize
            }
            #[inline(always)]
            fn drop_lowest(self) -> Self {
                self & self.wrapping_sub(1)
            }
        }
    )*};
}
bits!(u8, u16);

/// The bits of the lanes `k` where `pred(k)` holds.
pub fn bits_where<B: Bits>(mut pred: impl FnMut(usize) -> bool) -> B {
    (0..B::LANES)
        .filter(|&k| pred(k))
        .fold(B::EMPTY, |mask, k| mask.with(k))
}

/// Calls `f` with the index of each set bit of `mask` (a [`LaneMask::bitmask`]), lowest
/// first.
#[inline]
pub fn for_lanes<B: Bits>(mut mask: B, mut f: impl FnMut(usize)) {
    while mask != B::EMPTY {
        f(mask.lowest());
        mask = mask.drop_lowest();
    }
}

/// Entries of a table whose halves [`Codes8::pick`] picks from: the distinct vertices of
/// a leaf pack of eight triangles, which a mesh's packs share (nine to eleven, most of them).
pub const TABLE: usize = 12;

/// How a lane names entry `entry` of a table of [`TABLE`]: entries 0 to 7 as themselves,
/// 8 to 11 as 12 to 15. Bit 3 then picks the table's last eight floats (entries 4 to
/// 11), and the low three bits a float of the eight it picks: the form of `vpermt2ps` and
/// `vpermps`, with no bounds to check.
pub const fn table_code(entry: usize) -> u8 {
    assert!(entry < TABLE, "a table holds 12 entries");
    if entry < 8 {
        entry as u8
    } else {
        entry as u8 + 4
    }
}

/// The entry that [`table_code`] names by `code`.
#[inline(always)]
pub const fn table_entry(code: u8) -> usize {
    (if code < 8 { code } else { code - 4 }) as usize
}

/// Eight lanes' codes ([`table_code`]), widened once for the tables they read.
#[derive(Clone, Copy, Debug)]
pub struct Codes8([u32; 8]);

impl Codes8 {
    /// The codes `codes`, which [`table_code`] made.
    #[inline(always)]
    pub fn new(codes: &[u8; 8]) -> Self {
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
        // SAFETY: the load reads the eight bytes of `codes`, and the build enables the
        // instruction (`cfg`); one `vpmovzxbd`, where the compiler widened each by shifts.
        unsafe {
            use std::arch::x86_64::*;
            let wide = _mm256_cvtepu8_epi32(_mm_loadl_epi64(codes.as_ptr().cast()));
            Codes8(std::mem::transmute::<__m256i, [u32; 8]>(wide))
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
        Codes8(codes.map(u32::from))
    }

    /// Lane `k`: lane `code k` of `low` (entries 0 to 7 of a table) for the codes
    /// below 8, else lane `code k - 8` of `high` (its entries 4 to 11); by one `vpermt2ps`
    /// with AVX-512, two `vpermps` and a blend with AVX2. Scalar twin: [`Codes8::pick_lanes`].
    #[inline(always)]
    pub fn pick(&self, low: F32x8, high: F32x8) -> F32x8 {
        #[cfg(all(target_arch = "x86_64", target_feature = "avx512vl"))]
        // SAFETY: the loads read the arrays they are given, and the build enables the
        // instructions (`cfg`).
        unsafe {
            use std::arch::x86_64::*;
            let codes = _mm256_loadu_si256(self.0.as_ptr().cast());
            let low = _mm256_loadu_ps(low.to_array().as_ptr());
            let high = _mm256_loadu_ps(high.to_array().as_ptr());
            let lanes = _mm256_permutex2var_ps(low, codes, high);
            F32x8::from_array(std::mem::transmute::<__m256, [f32; 8]>(lanes))
        }
        #[cfg(all(
            target_arch = "x86_64",
            target_feature = "avx2",
            not(target_feature = "avx512vl")
        ))]
        // SAFETY: as above.
        unsafe {
            use std::arch::x86_64::*;
            let codes = _mm256_loadu_si256(self.0.as_ptr().cast());
            let low = _mm256_permutevar8x32_ps(_mm256_loadu_ps(low.to_array().as_ptr()), codes);
            let high = _mm256_permutevar8x32_ps(_mm256_loadu_ps(high.to_array().as_ptr()), codes);
            // Bit 3 of a code, moved to the sign bit, picks the high lanes.
            let pick_high = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(codes));
            let lanes = _mm256_blendv_ps(low, high, pick_high);
            F32x8::from_array(std::mem::transmute::<__m256, [f32; 8]>(lanes))
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
        self.pick_lanes(low, high)
    }

    /// [`Codes8::pick`] one lane at a time.
    #[inline(always)]
    pub fn pick_lanes(&self, low: F32x8, high: F32x8) -> F32x8 {
        F32x8::from_fn(|k| match self.0[k] {
            code @ 0..8 => low.lane(code as usize),
            code => high.lane(code as usize - 8),
        })
    }
}

/// Entries 0 to 7 of `table`, and 4 to 11: the halves that [`Codes8::pick`] picks from.
#[inline(always)]
pub fn table_halves(table: &[f32; TABLE]) -> (F32x8, F32x8) {
    let half = |start: usize| {
        F32x8::from_array(table[start..start + 8].try_into().expect("eight entries"))
    };
    (half(0), half(4))
}

/// Asks the cache for every line of the `T` at `value`, to be read soon: a hint, which
/// changes no result. The address need not be valid (nor in bounds: a walk asks without
/// the bounds checks an index would cost), as a prefetch reads nothing and cannot fault.
#[inline(always)]
pub fn prefetch<T>(value: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch only hints the cache; it reads nothing and cannot fault, at any
    // address, and the addresses are made with wrapping arithmetic.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let (first, size) = (value.cast::<i8>(), std::mem::size_of::<T>());
        // An address every 64 bytes (a line), and the last byte, whose line they miss
        // where `T` may start within a line.
        for at in (0..size).step_by(64) {
            _mm_prefetch::<_MM_HINT_T0>(first.wrapping_add(at));
        }
        if !std::mem::align_of::<T>().is_multiple_of(64) {
            _mm_prefetch::<_MM_HINT_T0>(first.wrapping_add(size.max(1) - 1));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

/// Every mask of eight lanes, by its bit mask.
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

/// Three-vectors as structure of arrays, lane `i` `(x[i], y[i], z[i])`, each operation as
/// glam's on each lane's `Vec3`.
#[derive(Clone, Copy, Debug)]
pub struct Vec3Lanes<F> {
    pub x: F,
    pub y: F,
    pub z: F,
}

impl<F: Floats> Vec3Lanes<F> {
    /// `v` in each component, lane by lane (glam's `Vec3::splat` of each lane's `v`).
    #[inline]
    pub fn from_components(v: F) -> Self {
        Vec3Lanes { x: v, y: v, z: v }
    }

    /// The same vector in every lane.
    #[inline]
    pub fn splat(v: Vec3) -> Self {
        Vec3Lanes {
            x: F::splat(v.x),
            y: F::splat(v.y),
            z: F::splat(v.z),
        }
    }

    /// Lane `i` is `lane(i)`.
    #[inline]
    pub fn from_fn(lane: impl Fn(usize) -> Vec3) -> Self {
        Vec3Lanes {
            x: F::from_fn(|i| lane(i).x),
            y: F::from_fn(|i| lane(i).y),
            z: F::from_fn(|i| lane(i).z),
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
    pub fn dot(self, rhs: Self) -> F {
        self.x * rhs.x + self.y * rhs.y + self.z * rhs.z
    }

    /// The cross product, each component computed as glam's `Vec3::cross` does.
    #[inline]
    pub fn cross(self, rhs: Self) -> Self {
        Vec3Lanes {
            x: self.y * rhs.z - rhs.y * self.z,
            y: self.z * rhs.x - rhs.z * self.x,
            z: self.x * rhs.y - rhs.x * self.y,
        }
    }

    /// Each component times the lane's scalar `s` (glam's `f32 * Vec3`).
    #[inline]
    pub fn scale(self, s: F) -> Self {
        Vec3Lanes {
            x: s * self.x,
            y: s * self.y,
            z: s * self.z,
        }
    }

    /// [`Floats::min`] per component, as glam's `Vec3::min`.
    #[inline]
    pub fn min(self, rhs: Self) -> Self {
        Vec3Lanes {
            x: self.x.min(rhs.x),
            y: self.y.min(rhs.y),
            z: self.z.min(rhs.z),
        }
    }

    /// [`Floats::max`] per component, as glam's `Vec3::max`.
    #[inline]
    pub fn max(self, rhs: Self) -> Self {
        Vec3Lanes {
            x: self.x.max(rhs.x),
            y: self.y.max(rhs.y),
            z: self.z.max(rhs.z),
        }
    }

    /// Each component's magnitude, as glam's `Vec3::abs`.
    #[inline]
    pub fn abs(self) -> Self {
        Vec3Lanes {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// `sqrt(v . v)`, as glam's `Vec3::length`.
    #[inline]
    pub fn length(self) -> F {
        self.dot(self).sqrt()
    }

    /// `v * (1 / |v|)`, as glam's `Vec3::normalize`.
    #[inline]
    pub fn normalize(self) -> Self {
        self.scale(F::splat(1.0) / self.length())
    }

    /// `1 / v` per component, as glam's `Vec3::recip`.
    #[inline]
    pub fn recip(self) -> Self {
        let one = F::splat(1.0);
        Vec3Lanes {
            x: one / self.x,
            y: one / self.y,
            z: one / self.z,
        }
    }

    /// [`LaneMask::select`] on each component.
    #[inline]
    pub fn select(mask: F::Mask, if_true: Self, if_false: Self) -> Self {
        Vec3Lanes {
            x: mask.select(if_true.x, if_false.x),
            y: mask.select(if_true.y, if_false.y),
            z: mask.select(if_true.z, if_false.z),
        }
    }
}

impl<F: Floats> Neg for Vec3Lanes<F> {
    type Output = Self;
    /// Flips each component's sign bit, as glam's `-v`.
    #[inline]
    fn neg(self) -> Self {
        Vec3Lanes {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl<F: Floats> Add for Vec3Lanes<F> {
    type Output = Self;
    #[inline]
    fn add(self, rhs: Self) -> Self {
        Vec3Lanes {
            x: self.x + rhs.x,
            y: self.y + rhs.y,
            z: self.z + rhs.z,
        }
    }
}

/// Each component divided by the lane's scalar (glam's `Vec3 / f32`).
impl<F: Floats> Div<F> for Vec3Lanes<F> {
    type Output = Self;
    #[inline]
    fn div(self, rhs: F) -> Self {
        Vec3Lanes {
            x: self.x / rhs,
            y: self.y / rhs,
            z: self.z / rhs,
        }
    }
}

impl<F: Floats> Sub for Vec3Lanes<F> {
    type Output = Self;
    #[inline]
    fn sub(self, rhs: Self) -> Self {
        Vec3Lanes {
            x: self.x - rhs.x,
            y: self.y - rhs.y,
            z: self.z - rhs.z,
        }
    }
}

impl<F: Floats> Mul for Vec3Lanes<F> {
    type Output = Self;
    /// Component by component, as glam's `Vec3 * Vec3`.
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Vec3Lanes {
            x: self.x * rhs.x,
            y: self.y * rhs.y,
            z: self.z * rhs.z,
        }
    }
}

/// The lane types of one width: `$floats` over `wide`'s `$wide` (its bits `$uint`), `$mask`
/// with bits `$bits`, `$vec` the three-vectors, `$n` lanes.
macro_rules! lanes {
    ($floats:ident, $mask:ident, $vec:ident, $wide:ident, $uint:ident, $bits:ty, $n:literal) => {
        #[doc = concat!(stringify!($n), " `f32` lanes.")]
        #[derive(Clone, Copy, Debug)]
        pub struct $floats($wide);

        #[doc = concat!(stringify!($n), " lane flags (each lane all ones or all zeros), from comparisons.")]
        #[derive(Clone, Copy, Debug)]
        pub struct $mask($wide);

        #[doc = concat!(stringify!($n), " 3-vectors as structure of arrays.")]
        pub type $vec = Vec3Lanes<$floats>;

        impl $floats {
            pub const ZERO: $floats = $floats::splat(0.0);

            #[inline]
            pub const fn splat(value: f32) -> Self {
                $floats($wide::splat(value))
            }

            #[inline]
            pub const fn from_array(lanes: [f32; $n]) -> Self {
                $floats($wide::new(lanes))
            }

            #[inline]
            pub const fn to_array(self) -> [f32; $n] {
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

            /// Lane-wise `if self < rhs { self } else { rhs }`: the x86 `minps` rule, and
            /// glam's `Vec3::min`. NaN in either operand, or a tie such as `-0.0` against
            /// `0.0`, gives `rhs`.
            #[inline]
            pub fn min(self, rhs: Self) -> Self {
                // `minps` is exactly this rule (the unit tests pin it).
                $floats(self.0.fast_min(rhs.0))
            }

            /// Lane-wise `if self > rhs { self } else { rhs }` (`maxps`, glam's
            /// `Vec3::max`). NaN in either operand, or a tie, gives `rhs`.
            #[inline]
            pub fn max(self, rhs: Self) -> Self {
                $floats(self.0.fast_max(rhs.0))
            }

            /// The larger operand, ignoring a NaN one as `f32::max` does; a tie (`-0.0`
            /// against `0.0`) gives `rhs`, a rule `f32::max` leaves open. Scalar twin:
            /// `intersect::max_num`.
            #[inline]
            pub fn max_num(self, rhs: Self) -> Self {
                (self.gt(rhs) | rhs.is_nan()).select(self, rhs)
            }

            /// Correctly rounded square root (NaN for negative lanes), as `f32::sqrt`.
            #[inline]
            pub fn sqrt(self) -> Self {
                $floats(self.0.sqrt())
            }

            /// Clears the sign bit, as `f32::abs`.
            #[inline]
            pub fn abs(self) -> Self {
                $floats(self.0.abs())
            }

            /// The magnitude of `self` with the sign bit of `sign`, as `f32::copysign`
            /// (NaN operands included: only bits move).
            #[inline]
            pub fn copysign(self, sign: Self) -> Self {
                $floats(self.0.copysign(sign.0))
            }

            /// The smallest lane, by `min` between halves, then quarters, and so on down
            /// to pairs: where no lane is NaN, the least value (either zero where `-0.0`
            /// and `0.0` tie), as a fold of `f32::min` over the lanes gives.
            #[inline]
            pub fn min_lane(self) -> f32 {
                self.reduce($floats::min)
            }

            /// The largest lane, as `min_lane` with `max`.
            #[inline]
            pub fn max_lane(self) -> f32 {
                self.reduce($floats::max)
            }

            /// `combine` of the lanes pairwise: lane `i` with lane `i ^ half`, for halves
            /// of the lanes, then of each half, down to pairs (shuffles).
            #[inline(always)]
            fn reduce(self, combine: impl Fn($floats, $floats) -> $floats) -> f32 {
                let swapped = |v: $floats, half: usize| {
                    let a = v.to_array();
                    $floats::from_array(std::array::from_fn(|i| a[i ^ half]))
                };
                let mut folded = self;
                if $n > 8 {
                    folded = combine(folded, swapped(folded, 8));
                }
                folded = combine(folded, swapped(folded, 4));
                folded = combine(folded, swapped(folded, 2));
                combine(folded, swapped(folded, 1)).to_array()[0]
            }

            /// Ordered comparisons: a NaN lane compares false, as in scalar Rust.
            #[inline]
            pub fn lt(self, rhs: Self) -> $mask {
                $mask(self.0.simd_lt(rhs.0))
            }

            #[inline]
            pub fn le(self, rhs: Self) -> $mask {
                $mask(self.0.simd_le(rhs.0))
            }

            #[inline]
            pub fn gt(self, rhs: Self) -> $mask {
                $mask(self.0.simd_gt(rhs.0))
            }

            #[inline]
            pub fn ge(self, rhs: Self) -> $mask {
                $mask(self.0.simd_ge(rhs.0))
            }

            /// Equality (`-0.0 == 0.0`; NaN equals nothing).
            #[inline]
            pub fn eq(self, rhs: Self) -> $mask {
                $mask(self.0.simd_eq(rhs.0))
            }

            #[inline]
            pub fn is_nan(self) -> $mask {
                $mask(self.0.is_nan())
            }

            /// `self` raised to `exponent` lane by lane with `f32::powf` (the C library's
            /// `powf`, whose exact bits no vector form here reproduces) in the lanes of
            /// `lanes`, zero in the others.
            #[inline]
            pub fn powf(self, exponent: Self, lanes: $mask) -> Self {
                let (base, exponent) = (self.to_array(), exponent.to_array());
                let mut power = [0.0; $n];
                for_lanes(lanes.bitmask(), |k| power[k] = base[k].powf(exponent[k]));
                $floats::from_array(power)
            }

            /// The next float above each lane, as `f32::next_up` (NaN and infinity stay):
            /// one step of the lane's bits, away from zero for positive lanes, towards it
            /// for negative.
            #[inline]
            pub fn next_up(self) -> Self {
                let bits = self.0.to_bits();
                let magnitude = bits & $uint::splat(0x7fff_ffff);
                let one = $uint::splat(1);
                let positive = bits.simd_eq(magnitude);
                let step = positive.select(bits + one, bits - one);
                let next = magnitude.simd_eq($uint::ZERO).select(one, step);
                let keep = self.is_nan() | self.eq($floats::splat(f32::INFINITY));
                keep.select(self, $floats($wide::from_bits(next)))
            }

            /// The next float below each lane, as `f32::next_down`: `-(-x).next_up()`, bit
            /// for bit.
            #[inline]
            pub fn next_down(self) -> Self {
                -(-self).next_up()
            }

            /// Neither NaN nor infinite, as `f32::is_finite`.
            #[inline]
            pub fn is_finite(self) -> $mask {
                self.abs().lt($floats::splat(f32::INFINITY))
            }
        }

        impl Floats for $floats {
            const LANES: usize = $n;
            type Mask = $mask;
            #[inline(always)]
            fn splat(value: f32) -> Self {
                $floats::splat(value)
            }
            #[inline(always)]
            fn from_fn(lane: impl FnMut(usize) -> f32) -> Self {
                $floats::from_array(std::array::from_fn(lane))
            }
            #[inline(always)]
            fn lane(&self, i: usize) -> f32 {
                $floats::lane(self, i)
            }
            #[inline(always)]
            fn set_lane(&mut self, i: usize, value: f32) {
                $floats::set_lane(self, i, value)
            }
            #[inline(always)]
            fn min(self, rhs: Self) -> Self {
                $floats::min(self, rhs)
            }
            #[inline(always)]
            fn max(self, rhs: Self) -> Self {
                $floats::max(self, rhs)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $floats::sqrt(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                $floats::abs(self)
            }
            #[inline(always)]
            fn copysign(self, sign: Self) -> Self {
                $floats::copysign(self, sign)
            }
            #[inline(always)]
            fn lt(self, rhs: Self) -> $mask {
                $floats::lt(self, rhs)
            }
            #[inline(always)]
            fn le(self, rhs: Self) -> $mask {
                $floats::le(self, rhs)
            }
            #[inline(always)]
            fn gt(self, rhs: Self) -> $mask {
                $floats::gt(self, rhs)
            }
            #[inline(always)]
            fn ge(self, rhs: Self) -> $mask {
                $floats::ge(self, rhs)
            }
            #[inline(always)]
            fn eq(self, rhs: Self) -> $mask {
                $floats::eq(self, rhs)
            }
            #[inline(always)]
            fn is_finite(self) -> $mask {
                $floats::is_finite(self)
            }
        }

        impl Add for $floats {
            type Output = $floats;
            #[inline]
            fn add(self, rhs: Self) -> Self {
                $floats(self.0 + rhs.0)
            }
        }

        impl Sub for $floats {
            type Output = $floats;
            #[inline]
            fn sub(self, rhs: Self) -> Self {
                $floats(self.0 - rhs.0)
            }
        }

        impl Mul for $floats {
            type Output = $floats;
            #[inline]
            fn mul(self, rhs: Self) -> Self {
                $floats(self.0 * rhs.0)
            }
        }

        impl Div for $floats {
            type Output = $floats;
            #[inline]
            fn div(self, rhs: Self) -> Self {
                $floats(self.0 / rhs.0)
            }
        }

        impl Neg for $floats {
            type Output = $floats;
            /// Flips the sign bit, as scalar negation does (also for NaN and zero).
            #[inline]
            fn neg(self) -> Self {
                $floats(-self.0)
            }
        }

        impl $mask {
            pub const ALL: $mask = $mask($wide::splat(f32::from_bits(u32::MAX)));
            pub const NONE: $mask = $mask($wide::splat(0.0));

            /// The mask whose lane `i` is set when bit `i` of `bits` is: a load from a table
            /// for each eight lanes (building the lanes one by one showed up in profiles of
            /// the traversal).
            #[inline]
            pub fn from_bitmask(bits: $bits) -> Self {
                let mut lanes = [0.0; $n];
                for (eight, chunk) in lanes.chunks_exact_mut(8).enumerate() {
                    chunk.copy_from_slice(&MASKS[(bits >> (8 * eight)) as u8 as usize]);
                }
                $mask($wide::new(lanes))
            }

            /// Bit `i` set when lane `i` is.
            #[inline]
            pub fn bitmask(self) -> $bits {
                self.0.to_bitmask() as $bits
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
            pub fn and_not(self, rhs: $mask) -> $mask {
                self & !rhs
            }

            /// Lane-wise `if self { if_true } else { if_false }`.
            #[inline]
            pub fn select(self, if_true: $floats, if_false: $floats) -> $floats {
                $floats(self.0.select(if_true.0, if_false.0))
            }

            /// `select` on each component.
            #[inline]
            pub fn select_vec(self, if_true: $vec, if_false: $vec) -> $vec {
                Vec3Lanes::select(self, if_true, if_false)
            }
        }

        impl LaneMask for $mask {
            type Floats = $floats;
            type Bits = $bits;
            #[inline(always)]
            fn from_bitmask(bits: $bits) -> Self {
                $mask::from_bitmask(bits)
            }
            #[inline(always)]
            fn bitmask(self) -> $bits {
                $mask::bitmask(self)
            }
            #[inline(always)]
            fn and_not(self, rhs: Self) -> Self {
                $mask::and_not(self, rhs)
            }
            #[inline(always)]
            fn select(self, if_true: $floats, if_false: $floats) -> $floats {
                $mask::select(self, if_true, if_false)
            }
        }

        impl BitAnd for $mask {
            type Output = $mask;
            #[inline]
            fn bitand(self, rhs: Self) -> Self {
                $mask(self.0 & rhs.0)
            }
        }

        impl BitOr for $mask {
            type Output = $mask;
            #[inline]
            fn bitor(self, rhs: Self) -> Self {
                $mask(self.0 | rhs.0)
            }
        }

        impl Not for $mask {
            type Output = $mask;
            #[inline]
            fn not(self) -> Self {
                $mask(!self.0)
            }
        }

        impl Vec3Lanes<$floats> {
            pub const ZERO: $vec = Vec3Lanes {
                x: $floats::ZERO,
                y: $floats::ZERO,
                z: $floats::ZERO,
            };

            /// Lane `i` from `lanes[i]`.
            #[inline]
            pub fn from_lanes(lanes: [Vec3; $n]) -> Self {
                Self::from_fn(|i| lanes[i])
            }
        }
    };
}

lanes!(F32x8, Mask8, Vec3x8, f32x8, u32x8, u8, 8);
lanes!(F32x16, Mask16, Vec3x16, f32x16, u32x16, u16, 16);

#[cfg(test)]
mod tests {
    use super::*;

    const NAN: f32 = f32::NAN;

    /// The tests of one width's types: every operation against the scalar rule it
    /// documents, bit for bit, on lanes whose first eight hold the special cases (and at
    /// sixteen lanes, the next eight again, swapped).
    macro_rules! lane_tests {
        ($module:ident, $floats:ident, $mask:ident, $vec:ident, $bits:ty, $n:literal) => {
            mod $module {
                use super::*;

                fn bits(v: $floats) -> [u32; $n] {
                    v.to_array().map(f32::to_bits)
                }

                fn lanes(first: [f32; 8], second: [f32; 8]) -> [f32; $n] {
                    std::array::from_fn(|i| {
                        if i % 16 < 8 {
                            first[i % 8]
                        } else {
                            second[i % 8]
                        }
                    })
                }

                fn pairs() -> ($floats, $floats) {
                    let a = [NAN, 1.0, NAN, -0.0, 0.0, 2.0, -1.0, f32::INFINITY];
                    let b = [1.0, NAN, NAN, 0.0, -0.0, 3.0, -2.0, f32::NEG_INFINITY];
                    (
                        $floats::from_array(lanes(a, b)),
                        $floats::from_array(lanes(b, a)),
                    )
                }

                #[test]
                fn bitmasks_round_trip() {
                    for bits in (0..=<$bits>::MAX).step_by(7).chain([<$bits>::MAX]) {
                        assert_eq!($mask::from_bitmask(bits).bitmask(), bits);
                    }
                }

                #[test]
                fn min_max_follow_their_scalar_rules() {
                    let (a, b) = pairs();
                    let (sa, sb) = (a.to_array(), b.to_array());
                    let each = |f: fn(f32, f32) -> f32| -> [u32; $n] {
                        std::array::from_fn(|i| f(sa[i], sb[i]).to_bits())
                    };
                    assert_eq!(bits(a.min(b)), each(|x, y| if x < y { x } else { y }));
                    assert_eq!(bits(a.max(b)), each(|x, y| if x > y { x } else { y }));
                    assert_eq!(
                        bits(a.max_num(b)),
                        each(|x, y| if x > y || y.is_nan() { x } else { y })
                    );
                    // The lanes' least and largest, as a fold where no lane is NaN.
                    let finite = $floats::from_fn(|i| (i as f32 * 7.25) % 5.5 - 2.0);
                    let f = finite.to_array();
                    assert_eq!(
                        finite.min_lane(),
                        f.iter().copied().fold(f32::INFINITY, f32::min)
                    );
                    assert_eq!(
                        finite.max_lane(),
                        f.iter().copied().fold(f32::NEG_INFINITY, f32::max)
                    );
                }

                #[test]
                fn comparisons_and_masks() {
                    let (a, b) = pairs();
                    let (sa, sb) = (a.to_array(), b.to_array());
                    let each = |f: &dyn Fn(f32, f32) -> bool| -> $bits {
                        (0..$n)
                            .filter(|&i| f(sa[i], sb[i]))
                            .fold(0, |m, i| m | 1 << i)
                    };
                    assert_eq!(a.lt(b).bitmask(), each(&|x, y| x < y));
                    assert_eq!(a.le(b).bitmask(), each(&|x, y| x <= y));
                    assert_eq!(a.gt(b).bitmask(), each(&|x, y| x > y));
                    assert_eq!(a.ge(b).bitmask(), each(&|x, y| x >= y));
                    assert_eq!(a.eq(b).bitmask(), each(&|x, y| x == y));
                    assert_eq!(a.is_nan().bitmask(), each(&|x, _| x.is_nan()));
                    assert_eq!(a.is_finite().bitmask(), each(&|x, _| x.is_finite()));
                    let m = $mask::from_bitmask(0b1010_0110);
                    assert_eq!((m & $mask::from_bitmask(0b11)).bitmask(), 0b10);
                    assert_eq!((m | $mask::from_bitmask(0b1)).bitmask(), 0b1010_0111);
                    assert_eq!(m.and_not($mask::from_bitmask(0b110)).bitmask(), 0b1010_0000);
                    assert_eq!((!m).bitmask(), !0b1010_0110);
                    assert!(m.any() && !m.all() && !m.none());
                    assert!($mask::ALL.all() && $mask::NONE.none());
                    let picked = m
                        .select($floats::splat(1.0), $floats::splat(2.0))
                        .to_array();
                    assert_eq!(&picked[..8], &[2.0, 1.0, 1.0, 2.0, 2.0, 1.0, 2.0, 1.0]);
                    assert!(picked[8..].iter().all(|&x| x == 2.0));
                }

                #[test]
                fn sign_root_and_power_helpers_match_scalar() {
                    let (a, b) = pairs();
                    let (sa, sb) = (a.to_array(), b.to_array());
                    let each = |f: &dyn Fn(f32, f32) -> f32| -> [u32; $n] {
                        std::array::from_fn(|i| f(sa[i], sb[i]).to_bits())
                    };
                    assert_eq!(bits(a.copysign(b)), each(&|x, y| x.copysign(y)));
                    assert_eq!(bits(a.abs()), each(&|x, _| x.abs()));
                    assert_eq!(bits(b.sqrt()), each(&|_, y| y.sqrt()));
                    assert_eq!(bits(-a), each(&|x, _| -x));
                    let odd = $mask::from_bitmask(<$bits>::MAX / 3);
                    let power = a.abs().powf(b.abs(), odd).to_array();
                    for i in 0..$n {
                        let expected = if odd.bitmask() >> i & 1 == 1 {
                            sa[i].abs().powf(sb[i].abs())
                        } else {
                            0.0
                        };
                        assert_eq!(power[i].to_bits(), expected.to_bits(), "lane {i}");
                    }
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
                        let mut eight = [0.5; 8];
                        eight[..chunk.len()].copy_from_slice(chunk);
                        let all = lanes(eight, eight);
                        let v = $floats::from_array(all);
                        assert_eq!(bits(v.next_up()), all.map(|x| x.next_up().to_bits()));
                        assert_eq!(bits(v.next_down()), all.map(|x| x.next_down().to_bits()));
                    }
                }

                #[test]
                fn dot_and_cross_match_glam() {
                    let u = Vec3::new(1.5, -2.25, 1e-3);
                    let v = Vec3::new(-0.7, 3.1, 7.9);
                    let (a, b) = ($vec::splat(u), $vec::splat(v));
                    assert_eq!(a.dot(b).to_array()[3].to_bits(), u.dot(v).to_bits());
                    assert_eq!(a.cross(b).lane(5), u.cross(v));
                    assert_eq!(a.recip().lane($n - 1), u.recip());
                    let lanes = $vec::from_lanes(std::array::from_fn(|i| u * i as f32));
                    assert_eq!(lanes.lane($n - 1), u * ($n - 1) as f32);
                }
            }
        };
    }

    lane_tests!(eight, F32x8, Mask8, Vec3x8, u8, 8);
    lane_tests!(sixteen, F32x16, Mask16, Vec3x16, u16, 16);

    #[test]
    fn lane_bits_iterate_and_count() {
        let mut seen = Vec::new();
        for_lanes(0b1001_0000_0000_0110u16, |k| seen.push(k));
        assert_eq!(seen, [1, 2, 12, 15]);
        assert_eq!(
            (0b0110u8.count(), 0b0110u8.lowest(), 0b0110u8.highest()),
            (2, 1, 2)
        );
        assert_eq!(<u16 as Bits>::first(16), u16::MAX);
        assert_eq!(<u8 as Bits>::first(3), 0b111);
        assert!(0b100u16.has(2) && !0b100u16.has(1) && 0u8.with(7) == 0x80);
    }
}
