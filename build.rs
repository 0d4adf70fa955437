//! Build facts for `p3trace --version` and the JSON statistics: the commit the binary is
//! built from and the instruction set it is compiled for.

use std::path::Path;
use std::process::Command;

fn main() {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|out| out.status.success())
            .map(|out| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    // Outside a git checkout (a source package) the commit is unknown.
    let commit = git(&["rev-parse", "--short=12", "HEAD"]).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=P3TRACE_COMMIT={commit}");
    // A commit or a checkout rewrites HEAD or the branch it names: build again then.
    let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
    watched.extend(git(&["symbolic-ref", "-q", "HEAD"]));
    for name in watched {
        if let Some(path) = git(&["rev-parse", "--git-path", &name]) {
            if Path::new(&path).exists() {
                println!("cargo:rerun-if-changed={path}");
            }
        }
    }
    println!("cargo:rerun-if-changed=build.rs");

    let features = std::env::var("CARGO_CFG_TARGET_FEATURE").unwrap_or_default();
    println!(
        "cargo:rustc-env=P3TRACE_TARGET_FEATURES={}",
        features.replace(',', ", ")
    );
    let flags = std::env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    // `-C target-cpu=X` arrives as one flag or as two (`-C`, `target-cpu=X`).
    let cpu = flags
        .split('\x1f')
        .find_map(|flag| flag.trim_start_matches("-C").strip_prefix("target-cpu="))
        .unwrap_or("the target's default")
        .to_string();
    println!("cargo:rustc-env=P3TRACE_TARGET_CPU={cpu}");

    // Packets of 16 rays where the code may use AVX-512 (`wide` then runs 16 lanes as one
    // instruction), of 8 elsewhere; the features `packet16` and `packet8` force a width
    // (16 lanes run as two halves of 8 without AVX-512: the same values, for the tests).
    println!("cargo::rustc-check-cfg=cfg(packet16)");
    let forced = |width: &str| std::env::var_os(format!("CARGO_FEATURE_PACKET{width}")).is_some();
    let avx512 = features.split(',').any(|f| f == "avx512f");
    let sixteen = match (forced("16"), forced("8")) {
        (true, true) => panic!("the features packet16 and packet8 exclude each other"),
        (true, false) => true,
        (false, true) => false,
        (false, false) => avx512,
    };
    if sixteen {
        println!("cargo:rustc-cfg=packet16");
    }
    println!(
        "cargo:rustc-env=P3TRACE_PACKET={}",
        if sixteen { 16 } else { 8 }
    );

    // The CPU check, compiled for the x86-64 baseline whatever the Rust code targets.
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("x86_64") {
        let features = features.replace(',', ", ");
        cc::Build::new()
            .file("src/cpu_check.c")
            .flag("-march=x86-64")
            .define(
                "P3TRACE_TARGET_FEATURES",
                format!("\"{features}\"").as_str(),
            )
            .define("P3TRACE_TARGET_CPU", format!("\"{cpu}\"").as_str())
            .compile("cpu_check");
        println!("cargo:rerun-if-changed=src/cpu_check.c");
        // A build for a CPU newer than the check's table may use an extension the check
        // cannot ask for: the binary runs here, but another CPU without it would not be
        // stopped with a message. The x86-64 baseline needs no check.
        let table = std::fs::read_to_string("src/cpu_check.c").expect("src/cpu_check.c");
        let unchecked: Vec<&str> = features
            .split(", ")
            .filter(|f| !["", "sse", "sse2", "fxsr"].contains(f))
            .filter(|f| !table.contains(&format!("{{\"{f}\"")))
            .collect();
        if !unchecked.is_empty() {
            println!(
                "cargo:warning=the CPU check (src/cpu_check.c) cannot ask for {}: another CPU \
                 without them would stop on an illegal instruction, not with a message",
                unchecked.join(", ")
            );
        }
    }
}
