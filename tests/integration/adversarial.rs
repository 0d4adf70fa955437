//! Hostile input and hostile conditions, through the binary: bad scenes are refused with
//! exit 2 and `file:line:col` before anything is rendered; odd but valid scenes render
//! what they should; a failed or interrupted write never leaves an image behind.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::{p3trace, scratch, stderr, stdout};
use p3trace::imaging::to_byte;

/// A camera on line 1, looking down -Z at the origin from 5 units away.
const CAMERA: &str = "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45 resolution 16 12\n";
const BACKGROUND: [f32; 3] = [0.2, 0.4, 0.6];

fn background_line() -> String {
    format!(
        "bclr {} {} {}\n",
        BACKGROUND[0], BACKGROUND[1], BACKGROUND[2]
    )
}

/// The names in `dir`, sorted.
fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn write_scene(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("scene.p3f");
    std::fs::write(&path, text).unwrap();
    path
}

/// Each bad scene: its text, where the error is (line, column) and what the message says.
const BAD_SCENES: &[(&str, &str, (u32, u32), &str)] = &[
    (
        "nan radius",
        "s 0 0 0 nan",
        (2, 9),
        "must be a finite number",
    ),
    (
        "NaN coordinate",
        "s 0 NaN 0 1",
        (2, 5),
        "must be a finite number",
    ),
    (
        "infinite light",
        "l 1 inf 2",
        (2, 5),
        "must be a finite number",
    ),
    (
        "-inf in a material",
        "f 1 1 1 1 1 1 1 -inf 10 0 1",
        (2, 17),
        "must be a finite number",
    ),
    (
        "overflowing number",
        "s 1e39 0 0 1",
        (2, 3),
        "must be a finite number",
    ),
    (
        "number beyond the limit",
        "box 0 0 0 2e9 1 1",
        (2, 11),
        "at most 1e9 in magnitude",
    ),
    (
        "mesh count beyond the file",
        "mesh 2000000000 1\n0 0 0",
        (2, 6),
        "bytes remain",
    ),
    (
        "polygon count beyond the file",
        "p 1000000 0 0 0",
        (2, 3),
        "bytes remain",
    ),
    (
        "mesh triangles beyond the file",
        "mesh 3 3\n0 0 0 1 0 0 0 1 0\n1 2 3",
        (2, 1),
        "more numbers than the rest of the file holds",
    ),
    (
        "mesh index out of range",
        "mesh 3 1\n0 0 0 1 0 0 0 1 0\n1 2 4",
        (4, 5),
        "vertex index 4 is out of range",
    ),
    (
        "mesh index 0",
        "mesh 3 1\n0 0 0 1 0 0 0 1 0\n0 1 2",
        (4, 1),
        "vertex index 0",
    ),
    (
        "unknown directive",
        "sphere 0 0 0 1",
        (2, 1),
        "unknown directive 'sphere'",
    ),
    (
        "directive cut by the end of the file",
        "s 0 0 0",
        (3, 1),
        "found the end of the file",
    ),
    (
        "directive cut by the next one",
        "f 1 1 1\ns 0 0 0 1",
        (2, 8),
        "expected Kd (a number), found the end of the line ('s' follows on line 3)",
    ),
    (
        "negative radius",
        "s 0 0 0 -1",
        (2, 1),
        "the radius must not be negative",
    ),
    (
        "negative moving radius",
        "ms 0 0 0 1 0 0 -0.5 0 1",
        (2, 1),
        "the radius must not be negative",
    ),
];

/// Camera blocks that cannot make rays or images, each alone in its file.
const BAD_CAMERAS: &[(&str, &str, (u32, u32), &str)] = &[
    (
        "up parallel to the view",
        "v from 0 5 0 at 0 0 0 up 0 1 0 angle 45 resolution 16 12",
        (1, 1),
        "parallel to the view direction",
    ),
    (
        "from equal to at",
        "v from 1 1 1 at 1 1 1 up 0 1 0 angle 45 resolution 16 12",
        (1, 1),
        "'from' and 'at' are the same point",
    ),
    (
        "resolution 0",
        "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45 resolution 0 12",
        (1, 52),
        "the image width must be between 1 and",
    ),
    (
        "image beyond memory",
        "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45 resolution 65536 65536",
        (1, 41),
        "a 65536x65536 image needs 96.0 GiB",
    ),
];

