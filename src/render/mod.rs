//! From a scene to an image: primary rays from the [`camera`], colours from the Whitted
//! [`shade`]r, pixels gathered into a [`Film`] by tiles spread over threads.
//!
//! [`render`] builds the structure and loads the skybox side by side, then renders the
//! tiles of the region on rayon's threads: one ray at a time, or (the default) as a
//! stream per tile (`stream/`). The stream takes a tile's primary samples by blocks of
//! 4 x 2 pixels, each pixel's samples in order, so a packet's lanes are eight pixels at
//! 1 spp and one pixel's samples from 8 spp up; their rays are made eight at a time. Each
//! pixel sums its samples in one order whatever the mode, and tiles write their own block
//! of one buffer, so the image is the same for every mode and thread count. A stream
//! traces a tile's samples in batches (`BATCH_SAMPLES`), its queues in a worker's arena
//! reset per batch: a warm tile asks the global allocator for nothing.

pub mod camera;
pub mod cost;
pub mod light;
pub mod progress;
pub mod region;
pub mod sampler;
pub mod shade;
pub mod skybox;
mod stream;

use std::cell::RefCell;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bumpalo::collections::Vec as ArenaVec;
use bumpalo::Bump;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::accel::count::{Count, NoCount, RayCounts, RayKind, Tally, Work};
use crate::accel::{AccelKind, AccelOptions, Tracer};
use crate::imaging::Film;
use crate::intersect::IntersectOptions;
use crate::limits::{check_image_size, MAX_SPP_SIDE};
use crate::scene::{CameraSpec, Scene};
use crate::simd::PACKET;
use camera::{Camera, FilmSample};
use progress::{Meter, Progress};
use region::Region;
use sampler::{dim, Sample, SampleGrid, SampleRng};
use shade::{ShadeOptions, Shader};
use skybox::Skybox;

/// Tiles are square blocks of this many pixels a side: the unit of work of a thread.
pub const TILE: u32 = 16;

/// Where the samples of a pixel go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// One sample through the pixel centre.
    Centre,
    /// A grid of cells, one sample jittered in each (P3F.md 6.1, which has k x k).
    Jittered(SampleGrid),
}

impl Sampling {
    /// The file's `spp k`: 0 is the centre, k > 0 a k x k jittered grid.
    pub fn from_file_spp(k: u32) -> Self {
        if k == 0 {
            Sampling::Centre
        } else {
            Sampling::Jittered(SampleGrid::square(k))
        }
    }

    /// `--spp N` on the command line: N samples, as the squarest a x b jittered grid
    /// (a square N is the file's grid); 1 is the pixel centre.
    pub fn from_samples_per_pixel(n: u32) -> Result<Self, String> {
        let most = MAX_SPP_SIDE * MAX_SPP_SIDE;
        match n {
            0 => Err("--spp must be at least 1".into()),
            1 => Ok(Sampling::Centre),
            _ if n <= most => Ok(Sampling::Jittered(SampleGrid::with_cells(n))),
            _ => Err(format!("--spp {n} is more than {most} samples per pixel")),
        }
    }

    /// The grid of the pixel's samples (one cell for the centre).
    pub fn grid(self) -> SampleGrid {
        match self {
            Sampling::Centre => SampleGrid::square(1),
            Sampling::Jittered(grid) => grid,
        }
    }

    pub fn samples_per_pixel(self) -> u32 {
        self.grid().cells()
    }
}

/// How rays travel through the structures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderMode {
    /// One ray at a time: the reference path.
    Scalar,
    /// A tile's rays breadth first, depth by depth, every depth's rays and shadow rays
    /// as packets (`stream`). The image is the scalar one, byte for byte.
    Stream,
}

impl RenderMode {
    pub const ALL: [RenderMode; 2] = [RenderMode::Scalar, RenderMode::Stream];
}

