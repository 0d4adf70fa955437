//! `p3trace view` in a real window: an X server of the test's own (Xvfb), the window
//! driven by xdotool, its picture taken with xwd and compared with `render`'s image. Each
//! test skips, saying why, where Xvfb, xdotool or xwd is missing; under CI (`CI` set)
//! it fails instead, since `.ci/run` installs them.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use p3trace::imaging::Film;
use p3trace::render::sampler::SampleGrid;
use p3trace::render::{render, RenderMode, RenderOptions, Sampling, Stage};
use p3trace::scene::{parse_file, parse_file_in, Frame};
use p3trace::view::{camera_block, Accumulator, Orbit};

use crate::common::{project_file, scratch, skip, stderr, succeeds};

/// A scene small enough to converge in a moment: 4 samples a pixel, a glass sphere.
const SCENE: &str = "\
spp 2
bclr 0.1 0.2 0.3
v
from 0.5 -4 1.5
at 0 0 0.5
up 0 0 1
angle 40
hither 0.01
resolution 96 64
l 2 -3 4 1 1 1
f 0.9 0.8 0.6 0.8 1 1 1 0.2 30 0 1
p 4
4 4 0
-4 4 0
-4 -4 0
4 -4 0
f 0.8 0.3 0.2 0.7 1 1 1 0.5 40 0 1
s -0.6 0 0.5 0.5
f 1 1 1 0.1 1 1 1 0.5 80 0.8 1.5
s 0.7 0.3 0.6 0.6
";

const TIMEOUT: Duration = Duration::from_secs(30);

/// An X server of one test's own, on a display number it chose itself.
struct Display {
    server: Child,
    name: String,
}

/// Whether Xvfb, xdotool and xwd are installed; where one is not, says that the test
/// skips, or under CI fails.
fn tools_present() -> bool {
    for tool in ["Xvfb", "xdotool", "xwd"] {
        let found = Command::new("sh")
            .args(["-c", &format!("command -v {tool}")])
            .output()
            .is_ok_and(|o| o.status.success());
        if !found {
            assert!(
                std::env::var_os("CI").is_none(),
                "CI must install {tool} for the window tests (see .ci/run)"
            );
            skip(format_args!("{tool} is not installed"));
            return false;
        }
    }
    true
}

impl Display {
    /// The server, or `None` (said, or under CI a failure) where the tools are missing.
    fn start() -> Option<Display> {
        if !tools_present() {
            return None;
        }
        let mut server = Command::new("Xvfb")
            // No reset when the last client leaves (each xdotool call is a client): a
            // server resetting refuses the viewer's connection.
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "640x480x24",
                "-nolisten",
                "tcp",
            ])
            .arg("-noreset")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let mut number = String::new();
        BufReader::new(server.stdout.take().unwrap())
            .read_line(&mut number)
            .expect("Xvfb says its display");
        let display = Display {
            server,
            name: format!(":{}", number.trim()),
        };
        let start = Instant::now();
        while display.xdotool(&["getdisplaygeometry"]).is_empty() {
            assert!(
                start.elapsed() < TIMEOUT,
                "Xvfb on {} takes no client",
                display.name
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        Some(display)
    }

    fn xdotool(&self, args: &[&str]) -> String {
        let out = Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &self.name)
            .output()
            .expect("xdotool runs");
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }
}

impl Drop for Display {
    /// Ends the server as a session would, with SIGTERM: killed, it would leave its
    /// socket file, and a later server of the same number could not take it, so that
    /// Xlib (which connects through the file) would find no server there.
    fn drop(&mut self) {
        // SAFETY: a signal to a child process of ours, which we then wait for.
        unsafe { libc::kill(self.server.id() as libc::pid_t, libc::SIGTERM) };
        let _ = self.server.wait();
    }
}

/// A running viewer, its output gathered as it comes.
struct Viewer<'d> {
    display: &'d Display,
    child: Child,
    window: String,
    stdout: Arc<Mutex<String>>,
    stderr: Arc<Mutex<String>>,
}

