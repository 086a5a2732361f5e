//! Progress bars on a terminal (nothing under `--quiet` or when stderr is not a terminal).

use fluidymation::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// One bar, or nothing.
pub struct Bars {
    bar: Option<ProgressBar>,
}

impl Bars {
    /// A bar of `total` steps.
    pub fn new(quiet: bool, total: u64) -> Bars {
        if quiet || !std::io::stderr().is_terminal() {
            return Bars { bar: None };
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{bar:40.cyan/blue} {pos}/{len} {msg} [{elapsed_precise} < {eta}]")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Bars { bar: Some(bar) }
    }

    /// Advances by `n`.
    pub fn inc(&self, n: u64) {
        if let Some(b) = &self.bar {
            b.inc(n);
        }
    }

    /// Sets the message after the bar.
    pub fn set_message(&self, m: String) {
        if let Some(b) = &self.bar {
            b.set_message(m);
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// The library's progress as one bar: its length and position follow the reports, its
/// message names the stage.
impl Progress for Bars {
    fn update(&self, stage: &str, done: usize, total: usize) -> bool {
        if let Some(b) = &self.bar {
            b.set_length(total as u64);
            b.set_position(done as u64);
            b.set_message(stage.to_string());
        }
        true
    }
}
