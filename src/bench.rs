//! The trace-throughput protocol of `../shared/bench/PROTOCOL.md`: the same primary,
//! shadow and reflection rays that Embree is timed on, traced here, with checksums (hits
//! and the sum of `t`) that let the two be checked against each other.

use std::time::{Duration, Instant};

use bumpalo::Bump;
use glam::Vec3;
use rayon::prelude::*;

use crate::accel::count::{Count, CountLanes, Counter, NoCount, Tally, SHARE};
use crate::accel::stream::{self, Occlusions, Query};
use crate::accel::Tracer;
use crate::plural::count;
use crate::ray::{lane_mask, Ray, RayPacket};
use crate::render::light::{emitters, Receiver};
use crate::render::sampler::{Sample, SampleGrid, SampleRng};
use crate::scene::Scene;
use crate::simd::{Bits, PACKET};

/// The protocol's image width; the height follows the scene's aspect ratio.
pub const WIDTH: u32 = 1024;
/// Secondary rays start this far off the surface, along the normal facing the ray.
pub const OFFSET: f64 = 1e-4;
/// Blocks (a packet's rays each) handed to a thread at a time: 1024 rays.
const CHUNK: usize = 1024 / PACKET;
/// An idle lane of a block.
const IDLE: u32 = u32::MAX;
/// The packet path's name, with the build's packet width.
const PACKET_PATH: &str = if PACKET > 8 {
    "p3trace-packet16"
} else {
    "p3trace-packet8"
};
/// Each path's name in the protocol's lines.
const PATHS: [(&str, Path); 3] = [
    ("p3trace-single", Path::Single),
    (PACKET_PATH, Path::Packet),
    ("p3trace-stream", Path::Stream),
];

/// One of the protocol's ray sets.
#[derive(Clone, Debug)]
pub struct RaySet {
    pub name: &'static str,
    pub rays: Vec<Ray>,
    /// Each ray's `t_max` (`t_min` is 0 for every ray).
    pub t_max: Vec<f32>,
    /// Occlusion queries rather than closest hits.
    pub occlusion: bool,
    /// For occlusion queries, the index of the light each ray heads for, which the
    /// renderer knows as it makes its shadow rays: [`Path::Stream`] groups by it.
    pub light: Vec<u32>,
    /// The rays in groups of a packet, as indices into `rays` (`IDLE` past the end):
    /// pixel tiles 4 wide for primary rays (4 x 2 for 8 lanes, as the Embree harness
    /// groups them, 4 x 4 for 16), and consecutive rays otherwise, which [`ray_sets`]
    /// makes in the primary tiles' order. All paths walk the same blocks.
    pub blocks: Vec<[u32; PACKET]>,
}

/// How a set's rays travel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// One ray at a time.
    Single,
    /// A block as one packet.
    Packet,
    /// The blocks that a thread takes at a time (`CHUNK` of them) as one stream of the
    /// scheduler the renderer traces its queues with ([`crate::accel::stream`]), which
    /// regroups occlusion rays by their light before it traces them as packets
    /// (as Embree's stream API sorts an incoherent stream by direction), the regrouping
    /// timed with the tracing.
    Stream,
}

/// A packet of consecutive rays per block.
fn consecutive_blocks(n: usize) -> Vec<[u32; PACKET]> {
    (0..n.div_ceil(PACKET))
        .map(|b| {
            std::array::from_fn(|k| {
                let i = PACKET * b + k;
                if i < n {
                    i as u32
                } else {
                    IDLE
                }
            })
        })
        .collect()
}

/// Pixel tiles 4 wide and `PACKET / 4` high over a `width` x `height` image stored row
/// by row: lanes 0-3 on row `rows * ty`, lanes 4-7 on the row above, and so on.
fn tile_blocks(width: u32, height: u32) -> Vec<[u32; PACKET]> {
    let rows = (PACKET / 4) as u32;
    let mut blocks = Vec::with_capacity((width / 4 + 1) as usize * (height / rows + 1) as usize);
    for ty in 0..height.div_ceil(rows) {
        for tx in 0..width.div_ceil(4) {
            blocks.push(std::array::from_fn(|k| {
                let (x, y) = (4 * tx + k as u32 % 4, rows * ty + k as u32 / 4);
                if x < width && y < height {
                    y * width + x
                } else {
                    IDLE
                }
            }));
        }
    }
    blocks
}

