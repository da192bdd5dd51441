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
    assert!(
        err.contains("runs in simulate, mfpt (exact, euler)"),
        "{err}"
    );
}

/// `mfpt optimize --xt L --reset-clock SPEC`: the best mean waiting time of
/// the clock's law (shape fixed) by the renewal route; r_opt is the reset
/// frequency 1/m*, the clock at the optimum is recorded, and the renewal
/// route at the optimum is below the route at a mean three times shorter
/// and three times longer (linear drag, a fixed clock, full resetting).
#[test]
fn the_best_mean_waiting_time_of_a_clock() {
    let base = [
        "--xt",
        "1",
        "--v0",
        "0",
        "--drag",
        "linear",
        "--sigma",
        "1",
        "--lambda",
        "0.5",
        "--reset-position",
        "0",
        "--cells-x",
        "8",
        "--cells-v",
        "4",
        "--json",
    ];
    let opt_args = [
        "--reset-clock",
        "fixed:t=1",
        "--r-min",
        "0.1",
        "--r-max",
        "1",
        "--grid-points",
        "7",
        "--max-work",
        "1e13",
    ];
    let out = irtp(&[&["mfpt", "optimize"][..], &base, &opt_args].concat());
    assert_success(&out);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let r = &j["results"];
    let (f, m) = (
        r["r_opt"].as_f64().unwrap(),
        r["mean_opt"].as_f64().unwrap(),
    );
    assert!(r["interior"].as_bool().unwrap(), "{r}");
    assert_eq!(m, 1.0 / f);
    let spec = r["reset_clock_opt"].as_str().unwrap();
    assert_eq!(spec, format!("fixed:t={m}"));
    let (lo, hi) = (
        r["mean_opt_range"][0].as_f64().unwrap(),
        r["mean_opt_range"][1].as_f64().unwrap(),
    );
    assert!(lo <= m && m <= hi, "{r}");
    let tau_at = |spec: &str| {
        let out = irtp(
            &[
                &["mfpt", "--method", "renewal", "--reset-clock", spec][..],
                &base,
            ]
            .concat(),
        );
        assert_success(&out);
        let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        // A period too short for the fastest path to reach the target is
        // an infinite mean (tau null, infinite_mean true).
        match j["results"]["tau"].as_f64() {
            Some(t) => t,
            None => {
                assert_eq!(j["results"]["infinite_mean"], true, "{j}");
                f64::INFINITY
            }
        }
    };
    let tau = r["tau_opt"].as_f64().unwrap();
    assert!((tau_at(spec) - tau).abs() <= 1e-9 * tau);
    for other in [m / 3.0, 3.0 * m] {
        let t = tau_at(&format!("fixed:t={other}"));
        assert!(tau < t, "tau({m}) = {tau} vs tau({other}) = {t}");
    }
}
