//! Targets out of reach of a bounded reset clock (docs/equations.md,
//! "Search", the finiteness of the mean): one verdict from every route,
//! and the reach bound itself checked against the exact sampler.

use irtp::mfpt::ParticleOptions;
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::search::backward::{self, BackwardOptions};
use irtp::search::renewal::{self, RenewalOptions, WaitingTime};
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem, SearchResult};
use irtp::{DragLaw, Params};

/// Every registered law of bounded support (its end is 1), and the
/// periodic clock (`None`): `fixed`, a uniform law and a two-piece law by
/// `table` (linear survival pieces).
const BOUNDED: [Option<&str>; 4] = [
    None,
    Some("fixed:t=1"),
    Some("table:0:1;1:0"),
    Some("table:0:1;0.5:0.25;1:0"),
];

/// The CLI's defaults (tan drag, Sigma = 3, lambda = 0.5), full resetting to
/// x_r = 0 by `clock` (`None`: `--reset-period 1`).
fn problem(clock: Option<&str>, x0: f64, v0: f64, xt: f64) -> SearchProblem {
    let period = clock.is_none().then_some(1.0);
    let sched = Schedule::parse(period, Some(0.0), None)
        .unwrap()
        .with_clock(clock)
        .unwrap();
    let p = Params::new(DragLaw::Tan, 3.0, 0.5, 0.0, 0.0)
        .unwrap()
        .with_schedule(sched)
        .unwrap();
    SearchProblem::new(p, x0, v0, PositionTarget::Level(xt)).unwrap()
}

/// The exact sampler's run: `particles` censored at t_max = 20.
fn sampled(problem: &SearchProblem, particles: u64) -> search::ParticleSearch {
    let method = SearchMethod::Exact(ParticleOptions {
        particles,
        t_max: 20.0,
        seed: 7,
    });
    match search::solve(problem, &method, &NoProgress).unwrap() {
        SearchResult::Particles(r) => r,
        _ => unreachable!("a particle method"),
    }
}

/// x_t = 1 from x_r = 0 within a period of 1: the fastest path reaches
/// 0.913. Infinite mean with its cause; the renewal route reports tau =
/// inf; the backward solver refuses the clock (it runs Poisson only),
/// naming it; the exact sampler censors every particle (none arrives in
/// 20 periods).
#[test]
fn out_of_reach_is_infinite_on_every_route() {
    for clock in BOUNDED {
        let pr = problem(clock, 0.0, 0.0, 1.0);
        assert!(!pr.mean_is_finite(), "{clock:?}");
        let why = pr.infinite_mean_reason().unwrap();
        assert!(why.contains("out of reach"), "{clock:?}: {why}");
        let waiting = WaitingTime::of(pr.params()).unwrap();
        let opts = RenewalOptions {
            cells_x: 16,
            cells_v: 8,
            ..Default::default()
        };
        let r = renewal::solve(&pr, &waiting, &opts).unwrap();
        assert!(
            r.infinite_mean && r.tau == f64::INFINITY,
            "{clock:?}: {r:?}"
        );
        let e = backward::solve(&pr, &BackwardOptions::with_cells(16, 8)).unwrap_err();
        let named = clock.map_or("reset_period", |_| "reset_clock");
        assert!(e.parameter() == Some(named), "{clock:?}: {e}");
        let s = sampled(&pr, 64);
        assert!(!s.mean_is_finite && s.tau().is_nan(), "{clock:?}");
        assert_eq!(s.stats.summary().censored, 64, "{clock:?}");
    }
}

/// x_t = 0.5 is within reach (0.913 > 0.5): a finite mean on every route,
/// the renewal route's tau finite, and particles of the exact sampler
/// arrive. The reach bound is an upper bound: a target just inside it is
/// finite, one just outside infinite.
#[test]
fn reachable_targets_stay_finite() {
    for clock in BOUNDED {
        let pr = problem(clock, 0.0, 0.0, 0.5);
        assert!(pr.mean_is_finite(), "{clock:?}");
        let waiting = WaitingTime::of(pr.params()).unwrap();
        let opts = RenewalOptions {
            cells_x: 16,
            cells_v: 8,
            ..Default::default()
        };
        let r = renewal::solve(&pr, &waiting, &opts).unwrap();
        assert!(
            !r.infinite_mean && r.tau.is_finite() && r.tau > 0.0,
            "{r:?}"
        );
        let s = sampled(&pr, 64);
        assert!(s.stats.summary().censored < 64, "{clock:?}");
    }
    // The fastest flow from v_r = 0 over T = 1 (no flip, +Sigma).
    let reach = irtp::Drag::flow_displacement(&DragLaw::Tan, 3.0, 0.0, 1.0);
    assert!((0.9..0.93).contains(&reach), "{reach}");
    assert!(problem(None, 0.0, 0.0, reach * (1.0 - 1e-6)).mean_is_finite());
    assert!(!problem(None, 0.0, 0.0, reach * (1.0 + 1e-6)).mean_is_finite());
}

/// A start from which every path reaches the level before the first
/// periodic reset (x0 = 0.99, v0 = 1.2 towards x_t = 1): finite although
/// the target is out of reach from x_r, and the exact sampler sees every
/// particle arrive before T = 1.
#[test]
fn sure_arrival_before_the_first_reset_is_finite() {
    let pr = problem(None, 0.99, 1.2, 1.0);
    assert!(pr.mean_is_finite());
    let s = sampled(&pr, 64).stats.summary();
    assert_eq!(s.censored, 0);
    assert!(s.tau < 1.0, "{}", s.tau);
}
