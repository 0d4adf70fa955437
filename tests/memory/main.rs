//! The tests that count the heap: ten million spheres and ten million triangles within
//! the memory `docs/limits.md` states, a course render within a standard one's, and a
//! warm tile that asks the allocator for nothing.
//! They share a counting allocator, so they run one after another in a process of their
//! own: no libtest harness (`harness = false` in `Cargo.toml`), whose threads would run
//! them side by side.

mod counting;
mod huge_mesh;
mod huge_scene;
mod profiles;
mod tile_allocations;

#[global_allocator]
static ALLOCATOR: counting::Counting = counting::Counting;

const TESTS: [(&str, fn()); 4] = [
    (
        "huge_mesh::ten_million_triangles_render_within_the_stated_memory",
        huge_mesh::ten_million_triangles_render_within_the_stated_memory,
    ),
    (
        "huge_scene::ten_million_spheres_render_within_the_stated_memory",
        huge_scene::ten_million_spheres_render_within_the_stated_memory,
    ),
    (
        "profiles::a_course_render_copies_no_geometry",
        profiles::a_course_render_copies_no_geometry,
    ),
    (
        "tile_allocations::a_warm_tile_allocates_nothing",
        tile_allocations::a_warm_tile_allocates_nothing,
    ),
];

/// Takes what `cargo test` hands every test binary: name filters, `--list`, and
/// libtest's other flags, which mean nothing here. A failing test panics, and the
/// process exits with the panic's status.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let filters: Vec<&String> = args.iter().filter(|arg| !arg.starts_with('-')).collect();
    let chosen = TESTS.iter().filter(|(name, _)| {
        filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str()))
    });
    if args.iter().any(|arg| arg == "--list") {
        for (name, _) in chosen {
            println!("{name}: test");
        }
        return;
    }
    // None of these is ignored, so `--ignored` runs none.
    let chosen: Vec<_> = if args.iter().any(|arg| arg == "--ignored") {
        Vec::new()
    } else {
        chosen.collect()
    };
    println!("\nrunning {} tests", chosen.len());
    let start = std::time::Instant::now();
    for (name, test) in &chosen {
        println!("test {name} ... ");
        test();
        println!("test {name} ... ok");
    }
    println!(
        "\ntest result: ok. {} passed; 0 failed; 0 ignored; 0 measured; {} filtered out; \
         finished in {:.2}s\n",
        chosen.len(),
        TESTS.len() - chosen.len(),
        start.elapsed().as_secs_f64()
    );
}
