//! The exact first-passage sampler with a noise model
//! (`mfpt::solve` with `Method::Exact`, docs/equations.md Eqs.
//! (N46)-(N48)): the paper's noise spelt as a generator against the
//! two-state sampler, the π-averaged τ against the N-state backward
//! equations (`mfpt::backward`, Eqs. (N30)-(N31)) over
//! `irtp_testkit::noises::NOISE_CASES` at T = 0, bit-identical runs for
//! any thread count and shard split, and the refusals by name. Tolerances:
//! 4 standard errors raised to the Bonferroni bound over each test's
//! comparisons (`bonferroni_z`), the backward solver's own error estimate
//! added in quadrature; fixed seeds.

use irtp::mfpt::{self, BackwardOptions, FptSummary, Method, ParticleOptions, Problem};
use irtp::model::noise::NoiseModel;
use irtp::model::reset::{Periodic, Schedule};
use irtp::parallel::NoProgress;
use irtp::{DragLaw, Params};
use irtp_testkit::noises::{athermal, NoiseCase, NOISE_CASES, PAPER_AS_STATES};
use irtp_testkit::stats::bonferroni_z;

/// The interval a case's targets are chosen in: the noise's velocity
/// interval, cut to ±3.
fn interval(c: &NoiseCase) -> (f64, f64) {
    let (lo, hi) = c.params().bounds();
    (lo.max(-3.0), hi.min(3.0))
}

/// v_0 = v_r, v_t 60 % of the way to the upper edge (upward) or 40 % of
/// the way to the lower edge (downward), as the backward tests.
fn problems(c: &NoiseCase) -> [Problem; 2] {
    let (lo, hi) = interval(c);
    let v0 = c.reset_velocity;
    let p = c.params();
    [
        Problem::new(p.clone(), v0, v0 + 0.6 * (hi - v0)).expect("upward problem"),
        Problem::new(p, v0, v0 + 0.4 * (lo - v0)).expect("downward problem"),
    ]
}

fn exact(particles: u64, seed: u64) -> Method {
    Method::Exact(ParticleOptions {
        particles,
        t_max: f64::INFINITY,
        seed,
    })
}

/// The particle summary of `problem` by the exact sampler, checked: no
/// particle censored, every mean finite and positive.
fn sampled(problem: &Problem, particles: u64, seed: u64, name: &str) -> FptSummary {
    let s = mfpt::solve(problem, &exact(particles, seed), &NoProgress)
        .unwrap_or_else(|e| panic!("{name}: exact: {e}"))
        .summary()
        .expect("a particle estimate");
    assert_eq!(s.censored, 0, "{name}");
    for x in [s.tau, s.tau_err, s.tau_plus, s.tau_minus] {
        assert!(x.is_finite() && x > 0.0, "{name}: {s:?}");
    }
    assert!(s.work_per_particle > 0.0, "{name}");
    s
}

/// (τ, its error estimate) of the N-state backward equations.
fn backward(problem: &Problem, name: &str) -> (f64, f64) {
    let b = mfpt::solve(
        problem,
        &Method::Backward(BackwardOptions::default()),
        &NoProgress,
    )
    .unwrap_or_else(|e| panic!("{name}: backward: {e}"));
    let err = b.backward().map_or(0.0, |b| b.error_estimate);
    (b.tau(), if err.is_finite() { err } else { 0.0 })
}

/// Exact particles against the backward τ for `cases`, both directions;
/// returns the z scores (each asserted within the Bonferroni bound over
/// all of them).
fn against_backward(cases: &[&NoiseCase], particles: u64, seed: u64) -> Vec<f64> {
    let zmax = bonferroni_z(2 * cases.len());
    let mut zs = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        for (k, p) in problems(c).iter().enumerate() {
            let name = format!("{} v0 {} -> vt {:.4}", c.name, p.v0(), p.vt());
            let s = sampled(p, particles, seed + 2 * i as u64 + k as u64, &name);
            let (tau, err) = backward(p, &name);
            let z = (s.tau - tau) / s.tau_err.hypot(err);
            eprintln!(
                "{name}: exact {:.5} ± {:.5} ({:.1} events/particle), backward {tau:.6} ± \
                 {err:.1e}: z = {z:.2} (bound {zmax:.2})",
                s.tau, s.tau_err, s.work_per_particle
            );
            assert!(z.abs() < zmax, "{name}: z = {z} (bound {zmax})");
            zs.push(z);
        }
    }
    zs
}

fn case(name: &str) -> &'static NoiseCase {
    NOISE_CASES.iter().find(|c| c.name == name).unwrap()
}

/// Fast tier: tan under run-pause-tumble (an interior fixed point, v* = 0,
/// approached from either side) and a three-state noise with no symmetry,
/// tanh under an asymmetric telegraph noise; 6 comparisons, bound
/// `bonferroni_z(6)` ≈ 4.4.
#[test]
fn exact_passage_matches_the_backward_equations() {
    let cases = [case("tan-rpt"), case("tanh-asym"), case("tan-three")];
    against_backward(&cases, 20_000, 8100);
}

/// Slow tier: every athermal case of the suite, both directions
/// (Bonferroni over all comparisons).
#[test]
#[ignore = "slow tier: every athermal noise model, exact particles against the backward equations"]
fn exact_passage_matches_the_backward_equations_for_every_noise() {
    let cases: Vec<&NoiseCase> = athermal().collect();
    let zs = against_backward(&cases, 100_000, 8200);
    assert_eq!(zs.len(), 2 * cases.len());
}