/// What one pass over a set found, and the fastest pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetResult {
    pub hits: u64,
    pub tsum: f64,
    pub best: Duration,
}

impl SetResult {
    pub fn mrays_per_s(&self, rays: usize) -> f64 {
        rays as f64 / self.best.as_secs_f64().max(1e-12) / 1e6
    }
}

/// The image size of the protocol for `scene`.
pub fn resolution(scene: &Scene) -> (u32, u32) {
    let c = &scene.camera;
    let h = (WIDTH as f64 * c.height as f64 / c.width as f64).round();
    (WIDTH, (h as u32).max(1))
}

/// The three ray sets of the protocol: primary rays through every pixel centre (bottom
/// row first), then, from each primary hit, shadow rays to the lights in front of the
/// surface and one mirror reflection ray. Secondary rays are made in double precision,
/// as the Embree harness makes them, but tile by tile, in the order of the primary
/// blocks (the harness goes row by row): the renderer queues a depth's rays so, and its
/// packets of secondary rays are then neighbours' (dragon reflection, packets of 8: +12%).
pub fn ray_sets(scene: &Scene, tracer: &Tracer) -> [RaySet; 3] {
    let (width, height) = resolution(scene);
    let mut primary = RaySet {
        name: "primary",
        rays: Vec::with_capacity((width * height) as usize),
        t_max: vec![f32::INFINITY; (width * height) as usize],
        occlusion: false,
        light: Vec::new(),
        blocks: tile_blocks(width, height),
    };
    // The pinhole camera of P3F.md section 3 in double precision (aperture and focal
    // play no part), so that the rays round to the same floats as the Embree harness's.
    let c = &scene.camera;
    let (from, at, up) = (c.from.as_dvec3(), c.at.as_dvec3(), c.up.as_dvec3());
    let n = (from - at).normalize();
    let d = (from - at).length();
    let u = up.cross(n).normalize();
    let v = n.cross(u);
    let h = 2.0 * d * (c.angle as f64 * std::f64::consts::PI / 360.0).tan();
    let w = c.width as f64 / c.height as f64 * h;
    for y in 0..height {
        for x in 0..width {
            let sx = (x as f64 + 0.5) / width as f64 - 0.5;
            let sy = (y as f64 + 0.5) / height as f64 - 0.5;
            let dir = u * (w * sx) + v * (h * sy) - n * d;
            let ray = Ray::new(from.as_vec3(), dir.normalize().as_vec3());
            primary.rays.push(ray);
        }
    }
    // Each light as one point, its centre (an area light's grid of one cell): points
    // draw no random number, so one sample serves every hit.
    let lights = emitters(&scene.lights, c.up, None, SampleGrid::square(1), false);
    let sample = Sample {
        rng: SampleRng::new(0, 0, 0),
        cell: [0, 0],
        grid: SampleGrid::square(1),
    };
    let mut shadow = RaySet {
        name: "shadow",
        rays: Vec::new(),
        t_max: Vec::new(),
        occlusion: true,
        light: Vec::new(),
        blocks: Vec::new(),
    };
    let mut reflection = RaySet {
        name: "reflection",
        rays: Vec::new(),
        t_max: Vec::new(),
        occlusion: false,
        light: Vec::new(),
        blocks: Vec::new(),
    };
    let g = tracer.geometry;
    let in_blocks = primary.blocks.iter().flatten().filter(|&&i| i != IDLE);
    for ray in in_blocks.map(|&i| &primary.rays[i as usize]) {
        let Some(hit) = tracer.closest(ray, 0.0, f32::INFINITY) else {
            continue;
        };
        let d = ray.dir.as_dvec3();
        let p = ray.origin.as_dvec3() + d * hit.t as f64;
        // Geometric normals (not the interpolated ones of smooth triangles), in double
        // precision where the harness works in double.
        let normal = g.geometric_normal64(hit.prim, p, hit.u, hit.v);
        let facing = if normal.dot(d) < 0.0 { normal } else { -normal };
        let origin = p + facing * OFFSET;
        let receiver = Receiver {
            point: p,
            normal: facing,
            origin,
        };
        for (index, light) in lights.iter().enumerate() {
            if let Some(light) = light.sample(index, &receiver, &sample) {
                shadow
                    .rays
                    .push(Ray::new(origin.as_vec3(), light.dir.as_vec3()));
                shadow.t_max.push(light.distance);
                shadow.light.push(index as u32);
            }
        }
        let mirror = d - facing * (2.0 * d.dot(facing));
        reflection
            .rays
            .push(Ray::new(origin.as_vec3(), mirror.normalize().as_vec3()));
        reflection.t_max.push(f32::INFINITY);
    }
    shadow.blocks = consecutive_blocks(shadow.rays.len());
    reflection.blocks = consecutive_blocks(reflection.rays.len());
    [primary, shadow, reflection]
}

