//! `scripts/bench-chart.py`: the chart of p3trace against Embree, drawn from hand-made
//! result files in the shapes of `p3trace bench --json`, `p3trace bench` and
//! `embree-compare`. The script needs python3 and matplotlib (`scripts/requirements.txt`,
//! which `.ci/run` installs); without them these tests say that they skip, except under
//! CI, where a skip would hide a broken setup.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::{self, project_file, scratch, stderr};

/// Whether `python3 -c CODE` runs.
fn python_runs(code: &str) -> bool {
    Command::new("python3")
        .args(["-c", code])
        .output()
        .is_ok_and(|out| out.status.success())
}

/// True when the tests can go on; otherwise prints why they skip, or fails under CI.
fn have(what: &str, code: &str) -> bool {
    if python_runs(code) {
        return true;
    }
    let message = format!("{what} is missing");
    if std::env::var_os("CI").is_some() {
        panic!("{message}; CI must run these tests");
    }
    common::skip(message);
    false
}

fn have_python() -> bool {
    have("python3", "pass")
}

pub(crate) fn have_matplotlib() -> bool {
    have_python()
        && have(
            "matplotlib (python3 -m pip install -r scripts/requirements.txt)",
            "import matplotlib",
        )
}

fn chart(args: &[&Path]) -> Output {
    Command::new("python3")
        .arg(project_file("scripts/bench-chart.py"))
        .args(args)
        .output()
        .expect("python3 runs")
}

/// One result in the JSON shape of `p3trace bench --json`.
fn json_line(set: &str, api: &str, threads: u32, mrays: f64) -> String {
    format!(
        r#"{{"ray_set": "{set}", "api": "{api}", "threads": {threads}, "rays": 1048576, "hits": 620454, "tsum": 1344250.125, "mrays_per_s": {mrays}}}"#
    )
}

/// A `p3trace bench --json` object for `scene` with `lines`.
fn p3trace_json(scene: &str, lines: &[String]) -> String {
    format!(
        r#"{{
  "program": {{"name": "p3trace", "version": "0.1.0", "commit": "e95dd80", "target_features": ["avx2", "fma"]}},
  "cpu": {{"model": "Test CPU 9000", "logical_cpus": 2, "features": ["avx2", "fma"]}},
  "command": "bench",
  "scene": "{scene}",
  "resolution": [1024, 1024],
  "structure": {{"name": "bvh8 (sah)", "build_s": 0.0123, "stats": ["nodes 1234"]}},
  "reps": 7,
  "lines": [
    {}
  ]
}}
"#,
        lines.join(",\n    ")
    )
}

/// Result lines of every set at 1 and 2 threads for `tracer`'s `apis`, `scale` Mrays/s
/// apart, as text (`ray-set api threads rays hits tsum mrays_per_s`).
fn text_lines(tracer: &str, apis: &[&str], scale: f64) -> String {
    let mut text = String::new();
    for threads in [1, 2] {
        for (s, set) in ["primary", "shadow", "reflection"].iter().enumerate() {
            for (a, api) in apis.iter().enumerate() {
                let mrays = scale * (threads as f64) * (10.0 - s as f64 + a as f64 * 0.5);
                text += &format!(
                    "{set:<10}  {tracer}-{api:<8}  {threads:2}  1048576  620454  1344250.125  {mrays:8.2}\n"
                );
            }
        }
    }
    text
}

/// An `embree-compare` output for `scene`.
fn embree_text(scene: &str) -> String {
    format!(
        "# embree_p3f: P3F trace-throughput protocol (PROTOCOL.md), Intel Embree\n\
         # scene ../shared/scenes/{scene}\n\
         # cpu Test CPU 9000, 2 logical CPUs; best of 7 passes\n\
         # ray-set  api  threads  rays  hits  tsum  mrays_per_s\n{}\
         # checks passed\n",
        text_lines(
            "embree",
            &["single", "packet8", "packet16", "stream", "best"],
            1.0
        )
    )
}

