//! The `p3trace` command: parses the command line, calls the library, and maps failures
//! to exit codes (1 a render or I/O failure, 2 bad usage or a bad scene, 128 + N after
//! signal N: 130 Ctrl-C, 143 SIGTERM, 129 SIGHUP).

mod cli;
mod manual;
mod statistics;
mod window;

use std::io::{IsTerminal, Write};
use std::path::{Component, Path, PathBuf};
use std::process::ExitCode;

use clap::{CommandFactory, Parser};

use cli::{
    BenchArgs, Cli, Command, CompareArgs, GenCommand, ImageArgs, InfoArgs, MergeArgs, RenderArgs,
    SceneOutput, Settings,
};
use p3trace::accel::count::Counter;
use p3trace::accel::{AccelKind, AccelOptions, Tracer};
use p3trace::compare::levels;
use p3trace::farm::{self, Canvas};
use p3trace::generate::{dragon, mountain, random, skybox, sphereflake};
use p3trace::imaging::false_colour::Scale;
use p3trace::imaging::format::{ImageOutput, OutputFormat};
use p3trace::imaging::openexr::Placement;
use p3trace::imaging::Film;
use p3trace::intersect::IntersectOptions;
use p3trace::plural::{count, noun};
use p3trace::prim::PrimKind;
use p3trace::render::cost::{self, CostMap};
use p3trace::render::progress::Progress;
use p3trace::render::region::Region;
use p3trace::render::sampler::SampleGrid;
use p3trace::render::skybox::{damage_warning, not_loaded_warning, FaceFiles};
use p3trace::render::{self, RenderOptions, RenderReport, RenderWork, Sampling};
use p3trace::scene::{self, Frame, Light, Scene};

/// Why the command failed, and so which exit code it gives.
pub(crate) enum Failure {
    /// Bad usage or a bad scene: exit 2.
    Usage(String),
    /// A render or I/O failure: exit 1.
    Run(String),
}

/// The CPU check, run by the dynamic loader before any other code of the binary (the
/// standard library's start-up included, which link-time optimisation compiles for the
/// target CPU too): a CPU without the instructions the binary was compiled for would
/// otherwise die of an illegal instruction.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
#[used]
#[link_section = ".preinit_array"]
static CHECK_CPU_FIRST: unsafe extern "C" fn() = p3trace::machine::p3trace_check_cpu;

fn main() -> ExitCode {
    // A closed pipe ends the program quietly, as it does other command-line tools: Rust
    // ignores SIGPIPE, so every `println!` into a closed pipe would panic instead.
    #[cfg(unix)]
    // SAFETY: restoring a signal's default action, before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    #[cfg(unix)]
    exit_cleanly_on_signals();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => run_render(&args),
        Command::View(args) => window::run(&args),
        Command::Info(args) => run_info(&args),
        Command::Compare(args) => run_compare(&args),
        Command::Merge(args) => run_merge(&args),
        Command::Gen(command) => run_gen(command),
        Command::Bench(args) => run_bench(&args),
        Command::Completions { shell } => write_to_stdout(
            &manual::completion_script(Cli::command(), shell),
            "the completion script",
        ),
        Command::Man => {
            write_to_stdout(manual::man_page(Cli::command()).as_bytes(), "the man page")
        }
    };
    match result {
        Ok(code) => code,
        Err(Failure::Usage(message)) => {
            eprintln!("p3trace: error: {message}");
            ExitCode::from(2)
        }
        Err(Failure::Run(message)) => {
            eprintln!("p3trace: error: {message}");
            ExitCode::from(1)
        }
    }
}

/// On Ctrl-C (SIGINT), SIGTERM or SIGHUP: removes the file being written, if any, and
/// exits 128 + the signal's number, the status a shell gives a process the signal ended.
/// The signals are blocked in every thread (threads inherit the mask: this runs before
/// any other exists) and taken by one that waits for them, so the cleanup runs as
/// ordinary code, not in a signal handler. Should that thread fail to start, the signals
/// keep their default action: the target is still never truncated, but a `.partial` file
/// may stay.
#[cfg(unix)]
fn exit_cleanly_on_signals() {
    const SIGNALS: [(libc::c_int, &str); 3] = [
        (libc::SIGINT, "SIGINT"),
        (libc::SIGTERM, "SIGTERM"),
        (libc::SIGHUP, "SIGHUP"),
    ];
    // SAFETY: `set` is initialised by sigemptyset before use, and the mask changes this
    // thread's only.
    let set = unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for (signal, _) in SIGNALS {
            libc::sigaddset(&mut set, signal);
        }
        if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
            return;
        }
        set
    };
    let waiter = std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || loop {
            let mut signal = 0;
            // SAFETY: `set` is a valid signal set and `signal` a place for the answer;
            // sigwait fails only for an invalid set.
            if unsafe { libc::sigwait(&set, &mut signal) } != 0 {
                continue;
            }
            let _held_until_exit = p3trace::output::abandon_partial_files();
            let name = SIGNALS.iter().find(|(s, _)| *s == signal).map(|(_, n)| *n);
            eprintln!("p3trace: interrupted ({})", name.unwrap_or("a signal"));
            std::process::exit(128 + signal);
        });
    if waiter.is_err() {
        // SAFETY: as above.
        unsafe {
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        }
    }
}