#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub sampling: Sampling,
    pub shade: ShadeOptions,
    /// Use the scene's skybox (when it names one that loads).
    pub skybox: bool,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    pub seed: u64,
    /// How progress shows on stderr.
    pub progress: Progress,
    /// The acceleration structure and how to build it.
    pub accel: AccelOptions,
    pub mode: RenderMode,
    /// The shutter interval `[open, close]`: each primary sample takes a time uniform in
    /// it (motion blur, P3F.md 6.5); all at `open` when they are equal.
    pub shutter: [f32; 2],
    /// The pixels to render (a farm's part of the frame); `None` is the whole image.
    pub region: Option<Region>,
    /// Count the walks' work, pixel by pixel (`accel::count`: the walks built to count,
    /// a little slower).
    pub count: bool,
    /// The samples of each pixel to trace, by their place in the grid's order (row `q`,
    /// column `p`: `q * columns + p`); `None` is all. The film holds their mean, so a
    /// viewer that adds one sample's films in order, then divides by the grid's cells,
    /// has the whole render's pixels bit for bit.
    pub samples: Option<Range<u32>>,
    /// Once set, the render skips the tiles it has not begun and returns
    /// [`STOPPED`]: a viewer's frame made stale by the mouse.
    pub stop: Option<Arc<AtomicBool>>,
}

/// The error of a render that its `stop` flag ended.
pub const STOPPED: &str = "the render was stopped";

/// The shutter of the course's code, used when a scene has moving primitives.
pub const DEFAULT_SHUTTER: [f32; 2] = [0.0, 0.3];

impl RenderOptions {
    /// The settings the scene file asks for.
    pub fn from_scene(scene: &Scene) -> Self {
        RenderOptions {
            width: scene.camera.width,
            height: scene.camera.height,
            sampling: Sampling::from_file_spp(scene.spp),
            shade: ShadeOptions::default(),
            skybox: true,
            threads: None,
            seed: 0,
            progress: Progress::Hidden,
            accel: AccelOptions {
                kind: scene.accel.unwrap_or(AccelKind::Bvh),
                ..AccelOptions::default()
            },
            mode: RenderMode::Stream,
            shutter: if scene.geometry.has_moving() {
                DEFAULT_SHUTTER
            } else {
                [0.0; 2]
            },
            region: None,
            count: false,
            samples: None,
            stop: None,
        }
    }

    /// The samples of each pixel that the render traces (see `samples`), within the grid.
    pub fn traced_samples(&self) -> Range<u32> {
        let cells = self.sampling.samples_per_pixel();
        match &self.samples {
            Some(range) => range.start.min(cells)..range.end.min(cells),
            None => 0..cells,
        }
    }

    /// The pixels to render: the region asked for, else the whole image.
    pub fn region(&self) -> Region {
        self.region
            .unwrap_or_else(|| Region::full(self.width, self.height))
    }

    /// Refuses images too large to hold in memory, saying how much they would need,
    /// regions that reach outside the image, and an empty choice of samples.
    pub fn check_size(&self) -> Result<(), String> {
        check_image_size(self.width, self.height)?;
        let r = self.region();
        if r.x0 >= r.x1 || r.y0 >= r.y1 || r.x1 > self.width || r.y1 > self.height {
            return Err(format!(
                "the region {},{},{},{} is empty or outside the {}x{} image",
                r.x0, r.x1, r.y0, r.y1, self.width, self.height
            ));
        }
        if self.traced_samples().is_empty() {
            return Err(format!(
                "no samples to trace: {:?} of a pixel's {}",
                self.samples,
                self.sampling.samples_per_pixel()
            ));
        }
        Ok(())
    }
}

/// What a render produced besides the image.
#[derive(Clone, Debug)]
pub struct RenderReport {
    /// The pixels of `options.region()` only.
    pub film: Film,
    /// Every ray traced, by kind.
    pub rays: RayCounts,
    /// Time spent rendering, after the structure was built.
    pub elapsed: Duration,
    /// The worker threads that rendered.
    pub threads: usize,
    pub build_time: Duration,
    /// The threads the structure was built on.
    pub build_threads: usize,
    /// The structure's name and statistics lines.
    pub accel_name: String,
    pub accel_stats: Vec<String>,
    /// The folder of the skybox drawn, if one was (the scene named one, it was found and
    /// loaded, and it was wanted).
    pub skybox: Option<PathBuf>,
    pub warnings: Vec<String>,
    /// What the rays took, where `options.count` asked.
    pub work: Option<RenderWork>,
}

/// The work of a counted render's rays (`accel::count`).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderWork {
    /// Each pixel's: the work of its samples' rays by kind, for the pixels of
    /// `options.region()`, top row first.
    pub pixels: Vec<Work<Tally>>,
}

impl RenderWork {
    /// The work of every pixel's rays together, by kind.
    pub fn by_kind(&self) -> Work<Tally> {
        self.pixels.iter().fold(Work::default(), |mut all, pixel| {
            all.merge(pixel);
            all
        })
    }
}

