//! The fuzzing harness: deterministic cases from a seed, each written to a scratch folder and
//! read by its reader, with a time budget and a memory bound per case. A panic, a case over
//! [`time_limit`] (confirmed by a second run, the machine being shared) or a peak over
//! [`MEMORY_BOUND`] is a failure: its input is saved under `tests/fuzz/regressions/<reader>/`
//! and replayed by every normal test run afterwards ([`replay`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crate::alloc_support;

/// Most memory one case may allocate above what was in use before it.
pub const MEMORY_BOUND: usize = 512 << 20;

/// The time budget of one case: 2 s in release builds (debug builds are ~20× slower).
pub fn time_limit() -> Duration {
    if cfg!(debug_assertions) { Duration::from_secs(40) } else { Duration::from_secs(2) }
}

/// A long run prints its report so far after every this many cases.
const PROGRESS_EVERY: usize = 5_000;

/// A case that runs longer than this is stopped by ending the process (after saving it).
const HARD_LIMIT: Duration = Duration::from_secs(120);

/// SplitMix64: small, fast, and the same on every machine.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9e37_79b9_7f4a_7c15)
    }
    pub fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.u64() % n.max(1) as u64) as usize
    }
    /// Uniform in `lo..=hi`.
    pub fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.u64() % (hi - lo + 1) as u64) as i64
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        (self.u64() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
    pub fn f64(&mut self) -> f64 {
        (self.u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
    /// A number a hostile file would hold: ordinary, zero, negative, huge, tiny or not finite.
    pub fn hostile_f64(&mut self, ordinary: f64) -> f64 {
        match self.below(12) {
            0 => 0.0,
            1 => -ordinary,
            2 => 1e300,
            3 => -1e300,
            4 => 3.4e38,
            5 => 1e-300,
            6 => ordinary * 1e6,
            7 => f64::NAN,
            8 => f64::INFINITY,
            9 => -1.0,
            10 => (self.u64() % 100_000) as f64,
            _ => ordinary * (1.0 + self.f64()),
        }
    }
}

/// The input of one case: files by path relative to its folder.
pub type Files = Vec<(String, Vec<u8>)>;

/// A reader under test.
pub struct Reader {
    /// Folder name under `tests/fuzz/regressions/`.
    pub name: &'static str,
    /// Makes case number `case` of seed `seed`.
    pub make: fn(&mut Rng) -> Files,
    /// Reads the input in the folder; panics only when a property is violated.
    pub check: fn(&Path),
}

/// What a run found.
#[derive(Debug, Default)]
pub struct Report {
    pub cases: usize,
    pub failures: Vec<String>,
    pub slowest: (Duration, String),
    pub peak: usize,
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} cases, {} failures, slowest {:.3} s ({}), largest peak {:.1} MiB",
            self.cases,
            self.failures.len(),
            self.slowest.0.as_secs_f64(),
            self.slowest.1,
            self.peak as f64 / (1 << 20) as f64
        )
    }
}

/// One case at a time in the process, so that the allocation counters are the case's own.
pub fn exclusive() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz/regressions")
}

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("fm-fuzz-{}-{name}", std::process::id()))
}

fn write_files(dir: &Path, files: &Files) {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    for (name, bytes) in files {
        let p = dir.join(name);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).unwrap();
        }
        std::fs::write(&p, bytes).unwrap();
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if src.is_dir() {
            copy_dir(&src, &dst);
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}

/// Runs `check` on `dir` once: its time, its peak above the memory in use before, and the
/// panic message if it panicked.
fn measure(check: fn(&Path), dir: &Path) -> (Duration, usize, Option<String>) {
    let base = alloc_support::reset_peak();
    let t = Instant::now();
    let r = std::panic::catch_unwind(|| check(dir));
    let took = t.elapsed();
    let peak = alloc_support::peak().saturating_sub(base);
    let msg = r.err().map(|e| {
        e.downcast_ref::<String>()
            .cloned()
            .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default()
    });
    (took, peak, msg)
}