/// `n` with its digits in groups of three: `2,230,114`.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, digit) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(digit);
    }
    out
}

/// Whether `--json` (or `-o`) names standard output.
fn is_stdout(target: Option<&Path>) -> bool {
    target == Some(Path::new("-"))
}

/// Where the lines for people go: stdout, or stderr when the statistics or the image
/// take stdout.
fn human_output(stdout_taken: bool) -> fn(&str) {
    if stdout_taken {
        |line| eprintln!("{line}")
    } else {
        |line| println!("{line}")
    }
}

/// `16 spp`, or `8 spp (4x2)` where the grid is not square.
fn samples_label(sampling: Sampling) -> String {
    let grid = sampling.grid();
    if grid.columns == grid.rows {
        format!("{} spp", grid.cells())
    } else {
        format!("{} spp ({}x{})", grid.cells(), grid.columns, grid.rows)
    }
}

/// The scene argument that names the course's random scene rather than a file.
pub(crate) const RANDOM_SCENE: &str = "random";

/// Reads the scene `path` names in `frame`: a P3F file, or for `random` the course's
/// random scene laid out by `seed`. A file that cannot be read is an I/O failure (exit 1),
/// a bad scene a usage one (exit 2, at its `file:line:col`).
fn read_scene(path: &Path, seed: u64, frame: Frame) -> Result<Scene, Failure> {
    if path == Path::new(RANDOM_SCENE) {
        let text = random::random_scene(seed, None);
        return scene::parse_str_in(&text, RANDOM_SCENE, Path::new(""), frame)
            .map_err(|e| Failure::Run(e.to_string()));
    }
    scene::parse_file_in(path, frame).map_err(|e| match e {
        scene::FileError::Read(message) => Failure::Run(message),
        scene::FileError::Parse(e) => Failure::Usage(e.to_string()),
    })
}

/// The hash of the text of the scene `path` names (as for [`read_scene`]), which goes
/// into an EXR file's note for `merge` to check.
fn scene_hash(path: &Path, seed: u64) -> Result<u64, Failure> {
    if path == Path::new(RANDOM_SCENE) {
        return Ok(farm::scene_hash(
            random::random_scene(seed, None).as_bytes(),
        ));
    }
    let bytes = std::fs::read(path)
        .map_err(|e| Failure::Run(format!("cannot read '{}': {e}", path.display())))?;
    Ok(farm::scene_hash(&bytes))
}

/// [`read_scene`], then its warnings on stderr; a scene without a camera is refused.
fn load_scene(path: &Path, seed: u64, frame: Frame) -> Result<Scene, Failure> {
    let scene = read_scene(path, seed, frame)?;
    for w in &scene.warnings {
        eprintln!(
            "{}:{}:{}: warning: {}",
            scene.name, w.line, w.column, w.message
        );
    }
    if !scene.has_camera {
        return Err(Failure::Usage(format!(
            "{}: the scene has no camera block 'v'",
            scene.name
        )));
    }
    Ok(scene)
}

/// Refuses an output file that cannot be written (its folder is missing, say) before the
/// work whose result it would hold: an I/O failure (exit 1), as the write would have been.
fn check_output(path: &Path) -> Result<(), Failure> {
    p3trace::output::check_writable(path).map_err(Failure::Run)
}

/// [`check_output`] for the target of `--json`, if any (`-` is standard output).
fn check_statistics_target(target: Option<&Path>) -> Result<(), Failure> {
    target.map_or(Ok(()), |target| {
        statistics::check_target(target).map_err(Failure::Run)
    })
}

fn run_render(args: &RenderArgs) -> Result<ExitCode, Failure> {
    let output = render_output(args)?;
    let (scene, scene_hash) = render_scene(args)?;
    let options = render_options(args, &scene)?;
    let region = options.region();
    output
        .check_size(region.width(), region.height())
        .map_err(Failure::Usage)?;
    let cost = cost_map(args, &options)?;
    let report = render::render(&scene, &options).map_err(Failure::Run)?;
    for w in &report.warnings {
        eprintln!("p3trace: warning: {w}");
    }
    let made_by = cost.map(|map| (map, report.accel_name.as_str()));
    let note = farm::note(
        &scene,
        scene_hash,
        &options,
        report.skybox.is_some(),
        made_by,
        args.tile,
    );
    let placement = Placement {
        image: (options.width, options.height),
        origin: (region.x0, region.y0),
        note: Some(note),
    };
    match (&cost, &report.work) {
        (Some(map), Some(work)) => {
            let film = map.film(work, region.width(), region.height());
            let scale = Scale {
                max: args.cost_max,
                log: args.cost_scale,
            };
            cost::write(&film, &output, &placement, map, scale)
        }
        _ => report.film.write_placed(&output, &placement),
    }
    .map_err(Failure::Run)?;
    summarise(args, &scene, &options, &report, &output)?;
    Ok(ExitCode::SUCCESS)
}