/// A pool of `threads` worker threads, one per core without a number.
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start the worker threads: {e}"))
}

/// Renders `scene` with the structure `options.accel` asks for.
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<RenderReport, String> {
    options.check_size()?;
    let stage = Stage::new(scene, options);
    let mut report = stage.render(&scene.camera, options)?;
    report.warnings = stage.warnings;
    Ok(report)
}

/// A scene ready to render frame after frame: its structure built and its skybox loaded,
/// as `options` asked when it was made (structure, shutter, profile, mode).
///
/// ```
/// use p3trace::render::{render, RenderOptions, Sampling, Stage};
/// use p3trace::render::sampler::SampleGrid;
/// use p3trace::scene::parse_str;
///
/// let text = "v from 0 0 5 at 0 0 0 up 0 1 0 angle 40 hither 0.01 resolution 16 12
///             l 3 4 5 1 1 1  f 1 0.5 0.2 1 1 1 1 0.3 30 0 1  s 0 0 0 1";
/// let scene = parse_str(text, "stage", std::path::Path::new(".")).unwrap();
/// let options = RenderOptions {
///     sampling: Sampling::Jittered(SampleGrid::square(2)),
///     ..RenderOptions::from_scene(&scene)
/// };
/// // Built once, rendered twice: a sample of each pixel at a time, then the mean of the
/// // four, in the order `render` adds them, is `render`'s film bit for bit.
/// let stage = Stage::new(&scene, &options);
/// let mut sums = p3trace::view::Accumulator::new(16, 12);
/// for k in 0..4 {
///     let pass = RenderOptions { samples: Some(k..k + 1), ..options.clone() };
///     sums.add(&stage.render(&scene.camera, &pass).unwrap().film);
/// }
/// assert_eq!(sums.image(), render(&scene, &options).unwrap().film);
/// ```
pub struct Stage<'s> {
    scene: &'s Scene,
    tracer: Tracer<'s>,
    skybox: Option<Skybox>,
    /// The folder the skybox was found in and loaded from.
    skybox_folder: Option<PathBuf>,
    /// What loading the skybox found wrong.
    pub warnings: Vec<String>,
}

impl<'s> Stage<'s> {
    /// Builds the structure and loads the skybox side by side, on as many threads as the
    /// render may use (`options.threads`): a job given one core uses one.
    pub fn new(scene: &'s Scene, options: &RenderOptions) -> Self {
        let mut warnings = Vec::new();
        // Moving primitives are bounded over the whole shutter, and tested as the profile
        // says (the course's renderer solved the textbook quadratic).
        let accel_options = AccelOptions {
            shutter: options.shutter,
            intersect: IntersectOptions {
                roots: options.shade.profile.roots(),
                ..IntersectOptions::default()
            },
            ..options.accel
        };
        let build = || {
            rayon::join(
                || match (&scene.skybox, options.skybox) {
                    (Some(folder), true) => {
                        Some(folder.find().and_then(|dir| Ok((Skybox::load(&dir)?, dir))))
                    }
                    _ => None,
                },
                || {
                    let tracer = Tracer::new(&scene.geometry, &accel_options);
                    match options.mode {
                        // Only the stream renderer asks the rooms (`accel::interior`).
                        RenderMode::Stream => {
                            tracer.with_rooms(|m| scene.materials[m as usize].transmittance > 0.0)
                        }
                        RenderMode::Scalar => tracer,
                    }
                },
            )
        };
        // A pool that cannot start leaves the build to rayon's own: the render that
        // follows fails to start its pool, and says why.
        let (loaded, tracer) = match worker_pool(options.threads) {
            Ok(pool) => pool.install(build),
            Err(_) => build(),
        };
        let (skybox, skybox_folder) = match loaded {
            Some(Ok((sky, dir))) => {
                warnings.extend(
                    sky.damaged()
                        .iter()
                        .map(|face| skybox::damage_warning(face)),
                );
                (Some(sky), Some(dir))
            }
            Some(Err(e)) => {
                warnings.push(skybox::not_loaded_warning(&e));
                (None, None)
            }
            None => (None, None),
        };
        Stage {
            scene,
            tracer,
            skybox,
            skybox_folder,
            warnings,
        }
    }

