//! The one list of primitive kinds, and the ids that name a primitive.
//!
//! `prim_kinds!` is the list. It hands each kind's entry to a macro that generates
//! what the kinds need: [`PrimKind`] and its names here, and in
//! [`crate::scene::geometry`] the [`Geometry`](crate::scene::Geometry) struct with one
//! field per kind and the dispatch of counts, materials, bounds, intersection (one ray
//! and eight) and normals to the kind's storage, which implements
//! [`crate::intersect::Shapes`] in the kind's own file of `src/intersect/`. A `packed`
//! kind's storage also implements [`crate::intersect::LeafPack`], and `packed_kinds!`
//! hands the 8-wide BVH (`crate::accel::bvh8`) those kinds alone, so that it keeps their
//! leaves side by side without naming any. Adding a kind is its file there and one line
//! here (ARCHITECTURE.md, "Recipes").

/// Calls `$then!` with every primitive kind in [`PrimId`] order, one entry a line:
/// the [`PrimKind`] variant, its field of `Geometry`, its storage type (in
/// `crate::intersect`), the name `info` prints, `bounded` when acceleration structures
/// hold it or `unbounded` when `Tracer` tests it apart, and `packed` when the 8-wide BVH
/// stores up to eight of its primitives side by side in a leaf (its storage implements
/// [`crate::intersect::LeafPack`]) or `unpacked` when it tests them one at a time.
///
/// The order is part of the images: at equal distance the smaller id wins. Unbounded
/// kinds come last, so that a bounded primitive wins a tie against them.
macro_rules! prim_kinds {
    ($then:ident) => {
        $crate::prim::prim_kinds!(@ [$then] []);
    };
    // `$then` by its path, `$arg` before the lines (`packed_kinds!`).
    (@ [$($then:tt)*] [$($arg:tt)*]) => {
        $($then)*! {
            $($arg)*
            Sphere, spheres, Spheres, "spheres", bounded, packed;
            MovingSphere, moving_spheres, MovingSpheres, "moving spheres", bounded, unpacked;
            Triangle, triangles, Triangles, "triangles", bounded, packed;
            Box, boxes, Boxes, "boxes", bounded, packed;
            Cone, cones, Cones, "cones and cylinders", bounded, unpacked;
            Plane, planes, Planes, "planes", unbounded, unpacked;
        }
    };
}
pub(crate) use prim_kinds;

/// Calls `$then!` with the `packed` kinds of [`prim_kinds!`] alone, in [`PrimId`] order,
/// one `variant, field, storage;` a line.
macro_rules! packed_kinds {
    ($then:ident) => {
        $crate::prim::prim_kinds!(@ [$crate::prim::select_packed] [[$then]]);
    };
}
pub(crate) use packed_kinds;

/// The filter of [`packed_kinds!`]: reads the lines of [`prim_kinds!`] one at a time,
/// keeping the `packed` ones, then calls `$then!` with them.
macro_rules! select_packed {
    ([$then:ident] $($lines:tt)*) => {
        $crate::prim::select_packed!(@ $then [] $($lines)*);
    };
    (@ $then:ident [$($kept:tt)*]) => {
        $then! { $($kept)* }
    };
    (@ $then:ident [$($kept:tt)*]
        $kind:ident, $field:ident, $storage:ident, $name:literal, $bound:ident, packed;
        $($rest:tt)*
    ) => {
        $crate::prim::select_packed!(@ $then [$($kept)* $kind, $field, $storage;] $($rest)*);
    };
    (@ $then:ident [$($kept:tt)*]
        $kind:ident, $field:ident, $storage:ident, $name:literal, $bound:ident, unpacked;
        $($rest:tt)*
    ) => {
        $crate::prim::select_packed!(@ $then [$($kept)*] $($rest)*);
    };
}
pub(crate) use select_packed;

/// `true` for `bounded`, `false` for `unbounded`: the last word of a [`prim_kinds!`] line.
macro_rules! is_bounded {
    (bounded) => {
        true
    };
    (unbounded) => {
        false
    };
}

/// `true` for `packed`, `false` for `unpacked`.
macro_rules! is_packed {
    (packed) => {
        true
    };
    (unpacked) => {
        false
    };
}

macro_rules! define_prim_kind {
    ($($kind:ident, $field:ident, $storage:ident, $name:literal, $bound:ident, $pack:ident;)*) => {
        /// Which storage of [`crate::scene::Geometry`] a primitive lives in.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(u8)]
        pub enum PrimKind {
            $($kind,)*
        }

        impl PrimKind {
            pub const ALL: [PrimKind; [$(PrimKind::$kind),*].len()] = [$(PrimKind::$kind),*];

            pub fn name(self) -> &'static str {
                match self {
                    $(PrimKind::$kind => $name,)*
                }
            }

            /// Whether acceleration structures hold primitives of this kind.
            pub const fn is_bounded(self) -> bool {
                match self {
                    $(PrimKind::$kind => is_bounded!($bound),)*
                }
            }

            /// Whether the 8-wide BVH stores this kind's primitives side by side in its
            /// leaves.
            pub const fn is_packed(self) -> bool {
                match self {
                    $(PrimKind::$kind => is_packed!($pack),)*
                }
            }
        }
    };
}
prim_kinds!(define_prim_kind);