/// What `--cost` asks the image to show, refused for a counter that the structure never
/// counts.
fn cost_map(args: &RenderArgs, options: &RenderOptions) -> Result<Option<CostMap>, Failure> {
    let Some(counter) = args.cost else {
        return Ok(None);
    };
    let counts = options.accel.kind.counters();
    if !counts.contains(&counter) {
        let names: Vec<&str> = counts.iter().map(|c| c.name()).collect();
        let structure = match options.accel.kind {
            AccelKind::None => "brute force",
            AccelKind::Grid => "the grid",
            AccelKind::Bvh => "a BVH",
        };
        return Err(Failure::Usage(format!(
            "--cost {}: {structure} counts no {} ({} counted there: {}){}",
            counter.name(),
            counter.meaning(),
            if names.len() == 1 {
                "only prims is"
            } else {
                "these are"
            },
            names.join(", "),
            if counter == Counter::Cells {
                "; cells are the grid's, --accel grid"
            } else {
                ""
            }
        )));
    }
    Ok(Some(CostMap {
        counter,
        rays: args.cost_rays,
    }))
}

/// The image `render` writes: `-o` (`-` for standard output), or the scene's name with
/// the format's extension in the current folder.
fn render_output(args: &RenderArgs) -> Result<ImageOutput, Failure> {
    let target = args.output.clone().unwrap_or_else(|| {
        let stem = args.scene.file_stem().unwrap_or_default().to_string_lossy();
        let format = args.image.format.unwrap_or(OutputFormat::Png);
        PathBuf::from(format!("{stem}.{}", format.extension()))
    });
    // Refuse a bad output name, or one that cannot be written, before spending time on
    // the render.
    let output = image_output(&target, &args.image)?;
    if args.cost.is_some() && output.format == OutputFormat::Hdr {
        return Err(Failure::Usage(cost::refuse_hdr(&output)));
    }
    if output.path.is_none() && is_stdout(args.json.as_deref()) {
        return Err(Failure::Usage(
            "-o - and --json - both write to standard output: send one of them to a file".into(),
        ));
    }
    check_statistics_target(args.json.as_deref())?;
    Ok(output)
}

/// The image `-o TARGET` names with `--format` and `--quality`, refused (exit 2) where
/// they disagree, and (exit 1) where a file cannot be written.
fn image_output(target: &Path, image: &ImageArgs) -> Result<ImageOutput, Failure> {
    let output = ImageOutput::new(target, image.format, image.quality).map_err(Failure::Usage)?;
    if let Some(path) = &output.path {
        check_output(path)?;
    }
    Ok(output)
}

/// The scene as `render` takes it, read in the profile's frame, its lens as the flags set
/// it; and the hash of its text, for the image's note.
fn render_scene(args: &RenderArgs) -> Result<(Scene, u64), Failure> {
    let scene = settings_scene(&args.scene, &args.settings)?;
    let scene_hash = scene_hash(&args.scene, args.settings.seed)?;
    Ok((scene, scene_hash))
}

/// The scene `path` names as `render` and `view` take it: read in the profile's frame,
/// its lens as the flags set it.
pub(crate) fn settings_scene(path: &Path, settings: &Settings) -> Result<Scene, Failure> {
    let mut scene = load_scene(path, settings.seed, settings.profile.frame())?;
    if let Some(aperture) = settings.aperture {
        scene.camera.aperture = aperture;
    }
    if let Some(focal) = settings.focal {
        scene.camera.focal = focal;
    }
    scene
        .camera
        .validate()
        .map_err(|e| Failure::Usage(format!("{}: {e}", scene.name)))?;
    Ok(scene)
}

/// The scene's render options as the flags change them; an image too large is refused.
fn render_options(args: &RenderArgs, scene: &Scene) -> Result<RenderOptions, Failure> {
    let mut options = settings_options(&args.settings, scene)?;
    options.progress = match (args.quiet, std::io::stderr().is_terminal()) {
        (true, _) => Progress::Hidden,
        (false, true) => Progress::Bar,
        (false, false) => Progress::Lines,
    };
    options.region = region(args, options.width, options.height)?;
    options.count = args.stats || args.cost.is_some();
    options.check_size().map_err(Failure::Usage)?;
    Ok(options)
}

