//! The search solvers' error estimates bound their error (docs/equations.md,
//! "Search: the 2-D backward equation and the renewal route"), and the
//! mirror image of a symmetric problem.

use irtp::model::reset::Schedule;
use irtp::search::backward::{self, BackwardOptions};
use irtp::search::{PositionTarget, SearchProblem};
use irtp::{DragLaw, Params};

/// Full resetting to x_r = 0 at `rate` from (0, v0).
fn problem(
    drag: DragLaw,
    sigma: f64,
    lambda: f64,
    rate: f64,
    v0: f64,
    t: PositionTarget,
) -> SearchProblem {
    let sched = Schedule::parse(None, Some(0.0), None).unwrap();
    let p = Params::new(drag, sigma, lambda, rate, 0.0)
        .unwrap()
        .with_schedule(sched)
        .unwrap();
    SearchProblem::new(p, 0.0, v0, t).unwrap()
}

/// The reported error of a coarse solve (16 x 8) covers its distance to a
/// solve on meshes four times finer (with its own estimate), or the solve
/// is refused (exit 4): never an estimate that understates the error.
#[test]
fn reported_errors_bound_a_finer_solve() {
    let cases = [
        problem(
            DragLaw::Linear,
            1.0,
            0.5,
            1.0,
            0.0,
            PositionTarget::Level(1.0),
        ),
        problem(DragLaw::Tan, 3.0, 0.5, 1.0, 0.0, PositionTarget::Level(1.0)),
        problem(
            DragLaw::Tan,
            3.0,
            0.5,
            1.0,
            0.3,
            PositionTarget::Interval(-1.0, 2.0),
        ),
        problem(
            DragLaw::Linear,
            1.0,
            2.0,
            0.3,
            0.0,
            PositionTarget::Level(-1.5),
        ),
    ];
    for pr in cases {
        let fine = backward::solve(&pr, &BackwardOptions::with_cells(64, 32)).unwrap();
        match backward::solve(&pr, &BackwardOptions::with_cells(16, 8)) {
            Ok(coarse) => {
                let gap = (coarse.tau - fine.tau).abs();
                assert!(
                    gap <= coarse.error_estimate + fine.error_estimate,
                    "{pr:?}: {} vs {}: gap {gap:e}, estimates {:e} + {:e}",
                    coarse.tau,
                    fine.tau,
                    coarse.error_estimate,
                    fine.error_estimate
                );
            }
            Err(e) => assert!(e.is_numerical(), "{e}"),
        }
    }
}

/// x -> -x, v -> -v, eta -> -eta maps the search for x_t = 1 onto the one
/// for x_t = -1 (odd drag, symmetric noise, x_r = v_r = v0 = 0) and the
/// mesh onto its mirror image: the same tau to round-off, tau+ and tau-
/// exchanged; no round-off sign refusal on either side.
#[test]
fn mirror_targets_give_the_same_tau() {
    let opts = BackwardOptions::default();
    let up = problem(DragLaw::Tan, 3.0, 0.5, 1.0, 0.0, PositionTarget::Level(1.0));
    let down = problem(
        DragLaw::Tan,
        3.0,
        0.5,
        1.0,
        0.0,
        PositionTarget::Level(-1.0),
    );
    let (a, b) = (
        backward::solve(&up, &opts).unwrap(),
        backward::solve(&down, &opts).unwrap(),
    );
    let tol = 1e-9 * a.tau;
    assert!((a.tau - b.tau).abs() <= tol, "{} vs {}", a.tau, b.tau);
    assert!((a.tau_plus - b.tau_minus).abs() <= tol, "{a:?} {b:?}");
}
