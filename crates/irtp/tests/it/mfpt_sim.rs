//! Backward equations against the particle simulation (ground truth).

use crate::common::models;
use irtp::mfpt::backward::profile;
use irtp::mfpt::{
    self, BackwardOptions, DriftSign, FptStats, FptSummary, Method, ParticleOptions, Problem,
};
use irtp::parallel::NoProgress;
use irtp::{DragLaw, Params};

fn problem(drag: DragLaw, sigma: f64, lambda: f64, r: f64, vr: f64, v0: f64, vt: f64) -> Problem {
    Problem::new(Params::new(drag, sigma, lambda, r, vr).unwrap(), v0, vt).unwrap()
}

/// Euler time step: dt = min(1e-3, 1e-3 / r). The Euler bias (dynamics,
/// event timing, overshoot of at most dt) is O(dt) and grows with r·dt;
/// `euler_dt_bias_measurement` below compares dt with dt/2 (common random
/// numbers, 2e4 particles) on the whole table: |Δtau| < 1e-3 tau, so the
/// bias (≈ 2|Δtau|) is < 0.2 % of tau while 4 standard errors with 6000
/// particles are ≥ 3 % of tau: the 4-sigma test is not masked by the bias.
/// (With dt = 1e-3 at r = 10 the bias was ≈ 1 %: hence the r-dependent dt.)
fn dt_for(r: f64) -> f64 {
    1e-3f64.min(1e-3 / r)
}
const PARTICLES: u64 = 6000;

/// Euler first-passage statistics through `mfpt::solve`.
fn euler_first_passage(
    p: &Problem,
    dt: f64,
    t_max: f64,
    particles: u64,
    seed: u64,
    progress: &NoProgress,
) -> irtp::Result<FptStats> {
    let run = ParticleOptions {
        particles,
        t_max,
        seed,
    };
    let r = mfpt::solve(p, &Method::Euler { dt, run }, progress)?;
    Ok(r.stats().expect("particles").clone())
}

fn euler(p: &Problem, seed: u64) -> FptSummary {
    euler_first_passage(
        p,
        dt_for(p.params().rate()),
        1e4,
        PARTICLES,
        seed,
        &NoProgress,
    )
    .unwrap()
    .summary()
}

fn within(ode: f64, sim: f64, se: f64, what: &str) {
    assert!(
        (ode - sim).abs() < 4.0 * se,
        "{what}: ode {ode} vs euler {sim} ± {se} (z = {:.2})",
        (sim - ode) / se
    );
}

/// (drag, Sigma, lambda, r, v_r, v0, v_t)
#[allow(clippy::type_complexity)]
const CASES: [(DragLaw, f64, f64, f64, f64, f64, f64); 9] = [
    (DragLaw::Tan, 3.0, 0.5, 0.0, 0.0, -0.249, 0.5),
    (DragLaw::Tan, 3.0, 0.5, 2.0, 0.0, -0.249, 0.5),
    (DragLaw::Tan, 3.0, 0.5, 10.0, 0.0, -0.249, 0.3),
    (DragLaw::Tan, 3.0, 5.0, 2.0, 0.0, -0.249, 0.3),
    (DragLaw::Tan, 3.0, 5.0, 0.0, 0.0, -0.249, 0.5),
    (DragLaw::Tan, 3.0, 1.0, 1.0, 0.0, 0.3, -0.2),
    (DragLaw::Tanh, 0.6, 0.5, 0.2, 0.0, -0.249, 0.3),
    (DragLaw::Tanh, 0.6, 3.0, 0.5, 0.0, -0.249, 0.1),
    (DragLaw::Tanh, 0.6, 0.5, 10.0, 0.0, -0.249, 0.1),
];