/// Traces every set along every path with each of `thread_counts`, calling `report` with
/// a result line per set, path and thread count and a `p3trace-best` line per set. Every
/// path and thread count must find what the first found; one that does not is an error.
pub fn run(
    tracer: &Tracer,
    sets: &[RaySet],
    thread_counts: &[usize],
    reps: u32,
    mut report: impl FnMut(Line),
) -> Result<(), String> {
    let mut first: Vec<SetResult> = Vec::new();
    for &n in thread_counts {
        let pool = crate::render::worker_pool(Some(n))?;
        for (k, set) in sets.iter().enumerate() {
            let mut best: Option<SetResult> = None;
            for (api, path) in PATHS {
                let r = trace_set(tracer, set, path, &pool, reps)?;
                report(Line::new(set, api, n, &r));
                match first.get(k) {
                    None => first.push(r),
                    Some(one) if (one.hits, one.tsum) == (r.hits, r.tsum) => {}
                    Some(one) => {
                        return Err(format!(
                            "{}: {api} with {} gave hits {} tsum {:.3}, \
                             the first path hits {} tsum {:.3}",
                            set.name,
                            count(n as u64, "thread", "threads"),
                            r.hits,
                            r.tsum,
                            one.hits,
                            one.tsum
                        ))
                    }
                }
                if best.is_none_or(|b| r.best < b.best) {
                    best = Some(r);
                }
            }
            let best = best.expect("at least one path ran");
            report(Line::new(set, "p3trace-best", n, &best));
        }
    }
    Ok(())
}

/// Traces `set` `reps` times on `pool` along `path` and returns the checksums and the
/// fastest pass. Every pass must give the same checksums; a pass that does not is an error.
pub fn trace_set(
    tracer: &Tracer,
    set: &RaySet,
    path: Path,
    pool: &rayon::ThreadPool,
    reps: u32,
) -> Result<SetResult, String> {
    // Per lane: the hit's t, 0 for an occluded shadow ray, -1 for a miss.
    let mut answers = vec![[f32::NAN; PACKET]; set.blocks.len()];
    let mut counts = vec![[NoCount; PACKET]; set.blocks.len()];
    let mut result: Option<SetResult> = None;
    for pass in 1..=reps.max(1) {
        let start = Instant::now();
        trace_pass(tracer, set, path, pool, &mut answers, &mut counts);
        let elapsed = start.elapsed();
        let (hits, tsum) = checksum(&in_ray_order(set, &answers, f32::NAN));
        match &mut result {
            None => {
                result = Some(SetResult {
                    hits,
                    tsum,
                    best: elapsed,
                })
            }
            Some(r) if r.hits == hits && r.tsum == tsum => r.best = r.best.min(elapsed),
            Some(r) => {
                return Err(format!(
                    "{}: pass {pass} gave hits {hits} tsum {tsum:.3}, pass 1 hits {} tsum {:.3}",
                    set.name, r.hits, r.tsum
                ))
            }
        }
    }
    Ok(result.expect("at least one pass ran"))
}

/// The work of each ray of `set` traced along `path` on `pool`, in the set's order: one
/// untimed pass of the counted walks (`accel::count`), whose answers are the timed ones.
pub fn count_set(
    tracer: &Tracer,
    set: &RaySet,
    path: Path,
    pool: &rayon::ThreadPool,
) -> Vec<Tally> {
    let mut answers = vec![[f32::NAN; PACKET]; set.blocks.len()];
    let mut counts = vec![[Tally::default(); PACKET]; set.blocks.len()];
    trace_pass(tracer, set, path, pool, &mut answers, &mut counts);
    in_ray_order(set, &counts, Tally::default())
}

