//! The packed leaves of the 8-wide tree: for each `packed` kind of
//! [`prim_kinds!`](crate::prim), its packs ([`LeafPack::Pack`], or in large scenes
//! [`LeafPack::Compact`]) with the ids of their primitives, and the dispatch from a leaf's
//! kind and layout ([`pack_code`]) to them. The struct and its dispatch are generated from
//! the list ([`packed_kinds!`]); what is done with a pack is written once, over
//! [`PackOf`], so that the tree names no kind.

use super::node::{leaf_parts, pack_code, ChildRef};
use crate::accel::count::CountLanes;
use crate::accel::hit::ClosestHit;
use crate::intersect::{LeafPack, PackLayout, PackOf, PacketQuery, RayQuery, Shapes, CHAIN_HEAD};
use crate::prim::{packed_kinds, PrimId, PrimKind};
use crate::ray::Hit;
use crate::scene::Geometry;
use crate::simd::{for_lanes, F32xP, LaneBits, PACKET};
use rayon::prelude::*;
use std::collections::HashMap;
use std::marker::PhantomData;
use std::sync::Mutex;

/// The packs `P` of one packed kind's storage `K`, and the ids of each pack's primitives
/// lane by lane.
#[derive(Clone, Debug)]
struct Packs<K, P> {
    packs: Vec<P>,
    /// Padding lanes repeat the first id: they are never hit.
    ids: Vec<[PrimId; 8]>,
    storage: PhantomData<fn(&K)>,
}

impl<K, P: PackOf<K>> Packs<K, P> {
    fn new() -> Self {
        Packs {
            packs: Vec::new(),
            ids: Vec::new(),
            storage: PhantomData,
        }
    }

