//! A render farm on a real Slurm cluster: `scripts/slurm/local-cluster.sh` brings up
//! munged, slurmctld and slurmd from Debian's packages on this machine, and
//! `scripts/slurm/submit.sh` renders a course scene as a job array of 8 tiles and merges
//! them; the image must be the one-machine render byte for byte. Then an array is
//! cancelled mid-way, `submit.sh` is run again (it resubmits what `merge --missing` lists)
//! and the image is checked again. Every daemon is stopped by PID at the end, even when a
//! check fails.
//!
//! Skips, saying why, when not root or without apt-get (and no Slurm); under CI=true a
//! root run that cannot bring the cluster up fails instead.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use crate::common::{project_file, scratch};

const TILES: u32 = 8;
/// Not Slurm's default ports, so that a cluster someone runs by hand is left alone.
const PORT: &str = "6837";

fn succeeded(out: &Output, what: &str) -> String {
    assert!(
        out.status.success(),
        "{what}: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The cluster of this test; dropping it stops its daemons.
struct Cluster {
    dir: PathBuf,
}

impl Cluster {
    fn command(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut command = Command::new(program);
        command
            .env("P3TRACE_SLURM_DIR", &self.dir)
            .env("P3TRACE_SLURM_PORT", PORT)
            .env("SLURM_CONF", self.dir.join("etc/slurm.conf"))
            .env("P3TRACE", env!("CARGO_BIN_EXE_p3trace"));
        command
    }

    fn script(&self, action: &str) -> Output {
        self.command(project_file("scripts/slurm/local-cluster.sh"))
            .arg(action)
            .output()
            .expect("local-cluster.sh runs")
    }

    /// `submit.sh SCENE 8 OUT flags` with the environment `env`: the array's job (if any
    /// tile was missing) and the merge's.
    fn submit(
        &self,
        scene: &Path,
        out: &Path,
        flags: &[&str],
        env: &[(&str, &str)],
    ) -> (Option<String>, String) {
        let output = self
            .command(project_file("scripts/slurm/submit.sh"))
            .envs(env.iter().copied())
            .arg(scene)
            .arg(TILES.to_string())
            .arg(out)
            .args(flags)
            .output()
            .expect("submit.sh runs");
        let text = succeeded(&output, "submit.sh");
        let field = |key: &str| {
            text.lines()
                .find_map(|l| l.strip_prefix(key))
                .map(str::to_string)
        };
        (
            field("array="),
            field("merge=").expect("submit.sh prints merge="),
        )
    }

    /// The jobs (and array tasks) of `job` still queued or running.
    fn queued(&self, job: &str) -> usize {
        let out = self
            .command("squeue")
            .args(["-h", "-r", "-j", job])
            .output()
            .expect("squeue runs");
        // squeue exits 1 once it no longer knows the job.
        String::from_utf8_lossy(&out.stdout).lines().count()
    }

    /// Polls squeue (not `sbatch --wait`, which polls at 2, 10 and 42 s) until `jobs` are
    /// gone.
    fn wait(&self, jobs: &[&str]) {
        let what = format!("jobs {jobs:?} to leave the queue");
        poll(&what, 600, 200, || jobs.iter().all(|j| self.queued(j) == 0));
    }

    /// Every task of `job` as `scontrol` reports it: state and exit code.
    fn states(&self, job: &str) -> Vec<String> {
        let out = self
            .command("scontrol")
            .args(["show", "job", "-o", job])
            .output()
            .expect("scontrol runs");
        succeeded(&out, "scontrol show job")
            .lines()
            .map(|line| {
                line.split_whitespace()
                    .filter(|f| f.starts_with("JobState=") || f.starts_with("ExitCode="))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let out = self.script("stop");
        eprint!("{}", String::from_utf8_lossy(&out.stderr));
    }
}

/// Whether this machine can run the cluster: `Err` says why not.
/// Checks `done` every `every_ms` milliseconds until it holds; fails the test, naming
/// `what` it waited for, after `limit_s` seconds.
fn poll(what: &str, limit_s: u64, every_ms: u64, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < Duration::from_secs(limit_s),
            "waited {limit_s} s for {what}"
        );
        std::thread::sleep(Duration::from_millis(every_ms));
    }
}

fn can_run() -> Result<(), String> {
    let uid = Command::new("id")
        .arg("-u")
        .output()
        .map_err(|e| e.to_string())?;
    if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
        return Err("not root (munged, slurmd and the packages need it)".into());
    }
    let has = |program: &str| {
        Command::new("sh")
            .args(["-c", &format!("command -v {program}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if !has("apt-get") && !has("slurmctld") {
        let why = "no apt-get to install Slurm";
        if std::env::var("CI").as_deref() == Ok("true") {
            panic!("CI runs as root but cannot run the farm test: {why}");
        }
        return Err(why.into());
    }
    Ok(())
}

fn one_machine(scene: &Path, out: &Path, flags: &[&str]) -> Vec<u8> {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(flags);
    succeeded(&common::p3trace(&args), "one-machine render");
    std::fs::read(out).unwrap()
}

fn part_files(parts: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(parts)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".exr") || n.ends_with(".partial"))
        .collect();
    names.sort();
    names
}

#[test]
fn a_slurm_job_array_renders_the_one_machine_image_and_resumes_after_cancellation() {
    if let Err(why) = can_run() {
        common::skip(why);
        return;
    }
    let dir = scratch("farm");
    let cluster = Cluster {
        dir: dir.join("slurm"),
    };
    let started = cluster.script("start");
    succeeded(&started, "local-cluster.sh start");

    // A course scene when the course material is here, else the project's copy of it.
    let scene = common::shared()
        .map(|s| s.join("scenes/balls_medium.p3f"))
        .unwrap_or_else(|| project_file("scenes/balls_medium.p3f"));

    // 1. The whole array, then its merge; the partition's tiles by the binary that
    //    P3TRACE_PARTITIONS names for it, which notes each tile it renders.
    let flags = ["--resolution", "160x120", "--spp", "4", "--no-skybox"];
    let out = dir.join("frame.png");
    let (named, log) = (dir.join("named-p3trace.sh"), dir.join("named.log"));
    std::fs::write(
        &named,
        format!(
            "#!/bin/sh\necho \"$4\" >> '{}'\nexec '{}' \"$@\"\n",
            log.display(),
            env!("CARGO_BIN_EXE_p3trace")
        ),
    )
    .unwrap();
    std::fs::set_permissions(&named, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let partitions = format!(
        "other={} main={}",
        env!("CARGO_BIN_EXE_p3trace"),
        named.display()
    );
    let env = [("P3TRACE_PARTITIONS", partitions.as_str())];
    let (array, merge) = cluster.submit(&scene, &out, &flags, &env);
    let array = array.expect("the first submission renders every tile");
    cluster.wait(&[&array, &merge]);
    let tasks = cluster.states(&array);
    assert_eq!(tasks.len(), TILES as usize, "{tasks:?}");
    for state in tasks.iter().chain(&cluster.states(&merge)) {
        assert_eq!(state, "JobState=COMPLETED ExitCode=0:0");
    }
    let mut tiles: Vec<String> = std::fs::read_to_string(&log)
        .expect("the partition's binary ran")
        .lines()
        .map(str::to_string)
        .collect();
    tiles.sort();
    assert_eq!(
        tiles,
        (0..TILES)
            .map(|i| format!("{i}/{TILES}"))
            .collect::<Vec<_>>()
    );
    let whole = one_machine(&scene, &dir.join("one.png"), &flags);
    assert!(
        std::fs::read(&out).unwrap() == whole,
        "the farm's PNG differs"
    );

    // 2. An array cancelled once its first tile is written: tasks long enough (a second
    //    or more each, two at a time) that most are still to run.
    let flags = ["--resolution", "320x240", "--spp", "256", "--no-skybox"];
    let out = dir.join("resumed.exr");
    let parts = PathBuf::from(format!("{}.parts", out.display()));
    let (array, merge) = cluster.submit(&scene, &out, &flags, &[]);
    let array = array.unwrap();
    poll("a part to be written", 300, 50, || {
        part_files(&parts).iter().any(|n| n.ends_with(".exr"))
    });
    // Tasks are running as it is cancelled: scancel's SIGTERM reaches p3trace mid-render.
    // Between one task's end and the next one's start none is, so wait for one.
    let running_tasks = || {
        let out = cluster
            .command("squeue")
            .args(["-h", "-r", "-t", "RUNNING", "-j", &array])
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout).lines().count()
    };
    let mut running = 0;
    poll("a task of the array to run", 60, 50, || {
        running = running_tasks();
        running > 0
    });
    let cancel = cluster.command("scancel").arg(&array).output().unwrap();
    succeeded(&cancel, "scancel");
    // The merge depends on the array: it is cancelled with it.
    cluster.wait(&[&array, &merge]);
    assert!(!out.exists(), "a merge ran after the cancellation");
    let left = part_files(&parts);
    assert!(
        left.iter().all(|n| n.ends_with(".exr")),
        "a cancelled task left a partial file: {left:?}"
    );
    let mut args: Vec<String> = ["merge", "--missing", "--tiles", "8"]
        .map(String::from)
        .to_vec();
    args.extend(left.iter().map(|n| parts.join(n).display().to_string()));
    let listed = common::p3trace(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let missing = succeeded(&listed, "merge --missing");
    let missing: Vec<&str> = missing.lines().collect();
    assert!(
        !missing.is_empty() && missing.len() + left.len() == TILES as usize,
        "missing {missing:?} beside parts {left:?}"
    );
    eprintln!(
        "farm: cancelled with {} parts written and {running} tasks running; resubmitting {}",
        left.len(),
        missing.join(" ")
    );

    // 3. Again: only the missing tiles are submitted, and the frame is complete.
    let (array, merge) = cluster.submit(&scene, &out, &flags, &[]);
    let array = array.expect("tiles were missing");
    cluster.wait(&[&array, &merge]);
    let tasks = cluster.states(&array);
    assert_eq!(tasks.len(), missing.len(), "resubmitted {tasks:?}");
    for state in tasks.iter().chain(&cluster.states(&merge)) {
        assert_eq!(state, "JobState=COMPLETED ExitCode=0:0");
    }
    let whole = one_machine(&scene, &dir.join("one.exr"), &flags);
    assert!(
        std::fs::read(&out).unwrap() == whole,
        "the resumed EXR differs"
    );
    drop(cluster);
}
