//! The documents as a newcomer meets them: every shell block of README.md and docs/*.md
//! runs as shown and prints what the document shows, every relative link leads to a
//! file, the README starts with the two commands it promises (the second the one
//! `.ci/run` runs), and each document keeps to its length. And the documents as
//! references: a figure that README.md or docs/ quotes from BENCHMARKS.md is as
//! BENCHMARKS.md's section says it ([`contradictions`]), and prose names no commit
//! ([`commits_in_prose`]).
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

/// A document's prose in the units the checks below read, each with its line: every heading
/// and table row, and every sentence (ended by `. `) of a paragraph or list item; code blocks
/// and HTML comments left out.
fn prose(markdown: &str) -> Vec<(usize, String)> {
    fn flush(paragraph: &mut Vec<&str>, line: usize, units: &mut Vec<(usize, String)>) {
        let text = paragraph.join(" ");
        units.extend(
            (text.split(". "))
                .filter(|sentence| !sentence.trim().is_empty())
                .map(|sentence| (line, sentence.to_string())),
        );
        paragraph.clear();
    }
    let mut units = Vec::new();
    let mut paragraph: Vec<&str> = Vec::new();
    let mut first = 0;
    let mut in_code = false;
    for (number, line) in markdown.lines().enumerate() {
        let line = line.trim();
        let code_fence = line.starts_with("```");
        let own_unit = line.starts_with('|') || line.starts_with('#');
        if code_fence || in_code || own_unit || line.is_empty() || line.starts_with("<!--") {
            flush(&mut paragraph, first, &mut units);
        }
        in_code ^= code_fence;
        if code_fence || in_code || line.is_empty() || line.starts_with("<!--") {
            continue;
        }
        if own_unit {
            units.push((number + 1, line.to_string()));
            continue;
        }
        if line.starts_with("- ") {
            flush(&mut paragraph, first, &mut units);
        }
        if paragraph.is_empty() {
            first = number + 1;
        }
        paragraph.push(line);
    }
    flush(&mut paragraph, first, &mut units);
    units
}

/// The targets of a text's Markdown links: `[text](TARGET)`.
fn link_targets(text: &str) -> Vec<&str> {
    (text.split("](").skip(1))
        .filter_map(|rest| rest.split(')').next())
        .collect()
}

/// The text with its `code` spans and its links' targets left out: what it says in words
/// and figures.
fn words_and_figures(text: &str) -> String {
    let words: String = (text.split('`').step_by(2)).collect::<Vec<_>>().join(" ");
    let mut pieces = words.split("](");
    let mut kept = pieces.next().unwrap_or_default().to_string();
    for piece in pieces {
        kept.push_str(piece.split_once(')').map_or("", |(_, after)| after));
    }
    kept
}

/// The numbers of a text as written (`1,422,603`, `0.160`, `3.13.5`; not the digits of a
/// word such as `x86` or `packet16`), each with whether an `x` follows it as a ratio's
/// (`1.80x`, not `4x2`).
fn numbers(text: &str) -> Vec<(String, bool)> {
    let chars: Vec<char> = text.chars().collect();
    let digit_at = |i: usize| chars.get(i).is_some_and(char::is_ascii_digit);
    let mut found = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let in_word =
            i > 0 && (chars[i - 1].is_alphanumeric() || matches!(chars[i - 1], '_' | '.'));
        if !digit_at(i) || in_word {
            i += 1;
            continue;
        }
        let start = i;
        while digit_at(i) || (matches!(chars.get(i), Some('.' | ',')) && digit_at(i + 1)) {
            i += 1;
        }
        let ratio =
            chars.get(i) == Some(&'x') && !chars.get(i + 1).is_some_and(|c| c.is_alphanumeric());
        found.push((chars[start..i].iter().collect(), ratio));
    }
    found
}

