//! Censored first passages are never dropped nor averaged away: when a
//! particle has not arrived by t_max, `irtp mfpt` reports no tau, but the
//! restricted mean rmst = E[min(T, t_max)] as its lower bound, and the
//! Kaplan-Meier survival curve (survival.csv). Checked against the backward
//! equations, for both particle methods, and across thread counts.

use crate::common::{assert_success, irtp, irtp_env, json, read_json};
use serde_json::Value;
use std::path::Path;

/// The heavy-censoring case: rate 60 makes tau ~ 2e3, t_max = 1.
const HEAVY: [&str; 10] = [
    "mfpt", "--v0", "0", "--vt", "0.5", "--rate", "60", "--t-max", "1", "--json",
];

/// The paper's problem (tan, Sigma = 3, lambda = 0.5, r = 2): tau ~ 1.74.
const PAPER: [&str; 6] = ["mfpt", "--v0", "-0.249", "--vt", "0.5", "--json"];

fn args<'a>(base: &[&'a str], more: &[&'a str]) -> Vec<&'a str> {
    base.iter().chain(more).copied().collect()
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number: {v}"))
}

/// tau of the backward equations.
fn ode_tau(base: &[&str]) -> f64 {
    num(&json(&irtp(&args(base, &["--cells", "20000"]))), "tau")
}

/// survival.csv as rows of (t, survival, survival_err, at_risk).
fn survival(dir: &Path) -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string(dir.join("survival.csv")).expect("survival.csv");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,survival,survival_err,at_risk"));
    lines
        .map(|l| {
            let x: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
            [x[0], x[1], x[2], x[3]]
        })
        .collect()
}

/// The curve starts at S(0) = 1, never increases, and its integral
/// brackets rmst: S is right-continuous and non-increasing, so between
/// grid times t_k < t_k+1 it lies between S(t_k+1) and S(t_k). The curve
/// ends at t_max (censored) or where S = 0 (then the rest adds nothing).
fn check_curve(rows: &[[f64; 4]], rmst: f64, particles: f64) {
    assert_eq!(rows[0], [0.0, 1.0, 0.0, particles]);
    let (mut lower, mut upper) = (0.0, 0.0);
    for w in rows.windows(2) {
        let (a, b) = (w[0], w[1]);
        assert!(b[0] > a[0] && b[1] <= a[1] && b[3] <= a[3], "{a:?} {b:?}");
        assert!(b[2] >= 0.0 && b[2] <= 0.5 / particles.sqrt() * 2f64.sqrt());
        lower += b[1] * (b[0] - a[0]);
        upper += a[1] * (b[0] - a[0]);
    }
    // Rounding of the sums only (the bracket is ~10% wide).
    let eps = 1e-12 * rmst;
    assert!(
        lower - eps <= rmst && rmst <= upper + eps,
        "{lower} {rmst} {upper}"
    );
}

/// (a) Almost every particle censored: exit 0, no tau presented (JSON,
/// text, run.json), rmst <= t_max and below the backward tau by far more
/// than its error, survival.csv ending at t_max with the censored at risk.
#[test]
fn heavy_censoring_reports_a_lower_bound_not_a_mean() {
    let tau = ode_tau(&["mfpt", "--v0", "0", "--vt", "0.5", "--rate", "60", "--json"]);
    assert!(tau > 1e3, "{tau}");
    for method in [
        &["--method", "exact"][..],
        &["--method", "euler", "--dt", "1e-3"],
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let out = args(&args(&HEAVY, method), &["--out", dir.to_str().unwrap()]);
        let v = json(&irtp(&out));
        for k in ["tau", "tau_err", "tau_plus", "tau_minus"] {
            assert_eq!(v[k], Value::Null, "{k}: {v}");
        }
        let (n, c) = (num(&v, "particles"), num(&v, "censored"));
        assert!(c > 0.9 * n && c < n, "{v}");
        assert_eq!(num(&v, "censored_fraction"), c / n);
        let (rmst, err) = (num(&v, "rmst"), num(&v, "rmst_err"));
        assert_eq!(v["tau_lower_bound"], v["rmst"]);
        assert!(rmst > 0.9 && rmst <= 1.0 && err > 0.0, "{v}");
        assert!(rmst + 4.0 * err < tau, "rmst {rmst} ± {err} vs tau {tau}");
        let run = read_json(&dir.join("run.json"));
        assert_eq!(run["parameters"]["tau"], Value::Null);
        assert_eq!(run["parameters"]["tau_lower_bound"], v["rmst"]);
        let rows = survival(&dir);
        let last = rows.last().unwrap();
        assert_eq!((last[0], last[3]), (1.0, c));
        // S(t_max) is the censored fraction (of each half, averaged).
        assert!((last[1] - c / n).abs() < 1e-12, "{method:?} {last:?}");
        check_curve(&rows, rmst, n);

        let text = irtp(&args(&HEAVY[..9], method));
        assert_success(&text);
        let text = String::from_utf8(text.stdout).unwrap();
        assert!(text.starts_with("CENSORED: "), "{text}");
        assert!(text.contains("tau is NOT estimated") && text.contains("tau > rmst = "));
        assert!(text.contains("\ntau = null\n"), "{text}");
    }
}

