//! The stream renderer's queues live in each worker's arena: once warm, a tile asks the
//! global allocator for nothing. Measured by counting the calls of a counting allocator
//! over two renders that differ only in their number of tiles.

use crate::counting;
use p3trace::render::{render, RenderMode, RenderOptions, Sampling};
use p3trace::scene::parse_file;

pub fn a_warm_tile_allocates_nothing() {
    // Glass, mirrors and two lights: every depth and kind of queue.
    let scene = parse_file(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/showcase.p3f"
    )))
    .unwrap();
    let calls = |side: u32| {
        let mut options = RenderOptions::from_scene(&scene);
        (options.width, options.height) = (side, side);
        options.sampling = Sampling::from_samples_per_pixel(4).unwrap();
        options.threads = Some(1);
        // The sky's six faces decode on rayon's threads beside the build, in a number of
        // allocations that varies from run to run; misses take the background instead.
        options.skybox = false;
        assert_eq!(options.mode, RenderMode::Stream, "the default mode");
        let before = counting::calls();
        let report = render(&scene, &options).unwrap();
        assert!(report.rays.reflection > 0 && report.rays.refraction > 0);
        counting::calls() - before
    };
    let (small, large) = (calls(32), calls(256));
    // 4 tiles against 256: the per-render allocations (the film, the tile list, the
    // threads, the structure) are the same; an arena may grow a few more times.
    let more = large.saturating_sub(small);
    eprintln!("{small} allocations for 4 tiles, {large} for 256");
    assert!(
        more < 32,
        "{more} more allocations for 252 more tiles ({small} for 4, {large} for 256)"
    );
}
