//! Exact first-passage sampler vs the backward-equation MFPT (`irtp::mfpt`)
//! on the paper's Fig. 7 setting (v_0 = -0.249, v_t = 0.5, v_r = 0):
//! tau = (tau+ + tau-)/2 within 4 standard errors (backward discretisation
//! error estimate added in quadrature; it is far smaller), through
//! `irtp::mfpt::solve` with `Method::Exact` (what `irtp mfpt --method exact` runs);
//! plus a downward problem (mirror frame, swapped noise states).

use crate::common::models;
use irtp::mfpt::{
    self, BackwardOptions, BackwardSolution, FptSummary, Method, ParticleOptions, Problem,
};
use irtp::parallel::NoProgress;
use irtp::{DragLaw, Params};

/// tau by the backward equations (default mesh), through `mfpt::solve`.
fn backward(p: &Problem) -> BackwardSolution {
    let m = Method::Backward(BackwardOptions::default());
    *mfpt::solve(p, &m, &NoProgress).unwrap().backward().unwrap()
}

/// tau by exact particles (no time cap), through `mfpt::solve`.
fn exact(p: &Problem, particles: u64, seed: u64) -> FptSummary {
    let m = Method::Exact(ParticleOptions {
        particles,
        t_max: f64::INFINITY,
        seed,
    });
    mfpt::solve(p, &m, &NoProgress).unwrap().summary().unwrap()
}

#[test]
fn exact_mfpt_matches_backward_equations() {
    for (i, &(ref d, sigma, lambda, r)) in [
        (DragLaw::Tan, 3.0, 0.9, 0.0),
        (DragLaw::Tan, 3.0, 7.0, 2.0),
        (DragLaw::Tan, 3.0, 15.0, 5.0),
        (DragLaw::Tanh, 0.6, 0.5, 0.0),
        (DragLaw::Tanh, 0.6, 1.2, 0.2),
        (DragLaw::Tanh, 0.6, 3.0, 1.0),
    ]
    .iter()
    .enumerate()
    {
        let p = Params::new(d.clone(), sigma, lambda, r, 0.0).unwrap();
        let (v0, vt) = (-0.249, 0.5);
        let prob = Problem::new(p, v0, vt).unwrap();
        let ode = backward(&prob);
        let s = exact(&prob, 10_000, 50 + i as u64);
        assert_eq!(s.censored, 0);
        let err = ode.error_estimate;
        let err = if err.is_finite() { err } else { 0.0 };
        let se = (s.tau_err.powi(2) + err.powi(2)).sqrt();
        eprintln!(
            "{d} Sigma={sigma} lambda={lambda} r={r}: exact tau {:.5} ± {:.5}, backward {:.5}",
            s.tau, s.tau_err, ode.tau
        );
        assert!(
            ((s.tau - ode.tau) / se).abs() < 4.0,
            "{d} Sigma={sigma} lambda={lambda} r={r}: exact {} ± {}, backward {}",
            s.tau,
            s.tau_err,
            ode.tau
        );
    }
}

#[test]
fn exact_mfpt_downward_matches_backward_equations() {
    let p = models::tanh(1.2, 0.5);
    let prob = Problem::new(p, 0.3, -0.5).unwrap();
    let ode = backward(&prob);
    let s = exact(&prob, 10_000, 77);
    for (est, se, exact) in [
        (s.tau_plus, s.tau_plus_err, ode.tau_plus),
        (s.tau_minus, s.tau_minus_err, ode.tau_minus),
    ] {
        assert!(
            ((est - exact) / se).abs() < 4.0,
            "downward: {est} ± {se} vs backward {exact}"
        );
    }
}
