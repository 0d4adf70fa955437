//! `p3trace compare`: how two images differ, or how two cost images' counts compare.

use std::path::Path;
use std::process::ExitCode;

use super::{check_output, grouped};
use crate::cli::CompareArgs;
use crate::Failure;
use p3trace::compare::levels;
use p3trace::farm;
use p3trace::imaging::format::OutputFormat;
use p3trace::imaging::Film;
use p3trace::render::cost::CostMap;

pub fn run(args: &CompareArgs) -> Result<ExitCode, Failure> {
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