/// The scene's render options as the flags that `render` and `view` share change them.
pub(crate) fn settings_options(
    settings: &Settings,
    scene: &Scene,
) -> Result<RenderOptions, Failure> {
    let mut options = RenderOptions::from_scene(scene);
    if let Some((w, h)) = settings.resolution {
        (options.width, options.height) = (w, h);
    }
    if let Some(n) = settings.spp {
        options.sampling = Sampling::from_samples_per_pixel(n).map_err(Failure::Usage)?;
    }
    options.shade = options.shade.with_profile(settings.profile);
    if let Some(depth) = settings.max_depth {
        options.shade.max_depth = depth;
    }
    options.shade.schlick = settings.schlick;
    options.shade.soft_light_size = settings.soft_shadows.then_some(settings.light_size);
    options.shade.light_grid = SampleGrid::with_cells(settings.light_samples);
    options.shade.roughness = settings.roughness.unwrap_or(0.0);
    if let Some(shutter) = settings.shutter {
        options.shutter = shutter;
    }
    options.skybox = !settings.no_skybox;
    options.threads = settings.threads.map(|n| n as usize);
    options.seed = settings.seed;
    options.mode = settings.mode;
    options.accel = settings.accel.options(scene.accel);
    Ok(options)
}

/// The region of a `width` x `height` image that `--crop`, `--pixel-bounds` or `--tile`
/// asks for, if any.
fn region(args: &RenderArgs, width: u32, height: u32) -> Result<Option<Region>, Failure> {
    match (args.crop, args.pixel_bounds, args.tile) {
        (Some(crop), _, _) => Some(Region::crop(crop, width, height)),
        (_, Some(bounds), _) => Some(Region::pixel_bounds(bounds, width, height)),
        (_, _, Some(t)) => Some(Region::tile(t.index, t.count, width, height)),
        _ => None,
    }
    .transpose()
    .map_err(Failure::Usage)
}

/// What `render` says when done: the structure's build with `--stats`, the closing line
/// unless `--quiet`, and the statistics with `--json`.
fn summarise(
    args: &RenderArgs,
    scene: &Scene,
    options: &RenderOptions,
    report: &RenderReport,
    output: &ImageOutput,
) -> Result<(), Failure> {
    let say = human_output(is_stdout(args.json.as_deref()) || output.path.is_none());
    if args.stats {
        say(&format!(
            "{}: built in {:.3} s",
            report.accel_name,
            report.build_time.as_secs_f64()
        ));
        for line in &report.accel_stats {
            say(&format!("  {line}"));
        }
        let skybox = report.skybox.as_ref().map(|dir| dir.display().to_string());
        say(&format!("skybox: {}", skybox.as_deref().unwrap_or("none")));
        if let Some(work) = &report.work {
            for line in work_lines(work) {
                say(&line);
            }
        }
    }
    if !args.quiet {
        say(&closing_line(scene, options, report, output));
    }
    if let Some(target) = &args.json {
        let value = statistics::render(scene, options, report, output);
        statistics::write(target, &value).map_err(Failure::Run)?;
    }
    Ok(())
}

/// The traversal work of a render's rays by kind, in all and per ray, for the counters
/// that counted anything: the rays of the pixels of the image (or region).
fn work_lines(work: &RenderWork) -> Vec<String> {
    let w = work.by_kind();
    let total = w.total();
    let counters: Vec<Counter> = Counter::ALL
        .into_iter()
        .filter(|&c| total.get(c) > 0)
        .collect();
    let mut head = format!("traversal work {:>15}", "rays");
    for c in &counters {
        head.push_str(&format!(" {:>14}", c.name()));
    }
    let mut lines = vec![head];
    for (kind, tally) in w.named() {
        let rays = u64::from(tally.rays);
        let mut all = format!("  {kind:<10} {:>17}", grouped(rays));
        let mut each = format!("  {:<10} {:>17}", "", "per ray");
        for &c in &counters {
            let sum = u64::from(tally.get(c));
            all.push_str(&format!(" {:>14}", grouped(sum)));
            each.push_str(&format!(" {:>14.3}", sum as f64 / rays.max(1) as f64));
        }
        lines.push(all);
        lines.push(each);
    }
    lines
}

/// `balls_low.p3f: 512x512, 1 spp, 0.128 s, 1,171,239 rays, 9.17 Mrays/s -> balls_low.png`,
/// the region after the size when there is one.
fn closing_line(
    scene: &Scene,
    options: &RenderOptions,
    report: &RenderReport,
    output: &ImageOutput,
) -> String {
    let seconds = report.elapsed.as_secs_f64();
    let rays = report.rays.total();
    let part = match options.region {
        Some(r) => format!(" (region {},{},{},{})", r.x0, r.x1, r.y0, r.y1),
        None => String::new(),
    };
    format!(
        "{}: {}x{}{part}, {}, {:.3} s, {} {}, {:.2} Mrays/s -> {}",
        scene.name,
        options.width,
        options.height,
        samples_label(options.sampling),
        seconds,
        grouped(rays),
        noun(rays as f64, "ray", "rays"),
        rays as f64 / 1e6 / seconds.max(1e-9),
        output.name()
    )
}

