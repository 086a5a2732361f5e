//! Command implementations; each subcommand has its own file with its `Args` and `run`.

pub mod bench;
pub mod eval;
pub mod exemplar;
pub mod inspect;
pub mod jobs;
pub mod params;
pub mod plan;
pub mod progress;
pub mod quality;
pub mod render;
pub mod synth;
pub mod workload;

use std::io::Write;
use std::process::ExitCode;

/// Options shared by every command.
#[derive(Clone, Debug)]
pub struct Ctx {
    /// `--quiet`: errors only.
    pub quiet: bool,
    /// `-v` count.
    #[allow(dead_code)]
    pub verbose: u8,
}

struct Logger {
    level: log::LevelFilter,
}

impl log::Log for Logger {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= self.level && metadata.target().starts_with("fluidymation")
    }
    fn log(&self, record: &log::Record) {
        if self.enabled(record.metadata()) {
            let label = match record.level() {
                log::Level::Error => "error",
                log::Level::Warn => "warning",
                log::Level::Info => "info",
                _ => "debug",
            };
            let _ = writeln!(std::io::stderr(), "{}: {}", label, record.args());
        }
    }
    fn flush(&self) {}
}

/// When the environment variable [`EXIT_WITH_PARENT`] is `1`, stops this process soon after
/// the process that started it has ended. A job scheduler sets it: a worker that dies must
/// not leave its job running on (the job is retried elsewhere; everything it writes is
/// written atomically, so stopping it anywhere loses at most the frame in progress).
pub fn exit_with_parent() {
    #[cfg(unix)]
    if std::env::var(EXIT_WITH_PARENT).is_ok_and(|v| v == "1") {
        let parent = std::os::unix::process::parent_id();
        std::thread::spawn(move || {
            loop {
                std::thread::sleep(std::time::Duration::from_millis(200));
                if std::os::unix::process::parent_id() != parent {
                    let _ = writeln!(
                        std::io::stderr(),
                        "error: the process that started this job ({parent}) has ended; stopping"
                    );
                    std::process::exit(1);
                }
            }
        });
    }
}

/// See [`exit_with_parent`].
pub const EXIT_WITH_PARENT: &str = "FLUIDYMATION_EXIT_WITH_PARENT";

/// Routes the library's `log` messages to stderr (`warning: …`).
pub fn init_logging(quiet: bool, verbose: u8) {
    let level = match (quiet, verbose) {
        (true, _) => log::LevelFilter::Error,
        (false, 0) => log::LevelFilter::Warn,
        (false, 1) => log::LevelFilter::Info,
        _ => log::LevelFilter::Debug,
    };
    if log::set_boxed_logger(Box::new(Logger { level })).is_ok() {
        log::set_max_level(level);
    }
}

/// The texts of an error and its causes, without a cause that the text before it already
/// said: some errors print their source as part of their own message ("'out': Not a
/// directory", a JSON error ending with serde_json's message and position).
fn chain_texts(err: &anyhow::Error) -> Vec<String> {
    let mut texts = vec![err.to_string()];
    let mut said = texts[0].clone();
    for cause in err.chain().skip(1) {
        let text = cause.to_string();
        if !said.ends_with(&text) {
            texts.push(text.clone());
        }
        said = text;
    }
    texts
}

/// An error and its causes on one line, `context: error: cause` like `{:#}`, without the
/// repeats [`report_error`] leaves out (a batch's summary line of a failed file).
pub fn one_line(err: &anyhow::Error) -> String {
    chain_texts(err).join(": ")
}

/// Prints `error: …` with its chain of causes; exit code 130 when cancelled, else 1.
pub fn report_error(err: &anyhow::Error) -> ExitCode {
    let mut stderr = std::io::stderr();
    let texts = chain_texts(err);
    let _ = writeln!(stderr, "error: {}", texts[0]);
    for text in &texts[1..] {
        let _ = writeln!(stderr, "  caused by: {}", text);
    }
    let cancelled =
        err.chain().any(|c| matches!(c.downcast_ref::<fluidymation::Error>(), Some(fluidymation::Error::Cancelled)));
    if cancelled { ExitCode::from(130) } else { ExitCode::from(1) }
}

/// Finds an exemplar by name (in `extra_dirs`, `FLUIDYMATION_EXEMPLARS`, the user's folder and
/// the bundled set) or by folder path.
pub fn find_exemplar(key: &str, extra_dirs: &[std::path::PathBuf]) -> anyhow::Result<fluidymation::exemplar::Exemplar> {
    use anyhow::Context;
    let search = fluidymation::exemplar::SearchPath::standard(extra_dirs);
    fluidymation::exemplar::find(key, &search).with_context(|| format!("could not load exemplar '{}'", key))
}
