//! The sizes the program accepts, whether they come from a scene file or the command
//! line: a leaf module, so that the reader (`scene`), the CLI and the renderer check the
//! same numbers without the reader depending on the renderer.

/// Largest `spp k` accepted: k x k samples per pixel.
pub const MAX_SPP_SIDE: u32 = 1024;

/// Largest image side accepted from a file or the command line.
pub const MAX_RESOLUTION: u32 = 1 << 16;

/// Largest image rendered, in pixels (6 GiB of film and tile memory).
pub const MAX_PIXELS: u64 = 1 << 28;

/// Refuses a `width` x `height` image too large to hold in memory, saying how much it
/// would need.
pub fn check_image_size(width: u32, height: u32) -> Result<(), String> {
    let pixels = width as u64 * height as u64;
    if pixels <= MAX_PIXELS {
        return Ok(());
    }
    // The film and the tiles' copies hold 24 bytes a pixel.
    Err(format!(
        "a {width}x{height} image needs {:.1} GiB; the limit is {MAX_PIXELS} pixels",
        (pixels * 24) as f64 / (1u64 << 30) as f64
    ))
}