    /// Renders the scene seen by `camera` as `options` says; its structure, shutter,
    /// profile and mode are the ones the stage was made with, and soft lights face the
    /// scene's own up vector (which an orbit keeps). The report's warnings are left
    /// empty: they are the stage's.
    pub fn render(
        &self,
        camera: &CameraSpec,
        options: &RenderOptions,
    ) -> Result<RenderReport, String> {
        options.check_size()?;
        let tracer = &self.tracer;
        let (accel_name, accel_stats) = (tracer.name(), tracer.stats());
        let build_time = tracer.build_time();
        let jittered = matches!(options.sampling, Sampling::Jittered(_));
        let shader = Shader::new(
            self.scene,
            tracer,
            self.skybox.as_ref(),
            options.shade,
            jittered,
        );
        let camera = Camera::new(camera, options.width, options.height);

        let pool = worker_pool(options.threads)?;
        let region = options.region();
        // A counted render traces the whole frame's tiles that meet its region, in full: a
        // tile's packets, and so its pixels' counts, are then the whole frame's.
        let traced = match options.count {
            true => whole_tiles(region, options.width, options.height),
            false => region,
        };
        let tiles = tiles(traced, options.height);
        let progress = Meter::new(options.progress, tiles.len());
        let start = Instant::now();
        // Each tile writes its own block of these buffers: no allocation per tile.
        let block = (TILE * TILE) as usize;
        let mut tile_pixels = vec![Vec3::ZERO; tiles.len() * block];
        let job = TileJob {
            shader: &shader,
            camera: &camera,
            options,
            tiles: &tiles,
            progress: &progress,
        };
        let (rays, work) = pool.install(|| job.trace_counting(&mut tile_pixels, region));
        let elapsed = start.elapsed();
        progress.finish();
        if options
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
        {
            return Err(STOPPED.into());
        }
        let threads = pool.current_num_threads();

        let mut film = Film::new(region.width(), region.height());
        place(
            &tiles,
            &tile_pixels,
            region,
            options.height,
            &mut film.pixels,
        );
        Ok(RenderReport {
            film,
            rays,
            elapsed,
            threads,
            build_time,
            build_threads: tracer.build_threads(),
            accel_name,
            accel_stats,
            skybox: self.skybox_folder.clone(),
            warnings: Vec::new(),
            work,
        })
    }
}

/// What every tile of a frame shares: the job its tiles are cut from.
struct TileJob<'f> {
    shader: &'f Shader<'f>,
    camera: &'f Camera,
    options: &'f RenderOptions,
    tiles: &'f [Tile],
    progress: &'f Meter,
}

impl TileJob<'_> {
    /// Renders every tile on the current thread pool into its block of `pixels`, and
    /// returns the rays traced and, where the render counts, the work of each pixel of
    /// `region`.
    fn trace_counting(
        &self,
        pixels: &mut [Vec3],
        region: Region,
    ) -> (RayCounts, Option<RenderWork>) {
        let room = self.tiles.len() * (TILE * TILE) as usize;
        if !self.options.count {
            let mut work = vec![Work::<NoCount>::default(); room];
            return (self.trace(pixels, &mut work), None);
        }
        let mut work = vec![Work::<Tally>::default(); room];
        let rays = self.trace(pixels, &mut work);
        let mut counted = vec![Work::default(); region.pixels() as usize];
        place(self.tiles, &work, region, self.options.height, &mut counted);
        (rays, Some(RenderWork { pixels: counted }))
    }

    /// Renders every tile on the current thread pool into its block of `pixels` and of
    /// `work`, and returns the rays traced.
    fn trace<C: Count>(&self, pixels: &mut [Vec3], work: &mut [Work<C>]) -> RayCounts {
        let block = (TILE * TILE) as usize;
        pixels
            .par_chunks_mut(block)
            .zip(work.par_chunks_mut(block))
            .zip(self.tiles.par_iter())
            .map(|((pixels, work), &tile)| {
                if let Some(stop) = &self.options.stop {
                    if stop.load(Ordering::Relaxed) {
                        return RayCounts::default();
                    }
                }
                let rays = render_tile(self.shader, self.camera, self.options, tile, pixels, work);
                self.progress.tile_done();
                rays
            })
            .reduce(RayCounts::default, |mut total, rays| {
                total.merge(&rays);
                total
            })
    }
}

