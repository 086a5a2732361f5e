//! Progress reporting: a trait the library calls and the CLI implements (with indicatif).
//! The library never prints.

/// Receives progress of long work. Returning `false` asks the work to stop as soon as it
/// can; it then returns [`crate::Error::Cancelled`].
pub trait Progress: Send + Sync {
    /// `done` of `total` units of `stage` are finished (e.g. `"layer 02 body"`, 17, 120).
    fn update(&self, stage: &str, done: usize, total: usize) -> bool;
}

impl<F: Fn(&str, usize, usize) -> bool + Send + Sync> Progress for F {
    fn update(&self, stage: &str, done: usize, total: usize) -> bool {
        self(stage, done, total)
    }
}

/// A [`Progress`] that ignores updates and never cancels.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn update(&self, _: &str, _: usize, _: usize) -> bool {
        true
    }
}