    /// Stores `n` packs of `storage`'s primitives after those it holds, pack `i` holding
    /// `run(i)` (one to eight), made on rayon's threads into room made for them. A run
    /// that does not fit in one pack ([`PackOf::pack`]) takes two after the others, the
    /// first holding [`CHAIN_HEAD`] and going on in the second ([`PackOf::continues`]),
    /// and its own place a pack of its first primitive, which nothing refers to. Gives
    /// the place of the first of the `n` packs, and those runs' `i` and the places of
    /// their first packs.
    fn extend<'p>(
        &mut self,
        storage: &K,
        n: usize,
        run: impl Fn(usize) -> &'p [PrimId] + Sync,
    ) -> (usize, HashMap<usize, usize>)
    where
        K: Sync,
        P: Send,
    {
        // Room for a few runs in two packs (a mesh's leaves share their vertices: one in
        // 200 of `gen mount --level 10`'s holds more than twelve), so that those do not
        // make the arrays grow, which would copy them; the rest of the room is kept.
        let first = self.packs.len();
        let room = n + if P::CHAINS { 2 * (n / 128) } else { 0 };
        self.packs.reserve_exact(room);
        self.ids.reserve_exact(room);
        let lanes = |ids: &[PrimId]| {
            // Padding lanes repeat the first id.
            let mut lanes = [ids[0]; 8];
            lanes[..ids.len()].copy_from_slice(ids);
            lanes
        };
        let pack = |ids: &[PrimId]| P::pack(storage, ids.iter().map(|id| id.index()));
        let unfit = Mutex::new(Vec::new());
        self.packs.par_extend((0..n).into_par_iter().map(|i| {
            pack(run(i)).unwrap_or_else(|| {
                unfit.lock().expect("no thread panics holding it").push(i);
                pack(&run(i)[..1]).expect("one primitive fits a pack")
            })
        }));
        self.ids
            .par_extend((0..n).into_par_iter().map(|i| lanes(run(i))));
        let mut unfit = unfit.into_inner().expect("no thread panicked holding it");
        unfit.sort_unstable();
        let mut moved = HashMap::with_capacity(unfit.len());
        for i in unfit {
            let (head, tail) = run(i).split_at(CHAIN_HEAD);
            moved.insert(i, self.packs.len());
            self.packs.push(P::continued(
                pack(head).expect("four primitives fit a pack"),
            ));
            self.packs
                .push(pack(tail).expect("four primitives fit a pack"));
            self.ids.push(lanes(head));
            self.ids.push(lanes(tail));
        }
        (first, moved)
    }

    /// How many of the `count` primitives of the leaf whose first pack is `index` that
    /// pack holds, and the next one where the leaf goes on in it: `(head, tail)`, `tail`
    /// 0 where it does not. The kernels are called once for each (not in a loop over the
    /// packs, which kept more on the stack: a sphere walk's leaves ran 6% more
    /// instructions).
    #[inline(always)]
    fn split(&self, index: usize, count: usize) -> (usize, usize) {
        match P::CHAINS && P::continues(&self.packs[index]) {
            false => (count, 0),
            true => (CHAIN_HEAD, count - CHAIN_HEAD),
        }
    }

    /// Tests the packs of the leaf whose first pack is `index`, which holds `count`,
    /// against `query`, keeping the winner in `closest`.
    #[inline(always)]
    fn closest<const FRAME: usize>(
        &self,
        (index, count): (usize, usize),
        query: &RayQuery,
        closest: &mut ClosestHit,
    ) {
        self.closest_in::<FRAME>(index, query, closest);
        if self.split(index, count).1 > 0 {
            self.closest_in::<FRAME>(index + 1, query, closest);
        }
    }

    /// [`Packs::closest`] for pack `index` alone.
    #[inline(always)]
    fn closest_in<const FRAME: usize>(
        &self,
        index: usize,
        query: &RayQuery,
        closest: &mut ClosestHit,
    ) {
        let hits = P::leaf::<FRAME>(&self.packs[index], query, closest.bound());
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

    /// Whether a primitive of the leaf whose first pack is `index`, which holds `count`,
    /// blocks `query` within `(t_min, t_max)`.
    #[inline(always)]
    fn blocks<const FRAME: usize>(
        &self,
        (index, count): (usize, usize),
        query: &RayQuery,
        t_max: f32,
    ) -> bool {
        let blocks_in = |index: usize| P::leaf::<FRAME>(&self.packs[index], query, t_max);
        blocks_in(index).hit.any()
            || (self.split(index, count).1 > 0 && blocks_in(index + 1).hit.any())
    }

    /// The primitives of the leaf whose first pack is `index`, which holds `count`,
    /// against the lanes `lanes` of `packet`, one primitive against every lane at a time;
    /// each lane keeps its winner, as [`Packs::closest`] has it keep (the tie rule does not
    /// depend on order).
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
        // Each lane's bound, renewed in the lanes a primitive hits (not gathered again
        // from all the lanes: that was a fifth of this loop's instructions).
        let mut bound = closest.each_ref().map(ClosestHit::bound);
        let (head, tail) = self.split(index, count);
        self.closest_packet_in((index, head), query, lanes, closest, &mut bound);
        if tail > 0 {
            self.closest_packet_in((index + 1, tail), query, lanes, closest, &mut bound);
        }
    }

    /// [`Packs::closest_packet`] for the first `count` primitives of pack `index`, with
    /// each lane's bound `bound`.
    #[inline(always)]
    fn closest_packet_in(
        &self,
        (index, count): (usize, usize),
        query: &PacketQuery,
        lanes: LaneBits,
        closest: &mut [ClosestHit; PACKET],
        bound: &mut [f32; PACKET],
    ) {
        let (slots, ids) = (P::slots(&self.packs[index]), &self.ids[index]);
        for (slot, &prim) in ids.iter().enumerate().take(count) {
            let hits = P::slot_packet(slots, slot, query, F32xP::from_array(*bound), lanes);
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

    /// The lanes of `lanes` that a primitive of the leaf whose first pack is `index`, which
    /// holds `count`, blocks within the packet's interval, one primitive against every lane at a time.
    #[inline(never)]
    fn blocks_packet<C>(
        &self,
        (index, count): (usize, usize),
        query: &PacketQuery,
        lanes: LaneBits,
        counted: &mut impl CountLanes<C>,
    ) -> LaneBits {
        counted.leaf(lanes);
        let t_max = F32xP::from_array(query.packet.t_max);
        let (head, tail) = self.split(index, count);
        let blocked = self.blocks_packet_in((index, head), query, t_max, lanes, 0, counted);
        match tail > 0 && blocked != lanes {
            true => self.blocks_packet_in((index + 1, tail), query, t_max, lanes, blocked, counted),
            false => blocked,
        }
    }

    /// [`Packs::blocks_packet`] for the first `count` primitives of pack `index`, the
    /// lanes `blocked` blocked already.
    #[inline(always)]
    fn blocks_packet_in<C>(
        &self,
        (index, count): (usize, usize),
        query: &PacketQuery,
        t_max: F32xP,
        lanes: LaneBits,
        mut blocked: LaneBits,
        counted: &mut impl CountLanes<C>,
    ) -> LaneBits {
        let slots = P::slots(&self.packs[index]);
        for slot in 0..count {
            let open = lanes & !blocked;
            counted.prims(open, 1);
            let hits = P::slot_packet(slots, slot, query, t_max, open);
            blocked |= hits.hit.bitmask();
            if blocked == lanes {
                break;
            }
        }
        blocked
    }

    /// Asks the cache for pack `index`, and with `ids` for its primitives' ids too.
    #[inline(always)]
    fn prefetch(&self, index: usize, ids: bool) {
        crate::simd::prefetch(self.packs.as_ptr().wrapping_add(index));
        if ids {
            crate::simd::prefetch(self.ids.as_ptr().wrapping_add(index));
        }
    }

    /// The ids of the primitives of the leaf whose first pack is `index`, which holds
    /// `count`.
    #[cfg(test)]
    fn prims(&self, index: usize, count: usize) -> Vec<PrimId> {
        let (head, tail) = self.split(index, count);
        let mut prims = self.ids[index][..head].to_vec();
        if tail > 0 {
            prims.extend_from_slice(&self.ids[index + 1][..tail]);
        }
        prims
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

/// A packed kind's packs of both layouts ([`LeafPack::Pack`], [`LeafPack::Compact`]): a
/// tree fills one of them.
#[derive(Clone, Debug)]
struct KindPacks<K: LeafPack> {
    full: Packs<K, K::Pack>,
    compact: Packs<K, K::Compact>,
}

impl<K: LeafPack> KindPacks<K> {
    fn new() -> Self {
        KindPacks {
            full: Packs::new(),
            compact: Packs::new(),
        }
    }

    fn framed(&self) -> bool {
        (<K::Pack as PackOf<K>>::FRAMED && !self.full.packs.is_empty())
            || (<K::Compact as PackOf<K>>::FRAMED && !self.compact.packs.is_empty())
    }

    fn memory(&self) -> usize {
        self.full.memory() + self.compact.memory()
    }
}

/// Whether a walk compiled for compact packs or not (`$compact`, [`Leaves::compact`])
/// tests the full packs of the storage `$storage`: always where it has no compact ones
/// ([`LeafPack::HAS_COMPACT`]). Constants, so that each walk's dispatch holds only its
/// arms.
macro_rules! full {
    ($compact:expr, $storage:ident) => {
        !($compact && <crate::intersect::$storage as LeafPack>::HAS_COMPACT)
    };
}

/// Whether a walk compiled for compact packs or not (`$compact`) tests the compact packs
/// of the storage `$storage`.
macro_rules! compact {
    ($compact:expr, $storage:ident) => {
        $compact && <crate::intersect::$storage as LeafPack>::HAS_COMPACT
    };
}

macro_rules! define_leaves {
    ($($kind:ident, $field:ident, $storage:ident;)*) => {
        /// The packs of every packed kind, one field a kind.
        #[derive(Clone, Debug)]
        pub struct Leaves {
            $($field: KindPacks<crate::intersect::$storage>,)*
        }

        impl Leaves {
            /// No packs yet.
            pub fn new() -> Self {
                Leaves {
                    $($field: KindPacks::new(),)*
                }
            }

            /// Stores `n` packs of the packed kind `kind` after those it holds, in the
            /// layout `layout` chooses for the kind's primitives, pack `i` holding the
            /// primitives `run(i)` (one to eight), made on rayon's threads. Gives the leaf
            /// code of the layout ([`pack_code`]), the index of the first pack, and the
            /// places of the runs that take two packs ([`Packs::extend`]).
            pub fn extend<'p>(
                &mut self,
                geometry: &Geometry,
                kind: PrimKind,
                layout: PackLayout,
                n: usize,
                run: impl Fn(usize) -> &'p [PrimId] + Sync,
            ) -> (u32, usize, HashMap<usize, usize>) {
                match kind {
                    $(PrimKind::$kind => {
                        let storage = &geometry.$field;
                        let packs = &mut self.$field;
                        type K = crate::intersect::$storage;
                        let compact = layout.compact::<K>(storage.len());
                        let (first, moved) = match compact {
                            false => packs.full.extend(storage, n, run),
                            true => packs.compact.extend(storage, n, run),
                        };
                        (pack_code(kind, compact), first, moved)
                    })*
                    _ => unreachable!("{kind:?} is not packed"),
                }
            }

            /// Whether the tree holds packs whose test reads the ray's frame
            /// ([`PackOf::FRAMED`]).
            #[inline(always)]
            pub fn framed(&self) -> bool {
                false $(|| self.$field.framed())*
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

            /// Whether the tree holds compact packs: its walks are then compiled for them
            /// (`COMPACT`), and others without them (with their arms in the walks, even out
            /// of line, the full packs' walks lost 1.5-3.5%: `bench`, dragon primary).
            pub fn compact(&self) -> bool {
                false $(|| !self.$field.compact.packs.is_empty())*
            }

            /// Tests the packs of the leaf `child` against `query`, keeping the winner in
            /// `closest`; `false` when `child` holds no pack (a run of primitives). A walk
            /// of a tree of compact packs has `COMPACT` set ([`Leaves::compact`]).
            #[inline(always)]
            pub fn closest<const FRAME: usize, const COMPACT: bool>(
                &self,
                child: ChildRef,
                query: &RayQuery,
                closest: &mut ClosestHit,
            ) -> bool {
                let (code, count, index) = leaf_parts(child);
                match code {
                    $(c if full!(COMPACT, $storage) && c == const { pack_code(PrimKind::$kind, false) } => {
                        self.$field.full.closest::<FRAME>((index, count), query, closest);
                    })*
                    $(c if compact!(COMPACT, $storage) && c == const { pack_code(PrimKind::$kind, true) } => {
                        self.$field.compact.closest::<FRAME>((index, count), query, closest);
                    })*
                    _ => return false,
                }
                true
            }

            /// Whether a primitive of the packs of the leaf `child` blocks `query` within
            /// `(t_min, t_max)`; `None` when `child` holds no pack.
            #[inline(always)]
            pub fn blocks<const FRAME: usize, const COMPACT: bool>(
                &self,
                child: ChildRef,
                query: &RayQuery,
                t_max: f32,
            ) -> Option<bool> {
                let (code, count, index) = leaf_parts(child);
                let leaf = (index, count);
                match code {
                    $(c if full!(COMPACT, $storage) && c == const { pack_code(PrimKind::$kind, false) } => {
                        Some(self.$field.full.blocks::<FRAME>(leaf, query, t_max))
                    })*
                    $(c if compact!(COMPACT, $storage) && c == const { pack_code(PrimKind::$kind, true) } => {
                        Some(self.$field.compact.blocks::<FRAME>(leaf, query, t_max))
                    })*
                    _ => None,
                }
            }

            /// [`Packs::closest_packet`] for the leaf `child` and the lanes `lanes` of
            /// `query`'s packet when testing each of its primitives against all lanes
            /// costs less than testing each lane against every slot ([`by_primitive`]).
            /// `false` otherwise, the lanes left untested.
            #[inline(always)]
            pub fn closest_packet<C, const COMPACT: bool>(
                &self,
                child: ChildRef,
                query: &PacketQuery,
                lanes: LaneBits,
                closest: &mut [ClosestHit; PACKET],
                counted: &mut impl CountLanes<C>,
            ) -> bool {
                let (code, count, index) = leaf_parts(child);
                let fewer = by_primitive(count, lanes, CLOSEST_WEIGHTS);
                let leaf = (index, count);
                match code {
                    $(c if full!(COMPACT, $storage) && fewer && c == const { pack_code(PrimKind::$kind, false) } => {
                        self.$field.full.closest_packet(leaf, query, lanes, closest, counted);
                    })*
                    $(c if compact!(COMPACT, $storage) && fewer && c == const { pack_code(PrimKind::$kind, true) } => {
                        self.$field.compact.closest_packet(leaf, query, lanes, closest, counted);
                    })*
                    _ => return false,
                }
                true
            }

            /// [`Packs::blocks_packet`] for the leaf `child` and the lanes `lanes` of
            /// `query`'s packet when that costs less ([`by_primitive`]); `None` otherwise,
            /// the lanes left untested.
            #[inline(always)]
            pub fn blocks_packet<C, const COMPACT: bool>(
                &self,
                child: ChildRef,
                query: &PacketQuery,
                lanes: LaneBits,
                counted: &mut impl CountLanes<C>,
            ) -> Option<LaneBits> {
                let (code, count, index) = leaf_parts(child);
                let fewer = by_primitive(count, lanes, OCCLUSION_WEIGHTS);
                let leaf = (index, count);
                match code {
                    $(c if full!(COMPACT, $storage) && fewer && c == const { pack_code(PrimKind::$kind, false) } => {
                        Some(self.$field.full.blocks_packet(leaf, query, lanes, counted))
                    })*
                    $(c if compact!(COMPACT, $storage) && fewer && c == const { pack_code(PrimKind::$kind, true) } => {
                        Some(self.$field.compact.blocks_packet(leaf, query, lanes, counted))
                    })*
                    _ => None,
                }
            }

            /// Asks the cache for the first pack of the leaf `child`, if it holds one, and
            /// with `ids` for its primitives' ids too (which a closest hit reads).
            #[inline(always)]
            pub fn prefetch<const COMPACT: bool>(&self, child: ChildRef, ids: bool) {
                let (code, _, index) = leaf_parts(child);
                match code {
                    $(c if full!(COMPACT, $storage) && c == const { pack_code(PrimKind::$kind, false) } => {
                        self.$field.full.prefetch(index, ids);
                    })*
                    $(c if compact!(COMPACT, $storage) && c == const { pack_code(PrimKind::$kind, true) } => {
                        self.$field.compact.prefetch(index, ids);
                    })*
                    _ => {}
                }
            }

            /// The ids of the primitives of the leaf `child`, which holds packs.
            #[cfg(test)]
            pub fn prims(&self, child: ChildRef) -> Vec<PrimId> {
                let (code, count, index) = leaf_parts(child);
                match code {
                    $(c if c == const { pack_code(PrimKind::$kind, false) } => {
                        self.$field.full.prims(index, count)
                    })*
                    $(c if compact!(true, $storage) && c == const { pack_code(PrimKind::$kind, true) } => {
                        self.$field.compact.prims(index, count)
                    })*
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
