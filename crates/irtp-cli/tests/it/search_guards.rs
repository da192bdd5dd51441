//! Guards of the search commands that must act before any work: a scan's
//! point list is sized against the budget before it is allocated (a huge
//! `--points` is refused at once, exit 2), and the Euler search's dt → 0
//! extrapolation is verified (a target within a few steps gave a negative
//! mean time with exit 0; now exit 4 naming `--dt`).

use super::common::irtp;
use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

/// One line on stderr, under 200 characters, with exit `code`, nothing on
/// stdout and nothing in `parent` (the `--out` directory not created).
fn assert_refused(o: &Output, code: i32, parent: &Path) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(code), "{err}");
    assert!(
        o.stdout.is_empty(),
        "stdout: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.len() < 200, "{} chars: {err}", err.len());
    assert_eq!(std::fs::read_dir(parent).unwrap().count(), 0, "{err}");
    err
}

/// `--points 1e8` of every search scan axis and method is refused within a
/// second, naming `--points` (before this, the rate scan grew to 10 GB in
/// 20 s); so is `--points 1e8` with the work limit lifted, by the memory
/// the point list would take. `mfpt optimize --grid-points 1e8` likewise.
#[test]
fn huge_search_scans_are_refused_before_allocating() {
    let search = ["--xt", "1", "--v0", "0", "--reset-position", "0"];
    let rate = ["--over", "rate", "--from", "0.1", "--to", "10"];
    let huge = ["--points", "100000000"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            [&["mfpt", "scan"][..], &search, &rate, &huge].concat(),
            "--points",
        ),
        (
            [
                &["mfpt", "scan"][..],
                &search,
                &["--over", "x0", "--from", "-1", "--to", "0.5"],
                &huge,
            ]
            .concat(),
            "--points",
        ),
        (
            [
                &["mfpt", "scan"][..],
                &search,
                &rate,
                &huge,
                &["--method", "exact", "--particles", "1000"],
            ]
            .concat(),
            "--points",
        ),
        (
            [
                &["mfpt", "scan", "--interval=-1,1", "--v0", "0"][..],
                &rate,
                &huge,
            ]
            .concat(),
            "--points",
        ),
        // Memory alone: the work limit lifted.
        (
            [
                &["mfpt", "scan"][..],
                &search,
                &rate,
                &huge,
                &["--max-work", "1e30"],
            ]
            .concat(),
            "--points",
        ),
        (
            [
                &["mfpt", "optimize"][..],
                &search,
                &["--grid-points", "100000000"],
            ]
            .concat(),
            "--grid-points",
        ),
    ];
    for (args, flag) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("res");
        let t0 = Instant::now();
        let o = irtp(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
        let took = t0.elapsed();
        let err = assert_refused(&o, 2, tmp.path());
        assert!(
            err.contains("too costly") && err.contains(flag),
            "{args:?}: {err}"
        );
        assert!(took < Duration::from_secs(1), "{args:?}: {took:?}");
    }
}

/// The case: the target 1e-12 away is crossed within two steps by
/// the particles started in +Sigma, so T(dt) = 2 dt, T(dt/2) = dt and the
/// extrapolation 2 T(dt/2) - T(dt) is 0 up to noise (it printed
/// tau_plus = -1.8e-4, exit 0). Refused: exit 4, naming --dt.
#[test]
fn euler_search_refuses_an_extrapolation_outside_its_regime() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    let o = irtp(&[
        "mfpt",
        "--v0",
        "0",
        "--reset-position",
        "0",
        "--xt",
        "1e-12",
        "--method",
        "euler",
        "--dt",
        "0.01",
        "--particles",
        "2000",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = assert_refused(&o, 4, tmp.path());
    assert!(err.contains("--dt") && err.contains("tau_plus"), "{err}");
    // The same target with a step small against the passage is answered.
    let o = irtp(&[
        "mfpt",
        "--v0",
        "0",
        "--reset-position",
        "0",
        "--xt",
        "0.5",
        "--method",
        "euler",
        "--dt",
        "0.01",
        "--particles",
        "2000",
        "--json",
    ]);
    let s = super::common::summary(&o);
    for k in ["tau", "tau_plus", "tau_minus"] {
        let x = s["results"][k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k}: {s}"));
        // Above the least time: the distance at the largest speed v_u = atan(3).
        assert!(x > 0.5 / 3f64.atan(), "{k} = {x}");
    }
}
