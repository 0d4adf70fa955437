//! Counts and differences drawn in false colour: a cost image's counts on viridis with
//! its colour bar and scale ([`picture`]), and `compare`'s differences on a heat ramp
//! ([`heat`]).

use glam::Vec3;

use super::font::{draw_text, GLYPH_H, GLYPH_W};
use super::Film;

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

/// The false-colour picture of the counts in `film`'s first channel: each count on
/// viridis from 0 to the top of `scale` (counts above it take its colour, and its label
/// says so with a `+`), and to its right a strip with `name` (what is counted, in
/// capitals), the colour bar and the counts at its ticks.
pub fn picture(film: &Film, name: &str, scale: Scale) -> Film {
    let top = scale.top(film);
    let beyond = film.pixels.iter().any(|p| p.x > top);
    let mut labels: Vec<String> = TICKS
        .iter()
        .map(|&t| count_label(scale.count_at(t, top), top))
        .collect();
    if beyond {
        labels[TICKS.len() - 1].push('+');
    }
    let mut title = name.to_ascii_uppercase();
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

/// The heat ramp's colours at 0, 1/4, 1/2, 3/4 and 1 of the full scale: black, blue, red,
/// yellow, white, each brighter than the one before.
const HEAT_RAMP: [Vec3; 5] = [
    Vec3::ZERO,
    Vec3::new(0.0, 0.0, 1.0),
    Vec3::new(1.0, 0.0, 0.0),
    Vec3::new(1.0, 1.0, 0.0),
    Vec3::ONE,
];

/// The least share of the full scale that a differing pixel is drawn at: one level of
/// blue, so that black means equal however small the difference.
const LEAST_VISIBLE: f32 = 1.0 / (4.0 * 255.0);

/// The heat ramp's colour at `share` of the full scale, white from 1 on; black for 0 and
/// for NaN (equal images' 0 / 0).
pub fn heat(share: f32) -> Vec3 {
    if !(share > 0.0) {
        return HEAT_RAMP[0];
    }
    let position = share.clamp(LEAST_VISIBLE, 1.0) * 4.0;
    let step = (position as usize).min(3);
    HEAT_RAMP[step].lerp(HEAT_RAMP[step + 1], position - step as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let picture = picture(&film, "prims", Scale::default());
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
        let fixed = super::picture(&film, "prims", fixed);
        assert_eq!(fixed.get(32, 0), viridis(1.0));
        assert_eq!(fixed.get(63, 0), viridis(1.0));
        assert_eq!(fixed.get(16, 0), viridis(0.5));
        // On a log scale, 0 is still the bottom, and the geometric middle the middle.
        let log = Scale {
            max: Some(63.0),
            log: true,
        };
        let log = super::picture(&film, "prims", log);
        assert_eq!(log.get(0, 0), viridis(0.0));
        assert_eq!(log.get(63, 0), viridis(1.0));
        assert!((log.get(7, 0) - viridis(0.5)).abs().max_element() < 1e-6);
        // The strip holds white text.
        let mut strip = (64..picture.width).flat_map(|x| (0..100).map(move |y| (x, y)));
        assert!(strip.any(|(x, y)| picture.get(x, y) == Vec3::ONE));
    }

    #[test]
    fn heat_ramp_rises_through_blue_red_and_yellow() {
        assert_eq!(heat(0.0), Vec3::ZERO);
        assert_eq!(heat(0.25), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(heat(0.5), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(heat(0.75), Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(heat(1.0), Vec3::ONE);
        // Brighter at every step, by Rec. 709 luminance.
        let luminance = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let steps: Vec<f32> = (0..=100)
            .map(|i| luminance(heat(i as f32 / 100.0)))
            .collect();
        assert!(steps.windows(2).all(|w| w[0] < w[1]), "{steps:?}");
    }
}
