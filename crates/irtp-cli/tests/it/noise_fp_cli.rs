//! `irtp fp stationary|transient|msd` with `--noise` and `--temperature`
//! (the N-state solvers, docs/equations.md (N20)-(N29)): they write their
//! files with the noise and temperature in the recorded parameters, and
//! refuse bad input by flag with exit 2 and nothing written.

use super::common::*;

const RPT: &str = "rpt:sigma=1,alpha=1,beta=1";

/// The recorded model of an output directory names the noise and T.
fn recorded(dir: &std::path::Path, noise: &str, t: f64) {
    let run = read_json(&dir.join("run.json"));
    let model = &run["parameters"]["model"];
    let text = model.to_string();
    assert!(text.contains(noise), "{noise} not in {text}");
    assert_eq!(model["temperature"].as_f64(), Some(t), "{text}");
    let summary = read_json(&dir.join("summary.json"));
    assert!(summary["params"].to_string().contains(noise), "{summary}");
}

/// A CSV header.
fn header(path: &std::path::Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines().next().unwrap().to_string()
}

#[test]
fn fp_stationary_runs_a_noise_model_and_thermal_noise() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str, f64, usize); 2] = [
        (&["--noise", RPT, "--drag", "tan"], "rpt:", 0.0, 3),
        (
            &[
                "--noise",
                "none",
                "--temperature",
                "0.5",
                "--drag",
                "linear",
                "--rate",
                "0",
            ],
            "none",
            0.5,
            1,
        ),
    ];
    for (i, (flags, name, t, states)) in cases.iter().enumerate() {
        let dir = tmp.path().join(format!("s{i}"));
        let args = [
            &["fp", "stationary", "--cells", "400", "--json", "--out"][..],
            &[dir.to_str().unwrap()][..],
            flags,
        ]
        .concat();
        let j = json(&irtp(&args));
        recorded(&dir, name, *t);
        let cols: Vec<String> = (0..*states).map(|k| format!("p_{k}")).collect();
        assert_eq!(
            header(&dir.join("density.csv")),
            format!("v,p,{},dv", cols.join(","))
        );
        assert_eq!(j["levels"].as_array().unwrap().len(), *states, "{j}");
        assert!(j["error_estimates"]["v2"].as_f64().unwrap() < 1e-3, "{j}");
        assert_eq!(j["drift"], j["v_mean"]);
        if *t > 0.0 {
            // Ornstein-Uhlenbeck, r = 0: <v²> = T, to the error estimate.
            let est = j["error_estimates"]["v2"].as_f64().unwrap();
            assert!((j["v2"].as_f64().unwrap() - 0.5).abs() <= est, "{j}");
            assert!(j["tail_mass"].as_f64().unwrap() < 1e-10, "{j}");
        }
    }
}

#[test]
fn fp_transient_and_msd_run_a_noise_model() {
    let tmp = tempfile::tempdir().unwrap();
    let runs: [&[&str]; 2] = [
        &[
            "fp",
            "transient",
            "--cells",
            "128",
            "--t-max",
            "1",
            "--samples",
            "5",
            "--snapshots",
            "2",
        ],
        &["fp", "msd", "--cells", "50", "--t-max", "1"],
    ];
    for (i, cmd) in runs.iter().enumerate() {
        let dir = tmp.path().join(format!("t{i}"));
        let args = [
            *cmd,
            &[
                "--noise",
                "rpt:sigma=0.6,alpha=1,beta=1",
                "--temperature",
                "0.1",
                "--drag",
                "tanh",
                "--json",
                "--out",
            ][..],
            &[dir.to_str().unwrap()][..],
        ]
        .concat();
        json(&irtp(&args));
        recorded(&dir, "rpt:", 0.1);
        if i == 0 {
            assert_eq!(header(&dir.join("snapshots.csv")), "t,v,p,p_0,p_1,p_2");
        }
    }
}

#[test]
fn fp_with_a_noise_model_refuses_bad_input_by_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &["fp", "stationary", "--noise", RPT, "--cells", "402"],
            "--cells",
        ),
        (
            &[
                "fp",
                "transient",
                "--noise",
                RPT,
                "--t-max",
                "1",
                "--scheme",
                "paper",
            ],
            "--scheme",
        ),
        (
            &["fp", "stationary", "--noise", RPT, "--temperature", "-1"],
            "--temperature",
        ),
        (
            &[
                "fp",
                "stationary",
                "--noise",
                RPT,
                "--reset-to",
                "uniform:lo=-0.5,hi=0.5",
                "--rate",
                "1",
            ],
            "--reset-to",
        ),
    ];
    for (i, (args, flag)) in cases.iter().enumerate() {
        let dir = tmp.path().join(format!("b{i}")).join("out");
        std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
        let full = [*args, &["--out", dir.to_str().unwrap()][..]].concat();
        assert_rejected(&irtp(&full), flag, &dir);
    }
}

/// `fp stationary` and `mfpt` (backward) run an exponential refractory
/// period with a noise model (docs/equations.md (R10), (R11)): the held
/// mass r M/(1 + r M) (r = 2, M = 0.5) per state as π/2 in `held`, and a
/// finite τ.
#[test]
fn a_refractory_period_runs_with_a_noise_model() {
    let base = [
        "--drag",
        "tan",
        "--noise",
        RPT,
        "--refractory",
        "exp:mean=0.5",
    ];
    let s = json(&irtp(
        &[&["fp", "stationary"][..], &base, &["--json"]].concat(),
    ));
    assert!(
        (s["refractory_mass"].as_f64().unwrap() - 0.5).abs() < 1e-14,
        "{s}"
    );
    let held: Vec<f64> = serde_json::from_value(s["held"].clone()).unwrap();
    let pi: Vec<f64> = serde_json::from_value(s["pi"].clone()).unwrap();
    for (q, p) in held.iter().zip(&pi) {
        assert!((q - 0.5 * p).abs() < 1e-15, "{held:?} vs {pi:?}");
    }
    let vt = ["--v0", "0", "--vt", "0.5", "--json"];
    let m = json(&irtp(&[&["mfpt"][..], &base, &vt].concat()));
    let tau = m["tau"].as_f64().unwrap_or(f64::NAN);
    assert!(tau.is_finite() && tau > 0.0, "{m}");
}
