//! The P3F reader on arbitrary bytes, in the file's frame and the camera's: it must
//! answer with a scene or an error that names a position, never panic, and never
//! allocate beyond what the input could hold.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use p3trace::scene::p3f::parse_bytes;
use p3trace::scene::{parse_str_in, Frame, Scene};

/// Whatever the reader accepts, the camera must accept too; an error names its place.
fn check(read: Result<Scene, p3trace::scene::ParseError>) {
    match read {
        Ok(scene) => {
            if scene.has_camera {
                assert_eq!(scene.camera.validate(), Ok(()));
            }
        }
        Err(e) => {
            assert!(e.to_string().starts_with("fuzz.p3f:"), "{e}");
        }
    }
}

fuzz_target!(|bytes: &[u8]| {
    check(parse_bytes(bytes, "fuzz.p3f", Path::new("")));
    if let Ok(text) = std::str::from_utf8(bytes) {
        check(parse_str_in(text, "fuzz.p3f", Path::new(""), Frame::Camera));
    }
});
