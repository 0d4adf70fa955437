//! The 8-wide node: eight children's boxes side by side and their references, and the
//! encoding of a reference to a node or to a leaf.

use crate::intersect::{BoxPack8, BoxRay};
use crate::prim::PrimKind;

/// Children per node.
pub const WIDTH: usize = 8;

/// A child reference: a node index, or a leaf (the top bit) with its kind in the
/// [`KIND_BITS`] bits below ([`RUN`], or a packed kind's [`pack_code`]), its primitive
/// count less one in the three bits below those, and below, its first primitive (a run of
/// `prims`) or its pack.
pub type ChildRef = u32;
pub const LEAF: u32 = 1 << 31;
/// Enough bits for a run and every packed kind in both layouts: three for up to three
/// packed kinds.
const KIND_BITS: u32 = u32::BITS - (2 * PrimKind::PACKED.len() as u32).leading_zeros();
const KIND_SHIFT: u32 = 31 - KIND_BITS;
const COUNT_SHIFT: u32 = KIND_SHIFT - 3;
const INDEX_MASK: u32 = (1 << COUNT_SHIFT) - 1;
/// The kind of a leaf that is a run of `prims`, tested one primitive at a time.
pub const RUN: u32 = 0;
/// The most primitives a leaf may hold, and the most a tree may hold, to be encoded.
pub const MAX_LEAF_PRIMS: usize = 1 << (KIND_SHIFT - COUNT_SHIFT);
pub const MAX_PRIMS: usize = INDEX_MASK as usize + 1;

/// The leaf kind of a pack of the packed kind `kind`, in the compact layout or not
/// ([`crate::intersect::LeafPack::Compact`]): one more than its place in
/// [`PrimKind::PACKED`], and after all of those where compact. A kind that is not packed
/// has none (a compile-time error where it is asked for in a constant).
pub const fn pack_code(kind: PrimKind, compact: bool) -> u32 {
    let mut i = 0;
    while i < PrimKind::PACKED.len() {
        if PrimKind::PACKED[i] as u8 == kind as u8 {
            let layout = if compact { PrimKind::PACKED.len() } else { 0 };
            return (layout + i) as u32 + 1;
        }
        i += 1;
    }
    panic!("the kind is not packed")
}

pub fn leaf_ref(kind: u32, count: usize, index: usize) -> ChildRef {
    LEAF | kind << KIND_SHIFT | ((count as u32 - 1) << COUNT_SHIFT) | index as u32
}

/// A leaf reference's kind, primitive count and index.
pub fn leaf_parts(child: ChildRef) -> (u32, usize, usize) {
    (
        (child & !LEAF) >> KIND_SHIFT,
        ((child >> COUNT_SHIFT) & (MAX_LEAF_PRIMS as u32 - 1)) as usize + 1,
        (child & INDEX_MASK) as usize,
    )
}

/// Eight children's boxes side by side, then their references: 228 bytes of data padded
/// to four cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node8 {
    pub boxes: BoxPack8,
    pub child: [ChildRef; WIDTH],
    /// Children in use: slots `0..count`. The others hold padding boxes, which no box
    /// value can make the box test miss, so they are left out of its mask.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<Node8>() == 256);

impl Node8 {
    /// The used children that the ray enters within `[t_min, t_max]`, as a bit mask, and
    /// their entry distances (lanes outside the mask are unspecified).
    #[inline]
    pub fn entries(&self, ray: &BoxRay, t_min: f32, t_max: f32) -> (u8, [f32; WIDTH]) {
        let used = ((1u32 << self.count) - 1) as u8;
        let intervals = ray.intervals8(&self.boxes, t_min, t_max);
        (intervals.hit.bitmask() & used, intervals.entry.to_array())
    }
}
