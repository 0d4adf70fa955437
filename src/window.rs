//! `p3trace view`: a scene in a window (minifb), rendered again as the mouse moves the
//! camera ([`p3trace::view`]) and read again when its files change (notify).
//!
//! Two threads: the window's (this one: input, title, picture, and the scene read again)
//! and a renderer, which takes the newest [`Job`] and sends its frame back. A job that
//! the mouse makes stale is stopped between tiles (`RenderOptions::stop`), so that a drag
//! never waits for a full pass. While the camera moves, frames are small (the preview's
//! factor adapts so that one takes about [`PREVIEW_TIME`]) and scaled up; once it stops,
//! full passes add one sample of each pixel's grid each until the image is `render`'s;
//! then the window only waits for input.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use minifb::{InputCallback, Key, MouseButton, MouseMode, Window, WindowOptions};
use notify::{RecommendedWatcher, RecursiveMode, Watcher};

use crate::cli::ViewArgs;
use crate::Failure;
use p3trace::accel::count::CostRays;
use p3trace::accel::AccelKind;
use p3trace::imaging::false_colour::{self, Scale};
use p3trace::imaging::{to_byte, Film};
use p3trace::render::cost::CostMap;
use p3trace::render::{RenderOptions, RenderReport, Sampling, Stage};
use p3trace::scene::{CameraSpec, Scene};
use p3trace::view::{camera_block, Accumulator, Orbit};

/// How long a frame may take while the camera moves: the mouse's next frame is on screen
/// within about twice this (the frame under way, then the new one).
const PREVIEW_TIME: Duration = Duration::from_millis(20);

/// The camera counts as moving for this long after the mouse last moved it.
const SETTLE: Duration = Duration::from_millis(120);

/// How long after a change on disk the scene is read, so that an editor's several writes
/// make one reload.
const RELOAD_DELAY: Duration = Duration::from_millis(80);

/// How often the window looks at its input when no frame wakes it: a mouse event waits
/// at most this long before the view changes.
const POLL: Duration = Duration::from_millis(10);

/// Opens the window and runs until Esc, q or the window is closed.
pub fn run(args: &ViewArgs) -> Result<ExitCode, Failure> {
    let has = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    if !has("DISPLAY") && !has("WAYLAND_DISPLAY") {
        return Err(Failure::Run(
            "view needs a display: neither DISPLAY (X11) nor WAYLAND_DISPLAY (Wayland) is \
             set (over SSH, connect with ssh -X); `p3trace render` writes the image to a file"
                .into(),
        ));
    }
    let scene = read(args)?;
    let base = crate::commands::settings_options(&args.settings, &scene)?;
    base.check_size().map_err(Failure::Usage)?;
    let (width, height) = (base.width as usize, base.height as usize);
    let mut window = Window::new(&title_name(&scene), width, height, WindowOptions::default())
        .map_err(|e| {
            Failure::Run(format!(
                "cannot open a window ({e}); `p3trace render` writes the image to a file"
            ))
        })?;
    // The loop waits for frames and input itself (`POLL`).
    window.set_target_fps(0);
    let jobs = Arc::new(Slot::default());
    let (done_tx, done_rx) = mpsc::channel();
    let renderer = {
        let jobs = Arc::clone(&jobs);
        std::thread::spawn(move || serve(&jobs, &done_tx))
    };
    let (watch_tx, watch_rx) = mpsc::channel();
    let watcher = watch(args, &scene, watch_tx);
    let mut viewer = Viewer::new(args, scene, base);
    let result = viewer.run(&mut window, &jobs, &done_rx, &watch_rx, watcher);
    jobs.quit();
    // The renderer stops between tiles; its frame is not waited for beyond that.
    let _ = renderer.join();
    result
}

/// The scene as `render` reads it with the same flags.
fn read(args: &ViewArgs) -> Result<Scene, Failure> {
    crate::commands::settings_scene(&args.scene, &args.settings)
}

