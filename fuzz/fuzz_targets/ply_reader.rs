//! The PLY reader (`gen dragon --ply`) on arbitrary bytes, gzipped or not: it must answer
//! with a mesh whose every index names a vertex, or an error that names the file, never
//! panic, and never allocate beyond what the input could hold.
#![no_main]

use libfuzzer_sys::fuzz_target;
use p3trace::scene::ply::parse_ply_file;

fuzz_target!(|bytes: &[u8]| {
    match parse_ply_file(bytes, "fuzz.ply") {
        Ok(mesh) => {
            let vertices = mesh.vertices.len();
            for triangle in &mesh.triangles {
                assert!(triangle.iter().all(|&i| (i as usize) < vertices), "{triangle:?}");
            }
        }
        Err(e) => assert!(e.starts_with("fuzz.ply: "), "{e}"),
    }
});