/// One pass over `set` along `path` on `pool`: the answer of each lane of each block, and
/// its work in `counts`.
fn trace_pass<C: Count>(
    tracer: &Tracer,
    set: &RaySet,
    path: Path,
    pool: &rayon::ThreadPool,
    answers: &mut [[f32; PACKET]],
    counts: &mut [[C; PACKET]],
) {
    answers.fill([f32::NAN; PACKET]);
    pool.install(|| {
        let chunks = answers
            .par_chunks_mut(CHUNK)
            .zip(counts.par_chunks_mut(CHUNK))
            .zip(set.blocks.par_chunks(CHUNK));
        match path {
            Path::Single => chunks.for_each(|((answers, counts), blocks)| {
                each_block(blocks, answers, counts, |b| trace_single(tracer, set, b))
            }),
            Path::Packet => chunks.for_each(|((answers, counts), blocks)| {
                each_block(blocks, answers, counts, |b| trace_packet(tracer, set, b))
            }),
            // Scratch space for a stream, as each of the renderer's workers has.
            Path::Stream => {
                chunks.for_each_init(Bump::new, |arena, ((answers, counts), blocks)| {
                    arena.reset();
                    trace_stream(tracer, set, blocks, answers, counts, arena)
                })
            }
        }
    });
}

/// The answers and counts of `blocks`, each block by `trace`.
fn each_block<C: Count>(
    blocks: &[[u32; PACKET]],
    answers: &mut [[f32; PACKET]],
    counts: &mut [[C; PACKET]],
    trace: impl Fn(&[u32; PACKET]) -> ([f32; PACKET], [C; PACKET]),
) {
    for ((answer, count), block) in answers.iter_mut().zip(counts).zip(blocks) {
        (*answer, *count) = trace(block);
    }
}

/// The answer and work of each lane of `block`, one ray at a time.
fn trace_single<C: Count>(
    tracer: &Tracer,
    set: &RaySet,
    block: &[u32; PACKET],
) -> ([f32; PACKET], [C; PACKET]) {
    let mut counts = [C::default(); PACKET];
    let mut lanes = counts.iter_mut();
    let answers = block.map(|i| {
        let count = lanes.next().expect("a count per lane");
        if i == IDLE {
            return -1.0;
        }
        let (ray, t_max) = (&set.rays[i as usize], set.t_max[i as usize]);
        if set.occlusion {
            if tracer.occluded_counting(ray, 0.0, t_max, count) {
                0.0
            } else {
                -1.0
            }
        } else {
            tracer
                .closest_counting(ray, 0.0, t_max, count)
                .map_or(-1.0, |h| h.t)
        }
    });
    (answers, counts)
}

/// The answer and work of each lane of `block`, the block as one packet.
fn trace_packet<C: Count>(
    tracer: &Tracer,
    set: &RaySet,
    block: &[u32; PACKET],
) -> ([f32; PACKET], [C; PACKET]) {
    let active = lane_mask(|k| block[k] != IDLE);
    // Idle lanes carry a copy of the first ray and are masked off.
    let lane = |k: usize| if block[k] == IDLE { block[0] } else { block[k] } as usize;
    let (mut rays, mut t_max) = ([Ray::new(Vec3::ZERO, Vec3::ZERO); PACKET], [0.0; PACKET]);
    for k in 0..PACKET {
        let i = lane(k);
        (rays[k], t_max[k]) = (set.rays[i], set.t_max[i]);
    }
    let packet = RayPacket::new(&rays).with_t_max(t_max).with_active(active);
    let mut count = C::Lanes::default();
    let answers = if set.occlusion {
        let blocked = tracer.occluded_packet_counting::<C>(&packet, &mut count);
        std::array::from_fn(|k| if blocked.has(k) { 0.0 } else { -1.0 })
    } else {
        let hits = tracer.closest_packet_counting::<C>(&packet, &mut count);
        hits.map(|h| h.map_or(-1.0, |h| h.t))
    };
    (answers, std::array::from_fn(|k| count.lane(k)))
}

