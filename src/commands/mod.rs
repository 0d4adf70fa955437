//! The commands of `p3trace`, a file each (`view`'s is `window.rs`), and what several of
//! them share: reading the scene, checking output files before the work, the options
//! that `render` and `view` take alike, and how lines for people are written.

pub mod bench;
pub mod compare;
pub mod gen;
pub mod info;
pub mod merge;
pub mod render;

use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

use crate::cli::{ImageArgs, Settings};
use crate::Failure;
use p3trace::generate::random;
use p3trace::imaging::format::ImageOutput;
use p3trace::render::sampler::SampleGrid;
use p3trace::render::{RenderOptions, Sampling};
use p3trace::scene::{self, Frame, Scene};

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
        crate::statistics::check_target(target).map_err(Failure::Run)
    })
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

/// Writes `bytes` to standard output; `what` names them in the message should it fail.
pub(crate) fn write_to_stdout(bytes: &[u8], what: &str) -> Result<ExitCode, Failure> {
    std::io::stdout()
        .lock()
        .write_all(bytes)
        .map_err(|e| Failure::Run(format!("cannot write {what}: {e}")))?;
    Ok(ExitCode::SUCCESS)
}
