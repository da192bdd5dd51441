//! `mfpt --method backward`, `mfpt scan` and `mfpt optimize` with a noise
//! model (`irtp::mfpt::backward`, docs/equations.md Eqs. (N30)-(N36)): runs
//! write their outputs with the noise and temperature in the parameters and
//! give the library's numbers; bad input is refused naming the flag.

use super::common::*;
use irtp::mfpt::{backward, BackwardOptions, Problem};
use irtp::model::noise::NoiseModel;
use irtp::{DragLaw, Params};

const RPT: &str = "rpt:sigma=1,alpha=1,beta=1";

fn problem(drag: DragLaw, spec: &str, t: f64, rate: f64, vr: f64, v0: f64, vt: f64) -> Problem {
    let noise = NoiseModel::parse(spec, t).unwrap();
    Problem::new(Params::with_noise(drag, noise, rate, vr).unwrap(), v0, vt).unwrap()
}

/// A run-pause-tumble and a thermal case: the outputs are written, the
/// parameters name the noise (and temperature), and τ is the library's.
#[test]
fn backward_runs_a_noise_model_and_writes_it() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = [
        ("tan", RPT, 0.0, ["--v0", "0", "--vt", "0.5", "--rate", "1"]),
        (
            "linear",
            "none",
            0.5,
            ["--v0", "0", "--vt", "1", "--rate", "0.5"],
        ),
    ];
    for (i, (drag, spec, t, args)) in cases.into_iter().enumerate() {
        let dir = tmp.path().join(format!("o{i}"));
        let ts = t.to_string();
        let base = [
            "mfpt",
            "--method",
            "backward",
            "--cells",
            "4000",
            "--drag",
            drag,
            "--noise",
            spec,
            "--temperature",
            &ts,
            "--json",
            "--out",
            dir.to_str().unwrap(),
        ];
        let out = irtp(&[&base[..], &args[..]].concat());
        let s = summary(&out);
        let v0: f64 = args[1].parse().unwrap();
        let vt: f64 = args[3].parse().unwrap();
        let rate: f64 = args[5].parse().unwrap();
        let lib = backward::solve_states(
            &problem(drag.parse().unwrap(), spec, t, rate, 0.0, v0, vt),
            &BackwardOptions::with_cells(4000),
        )
        .unwrap();
        assert_eq!(s["results"]["tau"].as_f64(), Some(lib.tau), "{s}");
        let params = s["params"].to_string();
        assert!(
            params.contains("noise") && params.contains(spec),
            "{params}"
        );
        let run = read_json(&dir.join("run.json"));
        let text = run["parameters"].to_string();
        assert!(text.contains(spec), "{text}");
        if t > 0.0 {
            assert!(text.contains("temperature"), "{text}");
        }
        let profile = std::fs::read_to_string(dir.join("profile.csv")).unwrap();
        assert!(profile.lines().count() > 100);
    }
}

/// scan over the rate and optimize run a noise model.
#[test]
fn scan_and_optimize_run_a_noise_model() {
    let noise = ["--drag", "tan", "--noise", RPT, "--cells", "2000", "--json"];
    let scan = [
        "mfpt", "scan", "--v0", "0", "--vt", "0.5", "--over", "rate", "--from", "0.5", "--to", "1",
        "--points", "2",
    ];
    summary(&irtp(&[&scan[..], &noise[..]].concat()));
    let opt = ["mfpt", "optimize", "--v0", "0", "--vt", "0.5"];
    let j = json(&irtp(&[&opt[..], &noise[..]].concat()));
    assert!(j.to_string().contains("rate"), "{j}");
}

/// A target outside the noise's interval, a negative temperature, and tan
/// with T > 1: exit 2, one line naming the flag, nothing written.
#[test]
fn bad_noise_backward_input_names_the_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: [(Vec<&str>, &str); 3] = [
        (
            vec!["--drag", "tan", "--noise", RPT, "--v0", "0", "--vt", "0.8"],
            "--vt",
        ),
        (
            vec![
                "--drag",
                "linear",
                "--noise",
                "none",
                "--temperature",
                "-1",
                "--v0",
                "0",
                "--vt",
                "1",
            ],
            "--temperature",
        ),
        (
            vec![
                "--drag",
                "tan",
                "--noise",
                "none",
                "--temperature",
                "2",
                "--v0",
                "0",
                "--vt",
                "1",
            ],
            "--temperature",
        ),
    ];
    for (i, (args, flag)) in cases.into_iter().enumerate() {
        let dir = tmp.path().join(format!("b{i}")).join("out");
        std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
        let base = [
            "mfpt",
            "--method",
            "backward",
            "--out",
            dir.to_str().unwrap(),
        ];
        let out = irtp(&[&base[..], &args[..]].concat());
        assert_rejected(&out, flag, &dir);
    }
}