fn run_info(args: &InfoArgs) -> Result<ExitCode, Failure> {
    // Described in the file's coordinates, as written.
    let scene = load_scene(&args.scene, args.seed, Frame::File)?;
    let g = &scene.geometry;
    println!("scene: {}", scene.name);
    let total: usize = PrimKind::ALL.iter().map(|&k| g.count(k)).sum();
    println!("objects: {total}");
    for kind in PrimKind::ALL {
        println!("  {:<20} {}", kind.name(), g.count(kind));
    }
    if scene.meshes > 0 {
        println!(
            "  ({} from {})",
            count(scene.mesh_triangles as u64, "triangle", "triangles"),
            count(scene.meshes as u64, "mesh", "meshes")
        );
    }
    let smooth = g.triangles.vertex_normals.len() as u64;
    if smooth > 0 {
        println!(
            "  ({} vertex normals)",
            count(smooth, "triangle has", "triangles have")
        );
    }
    println!("materials: {}", scene.materials.len());
    let lights: Vec<String> = Light::KINDS
        .iter()
        .map(|&kind| {
            let n = scene.lights.iter().filter(|l| l.kind() == kind).count();
            format!("{n} {kind}")
        })
        .collect();
    println!("lights: {}", lights.join(", "));
    let c = &scene.camera;
    println!(
        "camera: from {} at {} up {}, angle {}, {}x{}, hither {}, aperture {}, focal {}",
        c.from, c.at, c.up, c.angle, c.width, c.height, c.hither, c.aperture, c.focal
    );
    println!("background: {}", scene.background);
    match scene.skybox.as_ref().map(|folder| folder.find()) {
        Some(Ok(dir)) => {
            println!("skybox: {}", dir.display());
            // What `render` would say of its faces, read but not decoded.
            let warnings = match FaceFiles::read(&dir) {
                Ok(faces) => faces.damaged().iter().map(|f| damage_warning(f)).collect(),
                Err(e) => vec![not_loaded_warning(&e)],
            };
            for w in warnings {
                eprintln!("p3trace: warning: {w}");
            }
        }
        Some(Err(e)) => println!("skybox: missing ({e}): the background colour is used"),
        None => println!("skybox: none"),
    }
    let accel = scene
        .accel
        .map_or("not set".to_string(), |a| format!("{a:?}").to_lowercase());
    println!("accel (file): {accel}");
    println!("spp (file): {}", scene.spp);
    // The structure as `render` builds it: over positions in the profile's frame, moving
    // spheres bounded over the scene's default shutter, spheres padded for the profile's
    // roots.
    let frame = args.profile.frame();
    let rendered = (frame != Frame::File)
        .then(|| read_scene(&args.scene, args.seed, frame))
        .transpose()?;
    let rendered = rendered.as_ref().unwrap_or(&scene);
    let options = AccelOptions {
        shutter: RenderOptions::from_scene(rendered).shutter,
        intersect: IntersectOptions {
            sphere_roots: args.profile.sphere_roots(),
            ..IntersectOptions::default()
        },
        ..args.accel.options(rendered.accel)
    };
    let structure = Tracer::new(&rendered.geometry, &options);
    println!(
        "structure: {}, built in {:.3} s",
        structure.name(),
        structure.build_time().as_secs_f64()
    );
    for line in structure.stats() {
        println!("  {line}");
    }
    Ok(ExitCode::SUCCESS)
}

fn run_compare(args: &CompareArgs) -> Result<ExitCode, Failure> {
    // Refuse a bad name for the heat map, or one that cannot be written, before reading
    // the images.
    if let Some(path) = &args.diff {
        OutputFormat::from_path(path).map_err(Failure::Usage)?;
        check_output(path)?;
    }
    match (cost_part(&args.first)?, cost_part(&args.second)?) {
        (Some(a), Some(b)) => return compare_costs(args, &a, &b),
        (None, None) => {}
        (a, _) => {
            let (cost, colour) = match a {
                Some(_) => (&args.first, &args.second),
                None => (&args.second, &args.first),
            };
            return Err(Failure::Usage(format!(
                "{} is a cost image (render --cost) and {} is not: they do not compare",
                cost.display(),
                colour.display()
            )));
        }
    }
    let a = p3trace::compare::load(&args.first).map_err(Failure::Usage)?;
    let b = p3trace::compare::load(&args.second).map_err(Failure::Usage)?;
    let c = p3trace::compare::compare(&a, &b, args.tolerance).map_err(Failure::Usage)?;
    let share = 100.0 * c.within_tolerance;
    println!("size: {}x{}", c.width, c.height);
    println!("psnr: {:.2} dB", c.psnr);
    println!("ssim: {:.4}", c.ssim);
    println!("max channel difference: {}", levels(c.max_difference));
    println!("pixels within {}: {share:.3}%", levels(args.tolerance));
    if let Some(path) = &args.diff {
        let full = args.diff_scale;
        c.heat_map(full).write(path).map_err(Failure::Run)?;
        println!("diff: {} ({})", path.display(), c.heat_map_scale(full));
    }
    if share + 1e-9 < args.min_match {
        println!(
            "differ: fewer than {}% of pixels within the tolerance",
            args.min_match
        );
        return Ok(ExitCode::from(1));
    }
    println!("match");
    Ok(ExitCode::SUCCESS)
}