/// A ray of a set and its `t_max`, as a stream takes it, and the place of its answer.
#[derive(Clone, Copy)]
struct SetQuery<'s> {
    ray: &'s Ray,
    t_max: f32,
    place: usize,
}

impl Query for SetQuery<'_> {
    fn ray(&self) -> &Ray {
        self.ray
    }

    fn t_max(&self) -> f32 {
        self.t_max
    }
}

/// The answers and work of up to [`CHUNK`] `blocks` as one stream of
/// [`crate::accel::stream`], its scratch space in `arena`: closest-hit rays in block
/// order, occlusion rays grouped by their light, as the renderer traces its queues. Idle
/// lanes are left out.
fn trace_stream<C: Count>(
    tracer: &Tracer,
    set: &RaySet,
    blocks: &[[u32; PACKET]],
    answers: &mut [[f32; PACKET]],
    counts: &mut [[C; PACKET]],
    arena: &Bump,
) {
    let (answers, counts) = (answers.as_flattened_mut(), counts.as_flattened_mut());
    // The rays of the stream, by their index in the set.
    let rays = blocks.as_flattened().iter().enumerate();
    let rays = rays.filter(|(_, &i)| i != IDLE).map(|(place, &i)| {
        let i = i as usize;
        let (ray, t_max) = (&set.rays[i], set.t_max[i]);
        (i, SetQuery { ray, t_max, place })
    });
    if set.occlusion {
        let mut stream = Occlusions::with_capacity_in(PACKET * blocks.len(), arena);
        for (i, query) in rays {
            stream.push(set.light[i], query);
        }
        let (blocked, work) = stream.trace::<C>(tracer, arena);
        for (query, &blocked) in stream.queries().iter().zip(blocked) {
            answers[query.place] = if blocked { 0.0 } else { -1.0 };
        }
        if C::ON {
            for (query, &work) in stream.queries().iter().zip(work) {
                counts[query.place] = work;
            }
        }
    } else {
        let queries = rays.map(|(_, query)| query);
        stream::closest_counting::<_, C>(tracer, queries, |queries, hits, work| {
            for (query, hit) in queries.iter().zip(hits) {
                answers[query.place] = hit.map_or(-1.0, |h| h.t);
            }
            if C::ON {
                for (k, query) in queries.iter().enumerate() {
                    counts[query.place] = work.lane(k);
                }
            }
        });
    }
}

/// Each lane's value of `blocks` rearranged into the order of the set's rays.
fn in_ray_order<T: Copy>(set: &RaySet, lanes: &[[T; PACKET]], unset: T) -> Vec<T> {
    let mut ordered = vec![unset; set.rays.len()];
    for (block, values) in set.blocks.iter().zip(lanes) {
        for (&i, &value) in block.iter().zip(values) {
            if i != IDLE {
                ordered[i as usize] = value;
            }
        }
    }
    ordered
}

/// Hits and the sum of their `t`, summed in ray order in double precision.
fn checksum(answers: &[f32]) -> (u64, f64) {
    answers
        .iter()
        .filter(|&&t| t >= 0.0)
        .fold((0, 0.0), |(hits, sum), &t| (hits + 1, sum + t as f64))
}

/// How one counter spreads over a set's rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    pub mean: f64,
    /// The 50th, 90th and 99th percentiles (nearest rank).
    pub p50: u32,
    pub p90: u32,
    pub p99: u32,
    pub total: u64,
}

impl Spread {
    fn of(mut values: Vec<u32>) -> Self {
        values.sort_unstable();
        let n = values.len();
        let rank = |q: f64| values.get(((q * n as f64).ceil() as usize).max(1) - 1);
        let total: u64 = values.iter().map(|&v| u64::from(v)).sum();
        Spread {
            mean: total as f64 / n.max(1) as f64,
            p50: rank(0.5).copied().unwrap_or(0),
            p90: rank(0.9).copied().unwrap_or(0),
            p99: rank(0.99).copied().unwrap_or(0),
            total,
        }
    }
}

