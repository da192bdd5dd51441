//! `simulate --method euler` runs every schedule modifier with a noise
//! model (the Euler sampler's scheduled loop over the noise's steps):
//! periodic and renewal clocks, both refractory periods and position
//! resetting with rpt, and periodic resetting with thermal noise, exit 0
//! and write their outputs.

use crate::common::{assert_success, irtp, read_json};

/// (noise, temperature, modifier flags) of each run.
const RUNS: [(&str, &str, &[&str]); 6] = [
    ("rpt:sigma=3,alpha=1,beta=2", "0", &["--reset-period", "1"]),
    (
        "rpt:sigma=3,alpha=1,beta=2",
        "0",
        &["--reset-clock", "gamma:k=2,theta=0.5"],
    ),
    (
        "rpt:sigma=3,alpha=1,beta=2",
        "0",
        &["--refractory", "exp:mean=0.5"],
    ),
    (
        "rpt:sigma=3,alpha=1,beta=2",
        "0",
        &["--refractory", "fixed:t=0.5"],
    ),
    (
        "rpt:sigma=3,alpha=1,beta=2",
        "0",
        &["--reset-position", "0"],
    ),
    (
        "telegraph:sigma=1,lambda=0.5",
        "0.3",
        &["--reset-period", "1"],
    ),
];

#[test]
fn euler_sampler_runs_every_modifier_with_a_noise_model() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, (noise, temp, flags)) in RUNS.iter().enumerate() {
        let dir = tmp.path().join(format!("run{i}"));
        let mut args = vec![
            "simulate",
            "--method",
            "euler",
            "--drag",
            "tan",
            "--noise",
            noise,
            "--temperature",
            temp,
            "--dt",
            "0.001",
            "--particles",
            "100",
            "--out",
            dir.to_str().unwrap(),
        ];
        args.extend_from_slice(flags);
        let out = irtp(&args);
        assert_success(&out);
        let summary = read_json(&dir.join("summary.json"));
        assert!(summary.is_object(), "{flags:?}: {summary}");
        assert!(dir.join("moments.csv").exists(), "{flags:?}");
        assert!(dir.join("density.csv").exists(), "{flags:?}");
        if flags[0] == "--reset-position" {
            assert!(dir.join("position.csv").exists(), "{flags:?}");
        }
    }
}