/// `mfpt distribution --method backward` runs a noise model at temperature
/// 0 and writes its files (the mean that of the library's backward tau);
/// with thermal noise and a drag the thermal backward equations do not run
/// it is refused naming `--drag`, nothing written.
#[test]
fn distribution_runs_a_noise_model_and_writes_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let base = [
        "mfpt",
        "distribution",
        "--v0",
        "0",
        "--vt",
        "0.5",
        "--rate",
        "1",
        "--method",
        "backward",
        "--noise",
        RPT,
        "--cells",
        "2000",
        "--points",
        "51",
    ];
    let d = dir.to_str().unwrap();
    let s = summary(&irtp(&[&base[..], &["--json", "--out", d][..]].concat()));
    let r = &s["results"];
    let (mean, tau) = (
        r["distribution_mean"].as_f64().unwrap(),
        r["tau"].as_f64().unwrap(),
    );
    assert!((mean - tau).abs() < 1e-3 * tau, "{s}");
    let atom = r["atom_mass"].as_f64().unwrap();
    assert!(atom > 0.0 && atom < 1.0, "{s}");
    // run-pause-tumble to v_t = 0.5 < g⁻¹(1): only the +1 state's flow
    // reaches it.
    let atoms = r["atoms"].as_array().expect("atoms");
    assert_eq!(atoms.len(), 1, "{s}");
    assert_eq!(atoms[0]["level"].as_f64(), Some(1.0), "{s}");
    assert!(s["params"].to_string().contains(RPT), "{s}");
    let csv = std::fs::read_to_string(dir.join("distribution.csv")).unwrap();
    assert_eq!(csv.lines().count(), 52, "{csv}");
    assert!(dir.join("run.json").exists());
    let refused = tmp.path().join("t").join("out");
    std::fs::create_dir_all(refused.parent().unwrap()).unwrap();
    let args = [
        &base[..],
        &[
            "--temperature",
            "0.5",
            "--drag",
            "cubic",
            "--out",
            refused.to_str().unwrap(),
        ][..],
    ]
    .concat();
    let err = assert_rejected(&irtp(&args), "--drag", &refused);
    assert!(err.contains("this drag with thermal noise"), "{err}");
}

/// `mfpt distribution` with thermal noise (Eq. (N49)): the paper's noise
/// with a temperature and tanh drag runs, records the temperature and its
/// provenance, and its survival starts at 1 and falls; E(T) agrees with
/// the thermal backward tau printed beside it.
#[test]
fn distribution_runs_with_thermal_noise() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let args = [
        "mfpt",
        "distribution",
        "--drag",
        "tanh",
        "--sigma",
        "0.5",
        "--lambda",
        "1",
        "--temperature",
        "0.1",
        "--v0",
        "0",
        "--vt",
        "0.3",
        "--rate",
        "1",
        "--json",
        "--out",
        dir.to_str().unwrap(),
    ];
    let s = summary(&irtp(&args));
    let r = &s["results"];
    let (mean, tau) = (
        r["distribution_mean"].as_f64().unwrap(),
        r["tau"].as_f64().unwrap(),
    );
    assert!((mean - tau).abs() < 1e-2 * tau, "{s}");
    // No atoms with thermal noise: +0 (not -0).
    assert_eq!(r["atom_mass"].to_string(), "0.0", "{s}");
    assert!(s["params"].to_string().contains("temperature"), "{s}");
    // The provenance file: who wrote it, from what, with which parameters.
    let run = std::fs::read_to_string(dir.join("run.json")).unwrap();
    let run: serde_json::Value = serde_json::from_str(&run).unwrap();
    for k in ["software", "version", "git_revision", "argv", "checksums"] {
        assert!(run.get(k).is_some(), "no {k} in {run}");
    }
    assert!(
        run["parameters"].to_string().contains("temperature"),
        "{run}"
    );
    let csv = std::fs::read_to_string(dir.join("distribution.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = head
        .iter()
        .position(|&h| h == "survival")
        .expect("survival");
    let surv: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    assert!((surv[0] - 1.0).abs() < 1e-12, "{csv}");
    assert!(surv.windows(2).all(|w| w[1] <= w[0] + 1e-6), "{csv}");
    assert!(*surv.last().unwrap() < 0.5, "{csv}");
}
