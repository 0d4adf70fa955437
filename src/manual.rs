//! The shell completions and the man page, generated from the clap definitions so that
//! they never disagree with `--help`.

use std::io::Write;

use clap::Command;
use clap_complete::Shell;
use clap_mangen::roff::{roman, Roff};
use clap_mangen::Man;

/// The completion script of `command` for `shell`.
pub fn completion_script(mut command: Command, shell: Shell) -> Vec<u8> {
    let name = command.get_name().to_string();
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut command, name, &mut script);
    script
}

/// One roff page for the whole program: name, synopsis, description and options, then a
/// section per command with its synopsis, description and options, then the exit status.
pub fn man_page(command: Command) -> String {
    let mut command = without_help_commands(command);
    // Gives every command its full name ("p3trace gen balls") for its synopsis.
    command.build();
    // The title line names the version's first line only: the `.TH` macro ends at the
    // line's end, so that a long version's other lines would stand atop the page.
    let version = command.get_version().and_then(|v| v.lines().next());
    let source = format!("{} {}", command.get_name(), version.unwrap_or_default());
    let top = Man::new(command.clone()).source(source.trim_end());
    let mut page = rendered(|out| {
        top.render_title(out)?;
        top.render_name_section(out)?;
        top.render_synopsis_section(out)?;
        top.render_description_section(out)?;
        top.render_options_section(out)
    });
    for leaf in leaf_commands(&command) {
        page.push_str(&command_section(leaf));
    }
    if let Some(exit_status) = command.get_after_help() {
        let mut roff = Roff::new();
        roff.control("SH", ["EXIT STATUS"])
            .text([roman(exit_status.to_string())]);
        page.push_str(&roff.render());
    }
    with_one_preamble(&page)
}

/// What `render` writes, as text.
fn rendered(render: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> String {
    let mut out = Vec::new();
    render(&mut out).expect("writing into memory cannot fail");
    String::from_utf8(out).expect("roff is written from UTF-8 text")
}

/// `command` without the `help` subcommands clap adds, which `--help` already covers.
fn without_help_commands(command: Command) -> Command {
    command
        .disable_help_subcommand(true)
        .mut_subcommands(without_help_commands)
}

/// The commands that do something, depth first: `gen balls`, not `gen`.
fn leaf_commands(command: &Command) -> Vec<&Command> {
    if !command.has_subcommands() {
        return vec![command];
    }
    command.get_subcommands().flat_map(leaf_commands).collect()
}

/// A command's section: its full name as the heading, and its own page's sections one
/// level down. A `.SH` line is always a heading: roff escapes text lines that start with
/// a dot.
fn command_section(command: &Command) -> String {
    let man = Man::new(command.clone());
    let sections = rendered(|out| {
        man.render_synopsis_section(out)?;
        man.render_description_section(out)?;
        man.render_options_section(out)
    });
    let name = command.get_bin_name().unwrap_or(command.get_name());
    let mut text = Roff::new()
        .control("SH", [name.to_uppercase().as_str()])
        .render();
    for line in sections.lines() {
        match line.strip_prefix(".SH ") {
            Some(heading) => text.push_str(&format!(".SS {heading}\n")),
            None => text.push_str(&format!("{line}\n")),
        }
    }
    text
}

/// The lines roff writes before every piece it renders, defining the apostrophe.
const APOSTROPHE_PREAMBLE: [&str; 2] = [r".ie \n(.g .ds Aq \(aq", r".el .ds Aq '"];

/// `page` with the apostrophe's definition once, at the top, where the pieces it was put
/// together from had one each.
fn with_one_preamble(page: &str) -> String {
    let mut text = APOSTROPHE_PREAMBLE.map(|line| format!("{line}\n")).concat();
    for line in page.lines() {
        if !APOSTROPHE_PREAMBLE.contains(&line) {
            text.push_str(line);
            text.push('\n');
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Arg;

    fn tool() -> Command {
        Command::new("tool")
            .about("Does things")
            .after_help("Exit status: 0 done.")
            .subcommand(
                Command::new("run")
                    .about("Runs.\n.SH not a heading")
                    .arg(Arg::new("fast").long("fast").help("Quickly")),
            )
            .subcommand(Command::new("make").subcommand(Command::new("cake")))
    }

    #[test]
    fn one_section_per_command_that_does_something_and_no_help_command() {
        let page = man_page(tool());
        let headings: Vec<_> = page.lines().filter(|l| l.starts_with(".SH")).collect();
        assert_eq!(
            headings,
            [
                ".SH NAME",
                ".SH SYNOPSIS",
                ".SH DESCRIPTION",
                ".SH OPTIONS",
                ".SH \"TOOL RUN\"",
                ".SH \"TOOL MAKE CAKE\"",
                ".SH \"EXIT STATUS\"",
            ]
        );
        assert!(page.contains(r"\fB\-\-fast\fR"));
        assert!(page.contains(r"\&.SH not a heading"), "text stays text");
    }

    #[test]
    fn the_title_is_one_line_with_the_version_s_first() {
        let page = man_page(tool().version("1.0 (commit abc)\ninstruction set: all"));
        let lines: Vec<_> = page.lines().skip(2).take(2).collect();
        assert_eq!(
            lines,
            [r#".TH tool 1  "tool 1.0 (commit abc)" "#, ".SH NAME"]
        );
        assert!(!page.contains("instruction set"), "{page}");
    }

    #[test]
    fn the_apostrophe_is_defined_once_before_the_title() {
        let page = man_page(tool());
        let lines: Vec<_> = page.lines().take(3).collect();
        assert_eq!(lines[..2], APOSTROPHE_PREAMBLE);
        assert!(lines[2].starts_with(".TH tool 1"));
        assert_eq!(page.matches(APOSTROPHE_PREAMBLE[0]).count(), 1);
    }

    #[test]
    fn completion_scripts_name_the_subcommands() {
        let script = completion_script(tool(), Shell::Bash);
        let script = String::from_utf8(script).unwrap();
        assert!(script.contains("--fast") && script.contains("cake"));
    }
}
