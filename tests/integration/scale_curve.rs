//! `scripts/scale-curve.py`: the protocol over generated scenes of growing size. The real
//! `p3trace bench` runs on small levels; the anchors are stand-ins that answer with
//! p3trace's own lines at a known fraction of its speed, so every ratio is known.

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::{Command, Output};

use crate::bench_chart::have_matplotlib;
use crate::common::{project_file, scratch, stderr, stdout};

/// A stand-in anchor: the lines of the p3trace result the script wrote just before for the
/// same scene, renamed `NAME-best`, at 1/`divisor` of the speed, hits shifted by `extra`.
fn stand_in(dir: &Path, name: &str, divisor: u32, extra: u32) -> String {
    let path = dir.join(format!("{name}.sh"));
    let script = format!(
        r##"#!/bin/sh
# usage: SCENE.p3f --threads 1 --reps N
echo "# build_s 0.5 (quality medium, API names without a suffix)"
echo "# build_s bvh8cpu 0.25 / 1.0, bvh4cpu 0.1 / 0.2"
awk '$2 == "p3trace-best" {{ printf "%s {name}-best %s %s %d %s %.2f\n", $1, $3, $4, $5 + {extra}, $6, $7 / {divisor} }}' "${{1%.p3f}}.p3trace.txt"
"##
    );
    std::fs::write(&path, script).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    path.display().to_string()
}

/// A stand-in for `embree-render --best`: a best line at twice p3trace's least render time,
/// which the script kept for the same scene just before.
fn stand_in_render(dir: &Path) -> String {
    let path = dir.join("embree-render.sh");
    let script = r##"#!/bin/sh
# usage: SCENE.p3f --threads 1 --best --reps N
awk '/^# scale-curve render_s/ { printf "scene 512 512 1 best %.9f 1000 1.0\n", 2 * $4 }' "${1%.p3f}.render.p3trace.txt"
"##;
    std::fs::write(&path, script).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    path.display().to_string()
}

/// The script with the flags `flags` (split at spaces) and the options `options`, each a
/// flag and its value (a path, which may hold a space).
fn curve(flags: &str, options: &[(&str, &str)]) -> Output {
    Command::new("python3")
        .arg(project_file("scripts/scale-curve.py"))
        .args(flags.split_whitespace())
        .args(options.iter().flat_map(|&(flag, value)| [flag, value]))
        .output()
        .expect("python3 runs")
}

