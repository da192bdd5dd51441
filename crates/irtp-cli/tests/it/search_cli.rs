//! `irtp mfpt --xt L | --interval A,B`: the search problem (first passage in
//! position) from the command line: the output contract with provenance,
//! the infinite mean (exit 0, tau null, the tail exponent), thread-count
//! invariance, and every class of bad input refused naming its flag
//! (exit 2, one line, nothing written).

use crate::common::{assert_rejected, irtp, irtp_env, json, read_json, summary};

const FULL: [&str; 12] = [
    "mfpt",
    "--xt",
    "0.8",
    "--x0",
    "0.1",
    "--v0",
    "0.2",
    "--method",
    "exact",
    "--reset-position",
    "0",
    "--particles",
];

#[test]
fn a_search_writes_its_results_with_provenance() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let d = dir.to_str().unwrap();
    let out = irtp(&[&FULL[..], &["2000", "--seed", "5", "--out", d, "--json"]].concat());
    let v = summary(&out);
    assert_eq!(v["method"], "exact");
    let r = &v["results"];
    assert_eq!(r["infinite_mean"], false);
    assert!(r["tail_exponent"].is_null());
    let tau = r["tau"].as_f64().expect("a finite mean");
    assert!(tau > 0.0 && r["tau_err"].as_f64().unwrap() > 0.0, "{r}");
    assert_eq!(r["problem"]["x0"], 0.1);
    assert_eq!(r["problem"]["v0"], 0.2);
    assert_eq!(r["problem"]["target"]["Level"], 0.8);
    assert_eq!(r["problem"]["params"]["reset_position"], 0.0);
    for f in ["summary.json", "run.json", "mfpt.json", "survival.csv"] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let run = read_json(&dir.join("run.json"));
    let text = run.to_string();
    for key in ["\"seed\":5", "\"version\"", "\"Level\":0.8", "\"x0\":0.1"] {
        assert!(text.contains(key), "run.json lacks {key}: {text}");
    }
    let surv = std::fs::read_to_string(dir.join("survival.csv")).unwrap();
    assert!(
        surv.starts_with("t,survival,survival_err,at_risk"),
        "{surv}"
    );
}

#[test]
fn an_interval_search_runs_and_threads_do_not_change_it() {
    let args = [
        "mfpt",
        "--interval",
        "-0.4,0.5",
        "--v0",
        "0",
        "--method",
        "exact",
        "--drag",
        "tanh",
        "--sigma",
        "0.6",
        "--particles",
        "3000",
        "--json",
    ];
    let one = json(&irtp_env(&args, &[("RAYON_NUM_THREADS", "1")]));
    let two = json(&irtp_env(&args, &[("RAYON_NUM_THREADS", "2")]));
    assert_eq!(one, two);
    assert_eq!(one["problem"]["target"]["Interval"][0], -0.4);
    assert!(one["tau"].as_f64().unwrap() > 0.0, "{one}");
}

/// Velocity-only resetting and a one-sided level: exit 0, tau null,
/// `infinite_mean` true with its reason, and the tail exponent with its
/// error and window.
#[test]
fn an_infinite_mean_is_reported_as_such() {
    let out = irtp(&[
        "mfpt",
        "--xt",
        "0.5",
        "--v0",
        "0",
        "--method",
        "exact",
        "--drag",
        "linear",
        "--sigma",
        "1",
        "--lambda",
        "2",
        "--rate",
        "1",
        "--particles",
        "2000",
        "--t-max",
        "1000",
        "--json",
    ]);
    let r = json(&out);
    assert!(r["tau"].is_null() && r["tau_plus"].is_null() && r["tau_err"].is_null());
    assert_eq!(r["infinite_mean"], true);
    assert!(r["infinite_mean_reason"]
        .as_str()
        .unwrap()
        .contains("infinite"));
    let tail = &r["tail_exponent"];
    let (theta, err) = (
        tail["theta"].as_f64().unwrap(),
        tail["theta_err"].as_f64().unwrap(),
    );
    assert!(theta > 0.0 && err > 0.0, "{tail}");
    assert!(tail["t_to"].as_f64().unwrap() <= 1000.0, "{tail}");
    // The text report leads with it.
    let text = irtp(&[
        "mfpt",
        "--xt",
        "0.5",
        "--v0",
        "0",
        "--method",
        "exact",
        "--particles",
        "200",
        "--t-max",
        "100",
    ]);
    let s = String::from_utf8_lossy(&text.stdout);
    assert!(s.starts_with("INFINITE MEAN: tau is not reported"), "{s}");
}

