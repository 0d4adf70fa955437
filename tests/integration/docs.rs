//! The documents as a newcomer meets them: every shell block of README.md and docs/*.md
//! runs as shown and prints what the document shows, every relative link leads to a
//! file, the README starts with the two commands it promises (the second the one
//! `.ci/run` runs), and each document keeps to its length.
//!
//! A block opened with ```` ```sh ```` runs unless the line before it is
//! `<!-- not run: REASON -->`. It runs under `bash -euo pipefail` in a scratch folder
//! holding a copy of `scenes/` and a link to `scripts/`, with the course material
//! as `../shared` (a block that names `../shared` skips when it is absent); `cargo run
//! --release --`, `target/release/p3trace`, `p3trace` and `$P3TRACE` (which the scripts
//! read) all run the binary under test, and any other `cargo` fails.
//!
//! A ```` ```text ```` block right after a run block (blank lines between) is what it
//! prints, stdout and stderr together ([`Shown::matches`]): line by line, runs of spaces
//! as one; a line `...` stands for any lines left out, and `...` within a line for text
//! that depends on the machine (`# cpu ...`). What changes between runs or builds is
//! masked on both sides ([`mask`]): a number before `s`, `ms` or `Mrays/s`, or after
//! `build_s`; the commit; the packet width (`packets: 16 rays`, `p3trace-packet16`); a
//! protocol line's last column, its rate. Every other figure is compared: counts, sizes
//! in MiB (the same at both packet widths), checksums, image differences.

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
    /// What it prints, for a shell block: the text block right after it.
    shown: Option<Shown>,
}

fn blocks(path: &str) -> Vec<Block> {
    let markdown = std::fs::read_to_string(project_file(path)).expect("the document reads");
    let mut blocks: Vec<Block> = Vec::new();
    let mut lines = markdown.lines().enumerate();
    let mut previous = "";
    // Whether only blank lines stand between the last block and here.
    let mut right_after_a_block = false;
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
            let block = Block {
                place: format!("{path}:{}", number + 1),
                language: language.trim().to_string(),
                not_run,
                text: text.join("\n"),
                shown: None,
            };
            match blocks.last_mut() {
                Some(shell)
                    if right_after_a_block
                        && shell.language == "sh"
                        && block.language == "text" =>
                {
                    shell.shown = Some(Shown {
                        place: block.place,
                        lines: text.iter().map(|line| line.to_string()).collect(),
                    });
                }
                _ => blocks.push(block),
            }
            previous = "";
            right_after_a_block = true;
        } else {
            previous = line;
            right_after_a_block &= line.trim().is_empty();
        }
    }
    blocks
}

/// The output a document shows under a command.
struct Shown {
    /// Where the text block opens.
    place: String,
    lines: Vec<String>,
}

/// The line `...` of a shown output, or a piece of a line, that stands for what is left out.
const LEFT_OUT: &str = "...";

impl Shown {
    /// Whether `printed` is what the document shows: each shown line matches a printed
    /// line ([`line_matches`]), in order, and a line [`LEFT_OUT`] any lines, none
    /// included; both sides masked ([`mask`]).
    fn matches(&self, printed: &str) -> bool {
        let shown: Vec<String> = self.lines.iter().map(|l| mask(l)).collect();
        let printed: Vec<String> = printed.lines().map(mask).collect();
        // can[i][j]: the first i shown lines match the first j printed ones.
        let mut can = vec![vec![false; printed.len() + 1]; shown.len() + 1];
        can[0][0] = true;
        for (i, line) in shown.iter().enumerate() {
            for j in 0..=printed.len() {
                can[i + 1][j] = if line == LEFT_OUT {
                    can[i][j] || (j > 0 && can[i + 1][j - 1])
                } else {
                    j > 0 && can[i][j - 1] && line_matches(line, &printed[j - 1])
                };
            }
        }
        can[shown.len()][printed.len()]
    }
}

/// Whether the `printed` line is the `shown` one, a [`LEFT_OUT`] in it standing for any
/// text.
fn line_matches(shown: &str, printed: &str) -> bool {
    let mut pieces = shown.split(LEFT_OUT);
    let first = pieces.next().unwrap_or_default();
    let Some(mut rest) = printed.strip_prefix(first) else {
        return false;
    };
    let mut pieces: Vec<&str> = pieces.collect();
    let Some(last) = pieces.pop() else {
        return rest.is_empty();
    };
    for piece in pieces {
        match rest.find(piece) {
            Some(at) => rest = &rest[at + piece.len()..],
            None => return false,
        }
    }
    rest.len() >= last.len() && rest.ends_with(last)
}

/// What closes a figure in a line: `0.160 s,`, `(commit 1a2b3c)`.
const CLOSING: [char; 3] = [',', ';', ')'];