/// A heading's anchor, as GitHub makes it: lower case, spaces as `-`, punctuation left out.
fn anchor(heading: &str) -> String {
    (heading
        .trim_start_matches('#')
        .trim()
        .to_lowercase()
        .chars())
    .filter_map(|c| match c {
        ' ' => Some('-'),
        c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
        _ => None,
    })
    .collect()
}

/// A document's sections by their anchors: each heading with the text under it to the next
/// heading of its level or above (its subsections included).
fn sections(markdown: &str) -> Vec<(String, String)> {
    let lines: Vec<&str> = markdown.lines().collect();
    let mut headings = Vec::new();
    let mut in_code = false;
    for (i, line) in lines.iter().enumerate() {
        in_code ^= line.trim_start().starts_with("```");
        let level = line.chars().take_while(|&c| c == '#').count();
        if !in_code && level > 0 && line[level..].starts_with(' ') {
            headings.push((i, level));
        }
    }
    (headings.iter().enumerate())
        .map(|(k, &(start, level))| {
            let end = (headings[k + 1..].iter())
                .find(|&&(_, other)| other <= level)
                .map_or(lines.len(), |&(i, _)| i);
            (anchor(lines[start]), lines[start..end].join("\n"))
        })
        .collect()
}

/// What `markdown` (the document `name`) quotes from BENCHMARKS.md (`benchmarks`) that
/// BENCHMARKS.md does not say, one line each. A sentence or table row that links to
/// `BENCHMARKS.md#SECTION` quotes that section: every number of its words (not its `code`)
/// written with a decimal point, or as a ratio `1.80x`, must be one of the section's numbers
/// as written there (1.4 is not 1.40), and the section must exist; a link without
/// `#SECTION` stands for the whole file. A sentence that names figures of BENCHMARKS.md
/// without such a link is not checked: it should link instead.
fn contradictions(name: &str, markdown: &str, benchmarks: &str) -> Vec<String> {
    let sections = sections(benchmarks);
    let numbers_of = |text: &str| -> std::collections::HashSet<String> {
        numbers(text)
            .into_iter()
            .map(|(number, _)| number)
            .collect()
    };
    let mut found = Vec::new();
    for (line, unit) in prose(markdown) {
        let quoted: Vec<&str> = (link_targets(&unit).into_iter())
            .filter(|target| target.split('#').next().unwrap().ends_with("BENCHMARKS.md"))
            .collect();
        let mut held = std::collections::HashSet::new();
        for target in &quoted {
            match target.split_once('#') {
                None => held.extend(numbers_of(benchmarks)),
                Some((_, wanted)) => match sections.iter().find(|(anchor, _)| anchor == wanted) {
                    Some((_, text)) => held.extend(numbers_of(text)),
                    None => found.push(format!(
                        "{name}:{line}: BENCHMARKS.md has no section #{wanted}"
                    )),
                },
            }
        }
        if quoted.is_empty() {
            continue;
        }
        for (figure, ratio) in numbers(&words_and_figures(&unit)) {
            if (figure.contains('.') || ratio) && !held.contains(&figure) {
                found.push(format!(
                    "{name}:{line}: {figure} is not in the part of BENCHMARKS.md it links to ({}): {unit}",
                    quoted.join(", ")
                ));
            }
        }
    }
    found
}

