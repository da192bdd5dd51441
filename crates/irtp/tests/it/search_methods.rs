//! The search problem's particle runs beyond the exact sampler: the Euler
//! scheme at dt and dt/2 extrapolated to dt → 0 against the exact sampler,
//! and particle runs cut into units of particles whose merged totals are
//! bit-identical to the run made whole (velocity target and search, exact
//! and Euler), for any thread count.

use irtp::mfpt::{self, ParticleOptions, Problem};
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem, SearchResult};
use irtp::{DragLaw, Params};

/// Full resetting to (x_r, v_r) = (0, 0) at rate `rate` (noise kept).
fn full(law: DragLaw, sigma: f64, rate: f64) -> Params {
    let schedule = Schedule::parse(None, Some(0.0), None).unwrap();
    Params::new(law, sigma, 1.0, rate, 0.0)
        .unwrap()
        .with_schedule(schedule)
        .unwrap()
}

fn run(particles: u64, seed: u64) -> ParticleOptions {
    ParticleOptions {
        particles,
        t_max: 1e4,
        seed,
    }
}

/// The Euler estimate extrapolated to dt → 0 agrees with the exact sampler
/// within 4 combined standard errors (Bonferroni over the 2 problems:
/// 4 sigma is a two-sided chance below 1.3e-4 each), for linear drag with
/// a level and tan drag with an interval, both under full resetting; the
/// extrapolation is 2 T(dt/2) - T(dt), bit for bit.
#[test]
fn euler_search_extrapolates_to_the_exact_sampler() {
    let cases = [
        (
            full(DragLaw::Linear, 1.0, 0.5),
            0.0,
            PositionTarget::Level(0.8),
        ),
        (
            full(DragLaw::Tan, 1.0, 1.0),
            0.1,
            PositionTarget::Interval(-0.6, 0.5),
        ),
    ];
    for (p, v0, target) in cases {
        let pr = SearchProblem::new(p, 0.0, v0, target).unwrap();
        let euler = SearchMethod::Euler {
            dt: 0.02,
            run: run(40_000, 11),
        };
        let SearchResult::Euler(e) = search::solve(&pr, &euler, &NoProgress).unwrap() else {
            panic!("an Euler result")
        };
        let (c, f) = (e.coarse.summary(), e.fine.summary());
        assert_eq!(e.extrapolated.tau, 2.0 * f.tau - c.tau);
        assert_eq!(e.extrapolated.tau_err, 2.0 * f.tau_err + c.tau_err);
        let exact = search::solve(&pr, &SearchMethod::Exact(run(40_000, 12)), &NoProgress).unwrap();
        let (tau, _, _, err) = exact.tau();
        let (ex, _, _, ex_err) = SearchResult::Euler(e.clone()).tau();
        let z = (ex - tau).abs() / (ex_err * ex_err + err * err).sqrt();
        eprintln!(
            "{target:?}: Euler dt {} ± {}, dt/2 {} ± {}, extrapolated {ex} ± {ex_err}; \
             exact {tau} ± {err}; z = {z:.2}",
            c.tau, c.tau_err, f.tau, f.tau_err
        );
        assert!(
            z < 4.0,
            "{target:?}: Euler extrapolated {ex} ± {ex_err}, exact {tau} ± {err} (z = {z:.2}); \
             dt: {} ± {}, dt/2: {} ± {}",
            c.tau,
            c.tau_err,
            f.tau,
            f.tau_err
        );
        assert!(e.mean_is_finite && c.censored == 0 && f.censored == 0);
    }
}

/// The Euler sampler refuses a step beyond its limits by name (it runs
/// refractory periods: `search_euler_refractory`).
#[test]
fn euler_search_refuses_by_name() {
    let pr = SearchProblem::new(
        full(DragLaw::Linear, 1.0, 0.5),
        0.0,
        0.0,
        PositionTarget::Level(1.0),
    )
    .unwrap();
    let name = |m: SearchMethod, pr: &SearchProblem| {
        let e = m.check(pr).unwrap_err();
        e.parameter().unwrap_or_else(|| panic!("{e}"))
    };
    let euler = |dt, t_max| SearchMethod::Euler {
        dt,
        run: ParticleOptions {
            particles: 100,
            t_max,
            seed: 1,
        },
    };
    assert_eq!(name(euler(-0.1, 10.0), &pr), "dt");
    assert_eq!(name(euler(3.0, 10.0), &pr), "dt");
    assert_eq!(name(euler(0.01, f64::INFINITY), &pr), "t_max");
}

