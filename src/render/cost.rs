//! Cost images (`render --cost`): each pixel's count of one traversal counter
//! (`accel::count`), summed over its samples' rays, instead of its colour. A cost image is
//! a [`Film`] whose three channels hold the count, so that regions of one merge as colour
//! ones do (`farm`); what it shows is a line of its note ([`CostMap::note_line`]), which
//! keeps parts of cost and colour images apart. It is written as a false-colour picture
//! with its scale beside it (PNG, PPM, JPEG: viridis, a perceptual map, from 0 at the
//! bottom of the bar to the top of the scale) or as the raw counts (OpenEXR, one float channel `Y`).

use glam::Vec3;

use super::film::{Film, ImageOutput, OutputFormat, Placement};
use super::{RenderMode, RenderWork};
use crate::accel::count::{CostRays, Counter};
use crate::simd::PACKET;

/// What a cost image shows: one counter, over the rays `rays` says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CostMap {
    pub counter: Counter,
    pub rays: CostRays,
}

/// The key of the note line that says a render is a cost image.
const NOTE_KEY: &str = "cost: ";

impl CostMap {
    /// The line of the note of a cost image made with the structure `structure` in ray
    /// mode `mode` and, for packets, the build's packet width, which change its counts
    /// (not its colours): `cost: prims per pixel, all rays (bvh sah, stream mode, packets
    /// of 8)`.
    pub fn note_line(&self, structure: &str, mode: RenderMode) -> String {
        let rays = match self.rays {
            CostRays::All => "all rays",
            CostRays::Primary => "primary rays",
        };
        let mode = match mode {
            RenderMode::Scalar => "scalar mode".to_string(),
            RenderMode::Stream => format!("stream mode, packets of {PACKET}"),
        };
        format!(
            "{NOTE_KEY}{} per pixel, {rays} ({structure}, {mode})",
            self.counter.name()
        )
    }

    /// What the note `note` says its image shows, if it is a cost image's (`Err` for a
    /// cost line this program cannot read).
    pub fn from_note(note: &str) -> Result<Option<CostMap>, String> {
        let Some(line) = note.lines().find_map(|l| l.strip_prefix(NOTE_KEY)) else {
            return Ok(None);
        };
        let unknown = || format!("an unknown cost line '{NOTE_KEY}{line}'");
        let (shown, _made_by) = line.split_once(" (").ok_or_else(unknown)?;
        let (counter, rays) = shown.split_once(" per pixel, ").ok_or_else(unknown)?;
        let counter = Counter::from_name(counter).ok_or_else(unknown)?;
        let rays = match rays {
            "all rays" => CostRays::All,
            "primary rays" => CostRays::Primary,
            _ => return Err(unknown()),
        };
        Ok(Some(CostMap { counter, rays }))
    }

    /// The cost image of `work` (a render of a `width` x `height` region): each pixel's
    /// count in all three channels.
    pub fn film(&self, work: &RenderWork, width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            pixels: work
                .pixels
                .iter()
                .map(|work| Vec3::splat(work.of(self.rays).get(self.counter) as f32))
                .collect(),
        }
    }
}

/// How a picture shows counts: from 0 at the bottom of its colour bar to a top, linearly
/// or on a logarithmic scale (of 1 plus the count, so that 0 stays at the bottom).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Scale {
    /// The top: the count drawn in the bar's top colour, which larger counts take too.
    /// `None`: the 99th percentile of the image's counts (at least 1), so that a few
    /// pixels of very many rays (a glass sphere's rim) do not leave the rest dark.
    pub max: Option<f32>,
    pub log: bool,
}

impl Scale {
    /// The top of the scale for the counts of `film`.
    fn top(&self, film: &Film) -> f32 {
        self.max.unwrap_or_else(|| {
            let mut counts: Vec<f32> = film.pixels.iter().map(|p| p.x).collect();
            let rank = (counts.len() * 99 / 100).min(counts.len().saturating_sub(1));
            let (_, at, _) = counts.select_nth_unstable_by(rank, f32::total_cmp);
            at.max(1.0)
        })
    }

    /// Where `count` lies on a scale whose top is `top`: 0 at the bottom, 1 at the top.
    fn share(&self, count: f32, top: f32) -> f32 {
        match self.log {
            true => count.ln_1p() / top.ln_1p(),
            false => count / top,
        }
    }

    /// The count at share `t` of a scale whose top is `top`.
    fn count_at(&self, t: f32, top: f32) -> f32 {
        match self.log {
            true => (t * top.ln_1p()).exp_m1(),
            false => t * top,
        }
    }
}

/// Writes the cost image `film` as `output` says: PNG, PPM and JPEG as the picture
/// ([`picture`], on `scale`), EXR as the raw counts with `placement`. HDR is refused: a
/// cost image is a picture or counts.
pub fn write(
    film: &Film,
    output: &ImageOutput,
    placement: &Placement,
    map: &CostMap,
    scale: Scale,
) -> Result<(), String> {
    match output.format {
        OutputFormat::Exr => film.write_counts(output, placement),
        OutputFormat::Hdr => Err(refuse_hdr(output)),
        OutputFormat::Png | OutputFormat::Ppm | OutputFormat::Jpeg => {
            let picture = picture(film, map, scale);
            picture.write_placed(output, &Placement::whole(&picture))
        }
    }
}