/// The traversal work of a set's rays along one path: each counter's spread per ray and,
/// for packets, how many of a packet's lanes are active at a node visited and at a
/// leaf tested, on average (visits finished one ray at a time count as one lane).
#[derive(Clone, Debug, PartialEq)]
pub struct PathWork {
    pub ray_set: &'static str,
    pub api: &'static str,
    pub rays: usize,
    pub counters: Vec<(Counter, Spread)>,
    pub lanes_at_nodes: Option<f64>,
    pub lanes_at_leaves: Option<f64>,
}

impl PathWork {
    /// The work of `set`'s rays whose counts are `tallies`, traced along `path`.
    pub fn new(set: &RaySet, (api, path): (&'static str, Path), tallies: &[Tally]) -> Self {
        let counters = Counter::ALL
            .into_iter()
            .map(|c| (c, Spread::of(tallies.iter().map(|t| t.get(c)).collect())))
            .collect();
        // Visits are the lanes' shares summed (`accel::count`).
        let lanes = |events: fn(&Tally) -> u32, share: fn(&Tally) -> u64| {
            let events: u64 = tallies.iter().map(|t| u64::from(events(t))).sum();
            let visits = tallies.iter().map(share).sum::<u64>() as f64 / SHARE as f64;
            (path != Path::Single && visits > 0.0).then(|| events as f64 / visits)
        };
        PathWork {
            ray_set: set.name,
            api,
            rays: tallies.len(),
            counters,
            lanes_at_nodes: lanes(|t| t.nodes, |t| t.node_share),
            lanes_at_leaves: lanes(|t| t.leaves, |t| t.leaf_share),
        }
    }

    /// `# work` comment lines: a line per counter that counted anything, then the lanes.
    pub fn lines(&self) -> Vec<String> {
        let head = format!("# work  {:<10}  {:<15}", self.ray_set, self.api);
        let mut lines: Vec<String> = self
            .counters
            .iter()
            .filter(|(_, s)| s.total > 0)
            .map(|(c, s)| {
                format!(
                    "{head}  {:<6}  mean {:8.3}  p50 {:4}  p90 {:4}  p99 {:4}  total {}",
                    c.name(),
                    s.mean,
                    s.p50,
                    s.p90,
                    s.p99,
                    s.total
                )
            })
            .collect();
        if let (Some(nodes), Some(leaves)) = (self.lanes_at_nodes, self.lanes_at_leaves) {
            lines.push(format!(
                "{head}  lanes   {nodes:.2} of {PACKET} at a node, {leaves:.2} of {PACKET} at a leaf"
            ));
        }
        lines
    }
}

/// The work of every set along every path, counted on `pool` (counts do not depend on
/// the thread count).
pub fn work(tracer: &Tracer, sets: &[RaySet], pool: &rayon::ThreadPool) -> Vec<PathWork> {
    sets.iter()
        .flat_map(|set| {
            PATHS.map(|path| PathWork::new(set, path, &count_set(tracer, set, path.1, pool)))
        })
        .collect()
}

/// One result of the protocol: a set traced along one path (`api`) with `threads`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    pub ray_set: &'static str,
    pub api: &'static str,
    pub threads: usize,
    pub rays: usize,
    pub hits: u64,
    pub tsum: f64,
    pub mrays_per_s: f64,
}

impl Line {
    fn new(set: &RaySet, api: &'static str, threads: usize, r: &SetResult) -> Self {
        Line {
            ray_set: set.name,
            api,
            threads,
            rays: set.rays.len(),
            hits: r.hits,
            tsum: r.tsum,
            mrays_per_s: r.mrays_per_s(set.rays.len()),
        }
    }
}