/// Each class of bad input: exit 2, one line naming the flag, no output
/// directory.
#[test]
fn bad_search_inputs_are_refused_naming_the_flag() {
    let base = ["mfpt", "--v0", "0", "--method", "exact"];
    let cases: [(&[&str], &str); 10] = [
        (&["--xt", "1", "--reset-position", "2"], "--reset-position"),
        (
            &["--xt", "-1", "--reset-position", "-1"],
            "--reset-position",
        ),
        (
            &["--interval", "-1,1", "--reset-position", "3"],
            "--reset-position",
        ),
        (&["--interval", "1,-1"], "--interval"),
        (&["--interval", "0.5,0.5", "--x0", "0.5"], "--interval"),
        (&["--interval", "-1,nan"], "--interval"),
        (&["--interval", "-1"], "--interval"),
        (&["--xt", "nan"], "--xt"),
        (&["--xt", "1", "--x0", "nan"], "--x0"),
        (&["--xt", "0.5", "--t-max", "inf"], "--t-max"),
    ];
    for (extra, flag) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let d = dir.to_str().unwrap();
        let out = irtp(&[&base[..], extra, &["--out", d]].concat());
        assert_rejected(&out, flag, &dir);
    }
    // The backward solver (the default) and the renewal route refuse
    // velocity-only resetting with a one-sided level (an infinite mean)
    // naming --reset-position, a mesh or time grid out of range naming its
    // flag; Euler a step out of range; a method's flags with another.
    for (extra, flag) in [
        (&[][..], "--reset-position"),
        (
            &["--method", "renewal", "--rate", "1"][..],
            "--reset-position",
        ),
        (
            &[
                "--method",
                "renewal",
                "--reset-position",
                "0",
                "--time-steps",
                "2",
            ][..],
            "--time-steps",
        ),
        (
            &[
                "--method",
                "renewal",
                "--reset-position",
                "0",
                "--horizon-tail",
                "2",
            ][..],
            "--horizon-tail",
        ),
        (
            &[
                "--method",
                "renewal",
                "--reset-position",
                "0",
                "--seed",
                "2",
            ][..],
            "--seed",
        ),
        (
            &["--reset-position", "0", "--time-steps", "50"][..],
            "--time-steps",
        ),
        (&["--method", "euler", "--dt", "-1"][..], "--dt"),
        (
            &["--method", "euler", "--dt", "0.01", "--t-max", "inf"][..],
            "--t-max",
        ),
        (
            &["--reset-position", "0", "--cells-x", "1"][..],
            "--cells-x",
        ),
        (
            &["--reset-position", "0", "--cells-v", "0"][..],
            "--cells-v",
        ),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let d = dir.to_str().unwrap();
        let out = irtp(
            &[
                &["mfpt", "--xt", "1", "--v0", "0"][..],
                extra,
                &["--out", d],
            ]
            .concat(),
        );
        assert_rejected(&out, flag, &dir);
    }
    // The mesh's cost is checked before anything is written.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let args = [
        "mfpt",
        "--xt",
        "1",
        "--v0",
        "0",
        "--reset-position",
        "0",
        "--max-work",
        "1e3",
    ];
    let out = irtp(&[&args[..], &["--out", dir.to_str().unwrap()]].concat());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("too costly") && err.contains("--cells-x"),
        "{err}"
    );
    assert!(!dir.exists());
    // --x0 without a search target, and a velocity and a position target.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let d = dir.to_str().unwrap();
    let out = irtp(&["mfpt", "--vt", "0.5", "--v0", "0", "--x0", "1", "--out", d]);
    assert_rejected(&out, "--x0", &dir);
    let out = irtp(&[
        "mfpt", "--vt", "0.5", "--v0", "0", "--method", "renewal", "--out", d,
    ]);
    assert_rejected(&out, "--method", &dir);
    let out = irtp(&["mfpt", "--vt", "0.5", "--xt", "1", "--v0", "0", "--out", d]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--xt") && err.contains("--vt") && err.lines().count() == 1,
        "{err}"
    );
    assert!(!dir.exists());
}

