//! `p3trace merge`: a farm's parts into one image, or the tiles still missing.

use std::io::Write;
use std::process::ExitCode;

use super::image_output;
use crate::cli::MergeArgs;
use crate::Failure;
use p3trace::farm::{self, Canvas};
use p3trace::imaging::false_colour::Scale;
use p3trace::plural::count;
use p3trace::render::cost::{self, CostMap};

pub fn run(args: &MergeArgs) -> Result<ExitCode, Failure> {
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
