//! The packed leaves of the 8-wide tree: for each `packed` kind of
//! [`prim_kinds!`](crate::prim), its packs ([`LeafPack::Pack`]) with the ids of their
//! primitives, and the dispatch from a leaf's kind ([`pack_code`]) to them. The struct and
//! its dispatch are generated from the list ([`packed_kinds!`]); what is done with a pack
//! is written once, over [`LeafPack`], so that the tree names no kind.

use super::node::{leaf_parts, pack_code, ChildRef};
use crate::accel::count::CountLanes;
use crate::accel::hit::ClosestHit;
use crate::intersect::{LeafPack, PacketQuery, RayQuery};
use crate::prim::{packed_kinds, PrimId, PrimKind};
use crate::ray::Hit;
use crate::scene::Geometry;
use crate::simd::{for_lanes, F32xP, LaneBits, PACKET};
use rayon::prelude::*;

/// The packs of one packed kind, and the ids of each pack's primitives lane by lane.
#[derive(Clone, Debug)]
struct Packs<K: LeafPack> {
    packs: Vec<K::Pack>,
    /// Padding lanes repeat the first id: they are never hit.
    ids: Vec<[PrimId; 8]>,
}

impl<K: LeafPack> Packs<K> {
    fn new() -> Self {
        Packs {
            packs: Vec::new(),
            ids: Vec::new(),
        }
    }

    /// Stores `n` packs of `storage`'s primitives after those it holds, pack `i` holding
    /// `run(i)` (one to eight), made on rayon's threads into room made for exactly them.
    fn extend<'p>(&mut self, storage: &K, n: usize, run: impl Fn(usize) -> &'p [PrimId] + Sync)
    where
        K: Sync,
        K::Pack: Send,
    {
        self.packs.reserve_exact(n);
        self.ids.reserve_exact(n);
        let runs = (0..n).into_par_iter().map(&run);
        self.packs
            .par_extend(runs.map(|ids| storage.pack(ids.iter().map(|id| id.index()))));
        self.ids.par_extend((0..n).into_par_iter().map(|i| {
            let ids = run(i);
            // Padding lanes repeat the first id.
            let mut lanes = [ids[0]; 8];
            lanes[..ids.len()].copy_from_slice(ids);
            lanes
        }));
    }

    /// Tests pack `index` against `query`, keeping the winner in `closest`.
    #[inline(always)]
    fn closest<const FRAME: usize>(
        &self,
        index: usize,
        query: &RayQuery,
        closest: &mut ClosestHit,
    ) {
        let hits = K::leaf::<FRAME>(&self.packs[index], query, closest.bound());
        let (t, u, v) = (hits.t.to_array(), hits.u.to_array(), hits.v.to_array());
        let ids = &self.ids[index];
        for_lanes(hits.hit.bitmask(), |k| {
            closest.offer(Hit {
                t: t[k],
                prim: ids[k],
                u: u[k],
                v: v[k],
            })
        });
    }

    /// Whether a primitive of pack `index` blocks `query` within `(t_min, t_max)`.
    #[inline(always)]
    fn blocks<const FRAME: usize>(&self, index: usize, query: &RayQuery, t_max: f32) -> bool {
        K::leaf::<FRAME>(&self.packs[index], query, t_max).hit.any()
    }

    /// The primitives of pack `index`, which holds `count`, against the lanes `lanes`
    /// of `packet`, one primitive against every lane at a time; each lane keeps its
    /// winner, as [`Packs::closest`] has it keep (the tie rule does not depend on order).
    ///
    /// Not inlined, nor is [`Packs::blocks_packet`]: with three packed kinds, their loops
    /// inlined into the packet walks cost `bench` 0.8% more instructions, and a call per
    /// pack leaf costs less.
    #[inline(never)]
    fn closest_packet<C>(
        &self,
        (index, count): (usize, usize),
        query: &PacketQuery,
        lanes: LaneBits,
        closest: &mut [ClosestHit; PACKET],
        counted: &mut impl CountLanes<C>,
    ) {
        counted.leaf(lanes);
        counted.prims(lanes, count as u32);
        let (pack, ids) = (&self.packs[index], &self.ids[index]);
        // Each lane's bound, renewed in the lanes a primitive hits (not gathered again
        // from all the lanes: that was a fifth of this loop's instructions).
        let mut bound = closest.each_ref().map(ClosestHit::bound);
        for (slot, &prim) in ids.iter().enumerate().take(count) {
            let hits = K::slot_packet(pack, slot, query, F32xP::from_array(bound), lanes);
            let hit = hits.hit.bitmask();
            if hit != 0 {
                let (t, u, v) = (hits.t.to_array(), hits.u.to_array(), hits.v.to_array());
                for_lanes(hit, |k| {
                    closest[k].offer(Hit {
                        t: t[k],
                        prim,
                        u: u[k],
                        v: v[k],
                    });
                    bound[k] = closest[k].bound();
                });
            }
        }
    }

    /// The lanes of `lanes` that a primitive of pack `index`, which holds `count`,
    /// blocks within the packet's interval, one primitive against every lane at a time.
    #[inline(never)]
    fn blocks_packet<C>(
        &self,
        (index, count): (usize, usize),
        query: &PacketQuery,
        lanes: LaneBits,
        counted: &mut impl CountLanes<C>,
    ) -> LaneBits {
        counted.leaf(lanes);
        let pack = &self.packs[index];
        let t_max = F32xP::from_array(query.packet.t_max);
        let mut blocked: LaneBits = 0;
        for slot in 0..count {
            let open = lanes & !blocked;
            counted.prims(open, 1);
            let hits = K::slot_packet(pack, slot, query, t_max, open);
            blocked |= hits.hit.bitmask();
            if blocked == lanes {
                break;
            }
        }
        blocked
    }

    fn memory(&self) -> usize {
        std::mem::size_of_val(&self.packs[..]) + std::mem::size_of_val(&self.ids[..])
    }
}

