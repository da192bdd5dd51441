//! Errors name what the user typed: the missing flags, the flag whose value
//! is wrong (never a flag left at its default), the end of a scanned range;
//! bare `irtp` prints the usage. Every input error: exit 2, one line.

use std::process::Command;

fn irtp(args: &[&str]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn one_line_error(args: &[&str]) -> String {
    let (code, err) = irtp(args);
    assert_eq!(code, Some(2), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    err
}

#[test]
fn bare_command_prints_usage() {
    for args in [&[][..], &["fp"][..]] {
        let (code, err) = irtp(args);
        assert_eq!(code, Some(2));
        assert!(err.contains("Usage:"), "{args:?}: {err}");
    }
}

#[test]
fn missing_required_flags_are_named() {
    let err = one_line_error(&["mfpt", "--vt", "0.5"]);
    assert!(err.contains("--v0"), "{err}");
    let err = one_line_error(&["mfpt"]);
    assert!(err.contains("--v0") && err.contains("--vt"), "{err}");
}

#[test]
fn the_typed_flag_is_blamed() {
    // v_r is left at its default 0: the start v0 is on the wrong side.
    let err = one_line_error(&["mfpt", "--v0", "0.8", "--vt", "0.5"]);
    assert!(err.starts_with("irtp: error: invalid --v0 = 0.8"), "{err}");
    let scan = ["mfpt", "scan", "--over", "vt", "--v0", "0"];
    let err = one_line_error(&[&scan[..], &["--from", "0.2", "--to", "5"]].concat());
    assert!(err.starts_with("irtp: error: invalid --to = 5"), "{err}");
    let err = one_line_error(&[&scan[..], &["--from", "-5", "--to", "-0.2"]].concat());
    assert!(err.starts_with("irtp: error: invalid --from = -5"), "{err}");
    let rate = ["mfpt", "scan", "--over", "rate", "--v0", "0", "--vt", "0.5"];
    let err = one_line_error(&[&rate[..], &["--from", "-1", "--to", "5"]].concat());
    assert!(err.starts_with("irtp: error: invalid --from = -1"), "{err}");
}

#[test]
fn flags_that_do_not_apply_are_refused() {
    let err = one_line_error(&[
        "mfpt", "scan", "--over", "vt", "--v0", "0", "--from", "0.2", "--to", "0.5", "--vt", "0.3",
    ]);
    assert!(err.contains("--vt") && err.contains("--over rate"), "{err}");
    let err = one_line_error(&["simulate", "--dt", "0.01"]);
    assert!(err.contains("--dt"), "{err}");
    let cases: [(&[&str], &str); 7] = [
        (&["fp", "stationary", "--seed", "3"], "--seed"),
        (
            &["fp", "transient", "--t-max", "1", "--seed", "3"],
            "--seed",
        ),
        (
            &["mfpt", "--v0", "0", "--vt", "0.5", "--seed", "3"],
            "--seed",
        ),
        (
            &["mfpt", "--v0", "0", "--vt", "0.5", "--dt", "0.01"],
            "--dt",
        ),
        (
            &[
                "mfpt", "--v0", "0", "--vt", "0.5", "--method", "exact", "--dt", "0.01",
            ],
            "--dt",
        ),
        (
            &["mfpt", "--v0", "0", "--vt", "0.5", "--particles", "100"],
            "--particles",
        ),
        (
            &[
                "mfpt", "optimize", "--v0", "0", "--vt", "0.5", "--rate", "3",
            ],
            "--rate",
        ),
    ];
    for (args, flag) in cases {
        let err = one_line_error(args);
        assert!(
            err.starts_with(&format!("irtp: error: invalid {flag} =")),
            "{args:?}: {err}"
        );
    }
    // The same flags where they apply.
    let (code, err) = irtp(&[
        "mfpt",
        "--v0",
        "0",
        "--vt",
        "0.5",
        "--method",
        "euler",
        "--dt",
        "0.01",
        "--seed",
        "3",
        "--particles",
        "200",
    ]);
    assert_eq!(code, Some(0), "{err}");
}

#[test]
fn runs_over_budget_are_refused_before_starting() {
    let cases: [(&[&str], &str); 5] = [
        (&["simulate", "--particles", "1000000000000"], "--particles"),
        (&["simulate", "--t-max", "1e300"], "--t-max"),
        (&["simulate", "--lambda", "1e9"], "--lambda"),
        (
            &[
                "fp",
                "transient",
                "--scheme",
                "paper",
                "--t-max",
                "10",
                "--rate",
                "1e9",
            ],
            "--rate",
        ),
        (
            &[
                "mfpt", "scan", "--over", "vt", "--from", "0.1", "--to", "1", "--points", "1e8",
                "--v0", "0",
            ],
            "--points",
        ),
    ];
    for (args, flag) in cases {
        let start = std::time::Instant::now();
        let err = one_line_error(args);
        assert!(
            err.contains("too costly") && err.contains(flag),
            "{args:?}: {err}"
        );
        assert!(err.contains("--max-work"), "{err}");
        assert!(
            start.elapsed().as_secs_f64() < 10.0,
            "{args:?} took {:?}",
            start.elapsed()
        );
    }
    let err = one_line_error(&["analytic", "--points", "1e9"]);
    assert!(
        err.contains("bytes of memory") && err.contains("--max-memory"),
        "{err}"
    );
    // Raising the budget lets it through the check (here: into the next one).
    let err = one_line_error(&["simulate", "--samples", "1e9", "--max-memory", "1e20"]);
    assert!(err.contains("--max-work"), "{err}");
}

/// The exact sampler's cost estimate counts the resets of a periodic clock
/// and the ends of refractory periods (10 particles, resets every 10⁻⁶ to
/// t = 1: ≥ 10⁷ events against a budget of 10⁶), refused before any work.
#[test]
fn periodic_and_refractory_events_count_against_max_work() {
    for extra in [
        &["--reset-period", "1e-6"][..],
        &["--reset-period", "1e-6", "--refractory", "fixed:t=1e-9"],
    ] {
        let mut args = vec![
            "simulate",
            "--particles",
            "10",
            "--t-max",
            "1",
            "--max-work",
            "1e6",
        ];
        args.extend_from_slice(extra);
        let err = one_line_error(&args);
        assert!(
            err.contains("too costly") && err.contains("--max-work"),
            "{args:?}: {err}"
        );
    }
}

/// With a noise model the exact sampler's cost estimate counts the events
/// of its fastest state (here left at rate 10⁷: 10 particles to t = 1 are
/// ≥ 10⁸ events against a budget of 10⁶), refused before any work and
/// naming `--noise` among the flags that set it.
#[test]
fn a_noise_models_event_rate_counts_against_max_work() {
    let args = [
        "simulate",
        "--drag",
        "tan",
        "--noise",
        "rpt:sigma=1,alpha=1e7,beta=1",
        "--particles",
        "10",
        "--t-max",
        "1",
        "--max-work",
        "1e6",
    ];
    let start = std::time::Instant::now();
    let err = one_line_error(&args);
    assert!(
        err.contains("too costly") && err.contains("--max-work") && err.contains("--noise"),
        "{err}"
    );
    assert!(
        start.elapsed().as_secs_f64() < 10.0,
        "{:?}",
        start.elapsed()
    );
}

/// A reader that closes the pipe early (`irtp ... | head`) ends the
/// program quietly, as it ends any Unix filter: no panic, no message.
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_program_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let plan = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/sweeps/analytic.toml"
    );
    let out = dir.path().join("s");
    let mut child = Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args(["sweep", "slurm", plan, "--dry-run", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader is gone before the first line
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        o.status.success() || o.status.signal() == Some(libc::SIGPIPE),
        "{:?}: {err}",
        o.status
    );
}
