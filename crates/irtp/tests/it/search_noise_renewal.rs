//! The search's renewal route and its distribution S(t) with a
//! finite-state noise model at T = 0 (the noise kept at a reset, the start
//! drawn from the stationary law π): run-pause-tumble and a three-state
//! noise without symmetry, full resetting, against the 2-D backward
//! equation (within the two error estimates) and the exact sampler (within
//! a Bonferroni 4-sigma bound plus the error estimate).

use irtp::mfpt::ParticleOptions;
use irtp::model::noise::NoiseModel;
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::search::backward::{self, BackwardOptions};
use irtp::search::distribution::{self, DistributionOptions};
use irtp::search::renewal::{self, RenewalOptions, WaitingTime};
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem, SearchResult};
use irtp::{DragLaw, Params};
use irtp_testkit::noises::THREE;
use irtp_testkit::stats::bonferroni_z;

const RPT: &str = "rpt:sigma=1,alpha=1,beta=2";

/// Linear drag, `noise` at T = 0, full resetting to (0, 0) at rate 0.5
/// (noise kept), from (0, 0) to `target`.
fn problem(noise: &str, target: PositionTarget) -> SearchProblem {
    let model = NoiseModel::parse(noise, 0.0).unwrap();
    let params = Params::with_noise(DragLaw::Linear, model, 0.5, 0.0)
        .unwrap()
        .with_schedule(Schedule::parse(None, Some(0.0), None).unwrap())
        .unwrap();
    SearchProblem::new(params, 0.0, 0.0, target).unwrap()
}

/// (tau, standard error, the Kaplan-Meier curve) by the exact sampler.
fn exact(pr: &SearchProblem, seed: u64) -> (f64, f64, irtp::mfpt::SurvivalCurve) {
    let run = ParticleOptions {
        particles: 20_000,
        t_max: 1e4,
        seed,
    };
    match search::solve(pr, &SearchMethod::Exact(run), &NoProgress).unwrap() {
        SearchResult::Particles(r) => {
            let s = r.stats.summary();
            (s.tau, s.tau_err, r.stats.survival())
        }
        other => panic!("the exact sampler gave {other:?}"),
    }
}

/// The fast tier's case: an interval (no far stretch, a short search).
const INTERVAL: (&str, PositionTarget) = (RPT, PositionTarget::Interval(-0.7, 0.5));

/// The slow tier's cases: levels (a far stretch, searches 4 x longer).
const LEVELS: [(&str, PositionTarget); 2] = [
    (RPT, PositionTarget::Level(1.0)),
    (THREE, PositionTarget::Level(1.0)),
];

/// See [`renewal_check`].
#[test]
fn renewal_with_a_noise_model_matches_backward_and_exact() {
    renewal_check(&[INTERVAL], 300);
}

/// See [`renewal_check`].
#[test]
#[ignore = "slow tier: the renewal route with rpt and three-state noise to a level (~30 s)"]
fn renewal_with_a_noise_model_matches_backward_and_exact_levels() {
    renewal_check(&LEVELS, 310);
}

/// The renewal route's tau against the backward solver's (within the sum
/// of their error estimates) and the exact sampler's (within z SE plus
/// the renewal error estimate, z Bonferroni over the cases), with the
/// per-state values T(x0, v0, s) reported for each of the N states.
fn renewal_check(cases: &[(&str, PositionTarget)], seed: u64) {
    let z = bonferroni_z(cases.len());
    let opts = RenewalOptions {
        cells_x: 16,
        cells_v: 8,
        steps: 40,
        ..Default::default()
    };
    for (k, &(noise, target)) in cases.iter().enumerate() {
        let pr = problem(noise, target);
        let waiting = WaitingTime::of(pr.params()).unwrap();
        let r = renewal::solve(&pr, &waiting, &opts).unwrap();
        let b = backward::solve(&pr, &BackwardOptions::with_cells(16, 8)).unwrap();
        let (tau, se, _) = exact(&pr, seed + k as u64);
        eprintln!(
            "{noise} {target:?}: renewal {} ± {}, backward {} ± {}, exact {tau} ± {se}",
            r.tau, r.error_estimate, b.tau, b.error_estimate
        );
        let states = r.tau_states.as_ref().unwrap();
        let n = NoiseModel::parse(noise, 0.0).unwrap().levels().len();
        assert!(states.len() == n && r.reset_states.as_ref().unwrap().len() == n);
        assert!(r.tau_plus.is_nan() && r.error_estimate.is_finite());
        let both = r.error_estimate + b.error_estimate;
        assert!((r.tau - b.tau).abs() < both, "{noise}: renewal vs backward");
        assert!(
            (r.tau - tau).abs() < z * se + r.error_estimate,
            "{noise}: renewal {} vs exact {tau} ± {se}",
            r.tau
        );
    }
}

