//! `irtp simulate` through the binary: outputs, JSON contract,
//! thread-count independence, and bad-input handling.

use crate::common::{assert_rejected, assert_success, irtp_env, json, read_json};
use std::path::Path;
use std::process::Output;

/// A small, fast run.
const SMALL: &[&str] = &[
    "--particles",
    "300",
    "--t-max",
    "0.5",
    "--burn-in",
    "0.2",
    "--samples",
    "6",
    "--bins",
    "10",
];

/// SMALL with the flags of `over` replaced by `over`'s values.
fn with_defaults<'a>(over: &[&'a str]) -> Vec<&'a str> {
    let mut args: Vec<&str> = Vec::new();
    for pair in SMALL.chunks(2) {
        if !over.contains(&pair[0]) {
            args.extend(pair);
        }
    }
    args.extend(over);
    args
}

/// `irtp simulate args...` on `threads` rayon threads.
fn simulate(args: &[&str], threads: &str) -> Output {
    let all = [&["simulate"][..], args].concat();
    irtp_env(&all, &[("RAYON_NUM_THREADS", threads)])
}

#[test]
fn writes_outputs_and_json() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    let mut args = SMALL.to_vec();
    args.extend([
        "--out",
        out.to_str().unwrap(),
        "--json",
        "--seed",
        "9",
        "--method",
        "euler",
    ]);
    let j = json(&simulate(&args, "2"));
    for key in [
        "v2",
        "v2_err",
        "x2_final",
        "x2_final_err",
        "particles",
        "steps",
        "method",
        "dt",
        "wall_time_s",
    ] {
        assert!(!j[key].is_null(), "missing {key} in {j}");
    }
    assert_eq!(j["particles"], 300);
    assert_eq!(j["steps"], 300 * 500);
    assert_eq!(j["method"], "euler");
    assert!(j["v2"].as_f64().unwrap() > 0.0);

    let moments = std::fs::read_to_string(out.join("moments.csv")).unwrap();
    let header = moments.lines().next().unwrap();
    for col in ["t", "v_mean", "v2", "v2_err", "x_mean", "x2", "x2_err"] {
        assert!(header.split(',').any(|c| c == col), "{header}");
    }
    assert_eq!(moments.lines().count(), 1 + 6);
    let density = std::fs::read_to_string(out.join("density.csv")).unwrap();
    assert_eq!(
        density.lines().next().unwrap(),
        "v,p,p_err,p_final,p_final_err"
    );
    assert_eq!(density.lines().count(), 1 + 10);
    let run = read_json(&out.join("run.json"));
    assert_eq!(run["method"], "euler");
    assert_eq!(run["seed"], 9);
    assert_eq!(run["parameters"]["dt"], 1e-3);
    assert_eq!(run["parameters"]["model"]["drag"], "tan");
    assert!(run["wall_time_s"].as_f64().unwrap() >= 0.0);
    assert!(!run["version"].is_null());
    // Nothing else left behind (no staging directory).
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
}

#[test]
fn human_summary_without_json() {
    let o = simulate(SMALL, "1");
    assert_success(&o);
    let s = String::from_utf8(o.stdout).unwrap();
    assert!((2..=6).contains(&s.lines().count()), "{s}");
    assert!(s.contains("<v^2>"), "{s}");
}

fn run_to(dir: &Path, threads: &str, extra: &[&str]) -> (Vec<u8>, Vec<u8>) {
    let mut args = SMALL.to_vec();
    args.extend(extra);
    args.extend(["--out", dir.to_str().unwrap()]);
    assert_success(&simulate(&args, threads));
    (
        std::fs::read(dir.join("moments.csv")).unwrap(),
        std::fs::read(dir.join("density.csv")).unwrap(),
    )
}

/// moments.csv and density.csv are byte-identical for 1 and 2 threads.
#[test]
fn identical_files_for_one_and_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, extra) in [
        &[][..],
        &["--method", "euler"][..],
        &[
            "--method",
            "euler",
            "--events",
            "bernoulli",
            "--drag",
            "tanh",
            "--sigma",
            "0.6",
        ][..],
    ]
    .into_iter()
    .enumerate()
    {
        // One directory per run: --out over another run is refused.
        let a = run_to(&tmp.path().join(format!("a{i}")), "1", extra);
        let b = run_to(&tmp.path().join(format!("b{i}")), "2", extra);
        assert_eq!(a, b);
    }
}

