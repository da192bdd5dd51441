//! `simulate --method euler` and `mfpt --method euler` with `--noise` and
//! `--temperature` (docs/equations.md, "Euler schemes with a noise
//! model"): they run, write their files with the noise model in the
//! provenance, and refuse a step beyond the noise's bound by `--dt`.

use super::common::*;

fn sim(extra: &[&str], out: &str) -> std::process::Output {
    let base = [
        "simulate",
        "--method",
        "euler",
        "--particles",
        "200",
        "--t-max",
        "2",
        "--burn-in",
        "1",
        "--dt",
        "0.01",
        "--out",
        out,
    ];
    irtp(&[&base[..], extra].concat())
}

/// Thermal noise alone on linear drag and run-pause-tumble with thermal
/// noise on tan drag (the drift-implicit step): exit 0, the tables
/// written, `noise` and `temperature` in run.json's parameters.
#[test]
fn simulate_euler_runs_noise_models_and_records_them() {
    let tmp = tempfile::tempdir().unwrap();
    let runs: [(&[&str], &str, &str); 2] = [
        (
            &[
                "--drag",
                "linear",
                "--noise",
                "none",
                "--temperature",
                "0.5",
            ],
            "none",
            "0.5",
        ),
        (
            &[
                "--drag",
                "tan",
                "--noise",
                "rpt:sigma=1,alpha=1,beta=1",
                "--temperature",
                "0.1",
            ],
            "rpt:sigma=1,alpha=1,beta=1",
            "0.1",
        ),
    ];
    for (i, (flags, spec, t)) in runs.iter().enumerate() {
        let dir = tmp.path().join(format!("o{i}"));
        let out = sim(flags, dir.to_str().unwrap());
        assert_success(&out);
        let run = read_json(&dir.join("run.json"));
        let params = run["parameters"].to_string();
        assert!(
            params.contains(&format!("\"noise\":\"{spec}\"")),
            "{params}"
        );
        assert!(params.contains(&format!("\"temperature\":{t}")), "{params}");
        let csvs = std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .path()
                    .extension()
                    .is_some_and(|x| x == "csv")
            })
            .count();
        assert!(csvs >= 2, "{dir:?}");
        let summary = read_json(&dir.join("summary.json"));
        let v2 = summary["results"]["v2"].as_f64().unwrap();
        assert!(v2 > 0.0 && v2.is_finite(), "{summary}");
    }
}

/// A step beyond the N-level bound (asymmetric telegraph on tan drag:
/// 1/(1 + 1.5²) ≈ 0.3077) exits 2 naming --dt, nothing written.
#[test]
fn simulate_euler_refuses_a_step_beyond_the_noise_bound() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("o").join("out");
    std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
    let args = [
        "simulate",
        "--method",
        "euler",
        "--particles",
        "10",
        "--t-max",
        "2",
        "--burn-in",
        "1",
        "--drag",
        "tan",
        "--noise",
        "telegraph:plus=1.5,minus=0.75,rate_plus=0.8,rate_minus=0.4",
        "--dt",
        "0.31",
        "--out",
        dir.to_str().unwrap(),
    ];
    let err = assert_rejected(&irtp(&args), "--dt", &dir);
    assert!(err.contains("0.307"), "{err}");
}

/// mfpt --method euler with thermal noise alone: runs, records the noise.
#[test]
fn mfpt_euler_runs_a_noise_model() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("m");
    let out = irtp(&[
        "mfpt",
        "--method",
        "euler",
        "--drag",
        "linear",
        "--noise",
        "none",
        "--temperature",
        "0.5",
        "--v0",
        "0",
        "--vt",
        "0.5",
        "--rate",
        "1",
        "--particles",
        "200",
        "--dt",
        "0.01",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_success(&out);
    let run = read_json(&dir.join("run.json"));
    let params = run["parameters"].to_string();
    assert!(params.contains("\"noise\":\"none\""), "{params}");
    assert!(params.contains("\"temperature\":0.5"), "{params}");
}