#[test]
fn bad_scenes_exit_2_at_their_position_and_render_nothing() {
    let cases = BAD_SCENES
        .iter()
        .map(|&(name, bad, at, says)| (name, format!("{CAMERA}{bad}\n"), at, says))
        .chain(
            BAD_CAMERAS
                .iter()
                .map(|&(name, text, at, says)| (name, format!("{text}\n"), at, says)),
        );
    for (name, text, (line, column), says) in cases {
        let dir = scratch("adversarial_errors");
        let scene = write_scene(&dir, &text);
        let image = dir.join("out.png");
        let out = p3trace(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            image.to_str().unwrap(),
        ]);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{name}: {message}");
        let prefix = format!("p3trace: error: {}:{line}:{column}: ", scene.display());
        assert!(message.starts_with(&prefix), "{name}: {message}");
        assert!(message.contains(says), "{name}: {message}");
        assert!(!message.contains("panicked"), "{name}: {message}");
        assert_eq!(stdout(&out), "", "{name}: results on stdout");
        assert_eq!(
            files_in(&dir),
            ["scene.p3f"],
            "{name}: something was written"
        );
    }
}

/// Renders `text` with every structure in both modes; all must succeed with the same
/// image, which is returned with the stderr of the first run.
fn render_everywhere(name: &str, text: &str) -> (image::RgbImage, String) {
    let dir = scratch(&format!("adversarial_{name}"));
    let scene = write_scene(&dir, text);
    let mut first: Option<(image::RgbImage, String)> = None;
    for accel in ["none", "grid", "bvh"] {
        for mode in ["scalar", "stream"] {
            let image_path = dir.join(format!("{accel}-{mode}.ppm"));
            let out = p3trace(&[
                "render",
                scene.to_str().unwrap(),
                "--accel",
                accel,
                "--mode",
                mode,
                "-o",
                image_path.to_str().unwrap(),
            ]);
            let message = stderr(&out);
            assert!(out.status.success(), "{name} {accel} {mode}: {message}");
            assert!(!message.contains("panicked"), "{name}: {message}");
            let image = image::open(&image_path).unwrap().into_rgb8();
            assert_eq!(image.dimensions(), (16, 12), "{name}");
            match &first {
                None => first = Some((image, message)),
                Some((expected, _)) => {
                    assert!(&image == expected, "{name}: {accel} {mode} differs")
                }
            }
        }
    }
    first.unwrap()
}

fn background_bytes() -> [u8; 3] {
    BACKGROUND.map(to_byte)
}

fn assert_only_background(name: &str, image: &image::RgbImage) {
    for (x, y, pixel) in image.enumerate_pixels() {
        assert_eq!(pixel.0, background_bytes(), "{name}: pixel ({x}, {y})");
    }
}

#[test]
fn degenerate_triangles_in_front_of_the_camera_are_never_hit() {
    let text = format!(
        "{CAMERA}{}l 0 5 5\nf 1 0 0 1 1 1 1 0.5 10 0 1\n\
         p 3 -1 -1 0 0 0 0 1 1 0\n\
         p 3 -1 -1 0 -1 -1 0 1 1 0\n\
         p 3 0 0 0 0 0 0 0 0 0\n\
         p 3 0 0 1 1e-30 0 1 0 1e-30 1\n\
         p 4 -2 -2 0 -1 -1 0 1 1 0 2 2 0\n\
         pp 3 -1 0 0 0 0 1 0 0 0 0 0 1 1 0 0 0 0 1\n\
         mesh 3 2 -1 0 0 1 0 0 2 0 0 1 2 3 1 1 2\n",
        background_line()
    );
    let (image, _) = render_everywhere("degenerate", &text);
    assert_only_background("degenerate triangles", &image);
}