/// `irtp mfpt distribution --xt`: the sampled search-time histogram and
/// Kaplan-Meier curve; its density integrates to the arrived fraction and
/// no passage comes before |L - x0| / v_max; the backward method (the
/// default) is refused naming `--method`.
#[test]
fn a_search_distribution_writes_the_histogram_and_survival() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let d = dir.to_str().unwrap();
    let args = [
        "mfpt",
        "distribution",
        "--xt",
        "1",
        "--v0",
        "0",
        "--reset-position",
        "0",
        "--method",
        "exact",
        "--particles",
        "4000",
        "--out",
        d,
        "--json",
    ];
    let r = json(&irtp(&args));
    assert_eq!(r["infinite_mean"], false);
    assert!(r["tau"].as_f64().unwrap() > 0.0);
    let hist = std::fs::read_to_string(dir.join("histogram.csv")).unwrap();
    let mut mass = 0.0;
    // tan at Sigma = 3: v_max = atan(3).
    let least = 1.0 / 3f64.atan();
    for line in hist.lines().skip(1) {
        let row: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        mass += row[2] * (row[1] - row[0]);
        if row[4] > 0.0 {
            assert!(row[1] >= least, "{line}");
        }
    }
    assert!((mass - 1.0).abs() < 1e-9, "{mass}");
    assert!(dir.join("survival.csv").exists() && dir.join("distribution.json").exists());
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let d = dir.to_str().unwrap();
    // The backward equation (the default) refuses a level without full
    // resetting (x unbounded) naming --reset-position.
    let out = irtp(&["mfpt", "distribution", "--xt", "1", "--v0", "0", "--out", d]);
    assert_rejected(&out, "--reset-position", &dir);
    for (extra, flag) in [
        (&["--reset-position", "0", "--grid", "log"][..], "--grid"),
        (&["--reset-position", "0", "--rtol", "1e-3"][..], "--rtol"),
        (
            &["--reset-position", "0", "--cells-x", "1"][..],
            "--cells-x",
        ),
        (&["--reset-position", "0", "--points", "2"][..], "--points"),
        (&["--reset-position", "0", "--seed", "2"][..], "--seed"),
        (
            &[
                "--reset-position",
                "0",
                "--method",
                "exact",
                "--cells-v",
                "8",
            ][..],
            "--cells-v",
        ),
    ] {
        let args = [
            &["mfpt", "distribution", "--xt", "1", "--v0", "0"][..],
            extra,
            &["--out", d],
        ];
        assert_rejected(&irtp(&args.concat()), flag, &dir);
    }
}

