//! How far a render has got, on stderr: a bar on a terminal, plain lines elsewhere (a
//! farm's log, CI), where a bar would print nothing until the end.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use crate::plural::count;

/// How a render shows its progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    Hidden,
    /// A bar that redraws itself, for a terminal.
    Bar,
    /// Plain lines, for a render that lasts a few seconds (the rule: `due`).
    Lines,
}

/// A render shorter than this prints no progress line: the closing line says it all.
pub const QUIET_START: Duration = Duration::from_secs(3);
/// The shortest wait between two progress lines.
pub const LINE_GAP: Duration = Duration::from_secs(3);
/// The longest wait between two progress lines, while tiles finish.
pub const LINE_INTERVAL: Duration = Duration::from_secs(10);

/// Counts finished tiles and shows them as `Progress` asks.
pub struct Meter {
    bar: ProgressBar,
    lines: Option<Lines>,
}

struct Lines {
    total: usize,
    done: AtomicUsize,
    start: Instant,
    /// When the last line was printed (the start before any), from the start, and the
    /// tenth of the tiles it reached.
    last: Mutex<(Duration, usize)>,
}

impl Meter {
    pub fn new(progress: Progress, tiles: usize) -> Self {
        let bar = if progress == Progress::Bar {
            let bar = ProgressBar::new(tiles as u64);
            bar.set_style(
                ProgressStyle::with_template(
                    "{elapsed_precise} [{wide_bar}] {percent:>3}% eta {eta}",
                )
                .expect("the template is valid"),
            );
            bar
        } else {
            ProgressBar::hidden()
        };
        let start = Instant::now();
        let lines = (progress == Progress::Lines).then(|| Lines {
            total: tiles.max(1),
            done: AtomicUsize::new(0),
            start,
            last: Mutex::new((Duration::ZERO, 0)),
        });
        Meter { bar, lines }
    }

    /// One more tile is done.
    pub fn tile_done(&self) {
        self.bar.inc(1);
        if let Some(lines) = &self.lines {
            lines.tile_done();
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Lines {
    fn tile_done(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        let tenth = done * 10 / self.total;
        let elapsed = self.start.elapsed();
        let mut last = self.last.lock().unwrap_or_else(PoisonError::into_inner);
        let (printed_at, printed_tenth) = *last;
        if due(elapsed, elapsed - printed_at, tenth > printed_tenth) {
            *last = (elapsed, tenth.max(printed_tenth));
            eprintln!("{}", self.line(done, elapsed));
        }
    }

    /// `progress: 40% (120 of 300 tiles), 1.2 s elapsed, about 1.8 s left`.
    fn line(&self, done: usize, elapsed: Duration) -> String {
        let share = done as f64 / self.total as f64;
        let seconds = elapsed.as_secs_f64();
        let left = if done > 0 {
            seconds * (1.0 - share) / share
        } else {
            0.0
        };
        format!(
            "progress: {:.0}% ({done} of {}), {seconds:.1} s elapsed, about {left:.1} s left",
            100.0 * share,
            count(self.total as u64, "tile", "tiles")
        )
    }
}

/// Whether a tile finished `elapsed` into the render prints a line, `since` the last one
/// (or the start), where it reaches a tenth of the tiles that no line has (`new_tenth`):
/// a log shows a render that lasts at every tenth of its tiles, at least every
/// [`LINE_INTERVAL`], at most every [`LINE_GAP`], and one shorter than [`QUIET_START`] not
/// at all.
fn due(elapsed: Duration, since: Duration, new_tenth: bool) -> bool {
    elapsed >= QUIET_START && since >= LINE_GAP && (new_tenth || since >= LINE_INTERVAL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_say_the_share_done_and_estimate_what_is_left() {
        let lines = Lines {
            total: 300,
            done: AtomicUsize::new(0),
            start: Instant::now(),
            last: Mutex::new((Duration::ZERO, 0)),
        };
        assert_eq!(
            lines.line(120, Duration::from_secs_f64(1.2)),
            "progress: 40% (120 of 300 tiles), 1.2 s elapsed, about 1.8 s left"
        );
        let one = Lines { total: 1, ..lines };
        assert_eq!(
            one.line(1, Duration::from_secs(4)),
            "progress: 100% (1 of 1 tile), 4.0 s elapsed, about 0.0 s left"
        );
    }

    /// When `tiles` tiles finish at the times `finish` gives (in seconds), the times of
    /// the lines printed, as [`Lines::tile_done`] decides.
    fn schedule(tiles: usize, finish: impl Fn(usize) -> f64) -> Vec<f64> {
        let (mut printed_at, mut printed_tenth) = (0.0, 0);
        let mut lines = Vec::new();
        for done in 1..=tiles {
            let (at, tenth) = (finish(done), done * 10 / tiles);
            let since = Duration::from_secs_f64(at - printed_at);
            if due(Duration::from_secs_f64(at), since, tenth > printed_tenth) {
                (printed_at, printed_tenth) = (at, tenth.max(printed_tenth));
                lines.push(at);
            }
        }
        lines
    }

    #[test]
    fn a_log_shows_renders_that_last_and_no_more_than_a_line_every_few_seconds() {
        // 300 tiles in 2 s: nothing; in 20 s: from 3 s on, at every tenth that is 3 s or
        // more after the last line.
        assert!(schedule(300, |done| done as f64 * 2.0 / 300.0).is_empty());
        let lines = schedule(300, |done| done as f64 * 20.0 / 300.0);
        assert_eq!(lines.len(), 6, "{lines:?}");
        assert!(lines[0] >= 3.0 && lines[0] < 4.1, "{lines:?}");
        assert!(lines.windows(2).all(|w| w[1] - w[0] >= 3.0), "{lines:?}");
        // One tile a second after a long first one: no new tenth for a while, yet a line
        // at least every 10 s.
        let lines = schedule(1000, |done| 30.0 + done as f64);
        assert!(lines
            .windows(2)
            .all(|w| (3.0..=10.0).contains(&(w[1] - w[0]))));
        assert!(lines.len() >= 100, "{}", lines.len());
    }
}
