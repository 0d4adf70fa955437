//! The README's gallery, `docs/gallery/`, is what `scripts/gallery.sh` renders: the same
//! files, byte for byte. Renders are deterministic (every sample is a hash of its pixel,
//! its index and the seed), so this holds on any machine and any number of threads.

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

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
    let names = file_names(&committed);
    assert_eq!(
        file_names(&out),
        names,
        "the script's files against docs/gallery/"
    );
    for name in &names {
        assert!(
            std::fs::read(out.join(name)).unwrap() == std::fs::read(committed.join(name)).unwrap(),
            "docs/gallery/{name} is not what scripts/gallery.sh renders: run the script"
        );
    }
}