fn title_name(scene: &Scene) -> String {
    Path::new(&scene.name)
        .file_name()
        .map_or(scene.name.clone(), |n| n.to_string_lossy().into_owned())
}

/// What the renderer is asked to make.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pass {
    /// The image at 1 / factor of the window's size, one sample at each pixel's centre.
    Preview(u32),
    /// Sample `k` of every pixel of the full image.
    Sample(u32),
    /// The cost image of the full frame, every sample counted.
    Cost,
}

struct Job {
    scene: Arc<Scene>,
    /// Which reading of the scene file `scene` is: a new one builds a new stage.
    version: u64,
    camera: CameraSpec,
    options: RenderOptions,
    pass: Pass,
    /// The view the job shows: the window drops frames of views it has left.
    view: u64,
}

struct Done {
    pass: Pass,
    view: u64,
    accel: AccelKind,
    report: Result<RenderReport, String>,
    took: Duration,
}

/// The newest job, which the renderer takes; a newer one replaces a job not yet begun.
#[derive(Default)]
struct Slot {
    state: Mutex<(Option<Job>, bool)>,
    ready: Condvar,
}

impl Slot {
    fn put(&self, job: Job) {
        self.state.lock().unwrap().0 = Some(job);
        self.ready.notify_one();
    }

    /// The next job, waiting for one; `None` once the window has closed.
    fn take(&self) -> Option<Job> {
        let mut state = self.state.lock().unwrap();
        loop {
            if state.1 {
                return None;
            }
            if let Some(job) = state.0.take() {
                return Some(job);
            }
            state = self.ready.wait(state).unwrap();
        }
    }

    fn quit(&self) {
        self.state.lock().unwrap().1 = true;
        self.ready.notify_one();
    }
}

/// The keys pressed, in order, as the window's events bring them: a tap shorter than a
/// frame, which polling the keys' state would miss, is kept.
#[derive(Clone, Default)]
struct KeyPresses(Rc<RefCell<Vec<Key>>>);

impl InputCallback for KeyPresses {
    fn add_char(&mut self, _: u32) {}

    fn set_key_state(&mut self, key: Key, down: bool) {
        if down {
            self.0.borrow_mut().push(key);
        }
    }
}

/// Whether two jobs' options build the same structure ([`Stage::new`]).
fn same_stage(a: &RenderOptions, b: &RenderOptions) -> bool {
    a.accel == b.accel
        && a.mode == b.mode
        && a.skybox == b.skybox
        && a.shutter == b.shutter
        && a.shade.profile == b.shade.profile
}

/// The renderer's thread: each job in turn, a stage kept while jobs can share it.
fn serve(jobs: &Slot, done: &Sender<Done>) {
    let Some(mut job) = jobs.take() else {
        return;
    };
    let mut warned = None;
    loop {
        let scene = Arc::clone(&job.scene);
        let (version, options) = (job.version, job.options.clone());
        let stage = Stage::new(&scene, &options);
        if warned != Some(version) {
            for w in &stage.warnings {
                eprintln!("p3trace: warning: {w}");
            }
            warned = Some(version);
        }
        loop {
            let start = Instant::now();
            let report = stage.render(&job.camera, &job.options);
            let answer = Done {
                pass: job.pass,
                view: job.view,
                accel: job.options.accel.kind,
                report,
                took: start.elapsed(),
            };
            if done.send(answer).is_err() {
                return;
            }
            job = match jobs.take() {
                Some(job) => job,
                None => return,
            };
            if job.version != version || !same_stage(&job.options, &options) {
                break;
            }
        }
    }
}

