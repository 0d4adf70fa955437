//! The compact leaf pack of triangles ([`MeshPack8`]): eight triangles as the vertices
//! they share, which the 8-wide BVH takes in large scenes
//! ([`super::LeafPack::COMPACT_FROM`]), where the memory it saves (14 bytes a triangle)
//! matters more than the work of picking the vertices back (1-6% of the time). Its tests
//! are [`crate::intersect::triangle()`]'s watertight test, bit for bit: the vertices it
//! picks are the numbers a [`TrianglePack8`] holds.

use glam::Vec3;

use super::triangle::{
    settle, slot_hits, triangle_hit, trusted8, watertight_sheared, Shear, FRAMES,
};
#[cfg(doc)]
use super::TrianglePack8;
use super::{
    gather8, IntersectOptions, PackOf, PacketHits, PacketQuery, RayQuery, ShapeHit8, Triangles,
};
use crate::ray::Ray;
use crate::simd::{
    table_code, table_entry, table_halves, Codes8, F32x8, F32xP, LaneBits, Mask8, TABLE,
};

/// Eight triangles side by side for [`mesh_leaf`], as the vertices they share: a table of
/// up to [`TABLE`] distinct vertices per axis, and each slot's three corners as codes of
/// its entries ([`table_code`]), from which [`Codes8::pick`] makes the vertices per axis
/// that the test reads. 172 bytes, 24 a triangle of a mesh (7.3 triangles a pack at `gen
/// mount --level 10`), where a [`TrianglePack8`] takes 288 and 36.
///
/// Slots beyond `count` repeat slot 0 and are left out of every test.
#[derive(Clone, Copy, Debug)]
pub struct MeshPack8 {
    /// `table[axis][entry]`: coordinate `axis` of the pack's vertex `entry`.
    table: [[f32; TABLE]; 3],
    /// `corners[i][slot]`: the code of vertex `i` of slot `slot`.
    corners: [[u8; 8]; 3],
    /// The slots in use.
    count: u8,
    /// Whether the leaf goes on in the next pack ([`PackOf::continues`]).
    continues: bool,
}

impl MeshPack8 {
    /// Packs up to eight triangles (their vertices), or `None` when they hold more than
    /// [`TABLE`] distinct vertices (equal when their bits are).
    ///
    /// # Panics
    /// If given more than eight triangles.
    pub fn new(triangles: &[[Vec3; 3]]) -> Option<Self> {
        assert!(triangles.len() <= 8, "a pack holds at most 8 triangles");
        let mut table = [[0.0f32; TABLE]; 3];
        let mut entries: usize = 0;
        let mut corners = [[0; 8]; 3];
        for (slot, triangle) in triangles.iter().enumerate() {
            for (i, vertex) in triangle.iter().enumerate() {
                let bits = vertex.to_array().map(f32::to_bits);
                let same = |e: &usize| [0, 1, 2].map(|axis| table[axis][*e].to_bits()) == bits;
                let entry = match (0..entries).find(same) {
                    Some(entry) => entry,
                    None if entries < TABLE => {
                        for axis in 0..3 {
                            table[axis][entries] = vertex[axis];
                        }
                        entries += 1;
                        entries - 1
                    }
                    None => return None,
                };
                corners[i][slot] = table_code(entry);
            }
        }
        // Unused slots repeat slot 0.
        for codes in &mut corners {
            for slot in triangles.len()..8 {
                codes[slot] = codes[0];
            }
        }
        Some(MeshPack8 {
            table,
            corners,
            count: triangles.len() as u8,
            continues: false,
        })
    }

    /// Each slot's three corners' codes, widened for [`Codes8::pick`].
    #[inline(always)]
    fn codes(&self) -> [Codes8; 3] {
        self.corners.each_ref().map(Codes8::new)
    }

    /// The table's halves per axis ([`table_halves`]): `(low, high)`, each `[x, y, z]`.
    #[inline(always)]
    fn halves(&self) -> ([F32x8; 3], [F32x8; 3]) {
        let halves = self.table.each_ref().map(table_halves);
        (halves.map(|h| h.0), halves.map(|h| h.1))
    }

    /// `vertices[i][axis]`: coordinate `axis` of vertex `i` of each slot.
    #[inline(always)]
    fn vertices(&self) -> [[F32x8; 3]; 3] {
        pick_corners(&self.codes(), self.halves())
    }

