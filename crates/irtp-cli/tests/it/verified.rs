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
            let p = Problem::new(
                Params::new(drag.clone(), sigma, lambda, rate, vr).unwrap(),
                v0,
                vt,
            )
            .unwrap();
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
        assert_eq!(o.status.code(), Some(4), "r = {rate}: {err}");
        assert!(err.contains("exceeds the f64 range"), "{err}");
        assert!(!out.exists());
    }
    // The optimum search no longer finds a spurious "interior" optimum at the top of the range.
    let o = irtp(&[
        "mfpt", "optimize", "--v0", "-0.249", "--vt", "0.5", "--r-max", "1e9", "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let v = &v["results"];
    assert_eq!(v["at_upper_bound"], false, "{v}");
    assert!(v["r_opt"].as_f64().unwrap() < 10.0, "{v}");
}

#[test]
fn unresolved_stationary_density_is_refused() {
    let o = irtp(&["fp", "stationary", "--lambda", "1e9"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
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
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(
        err.contains("overflowed") && err.lines().count() == 1,
        "{err}"
    );
    assert!(o.stdout.is_empty() && !out.exists());
}

/// <v²> of the Sigma = 1 limit of tanh drag at r = 0, where the density is
/// cosh²(v) exp(-λ sinh²(v)) (the general r = 0 form with Σ² - tanh² →
/// sech²): composite Simpson on [0, 9] (the integrand is below 1e-300 beyond).
fn tanh_sigma_one_v2(lambda: f64) -> f64 {
    let p = |v: f64| v.cosh().powi(2) * (-lambda * v.sinh().powi(2)).exp();
    let (n, top) = (400_000, 9.0);
    let h = top / n as f64;
    let (mut m0, mut m2) = (0.0, 0.0);
    for i in 0..=n {
        let v = i as f64 * h;
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        m0 += w * p(v);
        m2 += w * v * v * p(v);
    }
    m2 / m0
}

#[test]
fn tanh_density_up_to_the_largest_sigma_below_one() {
    // c = λ/(1 - Σ²) reaches 2e15: the paper's form a ln s - c ln q cancels
    // catastrophically there; the answer must still converge to the Σ = 1
    // limit, with a deviation O(1 - Σ).
    let lambda = 0.5;
    let limit = tanh_sigma_one_v2(lambda);
    for delta in [1e-5, 1e-9, 1e-13, 1.1e-16] {
        let sigma = 1.0 - delta;
        let d = irtp::analytic::r0::R0Density::new(DragLaw::Tanh, sigma, lambda)
            .unwrap_or_else(|e| panic!("Sigma = 1 - {delta}: {e}"));
        let v2 = d.v2();
        assert!(
            (v2 - limit).abs() <= 10.0 * delta + 1e-12,
            "Sigma = 1 - {delta}: <v²> = {v2}, limit {limit}"
        );
    }
}

#[test]
fn exact_sampler_handles_steep_tan_media() {
    // tan at Sigma = 3000 and 3e4: the deficit tables meet tan's pole, where
    // sampled values carry rounding noise above 1e-14; the sampler must run
    // and agree with the exact r = 0 <v²> (two comparisons: Bonferroni at
    // 4 sigma overall is 4.17 standard errors each).
    for sigma in ["3000", "3e4"] {
        let o = irtp(&[
            "simulate",
            "--drag",
            "tan",
            "--sigma",
            sigma,
            "--rate",
            "0",
            "--particles",
            "2000",
            "--t-max",
            "30",
            "--burn-in",
            "10",
            "--json",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let j = &j["results"];
        let (v2, err) = (j["v2"].as_f64().unwrap(), j["v2_err"].as_f64().unwrap());
        let exact = irtp::analytic::r0::R0Density::new(DragLaw::Tan, sigma.parse().unwrap(), 0.5)
            .unwrap()
            .v2();
        assert!(
            (v2 - exact).abs() <= 4.17 * err,
            "Sigma = {sigma}: {v2} ± {err} against {exact}"
        );
    }
}