/// Watches the scene file's folder and the skybox's, sending the paths that change; none
/// for the built-in `random` scene, or where the system refuses a watch (said once).
fn watch(args: &ViewArgs, scene: &Scene, changes: Sender<PathBuf>) -> Option<RecommendedWatcher> {
    if args.scene == Path::new(crate::commands::RANDOM_SCENE) {
        return None;
    }
    let handler = move |event: notify::Result<notify::Event>| {
        // Reading the files (the reload's own reads among them) is no change.
        match event {
            Ok(event) if !event.kind.is_access() => {
                for path in event.paths {
                    let _ = changes.send(path);
                }
            }
            _ => {}
        }
    };
    let mut watcher = match notify::recommended_watcher(handler) {
        Ok(watcher) => watcher,
        Err(e) => {
            eprintln!(
                "p3trace: warning: cannot watch the scene's files ({e}); edits are not shown"
            );
            return None;
        }
    };
    let folder = folder_of(&args.scene);
    let mut folders = vec![folder];
    folders.extend(skybox_folder(scene));
    for folder in folders {
        if let Err(e) = watcher.watch(&folder, RecursiveMode::NonRecursive) {
            eprintln!(
                "p3trace: warning: cannot watch '{}' ({e}); its edits are not shown",
                folder.display()
            );
        }
    }
    Some(watcher)
}

/// The folder the scene's skybox is read from, if it names one that is found.
fn skybox_folder(scene: &Scene) -> Option<PathBuf> {
    scene.skybox.as_ref().and_then(|folder| folder.find().ok())
}

/// The folder a file lies in: `.` for a bare name.
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The structures the keys choose, with their names.
const STRUCTURES: [(Key, AccelKind, &str); 3] = [
    (Key::B, AccelKind::Bvh, "BVH"),
    (Key::G, AccelKind::Grid, "grid"),
    (Key::N, AccelKind::None, "brute force"),
];

fn structure_name(kind: AccelKind) -> &'static str {
    STRUCTURES.iter().find(|s| s.1 == kind).map_or("?", |s| s.2)
}

/// The window's state.
struct Viewer<'a> {
    args: &'a ViewArgs,
    scene: Arc<Scene>,
    version: u64,
    /// The options of the flags and the file, before the keys change them.
    base: RenderOptions,
    orbit: Orbit,
    accel: AccelKind,
    effects: bool,
    cost: bool,
    /// What is shown: a new view whenever the camera, the scene or a key changes it.
    view: u64,
    /// The job under way: its view, pass and stop flag.
    running: Option<(u64, Pass, Arc<AtomicBool>)>,
    /// The current view's passes so far, and whether its preview is shown.
    sums: Accumulator,
    previewed: bool,
    cost_shown: bool,
    preview_factor: u32,
    last_move: Instant,
    /// Where a drag was at the last frame, and which button holds it.
    drag: Option<(f32, f32, MouseButton)>,
    /// Each structure's time for a full pass, the title's comparison.
    pass_times: BTreeMap<&'static str, Duration>,
    /// When the current view's first full pass began, for the converged line.
    converging_since: Option<Instant>,
    /// The last frame's rate and rays per second, for the title.
    rate: (f64, f64),
    /// While the camera moves: when the first input not yet on screen came, and how long
    /// each input waited for its picture; the previews' rate. For the log line.
    unseen_input: Option<(Instant, u64)>,
    input_to_screen: Vec<Duration>,
    moving_fps: Vec<f64>,
    error: Option<String>,
    reload_at: Option<Instant>,
    /// The picture to draw next, and the window's pixels.
    due: Option<Film>,
    pixels: Vec<u32>,
    /// The image of the current view as shown, for `s`.
    shown: Option<Film>,
}