/// A few censored particles already withhold tau: the mean of the arrived
/// ones is biased low, rmst is the bound, and it lies below the backward tau.
#[test]
fn moderate_censoring_bounds_the_backward_tau() {
    let tau = ode_tau(&PAPER);
    let v = json(&irtp(&args(
        &PAPER,
        &["--method", "exact", "--t-max", "5", "--particles", "20000"],
    )));
    let c = num(&v, "censored");
    assert!(c > 0.0 && c < 0.2 * num(&v, "particles"), "{v}");
    assert_eq!(v["tau"], Value::Null);
    let (rmst, err) = (num(&v, "rmst"), num(&v, "rmst_err"));
    assert!(rmst + 4.0 * err < tau, "rmst {rmst} ± {err} vs tau {tau}");
}

/// (b) Nothing censored: rmst is tau to the bit (as are their errors), no
/// lower bound is given, and the survival curve reaches 0.
#[test]
fn uncensored_rmst_is_the_mean_and_the_curve_reaches_zero() {
    for method in [
        &["--method", "exact"][..],
        &["--method", "euler", "--dt", "2e-3"],
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let more = args(method, &["--particles", "4000", "--seed", "8"]);
        let v = json(&irtp(&args(
            &args(&PAPER, &more),
            &["--out", dir.to_str().unwrap()],
        )));
        assert_eq!(num(&v, "censored"), 0.0);
        assert_eq!(num(&v, "censored_fraction"), 0.0);
        assert_eq!(v["tau_lower_bound"], Value::Null);
        assert_eq!(num(&v, "rmst").to_bits(), num(&v, "tau").to_bits());
        assert_eq!(num(&v, "rmst_err").to_bits(), num(&v, "tau_err").to_bits());
        let rows = survival(&dir);
        let last = rows.last().unwrap();
        assert_eq!((last[1], last[2], last[3]), (0.0, 0.0, 0.0), "{method:?}");
        assert!(last[0] < 1e4);
        check_curve(&rows, num(&v, "rmst"), 4000.0);
        let text = String::from_utf8(irtp(&args(&PAPER[..5], &more)).stdout).unwrap();
        assert!(
            text.starts_with("method = ") && !text.contains("CENSORED"),
            "{text}"
        );
    }
}

/// (c) The integral of the Kaplan-Meier curve (rmst at a t_max far beyond
/// every passage) equals the backward-equation tau within 4 standard
/// errors, and censoring at a shorter t_max leaves the curve before t_max
/// unchanged, bit for bit (same particles, same paths).
#[test]
fn kaplan_meier_integral_matches_the_backward_equations() {
    let tau = ode_tau(&PAPER);
    let tmp = tempfile::tempdir().unwrap();
    let (long, short) = (tmp.path().join("long"), tmp.path().join("short"));
    let run = |t_max: &str, dir: &Path| {
        let more = [
            "--method",
            "exact",
            "--particles",
            "20000",
            "--seed",
            "21",
            "--t-max",
            t_max,
            "--out",
            dir.to_str().unwrap(),
        ];
        json(&irtp(&args(&PAPER, &more)))
    };
    let v = run("1e4", &long);
    assert_eq!(num(&v, "censored"), 0.0);
    let (rmst, err) = (num(&v, "rmst"), num(&v, "rmst_err"));
    assert!(
        (rmst - tau).abs() < 4.0 * err,
        "rmst {rmst} ± {err} vs tau {tau}"
    );
    check_curve(&survival(&long), rmst, 20000.0);

    let w = run("2", &short);
    assert!(num(&w, "censored") > 0.0 && num(&w, "rmst") < rmst);
    let (a, b) = (survival(&long), survival(&short));
    let before: Vec<_> = a.iter().filter(|r| r[0] < 2.0).collect();
    assert!(before.len() > 10);
    assert_eq!(before, b[..before.len()].iter().collect::<Vec<_>>());
    assert_eq!(b.len(), before.len() + 1);
    check_curve(&b, num(&w, "rmst"), 20000.0);
}