/// `irtp mfpt distribution --xt --method backward`: S(t), its error and
/// f(t) on a uniform grid; S is a non-increasing probability, and its
/// integral (restricted_mean, S(t_max) ~ 1e-5 beyond) is the stationary
/// solver's tau within their errors.
#[test]
fn a_search_distribution_by_the_backward_equation() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let base = [
        "mfpt",
        "--xt",
        "1",
        "--v0",
        "0",
        "--reset-position",
        "0",
        "--cells-x",
        "16",
        "--cells-v",
        "8",
    ];
    let args = [
        &base[..1],
        &["distribution"],
        &base[1..],
        &["--points", "101", "--json", "--out", dir.to_str().unwrap()],
    ]
    .concat();
    let r = json(&irtp(&args));
    assert_eq!(r["method"], "backward");
    assert_eq!(r["options"]["steps"], 100);
    let mean = json(&irtp(&[&base[..], &["--json"]].concat()));
    let text = std::fs::read_to_string(dir.join("distribution.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,survival,survival_err,density");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 101);
    let mut integral_err = 0.0;
    for w in rows.windows(2) {
        assert!(w[1][1] <= w[0][1] + w[0][2] + w[1][2] + 1e-9 && w[1][1] >= -w[1][2] - 1e-9);
        integral_err += w[1][2] * (w[1][0] - w[0][0]);
    }
    let (tau, e) = (
        mean["tau"].as_f64().unwrap(),
        mean["error_estimate"].as_f64().unwrap(),
    );
    let m = r["restricted_mean"].as_f64().unwrap();
    let tail = 2.0 * r["survival_t_max"].as_f64().unwrap() * (tau + e);
    assert!(
        (m - tau).abs() <= integral_err + e + tail,
        "∫S = {m} ± {integral_err}, tau = {tau} ± {e}"
    );
}

/// The cost is estimated before any work (a pilot of a few particles
/// gives the mean time in flight): too many particles, or an unbounded
/// time in flight, are refused naming the flags, exit 2, nothing written.
#[test]
fn a_costly_search_is_refused_before_it_starts() {
    let base = ["mfpt", "--v0", "0", "--method", "exact"];
    let cases: [(&[&str], &str); 2] = [
        (&["--xt", "1", "--particles", "1e12"], "--particles"),
        (
            &["--xt", "1e300", "--reset-position", "0", "--t-max", "inf"],
            "--t-max",
        ),
    ];
    for (extra, flag) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let d = dir.to_str().unwrap();
        let start = std::time::Instant::now();
        let out = irtp(&[&base[..], extra, &["--out", d]].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("too costly") && err.contains(flag), "{err}");
        assert!(
            err.contains("--max-work") && err.lines().count() == 1,
            "{err}"
        );
        assert!(!dir.exists());
        assert!(start.elapsed().as_secs_f64() < 10.0);
    }
}

