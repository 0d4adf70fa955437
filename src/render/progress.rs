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
    /// A line every [`LINE_INTERVAL`] or every tenth of the tiles, whichever comes first.
    Lines,
}

/// The longest wait between two progress lines.
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
    /// When the last line was printed, and the tenth of the tiles it reached.
    last: Mutex<(Instant, usize)>,
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
            last: Mutex::new((start, 0)),
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
        let now = Instant::now();
        let mut last = self.last.lock().unwrap_or_else(PoisonError::into_inner);
        let (printed_at, printed_tenth) = *last;
        if tenth > printed_tenth || now - printed_at >= LINE_INTERVAL {
            *last = (now, tenth.max(printed_tenth));
            eprintln!("{}", self.line(done, now - self.start));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_say_the_share_done_and_estimate_what_is_left() {
        let lines = Lines {
            total: 300,
            done: AtomicUsize::new(0),
            start: Instant::now(),
            last: Mutex::new((Instant::now(), 0)),
        };
        assert_eq!(
            lines.line(120, Duration::from_secs_f64(1.2)),
            "progress: 40% (120 of 300 tiles), 1.2 s elapsed, about 1.8 s left"
        );
    }
}
