//! The one list of primitive kinds, and the ids that name a primitive.
//!
//! `prim_kinds!` is the list. It hands each kind's entry to a macro that generates
//! what the kinds need: [`PrimKind`] and its names here, and in
//! [`crate::scene::geometry`] the [`Geometry`](crate::scene::Geometry) struct with one
//! field per kind and the dispatch of counts, materials, bounds, intersection (one ray
//! and eight) and normals to the kind's storage, which implements
//! [`crate::intersect::Shapes`] in the kind's own file of `src/intersect/`. Adding a kind
//! is its file there and one line here (ARCHITECTURE.md, "Recipes").

/// Calls `$then!` with every primitive kind in [`PrimId`] order, one entry a line:
/// the [`PrimKind`] variant, its field of `Geometry`, its storage type (in
/// `crate::intersect`), the name `info` prints, and `bounded` when acceleration
/// structures hold it or `unbounded` when `Tracer` tests it apart.
///
/// The order is part of the images: at equal distance the smaller id wins. Unbounded
/// kinds come last, so that a bounded primitive wins a tie against them.
macro_rules! prim_kinds {
    ($then:ident) => {
        $then! {
            Sphere, spheres, Spheres, "spheres", bounded;
            MovingSphere, moving_spheres, MovingSpheres, "moving spheres", bounded;
            Triangle, triangles, Triangles, "triangles", bounded;
            Box, boxes, Boxes, "boxes", bounded;
            Cone, cones, Cones, "cones and cylinders", bounded;
            Plane, planes, Planes, "planes", unbounded;
        }
    };
}
pub(crate) use prim_kinds;

/// `true` for `bounded`, `false` for `unbounded`: the last word of a [`prim_kinds!`] line.
macro_rules! is_bounded {
    (bounded) => {
        true
    };
    (unbounded) => {
        false
    };
}

macro_rules! define_prim_kind {
    ($($kind:ident, $field:ident, $storage:ident, $name:literal, $bound:ident;)*) => {
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
        }
    };
}
prim_kinds!(define_prim_kind);

impl PrimKind {
    /// The kinds that acceleration structures hold, in [`PrimId`] order.
    pub const BOUNDED: [PrimKind; Self::count_where(true)] = Self::select(true);
    /// The kinds that `Tracer` tests apart from the structure, in [`PrimId`] order.
    pub const UNBOUNDED: [PrimKind; Self::count_where(false)] = Self::select(false);

    const fn count_where(bounded: bool) -> usize {
        let (mut i, mut n) = (0, 0);
        while i < Self::ALL.len() {
            if Self::ALL[i].is_bounded() == bounded {
                n += 1;
            }
            i += 1;
        }
        n
    }

    /// The kinds whose `is_bounded` is `bounded`, in order (`N` of them).
    const fn select<const N: usize>(bounded: bool) -> [PrimKind; N] {
        let mut kinds = [PrimKind::Sphere; N];
        let (mut i, mut k) = (0, 0);
        while i < Self::ALL.len() {
            if Self::ALL[i].is_bounded() == bounded {
                kinds[k] = Self::ALL[i];
                k += 1;
            }
            i += 1;
        }
        kinds
    }
}

/// A primitive's kind and its index in that kind's arrays, packed in 32 bits so that hit
/// records and BVH leaves stay small: the kind takes the top 3 bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PrimId(u32);

impl PrimId {
    const INDEX_BITS: u32 = 29;
    /// The largest number of primitives of one kind.
    pub const MAX_INDEX: u32 = (1 << Self::INDEX_BITS) - 1;

    pub fn new(kind: PrimKind, index: u32) -> Self {
        debug_assert!(index <= Self::MAX_INDEX);
        PrimId(((kind as u32) << Self::INDEX_BITS) | index)
    }

    pub fn kind(self) -> PrimKind {
        PrimKind::ALL[(self.0 >> Self::INDEX_BITS) as usize]
    }

    pub fn index(self) -> usize {
        (self.0 & Self::MAX_INDEX) as usize
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
        }
        let bounded = PrimKind::BOUNDED.len();
        assert!(PrimKind::ALL[..bounded] == PrimKind::BOUNDED);
        assert!(PrimKind::ALL[bounded..] == PrimKind::UNBOUNDED);
        assert!(PrimKind::UNBOUNDED.iter().all(|k| !k.is_bounded()));
    }
}
