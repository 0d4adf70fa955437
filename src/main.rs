//! The `p3trace` command: parses the command line, hands each subcommand to its file in
//! `commands/`, and maps failures to exit codes (1 a render or I/O failure, 2 bad usage
//! or a bad scene, 128 + N after signal N: 130 Ctrl-C, 143 SIGTERM, 129 SIGHUP).

mod cli;
mod commands;
mod manual;
mod statistics;
mod window;

use std::process::ExitCode;

use clap::{CommandFactory, Parser};

use cli::{Cli, Command};
use commands::write_to_stdout;

/// Why the command failed, and so which exit code it gives.
pub(crate) enum Failure {
    /// Bad usage or a bad scene: exit 2.
    Usage(String),
    /// A render or I/O failure: exit 1.
    Run(String),
}

/// The CPU check, run by the dynamic loader before any other code of the binary (the
/// standard library's start-up included, which link-time optimisation compiles for the
/// target CPU too): a CPU without the instructions the binary was compiled for would
/// otherwise die of an illegal instruction.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
#[used]
#[link_section = ".preinit_array"]
static CHECK_CPU_FIRST: unsafe extern "C" fn() = p3trace::machine::p3trace_check_cpu;

fn main() -> ExitCode {
    // A closed pipe ends the program quietly, as it does other command-line tools: Rust
    // ignores SIGPIPE, so every `println!` into a closed pipe would panic instead.
    #[cfg(unix)]
    // SAFETY: restoring a signal's default action, before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    #[cfg(unix)]
    exit_cleanly_on_signals();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => commands::render::run(&args),
        Command::View(args) => window::run(&args),
        Command::Info(args) => commands::info::run(&args),
        Command::Compare(args) => commands::compare::run(&args),
        Command::Merge(args) => commands::merge::run(&args),
        Command::Gen(command) => commands::gen::run(command),
        Command::Bench(args) => commands::bench::run(&args),
        Command::Completions { shell } => write_to_stdout(
            &manual::completion_script(Cli::command(), shell),
            "the completion script",
        ),
        Command::Man => {
            write_to_stdout(manual::man_page(Cli::command()).as_bytes(), "the man page")
        }
    };
    match result {
        Ok(code) => code,
        Err(Failure::Usage(message)) => {
            eprintln!("p3trace: error: {message}");
            ExitCode::from(2)
        }
        Err(Failure::Run(message)) => {
            eprintln!("p3trace: error: {message}");
            ExitCode::from(1)
        }
    }
}

/// On Ctrl-C (SIGINT), SIGTERM or SIGHUP: removes the file being written, if any, and
/// exits 128 + the signal's number, the status a shell gives a process the signal ended.
/// The signals are blocked in every thread (threads inherit the mask: this runs before
/// any other exists) and taken by one that waits for them, so the cleanup runs as
/// ordinary code, not in a signal handler. Should that thread fail to start, the signals
/// keep their default action: the target is still never truncated, but a `.partial` file
/// may stay.
#[cfg(unix)]
fn exit_cleanly_on_signals() {
    const SIGNALS: [(libc::c_int, &str); 3] = [
        (libc::SIGINT, "SIGINT"),
        (libc::SIGTERM, "SIGTERM"),
        (libc::SIGHUP, "SIGHUP"),
    ];
    // SAFETY: `set` is initialised by sigemptyset before use, and the mask changes this
    // thread's only.
    let set = unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for (signal, _) in SIGNALS {
            libc::sigaddset(&mut set, signal);
        }
        if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
            return;
        }
        set
    };
    let waiter = std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || loop {
            let mut signal = 0;
            // SAFETY: `set` is a valid signal set and `signal` a place for the answer;
            // sigwait fails only for an invalid set.
            if unsafe { libc::sigwait(&set, &mut signal) } != 0 {
                continue;
            }
            let _held_until_exit = p3trace::output::abandon_partial_files();
            let name = SIGNALS.iter().find(|(s, _)| *s == signal).map(|(_, n)| *n);
            eprintln!("p3trace: interrupted ({})", name.unwrap_or("a signal"));
            std::process::exit(128 + signal);
        });
    if waiter.is_err() {
        // SAFETY: as above.
        unsafe {
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        }
    }
}