/// Judges one case in `dir`: `None` when it passed, else why it failed.
fn judge(reader: &Reader, dir: &Path, report: &mut Report, label: &str) -> Option<String> {
    let (mut took, peak, panic) = measure(reader.check, dir);
    if panic.is_none() && took > time_limit() {
        // Confirm: the machine is shared, one slow run may be someone else's load.
        took = took.min(measure(reader.check, dir).0);
    }
    report.cases += 1;
    report.peak = report.peak.max(peak);
    if took > report.slowest.0 {
        report.slowest = (took, label.to_string());
    }
    if let Some(p) = panic {
        return Some(format!("panicked: {p}"));
    }
    if took > time_limit() {
        return Some(format!("took {:.2} s (limit {:.0} s)", took.as_secs_f64(), time_limit().as_secs_f64()));
    }
    if peak > MEMORY_BOUND {
        return Some(format!("allocated {} MiB (bound {} MiB)", peak >> 20, MEMORY_BOUND >> 20));
    }
    None
}

/// The watchdog of a hanging case: saves it and ends the process after [`HARD_LIMIT`].
struct Watch {
    done: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Watch {
    fn start(dir: PathBuf, save_to: PathBuf) -> Watch {
        let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let d = done.clone();
        std::thread::spawn(move || {
            let t = Instant::now();
            while !d.load(Ordering::Relaxed) {
                if t.elapsed() > HARD_LIMIT {
                    copy_dir(&dir, &save_to);
                    eprintln!("a fuzz case hangs; saved as {}", save_to.display());
                    std::process::exit(101);
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        });
        Watch { done }
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Relaxed);
    }
}

/// The seed of this run: `FM_FUZZ_SEED`, else a new one (printed, so a run can be repeated).
pub fn seed() -> u64 {
    match std::env::var("FM_FUZZ_SEED") {
        Ok(s) => s.parse().expect("FM_FUZZ_SEED must be a number"),
        Err(_) => std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(1, |d| d.as_nanos() as u64),
    }
}

fn case_files(reader: &Reader, seed: u64, case: usize) -> Files {
    let case_seed = seed.wrapping_mul(0x100_0000_01b3).wrapping_add(case as u64);
    (reader.make)(&mut Rng::new(case_seed))
}

/// Writes the input of case `case` of `seed` into `dir`.
pub fn dump(reader: &Reader, seed: u64, case: usize, dir: &Path) {
    write_files(dir, &case_files(reader, seed, case));
}

/// Runs `cases` new cases of `reader` from `seed`; failures are saved as regressions.
pub fn run(reader: &Reader, seed: u64, cases: usize) -> Report {
    let _one = exclusive();
    let dir = scratch(reader.name);
    let mut report = Report::default();
    for case in 0..cases {
        let files = case_files(reader, seed, case);
        write_files(&dir, &files);
        let label = format!("seed {seed} case {case}");
        let save_to = root().join(reader.name).join(format!("{seed}-{case}"));
        let watch = Watch::start(dir.clone(), save_to.clone());
        let failed = judge(reader, &dir, &mut report, &label);
        drop(watch);
        if let Some(why) = failed {
            write_files(&save_to, &files);
            report.failures.push(format!("{label}: {why} (saved as {})", save_to.display()));
        }
        // A long run says how far it is (with --nocapture), so that a stopped one still counts.
        if (case + 1) % PROGRESS_EVERY == 0 && case + 1 < cases {
            eprintln!("fuzz {} (seed {seed}) so far: {report}", reader.name);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!("fuzz {}: {report}", reader.name);
    report
}

/// Replays every saved regression input of `reader` (each a folder under
/// `tests/fuzz/regressions/<reader>/`) under the same budget.
pub fn replay(reader: &Reader) -> Report {
    let _one = exclusive();
    let mut report = Report::default();
    let Ok(rd) = std::fs::read_dir(root().join(reader.name)) else { return report };
    let mut cases: Vec<PathBuf> = rd.flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
    cases.sort();
    let dir = scratch(&format!("{}-replay", reader.name));
    // Making a case warms up what a reader builds once (the resume reader's reference render),
    // so that it is not counted in the first replayed case's time.
    if !cases.is_empty() {
        (reader.make)(&mut Rng::new(0));
    }
    for case in cases {
        // A copy: a reader may write into its input (caches, resumed renders).
        let _ = std::fs::remove_dir_all(&dir);
        copy_dir(&case, &dir);
        let label = case.file_name().unwrap_or_default().to_string_lossy().into_owned();
        if let Some(why) = judge(reader, &dir, &mut report, &label) {
            report.failures.push(format!("{}: {why}", case.display()));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    report
}
