//! The documents as a newcomer meets them: every shell block of README.md and docs/*.md
//! runs as shown, every relative link leads to a file, the README starts with the two
//! commands it promises (the second the one `.ci/run` runs), and each document keeps to
//! its length.
//!
//! A block opened with ```` ```sh ```` runs unless the line before it is
//! `<!-- not run: REASON -->`. It runs under `bash -euo pipefail` in a scratch folder
//! holding a copy of `scenes/` and a link to `scripts/`, with the course material
//! as `../shared` (a block that names `../shared` skips when it is absent); `cargo run
//! --release --`, `target/release/p3trace`, `p3trace` and `$P3TRACE` (which the scripts
//! read) all run the binary under test, and any other `cargo` fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{self, project_file, scratch};

/// A fenced block of a document.
struct Block {
    /// The document's path from the project's folder, and the line of the opening fence.
    place: String,
    language: String,
    /// Why it is not run, from the `<!-- not run: ... -->` line before it.
    not_run: Option<String>,
    text: String,
}

fn blocks(path: &str) -> Vec<Block> {
    let markdown = std::fs::read_to_string(project_file(path)).expect("the document reads");
    let mut blocks = Vec::new();
    let mut lines = markdown.lines().enumerate();
    let mut previous = "";
    while let Some((number, line)) = lines.next() {
        if let Some(language) = line.trim_start().strip_prefix("```") {
            let not_run = previous
                .trim()
                .strip_prefix("<!-- not run:")
                .and_then(|rest| rest.strip_suffix("-->"))
                .map(|why| why.trim().to_string());
            let text: Vec<&str> = lines
                .by_ref()
                .map(|(_, line)| line)
                .take_while(|line| !line.trim_start().starts_with("```"))
                .collect();
            blocks.push(Block {
                place: format!("{path}:{}", number + 1),
                language: language.trim().to_string(),
                not_run,
                text: text.join("\n"),
            });
            previous = "";
        } else {
            previous = line;
        }
    }
    blocks
}

/// README.md and every page of docs/, in a fixed order.
fn documents() -> Vec<String> {
    let mut pages: Vec<String> = std::fs::read_dir(project_file("docs"))
        .expect("docs/ lists")
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".md"))
        .map(|name| format!("docs/{name}"))
        .collect();
    pages.sort();
    pages.insert(0, "README.md".to_string());
    pages
}

fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_folder(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// Where a document's blocks run: `ROOT/project` (their working folder), `ROOT/shared`
/// and `ROOT/bin`.
fn sandbox(root: &Path, shared: Option<&Path>) -> PathBuf {
    let project = root.join("project");
    copy_folder(&project_file("scenes"), &project.join("scenes"));
    std::os::unix::fs::symlink(project_file("scripts"), project.join("scripts")).unwrap();
    if let Some(shared) = shared {
        std::os::unix::fs::symlink(shared, root.join("shared")).unwrap();
    }
    std::fs::create_dir_all(root.join("bin")).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_p3trace"), root.join("bin/p3trace")).unwrap();
    // A block that would build or test (the README's `cargo test` among them) must be
    // marked not run: the test would run itself. This `cargo` stops it.
    let cargo = root.join("bin/cargo");
    std::fs::write(
        &cargo,
        "#!/bin/sh\necho \"a block that runs cargo must be marked not run: cargo $*\" >&2\nexit 97\n",
    )
    .unwrap();
    std::fs::set_permissions(&cargo, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    project
}

#[test]
fn every_shell_block_runs_as_shown() {
    let scratch = scratch("docs_blocks");
    let shared = common::shared();
    let mut failures = Vec::new();
    let mut ran = 0;
    for document in documents() {
        // A document's blocks run one after another in a folder of its own: a block may
        // read what an earlier one of its page wrote.
        let root = scratch.join(document.replace('/', "_"));
        let project = sandbox(&root, shared.as_deref());
        let path = format!(
            "{}:{}",
            root.join("bin").display(),
            std::env::var("PATH").unwrap_or_default()
        );
        for block in blocks(&document) {
            if block.language != "sh" {
                continue;
            }
            if let Some(why) = &block.not_run {
                assert!(!why.is_empty(), "{}: say why it is not run", block.place);
                continue;
            }
            if block.text.contains("../shared") && shared.is_none() {
                common::skip(format_args!("{} needs the course material", block.place));
                continue;
            }
            let script = block
                .text
                .replace("cargo run --release -- ", "p3trace ")
                .replace("target/release/p3trace", "p3trace");
            let run = Command::new("bash")
                .args(["-euo", "pipefail", "-c", &script])
                .current_dir(&project)
                .env("PATH", &path)
                .env("P3TRACE", env!("CARGO_BIN_EXE_p3trace"))
                .output()
                .expect("bash runs");
            ran += 1;
            if !run.status.success() {
                failures.push(format!(
                    "{} failed ({}):\n{}\n--- stdout\n{}--- stderr\n{}",
                    block.place,
                    run.status,
                    block.text,
                    common::stdout(&run),
                    common::stderr(&run)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    assert!(ran > 0, "no block ran");
}

/// The README's first block holds the two commands: a render of a scene in `scenes/`,
/// then the test command, which must be the one `.ci/run` runs.
#[test]
fn the_readme_starts_with_the_two_commands() {
    let first = blocks("README.md")
        .into_iter()
        .find(|block| block.language == "sh")
        .expect("the README has a shell block");
    let lines: Vec<&str> = first.text.lines().collect();
    let [render, test] = lines[..] else {
        panic!("{}: two commands, found {lines:?}", first.place);
    };
    let scene = render
        .strip_prefix("cargo run --release -- render ")
        .and_then(|rest| rest.split_whitespace().next())
        .unwrap_or_else(|| panic!("{}: the first command renders: {render}", first.place));
    assert!(
        scene.starts_with("scenes/") && project_file(scene).is_file(),
        "{}: the first command renders a scene of scenes/, not {scene}",
        first.place
    );
    let ci = std::fs::read_to_string(project_file(".ci/run")).unwrap();
    assert!(
        ci.lines().any(|line| line.trim() == test),
        "{}: .ci/run must run the README's test command '{test}'",
        first.place
    );
}

/// `path` with its `..` and `.` taken out, by its text alone (it need not exist).
fn lexical(path: &Path) -> PathBuf {
    let mut clean = PathBuf::new();
    for part in path.components() {
        match part {
            std::path::Component::ParentDir => {
                clean.pop();
            }
            std::path::Component::CurDir => {}
            other => clean.push(other),
        }
    }
    clean
}

/// Every relative link of the documents names a file or folder of the project.
#[test]
fn every_relative_link_leads_somewhere() {
    let mut broken = Vec::new();
    for document in documents() {
        let text = std::fs::read_to_string(project_file(&document)).unwrap();
        let folder = project_file(&document).parent().unwrap().to_path_buf();
        for (number, line) in text.lines().enumerate() {
            for target in line
                .split("](")
                .skip(1)
                .filter_map(|rest| rest.split(')').next())
            {
                let file = target.split('#').next().unwrap();
                if file.is_empty() || file.contains("://") || file.starts_with("mailto:") {
                    continue;
                }
                let path = lexical(&folder.join(file));
                // Links out of the project (to the course material beside it) are the
                // reader's to follow: CI's checkout has no `../shared`.
                let inside = path.starts_with(project_file(""));
                if inside && !path.exists() {
                    broken.push(format!("{document}:{}: {target}", number + 1));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// The guides stay guides: each document within the length it was written to.
#[test]
fn the_documents_keep_to_their_length() {
    for (document, most) in [
        ("README.md", 250),
        ("BENCHMARKS.md", 300),
        ("ARCHITECTURE.md", 150),
    ] {
        let lines = std::fs::read_to_string(project_file(document))
            .unwrap()
            .lines()
            .count();
        assert!(lines <= most, "{document}: {lines} lines, at most {most}");
    }
}
