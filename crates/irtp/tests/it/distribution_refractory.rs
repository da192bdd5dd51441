//! The first-passage-time distribution of the time-dependent backward
//! equations with an exponential refractory period and the paper's noise
//! (docs/equations.md, (R12)): its own mean against the backward mean τ
//! with the hold (R6), S(t) against the exact sampler (4 standard errors,
//! Bonferroni-corrected), and the limit of a vanishing hold.

use crate::common::models;
use crate::common::stats::bonferroni_z;
use irtp::mfpt::{
    self, distribution, BackwardOptions, Distribution, DistributionOptions, Method,
    ParticleOptions, Problem,
};
use irtp::model::reset::{NoiseAtReset, Target};
use irtp::parallel::NoProgress;
use irtp::{DragLaw, Params};

/// `p` with an exponential refractory period of mean `m`.
fn held(p: Params, m: f64) -> Params {
    models::with_schedule(p, None, None, Some(&format!("exp:mean={m}")))
}

/// The paper's noise (Sigma = 1, lambda = 0.5, tan drag), r = 1, v_r = 0.
fn paper() -> Params {
    Params::new(DragLaw::Tan, 1.0, 0.5, 1.0, 0.0).unwrap()
}

fn options(cells: usize) -> DistributionOptions {
    DistributionOptions {
        backward: BackwardOptions::with_cells(cells),
        ..DistributionOptions::default()
    }
}

/// The distribution of `p` from 0 to 0.5 at `times` on `cells` cells.
fn solve(p: Params, times: &[f64], cells: usize) -> Distribution {
    let prob = Problem::new(p, 0.0, 0.5).unwrap();
    distribution(&prob, times, &options(cells)).unwrap()
}

/// ∫ S dt equals the backward mean τ with the same hold, within both
/// error estimates: a point target, and a uniform target (part of it
/// beyond v_t: a passage at the reset) with the noise re-drawn.
#[test]
fn held_distribution_mean_matches_backward_tau() {
    let uniform = |p: Params| {
        p.with_reset(Target::uniform(-0.4, 0.7), NoiseAtReset::Redrawn)
            .unwrap()
    };
    for (name, p) in [
        ("point", held(paper(), 0.5)),
        ("uniform", uniform(held(paper(), 0.5))),
    ] {
        let d = solve(p.clone(), &[0.0, 1.0, 2.0], 2000);
        let prob = Problem::new(p, 0.0, 0.5).unwrap();
        let b = mfpt::backward::solve(&prob, &BackwardOptions::with_cells(8000)).unwrap();
        let tol = d.mean_error + b.error_estimate + d.tail_mass * d.t_end;
        eprintln!("{name}: E(T) = {}, tau = {}, tol = {tol:e}", d.mean, b.tau);
        assert!(
            (d.mean - b.tau).abs() <= tol,
            "{name}: {} vs {}",
            d.mean,
            b.tau
        );
        // The hold lengthens the search (r M = 0.5 of held time per reset).
        let plain = solve(paper(), &[0.0, 1.0], 2000).mean;
        assert!(
            name != "point" || d.mean > plain + 0.1,
            "{} vs {plain}",
            d.mean
        );
    }
}

/// S(t) at the Kaplan-Meier grid times nearest tau / 2, tau and 2 tau
/// against the exact sampler's survival (half the particles started in
/// each state: the mixture S), |z| within 4 standard errors
/// (Bonferroni over the three times).
#[test]
fn held_distribution_survival_matches_exact_sampler() {
    let p = held(paper(), 0.5);
    let prob = Problem::new(p.clone(), 0.0, 0.5).unwrap();
    let run = ParticleOptions {
        particles: 40_000,
        t_max: 1e4,
        seed: 7301,
    };
    let r = mfpt::solve(&prob, &Method::Exact(run), &NoProgress).unwrap();
    let c = r.stats().expect("particles").survival();
    let tau = mfpt::backward::solve(&prob, &BackwardOptions::with_cells(4000))
        .unwrap()
        .tau;
    let idx: Vec<usize> = [0.5, 1.0, 2.0]
        .iter()
        .map(|x| {
            let near = |i: &usize| (c.t[*i] - x * tau).abs();
            (0..c.t.len())
                .min_by(|a, b| near(a).total_cmp(&near(b)))
                .unwrap()
        })
        .collect();
    let times: Vec<f64> = idx.iter().map(|&i| c.t[i]).collect();
    let d = solve(p, &times, 4000);
    let zmax = bonferroni_z(times.len());
    for (k, &i) in idx.iter().enumerate() {
        let z = (c.survival[i] - d.survival[k]) / c.survival_err[i].hypot(d.mesh_error);
        eprintln!(
            "t = {}: particles {:.4} ± {:.4}, S = {:.4}, z = {z:.2}",
            c.t[i], c.survival[i], c.survival_err[i], d.survival[k]
        );
        assert!(z.abs() <= zmax, "t = {}: z = {z}", c.t[i]);
    }
}

/// A hold of mean 1e-6 gives the plain distribution: S within the
/// integration's slack (10 rtol, as the distribution's own checks) and the
/// mean within r M tau-scale terms (1e-5).
#[test]
fn a_vanishing_hold_gives_the_plain_distribution() {
    let times: Vec<f64> = (0..=20).map(|k| 0.25 * k as f64).collect();
    let (a, b) = (
        solve(held(paper(), 1e-6), &times, 2000),
        solve(paper(), &times, 2000),
    );
    let worst = a
        .survival
        .iter()
        .zip(&b.survival)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    eprintln!("max |ΔS| = {worst:e}, ΔE(T) = {:e}", a.mean - b.mean);
    assert!(worst <= 10.0 * options(2000).rtol, "max |ΔS| = {worst}");
    assert!((a.mean - b.mean).abs() <= 1e-5, "{} vs {}", a.mean, b.mean);
    assert!(a.mean > b.mean, "a hold cannot shorten the search");
}
