//! Answers are verified or refused: the backward MFPT against its rigorous
//! lower bound (a reset-free stretch as long as the fastest flow to the
//! target is needed), the stationary FP moments against 0 <= <v²> <= v_u²
//! and D_eff >= 0. Cases that used to print a wrong number with exit 0.

use irtp::mfpt::backward::{self, BackwardOptions};
use irtp::mfpt::Problem;
use irtp::{DragLaw, Params};
use std::process::Command;

fn irtp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn backward_tau_respects_its_lower_bound() {
    let cases = [
        (DragLaw::Tan, 3.0, 0.5, -0.249, 0.5, 0.0),
        (DragLaw::Tanh, 0.6, 0.85, -0.2, 0.3, 0.05),
        (DragLaw::Linear, 1.0, 1.0, 0.4, -0.3, 0.1),
    ];
    for (drag, sigma, lambda, v0, vt, vr) in cases {
        for rate in [0.0, 0.5, 5.0, 50.0] {
            let p =
                Problem::new(Params::new(drag, sigma, lambda, rate, vr).unwrap(), v0, vt).unwrap();
            let bound = backward::lower_bound(&p);
            let s = backward::solve(&p, &BackwardOptions::with_cells(4000)).unwrap();
            assert!(
                bound > 0.0 && s.tau >= bound,
                "{drag} r = {rate}: tau {} < bound {bound}",
                s.tau
            );
        }
    }
}

#[test]
fn extreme_reset_rates_are_refused_not_answered() {
    // tau grows like e^{r T*}: from r = 1e4 on it exceeds the f64 range.
    for rate in ["1e4", "1e6", "1e7", "1e8"] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("o");
        let o = irtp(&[
            "mfpt",
            "--v0",
            "-0.249",
            "--vt",
            "0.5",
            "--rate",
            rate,
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "r = {rate}: {err}");
        assert!(err.contains("exceeds the f64 range"), "{err}");
        assert!(!out.exists());
    }
    // The optimum search no longer finds a spurious "interior" optimum at the top of the range.
    let o = irtp(&[
        "mfpt", "optimize", "--v0", "-0.249", "--vt", "0.5", "--r-max", "1e9", "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["at_upper_bound"], false, "{v}");
    assert!(v["r_opt"].as_f64().unwrap() < 10.0, "{v}");
}

#[test]
fn unresolved_stationary_density_is_refused() {
    let o = irtp(&["fp", "stationary", "--lambda", "1e9"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("does not resolve the density"), "{err}");
    assert!(o.stdout.is_empty());
}

#[test]
fn non_finite_results_are_refused() {
    // <v²> ~ Sigma² = 1e600 overflows: refused, nothing printed or written.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    let o = irtp(&[
        "simulate",
        "--drag",
        "linear",
        "--sigma",
        "1e300",
        "--particles",
        "100",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("overflowed") && err.lines().count() == 1,
        "{err}"
    );
    assert!(o.stdout.is_empty() && !out.exists());
}