/// Each bad input: exit code 2, exactly one stderr line naming the flag,
/// nothing on stdout, and the --out directory not created.
#[test]
fn bad_input_is_one_line_exit_2_nothing_written() {
    let cases: &[(&[&str], &str)] = &[
        (&["--sigma", "0"], "--sigma"),
        (&["--sigma", "-1"], "--sigma"),
        (&["--sigma", "NaN"], "--sigma"),
        (&["--sigma", "inf"], "--sigma"),
        (&["--drag", "tanh", "--sigma", "1"], "--sigma"),
        (&["--drag", "tanh", "--sigma", "1.5"], "--sigma"),
        (&["--lambda", "-0.5"], "--lambda"),
        (&["--lambda", "nan"], "--lambda"),
        (&["--rate", "-1"], "--rate"),
        (&["--rate", "inf"], "--rate"),
        (&["--reset-velocity", "1.3"], "--reset-velocity"),
        (&["--reset-velocity", "-1.3"], "--reset-velocity"),
        (&["--method", "euler", "--dt", "0"], "--dt"),
        (&["--method", "euler", "--dt", "-0.001"], "--dt"),
        (&["--method", "euler", "--dt", "0.1"], "--dt"),
        (&["--method", "euler", "--dt", "nan"], "--dt"),
        (
            &[
                "--method", "euler", "--rate", "20", "--dt", "0.06", "--drag", "linear",
            ],
            "--dt",
        ),
        // The exact sampler (default) has no time step or event sampler.
        (&["--dt", "1e-3"], "--dt"),
        (&["--events", "bernoulli"], "--events"),
        (&["--particles", "1"], "--particles"),
        (&["--particles", "0"], "--particles"),
        (&["--t-max", "0"], "--t-max"),
        (&["--t-max", "-1"], "--t-max"),
        (&["--t-max", "inf"], "--t-max"),
        (&["--burn-in", "0.5"], "--burn-in"),
        (&["--burn-in", "-0.1"], "--burn-in"),
        (&["--bins", "0"], "--bins"),
        (&["--samples", "1"], "--samples"),
        (&["--grid", "log", "--t-min", "0"], "--t-min"),
        (&["--grid", "log", "--t-min", "1"], "--t-min"),
        (&["--particles", "x"], "--particles"),
        (&["--drag", "quartic"], "--drag"),
    ];
    let tmp = tempfile::tempdir().unwrap();
    for (i, (bad, flag)) in cases.iter().enumerate() {
        let out = tmp.path().join(format!("out{i}"));
        let mut args = with_defaults(bad);
        args.extend(["--out", out.to_str().unwrap()]);
        let o = simulate(&args, "1");
        // Values that do not even parse are clap's errors (with a usage hint);
        // every parameter rule is our one-line message.
        let unparsable = ["x", "quartic"].contains(&bad[1]);
        if unparsable {
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{bad:?}: {err}");
            assert!(o.stdout.is_empty(), "{bad:?}");
            let first = err.lines().find(|l| !l.trim().is_empty()).unwrap();
            assert!(first.contains(flag), "{bad:?}: {err}");
            assert!(!out.exists(), "{bad:?} created the output dir");
        } else {
            assert_rejected(&o, flag, &out);
        }
    }
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

/// --out naming an existing file: one-line error naming --out, exit 2, the
/// file untouched and nothing else created.
#[test]
fn out_is_a_file() {
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("file");
    std::fs::write(&f, "keep").unwrap();
    let mut args = SMALL.to_vec();
    args.extend(["--out", f.to_str().unwrap()]);
    let o = simulate(&args, "1");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--out"), "{err}");
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "keep");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
}

/// A log grid denser than dt at its short end still runs; its times are
/// multiples of dt and strictly increasing.
#[test]
fn log_grid_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("log");
    let args = with_defaults(&["--grid", "log", "--t-min", "0.001", "--samples", "50"]);
    let mut args = args;
    args.extend(["--out", out.to_str().unwrap()]);
    assert_success(&simulate(&args, "2"));
    let m = std::fs::read_to_string(out.join("moments.csv")).unwrap();
    let t: Vec<f64> = m
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert!(t.len() >= 10 && t.len() <= 50);
    assert!(t.windows(2).all(|w| w[1] > w[0]));
    assert_eq!(*t.last().unwrap(), 0.5);
}
