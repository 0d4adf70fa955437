//! Renders a scene file to a PNG from your own code, at a size and sample count of your
//! choosing, and says how long it took.
//!
//! ```sh
//! cargo run --release --example render_png -- scenes/showcase.p3f showcase-small.png
//! ```

use p3trace::render::{render, RenderOptions, Sampling};
use p3trace::scene::parse_file;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = args.next().unwrap_or("scenes/showcase.p3f".into());
    let out = args.next().unwrap_or("showcase-small.png".into());
    let scene = parse_file(std::path::Path::new(&scene_path))?;
    let options = RenderOptions {
        width: 320,
        height: 240,
        sampling: Sampling::from_samples_per_pixel(4)?,
        ..RenderOptions::from_scene(&scene)
    };
    let report = render(&scene, &options)?;
    for warning in &report.warnings {
        eprintln!("warning: {warning}");
    }
    report.film.write(std::path::Path::new(&out))?;
    println!(
        "{scene_path}: {}x{}, {} rays in {:.3} s -> {out}",
        options.width,
        options.height,
        report.rays.total(),
        report.elapsed.as_secs_f64()
    );
    Ok(())
}
