//! A small process-wide store of expensive, immutable set-ups (the exact
//! sampler's flow tables of a law and Sigma), so that the points of a sweep
//! or a figure that share a medium build them once.
//!
//! Entries are keyed by a string that determines the value completely (the
//! law's `Debug` text, which prints every parameter to round-trip
//! precision, and the bit patterns of the other inputs): a hit returns a
//! clone of exactly what a fresh build would return, so results do not
//! depend on what ran before. The store keeps the [`CAPACITY`] most recently
//! used entries.

use std::any::Any;
use std::sync::{Arc, Mutex, OnceLock};

/// Entries kept (each a few hundred kB at most).
pub const CAPACITY: usize = 16;

type Entry = (String, Arc<dyn Any + Send + Sync>);

fn store() -> &'static Mutex<Vec<Entry>> {
    static STORE: OnceLock<Mutex<Vec<Entry>>> = OnceLock::new();
    STORE.get_or_init(|| Mutex::new(Vec::new()))
}

/// The value stored under `key`, or `build()`'s, stored when it is Ok.
/// The lock is not held while building (two threads may both build the
/// same value; either copy is stored, and they are equal).
pub fn shared<T, E>(key: String, build: impl FnOnce() -> Result<T, E>) -> Result<Arc<T>, E>
where
    T: Send + Sync + 'static,
{
    if let Some(v) = lookup::<T>(&key) {
        return Ok(v);
    }
    let v = Arc::new(build()?);
    let mut s = store().lock().unwrap_or_else(|e| e.into_inner());
    s.retain(|(k, _)| *k != key);
    if s.len() >= CAPACITY {
        s.remove(0);
    }
    s.push((key, v.clone()));
    Ok(v)
}

/// A stored value of type T under `key`, marked most recently used.
fn lookup<T: Send + Sync + 'static>(key: &str) -> Option<Arc<T>> {
    let mut s = store().lock().unwrap_or_else(|e| e.into_inner());
    let i = s.iter().position(|(k, _)| k == key)?;
    let entry = s.remove(i);
    let hit = entry.1.clone().downcast::<T>().ok();
    s.push(entry);
    hit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_once_per_key_and_keeps_the_recent_ones() {
        let builds = std::cell::Cell::new(0);
        let get = |k: &str| {
            shared::<String, ()>(format!("memo-test {k}"), || {
                builds.set(builds.get() + 1);
                Ok(k.to_uppercase())
            })
            .unwrap()
        };
        assert_eq!(*get("a"), "A");
        assert_eq!(*get("a"), "A");
        assert_eq!(*get("b"), "B");
        assert_eq!(builds.get(), 2);
        // A failed build stores nothing.
        let e = shared::<String, &str>("memo-test fail".into(), || Err("no"));
        assert_eq!(e.unwrap_err(), "no");
        assert!(lookup::<String>("memo-test fail").is_none());
        // The same key with another type is a miss, not a wrong value.
        assert!(lookup::<u64>("memo-test a").is_none());
    }
}