/// Copies each tile's block of `blocks` (rows from the tile's bottom) to its place in
/// `image`, the pixels of `region` top row first, of an image `height` rows high; a
/// tile's pixels outside the region are left out.
fn place<T: Copy>(tiles: &[Tile], blocks: &[T], region: Region, height: u32, image: &mut [T]) {
    let block = (TILE * TILE) as usize;
    for (tile, values) in tiles.iter().zip(blocks.chunks(block)) {
        for (k, value) in values[..(tile.width * tile.height) as usize]
            .iter()
            .enumerate()
        {
            let (x, y) = (
                tile.x + k as u32 % tile.width,
                tile.y + k as u32 / tile.width,
            );
            let row = height - 1 - y;
            if region.contains(x, row) {
                image[((row - region.y0) * region.width() + x - region.x0) as usize] = *value;
            }
        }
    }
}

/// The pixels of the whole frame's tiles that meet `region` of a `width` x `height`
/// image, as a region: `region` grown to the tiles' edges, which lie every [`TILE`]
/// pixels from the image's left column and bottom row.
fn whole_tiles(region: Region, width: u32, height: u32) -> Region {
    let down = |n: u32| n / TILE * TILE;
    let up = |n: u32, end: u32| n.div_ceil(TILE).saturating_mul(TILE).min(end);
    // Rows counted from the bottom, as tiles count them.
    let (bottom, top) = (down(height - region.y1), up(height - region.y0, height));
    Region {
        x0: down(region.x0),
        x1: up(region.x1, width),
        y0: height - top,
        y1: height - bottom,
    }
}

/// A block of pixels; `y` counts rows from the bottom of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Tile {
    x: u32,
    y: u32,
    width: u32,
    height: u32,
}

/// The tiles covering `region` of an image `height` rows high; a region's tiles start at
/// its own corner, so it costs its pixels only.
fn tiles(region: Region, height: u32) -> Vec<Tile> {
    // The region's rows counted from the bottom, as tiles count them.
    let (bottom, top) = (height - region.y1, height - region.y0);
    let mut tiles = Vec::new();
    for y in (bottom..top).step_by(TILE as usize) {
        for x in (region.x0..region.x1).step_by(TILE as usize) {
            tiles.push(Tile {
                x,
                y,
                width: TILE.min(region.x1 - x),
                height: TILE.min(top - y),
            });
        }
    }
    tiles
}

thread_local! {
    /// Each worker's scratch memory, reset for every batch of a tile's samples: the
    /// streams' queues never go through the global allocator.
    static SCRATCH: RefCell<Bump> = RefCell::new(Bump::new());
}

/// The stream queues a tile's primary samples by blocks of this many pixels across and
/// up, the pixels of its packets: 4 x 2 for packets of eight rays, 4 x 4 for sixteen.
const PACKET_WIDTH: u32 = 4;
const PACKET_HEIGHT: u32 = (PACKET / 4) as u32;

/// The primary samples a stream traces at once, in whole pixels (one pixel where it has
/// more): with the rays they spawn, their queues stay within a core's L2 cache.
const BATCH_SAMPLES: usize = 512;

/// Writes the pixels of one tile into `pixels` and their rays' work into `work`, row by
/// row from its bottom row, and returns the rays they took.
fn render_tile<C: Count>(
    shader: &Shader,
    camera: &Camera,
    options: &RenderOptions,
    tile: Tile,
    pixels: &mut [Vec3],
    work: &mut [Work<C>],
) -> RayCounts {
    let mut rays = RayCounts::default();
    let grid = options.sampling.grid();
    let jittered = options.sampling != Sampling::Centre;
    // Sample (p, q) of pixel (x, y): the same ray and random numbers in both modes.
    let [open, close] = options.shutter;
    let film_sample = |x: u32, y: u32, p: u32, q: u32| {
        let rng = SampleRng::new(y * options.width + x, q * grid.columns + p, options.seed);
        let (jx, jy) = if jittered {
            (rng.uniform(dim::FILM_X), rng.uniform(dim::FILM_Y))
        } else {
            (0.5, 0.5)
        };
        let sx = x as f32 + (p as f32 + jx) / grid.columns as f32;
        let sy = y as f32 + (q as f32 + jy) / grid.rows as f32;
        let lens = if camera.is_thin_lens() {
            rng.unit_disk(dim::LENS_U, dim::LENS_V)
        } else {
            Vec2::ZERO
        };
        let time = if close > open {
            open + (close - open) * rng.uniform(dim::TIME)
        } else {
            open
        };
        let sample = Sample {
            rng,
            cell: [p, q],
            grid,
        };
        (FilmSample { sx, sy, lens, time }, sample)
    };
    // Each pixel sums its samples in place, then takes their mean.
    let sums = &mut pixels[..(tile.width * tile.height) as usize];
    sums.fill(Vec3::ZERO);
    SCRATCH.with_borrow_mut(|arena| {
        trace_tile(
            shader,
            camera,
            options,
            tile,
            grid,
            film_sample,
            arena,
            (sums, work),
            &mut rays,
        )
    });
    let samples = options.traced_samples().len() as f32;
    for pixel in sums.iter_mut() {
        *pixel /= samples;
    }
    rays
}