fn gather(stream: impl Read + Send + 'static) -> Arc<Mutex<String>> {
    let text = Arc::new(Mutex::new(String::new()));
    let sink = Arc::clone(&text);
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines().map_while(Result::ok) {
            let mut text = sink.lock().unwrap();
            text.push_str(&line);
            text.push('\n');
        }
    });
    text
}

impl<'d> Viewer<'d> {
    /// `p3trace view SCENE ARGS` in `folder`, once its window is up and has the focus.
    fn open(display: &'d Display, scene: &Path, args: &[&str], folder: &Path) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_p3trace"))
            .arg("view")
            .arg(scene)
            .args(args)
            .current_dir(folder)
            .env("DISPLAY", &display.name)
            .env_remove("WAYLAND_DISPLAY")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("p3trace view starts");
        let stdout = gather(child.stdout.take().unwrap());
        let stderr = gather(child.stderr.take().unwrap());
        let name = scene.file_name().unwrap().to_string_lossy().into_owned();
        let start = Instant::now();
        let window = loop {
            let found = display.xdotool(&["search", "--name", &name]);
            if let Some(id) = found.lines().next() {
                break id.to_string();
            }
            if let Ok(Some(status)) = child.try_wait() {
                panic!("view exited ({status}): {}", stderr.lock().unwrap());
            }
            assert!(start.elapsed() < TIMEOUT, "no window named {name}");
            std::thread::sleep(Duration::from_millis(50));
        };
        display.xdotool(&["windowfocus", "--sync", &window]);
        display.xdotool(&["mousemove", "--window", &window, "10", "10"]);
        Viewer {
            display,
            child,
            window,
            stdout,
            stderr,
        }
    }

    fn title(&self) -> String {
        self.display.xdotool(&["getwindowname", &self.window])
    }

    /// Waits until the title says `what`, and returns it.
    fn wait_title(&self, what: impl Fn(&str) -> bool, meaning: &str) -> String {
        let start = Instant::now();
        loop {
            let title = self.title();
            if what(&title) {
                return title;
            }
            assert!(
                start.elapsed() < TIMEOUT,
                "the title never showed {meaning}: {title}; stderr: {}",
                self.stderr.lock().unwrap()
            );
            std::thread::sleep(Duration::from_millis(30));
        }
    }

    /// Waits until all 4 samples are in: the image is then `render`'s.
    fn wait_converged(&self) -> String {
        self.wait_title(|t| t.contains("| 4/4 spp"), "4/4 spp")
    }

    fn key(&self, key: &str) {
        self.display.xdotool(&["key", key]);
    }

    /// Waits until the viewer's standard output holds `what`.
    fn wait_stdout(&self, what: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let out = self.stdout.lock().unwrap().clone();
            if what(&out) {
                return out;
            }
            assert!(start.elapsed() < TIMEOUT, "stdout never came: {out}");
            std::thread::sleep(Duration::from_millis(30));
        }
    }

    /// A drag with `button` from `(x, y)` by `(dx, dy)` pixels of the window, each step
    /// held long enough for the viewer's frames to see it.
    fn drag(&self, button: &str, (x, y): (u32, u32), (dx, dy): (i32, i32)) {
        let d = self.display;
        let (x, y) = (x.to_string(), y.to_string());
        d.xdotool(&["mousemove", "--window", &self.window, &x, &y]);
        std::thread::sleep(Duration::from_millis(150));
        d.xdotool(&["mousedown", button]);
        std::thread::sleep(Duration::from_millis(150));
        d.xdotool(&["mousemove_relative", "--", &dx.to_string(), &dy.to_string()]);
        std::thread::sleep(Duration::from_millis(150));
        d.xdotool(&["mouseup", button]);
        std::thread::sleep(Duration::from_millis(150));
    }

    /// The window's picture: its width, height and RGB bytes, top row first.
    fn screenshot(&self) -> (u32, u32, Vec<u8>) {
        let out = Command::new("xwd")
            .args(["-silent", "-id", &self.window])
            .env("DISPLAY", &self.display.name)
            .output()
            .expect("xwd runs");
        assert!(out.status.success(), "xwd: {}", stderr(&out));
        read_xwd(&out.stdout)
    }

    /// Waits until the window's picture is what `what` looks for.
    fn wait_picture(&self, what: impl Fn(&(u32, u32, Vec<u8>)) -> bool, meaning: &str) {
        let start = Instant::now();
        while !what(&self.screenshot()) {
            assert!(
                start.elapsed() < TIMEOUT,
                "the window never showed {meaning}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Waits for the viewer to exit, and returns its status.
    fn exit(mut self) -> ExitStatus {
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                return status;
            }
            assert!(start.elapsed() < TIMEOUT, "view did not exit");
            std::thread::sleep(Duration::from_millis(30));
        }
    }
}

