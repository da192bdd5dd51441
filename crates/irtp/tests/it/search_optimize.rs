//! The search's optimal reset rate (`irtp::search::optimize`): the one
//! minimiser of `mfpt optimize` over the 2-D backward equation, checked
//! against a dense scan, and its honest ends: r* = 0 where resetting does
//! not help, a refusal where the mean is infinite at every r.

use irtp::error::Error;
use irtp::mfpt::optimize::RateRange;
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::search::backward::BackwardOptions;
use irtp::search::optimize::{optimize_rate, scan, SearchAxis};
use irtp::search::{PositionTarget, SearchProblem};
use irtp::{DragLaw, Params};

/// tan, Sigma = 3, lambda = 1, from (0, 0), resets to v_r = 0 (and x_r = 0
/// with `full`).
fn problem(full: bool, target: PositionTarget) -> SearchProblem {
    let p = Params::new(DragLaw::Tan, 3.0, 1.0, 0.0, 0.0).unwrap();
    let p = if full {
        p.with_schedule(Schedule::parse(None, Some(0.0), None).unwrap())
            .unwrap()
    } else {
        p
    };
    SearchProblem::new(p, 0.0, 0.0, target).unwrap()
}

fn range(points: usize) -> RateRange {
    RateRange {
        r_min: 0.05,
        r_max: 20.0,
        grid_points: points,
        ..RateRange::default()
    }
}

/// Full resetting and a level: tau(0) is infinite, r* interior; the
/// optimiser's minimum is that of a dense scan (4× finer than its grid)
/// to within the scan's spacing and below every scanned tau.
#[test]
fn search_optimum_is_the_minimum_of_a_dense_scan() {
    let pr = problem(true, PositionTarget::Level(1.0));
    let o = BackwardOptions::with_cells(12, 6);
    let best = optimize_rate(&pr, &range(13), &o, &NoProgress)
        .unwrap()
        .optimum;
    println!("{best:?}");
    assert!(best.interior && !best.at_upper_bound, "{best:?}");
    assert_eq!(best.tau_r0, f64::INFINITY);
    let values = RateRange {
        grid_points: 49,
        ..range(13)
    }
    .grid();
    let dense = scan(&pr, SearchAxis::Rate, &values, &o, &NoProgress).unwrap();
    let j = (0..dense.len())
        .min_by(|&a, &b| dense[a].solution.tau.total_cmp(&dense[b].solution.tau))
        .unwrap();
    let (lo, hi) = (values[j.saturating_sub(1)], values[(j + 1).min(48)]);
    assert!(
        best.r_opt >= lo && best.r_opt <= hi,
        "{} not in [{lo}, {hi}]",
        best.r_opt
    );
    assert!(
        best.tau_opt <= dense[j].solution.tau,
        "{} > {}",
        best.tau_opt,
        dense[j].solution.tau
    );
    // The error range holds r*, inside the searched range.
    let (a, b) = best.r_opt_range;
    assert!(a < best.r_opt && best.r_opt < b && b.is_finite(), "{a} {b}");
    assert!(best.tau_opt_err > 0.0 && best.tau_opt_err < 0.5 * best.tau_opt);
}

/// The symmetric interval from its centre, with full resetting back to
/// it: a reset only undoes progress, so r* = 0 ("resetting does not
/// help"), tau(0) the minimum of the grid.
#[test]
fn resetting_that_does_not_help_gives_r_star_zero() {
    let pr = problem(true, PositionTarget::Interval(-1.0, 1.0));
    let o = BackwardOptions::with_cells(12, 6);
    let best = optimize_rate(&pr, &range(9), &o, &NoProgress)
        .unwrap()
        .optimum;
    println!("{best:?}");
    assert_eq!(best.r_opt, 0.0);
    assert!(!best.interior && best.tau_opt == best.tau_r0);
    assert!(best.tau_r0.is_finite());
    assert!(best.grid.iter().all(|&(_, t)| t > best.tau_r0), "{best:?}");
    assert_eq!(best.r_opt_range.0, 0.0);
}

/// Velocity-only resetting and a level: the mean is infinite at every r,
/// refused naming the flag that makes it finite; an interval runs.
#[test]
fn velocity_only_level_is_refused_an_interval_runs() {
    let o = BackwardOptions::with_cells(12, 6);
    let pr = problem(false, PositionTarget::Level(1.0));
    match optimize_rate(&pr, &range(9), &o, &NoProgress) {
        Err(Error::InvalidParameter { name, allowed, .. }) => {
            assert_eq!(name, "reset_position");
            assert!(allowed.contains("infinite at every r"), "{allowed}");
        }
        other => panic!("{other:?}"),
    }
    let pr = problem(false, PositionTarget::Interval(-1.0, 1.0));
    let best = optimize_rate(&pr, &range(9), &o, &NoProgress)
        .unwrap()
        .optimum;
    assert!(
        best.tau_r0.is_finite() && best.tau_opt <= best.tau_r0,
        "{best:?}"
    );
}
