//! The machine-readable statistics of `render --json` and `bench --json`: one JSON object
//! per run, with the program and the machine, the scene, the structure, the timings and
//! the rays.

use std::io::Write;
use std::path::Path;
use std::time::Duration;

use p3trace::accel::count::Counter;
use p3trace::bench::{Line, PathWork};
use p3trace::imaging::format::ImageOutput;
use p3trace::machine;
use p3trace::render::{RenderOptions, RenderReport, RenderWork};
use p3trace::scene::Scene;
use serde_json::{json, Value};

/// The program (version, commit, the instruction set it was compiled for) and the CPU.
fn program_and_cpu() -> (Value, Value) {
    let program = json!({
        "name": "p3trace",
        "version": machine::VERSION,
        "commit": machine::COMMIT,
        "target_cpu": machine::TARGET_CPU,
        "target_features": machine::TARGET_FEATURES.split(", ").collect::<Vec<_>>(),
        "packet_width": p3trace::simd::PACKET,
    });
    let cpu = json!({
        "model": machine::cpu_model(),
        "logical_cpus": machine::logical_cpus(),
        "features": machine::cpu_features(),
    });
    (program, cpu)
}

fn structure(name: &str, (time, threads): (Duration, usize), stats: &[String]) -> Value {
    json!({ "name": name, "build_s": time.as_secs_f64(), "build_threads": threads, "stats": stats })
}

/// A finished render of `scene` with `options`, written to `output`.
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    report: &RenderReport,
    output: &ImageOutput,
) -> Value {
    let (program, cpu) = program_and_cpu();
    let grid = options.sampling.grid();
    let rays = &report.rays;
    let seconds = report.elapsed.as_secs_f64();
    let region = options.region();
    let mut value = json!({
        "program": program,
        "cpu": cpu,
        "command": "render",
        "scene": scene.name,
        "skybox": report.skybox.as_ref().map(|dir| dir.display().to_string()),
        "output": output.path.as_ref().map_or("-".into(), |p| p.display().to_string()),
        "resolution": [options.width, options.height],
        "region": [region.x0, region.x1, region.y0, region.y1],
        "samples_per_pixel": options.sampling.samples_per_pixel(),
        "sample_grid": [grid.columns, grid.rows],
        "mode": format!("{:?}", options.mode).to_lowercase(),
        "profile": format!("{:?}", options.shade.profile).to_lowercase(),
        "max_depth": options.shade.max_depth,
        "threads": report.threads,
        "structure": structure(
            &report.accel_name,
            (report.build_time, report.build_threads),
            &report.accel_stats
        ),
        "render_s": seconds,
        "rays": {
            "primary": rays.primary,
            "shadow": rays.shadow,
            "reflection": rays.reflection,
            "refraction": rays.refraction,
            "total": rays.total(),
        },
        "mrays_per_s": rays.total() as f64 / 1e6 / seconds.max(1e-9),
    });
    if let Some(work) = &report.work {
        value["work"] = render_work(work);
    }
    value
}

/// A counted render's work by kind of ray (the rays of the image's, or region's, pixels):
/// the rays and each counter's total and mean per ray.
fn render_work(work: &RenderWork) -> Value {
    let w = work.by_kind();
    let mut by_kind = serde_json::Map::new();
    for (kind, tally) in w.named() {
        let rays = u64::from(tally.rays);
        let mut counters = serde_json::Map::new();
        counters.insert("rays".into(), json!(rays));
        for c in Counter::ALL {
            let total = u64::from(tally.get(c));
            counters.insert(
                c.name().into(),
                json!({ "total": total, "per_ray": total as f64 / rays.max(1) as f64 }),
            );
        }
        by_kind.insert(kind.into(), Value::Object(counters));
    }
    json!({ "by_kind": by_kind })
}

/// A run of the benchmark protocol: its settings and every line it printed.
pub struct BenchRun<'a> {
    pub scene: &'a Scene,
    pub resolution: (u32, u32),
    pub structure: &'a str,
    pub build_time: Duration,
    pub build_threads: usize,
    pub stats: &'a [String],
    pub reps: u32,
    pub lines: &'a [Line],
    /// Each set's work along each path, with `--stats`.
    pub work: &'a [PathWork],
}

pub fn bench(run: &BenchRun) -> Value {
    let (program, cpu) = program_and_cpu();
    let lines: Vec<Value> = run
        .lines
        .iter()
        .map(|l| {
            json!({
                "ray_set": l.ray_set,
                "api": l.api,
                "threads": l.threads,
                "rays": l.rays,
                "hits": l.hits,
                "tsum": l.tsum,
                "mrays_per_s": l.mrays_per_s,
            })
        })
        .collect();
    let mut value = json!({
        "program": program,
        "cpu": cpu,
        "command": "bench",
        "scene": run.scene.name,
        "resolution": [run.resolution.0, run.resolution.1],
        "structure": structure(run.structure, (run.build_time, run.build_threads), run.stats),
        "reps": run.reps,
        "lines": lines,
    });
    if !run.work.is_empty() {
        value["work"] = run.work.iter().map(work).collect();
    }
    value
}

/// One set's work along one path: each counter's spread per ray and, for packets, the
/// lanes active at nodes and leaves.
fn work(w: &PathWork) -> Value {
    let mut counters = serde_json::Map::new();
    for (counter, s) in &w.counters {
        counters.insert(
            counter.name().into(),
            json!({ "mean": s.mean, "p50": s.p50, "p90": s.p90, "p99": s.p99, "total": s.total }),
        );
    }
    json!({
        "ray_set": w.ray_set,
        "api": w.api,
        "rays": w.rays,
        "per_ray": counters,
        "lanes_at_nodes": w.lanes_at_nodes,
        "lanes_at_leaves": w.lanes_at_leaves,
    })
}

/// Writes `value` to `target`, a file (replaced only once complete) or standard output
/// for `-`, with a final newline.
/// Checks, before the run, that [`write()`] can write to `target`.
pub fn check_target(target: &Path) -> Result<(), String> {
    if target == Path::new("-") {
        Ok(())
    } else {
        p3trace::output::check_writable(target)
    }
}

pub fn write(target: &Path, value: &Value) -> Result<(), String> {
    let write_to = |out: &mut dyn Write| {
        serde_json::to_writer_pretty(&mut *out, value)?;
        writeln!(out)
    };
    if target == Path::new("-") {
        write_to(&mut std::io::stdout().lock())
            .map_err(|e| format!("cannot write the statistics: {e}"))
    } else {
        p3trace::output::write_atomically(target, |out| write_to(out))
    }
}