#[test]
fn the_curve_gives_each_scene_its_ratios_build_times_and_memory() {
    if !have_matplotlib() {
        return;
    }
    let dir = scratch("scale_curve");
    let embree = stand_in(&dir, "embree", 2, 0);
    let tinybvh = stand_in(&dir, "tinybvh", 4, 0);
    let out = dir.display().to_string();
    let plot = dir.join("curve.png");
    let markdown = dir.join("curve.md");
    let binary = env!("CARGO_BIN_EXE_p3trace");
    let (plot_arg, markdown_arg) = (plot.display().to_string(), markdown.display().to_string());
    let flags = "--mount 1-2 --balls 1 --reps 1";
    let options = [
        ("--dir", out.as_str()),
        ("--embree", &embree),
        ("--tinybvh", &tinybvh),
        ("--plot", &plot_arg),
        ("--markdown", &markdown_arg),
    ];
    let run = curve(flags, &[&options[..], &[("--p3trace", binary)]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let table = stdout(&run);
    assert_eq!(std::fs::read_to_string(&markdown).unwrap(), table);
    // Embree's stand-in runs at half p3trace's speed, tinybvh's (meshes only) at a quarter.
    for (scene, primitives) in [("mount_1", "12"), ("mount_2", "36"), ("balls_1", "12")] {
        let row =
            format!("| {scene} | {primitives} | 2.00 (E) | 2.00 (E) | 2.00 (E) | 2.00 | 2.00 | ");
        let line = table.lines().find(|l| l.starts_with(&row));
        // Then p3trace's build time and Embree's, and their peak memory.
        assert!(
            line.is_some_and(|l| l.contains(" / 0.500 | ")),
            "{row}\n{table}"
        );
    }
    let figures: Vec<&str> = table
        .lines()
        .filter(|l| l.starts_with("| mount_2 | "))
        .collect();
    assert_eq!(figures.len(), 4, "{table}");
    assert!(figures[2].starts_with("| mount_2 | embree | ") && figures[2].contains("| 0.500 |"));
    assert!(figures[3].starts_with("| mount_2 | tinybvh | ") && figures[3].contains("| 0.250 |"));
    assert!(
        !table.contains("| balls_1 | tinybvh |"),
        "tinybvh takes triangles only\n{table}"
    );
    // Each tracer's peak memory, in MiB: at least the protocol's million primary rays.
    let peak: f64 = figures[1]
        .rsplit('|')
        .nth(1)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(peak >= 16.0, "{table}");
    assert!(std::fs::metadata(&plot).unwrap().len() > 10_000);

    // --reuse reads the results kept in DIR and runs nothing: not even the binary.
    std::fs::remove_file(&plot).unwrap();
    let missing = [("--p3trace", "/nonexistent/p3trace")];
    let run = curve(
        &format!("{flags} --reuse"),
        &[&options[..], &missing].concat(),
    );
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(stdout(&run), table);
    assert!(plot.exists());

    // --renders: a column of Embree's least render time over p3trace's, here twice it.
    let embree_render = stand_in_render(&dir);
    let options = [
        ("--dir", out.as_str()),
        ("--embree", &embree),
        ("--tinybvh", ""),
        ("--p3trace", binary),
        ("--embree-render", &embree_render),
    ];
    let run = curve(
        "--no-balls --mount 1 --reps 1 --renders --render-reps 2",
        &options,
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let table = stdout(&run);
    assert!(table.starts_with("| scene |") && table.lines().next().unwrap().ends_with(" render |"));
    let row = table.lines().find(|l| l.starts_with("| mount_1 | 12 |"));
    assert!(row.is_some_and(|l| l.ends_with(" | 2.00 |")), "{table}");
    let kept = std::fs::read_to_string(dir.join("mount_1.render.p3trace.txt")).unwrap();
    assert_eq!(
        kept.lines().filter(|l| l.starts_with('{')).count(),
        2,
        "{kept}"
    );

    // --rounds 2: every tracer twice, in turn, each round's results kept; each figure is
    // its tracer's best over the rounds.
    let run = curve(
        "--no-balls --mount 1 --reps 1 --renders --render-reps 1 --rounds 2",
        &options,
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let table = stdout(&run);
    let best_rate = |file: &str, set: &str| -> f64 {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let line = text.lines().find(|l| {
            let fields: Vec<&str> = l.split_whitespace().collect();
            fields.len() == 7 && fields[0] == set && fields[1].ends_with("-best")
        });
        line.unwrap()
            .split_whitespace()
            .last()
            .unwrap()
            .parse()
            .unwrap()
    };
    for tracer in ["p3trace", "embree"] {
        let rates: Vec<String> = ["primary", "shadow", "reflection"]
            .iter()
            .map(|set| {
                let best = best_rate(&format!("mount_1.{tracer}.txt"), set)
                    .max(best_rate(&format!("mount_1.{tracer}.r2.txt"), set));
                format!("{best:.2}")
            })
            .collect();
        let row = format!("| mount_1 | {tracer} | {} |", rates.join(" | "));
        assert!(table.contains(&row), "{row}\n{table}");
    }
    assert!(dir.join("mount_1.render.p3trace.r2.txt").exists());
    assert!(dir.join("mount_1.render.embree.r2.txt").exists());
    let run = curve("--no-balls --mount 1 --rounds 0", &options);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));

    // Hits that differ by 100, within 0.05% of the rays (not of mount_1's 21,928 blocked
    // shadow rays): they agree. By 5,000, beyond it: the tables, then exit 1.
    let against = |extra: u32| {
        let embree = stand_in(&dir, "embree", 2, extra);
        let options = [
            ("--dir", out.as_str()),
            ("--embree", &embree),
            ("--tinybvh", ""),
            ("--p3trace", binary),
        ];
        curve("--no-balls --mount 1 --reps 1", &options)
    };
    let run = against(100);
    assert!(run.status.success(), "{}", stderr(&run));
    let run = against(5000);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("disagree on mount_1 primary, mount_1 shadow, mount_1 reflection"),
        "{}",
        stderr(&run)
    );
}
