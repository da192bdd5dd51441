//! The cost estimates of the 2-D search solvers against the work they
//! count (`search::backward::estimate`, `search::renewal::estimate` and
//! the solutions' `work`: band factorisations and solves, docs/equations.md
//! (S2)): within a factor of 3 either way over levels, intervals, rates
//! and clocks; and the rate optimiser's total estimate
//! (`search::optimize::estimate_work`) against the work of all its solves.

use irtp::mfpt::optimize::RateRange;
use irtp::model::reset::{Clock, Schedule};
use irtp::parallel::NoProgress;
use irtp::search::backward::{self, BackwardOptions};
use irtp::search::optimize;
use irtp::search::renewal::{self, RenewalOptions, WaitingTime};
use irtp::search::{PositionTarget, SearchProblem};
use irtp::{DragLaw, Params};

/// Full resetting to x_r = 0 at `rate` from (0, 0).
fn problem(drag: DragLaw, sigma: f64, rate: f64, t: PositionTarget) -> SearchProblem {
    let sched = Schedule::parse(None, Some(0.0), None).unwrap();
    let p = Params::new(drag, sigma, 0.5, rate, 0.0)
        .unwrap()
        .with_schedule(sched)
        .unwrap();
    SearchProblem::new(p, 0.0, 0.0, t).unwrap()
}

/// estimate / counted work in [1/3, 3].
fn assert_within_3(what: &str, estimate: f64, work: f64) {
    let ratio = estimate / work;
    println!("{what}: estimate {estimate:.3e}, counted {work:.3e}, ratio {ratio:.2}");
    assert!(
        (1.0 / 3.0..=3.0).contains(&ratio),
        "{what}: estimate {estimate:e} vs counted {work:e} (ratio {ratio})"
    );
}

/// The sizes of mesh, target and rate the estimate must follow.
fn cases() -> Vec<(SearchProblem, usize, usize)> {
    let level = PositionTarget::Level(1.0);
    let interval = PositionTarget::Interval(-1.0, 2.0);
    vec![
        (problem(DragLaw::Linear, 1.0, 0.3, level), 16, 8),
        (problem(DragLaw::Linear, 1.0, 3.0, level), 32, 16),
        (problem(DragLaw::Linear, 1.0, 0.01, level), 16, 8),
        (problem(DragLaw::Tan, 3.0, 1.0, interval), 24, 12),
        (problem(DragLaw::Tanh, 0.8, 2.0, interval), 16, 32),
        (
            problem(DragLaw::Linear, 1.0, 1.0, PositionTarget::Level(-2.0)),
            40,
            8,
        ),
    ]
}

/// The backward solver: the estimate of the meshes it solves (no climb:
/// a climbed level is checked against the budget on its own).
#[test]
fn backward_estimate_is_within_3x_of_the_work_done() {
    for (pr, cx, cv) in cases() {
        let opts = BackwardOptions {
            climb: false,
            ..BackwardOptions::with_cells(cx, cv)
        };
        let est = backward::estimate(&pr, &opts).unwrap().work;
        let s = backward::solve(&pr, &opts).unwrap();
        assert_within_3(&format!("backward {cx}x{cv} {pr:?}"), est, s.work);
    }
}

/// The renewal route under a Poisson clock, a period and a renewal law.
#[test]
fn renewal_estimate_is_within_3x_of_the_work_done() {
    let clocks = [
        WaitingTime::Poisson { rate: 1.0 },
        WaitingTime::Periodic { period: 2.0 },
        WaitingTime::Renewal {
            clock: Clock::parse("gamma:k=2,theta=0.5").unwrap(),
        },
    ];
    for (k, (pr, cx, cv)) in cases().into_iter().enumerate().take(4) {
        let waiting = clocks[k % clocks.len()].clone();
        let opts = RenewalOptions {
            cells_x: cx / 2,
            cells_v: cv / 2,
            steps: 20 + 10 * k,
            climb: false,
            ..Default::default()
        };
        let est = renewal::estimate(&pr, &waiting, &opts).unwrap().work;
        let s = renewal::solve(&pr, &waiting, &opts).unwrap();
        assert_within_3(&format!("renewal {waiting:?} {pr:?}"), est, s.work);
    }
}

