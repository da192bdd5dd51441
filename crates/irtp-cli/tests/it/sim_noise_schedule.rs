//! `simulate --method exact` runs every schedule modifier with a
//! finite-state noise (one event loop over the noise's states): the
//! periodic and renewal clocks, both refractory periods and position
//! resetting with rpt, states: and telegraph: noises exit 0 and write their
//! outputs; with thermal noise a modifier is refused in one line naming its
//! flag, nothing written.

use crate::common::{assert_rejected, assert_success, irtp, read_json};

/// (noise, modifier flags, Poisson rate) of each run.
const RUNS: [(&str, &[&str], &str); 6] = [
    ("rpt:sigma=3,alpha=1,beta=2", &["--reset-period", "1"], "0"),
    (
        "rpt:sigma=3,alpha=1,beta=2",
        &["--reset-clock", "gamma:k=2,theta=0.5"],
        "0",
    ),
    (
        "rpt:sigma=3,alpha=1,beta=2",
        &["--refractory", "exp:mean=0.5"],
        "1",
    ),
    (
        "rpt:sigma=3,alpha=1,beta=2",
        &["--refractory", "fixed:t=0.5"],
        "1",
    ),
    (
        "states:levels=[-0.6,0.3,1.1],rates=[[-1,0.6,0.4],[0.5,-0.8,0.3],[0.2,0.9,-1.1]]",
        &["--reset-position", "0"],
        "1",
    ),
    (
        "telegraph:plus=2,minus=1,rate_plus=1,rate_minus=0.5",
        &["--reset-position", "0"],
        "1",
    ),
];

#[test]
fn exact_sampler_runs_every_modifier_with_a_noise_model() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, (noise, flags, rate)) in RUNS.iter().enumerate() {
        let dir = tmp.path().join(format!("run{i}"));
        let mut args = vec![
            "simulate",
            "--drag",
            "tan",
            "--noise",
            noise,
            "--rate",
            rate,
            "--particles",
            "400",
            "--out",
            dir.to_str().unwrap(),
        ];
        args.extend_from_slice(flags);
        let out = irtp(&args);
        assert_success(&out);
        let summary = read_json(&dir.join("summary.json"));
        assert!(summary.is_object(), "{flags:?}: {summary}");
        assert!(dir.join("moments.csv").exists(), "{flags:?}");
        if flags[0] == "--reset-position" {
            assert!(dir.join("position.csv").exists(), "{flags:?}");
        }
    }
}

/// Thermal noise (linear drag, its Ornstein-Uhlenbeck segments) runs the
/// Poisson protocol only: a modifier is refused in one line (< 200
/// characters) naming its flag, exit 2, nothing written.
#[test]
fn thermal_noise_refuses_a_modifier_by_its_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out").join("run");
    std::fs::create_dir(tmp.path().join("out")).unwrap();
    let out = irtp(&[
        "simulate",
        "--drag",
        "linear",
        "--noise",
        "rpt:sigma=1,alpha=1,beta=2",
        "--temperature",
        "0.5",
        "--reset-period",
        "1",
        "--particles",
        "100",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let err = assert_rejected(&out, "--reset-period", &dir);
    assert!(err.trim_end().chars().count() < 200, "{err}");
    assert!(
        err.contains("not run by simulate --method exact; runs in simulate (euler)"),
        "{err}"
    );
}