impl<'a> Viewer<'a> {
    fn new(args: &'a ViewArgs, scene: Scene, base: RenderOptions) -> Self {
        let orbit = Orbit::new(&scene.camera);
        let (width, height) = (base.width, base.height);
        Viewer {
            args,
            scene: Arc::new(scene),
            version: 0,
            accel: base.accel.kind,
            base,
            orbit,
            effects: true,
            cost: false,
            view: 0,
            running: None,
            sums: Accumulator::new(width, height),
            previewed: false,
            cost_shown: false,
            preview_factor: 4,
            last_move: Instant::now() - SETTLE,
            drag: None,
            pass_times: BTreeMap::new(),
            converging_since: None,
            rate: (0.0, 0.0),
            unseen_input: None,
            input_to_screen: Vec::new(),
            moving_fps: Vec::new(),
            error: None,
            reload_at: None,
            due: None,
            pixels: vec![0; (width * height) as usize],
            shown: None,
        }
    }

    fn run(
        &mut self,
        window: &mut Window,
        jobs: &Slot,
        done: &Receiver<Done>,
        changes: &Receiver<PathBuf>,
        _watcher: Option<RecommendedWatcher>,
    ) -> Result<ExitCode, Failure> {
        let mut title = String::new();
        let pressed = KeyPresses::default();
        window.set_input_callback(Box::new(pressed.clone()));
        while window.is_open() {
            if self.keys(&pressed) {
                break;
            }
            self.mouse(window);
            self.notice_changes(changes);
            self.reload_when_due();
            // A frame wakes the window at once; input is looked at every poll. The next
            // job goes before the picture is drawn, so the renderer never waits for it.
            let mut wait = POLL;
            while let Ok(frame) = done.recv_timeout(wait) {
                self.take(frame);
                wait = Duration::ZERO;
            }
            self.schedule(jobs);
            let (w, h) = (self.base.width as usize, self.base.height as usize);
            let shown = if let Some(film) = self.due.take() {
                self.show(&film);
                window.update_with_buffer(&self.pixels, w, h)
            } else {
                window.update();
                Ok(())
            };
            shown.map_err(|e| Failure::Run(format!("cannot draw the window: {e}")))?;
            // After the picture: the X server takes requests in order, so a title that
            // says a pass is in means its picture is on screen.
            let wanted = self.title();
            if wanted != title {
                window.set_title(&wanted);
                title = wanted;
            }
        }
        // A pass of brute force can take long: the renderer stops at its next tile.
        if let Some((_, _, stop)) = &self.running {
            stop.store(true, Ordering::Relaxed);
        }
        Ok(ExitCode::SUCCESS)
    }

    /// The keys pressed since the last frame; true to quit.
    fn keys(&mut self, pressed: &KeyPresses) -> bool {
        let keys: Vec<Key> = pressed.0.borrow_mut().drain(..).collect();
        for key in keys {
            match key {
                Key::Escape | Key::Q => return true,
                Key::R => {
                    self.orbit.reset();
                    self.new_view();
                }
                Key::C => {
                    // The file's lens, whether or not `e` turned the effects off.
                    print!("{}", camera_block(&self.orbit.camera(), self.scene.origin));
                    let _ = std::io::stdout().flush();
                }
                Key::S => self.save(),
                Key::E => {
                    self.effects = !self.effects;
                    self.new_view();
                }
                Key::K => {
                    self.cost = !self.cost;
                    self.new_view();
                }
                _ => {
                    if let Some(&(_, kind, _)) = STRUCTURES.iter().find(|s| s.0 == key) {
                        if kind != self.accel {
                            self.accel = kind;
                            self.new_view();
                        }
                    }
                }
            }
        }
        false
    }

    /// Left drag orbits, right drag and the wheel move the eye along the view.
    fn mouse(&mut self, window: &Window) {
        let held = [MouseButton::Left, MouseButton::Right]
            .into_iter()
            .find(|&b| window.get_mouse_down(b));
        let at = window.get_mouse_pos(MouseMode::Pass);
        match (held, at, self.drag) {
            (Some(button), Some((x, y)), Some((x0, y0, was))) if button == was => {
                let (dx, dy) = (x - x0, y - y0);
                if dx != 0.0 || dy != 0.0 {
                    match button {
                        MouseButton::Left => self.orbit.turn(dx, dy),
                        // Down moves away, as the course program's right drag does.
                        _ => self.orbit.dolly(-dy / 20.0),
                    }
                    self.moved();
                }
                self.drag = Some((x, y, button));
            }
            (Some(button), Some((x, y)), _) => self.drag = Some((x, y, button)),
            _ => self.drag = None,
        }
        if let Some((_, wheel)) = window.get_scroll_wheel() {
            if wheel != 0.0 {
                self.orbit.dolly(wheel.signum());
                self.moved();
            }
        }
    }