/// The rate optimiser (`mfpt optimize --xt`, full resetting to x_r = 0
/// and v_r = 0): its total estimate against the work of every solve it
/// makes (grid, golden section, the checked one at the optimum), over
/// drags and levels at three distances; and an interval whose optimum is
/// r = 0, where the golden section is skipped: the estimate is above the
/// work done (the skipped solves are priced), never below.
#[test]
fn optimize_estimate_is_within_3x_of_the_work_done() {
    let range = RateRange {
        r_min: 0.05,
        r_max: 20.0,
        grid_points: 9,
        ..RateRange::default()
    };
    let cases = [
        (DragLaw::Linear, 1.0, 1.0),
        (DragLaw::Linear, 1.0, 2.0),
        (DragLaw::Linear, 1.0, 3.0),
        (DragLaw::Tan, 3.0, 1.0),
        (DragLaw::Tan, 3.0, 2.0),
    ];
    let opts = BackwardOptions::with_cells(12, 6);
    for (drag, sigma, l) in cases {
        let pr = problem(drag.clone(), sigma, 0.0, PositionTarget::Level(l));
        let est = optimize::estimate_work(&pr, &range, &opts).unwrap();
        let best = optimize::optimize_rate(&pr, &range, &opts, &NoProgress).unwrap();
        let r = best.optimum.r_opt;
        assert!(best.optimum.interior, "{drag:?} L = {l}: r* = {r}");
        assert_within_3(
            &format!("optimize {drag:?} L = {l}, r* {r:.3}"),
            est,
            best.work,
        );
    }
    let pr = problem(DragLaw::Tan, 3.0, 0.0, PositionTarget::Interval(-1.0, 2.0));
    let est = optimize::estimate_work(&pr, &range, &opts).unwrap();
    let best = optimize::optimize_rate(&pr, &range, &opts, &NoProgress).unwrap();
    println!(
        "optimize interval: estimate {est:.3e}, counted {:.3e}",
        best.work
    );
    assert_eq!(best.optimum.r_opt, 0.0);
    assert!(
        est >= best.work && best.work > 0.0,
        "{est:e} < {:e}",
        best.work
    );
}

/// The rate optimiser at the command line's defaults (`mfpt optimize --xt
/// 2 --v0 0 --reset-position 0`: tan drag, Sigma 3, 61 rates from 1e-3
/// to 1e3, 32 x 16 cells), where the screen leaves the dear small rates
/// out of the full solves: the estimate against the work counted.
#[test]
fn optimize_estimate_at_the_defaults_is_within_3x_of_the_work_done() {
    let range = RateRange::default();
    let opts = BackwardOptions::with_cells(32, 16);
    let pr = problem(DragLaw::Tan, 3.0, 0.0, PositionTarget::Level(2.0));
    let est = optimize::estimate_work(&pr, &range, &opts).unwrap();
    let best = optimize::optimize_rate(&pr, &range, &opts, &NoProgress).unwrap();
    let locate = BackwardOptions {
        climb: false,
        ..opts
    };
    let mut grid: Vec<f64> = range
        .grid()
        .into_iter()
        .map(|r| {
            backward::estimate(&pr.with_rate(r).unwrap(), &locate)
                .unwrap()
                .work
        })
        .collect();
    let screens = optimize::screen_work(&pr, &range, &opts).unwrap();
    grid.sort_by(f64::total_cmp);
    let n = grid.len();
    println!(
        "defaults: screens {screens:.3e}, grid {:.3e}, locating solves {}, median {:.3e}, \
         upper quartile {:.3e}",
        grid.iter().sum::<f64>(),
        optimize::locate_solves(&range),
        grid[n / 2],
        grid[3 * n / 4]
    );
    assert!(best.optimum.interior);
    assert_within_3("optimize at the defaults", est, best.work);
}
