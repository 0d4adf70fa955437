//! The merge's reader of EXR parts (`p3trace merge`) on arbitrary bytes: bad, truncated
//! or forged headers and pixels must give an error that names the file, never a panic,
//! and never an allocation beyond what the bytes could hold. A part that reads is laid on
//! a canvas twice (an overlap that agrees) and its gaps and missing tiles are asked for;
//! then it is laid beside a real part (a tile of another frame, or of the same one), which
//! it may mismatch in note, size or pixels: an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use p3trace::farm::{read_part, Canvas};

/// Tile 1/3 of an 8 x 6 render of an earlier version of scenes/showcase.p3f.
const TILE: &[u8] = include_bytes!("../seeds/exr_part/tile-1-of-3.exr");

fuzz_target!(|bytes: &[u8]| {
    let part = match read_part(bytes, "fuzz.exr") {
        Ok(part) => part,
        Err(e) => {
            assert!(e.starts_with("fuzz.exr: "), "{e}");
            return;
        }
    };
    let (width, height) = part.image;
    let r = part.region;
    assert!(r.x0 < r.x1 && r.x1 <= width && r.y0 < r.y1 && r.y1 <= height);
    assert_eq!(part.pixels.len() as u64, r.pixels());
    // The canvas is the whole frame, as large as the header says (as a render of that
    // size would be): only small frames here, within libFuzzer's memory.
    if u64::from(width) * u64::from(height) > 1 << 22 {
        return;
    }
    let mut canvas = Canvas::new(&part);
    canvas.add(&part).unwrap();
    canvas.add(&part).unwrap();
    let count = canvas.tile_count().unwrap_or(height.min(8));
    let missing = canvas.missing_tiles(count).unwrap();
    assert_eq!(missing.is_empty(), canvas.gaps().is_none());

    let tile = read_part(TILE, "tile.exr").unwrap();
    let mut canvas = Canvas::new(&tile);
    canvas.add(&tile).unwrap();
    if let Err(e) = canvas.add(&part) {
        assert!(e.contains("fuzz.exr"), "{e}");
    }
    let _ = canvas.missing_tiles(3).unwrap();
});