/// A line with its runs of spaces as one, and what changes between runs and builds as
/// `#` (the module's comment lists what).
fn mask(line: &str) -> String {
    let words: Vec<&str> = line.split_whitespace().collect();
    let protocol_line = words.get(1).is_some_and(|api| api.starts_with("p3trace-"));
    let masked: Vec<String> = (words.iter().enumerate())
        .map(|(i, word)| {
            let before = if i > 0 { words[i - 1] } else { "" };
            let unit = words.get(i + 1).map(|u| u.trim_end_matches(CLOSING));
            let figure = word.trim_end_matches(CLOSING);
            let is_number = !figure.is_empty()
                && figure
                    .chars()
                    .all(|c| c.is_ascii_digit() || c == '.' || c == ',');
            let run_dependent = matches!(unit, Some("s" | "ms" | "Mrays/s"))
                || matches!(before, "build_s" | "packets:" | "(commit")
                || (protocol_line && i + 1 == words.len());
            if run_dependent && (is_number || before == "(commit") {
                format!("#{}", &word[figure.len()..])
            } else {
                word.replace("packet16", "packet#")
                    .replace("packet8", "packet#")
            }
        })
        .collect();
    masked.join(" ")
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
            // stderr into stdout, as a terminal shows them: in the order they come.
            let run = Command::new("bash")
                .args(["-euo", "pipefail", "-c", &format!("exec 2>&1\n{script}")])
                .current_dir(&project)
                .env("PATH", &path)
                .env("P3TRACE", env!("CARGO_BIN_EXE_p3trace"))
                .output()
                .expect("bash runs");
            ran += 1;
            let printed = common::stdout(&run);
            if !run.status.success() {
                failures.push(format!(
                    "{} failed ({}):\n{}\n--- output\n{printed}",
                    block.place, run.status, block.text,
                ));
            } else if let Some(shown) = block.shown.as_ref().filter(|s| !s.matches(&printed)) {
                failures.push(format!(
                    "{} shows another output than {} prints:\n{}\n--- shown\n{}\n--- printed\n{printed}",
                    shown.place,
                    block.place,
                    block.text,
                    shown.lines.join("\n")
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    assert!(ran > 0, "no block ran");
}

/// What a shown output stands for: the masked figures, `...` lines and pieces of lines.
#[test]
fn shown_outputs_mask_what_changes_between_runs_and_nothing_else() {
    let shown = |text: &str| Shown {
        place: "test".into(),
        lines: text.lines().map(String::from).collect(),
    };
    let render = shown("a.p3f: 8x8, 1 spp, 0.010 s, 72,815 rays, 7.66 Mrays/s -> a.png");
    assert!(render.matches("a.p3f: 8x8, 1 spp, 1.5 s, 72,815 rays, 12.00 Mrays/s -> a.png\n"));
    assert!(!render.matches("a.p3f: 8x8, 1 spp, 0.010 s, 72,816 rays, 7.66 Mrays/s -> a.png"));
    assert!(!render.matches("a.p3f: 8x8, 1 spp, 0.010 s, 72,815 rays, 7.66 Mrays/s -> b.png"));
    let bench = shown(
        "# structure bvh sah, build_s 0.0001\n# cpu ...; best of 1 pass\n...\n\
                       primary  p3trace-packet8  1  1048576  1048576  4630431.553  21.11\n...",
    );
    let printed = "# structure bvh sah, build_s 0.0123\n# cpu Some CPU, 2 CPUs; best of 1 pass\n\
                   primary p3trace-single 1 1048576 1048576 4630431.553 9.56\n\
                   primary p3trace-packet16 1 1048576 1048576 4630431.553 45.95\n";
    assert!(bench.matches(printed));
    assert!(!bench.matches(&printed.replace("4630431.553 45", "4630431.554 45")));
    assert!(!bench.matches(&printed.replace("best of 1", "best of 2")));
    let info = shown("  memory: 0.07 MiB\n  8-wide: 80 nodes, depth 4, 0.19 MiB");
    assert!(info.matches("memory: 0.07 MiB\n8-wide: 80 nodes, depth 4, 0.19 MiB"));
    assert!(!info.matches("memory: 0.07 MiB\n8-wide: 80 nodes, depth 4, 0.13 MiB"));
    assert!(
        !info.matches("memory: 0.07 MiB"),
        "every shown line is printed"
    );
    let version = shown("p3trace 0.1.0 (commit da6e5d8c76cb)\npackets: 16 rays");
    assert!(version.matches("p3trace 0.1.0 (commit 0123456789ab)\npackets: 8 rays"));
    assert!(!version.matches("p3trace 0.2.0 (commit 0123456789ab)\npackets: 8 rays"));
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
