//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output};

use p3trace::accel::stream::Query;
use p3trace::accel::AccelKind;
use p3trace::imaging::Film;
use p3trace::ray::Ray;
use p3trace::render::{render, RenderOptions};
use p3trace::scene::Scene;

/// Says that the running test skips (all of it, or the part that needs what is missing)
/// and why, as `skipped: TEST: WHY`. Written to the process's stderr itself, not through
/// `eprintln!`, which the test harness captures and shows only for failing tests: so a
/// skip shows in `cargo test`'s output beside the tests' `ok`.
pub fn skip(why: impl std::fmt::Display) {
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("a test");
    let _ = writeln!(std::io::stderr().lock(), "skipped: {test}: {why}");
}

/// The course material beside the project (`../shared`), or `P3TRACE_SHARED` when set.
/// When it is absent, says that the test skips ([`skip`]) and returns `None`.
pub fn shared() -> Option<PathBuf> {
    let dir = std::env::var_os("P3TRACE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    if dir.join("scenes").is_dir() {
        Some(dir)
    } else {
        skip(format_args!(
            "the course material is not at {} (set P3TRACE_SHARED)",
            dir.display()
        ));
        None
    }
}

pub fn project_file(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Runs the `p3trace` binary with `args`.
pub fn p3trace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_p3trace"))
        .args(args)
        .output()
        .expect("the p3trace binary runs")
}

/// Runs the `p3trace` binary with `args`, which must succeed.
pub fn succeeds(args: &[&str]) -> Output {
    let out = p3trace(args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    out
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A fresh scratch folder under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Renders `scene` without its skybox, with the settings of its file changed by
/// `configure`. The course files say `accel 0`; every structure gives the same image
/// (tests/accel.rs), and the BVH gives it in a fraction of the time.
pub fn render_scene(scene: &Scene, configure: impl FnOnce(&mut RenderOptions)) -> Film {
    let mut options = RenderOptions::from_scene(scene);
    options.skybox = false;
    options.accel.kind = AccelKind::Bvh;
    configure(&mut options);
    render(scene, &options).expect("the render runs").film
}

/// A query of a stream: a ray and its `t_max`.
#[derive(Clone, Copy)]
pub struct Bounded(pub Ray, pub f32);

impl Query for Bounded {
    fn ray(&self) -> &Ray {
        &self.0
    }

    fn t_max(&self) -> f32 {
        self.1
    }
}
