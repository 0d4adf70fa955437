//! The merge's reader of EXR parts (`p3trace merge`) on arbitrary bytes: bad, truncated
//! or forged headers and pixels must give an error that names the file, never a panic,
//! and never an allocation beyond what the bytes could hold. A part that reads is laid
//! on a canvas twice (an overlap that agrees) and its gaps and missing tiles are asked
//! for.
#![no_main]

use libfuzzer_sys::fuzz_target;
use p3trace::farm::{read_part, Canvas};

fuzz_target!(|bytes: &[u8]| {
    match read_part(bytes, "fuzz.exr") {
        Ok(part) => {
            let (width, height) = part.image;
            let r = part.region;
            assert!(r.x0 < r.x1 && r.x1 <= width && r.y0 < r.y1 && r.y1 <= height);
            assert_eq!(part.pixels.len() as u64, r.pixels());
            // The canvas is the whole frame, as large as the header says (as a render of
            // that size would be): only small frames here, within libFuzzer's memory.
            if u64::from(width) * u64::from(height) > 1 << 22 {
                return;
            }
            let mut canvas = Canvas::new(&part);
            canvas.add(&part).unwrap();
            canvas.add(&part).unwrap();
            let count = canvas.tile_count().unwrap_or(height.min(8));
            let missing = canvas.missing_tiles(count).unwrap();
            assert_eq!(missing.is_empty(), canvas.gaps().is_none());
        }
        Err(e) => assert!(e.starts_with("fuzz.exr: "), "{e}"),
    }
});
