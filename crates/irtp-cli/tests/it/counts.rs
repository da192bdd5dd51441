//! Count flags (`--particles`, `--cells`, `--points`, ...) take whole
//! numbers in scientific notation too: `2e3` runs exactly what `2000` runs;
//! a fraction or a negative count is one line naming the flag, exit 2.

use std::process::Command;

fn irtp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args(args)
        .output()
        .unwrap()
}

/// The `--json` object without its timings.
fn summary(args: &[&str]) -> serde_json::Value {
    let o = irtp(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let all: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut v = all["results"].clone();
    for k in ["wall_time_s", "particle_steps_per_s", "events_per_s"] {
        v.as_object_mut().unwrap().remove(k);
    }
    v
}

#[test]
fn scientific_notation_counts_run_the_same_computation() {
    let sim = |n: &str| {
        summary(&[
            "simulate",
            "--particles",
            n,
            "--t-max",
            "12",
            "--bins",
            "2e1",
            "--json",
        ])
    };
    assert_eq!(sim("2e3"), sim("2000"));
    let fp = |n: &str| summary(&["fp", "stationary", "--cells", n, "--json"]);
    assert_eq!(fp("1.2e3"), fp("1200"));
}

#[test]
fn fractional_or_negative_counts_are_refused() {
    for (flag, bad) in [
        ("--particles", "1.5"),
        ("--particles", "-5"),
        ("--bins", "1e30"),
        ("--samples", "abc"),
    ] {
        let o = irtp(&["simulate", flag, bad]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {bad}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(flag) && err.contains("not a count"), "{err}");
    }
}
