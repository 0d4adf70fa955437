//! Render farms without a scheduler: a region renders exactly the whole frame's pixels at
//! the cost of its own, and `merge` assembles EXR parts into the one-machine image byte
//! for byte (PNG and EXR alike), or refuses with exit 2 and says why.

use crate::common;

use std::path::{Path, PathBuf};

use crate::common::{p3trace, project_file, scratch, stderr, stdout};
use p3trace::accel::AccelKind;
use p3trace::farm::read_part;
use p3trace::imaging::format::ImageOutput;
use p3trace::imaging::openexr::Placement;
use p3trace::imaging::Film;
use p3trace::render::region::Region;
use p3trace::render::sampler::SampleGrid;
use p3trace::render::{render, RenderMode, RenderOptions, Sampling};
use p3trace::scene::parse_file;

/// The tile counts the issue asks for: one, two, a prime and many.
const COUNTS: [u32; 4] = [1, 2, 7, 64];
/// For the course's two largest scenes, whose parse and build every task repeats (64
/// tasks of the dragon took half the test's time): how a frame is cut into bands does
/// not depend on the scene, and the others merge from 64.
const COUNTS_OF_LARGE_SCENES: [u32; 3] = [1, 2, 7];
const LARGE_SCENES: [&str; 2] = ["dragon", "mount_very_high"];

#[test]
fn a_region_renders_the_whole_frames_pixels_and_only_its_own() {
    let scene = parse_file(&project_file("scenes/showcase.p3f")).unwrap();
    let (width, height) = (61, 47);
    let options = |mode, region| {
        let mut o = RenderOptions::from_scene(&scene);
        (o.width, o.height) = (width, height);
        o.sampling = Sampling::Jittered(SampleGrid::with_cells(2));
        o.shade.soft_light_size = Some(1.0);
        o.shade.roughness = 0.2;
        o.accel.kind = AccelKind::Bvh;
        o.mode = mode;
        o.region = region;
        o
    };
    for mode in RenderMode::ALL {
        let full = render(&scene, &options(mode, None)).unwrap().film;
        let regions = [
            Region::pixel_bounds([3, 40, 5, 30], width, height).unwrap(),
            Region::pixel_bounds([60, 61, 46, 47], width, height).unwrap(),
            Region::tile(3, 7, width, height).unwrap(),
            Region::crop([0.1, 0.9, 0.33, 0.5], width, height).unwrap(),
        ];
        for region in regions {
            let report = render(&scene, &options(mode, Some(region))).unwrap();
            let part = &report.film;
            assert_eq!((part.width, part.height), (region.width(), region.height()));
            for row in 0..part.height {
                for x in 0..part.width {
                    assert_eq!(
                        part.get(x, row),
                        full.get(region.x0 + x, region.y0 + row),
                        "{mode:?} {region:?} at ({x}, {row})"
                    );
                }
            }
            // Its cost: two primary rays for each of its pixels, none for the others.
            assert_eq!(report.rays.primary, 2 * region.pixels());
        }
    }
}

fn arg(path: &Path) -> &str {
    path.to_str().unwrap()
}