/// Why a cost image is not written as `output`, an HDR image.
pub fn refuse_hdr(output: &ImageOutput) -> String {
    format!(
        "a cost image cannot be written as HDR ({}): use .exr for the counts or .png for a picture",
        output.name()
    )
}

/// The false-colour picture of the cost image `film`: each count on viridis from 0 to the
/// top of `scale` (counts above it take its colour, and its label says so with a `+`),
/// and to its right a strip with the counter's name, the colour bar and the counts at
/// its ticks.
pub fn picture(film: &Film, map: &CostMap, scale: Scale) -> Film {
    let top = scale.top(film);
    let beyond = film.pixels.iter().any(|p| p.x > top);
    let mut labels: Vec<String> = TICKS
        .iter()
        .map(|&t| count_label(scale.count_at(t, top), top))
        .collect();
    if beyond {
        labels[TICKS.len() - 1].push('+');
    }
    let mut title = map.counter.name().to_ascii_uppercase();
    if scale.log {
        title.push_str(" LOG");
    }
    // Text twice as large on large images.
    let text_scale = if film.height >= 300 { 2 } else { 1 };
    let glyph = (GLYPH_W + 1) * text_scale;
    let longest = labels.iter().map(String::len).max().unwrap_or(1) as u32;
    let margin = 4 * text_scale;
    let bar_width = 10 * text_scale;
    let strip =
        (margin * 3 + bar_width + longest * glyph).max(2 * margin + title.len() as u32 * glyph);
    let width = film.width + strip;
    let mut out = Film::new(width, film.height);
    for row in 0..film.height {
        for x in 0..film.width {
            let count = film.get(x, row).x;
            out.pixels[(row * width + x) as usize] = viridis(scale.share(count, top));
        }
    }
    // The strip: dark grey, the title at the top, the bar below it to the bottom margin.
    for row in 0..film.height {
        for x in film.width..width {
            out.pixels[(row * width + x) as usize] = Vec3::splat(0.12);
        }
    }
    let text_height = GLYPH_H * text_scale;
    let bar_top = margin + text_height + margin;
    let bar_bottom = film.height.saturating_sub(margin + text_height / 2);
    let x0 = film.width + margin;
    draw_text(&mut out, &title, x0, margin, text_scale);
    if bar_bottom <= bar_top + 1 {
        return out;
    }
    let span = (bar_bottom - bar_top) as f32;
    for row in bar_top..bar_bottom {
        let colour = viridis((bar_bottom - 1 - row) as f32 / (span - 1.0).max(1.0));
        for x in x0..x0 + bar_width {
            out.pixels[(row * width + x) as usize] = colour;
        }
    }
    // Tick labels beside the bar, from the top down, as many as fit without touching.
    let label_x = x0 + bar_width + margin;
    let mut last_drawn: Option<u32> = None;
    for (&tick, label) in TICKS.iter().zip(&labels).rev() {
        // Centred on its tick, but within the bar's height.
        let centre = bar_bottom - 1 - (tick * (span - 1.0)).round() as u32;
        let y = centre
            .saturating_sub(text_height / 2)
            .clamp(bar_top, bar_bottom.saturating_sub(text_height).max(bar_top));
        if last_drawn.is_none_or(|above| y >= above + text_height + text_scale) {
            draw_text(&mut out, label, label_x, y, text_scale);
            last_drawn = Some(y);
        }
    }
    out
}

/// Where the bar's labelled ticks lie, as shares of the top of the scale.
const TICKS: [f32; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// A count at a tick of a scale whose top is `top`: whole where the scale is large, one
/// decimal where it is small.
fn count_label(value: f32, top: f32) -> String {
    if top >= 20.0 || value == value.round() {
        format!("{}", value.round() as u64)
    } else {
        format!("{value:.1}")
    }
}

/// Viridis (matplotlib's, Smith and van der Walt 2015) at 17 evenly spaced points, linear
/// between them.
const VIRIDIS: [[f32; 3]; 17] = [
    [0.2670, 0.0049, 0.3294],
    [0.2823, 0.0950, 0.4173],
    [0.2788, 0.1755, 0.4834],
    [0.2590, 0.2515, 0.5247],
    [0.2297, 0.3224, 0.5457],
    [0.1994, 0.3876, 0.5546],
    [0.1727, 0.4488, 0.5579],
    [0.1490, 0.5081, 0.5573],
    [0.1276, 0.5669, 0.5506],
    [0.1206, 0.6258, 0.5335],
    [0.1579, 0.6838, 0.5017],
    [0.2461, 0.7389, 0.4520],
    [0.3692, 0.7889, 0.3829],
    [0.5160, 0.8312, 0.2943],
    [0.6785, 0.8637, 0.1895],
    [0.8456, 0.8873, 0.0997],
    [0.9932, 0.9062, 0.1439],
];

/// The colour of share `t` of the scale on viridis, `t` clamped to [0, 1] (NaN is 0).
pub fn viridis(t: f32) -> Vec3 {
    let t = if t > 0.0 { t.min(1.0) } else { 0.0 };
    let at = t * (VIRIDIS.len() - 1) as f32;
    let i = (at as usize).min(VIRIDIS.len() - 2);
    let f = at - i as f32;
    Vec3::from_array(VIRIDIS[i]).lerp(Vec3::from_array(VIRIDIS[i + 1]), f)
}

const GLYPH_W: u32 = 5;
const GLYPH_H: u32 = 7;

/// A 5 x 7 glyph, rows from the top, bit 4 the leftmost column; `None` for a character
/// this font lacks.
fn glyph(c: char) -> Option<[u8; 7]> {
    Some(match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        '.' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C],
        '+' => [0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00],
        'A' => [0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x19, 0x15, 0x13, 0x11, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        ' ' => [0; 7],
        _ => return None,
    })
}