    fn moved(&mut self) {
        self.last_move = Instant::now();
        self.new_view();
        self.unseen_input.get_or_insert((self.last_move, self.view));
    }

    /// Leaves the view shown: the job under way stops, and the passes start again.
    fn new_view(&mut self) {
        self.view += 1;
        // A preview under way goes on: stopped at every move of a drag, none would be
        // seen; it is shown, and then the newest view's.
        if let Some((_, pass, stop)) = &self.running {
            if !matches!(pass, Pass::Preview(_)) {
                stop.store(true, Ordering::Relaxed);
            }
        }
        self.sums = Accumulator::new(self.base.width, self.base.height);
        self.previewed = false;
        self.cost_shown = false;
        self.converging_since = None;
    }

    fn moving(&self) -> bool {
        self.last_move.elapsed() < SETTLE
    }

    fn camera(&self) -> CameraSpec {
        let mut camera = self.orbit.camera();
        if !self.effects {
            camera.aperture = 0.0;
        }
        camera
    }

    /// The options of a pass of the current view.
    fn options(&self, pass: Pass) -> RenderOptions {
        let mut options = self.base.clone();
        options.accel.kind = self.accel;
        if !self.effects {
            options.shade.soft_light_size = None;
            options.shade.roughness = 0.0;
            options.shutter = [options.shutter[0]; 2];
        }
        match pass {
            Pass::Preview(factor) => {
                options.width = options.width.div_ceil(factor);
                options.height = options.height.div_ceil(factor);
                options.sampling = Sampling::Centre;
                options.count = self.cost;
            }
            Pass::Sample(k) => options.samples = Some(k..k + 1),
            Pass::Cost => options.count = true,
        }
        options
    }

    /// Sends the view's next job, if it needs one and none is under way.
    fn schedule(&mut self, jobs: &Slot) {
        if self.running.is_some() {
            return;
        }
        let passes = self.base.sampling.samples_per_pixel();
        let pass = if self.moving() || (!self.previewed && self.sums.passes() == 0) {
            if self.previewed {
                return;
            }
            Pass::Preview(self.preview_factor)
        } else if self.cost {
            if self.cost_shown {
                return;
            }
            Pass::Cost
        } else if self.sums.passes() < passes {
            Pass::Sample(self.sums.passes())
        } else {
            return;
        };
        if matches!(pass, Pass::Sample(0) | Pass::Cost) {
            self.converging_since = Some(Instant::now());
        }
        let stop = Arc::new(AtomicBool::new(false));
        let mut options = self.options(pass);
        options.stop = Some(Arc::clone(&stop));
        self.running = Some((self.view, pass, stop));
        jobs.put(Job {
            scene: Arc::clone(&self.scene),
            version: self.version,
            camera: self.camera(),
            options,
            pass,
            view: self.view,
        });
    }