/// Adds the colour and the rays' work of every sample of every pixel of `tile` into
/// `sums` and `work` (row by row from the tile's bottom row), one ray at a time or as
/// streams as `options.mode` says, and counts the rays into `rays`; scratch space comes
/// from `arena`.
#[allow(clippy::too_many_arguments)] // the tile's setting, its scratch and its sums
fn trace_tile<C: Count>(
    shader: &Shader,
    camera: &Camera,
    options: &RenderOptions,
    tile: Tile,
    grid: SampleGrid,
    film_sample: impl Fn(u32, u32, u32, u32) -> (FilmSample, Sample),
    arena: &mut Bump,
    (sums, work): (&mut [Vec3], &mut [Work<C>]),
    rays: &mut RayCounts,
) {
    let traced = options.traced_samples();
    match options.mode {
        RenderMode::Scalar => {
            for (i, (sum, pixel_work)) in sums.iter_mut().zip(work.iter_mut()).enumerate() {
                let (x, y) = (
                    tile.x + i as u32 % tile.width,
                    tile.y + i as u32 / tile.width,
                );
                for (p, q) in grid.cells_in(traced.clone()) {
                    let (film, sample) = film_sample(x, y, p, q);
                    let ray = camera.ray(&film);
                    let counts = (&mut *rays, &mut *pixel_work);
                    *sum += shader.trace(&ray, RayKind::Primary, &sample, 1, 1.0, counts);
                }
            }
        }
        RenderMode::Stream => {
            // The tile's pixels in the packets' order: blocks of 4 x 2 (or 4 x 4), each
            // block's row by row, so that a packet's rays leave through as few pixels as
            // it can hold (a block's at 1 spp, one pixel's from 8 spp up).
            let mut order = [(0, 0); (TILE * TILE) as usize];
            let mut pixels = 0;
            for by in (0..tile.height).step_by(PACKET_HEIGHT as usize) {
                for bx in (0..tile.width).step_by(PACKET_WIDTH as usize) {
                    for l in 0..PACKET_WIDTH * PACKET_HEIGHT {
                        let (x, y) = (bx + l % PACKET_WIDTH, by + l / PACKET_WIDTH);
                        if x < tile.width && y < tile.height {
                            order[pixels] = (x, y);
                            pixels += 1;
                        }
                    }
                }
            }
            // Each pixel's samples in their order, traced a batch of pixels at a time, each
            // batch's queues in the arena anew: a whole tile's at 16 spp outgrow the cache.
            let pixels_per_batch = (BATCH_SAMPLES / traced.len()).max(1);
            for batch in order[..pixels].chunks(pixels_per_batch) {
                arena.reset();
                let capacity = batch.len() * traced.len();
                let mut gathered = ArenaVec::with_capacity_in(capacity, arena);
                for &(x, y) in batch {
                    for (p, q) in grid.cells_in(traced.clone()) {
                        let (film, sample) = film_sample(tile.x + x, tile.y + y, p, q);
                        gathered.push((film, sample, y * tile.width + x));
                    }
                }
                // Their rays eight at a time; a short last chunk repeats its first sample.
                let mut primary = stream::Queue::primary_in(gathered.len(), arena);
                for chunk in gathered.chunks(8) {
                    let film = |k: usize| &chunk.get(k).unwrap_or(&chunk[0]).0;
                    let rays = camera.rays8(film);
                    for (k, &(_, sample, pixel)) in chunk.iter().enumerate() {
                        primary.push_primary(rays.ray(k), sample, pixel);
                    }
                }
                stream::trace(shader, arena, primary, (&mut *sums, &mut *work), rays);
            }
        }
    }
}