/// See [`distribution_check`].
#[test]
fn distribution_with_a_noise_model_matches_backward_and_exact() {
    distribution_check(&[INTERVAL], 60.0, 400);
}

/// See [`distribution_check`].
#[test]
#[ignore = "slow tier: S(t) with rpt and three-state noise to a level (~20 s)"]
fn distribution_with_a_noise_model_matches_backward_and_exact_levels() {
    distribution_check(&LEVELS, 200.0, 410);
}

/// S(t) with a noise model: its mean ∫ S dt (to `t_max`, where S is below
/// 1e-4, the tail bounded by S(t_max) t_max) against the backward tau,
/// and S at t = 2, 10, 20 (times of both the curve's uniform grid, step
/// 0.5, and the Kaplan-Meier grid) against the exact sampler's
/// Kaplan-Meier curve within z SE + the curve's error estimate (z
/// Bonferroni over the cases x 3 times).
fn distribution_check(cases: &[(&str, PositionTarget)], t_max: f64, seed: u64) {
    let z = bonferroni_z(3 * cases.len());
    for (k, &(noise, target)) in cases.iter().enumerate() {
        let pr = problem(noise, target);
        let opts = DistributionOptions {
            mesh: BackwardOptions::with_cells(16, 8),
            t_max,
            steps: (2.0 * t_max) as usize,
        };
        let d = distribution::solve(&pr, &opts).unwrap();
        let b = backward::solve(&pr, &BackwardOptions::with_cells(16, 8)).unwrap();
        let n = d.t.len() - 1;
        let dt = d.t[1];
        let mean_err = dt * d.survival_err.iter().sum::<f64>();
        let tail = d.survival[n] * d.t[n];
        eprintln!(
            "{noise}: ∫S = {} ± {mean_err} (S(t_max) = {}), backward {} ± {}",
            d.restricted_mean, d.survival[n], b.tau, b.error_estimate
        );
        assert!(
            d.survival[n] < 1e-4,
            "{noise}: S(t_max) = {}",
            d.survival[n]
        );
        let gap = b.tau - d.restricted_mean;
        assert!(
            gap.abs() < mean_err + b.error_estimate + tail,
            "{noise}: ∫S {} vs backward {}",
            d.restricted_mean,
            b.tau
        );
        let (_, _, km) = exact(&pr, seed + k as u64);
        for t in [2.0, 10.0, 20.0] {
            let i = d.t.iter().position(|&s| s == t).unwrap();
            let j = km.t.iter().position(|&s| s == t).unwrap();
            let (s, se) = (km.survival[j], km.survival_err[j]);
            eprintln!(
                "  S({t}) = {} ± {}, KM {s} ± {se}",
                d.survival[i], d.survival_err[i]
            );
            assert!(
                (d.survival[i] - s).abs() < z * se + d.survival_err[i],
                "{noise}: S({t}) = {} vs KM {s} ± {se}",
                d.survival[i]
            );
        }
    }
}

/// A refusal that remains: the renewal route needs full resetting (one
/// line naming `reset_position`).
#[test]
fn renewal_with_a_noise_model_refuses_velocity_resetting() {
    let model = NoiseModel::parse(RPT, 0.0).unwrap();
    let params = Params::with_noise(DragLaw::Linear, model, 0.5, 0.0).unwrap();
    let pr = SearchProblem::new(params, 0.0, 0.0, PositionTarget::Interval(-0.7, 0.5)).unwrap();
    let e =
        search::solve(&pr, &SearchMethod::Renewal(Default::default()), &NoProgress).unwrap_err();
    let msg = e.to_string();
    assert_eq!(e.parameter(), Some("reset_position"), "{msg}");
    assert!(msg.len() < 200 && !msg.contains('\n'), "{msg}");
}