/// A scratch folder with results of two scenes: `balls` as p3trace JSON and `mount` as
/// p3trace text, each with its Embree file.
fn fixtures(name: &str) -> (PathBuf, Vec<PathBuf>) {
    let dir = scratch(name);
    let mut lines = Vec::new();
    for threads in [1, 2] {
        for set in ["primary", "shadow", "reflection"] {
            lines.push(json_line(set, "p3trace-single", threads, 9.5));
            lines.push(json_line(set, "p3trace-packet8", threads, 12.25));
            lines.push(json_line(set, "p3trace-best", threads, 12.25));
        }
    }
    let files = [
        ("p3trace-balls.json", p3trace_json("balls.p3f", &lines)),
        ("embree-balls.txt", embree_text("balls.p3f")),
        (
            "p3trace-mount.txt",
            format!(
                "# p3trace bench: trace-throughput protocol (PROTOCOL.md)\n\
                 # scene ../shared/scenes/mount.p3f\n\
                 # structure bvh8 (sah), build_s 0.0400\n\
                 # cpu Test CPU 9000, 2 logical CPUs; best of 7 passes\n{}",
                text_lines("p3trace", &["single", "packet8", "best"], 1.2)
            ),
        ),
        ("embree-mount.txt", embree_text("mount.p3f")),
    ];
    let paths = files
        .iter()
        .map(|(file, text)| {
            let path = dir.join(file);
            std::fs::write(&path, text).expect("fixture written");
            path
        })
        .collect();
    (dir, paths)
}

/// Whether `png` has a pixel within a few levels of `rgb` (the script's bar colours).
fn has_colour(png: &image::RgbaImage, rgb: [u8; 3]) -> bool {
    png.pixels()
        .any(|p| (0..3).all(|c| p[c].abs_diff(rgb[c]) <= 3))
}

#[test]
fn draws_a_png_of_both_tracers() {
    if !have_matplotlib() {
        return;
    }
    let (dir, inputs) = fixtures("bench_chart_draws");
    for (name, extra) in [
        ("best.png", vec![]),
        ("all.png", vec!["--all-apis", "--threads", "2"]),
    ] {
        let out = dir.join(name);
        let mut args: Vec<&Path> = vec![Path::new("--out"), &out];
        args.extend(extra.iter().map(Path::new));
        // The Embree files first: pairing goes by scene name, not by order.
        args.extend([&inputs[1], &inputs[3], &inputs[0], &inputs[2]].map(PathBuf::as_path));
        let run = chart(&args);
        assert!(run.status.success(), "{name}: {}", stderr(&run));
        let png = image::open(&out).expect("a PNG").to_rgba8();
        let (w, h) = png.dimensions();
        assert!(
            (600..=3000).contains(&w) && (400..=2000).contains(&h),
            "{name}: {w}x{h}"
        );
        // p3trace-best's blue and embree-best's orange bars are both drawn.
        assert!(
            has_colour(&png, [0x1f, 0x4e, 0x9c]),
            "{name}: no p3trace bar"
        );
        assert!(
            has_colour(&png, [0xc8, 0x56, 0x0f]),
            "{name}: no Embree bar"
        );
    }
}

#[test]
fn help_says_what_it_reads() {
    if !have_python() {
        return;
    }
    let run = chart(&[Path::new("--help")]);
    assert!(run.status.success());
    let help = String::from_utf8_lossy(&run.stdout);
    for word in [
        "--out",
        "--threads",
        "--all-apis",
        "--json",
        "embree-compare",
    ] {
        assert!(
            help.contains(word),
            "--help does not mention {word}: {help}"
        );
    }
}

