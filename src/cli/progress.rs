//! Progress bars on a terminal, and Ctrl-C: one [`Bars`] for every command.

use fluidymation::Progress;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::HashMap;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// Progress bars on a terminal (none under `--quiet` or when stderr is not a terminal): one
/// per stage the library reports (a layer, a file of a batch, a run of the quality suite) and
/// the frames as a total with ETA. A Ctrl-C ([`handle_interrupts`]) makes the reports ask the
/// work to stop.
pub struct Bars {
    multi: Option<MultiProgress>,
    bars: Mutex<HashMap<String, ProgressBar>>,
}

impl Bars {
    /// Bars on stderr unless `quiet` or stderr is not a terminal.
    pub fn new(quiet: bool) -> Bars {
        let show = !quiet && std::io::stderr().is_terminal();
        Bars {
            multi: show.then(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr())),
            bars: Mutex::new(HashMap::new()),
        }
    }

    /// True once Ctrl-C was pressed ([`handle_interrupts`]).
    pub fn interrupted(&self) -> bool {
        INTERRUPTED.load(Ordering::SeqCst)
    }

    /// Removes every bar from the terminal. Bars that are only dropped draw themselves once
    /// more (indicatif's default), which left a stale bar above the summary or the error.
    pub fn clear(&self) {
        if let Ok(bars) = self.bars.lock() {
            for bar in bars.values() {
                bar.finish_and_clear();
            }
        }
        if let Some(m) = &self.multi {
            let _ = m.clear();
        }
    }
}

impl Progress for Bars {
    fn update(&self, stage: &str, done: usize, total: usize) -> bool {
        if let Some(multi) = &self.multi
            && let Ok(mut bars) = self.bars.lock()
        {
            let bar = bars.entry(stage.to_string()).or_insert_with(|| {
                let (template, bar) = if stage == "frames" {
                    (
                        "{prefix:>16.bold} {bar:30.green/blue} {pos}/{len} frames  {elapsed_precise} < {eta_precise}",
                        ProgressBar::new(total as u64),
                    )
                } else {
                    ("{prefix:>16} {bar:30.cyan/blue} {pos}/{len}", ProgressBar::new(total as u64))
                };
                let bar = multi.add(bar);
                bar.set_style(ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar()));
                let name: String = stage.chars().take(16).collect();
                bar.set_prefix(if stage == "frames" { "total".to_string() } else { name });
                bar
            });
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        }
        !self.interrupted()
    }
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Installs the Ctrl-C handler: the first Ctrl-C stops after the frame in progress
/// (resumable); a second one quits at once.
pub fn handle_interrupts() {
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
}