    /// Takes a finished job, and the picture it makes, if any, is due.
    fn take(&mut self, frame: Done) {
        self.running = None;
        let report = match frame.report {
            Ok(report) => report,
            Err(e) if e == p3trace::render::STOPPED => return,
            Err(e) => {
                self.error = Some(e);
                return;
            }
        };
        let rays = report.rays.total() as f64;
        let seconds = frame.took.as_secs_f64().max(1e-6);
        self.rate = (1.0 / seconds, rays / seconds / 1e6);
        if let Pass::Sample(_) = frame.pass {
            self.pass_times
                .insert(structure_name(frame.accel), frame.took);
        }
        let current = frame.view == self.view;
        if !current && !matches!(frame.pass, Pass::Preview(_)) {
            return;
        }
        match frame.pass {
            Pass::Preview(factor) => {
                self.previewed = current;
                self.moving_fps.push(self.rate.0);
                if let Some((input, view)) = self.unseen_input {
                    if view <= frame.view {
                        self.input_to_screen.push(input.elapsed());
                        self.unseen_input = None;
                    }
                }
                // The next preview's factor, from this one's time: its cost goes with the
                // square of the image's side.
                let ratio = (frame.took.as_secs_f64() / PREVIEW_TIME.as_secs_f64()).sqrt();
                let ideal = factor as f64 * ratio;
                // Up at once past the time, down only well below it, so that it settles.
                if ideal > factor as f64 || ratio < 0.7 {
                    self.preview_factor = (ideal.ceil() as u32).clamp(1, 16);
                }
                self.due = Some(self.picture(&report, frame.accel));
            }
            Pass::Sample(_) => {
                self.sums.add(&report.film);
                self.due = Some(self.sums.image());
                if self.sums.passes() == self.base.sampling.samples_per_pixel() {
                    self.converged();
                }
            }
            Pass::Cost => {
                self.cost_shown = true;
                self.due = Some(self.picture(&report, frame.accel));
                self.converged();
            }
        }
    }

    /// The film a report shows: its colours, or its cost picture where it counted.
    fn picture(&self, report: &RenderReport, accel: AccelKind) -> Film {
        let Some(work) = &report.work else {
            return report.film.clone();
        };
        let map = CostMap {
            counter: accel.step(),
            rays: CostRays::All,
        };
        let (w, h) = (report.film.width, report.film.height);
        let counts = map.film(work, w, h);
        let scale = Scale {
            max: None,
            log: false,
        };
        let picture = false_colour::picture(&counts, map.counter.name(), scale);
        // The picture's colour bar stays out of the window: the counter is in the title.
        let mut film = Film::new(w, h);
        for row in 0..h {
            for x in 0..w {
                film.pixels[(row * w + x) as usize] = picture.get(x, row);
            }
        }
        film
    }

    /// Says on stderr how the view went: the previews while the camera moved, from an
    /// input to its picture, and the time to converge.
    fn converged(&mut self) {
        let Some(since) = self.converging_since.take() else {
            return;
        };
        let mut line = String::from("p3trace: view: ");
        if !self.moving_fps.is_empty() {
            let waits = &mut self.input_to_screen;
            waits.sort();
            let ms = |d: Duration| d.as_secs_f64() * 1e3;
            let fps =
                self.moving_fps.len() as f64 / self.moving_fps.iter().map(|f| 1.0 / f).sum::<f64>();
            line += &format!(
                "moving: {} frames at {fps:.0} FPS, input to screen {:.0} ms median, {:.0} ms at most; ",
                self.moving_fps.len(),
                waits.get(waits.len() / 2).map_or(0.0, |&d| ms(d)),
                waits.last().map_or(0.0, |&d| ms(d)),
            );
            self.moving_fps.clear();
            waits.clear();
        }
        let what = match self.cost {
            true => "the cost image".to_string(),
            false => format!("{} spp", self.base.sampling.samples_per_pixel()),
        };
        eprintln!(
            "{line}converged in {:.2} s ({what} at {}x{})",
            since.elapsed().as_secs_f64(),
            self.base.width,
            self.base.height
        );
    }