/// (d) JSON and survival.csv bit-identical for 1, 2 and 3 threads, with
/// censoring, for both particle methods and a scan.
#[test]
fn censored_results_are_bit_identical_for_any_thread_count() {
    let cases: [&[&str]; 3] = [
        &["--method", "exact", "--t-max", "1.5", "--particles", "9000"],
        &["--method", "euler", "--t-max", "1.5", "--particles", "5000"],
        &["--method", "exact", "--t-max", "1e4", "--particles", "9000"],
    ];
    for case in cases {
        let run = |threads: &str| {
            let tmp = tempfile::tempdir().unwrap();
            let dir = tmp.path().join("out");
            let all = args(&args(&PAPER, case), &["--out", dir.to_str().unwrap()]);
            let out = irtp_env(&all, &[("RAYON_NUM_THREADS", threads)]);
            assert_success(&out);
            let csv = std::fs::read(dir.join("survival.csv")).unwrap();
            (json(&out).to_string(), csv)
        };
        let one = run("1");
        assert_eq!(one, run("2"), "{case:?}");
        assert_eq!(one, run("3"), "{case:?}");
    }
    let scan = [
        "mfpt",
        "scan",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--over",
        "rate",
        "--from",
        "1",
        "--to",
        "60",
        "--points",
        "3",
        "--log",
        "--cells",
        "2000",
        "--method",
        "exact",
        "--t-max",
        "3",
        "--particles",
        "3000",
        "--json",
    ];
    let one = json(&irtp_env(&scan, &[("RAYON_NUM_THREADS", "1")])).to_string();
    assert_eq!(
        one,
        json(&irtp_env(&scan, &[("RAYON_NUM_THREADS", "2")])).to_string()
    );
}

/// `mfpt scan` with particles: a censored point shows no tau_sim (null in
/// JSON, nan in the CSV) but its rmst_sim and censored_fraction; the text
/// flags it.
#[test]
fn scan_withholds_tau_at_censored_points() {
    let base = [
        "mfpt",
        "scan",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--over",
        "rate",
        "--from",
        "0.5",
        "--to",
        "60",
        "--points",
        "2",
        "--log",
        "--cells",
        "2000",
        "--method",
        "exact",
        "--t-max",
        "20",
        "--particles",
        "2000",
    ];
    let v = json(&irtp(&args(&base, &["--json"])));
    let (ok, cut) = (&v[0], &v[1]);
    assert_eq!(num(ok, "censored"), 0.0);
    assert_eq!(num(ok, "rmst_sim").to_bits(), num(ok, "tau_sim").to_bits());
    assert!(num(cut, "censored_fraction") > 0.5, "{cut}");
    for k in ["tau_sim", "tau_sim_err", "tau_plus_sim", "tau_minus_sim"] {
        assert_eq!(cut[k], Value::Null, "{k}: {cut}");
    }
    let (rmst, err) = (num(cut, "rmst_sim"), num(cut, "rmst_sim_err"));
    assert!(rmst <= 20.0 && rmst + 4.0 * err < num(cut, "tau"), "{cut}");

    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    let out = irtp(&args(&base, &["--out", dir.to_str().unwrap()]));
    assert_success(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("# CENSORED at 1 of 2 points"), "{text}");
    let csv = std::fs::read_to_string(dir.join("mfpt_scan.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let col = |name: &str| rows[0].iter().position(|h| *h == name).unwrap();
    assert_eq!(rows[2][col("tau_sim")], "nan");
    assert_eq!(rows[2][col("rmst_sim")].parse::<f64>().unwrap(), rmst);
}