/// Runs the chart on the fixtures with `file` (named `name`) in place of input `replace`,
/// and checks that it exits 2 with a one-line message containing `expected`, and writes
/// no chart.
fn rejects(name: &str, replace: usize, text: &str, extra: &[&str], expected: &str) {
    let (dir, mut inputs) = fixtures(&format!("bench_chart_{}", name.replace('.', "_")));
    inputs[replace] = dir.join(name);
    std::fs::write(&inputs[replace], text).expect("fixture written");
    let out = dir.join("chart.png");
    let mut args: Vec<&Path> = vec![Path::new("--out"), &out];
    args.extend(extra.iter().map(Path::new));
    args.extend(inputs.iter().map(PathBuf::as_path));
    let run = chart(&args);
    let message = stderr(&run);
    assert_eq!(run.status.code(), Some(2), "{name}: {message}");
    assert!(message.contains(expected), "{name}: {message}");
    assert!(!message.contains("Traceback"), "{name}: {message}");
    assert_eq!(message.trim_end().lines().count(), 1, "{name}: {message}");
    assert!(!out.exists(), "{name}: a chart was written");
}

#[test]
fn malformed_input_exits_2_naming_file_and_line() {
    if !have_python() {
        return;
    }
    let embree = embree_text("balls.p3f");
    let last = embree.lines().count() + 1;
    let short_line = format!("{embree}primary  embree-best  1  1048576  620454  1344250.125\n");
    rejects(
        "short.txt",
        1,
        &short_line,
        &[],
        &format!("short.txt:{last}: expected the 7 fields 'ray-set api threads rays hits tsum mrays_per_s', got 6"),
    );
    let word = format!("{embree}primary  embree-best  1  1048576  620454  1344250.125  fast\n");
    rejects(
        "word.txt",
        1,
        &word,
        &[],
        &format!("word.txt:{last}: expected"),
    );
    let bad_json = "{\n  \"scene\": \"balls.p3f\",\n  \"lines\": [,]\n}\n";
    rejects(
        "broken.json",
        0,
        bad_json,
        &[],
        "broken.json:3:13: invalid JSON",
    );
    let bad_type = p3trace_json(
        "balls.p3f",
        &[
            json_line("primary", "p3trace-best", 1, 12.0),
            json_line("shadow", "p3trace-best", 1, 1.5).replace("1.5}", "\"1.5\"}"),
        ],
    );
    rejects(
        "type.json",
        0,
        &bad_type,
        &[],
        "type.json: lines[1]: \"mrays_per_s\" must be a number, got \"1.5\"",
    );
    let no_scene = text_lines("embree", &["best"], 1.0);
    rejects(
        "anon.txt",
        1,
        &no_scene,
        &[],
        "anon.txt: no '# scene NAME' comment",
    );
    let other_tracer = embree_text("balls.p3f").replace("embree-stream", "optix-stream");
    rejects(
        "optix.txt",
        1,
        &other_tracer,
        &[],
        "unknown api 'optix-stream'",
    );
    // Both sides are needed: a scene whose Embree file is another scene's has no pair.
    rejects(
        "unpaired.txt",
        1,
        &embree_text("dragon.p3f"),
        &[],
        "has no embree file to compare with",
    );
    rejects(
        "threads.txt",
        1,
        &embree_text("balls.p3f"),
        &["--threads", "3"],
        "no results with 3 thread(s)",
    );
    rejects(
        "empty.txt",
        1,
        "",
        &[],
        "empty.txt: no '# scene NAME' comment",
    );
}

#[test]
fn a_missing_file_exits_2_naming_it() {
    if !have_python() {
        return;
    }
    let dir = scratch("bench_chart_missing");
    let (out, missing) = (dir.join("chart.png"), dir.join("nowhere.txt"));
    let run = chart(&[Path::new("--out"), &out, &missing]);
    assert_eq!(run.status.code(), Some(2));
    let message = stderr(&run);
    assert!(
        message.contains("nowhere.txt: cannot read: No such file or directory"),
        "{message}"
    );
}