/// Whether a pack of `count` primitives is tested one primitive against the lanes `lanes`
/// at a time, rather than one lane against its eight slots at a time: where that makes
/// fewer tests, weighed by what each costs (`(primitive, lane)`, [`CLOSEST_WEIGHTS`] or
/// [`OCCLUSION_WEIGHTS`]).
#[inline(always)]
fn by_primitive(count: usize, lanes: LaneBits, (primitive, lane): (usize, usize)) -> bool {
    count * primitive < lanes.count_ones() as usize * lane
}

/// [`by_primitive`]'s weights in closest-hit leaves. At 8 lanes the two tests cost alike;
/// a primitive's test of 16 lanes costs about one and a half of a lane's 8-slot test
/// (Zen 4 runs it as two halves, which share its set-up): weighed alike there, or 2 to
/// 1, it was slower (`bench`, EPYC-512, best paths: dragon reflection -1.5%,
/// mount_very_high reflection -2%; 2 to 1, mount_very_high primary -5%). Full-width
/// AVX-512 is not measured.
const CLOSEST_WEIGHTS: (usize, usize) = if PACKET == 16 { (3, 2) } else { (1, 1) };

/// [`by_primitive`]'s weights in occlusion leaves: two thirds of the closest-hit ones, as
/// a primitive's test there leaves out the lanes already blocked and the pack's loop
/// stops once all are (at 8 lanes, weighed alike: mount_very_high shadow -3.5%).
const OCCLUSION_WEIGHTS: (usize, usize) = if PACKET == 16 { (1, 1) } else { (2, 3) };

