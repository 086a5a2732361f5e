//! Many files in one run: several at once on the same cores, sharing the exemplars and their
//! prepared sources; a file that fails does not stop the others.

use super::{RenderOptions, RenderSummary, render_with, style_of_key};
use crate::anim::Animation;
use crate::error::Result;
use crate::exemplar::Exemplar;
use crate::progress::Progress;
use crate::synth::{Params, Source};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// One slot of a [`StyleCache`]: filled by the first file that needs it, while files that
/// need the same one wait for it instead of computing it again.
type Slot<T> = Arc<Mutex<Option<T>>>;

/// A prepared source is found by its exemplar (name and search folders) and parameters.
type SourceKey = (String, Params);

/// Exemplars and their prepared sources (guides and pyramid), shared by the files of a batch:
/// each is loaded or prepared once.
///
/// Use it from threads of your own, not from inside rayon tasks: a file waiting for another
/// to finish preparing an exemplar blocks its thread.
#[derive(Default)]
pub(crate) struct StyleCache {
    exemplars: Mutex<Vec<(String, Slot<Exemplar>)>>,
    sources: Mutex<Vec<(SourceKey, Slot<Source>)>>,
}

fn slot<K: PartialEq, T>(list: &Mutex<Vec<(K, Slot<T>)>>, key: K) -> Slot<T> {
    let mut list = list.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, s)) = list.iter().find(|(k, _)| *k == key) {
        return s.clone();
    }
    let s: Slot<T> = Arc::default();
    list.push((key, s.clone()));
    s
}

fn get_or_try<T: Clone>(slot: &Slot<T>, make: impl FnOnce() -> Result<T>) -> Result<T> {
    let mut value = slot.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(v) = value.as_ref() {
        return Ok(v.clone());
    }
    let v = make()?;
    *value = Some(v.clone());
    Ok(v)
}

impl StyleCache {
    /// An empty cache.
    pub(crate) fn new() -> StyleCache {
        StyleCache::default()
    }

    /// The exemplar of the style of `opts` whose key ([`Style::key`](super::Style::key)) is
    /// `name`, looked up in [`RenderOptions::exemplar_dirs`] and the standard places.
    pub fn exemplar(&self, name: &str, opts: &RenderOptions) -> Result<Exemplar> {
        let dirs = &opts.exemplar_dirs;
        let key = format!("{name}\u{0}{dirs:?}");
        get_or_try(&slot(&self.exemplars, key), || {
            style_of_key(opts, name).load(dirs)?.ok_or_else(|| crate::Error::param("style", name, "an exemplar"))
        })
    }

    /// The source of `exemplar` (found as `name` in `dirs`) prepared for `params`.
    pub fn source(&self, name: &str, exemplar: &Exemplar, params: &Params, dirs: &[PathBuf]) -> Result<Source> {
        let key = (format!("{name}\u{0}{dirs:?}"), params.clone());
        get_or_try(&slot(&self.sources, key), || Source::prepare(exemplar, params))
    }
}

/// Renders every `(animation, options, progress)` of `files`, at most `at_once` files at the
/// same time (each with its layers in parallel on the shared rayon pool), with one
/// cache of exemplars and prepared sources. Returns each file's result in the order given; an error in one file does
/// not stop the others.
///
/// The output of each file is the same as [`render`](super::render) alone gives.
pub fn render_batch(
    files: &[(&Animation, &RenderOptions, &dyn Progress)],
    at_once: usize,
) -> Vec<Result<RenderSummary>> {
    let cache = StyleCache::new();
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<Result<RenderSummary>>>> = files.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..at_once.clamp(1, files.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some((anim, opts, progress)) = files.get(i) else { break };
                    let r = render_with(anim, opts, &cache, *progress);
                    *results[i].lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
                }
            });
        }
    });
    results
        .into_iter()
        .map(|r| r.into_inner().unwrap_or_else(|e| e.into_inner()).unwrap_or(Err(crate::Error::Cancelled)))
        .collect()
}