    /// Draws `film` scaled to the window, and keeps it for `s` when it is full size.
    fn show(&mut self, film: &Film) {
        let (w, h) = (self.base.width, self.base.height);
        for y in 0..h {
            let row = y * film.height / h;
            for x in 0..w {
                let c = film.get(x * film.width / w, row).to_array().map(to_byte);
                self.pixels[(y * w + x) as usize] =
                    (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32;
            }
        }
        self.shown = (film.width == w && film.height == h).then(|| film.clone());
    }

    /// Writes the image shown as SCENE.png, or SCENE-1.png and on where that exists.
    fn save(&self) {
        let Some(film) = &self.shown else {
            eprintln!("p3trace: view: nothing to save yet (the camera is moving)");
            return;
        };
        let stem = self
            .args
            .scene
            .file_stem()
            .map_or("view".into(), |s| s.to_string_lossy().into_owned());
        let path = (0u64..)
            .map(|n| match n {
                0 => PathBuf::from(format!("{stem}.png")),
                n => PathBuf::from(format!("{stem}-{n}.png")),
            })
            .find(|p| !p.exists())
            .expect("some name is free");
        match film.write(&path) {
            Ok(()) => eprintln!("p3trace: view: saved {}", path.display()),
            Err(e) => eprintln!("p3trace: error: {e}"),
        }
    }

    /// Notes the changes on disk that concern the scene: its file, or its skybox's.
    fn notice_changes(&mut self, changes: &Receiver<PathBuf>) {
        let paths: Vec<PathBuf> = changes.try_iter().collect();
        if paths.is_empty() {
            return;
        }
        let skybox = skybox_folder(&self.scene).and_then(|dir| dir.canonicalize().ok());
        let in_skybox = |path: &Path| {
            let folder = path.parent().and_then(|dir| dir.canonicalize().ok());
            skybox.is_some() && folder == skybox
        };
        let file = self.args.scene.file_name();
        if paths.iter().any(|p| p.file_name() == file || in_skybox(p)) {
            self.reload_at = Some(Instant::now() + RELOAD_DELAY);
        }
    }

    /// Reads the scene again once its files have been still for [`RELOAD_DELAY`], with its
    /// settings (the window keeps its size): the camera moved by the mouse stays unless
    /// the file's camera changed; a scene that no longer reads leaves the image as it
    /// was, its error in the title and on stderr.
    fn reload_when_due(&mut self) {
        if self.reload_at.is_none_or(|at| Instant::now() < at) {
            return;
        }
        self.reload_at = None;
        let reread = read(self.args).and_then(|scene| {
            let base = crate::commands::settings_options(&self.args.settings, &scene)?;
            Ok((scene, base))
        });
        match reread {
            Ok((scene, base)) => {
                if scene.camera != self.scene.camera {
                    self.orbit = Orbit::new(&scene.camera);
                }
                // The file's settings anew (its samples, say), in the window's size.
                self.base = RenderOptions {
                    width: self.base.width,
                    height: self.base.height,
                    ..base
                };
                self.scene = Arc::new(scene);
                self.version += 1;
                self.error = None;
                self.new_view();
            }
            Err(Failure::Usage(message) | Failure::Run(message)) => {
                eprintln!("p3trace: error: {message}");
                self.error = Some(message);
            }
        }
    }

    fn title(&self) -> String {
        let mut title = format!(
            "{} | {:.1} FPS | {:.1} Mrays/s | ",
            title_name(&self.scene),
            self.rate.0,
            self.rate.1
        );
        if self.cost {
            title += &format!("cost: {} ", self.accel.step().name());
        } else {
            title += &format!(
                "{}/{} spp ",
                self.sums.passes(),
                self.base.sampling.samples_per_pixel()
            );
        }
        title += &format!("| {}", structure_name(self.accel));
        if !self.pass_times.is_empty() {
            let times: Vec<String> = self
                .pass_times
                .iter()
                .map(|(name, t)| format!("{name} {:.0} ms", t.as_secs_f64() * 1e3))
                .collect();
            title += &format!(" ({} a pass)", times.join(", "));
        }
        if !self.effects {
            title += " | effects off";
        }
        if let Some(e) = &self.error {
            title += &format!(" | error: {e}");
        }
        title
    }
}
