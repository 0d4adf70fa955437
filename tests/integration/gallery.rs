//! The README's gallery, `docs/gallery/`, is what `scripts/gallery.sh` renders: the same
//! files, byte for byte. Renders are deterministic (every sample is a hash of its pixel,
//! its index and the seed), so this holds on any machine and any number of threads.

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

use p3trace::simd::PACKET;

use crate::common::{project_file, scratch, stderr};

fn file_names(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

#[test]
fn the_gallery_is_what_its_script_renders() {
    let out = scratch("gallery");
    let run = Command::new(project_file("scripts/gallery.sh"))
        .env("P3TRACE", env!("CARGO_BIN_EXE_p3trace"))
        .env("OUT", &out)
        .output()
        .expect("the gallery script runs");
    assert!(run.status.success(), "{}", stderr(&run));
    let committed = project_file("docs/gallery");
    assert_the_same(
        &out,
        "docs/gallery",
        &file_names(&committed),
        "scripts/gallery.sh",
    );
}

/// The files `names` of the project's folder `committed` are those of `out`, which holds
/// nothing else, byte for byte: what `script` wrote.
fn assert_the_same(out: &Path, committed: &str, names: &BTreeSet<String>, script: &str) {
    assert_eq!(
        &file_names(out),
        names,
        "{script}'s files against {committed}/"
    );
    for name in names {
        let committed_file = project_file(committed).join(name);
        assert!(
            std::fs::read(out.join(name)).unwrap() == std::fs::read(committed_file).unwrap(),
            "{committed}/{name} is not what {script} renders: run the script"
        );
    }
}

/// `docs/cost/`, the cost images of the README and the benchmarking page, is what
/// `scripts/cost-gallery.sh` renders; its dragon images need the course material, and
/// are left out of the check without it. Its counts are those of packets of eight: a
/// 16-wide build's packets count other work.
#[test]
fn the_cost_images_are_what_their_script_renders() {
    if PACKET != 8 {
        crate::common::skip(
            "docs/cost/ holds the counts of packets of 8 rays; this build's are 16",
        );
        return;
    }
    let out = scratch("cost_gallery");
    let shared = crate::common::shared();
    let mut script = Command::new(project_file("scripts/cost-gallery.sh"));
    script
        .env("P3TRACE", env!("CARGO_BIN_EXE_p3trace"))
        .env("OUT", &out);
    // Without the course material, point the script at a folder without it.
    script.env(
        "P3TRACE_SHARED",
        shared.clone().unwrap_or_else(|| out.join("no-shared")),
    );
    let run = script.output().expect("the cost gallery script runs");
    assert!(run.status.success(), "{}", stderr(&run));
    let committed = project_file("docs/cost");
    let mut names = file_names(&committed);
    if shared.is_none() {
        names.retain(|name| !name.starts_with("dragon_"));
    }
    assert!(
        names.iter().any(|n| n.starts_with("balls_high_")),
        "{names:?}"
    );
    assert_the_same(&out, "docs/cost", &names, "scripts/cost-gallery.sh");
}
