//! The `irtp` command line: parse flags, validate into library configs, run,
//! print JSON / write files. All printing and exit codes live here.

pub mod analytic;
pub mod common;
pub mod fp;
pub mod mfpt;
pub mod progress;
pub mod reproduce;
pub mod simulate;

use serde::Serialize;

/// Print a value as one JSON object on stdout.
pub fn print_json<T: Serialize>(value: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string(value)?);
    Ok(())
}