    /// The vertices of slot `slot`.
    #[inline(always)]
    fn slot(&self, slot: usize) -> [Vec3; 3] {
        let [x, y, z] = &self.table;
        let entries = self.corners.map(|codes| table_entry(codes[slot]));
        entries.map(|e| Vec3::new(x[e], y[e], z[e]))
    }

    /// The slots in use, as a mask.
    #[inline(always)]
    fn used(&self) -> Mask8 {
        Mask8::from_bitmask(((1u32 << self.count) - 1) as u8)
    }
}

/// `corners[i][j]`: coordinate `j` of vertex `i` of each slot, picked by the slots' codes
/// `codes` from a table's halves `(low, high)` (each `[x, y, z]`, sheared or not).
#[inline(always)]
fn pick_corners(codes: &[Codes8; 3], (low, high): ([F32x8; 3], [F32x8; 3])) -> [[F32x8; 3]; 3] {
    codes
        .each_ref()
        .map(|codes| [0, 1, 2].map(|j| codes.pick(low[j], high[j])))
}

/// The watertight test for one ray against the eight triangles of a mesh pack, as
/// [`crate::intersect::triangle_leaf`] against a [`TrianglePack8`] of the same triangles.
pub fn mesh_leaf(ray: &Ray, pack: &MeshPack8, t_min: f32, t_max: f32) -> ShapeHit8 {
    let query = RayQuery::new(ray, t_min, IntersectOptions::default());
    with_frame!(super::frame_of(ray.dir), FRAME => leaf_hits::<FRAME>(&query, pack, t_max))
}

/// [`mesh_leaf`] for a query whose frame is `FRAME`. The table's vertices are taken
/// relative to the origin and sheared, then picked for the corners that share them: the
/// numbers of the test per corner, in fewer operations.
#[inline(always)]
fn leaf_hits<const FRAME: usize>(query: &RayQuery, pack: &MeshPack8, t_max: f32) -> ShapeHit8 {
    let shear = &Shear::on(query, FRAMES[FRAME]);
    let (t_min, t_max) = (F32x8::splat(query.t_min), F32x8::splat(t_max));
    let [sx, sy, sz] = shear.factors8();
    let sheared = |p: [F32x8; 3]| {
        let p = shear.relative8(&p);
        [p.x - sx * p.z, p.y - sy * p.z, p.z]
    };
    let (codes, (low, high)) = (pack.codes(), pack.halves());
    let corners = pick_corners(&codes, (sheared(low), sheared(high)));
    let (mut hits, exact) = watertight_sheared(
        corners.map(|[x, y, _]| [x, y]),
        corners.map(|[_, _, z]| z),
        sz,
        t_min,
        pack.used(),
    );
    if (hits.hit | exact).any() {
        let vertices = pick_corners(&codes, (low, high));
        let trusted = query.holds8(trusted8(&vertices), hits.t);
        let t_max_lane = t_max.lane(0);
        settle(&mut hits, trusted, exact, t_max, |k| {
            triangle_hit(query, pack.slot(k), t_max_lane)
        });
    }
    hits
}

impl PackOf<Triangles> for MeshPack8 {
    fn pack(storage: &Triangles, indices: impl Iterator<Item = usize>) -> Option<MeshPack8> {
        let (triangles, n) = gather8(indices.map(|i| storage.vertices(i)));
        MeshPack8::new(&triangles[..n])
    }

    const CHAINS: bool = true;

    #[inline(always)]
    fn continues(pack: &MeshPack8) -> bool {
        pack.continues
    }

    fn continued(pack: MeshPack8) -> MeshPack8 {
        MeshPack8 {
            continues: true,
            ..pack
        }
    }

    const FRAMED: bool = true;

    #[inline(always)]
    fn leaf<const FRAME: usize>(pack: &MeshPack8, query: &RayQuery, t_max: f32) -> ShapeHit8 {
        leaf_hits::<FRAME>(query, pack, t_max)
    }

    /// The vertices per axis, picked once for all the slots.
    type Slots<'a> = [[F32x8; 3]; 3];

    #[inline(always)]
    fn slots(pack: &MeshPack8) -> [[F32x8; 3]; 3] {
        pack.vertices()
    }

    #[inline(always)]
    fn slot_packet(
        vertices: [[F32x8; 3]; 3],
        slot: usize,
        query: &PacketQuery,
        t_max: F32xP,
        active: LaneBits,
    ) -> PacketHits {
        slot_hits(&vertices, slot, query, t_max, active)
    }
}
