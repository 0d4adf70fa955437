//! `p3trace render`: a scene to an image (or a cost image), its summary and statistics.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::{
    check_statistics_target, grouped, human_output, image_output, is_stdout, settings_options,
    settings_scene, RANDOM_SCENE,
};
use crate::cli::RenderArgs;
use crate::{statistics, Failure};
use p3trace::accel::count::Counter;
use p3trace::accel::AccelKind;
use p3trace::farm;
use p3trace::generate::random;
use p3trace::imaging::false_colour::Scale;
use p3trace::imaging::format::{ImageOutput, OutputFormat};
use p3trace::imaging::openexr::Placement;
use p3trace::plural::{count, noun};
use p3trace::render::cost::{self, CostMap};
use p3trace::render::progress::Progress;
use p3trace::render::region::Region;
use p3trace::render::{self, RenderOptions, RenderReport, RenderWork, Sampling};
use p3trace::scene::Scene;

pub fn run(args: &RenderArgs) -> Result<ExitCode, Failure> {
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

/// The scene as `render` takes it, read in the profile's frame, its lens as the flags set
/// it; and the hash of its text, for the image's note.
fn render_scene(args: &RenderArgs) -> Result<(Scene, u64), Failure> {
    let scene = settings_scene(&args.scene, &args.settings)?;
    let scene_hash = scene_hash(&args.scene, args.settings.seed)?;
    Ok((scene, scene_hash))
}

/// The hash of the text of the scene `path` names (as for [`super::read_scene`]), which goes
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
            "{}: built in {:.3} s on {}",
            report.accel_name,
            report.build_time.as_secs_f64(),
            count(report.build_threads as u64, "thread", "threads")
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

/// `16 spp`, or `8 spp (4x2)` where the grid is not square.
fn samples_label(sampling: Sampling) -> String {
    let grid = sampling.grid();
    if grid.columns == grid.rows {
        format!("{} spp", grid.cells())
    } else {
        format!("{} spp ({}x{})", grid.cells(), grid.columns, grid.rows)
    }
}
