//! From a scene to an image: primary rays from the [`camera`], colours from the Whitted
//! [`shade`]r, pixels gathered into a [`film`] by tiles spread over threads.

pub mod camera;
pub mod film;
pub mod sampler;
pub mod shade;
pub mod skybox;

use std::time::{Duration, Instant};

use glam::{Vec2, Vec3};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::accel::{Accel, AccelKind, AccelOptions, Tracer};
use crate::scene::Scene;
use camera::Camera;
use film::Film;
use sampler::{dim, SampleRng};
use shade::{ShadeOptions, Shader};
use skybox::Skybox;

/// Tiles are square blocks of this many pixels a side: the unit of work of a thread.
pub const TILE: u32 = 16;

/// Largest image rendered, in pixels (6 GiB of film and tile memory).
pub const MAX_PIXELS: u64 = 1 << 28;

/// Where the samples of a pixel go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// One sample through the pixel centre.
    Centre,
    /// A k x k grid of cells, one sample jittered in each (P3F.md 6.1).
    Jittered(u32),
}

impl Sampling {
    /// The file's `spp k`: 0 is the centre, k > 0 a k x k jittered grid.
    pub fn from_file_spp(k: u32) -> Self {
        if k == 0 {
            Sampling::Centre
        } else {
            Sampling::Jittered(k)
        }
    }

    /// `--spp N` on the command line: N must be a perfect square; 1 is the pixel centre.
    pub fn from_samples_per_pixel(n: u32) -> Result<Self, String> {
        let k = (n as f64).sqrt().round() as u32;
        match n {
            0 => Err("--spp must be at least 1".into()),
            1 => Ok(Sampling::Centre),
            _ if k * k == n && k <= crate::scene::p3f::MAX_SPP_SIDE => Ok(Sampling::Jittered(k)),
            _ => Err(format!(
                "--spp {n} is not a perfect square (k x k samples per pixel, such as 4, 16 or 64)"
            )),
        }
    }

    pub fn samples_per_pixel(self) -> u32 {
        match self {
            Sampling::Centre => 1,
            Sampling::Jittered(k) => k * k,
        }
    }
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
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// The acceleration structure and how to build it.
    pub accel: AccelOptions,
}

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
            progress: false,
            accel: AccelOptions {
                kind: scene.accel.unwrap_or(AccelKind::Bvh),
                ..AccelOptions::default()
            },
        }
    }

    /// Refuses images too large to hold in memory, saying how much they would need.
    pub fn check_size(&self) -> Result<(), String> {
        let pixels = self.width as u64 * self.height as u64;
        if pixels <= MAX_PIXELS {
            return Ok(());
        }
        // The film and the tiles' copies hold 24 bytes a pixel.
        Err(format!(
            "a {}x{} image needs {:.1} GiB; the limit is {MAX_PIXELS} pixels",
            self.width,
            self.height,
            (pixels * 24) as f64 / (1u64 << 30) as f64
        ))
    }
}

/// What a render produced besides the image.
#[derive(Clone, Debug)]
pub struct RenderReport {
    pub film: Film,
    /// Every ray traced: primary, shadow and secondary.
    pub rays: u64,
    /// Time spent rendering, after the structure was built.
    pub elapsed: Duration,
    pub build_time: Duration,
    /// The structure's name and statistics lines.
    pub accel_name: String,
    pub accel_stats: Vec<String>,
    pub warnings: Vec<String>,
}

/// Renders `scene` with the structure `options.accel` asks for.
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<RenderReport, String> {
    options.check_size()?;
    let mut warnings = Vec::new();
    let skybox = match (&scene.skybox, options.skybox) {
        (Some(dir), true) => match Skybox::load(dir) {
            Ok(sky) => Some(sky),
            Err(e) => {
                warnings.push(format!(
                    "skybox not loaded ({e}); the background colour is used instead"
                ));
                None
            }
        },
        _ => None,
    };
    let (accel, build_time) = Accel::build(&scene.geometry, &options.accel);
    let (accel_name, accel_stats) = (accel.name(), accel.stats());
    let tracer = Tracer::new(&scene.geometry, accel);
    let shader = Shader::new(scene, &tracer, skybox.as_ref(), options.shade);
    let camera = Camera::new(&scene.camera, options.width, options.height);

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start the worker threads: {e}"))?;
    let tiles = tiles(options.width, options.height);
    let progress = if options.progress {
        let bar = ProgressBar::new(tiles.len() as u64);
        bar.set_style(
            ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {percent:>3}% eta {eta}")
                .expect("the template is valid"),
        );
        bar
    } else {
        ProgressBar::hidden()
    };

    let start = Instant::now();
    let rendered: Vec<(Tile, Vec<Vec3>, u64)> = pool.install(|| {
        tiles
            .par_iter()
            .map(|&tile| {
                let (pixels, rays) = render_tile(&shader, &camera, options, tile);
                progress.inc(1);
                (tile, pixels, rays)
            })
            .collect()
    });
    let elapsed = start.elapsed();
    progress.finish_and_clear();

    let mut film = Film::new(options.width, options.height);
    let mut rays = 0;
    for (tile, pixels, tile_rays) in rendered {
        rays += tile_rays;
        for (k, colour) in pixels.into_iter().enumerate() {
            let (x, y) = (
                tile.x + k as u32 % tile.width,
                tile.y + k as u32 / tile.width,
            );
            let row = options.height - 1 - y;
            film.pixels[(row * options.width + x) as usize] = colour;
        }
    }
    Ok(RenderReport {
        film,
        rays,
        elapsed,
        build_time,
        accel_name,
        accel_stats,
        warnings,
    })
}

/// A block of pixels; `y` counts rows from the bottom of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Tile {
    x: u32,
    y: u32,
    width: u32,
    height: u32,
}

fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut tiles = Vec::new();
    for y in (0..height).step_by(TILE as usize) {
        for x in (0..width).step_by(TILE as usize) {
            tiles.push(Tile {
                x,
                y,
                width: TILE.min(width - x),
                height: TILE.min(height - y),
            });
        }
    }
    tiles
}

/// The pixels of one tile, row by row from its bottom row, and the rays they took.
fn render_tile(
    shader: &Shader,
    camera: &Camera,
    options: &RenderOptions,
    tile: Tile,
) -> (Vec<Vec3>, u64) {
    let mut rays = 0;
    let mut pixels = Vec::with_capacity((tile.width * tile.height) as usize);
    for y in tile.y..tile.y + tile.height {
        for x in tile.x..tile.x + tile.width {
            let pixel = y * options.width + x;
            let (k, jittered) = match options.sampling {
                Sampling::Centre => (1, false),
                Sampling::Jittered(k) => (k, true),
            };
            let mut sum = Vec3::ZERO;
            for q in 0..k {
                for p in 0..k {
                    let rng = SampleRng::new(pixel, q * k + p, options.seed);
                    let (jx, jy) = if jittered {
                        (rng.uniform(dim::FILM_X), rng.uniform(dim::FILM_Y))
                    } else {
                        (0.5, 0.5)
                    };
                    let sx = x as f32 + (p as f32 + jx) / k as f32;
                    let sy = y as f32 + (q as f32 + jy) / k as f32;
                    let lens = if camera.is_thin_lens() {
                        rng.unit_disk(dim::LENS_U, dim::LENS_V)
                    } else {
                        Vec2::ZERO
                    };
                    sum += shader.trace(&camera.ray(sx, sy, lens, 0.0), 1, 1.0, &mut rays);
                }
            }
            let colour = sum / (k * k) as f32;
            pixels.push(colour);
        }
    }
    (pixels, rays)
}
