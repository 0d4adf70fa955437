//! `p3trace bench`: the trace-throughput protocol (`p3trace::bench`), its report lines
//! and statistics.

use std::process::ExitCode;

use super::{check_statistics_target, human_output, is_stdout, load_scene};
use crate::cli::BenchArgs;
use crate::{statistics, Failure};
use p3trace::accel::Tracer;
use p3trace::plural::count;
use p3trace::prim::PrimKind;
use p3trace::render::worker_pool;
use p3trace::scene::Frame;

pub fn run(args: &BenchArgs) -> Result<ExitCode, Failure> {
    use p3trace::bench;
    check_statistics_target(args.json.as_deref())?;
    // The protocol's rays are made in the file's coordinates, as the Embree harness's.
    let scene = load_scene(&args.scene, args.seed, Frame::File)?;
    let options = args.accel.options(scene.accel);
    let cores = p3trace::machine::logical_cpus();
    let threads = args.threads.map_or(cores, |n| n as usize);
    // Built on the most threads the runs trace with, as Embree's harness builds on its
    // device's: with --threads 1 the build time is one core's.
    let build_pool = worker_pool(Some(threads)).map_err(Failure::Run)?;
    let tracer = build_pool.install(|| Tracer::new(&scene.geometry, &options));
    drop(build_pool);
    let (name, stats, build_time) = (tracer.name(), tracer.stats(), tracer.build_time());
    let sets = bench::ray_sets(&scene, &tracer);
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
        let one = worker_pool(Some(1)).map_err(Failure::Run)?;
        say(&format!("# structure {name}:"));
        for line in &stats {
            say(&format!("#   {line}"));
        }
        say("# work per ray: mean, 50th, 90th and 99th percentiles, and the set's total");
        let work = bench::work(&tracer, &sets, &one);
        for line in work.iter().flat_map(bench::PathWork::lines) {
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
            build_threads: tracer.build_threads(),
            stats: &stats,
            reps: args.reps,
            lines: &lines,
            work: &work,
        });
        statistics::write(target, &value).map_err(Failure::Run)?;
    }
    Ok(ExitCode::SUCCESS)
}
