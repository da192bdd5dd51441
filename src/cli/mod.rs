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

/// The command-line spelling of a library parameter name: `--` + the name
/// with `_` → `-` (`t_max` → `--t-max`), except for the names in the table;
/// a name the CLI already spelt as a flag (`--v0`) is kept.
pub fn flag_for(name: &str) -> String {
    const TABLE: &[(&str, &str)] = &[("figure", "FIGURE")];
    if name.starts_with('-') {
        return name.to_string();
    }
    match TABLE.iter().find(|(lib, _)| *lib == name) {
        Some((_, flag)) => flag.to_string(),
        None => format!("--{}", name.replace('_', "-")),
    }
}

/// Text-mode note listing the files an output directory received (nothing
/// when no `--out` was given).
pub fn print_written(dir: &Option<std::path::PathBuf>, files: &Option<Vec<std::path::PathBuf>>) {
    let (Some(dir), Some(files)) = (dir, files) else {
        return;
    };
    let names: Vec<String> = files
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    println!("wrote {}: {}", dir.display(), names.join(", "));
}

/// Print a value as one JSON object on stdout.
pub fn print_json<T: Serialize>(value: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string(value)?);
    Ok(())
}
