//! The `irtp` command line: parse flags (defined with the commands in
//! [`irtp_app`]), run, print JSON or text. All printing and exit codes
//! live here.

pub mod progress;
pub mod signals;
pub mod sweep;

use irtp_app::Outcome;
use std::io::Write;

/// The command-line spelling of a library parameter name: `--` + the name
/// with `_` → `-` (`t_max` → `--t-max`), except for the names in the table;
/// a name the CLI already spelt as a flag (`--v0`) is kept.
pub fn flag_for(name: &str) -> String {
    const TABLE: &[(&str, &str)] = &[("figure", "FIGURE"), ("dir", "DIR")];
    if name.starts_with('-') {
        return name.to_string();
    }
    match TABLE.iter().find(|(lib, _)| *lib == name) {
        Some((_, flag)) => flag.to_string(),
        None => format!("--{}", name.replace('_', "-")),
    }
}

/// Print an outcome: its JSON (one line) with `--json`, else its text
/// report and the files written. A closed pipe (`| head`) is not an
/// error: the results are already on disk.
pub fn present(outcome: &Outcome, json: bool) -> anyhow::Result<()> {
    let mut text = if json {
        serde_json::to_string(&outcome.summary)? + "\n"
    } else {
        outcome.results.text.clone()
    };
    if let (false, Some((dir, files))) = (json, &outcome.written) {
        let names: Vec<String> = files
            .iter()
            .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        text += &format!("wrote {}: {}\n", dir.display(), names.join(", "));
    }
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
    for w in &outcome.warnings {
        eprintln!("irtp: warning: {w}");
    }
    Ok(())
}
