//! A memo of the design's FE parts, for runs that repeat them: the envelope's corners and the
//! search's variants share the work table's modal run (one per table geometry), the leaf's FE
//! statics (one per leaf geometry, material and thickness) and the coil's.
//!
//! Each entry is keyed by the serialized inputs the part reads (nothing else), so a hit returns
//! exactly what the computation would: a corner run with memoised parts equals a run from
//! scratch. The memo is process-wide and bounded ([`MAX_ENTRIES`]; when full it starts over);
//! [`clear`] empties it and [`stats`] counts the parts reused and computed.
//!
//! The 3D machine's assembled model without its leaves and magnets (one per geometry and load,
//! tens of megabytes each) is kept in a second, smaller memo ([`get_or_large`], at most
//! [`MAX_LARGE`] entries; [`large_stats`] counts it).

use crate::Result;
use std::any::Any;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Entries kept at most (a table's modal run is the largest, some megabytes).
pub const MAX_ENTRIES: usize = 64;

#[derive(Default)]
struct Memo {
    map: HashMap<String, Arc<dyn Any + Send + Sync>>,
    /// Requests, and entries stored. Two threads may compute the same entry at once (neither
    /// waits for the other: a thread of the pool blocked on another's entry could be the one
    /// that entry's computation waits for); only the first stores it, so `stored` counts the
    /// distinct parts and `requests − stored` the further requests, whatever the threads'
    /// timing (each computation counted before). The counts are process-wide: work running
    /// alongside (the design search beside the envelope) adds its own.
    requests: usize,
    stored: usize,
}

/// Entries kept at most in the memo of large models ([`get_or_large`]).
pub const MAX_LARGE: usize = 8;

fn memo() -> &'static Mutex<Memo> {
    static M: OnceLock<Mutex<Memo>> = OnceLock::new();
    M.get_or_init(|| Mutex::new(Memo::default()))
}

fn large() -> &'static Mutex<Memo> {
    static M: OnceLock<Mutex<Memo>> = OnceLock::new();
    M.get_or_init(|| Mutex::new(Memo::default()))
}

/// The key of `kind` computed from `inputs` (their JSON text: f64 values print exactly).
pub fn key<T: serde::Serialize + ?Sized>(kind: &str, inputs: &T) -> String {
    format!(
        "{kind}:{}",
        serde_json::to_string(inputs).unwrap_or_else(|e| format!("unserializable {e}"))
    )
}

/// The value stored under `key`, or `compute()` stored there. The computation runs outside the
/// lock (two threads may compute the same entry; both get the same value).
pub fn get_or<T, F>(key: String, compute: F) -> Result<Arc<T>>
where
    T: Any + Send + Sync,
    F: FnOnce() -> Result<T>,
{
    get_or_in(memo(), MAX_ENTRIES, key, compute)
}

/// [`get_or`] in the memo of large models (at most [`MAX_LARGE`] entries).
pub fn get_or_large<T, F>(key: String, compute: F) -> Result<Arc<T>>
where
    T: Any + Send + Sync,
    F: FnOnce() -> Result<T>,
{
    get_or_in(large(), MAX_LARGE, key, compute)
}

fn get_or_in<T, F>(memo: &Mutex<Memo>, max: usize, key: String, compute: F) -> Result<Arc<T>>
where
    T: Any + Send + Sync,
    F: FnOnce() -> Result<T>,
{
    {
        let mut m = memo.lock().unwrap_or_else(|e| e.into_inner());
        m.requests += 1;
        if let Some(v) = m.map.get(&key).cloned() {
            if let Ok(v) = v.downcast::<T>() {
                return Ok(v);
            }
        }
    }
    let v = Arc::new(compute()?);
    let mut m = memo.lock().unwrap_or_else(|e| e.into_inner());
    if m.map.get(&key).is_some_and(|e| e.is::<T>()) {
        // Another thread stored it meanwhile (the same value: the same inputs).
        return Ok(v);
    }
    if m.map.len() >= max {
        m.map.clear();
    }
    m.map.insert(key, v.clone());
    m.stored += 1;
    Ok(v)
}

/// Empty the memo (the next parts are computed afresh).
pub fn clear() {
    for memo in [memo(), large()] {
        memo.lock().unwrap_or_else(|e| e.into_inner()).map.clear();
    }
}

/// (parts reused, parts computed and stored) since the process started ([`Memo`]).
pub fn stats() -> (usize, usize) {
    counts(memo())
}

/// The same for the memo of large models.
pub fn large_stats() -> (usize, usize) {
    counts(large())
}

fn counts(memo: &Mutex<Memo>) -> (usize, usize) {
    let m = memo.lock().unwrap_or_else(|e| e.into_inner());
    (m.requests.saturating_sub(m.stored), m.stored)
}

/// A copy of a modal run (its fields are all data).
pub fn clone_run(r: &crate::analysis::modal::ModalRun) -> crate::analysis::modal::ModalRun {
    crate::analysis::modal::ModalRun {
        report: r.report.clone(),
        shapes: r.shapes.clone(),
        lambda: r.lambda.clone(),
        vectors: r.vectors.clone(),
        model: r.model.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two threads asking for the same part at once both compute it (neither waits), but it is
    /// stored and counted once: one computed, one further request, whatever the timing (each
    /// computation counted as a miss before, so the envelope's counts varied from run to run).
    #[test]
    fn a_part_computed_twice_at_once_counts_once() {
        let memo = Mutex::new(Memo::default());
        let barrier = std::sync::Barrier::new(2);
        let values: Vec<f64> = std::thread::scope(|s| {
            let ask = || {
                *get_or_in(&memo, MAX_ENTRIES, "part".into(), || {
                    // Both threads are inside the computation before either stores it.
                    barrier.wait();
                    Ok(2.5f64)
                })
                .unwrap()
            };
            let (a, b) = (s.spawn(ask), s.spawn(ask));
            vec![a.join().unwrap(), b.join().unwrap()]
        });
        assert_eq!(values, [2.5, 2.5]);
        assert_eq!(counts(&memo), (1, 1));
        let again = get_or_in(&memo, MAX_ENTRIES, "part".into(), || Ok(0.0f64)).unwrap();
        assert_eq!(*again, 2.5);
        assert_eq!(counts(&memo), (2, 1));
    }
}