/// Unit ranges for `parts` parts of `units` units.
fn split(units: u64, parts: u64) -> Vec<std::ops::Range<u64>> {
    (0..parts)
        .map(|k| k * units / parts..(k + 1) * units / parts)
        .collect()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// A particle run cut into 3 parts (unit ranges computed separately, on 1
/// or 2 threads) and assembled gives the run made whole on 1 thread, bit
/// for bit: the search's exact and Euler methods, and the velocity
/// target's.
#[test]
fn particle_runs_in_parts_are_bit_identical_to_the_whole() {
    let n = 3 * irtp::parallel::UNIT + 3;
    let pr = SearchProblem::new(
        full(DragLaw::Tanh, 0.6, 1.0),
        0.0,
        0.1,
        PositionTarget::Level(0.3),
    )
    .unwrap();
    for method in [
        SearchMethod::Exact(run(n, 5)),
        SearchMethod::Euler {
            dt: 0.05,
            run: run(n, 6),
        },
    ] {
        let whole = pool(1).install(|| search::solve(&pr, &method, &NoProgress).unwrap());
        let units = method.unit_count().unwrap();
        assert!(units >= 3);
        for threads in [1, 2] {
            let parts: Vec<_> = split(units, 3)
                .into_iter()
                .flat_map(|r| {
                    pool(threads)
                        .install(|| search::particle_units(&pr, &method, r, &NoProgress).unwrap())
                })
                .collect();
            let merged = search::assemble(&pr, &method, &parts).unwrap();
            assert_eq!(merged, whole, "{} on {threads} threads", method.name());
        }
        let bad = search::particle_units(&pr, &method, 0..units + 1, &NoProgress);
        assert!(bad.is_err());
        assert!(search::assemble(&pr, &method, &[]).is_err());
    }
    let p = Params::new(DragLaw::Tanh, 0.6, 0.5, 0.2, 0.0).unwrap();
    let vp = Problem::new(p, -0.249, 0.1).unwrap();
    for method in [
        mfpt::Method::Exact(run(n, 7)),
        mfpt::Method::Euler {
            dt: 0.01,
            run: run(n, 8),
        },
    ] {
        let whole = pool(1).install(|| mfpt::solve(&vp, &method, &NoProgress).unwrap());
        let units = method.unit_count().unwrap();
        for threads in [1, 2] {
            let parts: Vec<_> = split(units, 3)
                .into_iter()
                .flat_map(|r| {
                    pool(threads)
                        .install(|| mfpt::particle_units(&vp, &method, r, &NoProgress).unwrap())
                })
                .collect();
            let merged = mfpt::assemble(&vp, &method, &parts).unwrap();
            assert_eq!(merged, whole, "{} on {threads} threads", method.name());
        }
    }
}

/// The distribution's options: a 16 × 8 coarse mesh (refined once), `steps`
/// steps to `t_max`.
fn dist_opts(t_max: f64, steps: usize) -> search::distribution::DistributionOptions {
    search::distribution::DistributionOptions {
        mesh: search::backward::BackwardOptions::with_cells(16, 8),
        t_max,
        steps,
    }
}

/// S(t) by linear interpolation on the uniform grid of `d`.
fn s_at(d: &search::distribution::SearchDistribution, t: f64) -> (f64, f64) {
    let dt = d.t[1];
    let i = ((t / dt).floor() as usize).min(d.t.len() - 2);
    let a = (t - d.t[i]) / dt;
    let lerp = |v: &[f64]| (1.0 - a) * v[i] + a * v[i + 1];
    (
        lerp(&d.survival),
        lerp(&d.survival_err).max(d.survival_err[i]),
    )
}

/// S(t) by the time-dependent backward equation with full resetting
/// against the exact sampler's Kaplan-Meier curve at 10 times spread over
/// the curve, for linear drag (a level) and tan drag (an interval): within
/// 4 standard errors of the curve plus the backward error estimate (20
/// comparisons, Bonferroni: each two-sided 4 sigma has a chance below
/// 6.4e-5). The curve is a probability, non-increasing, f = -dS/dt is its
/// slope, and ∫ S dt is the stationary solver's tau within both errors.
#[test]
fn backward_distribution_matches_the_sampler_and_the_mean() {
    let cases = [
        (
            full(DragLaw::Linear, 1.0, 0.5),
            0.0,
            PositionTarget::Level(0.8),
        ),
        (
            full(DragLaw::Tan, 1.0, 1.0),
            0.1,
            PositionTarget::Interval(-0.6, 0.5),
        ),
    ];
    for (p, v0, target) in cases {
        let pr = SearchProblem::new(p, 0.0, v0, target).unwrap();
        let mean =
            search::backward::solve(&pr, &search::backward::BackwardOptions::with_cells(16, 8))
                .unwrap();
        let t_max = 12.0 * mean.tau;
        let d = search::distribution::solve(&pr, &dist_opts(t_max, 200)).unwrap();
        let n = d.t.len() - 1;
        assert_eq!(d.survival[0], 1.0);
        for i in 1..=n {
            let e = d.survival_err[i] + d.survival_err[i - 1] + 1e-9;
            assert!(d.survival[i] <= d.survival[i - 1] + e && d.survival[i] >= -e);
        }
        // f is -dS/dt: its trapezoid integral is the drop of S.
        let drop: f64 = (1..=n)
            .map(|i| 0.5 * (d.density[i] + d.density[i - 1]) * d.t[1])
            .sum();
        assert!(
            (drop - (1.0 - d.survival[n])).abs() < 1e-2,
            "{drop} {}",
            d.survival[n]
        );
        // ∫ S dt against tau: the tail beyond t_max adds at most
        // S(t_max) times the mean of a fresh search from there, below tau
        // from the worst start; bounded by S(t_max) (tau + error) · 2.
        let integral_err: f64 = d.survival_err.iter().sum::<f64>() * d.t[1];
        let tail = d.survival[n] * 2.0 * (mean.tau + mean.error_estimate);
        let gap = (d.restricted_mean - mean.tau).abs();
        eprintln!(
            "{target:?}: ∫S = {} ± {integral_err}, tau = {} ± {}, S(t_max) = {}",
            d.restricted_mean, mean.tau, mean.error_estimate, d.survival[n]
        );
        assert!(
            gap <= integral_err + mean.error_estimate + tail,
            "{target:?}: ∫S = {} ± {integral_err}, tau = {} ± {}, tail {tail}",
            d.restricted_mean,
            mean.tau,
            mean.error_estimate
        );
        let exact = search::exact::stats(&pr, t_max, 40_000, 21, &NoProgress).unwrap();
        let km = exact.survival();
        let inside: Vec<usize> = (1..km.t.len())
            .filter(|&i| km.t[i] < t_max && km.survival[i] > 0.02)
            .collect();
        assert!(inside.len() >= 10, "{}", inside.len());
        for k in 0..10 {
            let i = inside[k * (inside.len() - 1) / 9];
            let (s, err) = s_at(&d, km.t[i]);
            let bound = 4.0 * km.survival_err[i] + err;
            eprintln!(
                "  t = {:.4}: backward {s:.5} ± {err:.1e}, Kaplan-Meier {:.5} ± {:.1e}",
                km.t[i], km.survival[i], km.survival_err[i]
            );
            assert!(
                (s - km.survival[i]).abs() <= bound,
                "{target:?} at t = {}: backward {s} ± {err}, sampler {} ± {}",
                km.t[i],
                km.survival[i],
                km.survival_err[i]
            );
        }
    }
}

/// The distribution refuses by name what it does not run: a level with
/// velocity-only resetting (x unbounded), a periodic clock.
#[test]
fn backward_distribution_refuses_by_name() {
    let name = |pr: &SearchProblem| match search::distribution::solve(pr, &dist_opts(5.0, 50)) {
        Err(e) if e.parameter().is_some() => e.parameter().unwrap(),
        r => panic!("{r:?}"),
    };
    let velocity_only = Params::new(DragLaw::Linear, 1.0, 1.0, 0.5, 0.0).unwrap();
    let pr =
        SearchProblem::new(velocity_only.clone(), 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    assert_eq!(name(&pr), "reset_position");
    let periodic = Params::new(DragLaw::Linear, 1.0, 1.0, 0.0, 0.0)
        .unwrap()
        .with_schedule(Schedule::parse(Some(2.0), Some(0.0), None).unwrap())
        .unwrap();
    let pr = SearchProblem::new(periodic, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    assert_eq!(name(&pr), "reset_period");
    // An interval with velocity-only resetting runs (a bounded x).
    let pr =
        SearchProblem::new(velocity_only, 0.0, 0.0, PositionTarget::Interval(-0.5, 0.5)).unwrap();
    let d = search::distribution::solve(&pr, &dist_opts(20.0, 100)).unwrap();
    assert!(d.survival[100] < 0.5 && d.survival[100] >= 0.0);
}
