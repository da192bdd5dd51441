//! `--reset-clock` (renewal resetting) on the command line: a search by
//! the exact sampler writes the clock's canonical spec into every
//! provenance file; a table read from a file is recorded inline; bad specs,
//! two clocks and a clock with a Poisson rate exit 2 with one line naming
//! the flag and nothing written; a method that does not run the clock
//! refuses it by name.

use crate::common::{assert_rejected, assert_success, irtp, read_json};

#[test]
fn search_with_a_gamma_clock_records_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let out = irtp(&[
        "mfpt",
        "--v0",
        "0",
        "--xt",
        "1",
        "--reset-position",
        "0",
        "--reset-clock",
        "gamma:k=2,theta=0.5",
        "--method",
        "exact",
        "--particles",
        "2000",
        "--seed",
        "3",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_success(&out);
    for f in ["run.json", "summary.json", "mfpt.json"] {
        let text = std::fs::read_to_string(dir.join(f)).unwrap();
        assert!(
            text.contains("\"reset_clock\": \"gamma:k=2,theta=0.5\""),
            "{f}: {text}"
        );
    }
    let s = read_json(&dir.join("summary.json"));
    let tau = s["results"]["tau"].as_f64().unwrap();
    assert!(tau.is_finite() && tau > 0.0, "{s}");
}

#[test]
fn a_table_file_is_recorded_inline() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("w.csv");
    std::fs::write(&csv, "t,W\n0,1\n0.5,0.6\n2,0\n").unwrap();
    let spec = format!("table:file={}", csv.display());
    let dir = tmp.path().join("run");
    let out = irtp(&[
        "simulate",
        "--method",
        "exact",
        "--particles",
        "200",
        "--t-max",
        "4",
        "--burn-in",
        "1",
        "--reset-clock",
        &spec,
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_success(&out);
    let run = std::fs::read_to_string(dir.join("run.json")).unwrap();
    assert!(
        run.contains("\"reset_clock\": \"table:0:1;0.5:0.6;2:0\""),
        "{run}"
    );
}

#[test]
fn bad_clocks_exit_2_naming_the_flag() {
    let cases: [(&[&str], &str); 7] = [
        (&["--reset-clock", "gamma:k=0,theta=1"], "--reset-clock"),
        (&["--reset-clock", "weibull:k=nan,scale=1"], "--reset-clock"),
        (&["--reset-clock", "pareto:alpha=2"], "--reset-clock"),
        (&["--reset-clock", "hazard:exp(-a)"], "--reset-clock"),
        (
            &["--reset-clock", "table:file=/nonexistent/w.csv"],
            "--reset-clock",
        ),
        (
            &["--reset-clock", "fixed:t=1", "--reset-period", "1"],
            "--reset-clock",
        ),
        (&["--reset-clock", "exp:rate=1", "--rate", "1"], "--rate"),
    ];
    for (flags, flag) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        let mut args = vec![
            "mfpt",
            "--v0",
            "0",
            "--xt",
            "1",
            "--reset-position",
            "0",
            "--method",
            "exact",
            "--out",
            dir.to_str().unwrap(),
        ];
        args.extend_from_slice(flags);
        let err = assert_rejected(&irtp(&args), flag, &dir);
        assert!(!err.contains("--rate=") && !err.contains(":--"), "{err}");
    }
    // The backward solvers do not run a renewal clock: refused by name.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let out = irtp(&[
        "fp",
        "stationary",
        "--reset-clock",
        "exp:rate=1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let err = assert_rejected(&out, "--reset-clock", &dir);
    assert!(err.contains("simulate --method exact"), "{err}");
}
