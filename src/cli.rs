//! The command line: clap definitions and the plain option structs they become.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "p3trace",
    version,
    about = "A fast Whitted and distribution ray tracer for P3F scenes (the P3D course format)",
    after_help = "Exit status: 0 success, 1 a render or I/O failure, 2 bad usage or a bad scene."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a P3F scene to an image.
    Render(RenderArgs),
    /// Print what a scene holds: objects by kind, materials, lights, camera.
    Info {
        /// The P3F scene file.
        scene: PathBuf,
    },
    /// Print how two images differ; exit 1 when too few pixels are within the tolerance.
    Compare(CompareArgs),
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The P3F scene file.
    pub scene: PathBuf,
    /// Output image; the extension picks the format: .png (8-bit), .ppm (8-bit binary
    /// P6) or .hdr (linear floating point). Default: the scene's name with .png, in the
    /// current folder.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Image size, overriding the scene's `resolution` (for example 1024x768).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Samples per pixel, a perfect square k*k (k x k jittered grid); 1 is one sample at
    /// the pixel centre. Default: the scene's `spp k` (k x k), or the centre for `spp 0`.
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    /// Depth at which rays stop spawning reflection and refraction rays (primary rays
    /// have depth 1).
    #[arg(long, value_name = "N", default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_depth: u32,
    /// Use Schlick's approximation instead of the exact Fresnel equations.
    #[arg(long)]
    pub schlick: bool,
    /// Ignore the scene's skybox (`env`): rays that leave the scene take the `bclr` colour.
    #[arg(long)]
    pub no_skybox: bool,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Seed of the random numbers of jittered sampling and the thin lens.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
    /// No progress bar and no closing statistics line (warnings still go to stderr).
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    pub first: PathBuf,
    pub second: PathBuf,
    /// Largest channel difference, in 8-bit levels, for a pixel to count as matching.
    #[arg(long, value_name = "N", default_value_t = 0.0)]
    pub tolerance: f32,
    /// Percentage of pixels that must match for the images to count as equal.
    #[arg(long, value_name = "PERCENT", default_value_t = 100.0)]
    pub min_match: f64,
}

fn parse_resolution(text: &str) -> Result<(u32, u32), String> {
    let max = p3trace::scene::p3f::MAX_RESOLUTION;
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{text}' is not WIDTHxHEIGHT, such as 512x512"))?;
    let side = |s: &str| match s.trim().parse::<u32>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("'{s}' is not an image side between 1 and {max}")),
    };
    Ok((side(w)?, side(h)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolutions() {
        assert_eq!(parse_resolution("640x480"), Ok((640, 480)));
        assert_eq!(parse_resolution("8X2"), Ok((8, 2)));
        assert!(parse_resolution("640").is_err());
        assert!(parse_resolution("0x5").is_err());
        assert!(parse_resolution("axb").is_err());
    }

    #[test]
    fn command_line_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }
}
