//! Shared helpers of the integration tests: run the `irtp` binary, parse
//! its JSON, and check the bad-input contract (one line, exit 2, nothing
//! written); [`models`] holds the shared parameter sets,
//! [`linear_protocols`] the linear-drag closed forms of the reset-protocol
//! modifiers (both from [`irtp_testkit`]).

pub use irtp_testkit::{linear_protocols, models, stats};

use std::path::Path;
use std::process::{Command, Output};

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_irtp");

/// Run `irtp args...`.
pub fn irtp(args: &[&str]) -> Output {
    irtp_env(args, &[])
}

/// Run `irtp args...` with extra environment variables (e.g. `RAYON_NUM_THREADS`).
pub fn irtp_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new(BIN)
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("run irtp")
}

/// Assert a zero exit status, showing stderr otherwise.
pub fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The single JSON object a successful `--json` run prints on one stdout
/// line (the `summary.json` schema: schema, command, method, params,
/// results, provenance).
pub fn summary(out: &Output) -> serde_json::Value {
    assert_success(out);
    let s = String::from_utf8(out.stdout.clone()).unwrap();
    assert_eq!(s.lines().count(), 1, "one JSON line: {s}");
    let v: serde_json::Value = serde_json::from_str(&s).expect("one JSON value");
    assert_eq!(v["schema"], "irtp.summary/1", "{s}");
    for k in ["command", "method", "params", "results", "provenance"] {
        assert!(v.get(k).is_some(), "no {k} in {s}");
    }
    v
}

/// The `results` of a successful `--json` run's object ([`summary`]).
pub fn json(out: &Output) -> serde_json::Value {
    summary(out)["results"].clone()
}

/// The last row of a CSV file, as numbers.
pub fn last_csv_row(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let last = text
        .lines()
        .last()
        .unwrap_or_else(|| panic!("{path:?}: empty"));
    last.split(',').map(|x| x.parse().unwrap()).collect()
}

/// Parse a JSON file (e.g. an output directory's run.json).
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    serde_json::from_str(&text).unwrap()
}

/// The bad-input contract: exit code 2, nothing on stdout, exactly one
/// stderr line `irtp: error: invalid <flag> = <value>: allowed ...`, and the
/// `--out` directory `dir` not created (nor anything else beside it).
/// Returns the stderr text.
pub fn assert_rejected(out: &Output, flag: &str, dir: &Path) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{flag}: {err}");
    assert!(out.stdout.is_empty(), "{flag}: stdout not empty");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with(&format!("irtp: error: invalid {flag} = ")),
        "{err}"
    );
    // A range (`: allowed ...`) or a combination a method does not run
    // (`... not run by METHOD; runs in ...`, irtp::capability).
    assert!(
        err.contains(": allowed ") || err.contains(" not run by "),
        "{err}"
    );
    assert!(!dir.exists(), "{flag}: {dir:?} was created");
    if let Some(parent) = dir.parent() {
        assert_eq!(
            std::fs::read_dir(parent).unwrap().count(),
            0,
            "{flag}: something was written in {parent:?}"
        );
    }
    err
}