#[test]
fn zero_radius_spheres_are_never_hit_and_warned_about() {
    let text = format!(
        "{CAMERA}{}l 0 5 5\nf 1 0 0 1 1 1 1 0.5 10 0 1\ns 0 0 0 0\nms 0 0 0 0 0 1 0 0 1\n",
        background_line()
    );
    let (image, message) = render_everywhere("zero_radius", &text);
    assert_only_background("zero-radius spheres", &image);
    assert!(
        message.contains("scene.p3f:5:1: warning: 's': a sphere of radius 0 is never hit"),
        "{message}"
    );
    assert!(
        message.contains("scene.p3f:6:1: warning: 'ms'"),
        "{message}"
    );
}

#[test]
fn scenes_without_objects_or_lights_render() {
    let (image, _) = render_everywhere("empty", &format!("{CAMERA}{}", background_line()));
    assert_only_background("no objects, no lights", &image);
    let (image, _) = render_everywhere(
        "light_no_objects",
        &format!("{CAMERA}{}l 0 5 5\n", background_line()),
    );
    assert_only_background("a light and no objects", &image);

    // A white diffuse sphere with no light: black where it is (no ambient term), the
    // background around it.
    let (image, _) = render_everywhere(
        "no_lights",
        &format!(
            "{CAMERA}{}f 1 1 1 1 0 0 0 0 10 0 1\ns 0 0 0 1\n",
            background_line()
        ),
    );
    assert_eq!(image.get_pixel(8, 6).0, [0, 0, 0]);
    assert_eq!(image.get_pixel(0, 0).0, background_bytes());
}

fn showcase() -> String {
    common::project_file("scenes/showcase.p3f")
        .display()
        .to_string()
}