impl Drop for Viewer<'_> {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The pixels of an XWD file (X11's window dump) of 24 or 32 bits a pixel, as RGB.
fn read_xwd(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let field = |i: usize| u32::from_be_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    let (header, width, height) = (field(0) as usize, field(4), field(5));
    let (lsb_first, bits, line) = (field(7) == 0, field(11), field(12) as usize);
    let (masks, colours) = ([field(14), field(15), field(16)], field(19) as usize);
    assert!(bits == 32 || bits == 24, "{bits} bits a pixel");
    let data = &bytes[header + 12 * colours..];
    let step = bits as usize / 8;
    let mut rgb = Vec::with_capacity((width * height * 3) as usize);
    for row in 0..height as usize {
        for x in 0..width as usize {
            let at = row * line + x * step;
            let mut raw = [0u8; 4];
            raw[..step].copy_from_slice(&data[at..at + step]);
            let pixel = if lsb_first {
                u32::from_le_bytes(raw)
            } else {
                u32::from_be_bytes(raw) >> (32 - bits)
            };
            for mask in masks {
                rgb.push(((pixel & mask) >> mask.trailing_zeros()) as u8);
            }
        }
    }
    (width, height, rgb)
}

/// The scene of these tests in a folder of the test's own.
fn scene_in(name: &str) -> (PathBuf, PathBuf) {
    let dir = scratch(name);
    let path = dir.join("viewed.p3f");
    std::fs::write(&path, SCENE).unwrap();
    (dir, path)
}