/// The README and docs/ quote no figure that BENCHMARKS.md contradicts ([`contradictions`]):
/// a figure lives in BENCHMARKS.md, and a sentence that gives it again links to its section
/// and gives it as written there.
#[test]
fn quoted_figures_agree_with_benchmarks() {
    let benchmarks = std::fs::read_to_string(project_file("BENCHMARKS.md")).unwrap();
    let found: Vec<String> = (documents().into_iter())
        .flat_map(|document| {
            let text = std::fs::read_to_string(project_file(&document)).unwrap();
            contradictions(&document, &text, &benchmarks)
        })
        .collect();
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// Whether a word is a commit's abbreviated or full hash: 7 to 40 hexadecimal digits, at
/// least one a letter and one a digit.
fn is_commit(word: &str) -> bool {
    (7..=40).contains(&word.len())
        && word
            .chars()
            .all(|c| c.is_ascii_digit() || ('a'..='f').contains(&c))
        && word.chars().any(|c| c.is_ascii_digit())
        && word.chars().any(|c| c.is_ascii_alphabetic())
}

/// The commits `markdown` names in its prose, one line each: a commit belongs in a table (a
/// measured column) or in a sentence that starts `Measured`, which says where a figure was
/// measured; prose states what is, and git keeps the history.
fn commits_in_prose(name: &str, markdown: &str) -> Vec<String> {
    (prose(markdown).into_iter())
        .filter(|(_, unit)| !unit.starts_with('|'))
        .filter(|(_, unit)| {
            !unit
                .trim_start_matches(['*', '(', ' '])
                .starts_with("Measured")
        })
        .flat_map(|(line, unit)| {
            (unit.split(|c: char| !c.is_ascii_alphanumeric()))
                .filter(|word| is_commit(word))
                .map(|commit| format!("{name}:{line}: {commit} in: {unit}"))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The documents name commits only where they say where a figure was measured
/// ([`commits_in_prose`]); docs/did-not-pay.md, the record of experiments, names theirs.
#[test]
fn prose_names_no_commit() {
    let mut pages = documents();
    pages.extend(["BENCHMARKS.md", "ARCHITECTURE.md", "CONTRIBUTING.md"].map(String::from));
    let found: Vec<String> = (pages.into_iter())
        .filter(|page| page != "docs/did-not-pay.md")
        .flat_map(|page| {
            let text = std::fs::read_to_string(project_file(&page)).unwrap();
            commits_in_prose(&page, &text)
        })
        .collect();
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// The two checks above catch what they are for, and pass what they should.
#[test]
fn a_contradicting_quote_or_a_commit_in_prose_is_caught() {
    let benchmarks = "# Benchmarks\n\n## Trace throughput\n\nMeans 1.43 and 1.44 (`--reps 7`).\n\n\
                      ### Agreement\n\nTsums within 0.01%.\n\n## Memory\n\n135.9 bytes a sphere.\n";
    let agrees = "It leads by 1.43-1.44x, tsums within 0.01%\n\
                  ([the figures](BENCHMARKS.md#trace-throughput)). It is 9.99 times as nice.\n\n\
                  | the heap | 135.9 bytes | [memory](../BENCHMARKS.md#memory) |\n\n\
                  Run it with `--roughness 0.2` ([how](BENCHMARKS.md)).\n";
    let found = contradictions("doc", agrees, benchmarks);
    assert!(found.is_empty(), "{found:?}");
    for contradicting in [
        "It leads by 1.45x ([the figures](BENCHMARKS.md#trace-throughput)).",
        "It takes 135.9 bytes ([the figures](BENCHMARKS.md#trace-throughput)).",
        "It leads by 1.4 ([the figures](../BENCHMARKS.md#trace-throughput)).",
        "| the lead | 2x | [the figures](BENCHMARKS.md#trace-throughput) |",
        "It leads by 1.43 ([the figures](BENCHMARKS.md#speed)).",
        "- It leads\n  by 1.50 ([the figures](BENCHMARKS.md)).",
    ] {
        let found = contradictions("doc", contradicting, benchmarks);
        assert!(!found.is_empty(), "not caught: {contradicting}");
    }
    let prose = "Measured: Xeon, 07a60ac, 2026-12-03. It is faster since\n07a60ac.\n\n\
                 | run | 07a60ac |\n\n**Measured at 1a2b3c4d**. 1048576 rays, `x86-64-v3`.\n";
    let found = commits_in_prose("doc", prose);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].starts_with("doc:1: 07a60ac"), "{found:?}");
}