macro_rules! define_leaves {
    ($($kind:ident, $field:ident, $storage:ident;)*) => {
        /// The packs of every packed kind, one field a kind.
        #[derive(Clone, Debug)]
        pub struct Leaves {
            $($field: Packs<crate::intersect::$storage>,)*
        }

        impl Leaves {
            /// No packs yet.
            pub fn new() -> Self {
                Leaves {
                    $($field: Packs::new(),)*
                }
            }

            /// Stores `n` packs of the packed kind `kind` after those it holds, pack `i`
            /// holding the primitives `run(i)` (one to eight), made on rayon's threads; gives
            /// the index of the first, which its leaves refer to by [`pack_code`].
            pub fn extend<'p>(
                &mut self,
                geometry: &Geometry,
                kind: PrimKind,
                n: usize,
                run: impl Fn(usize) -> &'p [PrimId] + Sync,
            ) -> usize {
                match kind {
                    $(PrimKind::$kind => {
                        let first = self.$field.packs.len();
                        self.$field.extend(&geometry.$field, n, run);
                        first
                    })*
                    _ => unreachable!("{kind:?} is not packed"),
                }
            }

            /// Whether the tree holds packs whose test reads the ray's frame
            /// ([`LeafPack::FRAMED`]).
            #[inline(always)]
            pub fn framed(&self) -> bool {
                false $(|| (<crate::intersect::$storage as LeafPack>::FRAMED
                    && !self.$field.packs.is_empty()))*
            }

            /// The frame ([`crate::intersect::frame_of`]) a walk of `query` takes: its
            /// own where the tree's packs read it, else one for every ray, so that a tree
            /// without them walks in one frame.
            #[inline(always)]
            pub fn frame(&self, query: &RayQuery) -> usize {
                if self.framed() {
                    crate::intersect::frame_of(query.ray.dir)
                } else {
                    2
                }
            }

            /// Tests the pack of the leaf `child` against `query`, keeping the winner in
            /// `closest`; `false` when `child` holds no pack (a run of primitives).
            #[inline(always)]
            pub fn closest<const FRAME: usize>(
                &self,
                child: ChildRef,
                query: &RayQuery,
                closest: &mut ClosestHit,
            ) -> bool {
                let (code, _, index) = leaf_parts(child);
                match code {
                    $(c if c == const { pack_code(PrimKind::$kind) } => {
                        self.$field.closest::<FRAME>(index, query, closest);
                        true
                    })*
                    _ => false,
                }
            }

            /// Whether a primitive of the pack of the leaf `child` blocks `query` within
            /// `(t_min, t_max)`; `None` when `child` holds no pack.
            #[inline(always)]
            pub fn blocks<const FRAME: usize>(
                &self,
                child: ChildRef,
                query: &RayQuery,
                t_max: f32,
            ) -> Option<bool> {
                let (code, _, index) = leaf_parts(child);
                match code {
                    $(c if c == const { pack_code(PrimKind::$kind) } => {
                        Some(self.$field.blocks::<FRAME>(index, query, t_max))
                    })*
                    _ => None,
                }
            }

            /// [`Packs::closest_packet`] for the leaf `child` and the lanes `lanes` of
            /// `query`'s packet when testing each of its primitives against all lanes
            /// costs less than testing each lane against every slot ([`by_primitive`]).
            /// `false` otherwise, the lanes left untested.
            #[inline(always)]
            pub fn closest_packet<C>(
                &self,
                child: ChildRef,
                query: &PacketQuery,
                lanes: LaneBits,
                closest: &mut [ClosestHit; PACKET],
                counted: &mut impl CountLanes<C>,
            ) -> bool {
                let (code, count, index) = leaf_parts(child);
                let fewer = by_primitive(count, lanes, CLOSEST_WEIGHTS);
                match code {
                    $(c if fewer && c == const { pack_code(PrimKind::$kind) } => {
                        self.$field.closest_packet((index, count), query, lanes, closest, counted);
                        true
                    })*
                    _ => false,
                }
            }

            /// [`Packs::blocks_packet`] for the leaf `child` and the lanes `lanes` of
            /// `query`'s packet when that costs less ([`by_primitive`]); `None` otherwise,
            /// the lanes left untested.
            #[inline(always)]
            pub fn blocks_packet<C>(
                &self,
                child: ChildRef,
                query: &PacketQuery,
                lanes: LaneBits,
                counted: &mut impl CountLanes<C>,
            ) -> Option<LaneBits> {
                let (code, count, index) = leaf_parts(child);
                let fewer = by_primitive(count, lanes, OCCLUSION_WEIGHTS);
                match code {
                    $(c if fewer && c == const { pack_code(PrimKind::$kind) } => {
                        Some(self.$field.blocks_packet((index, count), query, lanes, counted))
                    })*
                    _ => None,
                }
            }

            /// Asks the cache for the pack of the leaf `child`, if it holds one, and with
            /// `ids` for its primitives' ids too (which a closest hit reads).
            #[inline(always)]
            pub fn prefetch(&self, child: ChildRef, ids: bool) {
                let (code, _, index) = leaf_parts(child);
                match code {
                    $(c if c == const { pack_code(PrimKind::$kind) } => {
                        crate::simd::prefetch(&self.$field.packs[index]);
                        if ids {
                            crate::simd::prefetch(&self.$field.ids[index]);
                        }
                    })*
                    _ => {}
                }
            }

            /// The ids of the pack of the leaf `child`, lane by lane.
            #[cfg(test)]
            pub fn ids(&self, child: ChildRef) -> &[PrimId; 8] {
                let (code, _, index) = leaf_parts(child);
                match code {
                    $(c if c == const { pack_code(PrimKind::$kind) } => &self.$field.ids[index],)*
                    _ => unreachable!("no packed kind has the code {code}"),
                }
            }
            /// The bytes the packs and their ids take.
            pub fn memory(&self) -> usize {
                0 $(+ self.$field.memory())*
            }
        }
    };
}
packed_kinds!(define_leaves);