/// The cost image (`render --cost`) in the EXR file `path`, and what it shows; `None` for
/// any other file.
fn cost_part(path: &Path) -> Result<Option<(CostMap, farm::Part)>, Failure> {
    if OutputFormat::from_path(path) != Ok(OutputFormat::Exr) {
        return Ok(None);
    }
    let bytes = std::fs::read(path)
        .map_err(|e| Failure::Usage(format!("cannot read {}: {e}", path.display())))?;
    // A file that is not a part (no note of p3trace's) is for the image comparison.
    let Ok(part) = farm::read_part(&bytes, &path.display().to_string()) else {
        return Ok(None);
    };
    let map = CostMap::from_note(&part.identity).map_err(Failure::Usage)?;
    Ok(map.map(|map| (map, part)))
}

/// `compare` of two cost images: their totals and their ratio, the second's over the
/// first's.
fn compare_costs(
    args: &CompareArgs,
    (map_a, a): &(CostMap, farm::Part),
    (map_b, b): &(CostMap, farm::Part),
) -> Result<ExitCode, Failure> {
    if map_a.counter != map_b.counter {
        return Err(Failure::Usage(format!(
            "{} counts {} and {} counts {}: compare cost images of one counter",
            args.first.display(),
            map_a.counter.name(),
            args.second.display(),
            map_b.counter.name()
        )));
    }
    let film = |p: &farm::Part| Film {
        width: p.region.width(),
        height: p.region.height(),
        pixels: p.pixels.clone(),
    };
    let r = p3trace::compare::cost_ratio(&film(a), &film(b)).map_err(Failure::Usage)?;
    let made_by = |p: &farm::Part| {
        p.identity
            .lines()
            .find_map(|l| l.strip_prefix("cost: "))
            .unwrap_or_default()
            .to_string()
    };
    println!("cost: {} and {}", made_by(a), made_by(b));
    println!("size: {}x{}", a.region.width(), a.region.height());
    println!(
        "total: {} and {}",
        grouped(r.totals[0] as u64),
        grouped(r.totals[1] as u64)
    );
    println!("mean per pixel: {:.3} and {:.3}", r.means[0], r.means[1]);
    println!("largest: {} and {}", r.largest[0], r.largest[1]);
    println!("ratio (second / first): {:.4}", r.ratio);
    println!("pixels larger in the second: {:.3}%", 100.0 * r.larger);
    Ok(ExitCode::SUCCESS)
}