fn run_ok(args: &[&str]) {
    let out = p3trace(args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
}

/// Renders `scene` at 40 x 30 with `flags` to `out`.
fn render_small(scene: &Path, flags: &[&str], out: &Path) {
    let mut args = vec![
        "render",
        arg(scene),
        "-q",
        "--resolution",
        "40x30",
        "-o",
        arg(out),
    ];
    args.extend_from_slice(flags);
    run_ok(&args);
}

/// Renders `scene` with `flags` whole (PNG and EXR), then as N tiles for every N of
/// `counts`, merges each set both ways and checks the files equal the whole ones.
fn merges_exactly(name: &str, scene: &str, flags: &[&str], counts: &[u32]) {
    let dir = scratch(&format!("merge_{name}"));
    let render_to = |out: &Path, extra: &[&str]| {
        let mut args = vec!["render", scene, "-q", "-o", arg(out)];
        args.extend_from_slice(flags);
        args.extend_from_slice(extra);
        run_ok(&args);
    };
    let whole: Vec<(PathBuf, Vec<u8>)> = ["png", "exr"]
        .iter()
        .map(|ext| {
            let path = dir.join(format!("whole.{ext}"));
            render_to(&path, &[]);
            let bytes = std::fs::read(&path).unwrap();
            (path, bytes)
        })
        .collect();
    for &n in counts {
        let parts: Vec<PathBuf> = (0..n)
            .map(|i| {
                let part = dir.join(format!("part-{n}-{i}.exr"));
                render_to(&part, &["--tile", &format!("{i}/{n}")]);
                part
            })
            .collect();
        for (whole, bytes) in &whole {
            let merged = dir.join(format!(
                "merged-{n}.{}",
                whole.extension().unwrap().to_str().unwrap()
            ));
            let mut args = vec!["merge", "-o", arg(&merged)];
            args.extend(parts.iter().map(|p| arg(p)));
            run_ok(&args);
            assert!(
                std::fs::read(&merged).unwrap() == *bytes,
                "{name}: {n} tiles merged into {} differ from the whole render",
                merged.display()
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_course_scene_merges_into_the_one_machine_image() {
    let Some(shared) = common::shared() else {
        return;
    };
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(shared.join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "p3f"))
        .collect();
    scenes.sort();
    assert!(!scenes.is_empty());
    for scene in &scenes {
        let name = scene.file_stem().unwrap().to_str().unwrap();
        // Small frames: 64 rows for 64 tiles; the course's skybox photos are read by
        // the skybox case below.
        let counts: &[u32] = if LARGE_SCENES.contains(&name) {
            &COUNTS_OF_LARGE_SCENES
        } else {
            &COUNTS
        };
        merges_exactly(
            name,
            arg(scene),
            &["--resolution", "40x64", "--no-skybox"],
            counts,
        );
    }
}

/// Every distribution effect, the course profile, the skybox and the random scene.
#[test]
fn every_effect_merges_into_the_one_machine_image() {
    let scene = |name: &str| project_file(&format!("scenes/{name}.p3f"));
    let small = ["--resolution", "32x64"];
    let cases: [(&str, PathBuf, &[&str]); 9] = [
        ("antialiasing", scene("showcase"), &["--spp", "6"]),
        (
            "depth_of_field",
            scene("dof"),
            &["--spp", "4", "--aperture", "3"],
        ),
        (
            "soft_shadows_grid",
            scene("showcase"),
            &["--soft-shadows", "--spp", "1"],
        ),
        (
            "soft_and_area_lights",
            scene("showcase"),
            &["--soft-shadows", "--spp", "4"],
        ),
        (
            "fuzzy_reflections",
            scene("balls_box"),
            &["--spp", "4", "--roughness", "0.3"],
        ),
        ("motion_blur", scene("motion"), &["--spp", "4"]),
        (
            "course_profile_schlick",
            scene("balls_low"),
            &["--profile", "course", "--schlick"],
        ),
        ("skybox", scene("mount_low"), &["--seed", "5"]),
        (
            "random_scene",
            PathBuf::from("random"),
            &["--seed", "2", "--spp", "2"],
        ),
    ];
    for (name, path, flags) in cases {
        let mut all = small.to_vec();
        all.extend_from_slice(flags);
        merges_exactly(name, arg(&path), &all, &COUNTS);
    }
    // The course's skybox photographs, with one tile count: each task decodes them.
    if let Some(shared) = common::shared() {
        merges_exactly(
            "course_skybox",
            arg(&shared.join("scenes/dragon.p3f")),
            &["--resolution", "24x16"],
            &[7],
        );
    }
}

/// A small showcase frame rendered whole and as parts into `dir`.
fn render_parts(dir: &Path, extra: &[&str], parts: &[&str]) -> Vec<PathBuf> {
    let showcase = project_file("scenes/showcase.p3f");
    parts
        .iter()
        .map(|tile| {
            let path = dir.join(format!("{}.exr", tile.replace('/', "of")));
            let mut args = vec![
                "render",
                arg(&showcase),
                "-q",
                "--resolution",
                "40x30",
                "--tile",
                tile,
                "-o",
                arg(&path),
            ];
            args.extend_from_slice(extra);
            run_ok(&args);
            path
        })
        .collect()
}

fn merge(args: &[&str]) -> std::process::Output {
    let mut all = vec!["merge"];
    all.extend_from_slice(args);
    p3trace(&all)
}

fn refused(out: &std::process::Output, says: &str) {
    assert_eq!(out.status.code(), Some(2), "{}", stderr(out));
    assert!(
        stderr(out).contains(says),
        "expected '{says}' in: {}",
        stderr(out)
    );
}

#[test]
fn merge_refuses_parts_of_different_renders() {
    let dir = scratch("merge_mismatch");
    let out = dir.join("out.png");
    let base = render_parts(&dir, &[], &["0/2"]);
    for (flags, says) in [
        (&["--seed", "1"][..], "'seed: 0' against 'seed: 1'"),
        (&["--spp", "4"][..], "samples"),
        (&["--roughness", "0.5"][..], "shading"),
        (&["--aperture", "1"][..], "camera"),
        (&["--shutter", "0,1"][..], "shutter"),
    ] {
        let sub = dir.join(says.replace(['\'', ' ', ':'], "_"));
        std::fs::create_dir_all(&sub).unwrap();
        let other = render_parts(&sub, flags, &["1/2"]);
        refused(
            &merge(&[arg(&base[0]), arg(&other[0]), "-o", arg(&out)]),
            says,
        );
    }
    // Another scene, at the same size.
    let other = dir.join("other.exr");
    render_small(
        &project_file("scenes/balls_low.p3f"),
        &["--tile", "1/2"],
        &other,
    );
    refused(
        &merge(&[arg(&base[0]), arg(&other), "-o", arg(&out)]),
        "scene: ",
    );
    assert!(!out.exists());
}

/// `merge -o -` writes the frame to standard output, as `-o FILE` writes it; JPEG too.
#[test]
fn merge_writes_to_standard_output_and_jpeg() {
    let dir = scratch("merge_stdout");
    let parts = render_parts(&dir, &[], &["0/2", "1/2"]);
    for (name, format) in [("frame.png", None), ("frame.jpg", Some("jpg"))] {
        let file = dir.join(name);
        run_ok(&["merge", arg(&parts[0]), arg(&parts[1]), "-o", arg(&file)]);
        let mut args = vec!["merge", arg(&parts[0]), arg(&parts[1]), "-o", "-"];
        if let Some(format) = format {
            args.extend_from_slice(&["--format", format]);
        }
        let piped = p3trace(&args);
        assert!(piped.status.success(), "{}", stderr(&piped));
        assert!(piped.stdout == std::fs::read(&file).unwrap(), "{name}");
    }
}

#[test]
fn merge_names_the_missing_tiles_and_a_rerun_completes_the_frame() {
    let dir = scratch("merge_missing");
    let out = dir.join("out.png");
    let parts = render_parts(&dir, &[], &["0/5", "2/5", "3/5"]);
    let names: Vec<&str> = parts.iter().map(|p| arg(p)).collect();
    let mut args = names.clone();
    args.extend(["-o", arg(&out)]);
    refused(&merge(&args), "missing tiles: 1/5 4/5");
    assert!(!out.exists());

    let mut args = vec!["--missing"];
    args.extend(&names);
    let listed = merge(&args);
    assert!(listed.status.success(), "{}", stderr(&listed));
    assert_eq!(stdout(&listed), "1/5\n4/5\n");
    // Before any part exists, --tiles says how many there are.
    let all = merge(&["--missing", "--tiles", "3"]);
    assert_eq!(stdout(&all), "0/3\n1/3\n2/3\n");
    refused(&merge(&["--missing"]), "no parts");

    // Rerun only what was listed: the frame is the whole render's.
    let listed = stdout(&listed);
    let rerun: Vec<&str> = listed.lines().collect();
    let more = render_parts(&dir, &[], &rerun);
    let mut args: Vec<&str> = names.clone();
    args.extend(more.iter().map(|p| arg(p)));
    args.extend(["-o", arg(&out)]);
    run_ok(&{
        let mut a = vec!["merge"];
        a.extend(&args);
        a
    });
    let whole = dir.join("whole.png");
    render_small(&project_file("scenes/showcase.p3f"), &[], &whole);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&whole).unwrap());
    let listed = merge(&[
        "--missing",
        names[0],
        names[1],
        names[2],
        arg(&more[0]),
        arg(&more[1]),
    ]);
    assert_eq!(stdout(&listed), "");
}

#[test]
fn merge_takes_agreeing_overlaps_and_refuses_disagreeing_ones() {
    let dir = scratch("merge_overlap");
    let out = dir.join("out.exr");
    let parts = render_parts(&dir, &[], &["0/2", "1/2"]);
    // A crop over both tiles, rendered by the same command: it agrees.
    let crop = dir.join("crop.exr");
    render_small(
        &project_file("scenes/showcase.p3f"),
        &["--pixel-bounds", "5,30,10,20"],
        &crop,
    );
    run_ok(&[
        "merge",
        arg(&parts[0]),
        arg(&crop),
        arg(&parts[1]),
        "-o",
        arg(&out),
    ]);
    // The same crop with one pixel changed, and the note kept: refused at that pixel.
    let bytes = std::fs::read(&crop).unwrap();
    let part = read_part(&bytes, "crop.exr").unwrap();
    let mut film = Film {
        width: part.region.width(),
        height: part.region.height(),
        pixels: part.pixels.clone(),
    };
    film.pixels[3].x = f32::from_bits(film.pixels[3].x.to_bits() ^ 1);
    let forged = dir.join("forged.exr");
    film.write_placed(
        &ImageOutput::file(&forged).unwrap(),
        &Placement {
            image: part.image,
            origin: (part.region.x0, part.region.y0),
            note: Some(part.identity.clone()),
        },
    )
    .unwrap();
    refused(
        &merge(&[
            arg(&parts[0]),
            arg(&parts[1]),
            arg(&forged),
            "-o",
            arg(&out),
        ]),
        "overlap and disagree at pixel (8, 10)",
    );
    // A part that says it is a tile but covers other rows.
    let mut note = part.identity.clone();
    note.push_str("\ntile: 1/2");
    let liar = dir.join("liar.exr");
    film.write_placed(
        &ImageOutput::file(&liar).unwrap(),
        &Placement {
            image: part.image,
            origin: (part.region.x0, part.region.y0),
            note: Some(note),
        },
    )
    .unwrap();
    refused(
        &merge(&[arg(&parts[0]), arg(&liar), "-o", arg(&out)]),
        "says it is tile 1/2",
    );
}

#[test]
fn merge_refuses_what_is_not_a_part() {
    let dir = scratch("merge_bad");
    let out = dir.join("out.png");
    let parts = render_parts(&dir, &[], &["0/2", "1/2"]);
    let bytes = std::fs::read(&parts[1]).unwrap();
    let truncated = dir.join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    refused(
        &merge(&[arg(&parts[0]), arg(&truncated), "-o", arg(&out)]),
        "truncated.exr: ",
    );
    let png = dir.join("part.png");
    render_small(
        &project_file("scenes/showcase.p3f"),
        &["--tile", "1/2"],
        &png,
    );
    refused(
        &merge(&[arg(&parts[0]), arg(&png), "-o", arg(&out)]),
        "not a readable OpenEXR file",
    );
    // An EXR without a note: compare's heat map.
    let heat = dir.join("heat.exr");
    let whole = dir.join("whole.png");
    run_ok(&["merge", arg(&parts[0]), arg(&parts[1]), "-o", arg(&whole)]);
    let _ = p3trace(&["compare", arg(&whole), arg(&whole), "--diff", arg(&heat)]);
    refused(
        &merge(&[arg(&heat), "-o", arg(&out)]),
        "no 'p3trace' attribute",
    );
    refused(
        &merge(&[arg(&parts[0]), "-o", arg(&dir.join("out.gif"))]),
        ".exr",
    );
    refused(&merge(&["-o", arg(&out)]), "no parts");
    let missing = merge(&[arg(&dir.join("nothing.exr")), "-o", arg(&out)]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(!out.exists());
}

#[test]
fn regions_on_the_command_line() {
    let dir = scratch("render_regions");
    let showcase = project_file("scenes/showcase.p3f");
    let png = dir.join("crop.png");
    render_small(&showcase, &["--crop", "0,0.5,0.2,0.7"], &png);
    let image = image::open(&png).unwrap();
    assert_eq!((image.width(), image.height()), (20, 15));
    // The JSON says which pixels were rendered.
    let json = dir.join("tile.json");
    render_small(&showcase, &["--tile", "2/3", "--json", arg(&json)], &png);
    let value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(value["region"], serde_json::json!([0, 40, 20, 30]));
    for (flags, says) in [
        (&["--tile", "8/8"][..], "0 <= I < N"),
        (&["--tile", "0/31"][..], "at most 30 tiles"),
        (&["--crop", "0,2,0,1"][..], "X0,X1,Y0,Y1"),
        (
            &["--pixel-bounds", "0,41,0,30"][..],
            "outside the 40x30 image",
        ),
        (
            &["--tile", "0/2", "--crop", "0,1,0,1"][..],
            "cannot be used with",
        ),
    ] {
        let mut args = vec![
            "render",
            arg(&showcase),
            "-q",
            "--resolution",
            "40x30",
            "-o",
            arg(&png),
        ];
        args.extend_from_slice(flags);
        refused(&p3trace(&args), says);
    }
}

#[test]
fn a_task_killed_mid_render_leaves_no_part_and_is_listed_missing() {
    let dir = scratch("merge_killed");
    let parts = render_parts(&dir, &[], &["0/2"]);
    let part = dir.join("1of2.exr");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_p3trace"))
        .args([
            "render",
            arg(&project_file("scenes/balls_high.p3f")),
            "-q",
            "--spp",
            "64",
            "--resolution",
            "400x300",
            "--tile",
            "1/2",
            "--threads",
            "1",
            "-o",
            arg(&part),
        ])
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(300));
    // SIGKILL, as a node failure: no handler runs.
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!part.exists(), "a killed task left its part");
    let listed = merge(&["--missing", arg(&parts[0])]);
    assert_eq!(stdout(&listed), "1/2\n");
}

#[test]
fn parts_of_one_scene_reached_by_different_paths_merge() {
    let dir = scratch("merge_paths");
    let parts = render_parts(&dir, &[], &["0/2"]);
    // The other half from the project folder, by a relative path.
    let other = dir.join("1of2.exr");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_p3trace"))
        .current_dir(project_file(""))
        .args([
            "render",
            "scenes/showcase.p3f",
            "-q",
            "--resolution",
            "40x30",
        ])
        .args(["--tile", "1/2", "-o", arg(&other)])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let merged = dir.join("merged.exr");
    run_ok(&["merge", arg(&parts[0]), arg(&other), "-o", arg(&merged)]);
    let whole = dir.join("whole.exr");
    let showcase = project_file("scenes/showcase.p3f");
    render_small(&showcase, &[], &whole);
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&whole).unwrap()
    );
}