/// `render`'s image of `path` with `args`: its size and RGB bytes.
fn rendered(path: &Path, args: &[&str], dir: &Path) -> (u32, u32, Vec<u8>) {
    let out = dir.join("rendered.png");
    let mut all = vec![
        "render",
        path.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    all.extend(args);
    succeeds(&all);
    let image = image::open(&out).unwrap().to_rgb8();
    (image.width(), image.height(), image.into_raw())
}

#[test]
fn without_a_display_it_says_so_at_once() {
    let (_dir, path) = scene_in("view_no_display");
    let out = Command::new(env!("CARGO_BIN_EXE_p3trace"))
        .arg("view")
        .arg(&path)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let message = stderr(&out);
    for word in ["DISPLAY", "WAYLAND_DISPLAY", "p3trace render"] {
        assert!(message.contains(word), "{message}");
    }
}

#[test]
fn the_converged_window_is_the_render_and_s_saves_it() {
    let Some(display) = Display::start() else {
        return;
    };
    let (dir, path) = scene_in("view_converges");
    let viewer = Viewer::open(&display, &path, &[], &dir);
    let title = viewer.wait_converged();
    assert!(title.starts_with("viewed.p3f | "), "{title}");
    assert!(title.contains("FPS") && title.contains("Mrays/s") && title.contains("BVH"));
    let expected = rendered(&path, &[], &dir);
    assert!(
        viewer.screenshot() == expected,
        "the window differs from render's image"
    );

    viewer.key("s");
    viewer.key("s");
    let start = Instant::now();
    while !dir.join("viewed-1.png").exists() {
        assert!(start.elapsed() < TIMEOUT, "s saved no second file");
        std::thread::sleep(Duration::from_millis(30));
    }
    std::thread::sleep(Duration::from_millis(200));
    let render_png = std::fs::read(dir.join("rendered.png")).unwrap();
    for saved in ["viewed.png", "viewed-1.png"] {
        let bytes = std::fs::read(dir.join(saved)).unwrap();
        assert!(bytes == render_png, "{saved} differs from render's PNG");
    }
    viewer.key("Escape");
    assert!(viewer.exit().success());
}

#[test]
fn a_drag_orbits_as_the_course_program_and_r_restores_the_camera() {
    let Some(display) = Display::start() else {
        return;
    };
    let (dir, path) = scene_in("view_orbit");
    let viewer = Viewer::open(&display, &path, &[], &dir);
    viewer.wait_converged();
    viewer.drag("1", (20, 20), (30, 12));
    viewer.wait_converged();
    viewer.key("c");
    let scene = parse_file_in(&path, Frame::Camera).unwrap();
    let mut orbit = Orbit::new(&scene.camera);
    orbit.turn(30.0, 12.0);
    let turned = camera_block(&orbit.camera(), scene.origin);
    viewer.wait_stdout(|out| out == turned);
    let expected = rendered(&path, &[], &dir);
    viewer.wait_picture(|p| *p != expected, "the turned camera's image");

    viewer.key("r");
    viewer.key("c");
    let file = camera_block(&scene.camera, scene.origin);
    viewer.wait_stdout(|out| out == format!("{turned}{file}"));
    viewer.wait_picture(|p| *p == expected, "the file camera's image again");
    assert!(file.starts_with("v\nfrom 0.5 -4 1.5\nat 0 0 0.5\nup 0 0 1\nangle 40\n"));

    // The right button moves the eye along the view: further away going down.
    viewer.drag("3", (20, 20), (0, 20));
    viewer.wait_converged();
    viewer.key("c");
    let mut further = Orbit::new(&scene.camera);
    further.dolly(-1.0);
    let further = camera_block(&further.camera(), scene.origin);
    viewer.wait_stdout(|out| out.ends_with(&further));
    viewer.key("q");
    assert!(viewer.exit().success());
}

#[test]
fn an_edit_is_shown_and_a_broken_one_keeps_the_image() {
    let Some(display) = Display::start() else {
        return;
    };
    let (dir, path) = scene_in("view_reload");
    let viewer = Viewer::open(&display, &path, &[], &dir);
    viewer.wait_converged();
    let before = viewer.screenshot();

    let edited = SCENE.replace("bclr 0.1 0.2 0.3", "bclr 0.9 0.1 0.1");
    std::fs::write(&path, &edited).unwrap();
    let expected = rendered(&path, &[], &dir);
    viewer.wait_picture(|p| *p == expected, "the edit");
    assert!(expected != before);

    std::fs::write(
        &path,
        edited.replace("s 0.7 0.3 0.6 0.6", "s 0.7 0.3 zero 0.6"),
    )
    .unwrap();
    let title = viewer.wait_title(|t| t.contains("error:"), "the error");
    assert!(title.contains("viewed.p3f:20:"), "{title}");
    assert!(
        viewer.screenshot() == expected,
        "a broken scene changed the image"
    );
    assert!(viewer.stderr.lock().unwrap().contains("viewed.p3f:20:"));

    // Mended, the error goes; the file's settings are read again too.
    std::fs::write(&path, SCENE.replace("spp 2", "spp 3")).unwrap();
    viewer.wait_title(
        |t| !t.contains("error:") && t.contains("| 9/9 spp"),
        "no error",
    );
    viewer.key("Escape");
    assert!(viewer.exit().success());
}

#[test]
fn keys_switch_structure_cost_and_effects() {
    let Some(display) = Display::start() else {
        return;
    };
    let (dir, path) = scene_in("view_keys");
    let viewer = Viewer::open(&display, &path, &["--aperture", "3"], &dir);
    viewer.wait_converged();
    let bvh = viewer.screenshot();
    viewer.key("g");
    let title = viewer.wait_title(|t| t.contains("| grid") && t.contains("| 4/4"), "the grid");
    assert!(title.contains("BVH") && title.contains("a pass"), "{title}");
    assert!(
        viewer.screenshot() == bvh,
        "the grid's image differs from the BVH's"
    );
    viewer.key("n");
    viewer.wait_title(
        |t| t.contains("| brute force") && t.contains("| 4/4"),
        "brute force",
    );
    assert!(viewer.screenshot() == bvh);

    viewer.key("k");
    viewer.wait_title(|t| t.contains("cost: prims"), "the cost image");
    viewer.wait_picture(|p| *p != bvh, "the cost image");
    viewer.key("k");
    viewer.key("b");
    viewer.wait_title(
        |t| t.contains("| BVH") && t.contains("| 4/4"),
        "the colours",
    );
    assert!(viewer.screenshot() == bvh);
    viewer.key("e");
    viewer.wait_title(
        |t| t.contains("effects off") && t.contains("| 4/4"),
        "effects off",
    );
    let pinhole = rendered(&path, &["--aperture", "0"], &dir);
    assert!(pinhole != bvh && viewer.screenshot() == pinhole);
    viewer.key("Escape");
    assert!(viewer.exit().success());
}

/// The viewer's passes, one sample of each pixel's grid a pass on one stage, add up to the
/// render's film bit for bit: every effect on, a grid that is not square, both modes.
#[test]
fn passes_add_up_to_the_render_bit_for_bit() {
    for name in [
        "scenes/motion.p3f",
        "scenes/dof.p3f",
        "scenes/balls_box.p3f",
    ] {
        let scene = parse_file(&project_file(name)).unwrap();
        for mode in RenderMode::ALL {
            let mut options = RenderOptions::from_scene(&scene);
            (options.width, options.height) = (37, 29);
            options.sampling = Sampling::Jittered(SampleGrid::with_cells(6));
            options.shade.soft_light_size = Some(0.6);
            options.shade.roughness = 0.3;
            options.shutter = [0.0, 0.5];
            options.mode = mode;
            let whole = render(&scene, &options).unwrap().film;
            let stage = Stage::new(&scene, &options);
            let mut sums = Accumulator::new(options.width, options.height);
            for k in 0..6 {
                let pass = RenderOptions {
                    samples: Some(k..k + 1),
                    ..options.clone()
                };
                sums.add(&stage.render(&scene.camera, &pass).unwrap().film);
                let partial: Film = sums.image();
                assert_eq!(partial == whole, k == 5, "{name} {mode:?}: after pass {k}");
            }
            assert!(sums.image().pixels == whole.pixels, "{name} {mode:?}");
        }
    }
}

/// docs/view.md's screenshot is what `scripts/view-screenshot.sh` makes, pixel for pixel
/// (its PNG's compression is the local zlib's).
#[test]
fn the_screenshot_of_the_docs_is_what_its_script_makes() {
    if !tools_present() {
        return;
    }
    let out = scratch("view_screenshot").join("view.png");
    let run = Command::new(project_file("scripts/view-screenshot.sh"))
        .env("P3TRACE", env!("CARGO_BIN_EXE_p3trace"))
        .env("OUT", &out)
        .output()
        .expect("the screenshot script runs");
    assert!(run.status.success(), "{}", stderr(&run));
    let made = image::open(&out).unwrap().to_rgb8();
    let committed = image::open(project_file("docs/view.png"))
        .unwrap()
        .to_rgb8();
    assert!(
        made == committed,
        "docs/view.png is not what scripts/view-screenshot.sh makes: run the script"
    );
}
