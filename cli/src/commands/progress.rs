//! Progress of a bake on stderr: a bar on a terminal; otherwise (stderr redirected, or
//! `--json`) a plain line at most every few seconds, so that a log or a script shows the bake
//! moving instead of minutes of silence.

use std::cell::Cell;
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Seconds between plain progress lines unless `CAVECLOD_PROGRESS_INTERVAL` sets them.
const LINE_INTERVAL: f64 = 2.0;

/// Where progress goes.
pub enum Progress {
    /// A bar drawn on the terminal.
    Bar(ProgressBar),
    /// Plain lines, at most one per `interval`.
    Lines {
        /// Least time between two lines.
        interval: Duration,
        /// When the last line was written (the start at first).
        last: Cell<Instant>,
        /// What is counted (`collapses`, `triangles`).
        unit: &'static str,
    },
}

impl Progress {
    /// A bar drawn with `template` when stderr is a terminal and `plain` is false; plain
    /// lines counting `unit` otherwise.
    pub fn new(template: &str, unit: &'static str, plain: bool) -> Result<Self, String> {
        if plain || !std::io::stderr().is_terminal() {
            Ok(Self::Lines {
                interval: line_interval()?,
                last: Cell::new(Instant::now()),
                unit,
            })
        } else {
            progress_bar(template).map(Self::Bar)
        }
    }

    /// Shows the step `what`, with `(done, total)` when it counts.
    pub fn show(&self, what: &str, count: Option<(u64, u64)>) {
        match self {
            Self::Bar(bar) => {
                bar.set_message(what.to_string());
                if let Some((done, total)) = count {
                    bar.set_length(total);
                    bar.set_position(done);
                }
            }
            Self::Lines {
                interval,
                last,
                unit,
            } => {
                let now = Instant::now();
                if now.duration_since(last.get()) < *interval {
                    return;
                }
                last.set(now);
                // A closed stderr is no reason to fail the bake.
                let _ = writeln!(std::io::stderr().lock(), "{}", line(what, count, unit));
            }
        }
    }

    /// Clears the bar; plain lines stay.
    pub fn finish(&self) {
        if let Self::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}

/// The interval from `CAVECLOD_PROGRESS_INTERVAL` (seconds, 0 for every update), or
/// [`LINE_INTERVAL`].
fn line_interval() -> Result<Duration, String> {
    match std::env::var("CAVECLOD_PROGRESS_INTERVAL") {
        Err(_) => Ok(Duration::from_secs_f64(LINE_INTERVAL)),
        Ok(s) => s
            .trim()
            .parse::<f64>()
            .ok()
            .and_then(|x| Duration::try_from_secs_f64(x).ok())
            .ok_or_else(|| format!("CAVECLOD_PROGRESS_INTERVAL: '{s}' is not a number of seconds")),
    }
}

/// `bake: hierarchy 53,850/60,737 collapses (88%)`, or `bake: welding` without a count.
pub fn line(what: &str, count: Option<(u64, u64)>, unit: &str) -> String {
    match count {
        Some((done, total)) => {
            let percent = if total == 0 {
                100
            } else {
                (u128::from(done) * 100 / u128::from(total)) as u64
            };
            format!(
                "bake: {what} {}/{} {unit} ({percent}%)",
                grouped(done),
                grouped(total)
            )
        }
        None => format!("bake: {what}"),
    }
}

/// `n` with a comma between groups of three digits.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A progress bar drawn with `template`.
pub fn progress_bar(template: &str) -> Result<ProgressBar, String> {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(template)
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    Ok(bar)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_name_the_step_and_group_the_digits() {
        assert_eq!(
            line("hierarchy", Some((53_850, 60_737)), "collapses"),
            "bake: hierarchy 53,850/60,737 collapses (88%)"
        );
        assert_eq!(
            line("hierarchy", Some((0, 0)), "collapses"),
            "bake: hierarchy 0/0 collapses (100%)"
        );
        assert_eq!(line("welding", None, "collapses"), "bake: welding");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(1_234_567), "1,234,567");
    }
}