/// `--method renewal`: the renewal route of full resetting, its options in
/// the report (provenance) and its tau within the error estimates of the
/// direct backward solve; `--method euler`: tau = 2 T(dt/2) - T(dt) from
/// the two runs reported, within the combined errors of the exact sampler
/// (4 sigma), survival.csv from the run at dt/2.
#[test]
fn renewal_and_euler_searches_report_their_estimates() {
    let base = [
        "mfpt",
        "--xt",
        "0.8",
        "--v0",
        "0",
        "--drag",
        "linear",
        "--sigma",
        "1",
        "--rate",
        "0.5",
        "--reset-position",
        "0",
        "--json",
    ];
    let mesh = ["--cells-x", "16", "--cells-v", "8"];
    let with = |extra: &[&str]| json(&irtp(&[&base[..], extra].concat()));
    let renewal = with(&[&mesh[..], &["--method", "renewal", "--time-steps", "40"]].concat());
    assert_eq!(renewal["method"], "renewal");
    assert_eq!(renewal["options"]["steps"], 40);
    assert_eq!(renewal["options"]["cells_x"], 16);
    let backward = with(&[&mesh[..], &["--method", "backward"]].concat());
    let (tr, tb) = (
        renewal["tau"].as_f64().unwrap(),
        backward["tau"].as_f64().unwrap(),
    );
    let e =
        renewal["error_estimate"].as_f64().unwrap() + backward["error_estimate"].as_f64().unwrap();
    assert!(
        (tr - tb).abs() <= e,
        "renewal {tr}, backward {tb}, errors {e}"
    );
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("e");
    let euler = with(&[
        "--method",
        "euler",
        "--dt",
        "0.02",
        "--particles",
        "20000",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let f = |k: &str| euler[k].as_f64().unwrap();
    let (c, h) = (&euler["coarse"], &euler["fine"]);
    assert_eq!(
        f("tau"),
        2.0 * h["tau"].as_f64().unwrap() - c["tau"].as_f64().unwrap()
    );
    assert_eq!(f("dt"), 0.02);
    assert!(dir.join("survival.csv").exists());
    let exact = with(&["--method", "exact", "--particles", "20000", "--seed", "9"]);
    let (tx, ex) = (
        exact["tau"].as_f64().unwrap(),
        exact["tau_err"].as_f64().unwrap(),
    );
    let z = (f("tau") - tx).abs() / (f("tau_err").powi(2) + ex * ex).sqrt();
    assert!(
        z < 4.0,
        "euler {} ± {}, exact {tx} ± {ex}",
        f("tau"),
        f("tau_err")
    );
}

/// The search's scan and optimum on a small mesh (tan, Sigma = 3, full
/// resetting to (0, 0), the level L = 1).
const SEARCH: [&str; 14] = [
    "--drag",
    "tan",
    "--sigma",
    "3",
    "--lambda",
    "1",
    "--xt",
    "1",
    "--v0",
    "0",
    "--cells-x",
    "8",
    "--cells-v",
    "4",
];

/// `mfpt scan --xt ... --over rate`: the velocity scan's table and output
/// contract, one backward solve per rate (with its error estimate).
#[test]
fn a_search_scan_over_rate_writes_its_table() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    let d = dir.to_str().unwrap();
    let scan = [
        "mfpt",
        "scan",
        "--reset-position",
        "0",
        "--over",
        "rate",
        "--from",
        "0.1",
        "--to",
        "10",
        "--points",
        "4",
        "--log",
        "--out",
        d,
        "--json",
    ];
    let out = irtp(&[&scan[..2], &SEARCH[..], &scan[2..]].concat());
    let v = summary(&out);
    let rows = v["results"].as_array().expect("one object per row");
    assert_eq!(rows.len(), 4);
    for (row, r) in rows.iter().zip([0.1, 1.0, 10.0]) {
        if (row["rate"].as_f64().unwrap() - r).abs() < 1e-9 * r {
            assert!(row["tau"].as_f64().unwrap() >= 1.0 / 1.25, "{row}");
        }
        assert!(row["error_estimate"].as_f64().unwrap() >= 0.0, "{row}");
    }
    // tau grows like e^{r L / v_u} at large r: the last rate is the slowest.
    let tau = |i: usize| rows[i]["tau"].as_f64().unwrap();
    assert!(tau(3) > tau(1), "{rows:?}");
    let csv = std::fs::read_to_string(dir.join("mfpt_scan.csv")).unwrap();
    assert!(
        csv.starts_with("rate,tau,tau_plus,tau_minus,error_estimate\n"),
        "{csv}"
    );
    let run = read_json(&dir.join("run.json")).to_string();
    assert!(
        run.contains("\"over\":\"rate\"") && run.contains("\"Level\":1.0"),
        "{run}"
    );
}

/// `--over x0 --method exact` on an interval with velocity-only resetting:
/// the sampler at every start agrees with the backward equation within 4
/// standard errors (its error estimate added in quadrature).
#[test]
fn a_search_scan_over_x0_samples_every_point() {
    let out = irtp(&[
        "mfpt",
        "scan",
        "--drag",
        "tan",
        "--sigma",
        "3",
        "--lambda",
        "1",
        "--rate",
        "1",
        "--interval",
        "-1,1",
        "--v0",
        "0",
        "--over",
        "x0",
        "--from",
        "-0.5",
        "--to",
        "0.5",
        "--points",
        "3",
        "--cells-x",
        "16",
        "--cells-v",
        "8",
        "--method",
        "exact",
        "--particles",
        "4000",
        "--seed",
        "3",
        "--json",
    ]);
    let v = summary(&out);
    let rows = v["results"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for row in rows {
        let f = |k: &str| row[k].as_f64().unwrap_or_else(|| panic!("{k}: {row}"));
        let z = (f("tau_sim") - f("tau")) / f("tau_sim_err").hypot(f("error_estimate"));
        assert!(z.abs() < 4.0, "z = {z}: {row}");
        assert_eq!(f("censored"), 0.0);
    }
    assert_eq!(v["provenance"]["seed"], 3);
}

/// `mfpt optimize --xt --reset-position`: r* interior (tau(0) infinite,
/// null), inside its error range, tau* below every grid point.
#[test]
fn a_search_optimum_is_found_and_written() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("opt");
    let d = dir.to_str().unwrap();
    let opt = [
        "mfpt",
        "optimize",
        "--reset-position",
        "0",
        "--r-min",
        "0.05",
        "--r-max",
        "20",
        "--grid-points",
        "9",
        "--out",
        d,
        "--json",
    ];
    let out = irtp(&[&opt[..2], &SEARCH[..], &opt[2..]].concat());
    let v = summary(&out);
    let r = &v["results"];
    assert_eq!(r["interior"], true, "{r}");
    assert_eq!(r["at_upper_bound"], false);
    assert!(r["tau_r0"].is_null(), "{r}");
    let f = |k: &str| r[k].as_f64().unwrap();
    let (lo, hi) = (
        r["r_opt_range"][0].as_f64().unwrap(),
        r["r_opt_range"][1].as_f64().unwrap(),
    );
    assert!(lo < f("r_opt") && f("r_opt") < hi, "{r}");
    assert!(f("tau_opt_err") > 0.0);
    let grid = std::fs::read_to_string(dir.join("rate_grid.csv")).unwrap();
    let taus: Vec<f64> = grid
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    assert_eq!(taus.len(), 9);
    assert!(taus.iter().all(|&t| t >= f("tau_opt")), "{taus:?} {r}");
    assert!(dir.join("optimum.json").exists());
}

/// Each refusal of the search's scan and optimize names its flag (exit 2,
/// one line, nothing written): velocity-only resetting with a level (tau
/// infinite at every r), a given --rate, an axis of the other target, a
/// search-only flag with --vt, a scanned rate the solver refuses.
#[test]
fn search_scan_and_optimize_refusals_name_the_flag() {
    let lv = ["--xt", "1", "--v0", "0", "--reset-position", "0"];
    let scan = ["--from", "0.5", "--to", "1"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["optimize", "--xt", "1", "--v0", "0"],
            "--reset-position",
        ),
        (
            [&["optimize"][..], &lv, &["--rate", "1"]].concat(),
            "--rate",
        ),
        (
            [&["optimize"][..], &lv, &["--cells-x", "1"]].concat(),
            "--cells-x",
        ),
        (
            [&["scan"][..], &lv, &["--over", "vt"], &scan].concat(),
            "--over",
        ),
        (
            [
                &["scan", "--interval", "-1,1", "--v0", "0", "--over", "xt"][..],
                &scan,
            ]
            .concat(),
            "--over",
        ),
        (
            [
                &["scan"][..],
                &lv,
                &["--over", "rate", "--from", "0", "--to", "1"],
            ]
            .concat(),
            "--from",
        ),
        (
            [&["scan", "--v0", "0", "--over", "x0"][..], &scan].concat(),
            "--over",
        ),
        (
            // --vt applies to --over rate only (the table's rule).
            [
                &["scan", "--vt", "0.5", "--v0", "0", "--over", "x0"][..],
                &scan,
            ]
            .concat(),
            "--vt",
        ),
        (
            [
                &[
                    "scan", "--vt", "0.5", "--v0", "0", "--over", "rate", "--x0", "1",
                ][..],
                &scan,
            ]
            .concat(),
            "--x0",
        ),
        (
            vec!["optimize", "--vt", "0.5", "--v0", "0", "--cells-v", "8"],
            "--cells-v",
        ),
    ];
    for (args, flag) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let d = dir.to_str().unwrap();
        let out = irtp(&[&["mfpt"][..], &args, &["--out", d]].concat());
        assert_rejected(&out, flag, &dir);
    }
}