fn run_merge(args: &MergeArgs) -> Result<ExitCode, Failure> {
    // Refuse a bad output name, or one that cannot be written, before reading the parts.
    let output = (args.output.as_deref())
        .map(|target| image_output(target, &args.image))
        .transpose()?;
    // One part in memory at a time besides the canvas.
    let mut canvas: Option<Canvas> = None;
    for path in &args.parts {
        let bytes = std::fs::read(path)
            .map_err(|e| Failure::Run(format!("cannot read '{}': {e}", path.display())))?;
        let part = farm::read_part(&bytes, &path.display().to_string()).map_err(Failure::Usage)?;
        canvas
            .get_or_insert_with(|| Canvas::new(&part))
            .add(&part)
            .map_err(Failure::Usage)?;
    }
    let say_tiles = |tiles: Vec<String>| {
        let mut out = std::io::stdout().lock();
        tiles
            .iter()
            .try_for_each(|t| writeln!(out, "{t}"))
            .map_err(|e| Failure::Run(format!("cannot write the missing tiles: {e}")))
    };
    let Some(canvas) = canvas else {
        return match (args.missing, args.tiles) {
            // Every task of the array was lost: all of them are to run again.
            (true, Some(n)) => {
                say_tiles((0..n).map(|i| format!("{i}/{n}")).collect())?;
                Ok(ExitCode::SUCCESS)
            }
            _ => Err(Failure::Usage(
                "no parts to merge (with --missing, --tiles N lists all N tiles)".into(),
            )),
        };
    };
    let cost = CostMap::from_note(&canvas.identity).map_err(Failure::Usage)?;
    let scaled = [
        (args.cost_max.is_some(), "--cost-max"),
        (args.cost_scale.is_some(), "--cost-scale"),
    ];
    if let Some((_, flag)) = scaled.iter().find(|(given, _)| cost.is_none() && *given) {
        return Err(Failure::Usage(format!(
            "{flag}: the parts are of a colour image, not of a cost image (render --cost)"
        )));
    }
    let tile_count = args.tiles.or_else(|| canvas.tile_count());
    if args.missing {
        let n = tile_count.ok_or_else(|| {
            Failure::Usage(
                "the parts are not all tiles of one count: give --tiles N to name the \
                 missing tiles"
                    .into(),
            )
        })?;
        let missing = canvas.missing_tiles(n).map_err(Failure::Usage)?;
        say_tiles(missing.iter().map(|t| t.to_string()).collect())?;
        return Ok(ExitCode::SUCCESS);
    }
    if let Some((pixels, gap)) = canvas.gaps() {
        let mut message = format!(
            "the parts leave {} uncovered, within columns {}..{} and rows {}..{}",
            count(pixels, "pixel", "pixels"),
            gap.x0,
            gap.x1,
            gap.y0,
            gap.y1
        );
        if let Some(n) = tile_count {
            let missing = canvas.missing_tiles(n).map_err(Failure::Usage)?;
            let names: Vec<String> = missing.iter().map(|t| t.to_string()).collect();
            message.push_str(&format!(
                "; missing tiles: {} (`p3trace merge --missing` prints them one a line)",
                names.join(" ")
            ));
        }
        return Err(Failure::Usage(message));
    }
    let output = output.ok_or_else(|| Failure::Usage("merge needs -o FILE".into()))?;
    let placement = canvas.placement();
    match cost {
        Some(map) => {
            let scale = Scale {
                max: args.cost_max,
                log: args.cost_scale.unwrap_or(false),
            };
            cost::write(&canvas.film, &output, &placement, &map, scale)
        }
        None => canvas.film.write_placed(&output, &placement),
    }
    .map_err(Failure::Run)?;
    Ok(ExitCode::SUCCESS)
}