/// The paper's noise spelt as a generator (states ±1, rate 0.5) runs the
/// N-state loop (start drawn from π) and has the law of the two-state
/// sampler (start stratified ±Sigma): the means agree within the Bonferroni
/// bound over 4 comparisons (two laws, both directions) of the standard
/// error of their difference (independent streams).
#[test]
fn paper_as_states_has_the_two_state_samplers_law() {
    let cases: Vec<&NoiseCase> = NOISE_CASES
        .iter()
        .filter(|c| c.noise == PAPER_AS_STATES)
        .collect();
    assert_eq!(cases.len(), 2);
    let zmax = bonferroni_z(2 * cases.len());
    for c in cases {
        let drag: DragLaw = c.drag.parse().unwrap();
        let two = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
        for p in problems(c) {
            let q = Problem::new(two.clone(), p.v0(), p.vt()).unwrap();
            let a = sampled(&p, 20_000, 8300, c.name);
            let b = sampled(&q, 20_000, 8301, c.name);
            let z = (a.tau - b.tau) / a.tau_err.hypot(b.tau_err);
            eprintln!(
                "{} vt {:.4}: states {:.5} ± {:.5}, two-state {:.5} ± {:.5}: z = {z:.2}",
                c.name,
                p.vt(),
                a.tau,
                a.tau_err,
                b.tau,
                b.tau_err
            );
            assert!(z.abs() < zmax, "{}: z = {z} (bound {zmax})", c.name);
            // The same events per particle in law.
            let rel = (a.work_per_particle - b.work_per_particle).abs() / b.work_per_particle;
            assert!(rel < 0.1, "{}: events {a:?} {b:?}", c.name);
        }
    }
}

/// Bit-identical for 1 and 2 threads and for a split into shards (3
/// units of particles, cut 1 + 2).
#[test]
fn exact_passage_with_noise_is_identical_across_threads_and_shards() {
    let pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    };
    for c in [case("tan-three"), case("tanh-rpt")] {
        for p in problems(c) {
            let m = exact(10_000, 17);
            let go = |t| pool(t).install(|| mfpt::solve(&p, &m, &NoProgress).unwrap());
            let (a, b) = (go(1), go(2));
            assert_eq!(a, b, "{}", c.name);
            let all = m.unit_count().unwrap();
            assert!(all >= 2, "{all} units");
            let cut = all / 2;
            let mut units = mfpt::particle_units(&p, &m, 0..cut, &NoProgress).unwrap();
            units.extend(mfpt::particle_units(&p, &m, cut..all, &NoProgress).unwrap());
            assert_eq!(
                mfpt::assemble(&p, &m, &units).unwrap(),
                a,
                "{} shards",
                c.name
            );
        }
    }
}

fn refused_name(p: &Params, v0: f64, vt: f64) -> &'static str {
    let pr = Problem::new(p.clone(), v0, vt).unwrap();
    match mfpt::solve(&pr, &exact(10, 1), &NoProgress) {
        Err(e) if e.parameter().is_some() => e.parameter().unwrap(),
        other => panic!("not refused by name: {other:?}"),
    }
}

/// Thermal noise is refused naming `temperature` (no exact flow), a
/// schedule modifier runs, a level at a kink of a law without
/// a closed-form flow naming `noise`; the passage-time control variate
/// refuses thermal noise naming `temperature`.
#[test]
fn refusals_name_their_flag() {
    for c in NOISE_CASES.iter().filter(|c| c.thermal()) {
        let v0 = c.reset_velocity;
        let name = refused_name(&c.params(), v0, v0 + 0.2);
        assert_eq!(name, "temperature", "{}", c.name);
    }
    let rpt = NoiseModel::parse("rpt:sigma=1,alpha=1,beta=1", 0.0).unwrap();
    let thermal = NoiseModel::parse("rpt:sigma=1,alpha=1,beta=1", 0.5).unwrap();
    let p = Params::with_noise(DragLaw::Tan, thermal.clone(), 0.5, 0.0).unwrap();
    assert_eq!(refused_name(&p, 0.0, 0.3), "temperature");
    let periodic = Schedule {
        periodic: Some(Periodic::new(1.5).unwrap()),
        ..Schedule::default()
    };
    let p = Params::with_noise(DragLaw::Tan, rpt.clone(), 0.0, 0.0)
        .unwrap()
        .with_schedule(periodic)
        .unwrap();
    // Every schedule modifier runs with a noise model (one kernel).
    let pr = Problem::new(p, 0.0, 0.3).unwrap();
    assert!(mfpt::solve(&pr, &exact(10, 1), &NoProgress).is_ok());
    let power: DragLaw = "power:n=0.5".parse().unwrap();
    let p = Params::with_noise(power, rpt, 0.5, 0.0).unwrap();
    assert_eq!(refused_name(&p, 0.0, 0.3), "noise");
    // The passage-time control variate runs a noise model at T = 0
    // (mfpt_control_noise.rs) and refuses it with thermal noise.
    let p = Params::with_noise(DragLaw::Tan, thermal, 0.5, 0.0).unwrap();
    let pr = Problem::new(p, 0.0, 0.3).unwrap();
    match mfpt::control::run(&pr, (10, 1, f64::INFINITY), 64, 400, &NoProgress) {
        Err(e) => assert_eq!(e.parameter(), Some("temperature"), "{e}"),
        other => panic!("control variate with thermal noise: {other:?}"),
    }
}
