//! `irtp mfpt` through the binary.

use crate::common;
use crate::common::{assert_rejected, assert_success, irtp, json, read_json};

const PAPER: [&str; 10] = [
    "--drag", "tan", "--sigma", "3", "--lambda", "0.5", "--rate", "2", "--v0", "-0.249",
];

#[test]
fn direct_usage_ode_json() {
    let mut a = vec!["mfpt"];
    a.extend(PAPER);
    a.extend(["--vt", "0.5", "--json", "--cells", "4000"]);
    let v = json(&irtp(&a));
    let (t, tp, tm) = (
        v["tau"].as_f64().unwrap(),
        v["tau_plus"].as_f64().unwrap(),
        v["tau_minus"].as_f64().unwrap(),
    );
    assert!(tp > 0.0 && tm > tp);
    assert!((t - 0.5 * (tp + tm)).abs() < 1e-12);
    assert!((t - 1.7442128).abs() < 1e-6, "{t}");
    assert!(v["error_estimate"].as_f64().unwrap() < 1e-6);
    assert_eq!(v["method"], "backward");
}

#[test]
fn direct_usage_euler_reports_errors_and_censoring() {
    let mut a = vec!["mfpt"];
    a.extend(PAPER);
    a.extend([
        "--vt",
        "0.5",
        "--json",
        "--method",
        "euler",
        "--particles",
        "2000",
    ]);
    a.extend(["--dt", "1e-3", "--seed", "3"]);
    let v = json(&irtp(&a));
    let err = v["tau_err"].as_f64().unwrap();
    assert!(err > 0.0);
    assert_eq!(v["censored"], 0);
    assert_eq!(v["tau_lower_bound"], serde_json::Value::Null);
    assert_eq!(v["censored_fraction"], 0.0);
    assert_eq!(v["rmst"], v["tau"]);
    assert!((v["tau"].as_f64().unwrap() - 1.7442128).abs() < 4.0 * err);
    // Same seed, same answer.
    assert_eq!(v, json(&irtp(&a)));
}

#[test]
fn scan_writes_csv_and_provenance() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    let out = irtp(&[
        "mfpt",
        "scan",
        "--drag",
        "tanh",
        "--sigma",
        "0.6",
        "--lambda",
        "0.5",
        "--rate",
        "0.2",
        "--v0",
        "-0.249",
        "--over",
        "vt",
        "--from",
        "0.05",
        "--to",
        "0.15",
        "--points",
        "3",
        "--cells",
        "2000",
        "--method",
        "euler",
        "--particles",
        "400",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_success(&out);
    let csv = std::fs::read_to_string(dir.join("mfpt_scan.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("vt,tau,tau_plus,tau_minus,error_estimate,tau_sim,tau_sim_err"));
    assert_eq!(lines.count(), 3);
    let run = read_json(&dir.join("run.json"));
    assert_eq!(run["command"], "mfpt scan");
    assert_eq!(run["method"], "euler");

    let rate = irtp(&[
        "mfpt", "scan", "--v0", "-0.249", "--vt", "0.5", "--over", "rate", "--from", "0.01",
        "--to", "100", "--points", "5", "--log", "--cells", "2000", "--json",
    ]);
    let v = json(&rate);
    assert_eq!(v.as_array().unwrap().len(), 5);
    assert!((v[4]["rate"].as_f64().unwrap() - 100.0).abs() < 1e-9);
}

#[test]
fn optimize_json() {
    let v = json(&irtp(&[
        "mfpt",
        "optimize",
        "--drag",
        "tan",
        "--sigma",
        "3",
        "--lambda",
        "0.5",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--cells",
        "2000",
        "--grid-points",
        "21",
        "--json",
    ]));
    assert_eq!(v["interior"], true);
    let (r, t, t0) = (
        v["r_opt"].as_f64().unwrap(),
        v["tau_opt"].as_f64().unwrap(),
        v["tau_r0"].as_f64().unwrap(),
    );
    assert!(r > 1.0 && r < 5.0 && t < t0, "{v}");
    let v = json(&irtp(&[
        "mfpt",
        "optimize",
        "--drag",
        "tanh",
        "--sigma",
        "0.6",
        "--lambda",
        "0.5",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--cells",
        "2000",
        "--grid-points",
        "21",
        "--json",
    ]));
    assert_eq!(v["interior"], false);
    assert_eq!(v["r_opt"].as_f64().unwrap(), 0.0);
}

#[test]
fn bad_input_one_line_exit_2_nothing_written() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("res");
    let d = dir.to_str().unwrap();
    let cases: [(&[&str], &str); 9] = [
        (&["--vt", "1.249046"], "--vt"),
        (&["--vt", "2"], "--vt"),
        (&["--vt", "nan"], "--vt"),
        (&["--vt", "0.5", "--v0", "-1.3"], "--v0"),
        (
            &["--vt", "0.5", "--reset-velocity", "0.7"],
            "--reset-velocity",
        ),
        (
            &["--vt", "0.5", "--reset-velocity", "-1.3"],
            "--reset-velocity",
        ),
        (
            &["--vt", "0.5", "--drag", "tanh", "--sigma", "1.0"],
            "--sigma",
        ),
        (&["--vt", "0.5", "--lambda", "0"], "--lambda"),
        (&["--vt", "0.5", "--method", "euler", "--dt", "0.5"], "--dt"),
    ];
    for (extra, flag) in cases {
        let mut a = vec!["mfpt", "--v0", "-0.249", "--out", d];
        // A later --v0 overrides is not allowed by clap; put it first only once.
        if extra.contains(&"--v0") {
            a = vec!["mfpt", "--out", d];
        }
        a.extend(extra);
        assert_rejected(&irtp(&a), flag, &dir);
    }
    // v_t at v_u: the message says why it is never reached.
    let out = irtp(&["mfpt", "--v0", "-0.249", "--vt", "1.25"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("never reached"), "{err}");
    // Scan and optimize validate too.
    let out = irtp(&[
        "mfpt", "scan", "--v0", "-0.249", "--over", "vt", "--from", "0.1", "--to", "1.3", "--out",
        d,
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!dir.exists());
    // Negative numbers reach validation (not clap's "unexpected argument").
    let negative: [(&[&str], &str); 4] = [
        (
            &[
                "mfpt", "optimize", "--v0", "-0.249", "--vt", "0.5", "--r-min", "-1",
            ],
            "--r-min",
        ),
        (
            &[
                "mfpt", "optimize", "--v0", "-0.249", "--vt", "0.5", "--r-max", "-1",
            ],
            "--r-max",
        ),
        (
            &[
                "mfpt", "--v0", "-0.249", "--vt", "0.5", "--method", "euler", "--dt", "-1e-3",
            ],
            "--dt",
        ),
        (
            &[
                "mfpt", "--v0", "-0.249", "--vt", "0.5", "--method", "euler", "--t-max", "-5",
            ],
            "--t-max",
        ),
    ];
    // Exponent notation with a negative exponent parses too (clap's own
    // negative-number detection does not accept it).
    let a = irtp(&["mfpt", "--v0", "-2.49e-1", "--vt", "5e-1", "--json"]);
    let b = irtp(&["mfpt", "--v0", "-0.249", "--vt", "0.5", "--json"]);
    assert_eq!(
        a.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&a.stderr)
    );
    let (a, b) = (common::summary(&a), common::summary(&b));
    assert_eq!((&a["params"], &a["results"]), (&b["params"], &b["results"]));
    for (args, flag) in negative {
        let mut a = args.to_vec();
        a.extend(["--out", d]);
        assert_rejected(&irtp(&a), flag, &dir);
    }
}