fn run_bench(args: &BenchArgs) -> Result<ExitCode, Failure> {
    use p3trace::bench;
    check_statistics_target(args.json.as_deref())?;
    // The protocol's rays are made in the file's coordinates, as the Embree harness's.
    let scene = load_scene(&args.scene, args.seed, Frame::File)?;
    let options = args.accel.options(scene.accel);
    let tracer = Tracer::new(&scene.geometry, &options);
    let (name, stats, build_time) = (tracer.name(), tracer.stats(), tracer.build_time());
    let sets = bench::ray_sets(&scene, &tracer);
    let cores = p3trace::machine::logical_cpus();
    let threads = args.threads.map_or(cores, |n| n as usize);
    let (width, height) = bench::resolution(&scene);
    let say = human_output(is_stdout(args.json.as_deref()));
    say("# p3trace bench: trace-throughput protocol (PROTOCOL.md)");
    say(&format!("# scene {}", scene.name));
    let geometry = &scene.geometry;
    say(&format!(
        "# geometry {}, {}, {}",
        count(
            geometry.bounded_count() as u64,
            "bounded object",
            "bounded objects"
        ),
        count(geometry.count(PrimKind::Plane) as u64, "plane", "planes"),
        count(scene.lights.len() as u64, "light", "lights")
    ));
    say(&format!(
        "# resolution {width}x{height} (scene {}x{})",
        scene.camera.width, scene.camera.height
    ));
    say(&format!(
        "# structure {name}, build_s {:.4}",
        build_time.as_secs_f64()
    ));
    say(&format!(
        "# cpu {}, {}; best of {}",
        p3trace::machine::cpu_model(),
        count(cores as u64, "logical CPU", "logical CPUs"),
        count(args.reps.into(), "pass", "passes")
    ));
    say("# ray-set  api  threads  rays  hits  tsum  mrays_per_s");
    let mut thread_counts = vec![1];
    if threads > 1 {
        thread_counts.push(threads);
    }
    let mut lines = Vec::new();
    bench::run(&tracer, &sets, &thread_counts, args.reps, |line| {
        say(&line.to_string());
        lines.push(line);
    })
    .map_err(Failure::Run)?;
    let work = if args.stats {
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .map_err(|e| Failure::Run(format!("cannot start a worker thread: {e}")))?;
        say(&format!("# structure {name}:"));
        for line in &stats {
            say(&format!("#   {line}"));
        }
        say("# work per ray: mean, 50th, 90th and 99th percentiles, and the set's total");
        let work = bench::work(&tracer, &sets, &one);
        for line in work.iter().flat_map(bench::Work::lines) {
            say(&line);
        }
        work
    } else {
        Vec::new()
    };
    if let Some(target) = &args.json {
        let value = statistics::bench(&statistics::BenchRun {
            scene: &scene,
            resolution: (width, height),
            structure: &name,
            build_time,
            stats: &stats,
            reps: args.reps,
            lines: &lines,
            work: &work,
        });
        statistics::write(target, &value).map_err(Failure::Run)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The project's skybox folders, beside the scenes in `scenes/`, from the project's
/// folder (as the dragon's models in `data/` are).
const SKY_Z_UP: &str = "scenes/sky_zup";
const SKY_Y_UP: &str = "scenes/sky_yup";

fn run_gen(command: GenCommand) -> Result<ExitCode, Failure> {
    let (text, out) = match command {
        GenCommand::Balls { depth, out } => {
            let env = out.prepare(Some(SKY_Z_UP))?;
            (sphereflake::balls_scene(depth, env.as_deref()), out)
        }
        GenCommand::Mount { level, seed, out } => {
            let env = out.prepare(Some(SKY_Z_UP))?;
            (mountain::mount_scene(level, seed, env.as_deref()), out)
        }
        GenCommand::Random { seed, out } => {
            let env = out.prepare(None)?;
            (random::random_scene(seed, env.as_deref()), out)
        }
        GenCommand::Dragon {
            resolution,
            ply,
            out,
        } => {
            let env = out.prepare(Some(SKY_Y_UP))?;
            let path = ply
                .unwrap_or_else(|| Path::new("data/stanford-dragon").join(resolution.file_name()));
            if !path.is_file() {
                return Err(Failure::Usage(format!(
                    "no dragon model at {}: run scripts/fetch-dragon.sh, or give --ply FILE",
                    path.display()
                )));
            }
            let mesh = scene::ply::read_ply(&path).map_err(Failure::Usage)?;
            if mesh.triangles.is_empty() {
                return Err(Failure::Usage(format!("{}: no triangles", path.display())));
            }
            let source = path.display().to_string();
            (dragon::dragon_scene(&mesh, &source, env.as_deref()), out)
        }
        GenCommand::Skybox { up, size, output } => {
            skybox::write_skybox(&output, size, up).map_err(Failure::Run)?;
            return Ok(ExitCode::SUCCESS);
        }
    };
    match &out.output {
        Some(path) => {
            p3trace::output::write_atomically(path, |w| w.write_all(text.as_bytes()))
                .map_err(Failure::Run)?;
            Ok(ExitCode::SUCCESS)
        }
        None => write_to_stdout(text.as_bytes(), "the scene"),
    }
}

/// Writes `bytes` to standard output; `what` names them in the message should it fail.
fn write_to_stdout(bytes: &[u8], what: &str) -> Result<ExitCode, Failure> {
    std::io::stdout()
        .lock()
        .write_all(bytes)
        .map_err(|e| Failure::Run(format!("cannot write {what}: {e}")))?;
    Ok(ExitCode::SUCCESS)
}

impl SceneOutput {
    /// Before the scene is made: refuses an output file that cannot be written, and
    /// returns the folder for the `env` line: the one asked for, none with --no-env, else
    /// the scene's default, named from where the scene is written ([`path_from`]).
    fn prepare(&self, default: Option<&str>) -> Result<Option<String>, Failure> {
        if let Some(file) = &self.output {
            check_output(file)?;
        }
        let Some(sky) = self.env.as_deref().or(default).filter(|_| !self.no_env) else {
            return Ok(None);
        };
        let sky = PathBuf::from(sky);
        if !sky.is_dir() {
            eprintln!(
                "p3trace: warning: no skybox folder at {}: the scene will show its \
                 background colour (--env DIR names the folder, from the current one)",
                sky.display()
            );
        }
        let named = match &self.output {
            Some(file) => path_from(file, &sky)?,
            None => sky,
        };
        Ok(Some(named.display().to_string()))
    }
}

/// `target`, a path from the current folder, as a path from the folder of `file`: relative
/// where the two share more than the root (the project's own files keep their names in
/// `scenes/`), else absolute; an absolute `target` stays as it is.
fn path_from(file: &Path, target: &Path) -> Result<PathBuf, Failure> {
    if target.is_absolute() {
        return Ok(target.to_path_buf());
    }
    let folder = p3trace::output::folder_of(file);
    let cannot = |path: &Path, e: std::io::Error| {
        Failure::Run(format!("cannot find {}: {e}", path.display()))
    };
    let folder = folder.canonicalize().map_err(|e| cannot(folder, e))?;
    // A folder that does not exist (yet) is named as it is written.
    let target = match target.canonicalize() {
        Ok(target) => target,
        Err(_) => std::env::current_dir()
            .map_err(|e| cannot(Path::new("."), e))?
            .join(target),
    };
    let shared = (folder.components().zip(target.components()))
        .take_while(|(a, b)| a == b)
        .count();
    if shared <= 1 {
        return Ok(target);
    }
    let up = folder
        .components()
        .skip(shared)
        .map(|_| Component::ParentDir);
    let relative: PathBuf = up.chain(target.components().skip(shared)).collect();
    Ok(if relative.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        relative
    })
}