impl PrimKind {
    /// The kinds that acceleration structures hold, in [`PrimId`] order.
    pub const BOUNDED: [PrimKind; Self::count(Subset::Bounded)] = Self::select(Subset::Bounded);
    /// The kinds that `Tracer` tests apart from the structure, in [`PrimId`] order.
    pub const UNBOUNDED: [PrimKind; Self::count(Subset::Unbounded)] =
        Self::select(Subset::Unbounded);
    /// The kinds whose primitives the 8-wide BVH packs, in [`PrimId`] order.
    pub const PACKED: [PrimKind; Self::count(Subset::Packed)] = Self::select(Subset::Packed);

    const fn is_in(self, subset: Subset) -> bool {
        match subset {
            Subset::Bounded => self.is_bounded(),
            Subset::Unbounded => !self.is_bounded(),
            Subset::Packed => self.is_packed(),
        }
    }

    /// How many kinds `subset` holds.
    const fn count(subset: Subset) -> usize {
        let (mut i, mut n) = (0, 0);
        while i < Self::ALL.len() {
            if Self::ALL[i].is_in(subset) {
                n += 1;
            }
            i += 1;
        }
        n
    }

    /// The kinds of `subset`, in order (`N` of them).
    const fn select<const N: usize>(subset: Subset) -> [PrimKind; N] {
        let mut kinds = [PrimKind::Sphere; N];
        let (mut i, mut k) = (0, 0);
        while i < Self::ALL.len() {
            if Self::ALL[i].is_in(subset) {
                kinds[k] = Self::ALL[i];
                k += 1;
            }
            i += 1;
        }
        kinds
    }
}

/// The lists of kinds [`PrimKind`] keeps.
#[derive(Clone, Copy)]
enum Subset {
    Bounded,
    Unbounded,
    Packed,
}

/// A primitive's kind and its index in that kind's arrays, packed in 32 bits so that hit
/// records and BVH leaves stay small: the kind takes the top 3 bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PrimId(u32);

impl PrimId {
    const INDEX_BITS: u32 = 29;
    /// The largest number of primitives of one kind.
    pub const MAX_INDEX: u32 = (1 << Self::INDEX_BITS) - 1;

    pub const fn new(kind: PrimKind, index: u32) -> Self {
        debug_assert!(index <= Self::MAX_INDEX);
        PrimId(((kind as u32) << Self::INDEX_BITS) | index)
    }

    pub fn kind(self) -> PrimKind {
        PrimKind::ALL[(self.0 >> Self::INDEX_BITS) as usize]
    }

    pub fn index(self) -> usize {
        (self.0 & Self::MAX_INDEX) as usize
    }

    /// The kind of every primitive of `ids`, where they share one (none where `ids` is
    /// empty): their kind bits compared, the kind looked up once.
    pub fn shared_kind(ids: &[PrimId]) -> Option<PrimKind> {
        let first = ids.first()?;
        let shared = ids
            .iter()
            .all(|id| (id.0 ^ first.0) >> Self::INDEX_BITS == 0);
        shared.then(|| first.kind())
    }
}

// The kind must fit the bits above the index.
const _: () = assert!(PrimKind::ALL.len() <= 1 << (32 - PrimId::INDEX_BITS));

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_keep_kind_and_index_and_bounded_kinds_come_first() {
        for kind in PrimKind::ALL {
            let id = PrimId::new(kind, PrimId::MAX_INDEX);
            assert_eq!((id.kind(), id.index()), (kind, PrimId::MAX_INDEX as usize));
            for other in PrimKind::ALL {
                let shared = PrimId::shared_kind(&[id, PrimId::new(other, 0)]);
                assert_eq!(
                    shared,
                    (other == kind).then_some(kind),
                    "{kind:?} against {other:?}"
                );
            }
        }
        let bounded = PrimKind::BOUNDED.len();
        assert!(PrimKind::ALL[..bounded] == PrimKind::BOUNDED);
        assert!(PrimKind::ALL[bounded..] == PrimKind::UNBOUNDED);
        assert!(PrimKind::UNBOUNDED.iter().all(|k| !k.is_bounded()));
        assert!(PrimKind::PACKED
            .iter()
            .all(|k| k.is_bounded() && k.is_packed()));
    }
}