/// The protocol's line: `ray-set api threads rays hits tsum mrays_per_s`.
impl std::fmt::Display for Line {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:<10}  {:<15}  {:2}  {:8}  {:8}  {:16.3}  {:8.2}",
            self.ray_set, self.api, self.threads, self.rays, self.hits, self.tsum, self.mrays_per_s
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::AccelOptions;
    use crate::scene::p3f::parse_text;
    use glam::Vec3;

    const SCENE: &str = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\n\
        resolution 64 32\naperture 3\nfocal 2\nl 0 5 5\nl 0 -5 -5\ns 0 0 0 1\n";

    #[test]
    fn sets_follow_the_protocol() {
        let scene = parse_text(SCENE).unwrap();
        assert_eq!(resolution(&scene), (1024, 512));
        let tracer = Tracer::new(&scene.geometry, &AccelOptions::brute_force());
        let [primary, shadow, reflection] = ray_sets(&scene, &tracer);
        assert_eq!(primary.rays.len(), 1024 * 512);
        // Primary rays start at the eye (aperture ignored) and are unit length.
        assert!(primary
            .rays
            .iter()
            .all(|r| r.origin == Vec3::new(0.0, 0.0, 5.0)));
        assert!(primary
            .rays
            .iter()
            .all(|r| (r.dir.length() - 1.0).abs() < 1e-6));
        let hits = primary
            .rays
            .iter()
            .filter(|r| tracer.closest(r, 0.0, f32::INFINITY).is_some())
            .count();
        assert!(hits > 0);
        assert_eq!(reflection.rays.len(), hits);
        // Each hit sends a shadow ray to each light above its tangent plane: none at
        // the sides of the sphere, two near the bottom rim.
        let n = shadow.rays.len();
        assert!(n > hits / 2 && n < 2 * hits, "{n} shadow rays, {hits} hits");
        let lights = [Vec3::new(0.0, 5.0, 5.0), Vec3::new(0.0, -5.0, -5.0)];
        for (ray, &t_max) in shadow.rays.iter().zip(&shadow.t_max) {
            let end = ray.at(t_max);
            assert!(lights.iter().any(|l| end.distance(*l) < 1e-3), "{end}");
            assert!(ray.origin.length() > 1.0, "starts off the surface");
        }
        // A mirror ray off a sphere seen from outside points away from it.
        for r in &reflection.rays {
            assert!(r.dir.dot(r.origin) > -1e-3);
        }
    }

    /// An area light sends each hit one shadow ray, to its centre.
    #[test]
    fn shadow_rays_end_at_the_centre_of_an_area_light() {
        let text = SCENE.replace("l 0 -5 -5\n", "al 0 0 6 0 0 0 4 4 1 1 1\n");
        let scene = parse_text(&text).unwrap();
        let tracer = Tracer::new(&scene.geometry, &AccelOptions::brute_force());
        let [_, shadow, reflection] = ray_sets(&scene, &tracer);
        assert!(shadow.rays.len() > reflection.rays.len());
        let ends = [Vec3::new(0.0, 5.0, 5.0), Vec3::new(0.0, 0.0, 6.0)];
        for (ray, &t_max) in shadow.rays.iter().zip(&shadow.t_max) {
            let end = ray.at(t_max);
            assert!(ends.iter().any(|l| end.distance(*l) < 1e-3), "{end}");
        }
    }

    #[test]
    fn run_prints_every_path_and_the_best_per_set_and_thread_count() {
        let scene = parse_text(SCENE).unwrap();
        let tracer = Tracer::new(&scene.geometry, &AccelOptions::brute_force());
        let sets = ray_sets(&scene, &tracer);
        let mut lines = Vec::new();
        run(&tracer, &sets, &[1, 2], 1, |l| lines.push(l)).unwrap();
        assert_eq!(lines.len(), 3 * 4 * 2);
        let apis: Vec<&str> = lines[..4].iter().map(|l| l.api).collect();
        assert_eq!(
            apis,
            [
                "p3trace-single",
                PACKET_PATH,
                "p3trace-stream",
                "p3trace-best"
            ]
        );
        // The printed line has the protocol's seven fields.
        let text = lines[0].to_string();
        let fields: Vec<&str> = text.split_whitespace().collect();
        let rays = sets[0].rays.len().to_string();
        assert_eq!(
            fields[..4],
            ["primary", "p3trace-single", "1", rays.as_str()]
        );
        assert_eq!(fields.len(), 7);
    }

    #[test]
    fn blocks_cover_every_ray_once() {
        let covers = |blocks: Vec<[u32; PACKET]>, n: usize| {
            let mut seen = vec![0; n];
            for &i in blocks.iter().flatten().filter(|&&i| i != IDLE) {
                seen[i as usize] += 1;
            }
            seen.iter().all(|&count| count == 1)
        };
        for (w, h) in [(8, 4), (7, 5), (1, 1), (1024, 768)] {
            assert!(covers(tile_blocks(w, h), (w * h) as usize), "{w}x{h}");
        }
        assert!(covers(consecutive_blocks(13), 13));
        // The second tile of two rows: four pixels of each, the lanes of rows below idle.
        let tile = tile_blocks(8, 2)[1];
        assert_eq!(tile[..8], [4, 5, 6, 7, 12, 13, 14, 15]);
        assert!(tile[8..].iter().all(|&i| i == IDLE));
    }

    /// Ten lights, whose shadow rays a stream regroups light by light, and spheres that
    /// shadow one another: every path gives every ray of every set the same answer.
    #[test]
    fn streams_answer_as_single_rays_and_packets() {
        let mut text = String::from(
            "v\nfrom 0 0 8\nat 0 0 0\nup 0 1 0\nangle 50\nhither 0.01\nresolution 64 48\n",
        );
        for k in 0..10 {
            let a = k as f32 * 0.6;
            text += &format!("l {} {} 6\n", 6.0 * a.cos(), 6.0 * a.sin());
        }
        text += "s 0 0 0 1\ns 1.5 0.5 1.5 0.5\ns -1.2 -0.8 1.2 0.4\ns 0.3 -1.6 0.8 0.3\n";
        with_sets(&text, |tracer, sets, pool| {
            fn pass_answers<C: Count>(
                (tracer, set, pool): (&Tracer, &RaySet, &rayon::ThreadPool),
                path: Path,
            ) -> Vec<f32> {
                let mut answers = vec![[f32::NAN; PACKET]; set.blocks.len()];
                let mut counts = vec![[C::default(); PACKET]; set.blocks.len()];
                trace_pass(tracer, set, path, pool, &mut answers, &mut counts);
                in_ray_order(set, &answers, f32::NAN)
            }
            let answers = |set: &RaySet, path| pass_answers::<NoCount>((tracer, set, pool), path);
            for set in sets {
                let single = answers(set, Path::Single);
                assert!(
                    single.iter().all(|t| !t.is_nan()),
                    "{}: every ray answered",
                    set.name
                );
                for path in [Path::Packet, Path::Stream] {
                    assert!(answers(set, path) == single, "{} {path:?}", set.name);
                }
                // The counted pass of `--stats` finds what the timed ones do.
                for path in [Path::Single, Path::Packet, Path::Stream] {
                    let counted = pass_answers::<Tally>((tracer, set, pool), path);
                    assert!(counted == single, "{} {path:?} counted", set.name);
                }
            }
            let shadow = answers(&sets[1], Path::Single);
            let blocked = shadow.iter().filter(|&&t| t == 0.0).count();
            assert!(
                blocked > 1000 && blocked < shadow.len() / 2,
                "some shadow rays blocked, most not: {blocked} of {}",
                shadow.len()
            );
        });
    }

    /// The protocol's sets of the scene `text` under brute force, and two threads.
    fn with_sets(text: &str, check: impl FnOnce(&Tracer, &[RaySet; 3], &rayon::ThreadPool)) {
        let scene = parse_text(text).unwrap();
        let tracer = Tracer::new(&scene.geometry, &AccelOptions::brute_force());
        let sets = ray_sets(&scene, &tracer);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        check(&tracer, &sets, &pool);
    }

    #[test]
    fn checksums_count_hits_and_sum_t() {
        assert_eq!(checksum(&[-1.0, 2.5, 0.0, 1.5]), (3, 4.0));
        with_sets(SCENE, |tracer, sets, pool| {
            let primary = trace_set(tracer, &sets[0], Path::Single, pool, 2).unwrap();
            assert_eq!(primary.hits as usize, sets[2].rays.len());
            let packets = trace_set(tracer, &sets[0], Path::Packet, pool, 1).unwrap();
            assert_eq!((packets.hits, packets.tsum), (primary.hits, primary.tsum));
            let shadow = trace_set(tracer, &sets[1], Path::Packet, pool, 1).unwrap();
            assert_eq!(
                shadow.hits, 0,
                "nothing stands between the sphere and its light"
            );
            assert_eq!(shadow.tsum, 0.0);
        });
    }
}
