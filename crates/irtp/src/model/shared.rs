//! Laws compiled from their spec text (an expression drag, a hazard or
//! tabulated reset clock), shared while in use: parsing a text again while
//! a copy of its law lives gives that law (one compilation, one cache of
//! its own), and a law no copy holds any more is freed. The laws are `Arc`
//! inside their `Clone` types, so [`crate::Params`] is `Clone` without
//! leaking what a long session (a sweep, a Python kernel) parses.

use crate::error::Result;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock, Weak};

/// The laws of one kind in use, by their canonical text.
pub(crate) struct Shared<T>(OnceLock<Mutex<HashMap<String, Weak<T>>>>);

impl<T> Shared<T> {
    /// An empty table (for a `static`).
    pub const fn new() -> Self {
        Shared(OnceLock::new())
    }

    /// The law of `text` in use, else `compile()` shared from now on (the
    /// table's lock held meanwhile, so a text compiles once). Entries of
    /// freed laws are dropped here.
    pub fn get_or_compile(
        &self,
        text: &str,
        compile: impl FnOnce() -> Result<T>,
    ) -> Result<Arc<T>> {
        let table = self.0.get_or_init(|| Mutex::new(HashMap::new()));
        let mut laws = table.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(law) = laws.get(text).and_then(Weak::upgrade) {
            return Ok(law);
        }
        laws.retain(|_, law| law.strong_count() > 0);
        let law = Arc::new(compile()?);
        laws.insert(text.to_string(), Arc::downgrade(&law));
        Ok(law)
    }
}