/// v0 = -0.249, v_r = 0 (paper Fig. 7), both media, lambda small and large,
/// r from 0 to 10, several targets, and one target below v0 (reflection).
#[test]
#[ignore = "slow tier"]
fn backward_equations_match_euler_simulation() {
    let cases = CASES;
    for (i, &(ref d, s, l, r, vr, v0, vt)) in cases.iter().enumerate() {
        let p = problem(d.clone(), s, l, r, vr, v0, vt);
        let ode = profile(&p, &BackwardOptions::with_cells(4000))
            .unwrap()
            .at_start();
        let sim = euler(&p, 100 + i as u64);
        assert_eq!(sim.censored, 0);
        assert_eq!(sim.tau_lower_bound, None);
        let what = format!("{d} lambda={l} r={r} vt={vt}");
        within(ode.tau, sim.tau, sim.tau_err, &what);
        within(
            ode.tau_plus,
            sim.tau_plus,
            sim.tau_plus_err,
            &format!("{what} tau+"),
        );
        within(
            ode.tau_minus,
            sim.tau_minus,
            sim.tau_minus_err,
            &format!("{what} tau-"),
        );
    }
}

/// The paper's Eqs. (26)-(27) print the drifts as g(v) ± Sigma. Solved as
/// printed (with the paper's boundary conditions) they miss the simulation
/// by far more than 10 standard errors, while the generator's ±Sigma - g(v)
/// agrees (previous test).
#[test]
fn paper_printed_sign_disagrees_with_simulation() {
    let printed = BackwardOptions {
        cells: 4000,
        drift: DriftSign::PaperPrinted,
    };
    for (i, &(ref d, s, l, r, vt)) in [
        (DragLaw::Tan, 3.0, 0.5, 0.0, 0.5),
        (DragLaw::Tan, 3.0, 5.0, 0.0, 0.5),
        (DragLaw::Tanh, 0.6, 0.5, 0.2, 0.3),
    ]
    .iter()
    .enumerate()
    {
        let p = problem(d.clone(), s, l, r, 0.0, -0.249, vt);
        let paper = profile(&p, &printed).unwrap().at_start().tau;
        let sim = euler(&p, 200 + i as u64);
        let z = (paper - sim.tau).abs() / sim.tau_err;
        assert!(
            z > 10.0,
            "{d} lambda={l}: printed-sign tau {paper} vs euler {} (z = {z})",
            sim.tau
        );
    }
}

#[test]
fn bit_identical_for_any_thread_count() {
    let p = models::fig7(DragLaw::Tan, 0.5, 2.0, 0.5);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| euler_first_passage(&p, 1e-3, 1e4, 700, 9, &NoProgress).unwrap())
    };
    assert_eq!(run(1), run(3));
}

/// Particles not arrived by t_max are counted, not dropped: no mean is
/// presented, the restricted mean is the lower bound.
#[test]
fn censoring_is_reported() {
    let p = models::fig7(DragLaw::Tanh, 0.5, 0.0, 0.5);
    let st = euler_first_passage(&p, 1e-3, 2.0, 400, 4, &NoProgress).unwrap();
    let s = st.summary();
    assert_eq!(s.particles, 400);
    assert!(s.censored > 0 && s.tau_lower_bound == Some(s.rmst));
    assert_eq!(
        st.arrived.iter().map(|a| a.n).sum::<u64>() + s.censored,
        400
    );
    assert!(s.tau.is_nan() && s.tau_err.is_nan(), "{s:?}");
    assert!(s.rmst > 0.0 && s.rmst <= 2.0, "{s:?}");
}

/// The measurement behind the tolerance comment on [`dt_for`] (slow tier;
/// `cargo test -p irtp --test it -- --ignored --nocapture euler_dt_bias` prints
/// it): tau at dt and dt/2 with common random numbers, 2e4 particles, on the
/// whole table.
#[test]
#[ignore = "slow tier"]
fn euler_dt_bias_measurement() {
    for (i, &(ref d, s, l, r, vr, v0, vt)) in CASES.iter().enumerate() {
        let p = problem(d.clone(), s, l, r, vr, v0, vt);
        let t = |dt| {
            euler_first_passage(&p, dt, 1e4, 20_000, 500 + i as u64, &NoProgress)
                .unwrap()
                .summary()
                .tau
        };
        let dt = dt_for(r);
        let (a, b) = (t(dt), t(0.5 * dt));
        let rel = (a - b).abs() / b;
        println!("{d} lambda={l} r={r} vt={vt}: dt={dt} {a:.5} dt/2 {b:.5} rel {rel:.2e}");
        assert!(rel < 1e-3);
    }
}