#[test]
fn an_unknown_output_extension_is_refused_before_the_scene_is_read() {
    let dir = scratch("adversarial_extension");
    let out = p3trace(&[
        "render",
        dir.join("missing.p3f").to_str().unwrap(),
        "-o",
        dir.join("out.gif").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let message = stderr(&out);
    assert!(
        message.contains("cannot tell the image format"),
        "{message}"
    );
    assert!(files_in(&dir).is_empty());
}

#[test]
fn a_target_that_is_a_folder_fails_with_1_before_the_render() {
    let dir = scratch("adversarial_folder_target");
    std::fs::create_dir(dir.join("out.png")).unwrap();
    let target = dir.join("out.png");
    let out = p3trace(&[
        "render",
        &showcase(),
        "--resolution",
        "64x64",
        "-o",
        target.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        format!(
            "p3trace: error: cannot write {}: it is a folder\n",
            target.display()
        ),
        "refused before the render's progress lines"
    );
    assert_eq!(files_in(&dir), ["out.png"]);
    assert!(target.is_dir());
}

/// Every command that writes a file after long work checks first that it can: the
/// output's folder exists and is a folder, and a file can be made there. The refusal is
/// an I/O failure (exit 1, as the write's would be), and comes before the inputs are
/// read: these inputs do not exist, and are not what the message speaks of.
#[test]
fn an_output_that_cannot_be_written_is_refused_before_the_work() {
    let dir = scratch("adversarial_unwritable");
    let missing = dir.join("nope");
    let file = dir.join("file");
    std::fs::write(&file, b"").unwrap();
    let absent = dir.join("absent.p3f").display().to_string();
    let part = dir.join("absent.exr").display().to_string();
    let image = dir.join("absent.png").display().to_string();
    let ply = dir.join("absent.ply").display().to_string();
    // OUT stands for the output that cannot be written, `name` in `folder`.
    for (args, folder, name) in [
        (&["render", &absent, "-o", "OUT"][..], &missing, "x.png"),
        (&["render", &absent, "-o", "OUT"], &file, "x.png"),
        (
            &["render", &absent, "-o", &image, "--json", "OUT"],
            &missing,
            "s.json",
        ),
        (&["bench", &absent, "--json", "OUT"], &missing, "s.json"),
        (&["merge", &part, "-o", "OUT"], &missing, "m.exr"),
        (
            &["compare", &image, &image, "--diff", "OUT"],
            &missing,
            "d.png",
        ),
        (&["gen", "mount", "-o", "OUT"], &missing, "m.p3f"),
        (
            &["gen", "dragon", "--ply", &ply, "-o", "OUT"],
            &file,
            "d.p3f",
        ),
    ] {
        let target = folder.join(name).display().to_string();
        let args: Vec<&str> = args
            .iter()
            .map(|&a| if a == "OUT" { target.as_str() } else { a })
            .collect();
        let why = if folder == &missing {
            format!("the folder {} does not exist", folder.display())
        } else {
            format!("{} is not a folder", folder.display())
        };
        let out = p3trace(&args);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {}", stderr(&out));
        assert_eq!(
            stderr(&out),
            format!("p3trace: error: cannot write {target}: {why}\n"),
            "{args:?}"
        );
        assert_eq!(stdout(&out), "", "{args:?}");
    }
    assert_eq!(files_in(&dir), ["file"], "nothing written, no probe left");

    // A render that would take a while is refused at once, its progress never shown.
    let run = p3trace(&[
        "render",
        &showcase(),
        "--resolution",
        "512x512",
        "--spp",
        "16",
        "-o",
        missing.join("x.png").to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1));
    assert!(!stderr(&run).contains("progress"), "{}", stderr(&run));
}

/// A folder the user may not write into is refused before the render too (root may write
/// anywhere: then this test skips).
#[test]
fn a_folder_without_write_permission_is_refused_before_the_render() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("adversarial_read_only");
    let locked = dir.join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(locked.join("probe"), b"").is_ok() {
        std::fs::remove_file(locked.join("probe")).unwrap();
        common::skip("this user may write into a read-only folder (root)");
        return;
    }
    let target = locked.join("x.png");
    let out = p3trace(&[
        "render",
        dir.join("absent.p3f").to_str().unwrap(),
        "-o",
        target.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let prefix = format!("p3trace: error: cannot write {}: ", target.display());
    assert!(stderr(&out).starts_with(&prefix), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("ermission denied"),
        "{}",
        stderr(&out)
    );
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// A full disk, as the file size limit makes one: writes fail with "file too large"
/// (the shell ignores SIGXFSZ, which would otherwise kill the process mid-write).
#[test]
fn a_full_disk_keeps_the_old_image_and_leaves_no_partial_file() {
    let dir = scratch("adversarial_full_disk");
    let target = dir.join("out.ppm");
    std::fs::write(&target, b"the previous image").unwrap();
    let out = Command::new("sh")
        .args([
            "-c",
            "trap '' XFSZ; ulimit -f 8 && exec \"$0\" \"$@\"",
            env!("CARGO_BIN_EXE_p3trace"),
            "render",
            &showcase(),
            "--resolution",
            "256x256",
            "--spp",
            "1",
            "-o",
            target.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("cannot write"), "{}", stderr(&out));
    assert_eq!(files_in(&dir), ["out.ppm"]);
    assert_eq!(std::fs::read(&target).unwrap(), b"the previous image");
}

/// The signals that end a run cleanly, as `kill` names them, and the exit status each
/// gives: 128 + its number, as a shell reports a process the signal ended.
const SIGNALS: [(&str, i32); 3] = [("INT", 130), ("TERM", 143), ("HUP", 129)];

#[test]
fn ctrl_c_and_termination_exit_128_plus_the_signal_and_leave_no_image() {
    for (signal, status) in SIGNALS {
        interrupted_render_leaves_no_image(signal, status);
    }
}

/// Waits for `child` to end after `signal`, and returns what it said.
fn stopped(mut child: std::process::Child, signal: &str) -> std::process::Output {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(30) {
            child.kill().unwrap();
            panic!("p3trace did not stop within 30 s of SIG{signal}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn send(signal: &str, child: &std::process::Child) {
    let kill = Command::new("kill")
        .args([format!("-{signal}"), child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
}

/// Sends `signal` (as `kill` names it) to a long render, which must exit with `status`.
fn interrupted_render_leaves_no_image(signal: &str, status: i32) {
    let dir = scratch(&format!("adversarial_signal_{signal}"));
    let target = dir.join("out.png");
    // Minutes of work on one thread: still rendering when the interrupt comes.
    let mut child = Command::new(env!("CARGO_BIN_EXE_p3trace"))
        .args([
            "render",
            &showcase(),
            "--resolution",
            "1024x1024",
            "--spp",
            "256",
            "--threads",
            "1",
            "-o",
            target.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the render ended before the interrupt"
    );
    send(signal, &child);
    let out = stopped(child, signal);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(status), "SIG{signal}: {message}");
    assert!(
        message.contains(&format!("p3trace: interrupted (SIG{signal})")),
        "{message}"
    );
    assert!(files_in(&dir).is_empty(), "{:?}", files_in(&dir));
}

/// A signal that comes while the output is being written removes the partial file. The
/// partial file is made a FIFO that nobody reads, so that the writer blocks in the
/// middle of the scene (far longer than a pipe's buffer) until the signal comes.
#[test]
fn a_signal_during_the_write_removes_the_partial_file() {
    use std::os::unix::fs::OpenOptionsExt;
    for (signal, status) in SIGNALS {
        let dir = scratch(&format!("adversarial_signal_write_{signal}"));
        let target = dir.join("mount.p3f");
        // The shell makes the FIFO under the name the process it becomes (same PID)
        // will write through.
        let child = Command::new("sh")
            .args([
                "-c",
                "mkfifo \"$(dirname \"$1\")/.$(basename \"$1\").$$.partial\" && exec \"$0\" gen mount \
                 --level 7 -o \"$1\"",
                env!("CARGO_BIN_EXE_p3trace"),
                target.to_str().unwrap(),
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let fifo = dir.join(format!(".mount.p3f.{}.partial", child.id()));
        let start = Instant::now();
        while !fifo.exists() {
            assert!(start.elapsed() < Duration::from_secs(10), "no FIFO made");
            std::thread::sleep(Duration::from_millis(10));
        }
        // A reader that never reads: opening the FIFO for writing succeeds, and the
        // writes block once its buffer is full.
        let _reader = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(&fifo)
            .unwrap();
        std::thread::sleep(Duration::from_millis(500));
        send(signal, &child);
        let out = stopped(child, signal);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(status), "SIG{signal}: {message}");
        assert!(files_in(&dir).is_empty(), "{:?}", files_in(&dir));
    }
}

/// Six JPEG faces of a gradient in `dir`, as a photographed skybox holds them.
fn jpeg_skybox(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    let face = image::RgbImage::from_fn(128, 128, |x, y| {
        let noise = (x.wrapping_mul(2_654_435_761) ^ y.wrapping_mul(40_503)) >> 24;
        image::Rgb([(2 * x) as u8, (2 * y) as u8, noise as u8])
    });
    for name in p3trace::render::skybox::FACE_NAMES {
        face.save(dir.join(format!("{name}.jpg"))).unwrap();
    }
}

#[test]
fn a_damaged_skybox_face_is_named_by_render_and_info() {
    let dir = scratch("adversarial_damaged_sky");
    jpeg_skybox(&dir.join("sky"));
    let scene = write_scene(
        &dir,
        "env sky\nv from 0 0 0 at 0 0 -1 up 0 1 0 angle 120 hither 0.01 resolution 32 32\n",
    );
    let image = dir.join("out.png");
    let render = || {
        p3trace(&[
            "render",
            scene.to_str().unwrap(),
            "-q",
            "-o",
            image.to_str().unwrap(),
        ])
    };
    let sound = render();
    assert!(sound.status.success(), "{}", stderr(&sound));
    assert_eq!(stderr(&sound), "", "sound faces draw no warning");
    // The back face (the camera looks down -z) cut short by 12 bytes, as a copy that lost
    // bytes is.
    let back = dir.join("sky/back.jpg");
    let bytes = std::fs::read(&back).unwrap();
    std::fs::write(&back, &bytes[..bytes.len() - 12]).unwrap();
    let damaged = render();
    let message = stderr(&damaged);
    assert!(damaged.status.success(), "{message}");
    assert!(
        message.contains("warning: damaged skybox face")
            && message.contains("back.jpg (premature end of data segment)"),
        "{message}"
    );
    assert_eq!(
        message.lines().count(),
        1,
        "only the damaged face: {message}"
    );
    // info says it too, in the same words.
    let info = p3trace(&["info", scene.to_str().unwrap()]);
    assert!(info.status.success(), "{}", stderr(&info));
    assert_eq!(stderr(&info), message);
}