/// Draws `text` in white into `film` from `(x, row)` (its top-left corner), each glyph
/// pixel a `scale` x `scale` square, clipped to the film.
fn draw_text(film: &mut Film, text: &str, x: u32, row: u32, scale: u32) {
    for (i, c) in text.chars().enumerate() {
        let Some(rows) = glyph(c) else { continue };
        let left = x + i as u32 * (GLYPH_W + 1) * scale;
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..GLYPH_W {
                if bits & (1 << (GLYPH_W - 1 - col)) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (px, py) = (left + col * scale + dx, row + r as u32 * scale + dy);
                        if px < film.width && py < film.height {
                            film.pixels[(py * film.width + px) as usize] = Vec3::ONE;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_note_line_reads_back() {
        for counter in Counter::ALL {
            for rays in [CostRays::All, CostRays::Primary] {
                let map = CostMap { counter, rays };
                let line = map.note_line("bvh sah", RenderMode::Scalar);
                assert!(line.ends_with("(bvh sah, scalar mode)"), "{line}");
                let note = format!("p3trace\nscene: x\n{line}\ntile: 0/2");
                assert_eq!(CostMap::from_note(&note), Ok(Some(map)));
            }
        }
        assert_eq!(CostMap::from_note("p3trace\nskybox: no"), Ok(None));
        assert!(CostMap::from_note("cost: rays per pixel, all rays (grid, stream mode)").is_err());
    }

    #[test]
    fn viridis_runs_from_purple_to_yellow_and_clamps() {
        assert_eq!(viridis(0.0), Vec3::from_array(VIRIDIS[0]));
        assert_eq!(viridis(1.0), Vec3::from_array(VIRIDIS[16]));
        assert_eq!(viridis(2.0), viridis(1.0));
        assert_eq!(viridis(-1.0), viridis(0.0));
        assert_eq!(viridis(f32::NAN), viridis(0.0));
        // Brighter all the way up: perceptually ordered.
        let luma = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let steps: Vec<f32> = (0..=64).map(|k| luma(viridis(k as f32 / 64.0))).collect();
        assert!(steps.windows(2).all(|w| w[1] > w[0]), "{steps:?}");
    }

    #[test]
    fn the_picture_has_the_image_then_its_scale() {
        let mut film = Film::new(64, 100);
        for (i, p) in film.pixels.iter_mut().enumerate() {
            *p = Vec3::splat((i % 64) as f32);
        }
        let map = CostMap {
            counter: Counter::Prims,
            rays: CostRays::All,
        };
        let picture = picture(&film, &map, Scale::default());
        assert_eq!(picture.height, 100);
        assert!(picture.width > 64 + 30, "{}", picture.width);
        // The image's pixels on the scale, its largest count at the top.
        assert_eq!(picture.get(0, 0), viridis(0.0));
        assert_eq!(picture.get(63, 50), viridis(1.0));
        // A fixed scale saturates larger counts.
        let fixed = Scale {
            max: Some(32.0),
            log: false,
        };
        let fixed = super::picture(&film, &map, fixed);
        assert_eq!(fixed.get(32, 0), viridis(1.0));
        assert_eq!(fixed.get(63, 0), viridis(1.0));
        assert_eq!(fixed.get(16, 0), viridis(0.5));
        // On a log scale, 0 is still the bottom, and the geometric middle the middle.
        let log = Scale {
            max: Some(63.0),
            log: true,
        };
        let log = super::picture(&film, &map, log);
        assert_eq!(log.get(0, 0), viridis(0.0));
        assert_eq!(log.get(63, 0), viridis(1.0));
        assert!((log.get(7, 0) - viridis(0.5)).abs().max_element() < 1e-6);
        // The strip holds white text.
        let mut strip = (64..picture.width).flat_map(|x| (0..100).map(move |y| (x, y)));
        assert!(strip.any(|(x, y)| picture.get(x, y) == Vec3::ONE));
        // Every character of the labels it draws is in the font.
        for c in Counter::ALL {
            assert!(c
                .name()
                .to_ascii_uppercase()
                .chars()
                .all(|c| glyph(c).is_some()));
        }
        assert!("0123456789.+ LOG".chars().all(|c| glyph(c).is_some()));
    }
}
