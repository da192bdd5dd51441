//! The cross-method suite of the noise models: every case of
//! `irtp_testkit::noises::NOISE_CASES` (linear, tan and tanh drag under the
//! asymmetric telegraph, run-pause-tumble, three-state, thermal and
//! telegraph + thermal noises, and the paper's noise spelt as a generator)
//! is run by every method that runs it, and the methods are held against
//! each other (the closed forms of linear drag are each engine's own test):
//!
//! (a) stationary <v> and <v²>: the particle sampler (exact without thermal
//!     noise, Euler-Maruyama at dt and dt/2 extrapolated with it) against
//!     the N-state Fokker-Planck solver;
//! (b) the mean first passage v_r → v_t: Euler particles at dt and dt/2
//!     extrapolated (with the Brownian-bridge crossing check at T > 0)
//!     against the N-state backward equations (the exact first-passage
//!     sampler's own comparison, at T = 0: noise_fpt_exact.rs).
//!
//! One tolerance per suite: 4 standard errors raised to the Bonferroni
//! bound over every comparison of the suite, the deterministic solver's
//! own error estimate added in quadrature.

use crate::common::noises::{NoiseCase, NOISE_CASES};
use crate::common::stats::bonferroni_z;
use irtp::fp::{stationary, StationaryOptions};
use irtp::mfpt::{self, BackwardOptions, Method as MfptMethod, ParticleOptions, Problem};
use irtp::parallel::NoProgress;
use irtp::sim::{self, Method, SimSpec, TimeGrid};

/// Euler's step for the thermal cases (the extrapolation runs dt and dt/2).
const DT: f64 = 4e-3;

/// An estimate and its standard error.
type Est = (f64, f64);

/// The sampler's time-averaged (<v>, <v²>): exact without thermal noise,
/// Euler at DT and DT/2 extrapolated (2 m(dt/2) - m(dt), independent seeds)
/// with it.
fn sampled_moments(c: &NoiseCase, seed: u64) -> [Est; 2] {
    let p = c.params();
    let grid = TimeGrid::from_times(vec![0.0, 60.0]).unwrap();
    let run = |m: Method, seed: u64| {
        let spec = SimSpec::new(2000, grid.clone(), 10.0, 20, seed).unwrap();
        let o =
            sim::simulate(&p, &spec, m, &NoProgress).unwrap_or_else(|e| panic!("{}: {e}", c.name));
        [
            (o.v_time_avg.mean(), o.v_time_avg.sem()),
            (o.v2_time_avg.mean(), o.v2_time_avg.sem()),
        ]
    };
    if !c.thermal() {
        return run(Method::Exact, seed);
    }
    let (a, b) = (
        run(Method::euler(DT), seed),
        run(Method::euler(DT / 2.0), seed + 1),
    );
    [0, 1].map(|k| {
        (
            2.0 * b[k].0 - a[k].0,
            (4.0 * b[k].1 * b[k].1 + a[k].1 * a[k].1).sqrt(),
        )
    })
}

/// (a) Samplers vs Fokker-Planck, <v> and <v²>, every case.
#[test]
#[ignore = "slow tier: 14 noise models, particles against the N-state FP solver"]
fn samplers_match_fokker_planck_for_every_noise() {
    let zmax = bonferroni_z(2 * NOISE_CASES.len());
    for (i, c) in NOISE_CASES.iter().enumerate() {
        let p = c.params();
        let fp = stationary(&p, &StationaryOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", c.name));
        let summary = fp.noise.as_ref().expect("the N-state solver ran");
        let errors = summary.errors.unwrap_or([0.0; 3]);
        let mean: f64 = summary.state_means.iter().sum();
        let s = sampled_moments(c, 7100 + 2 * i as u64);
        for (k, (name, want, err)) in [("<v>", mean, errors[0]), ("<v²>", fp.v2, errors[1])]
            .into_iter()
            .enumerate()
        {
            let (got, se) = s[k];
            let z = (got - want) / se.hypot(err);
            eprintln!(
                "{}: {name} sampled {got:.5} ± {se:.5}, FP {want:.5} ± {err:.1e}: z = {z:.2}",
                c.name
            );
            assert!(z.abs() < zmax, "{}: {name} z = {z} (bound {zmax})", c.name);
        }
    }
}

/// A passage inside each case's velocity interval: from v_r upward, 60 %
/// of the way to the upper edge (or to v_r + 1 where the interval is
/// unbounded or longer).
fn passage(c: &NoiseCase) -> (f64, f64) {
    let (_, hi) = c.params().bounds();
    let v0 = c.reset_velocity;
    (v0, v0 + 0.6 * (hi.min(v0 + 1.0) - v0))
}

/// (b) Particles vs backward equations, the mean first passage, every case.
#[test]
#[ignore = "slow tier: 14 noise models, Euler particles at two steps against the backward equations"]
fn first_passage_samplers_match_backward_equations_for_every_noise() {
    let zmax = bonferroni_z(NOISE_CASES.len());
    for (i, c) in NOISE_CASES.iter().enumerate() {
        let (v0, vt) = passage(c);
        let prob = Problem::new(c.params(), v0, vt).unwrap_or_else(|e| panic!("{}: {e}", c.name));
        let ode = mfpt::solve(
            &prob,
            &MfptMethod::Backward(BackwardOptions::default()),
            &NoProgress,
        )
        .unwrap_or_else(|e| panic!("{}: backward: {e}", c.name));
        let tau = ode.tau();
        let err = ode
            .backward()
            .map(|b| b.error_estimate)
            .filter(|e| e.is_finite())
            .unwrap_or(0.0);
        let run = |seed: u64| ParticleOptions {
            particles: 16_000,
            t_max: 1e4,
            seed,
        };
        let sampled = |m: MfptMethod| {
            let s = mfpt::solve(&prob, &m, &NoProgress)
                .unwrap_or_else(|e| panic!("{}: {}: {e}", c.name, m.name()))
                .summary()
                .expect("a particle estimate");
            assert_eq!(s.censored, 0, "{}", c.name);
            (s.tau, s.tau_err)
        };
        let seed = 7300 + 2 * i as u64;
        let a = sampled(MfptMethod::Euler {
            dt: DT,
            run: run(seed),
        });
        let b = sampled(MfptMethod::Euler {
            dt: DT / 2.0,
            run: run(seed + 1),
        });
        let (got, se) = (2.0 * b.0 - a.0, (4.0 * b.1 * b.1 + a.1 * a.1).sqrt());
        let z = (got - tau) / se.hypot(err);
        eprintln!(
            "{}: tau {v0} -> {vt}: sampled {got:.4} ± {se:.4}, backward {tau:.5} ± {err:.1e}: z = {z:.2}",
            c.name
        );
        assert!(z.abs() < zmax, "{}: z = {z} (bound {zmax})", c.name);
    }
}
