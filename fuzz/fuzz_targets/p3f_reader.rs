//! The P3F reader on arbitrary bytes: it must answer with a scene or an error that names
//! a position, never panic, and never allocate beyond what the input could hold.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use p3trace::scene::p3f::parse_bytes;

fuzz_target!(|bytes: &[u8]| {
    match parse_bytes(bytes, "fuzz.p3f", Path::new("")) {
        Ok(scene) => {
            // Whatever the reader accepts, the camera must accept too.
            if scene.has_camera {
                assert_eq!(scene.camera.validate(), Ok(()));
            }
        }
        Err(e) => {
            assert!(e.to_string().starts_with("fuzz.p3f:"), "{e}");
        }
    }
});
