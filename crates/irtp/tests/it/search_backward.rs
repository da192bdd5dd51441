//! The search problem's deterministic solvers (`irtp::search::backward`,
//! `irtp::search::renewal`) against closed forms, finer meshes and each
//! other (docs/equations.md, "Search: the 2-D backward equation and the
//! renewal route").

use irtp::error::Error;
use irtp::model::reset::{NoiseAtReset, PositionReset, Schedule, Target};
use irtp::search::backward::{estimate, solve, BackwardOptions};
use irtp::search::renewal::{self, RenewalOptions, WaitingTime};
use irtp::search::{PositionTarget, SearchProblem};
use irtp::{DragLaw, Params};

/// Gaussian elimination with partial pivoting (the closed forms' small
/// linear systems).
fn gauss_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        let (top, rest) = a.split_at_mut(c + 1);
        let (pivot, bc) = (&top[c], b[c]);
        for (row, br) in rest.iter_mut().zip(&mut b[c + 1..]) {
            let f = row[c] / pivot[c];
            for (x, y) in row[c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * y;
            }
            *br -= f * bc;
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// Mean first-passage time (T+, T-) of the overdamped RTP dx/dt = ±c, flip
/// rate lambda, position reset to x_r at rate r > 0 (state kept), from x0
/// (docs/equations.md, search section, closed form (S4)): constant
/// particular part P± plus the modes e^{±k x}, k = √(r (2 lambda + r)) / c,
/// with (T+, T-) ∝ (1, lambda / (mu ± c k)), mu = lambda + r; the
/// coefficients from T+ = 0 at the upper exit, T- = 0 at the lower one, and
/// the self-consistency at x_r. Checked against a Monte Carlo simulation of
/// the RTP before use (1e5 particles, within the sampling error).
fn rtp_closed(c: f64, lambda: f64, r: f64, xr: f64, x0: f64, target: PositionTarget) -> [f64; 2] {
    let mu = lambda + r;
    let k = (r * (2.0 * lambda + r)).sqrt() / c;
    let (bk, bm) = (lambda / (mu + c * k), lambda / (mu - c * k));
    match target {
        PositionTarget::Level(l) if l > x0 => {
            let e1 = (k * (xr - l)).exp();
            let a = vec![
                vec![-lambda, lambda, r * e1],
                vec![lambda, -lambda, r * bk * e1],
                vec![1.0, 0.0, 1.0],
            ];
            let s = gauss_solve(a, vec![-1.0, -1.0, 0.0]);
            let e = (k * (x0 - l)).exp();
            [s[0] + s[2] * e, s[1] + s[2] * bk * e]
        }
        PositionTarget::Level(l) => {
            // Mirror x -> -x: the states swap.
            let m = rtp_closed(c, lambda, r, -xr, -x0, PositionTarget::Level(-l));
            [m[1], m[0]]
        }
        PositionTarget::Interval(a0, b0) => {
            let (e1, e2, d) = (
                (k * (xr - b0)).exp(),
                (-k * (xr - a0)).exp(),
                (-k * (b0 - a0)).exp(),
            );
            let a = vec![
                vec![-lambda, lambda, r * e1, r * e2],
                vec![lambda, -lambda, r * bk * e1, r * bm * e2],
                vec![1.0, 0.0, 1.0, d],
                vec![0.0, 1.0, bk * d, bm],
            ];
            let s = gauss_solve(a, vec![-1.0, -1.0, 0.0, 0.0]);
            let (f1, f2) = ((k * (x0 - b0)).exp(), (-k * (x0 - a0)).exp());
            [
                s[0] + s[2] * f1 + s[3] * f2,
                s[1] + s[2] * bk * f1 + s[3] * bm * f2,
            ]
        }
    }
}

/// Full resetting to (x_r, v_r), noise kept.
fn full(drag: &str, sigma: f64, lambda: f64, r: f64, xr: f64, vr: f64) -> Params {
    let schedule = Schedule {
        position: Some(PositionReset::new(xr).unwrap()),
        ..Default::default()
    };
    Params::new(drag.parse::<DragLaw>().unwrap(), sigma, lambda, r, vr)
        .unwrap()
        .with_schedule(schedule)
        .unwrap()
}

#[test]
fn rtp_closed_form_is_self_consistent() {
    // A level far away and an interval around it agree; mirror symmetry.
    let lv = rtp_closed(1.0, 1.0, 1.0, 0.0, 0.0, PositionTarget::Level(1.0));
    let iv = rtp_closed(
        1.0,
        1.0,
        1.0,
        0.0,
        0.0,
        PositionTarget::Interval(-60.0, 1.0),
    );
    assert!((lv[0] - iv[0]).abs() < 1e-9 && (lv[1] - iv[1]).abs() < 1e-9);
    let m = rtp_closed(1.0, 1.0, 1.0, 0.0, 0.0, PositionTarget::Level(-1.0));
    assert!((m[0] - lv[1]).abs() < 1e-12 && (m[1] - lv[0]).abs() < 1e-12);
}

/// Linear drag g = gamma v with Sigma = gamma c tends to the overdamped RTP
/// dx/dt = ±c as gamma -> ∞: the velocity relaxes in a time 1/gamma after
/// each flip and each reset, so the search is slowed by O((lambda + r) /
/// gamma) relative to the RTP. The differences fall like 1/gamma and stay
/// below twice that estimate, 2 (lambda + r) T_RTP / gamma.
#[test]
fn overdamped_limit_is_the_rtp() {
    let (c, lambda, r) = (1.0, 1.0, 1.0);
    let target = PositionTarget::Level(1.0);
    let rtp = rtp_closed(c, lambda, r, 0.0, 0.0, target);
    let rtp_tau = 0.5 * (rtp[0] + rtp[1]);
    let mut diffs = Vec::new();
    for gamma in [4.0, 16.0, 64.0, 256.0] {
        let p = full(
            &format!("power:n=1,k={gamma}"),
            gamma * c,
            lambda,
            r,
            0.0,
            0.0,
        );
        let problem = SearchProblem::new(p, 0.0, 0.0, target).unwrap();
        let s = solve(&problem, &BackwardOptions::with_cells(64, 8)).unwrap();
        let d = s.tau - rtp_tau;
        eprintln!(
            "gamma {gamma}: tau {} (± {}) tau± {} {}, RTP {rtp_tau} {rtp:?}: diff {d}, gamma diff {}",
            s.tau,
            s.error_estimate,
            s.tau_plus,
            s.tau_minus,
            gamma * d
        );
        assert!(
            d.abs() <= 2.0 * (lambda + r) * rtp_tau / gamma + s.error_estimate,
            "gamma {gamma}: {d}"
        );
        diffs.push(d);
    }
    for w in diffs.windows(2) {
        assert!(w[1].abs() < w[0].abs(), "differences fall: {diffs:?}");
        // The O(1/gamma) law: gamma d(gamma) settles (15.6, 13.8, 13.1, 12.0).
        let ratio = 4.0 * w[1] / w[0];
        assert!((0.8..1.25).contains(&ratio), "gamma diff: {diffs:?}");
    }
    let last = diffs[diffs.len() - 1];
    assert!(last.abs() <= 2.0 * (lambda + r) * rtp_tau / 256.0, "{last}");
}

/// The Richardson error estimate of `solve` bounds the actual error of the
/// extrapolated answer against a much finer (also extrapolated) solve.
fn estimate_bounds_error(
    problem: &SearchProblem,
    meshes: &[(usize, usize)],
    reference: (usize, usize),
) {
    let exact = solve(
        problem,
        &BackwardOptions::with_cells(reference.0, reference.1),
    )
    .unwrap();
    for &(cx, cv) in meshes {
        let s = solve(problem, &BackwardOptions::with_cells(cx, cv)).unwrap();
        let err = (s.tau - exact.tau).abs();
        eprintln!(
            "cells ({cx}, {cv}): tau {} estimate {} actual {err} (reference {} ± {})",
            s.tau, s.error_estimate, exact.tau, exact.error_estimate
        );
        assert!(
            err <= s.error_estimate,
            "({cx}, {cv}): {err} > {}",
            s.error_estimate
        );
        let plus = (s.tau_plus - exact.tau_plus).abs();
        let minus = (s.tau_minus - exact.tau_minus).abs();
        assert!(plus.max(minus) <= 2.0 * s.error_estimate);
    }
}

#[test]
fn mesh_error_estimate_bounds_the_error_interval() {
    let p = full("linear", 1.0, 0.5, 1.0, 0.0, 0.0);
    let problem = SearchProblem::new(p, 0.2, 0.3, PositionTarget::Interval(-0.5, 1.0)).unwrap();
    estimate_bounds_error(&problem, &[(8, 8), (16, 16)], (32, 32));
}

#[test]
#[ignore = "slow tier"]
fn mesh_error_estimate_bounds_the_error_level() {
    let p = full("tanh", 0.6, 0.5, 0.3, 0.0, 0.0);
    let problem = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    estimate_bounds_error(&problem, &[(16, 8), (32, 16)], (64, 32));
}
/// Velocity-only resetting (x kept) to an interval: as gamma -> ∞ a reset
/// of the velocity is forgotten within 1/gamma (the noise state is kept), so
/// the search tends to the overdamped RTP without resetting (closed form at
/// r -> 0: r = 1e-6 in the formula, whose modes then cancel only to 1e-10).
#[test]
fn velocity_only_resetting_overdamped_limit() {
    let (c, lambda, r) = (1.0, 1.0, 1.0);
    let target = PositionTarget::Interval(-0.5, 1.0);
    let rtp = rtp_closed(c, lambda, 1e-6, 0.0, 0.2, target);
    let rtp_tau = 0.5 * (rtp[0] + rtp[1]);
    let mut diffs = Vec::new();
    for gamma in [4.0, 16.0, 64.0] {
        let drag = format!("power:n=1,k={gamma}").parse::<DragLaw>().unwrap();
        let p = Params::new(drag, gamma * c, lambda, r, 0.0).unwrap();
        let problem = SearchProblem::new(p, 0.2, 0.0, target).unwrap();
        let s = solve(&problem, &BackwardOptions::with_cells(32, 16)).unwrap();
        let d = s.tau - rtp_tau;
        eprintln!(
            "gamma {gamma}: tau {} ± {}, RTP {rtp_tau}: diff {d}",
            s.tau, s.error_estimate
        );
        assert!(s.reset_values.is_none());
        assert!(d.abs() <= 2.0 * (lambda + r) * rtp_tau / gamma + s.error_estimate);
        diffs.push(d);
    }
    assert!(
        diffs[2].abs() < diffs[1].abs() && diffs[1].abs() < diffs[0].abs(),
        "{diffs:?}"
    );
}

/// Direct solve and renewal route on one mesh: the same discrete chain, so
/// they differ only by the renewal's time integration (its Richardson
/// estimate), its horizon (tail bound) and the truncations.
fn direct_vs_renewal(drag: &str, sigma: f64, rates: &[f64], cells: (usize, usize), refine: bool) {
    for &r in rates {
        let p = full(drag, sigma, 0.5, r, 0.0, 0.0);
        let problem = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
        let t = std::time::Instant::now();
        let opts = BackwardOptions {
            refine,
            ..BackwardOptions::with_cells(cells.0, cells.1)
        };
        let d = solve(&problem, &opts).unwrap();
        let ropts = RenewalOptions {
            cells_x: cells.0,
            cells_v: cells.1,
            refine,
            steps: 100,
            ..Default::default()
        };
        let s = renewal::solve(&problem, &WaitingTime::Poisson { rate: r }, &ropts).unwrap();
        let diff = (s.tau - d.tau).abs();
        let allowed = if refine {
            s.error_estimate + d.error_estimate
        } else {
            s.time_error + s.tail_bound + s.truncation_error + d.truncation_error
        };
        eprintln!(
            "{drag} r = {r}: direct {} renewal {} (time {:e}, tail {:e}) diff {diff:e} allowed \
             {allowed:e}; textbook {} ({:.4}); {:?}",
            d.tau,
            s.tau,
            s.time_error,
            s.tail_bound,
            s.textbook,
            s.textbook / s.tau,
            t.elapsed()
        );
        assert!(diff <= allowed, "{drag} r = {r}: {diff} > {allowed}");
        assert!((s.reset_values[0] - s.tau_plus).abs() <= 1e-12 * s.tau);
        assert!((s.reset_values[1] - s.tau_minus).abs() <= 1e-12 * s.tau);
    }
}

#[test]
fn renewal_matches_direct_linear() {
    direct_vs_renewal("linear", 1.0, &[0.3, 1.0, 3.0], (16, 8), false);
}

#[test]
fn renewal_matches_direct_tan() {
    direct_vs_renewal("tan", 3.0, &[0.3, 1.0, 3.0], (16, 8), false);
}

#[test]
fn renewal_matches_direct_tanh() {
    direct_vs_renewal("tanh", 0.6, &[0.3, 1.0, 3.0], (16, 8), false);
}

#[test]
fn renewal_matches_direct_power() {
    direct_vs_renewal("power:n=0.5", 1.0, &[0.3, 1.0, 3.0], (16, 8), false);
}

/// The unrefined comparisons' cases, extrapolated, but r = 3 only for tan
/// drag: at r = 3 the level is barely within reach for linear (v_u =
/// Sigma = L = 1, tau = 317), tanh (tau = 3265) and power n = 0.5 (tau =
/// 893), both ladders climb and those three cases took 88% of the test's
/// time, while the errors allowed (27%, 125% and 95% of tau) make them
/// the weakest checks of all; their discrete chains stay compared,
/// unrefined, in [`renewal_matches_direct_linear`],
/// [`renewal_matches_direct_tanh`] and [`renewal_matches_direct_power`].
#[test]
#[ignore = "slow tier"]
fn renewal_matches_direct_extrapolated() {
    for (drag, sigma, rates) in [
        ("linear", 1.0, &[0.3, 1.0][..]),
        ("tan", 3.0, &[0.3, 1.0, 3.0]),
        ("tanh", 0.6, &[0.3, 1.0]),
        ("power:n=0.5", 1.0, &[0.3, 1.0]),
    ] {
        direct_vs_renewal(drag, sigma, rates, (16, 8), true);
    }
}

/// The noise state is kept at a reset, so the periods are not independent:
/// the textbook E[min(T0, R)] / P(T0 < R) (a fresh random noise state each
/// period) is about 3% low for linear drag, Sigma = 1, lambda = 0.5,
/// L = 1, x0 = x_r = 0, v0 = v_r = 0, r = 0.3 (3.3% on both meshes: the
/// margin is the model's, not the mesh's).
#[test]
fn textbook_renewal_is_three_percent_low() {
    let p = full("linear", 1.0, 0.5, 0.3, 0.0, 0.0);
    let problem = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    let opts = RenewalOptions {
        cells_x: 16,
        cells_v: 8,
        refine: false,
        steps: 100,
        ..Default::default()
    };
    let s = renewal::solve(&problem, &WaitingTime::Poisson { rate: 0.3 }, &opts).unwrap();
    let low = 1.0 - s.textbook / s.tau;
    eprintln!(
        "tau {} textbook {}: {:.2}% low",
        s.tau,
        s.textbook,
        100.0 * low
    );
    assert!((0.025..0.04).contains(&low), "{low}");
}

/// Periodic (sharp) resetting every T through the renewal route: started
/// at the reset point the answer is the renewal value there; no tail is
/// cut; the bound tau >= L / v_u; the time error falls with the step.
#[test]
fn periodic_resetting_by_renewal() {
    let schedule = Schedule::parse(Some(2.0), Some(0.0), None).unwrap();
    let p = Params::new(DragLaw::Linear, 1.0, 0.5, 0.0, 0.0)
        .unwrap()
        .with_schedule(schedule)
        .unwrap();
    let problem = SearchProblem::new(p.clone(), 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    let waiting = WaitingTime::of(&p).unwrap();
    assert_eq!(waiting, WaitingTime::Periodic { period: 2.0 });
    let run = |steps| {
        let opts = RenewalOptions {
            cells_x: 16,
            cells_v: 8,
            refine: false,
            steps,
            ..Default::default()
        };
        renewal::solve(&problem, &waiting, &opts).unwrap()
    };
    let (a, b) = (run(50), run(200));
    eprintln!("periodic: {a:?}\n{b:?}");
    assert_eq!(a.tail_bound, 0.0);
    assert!((a.tau_plus - a.reset_values[0]).abs() <= 1e-12 * a.tau);
    assert!(a.tau_minus > a.tau_plus && a.tau_plus >= 1.0);
    assert!((a.tau - b.tau).abs() <= a.time_error && b.time_error < a.time_error);
    // The direct solver refuses a periodic clock, naming it.
    let e = solve(&problem, &BackwardOptions::default()).unwrap_err();
    assert_eq!(e.parameter(), Some("reset_period"), "{e}");
}

/// Infinite means and protocols the search solvers do not run are refused,
/// naming the parameter.
#[test]
fn refusals_name_the_parameter() {
    let name = |e: Error| e.parameter().unwrap_or_else(|| panic!("{e}"));
    let level = PositionTarget::Level(1.0);
    let velocity_only = Params::new(DragLaw::Linear, 1.0, 0.5, 1.0, 0.0).unwrap();
    let pr = SearchProblem::new(velocity_only, 0.0, 0.0, level).unwrap();
    assert!(!pr.mean_is_finite());
    let e = solve(&pr, &BackwardOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains("infinite") && !e.to_string().contains('\n'),
        "{e}"
    );
    assert_eq!(name(e), "reset_position");
    let e = renewal::solve(
        &pr,
        &WaitingTime::Poisson { rate: 1.0 },
        &RenewalOptions::default(),
    );
    assert_eq!(name(e.unwrap_err()), "reset_position");
    let no_rate = full("linear", 1.0, 0.5, 0.0, 0.0, 0.0);
    let pr = SearchProblem::new(no_rate, 0.0, 0.0, level).unwrap();
    assert_eq!(
        name(solve(&pr, &BackwardOptions::default()).unwrap_err()),
        "rate"
    );
    let refractory = Params::new(DragLaw::Linear, 1.0, 0.5, 1.0, 0.0)
        .unwrap()
        .with_schedule(Schedule::parse(None, Some(0.0), Some("fixed:t=0.5")).unwrap())
        .unwrap();
    let pr = SearchProblem::new(refractory, 0.0, 0.0, level).unwrap();
    assert_eq!(
        name(solve(&pr, &BackwardOptions::default()).unwrap_err()),
        "refractory"
    );
    // A reset position beyond the level, and a budget too small.
    let beyond = full("linear", 1.0, 0.5, 1.0, 2.0, 0.0);
    let e = SearchProblem::new(beyond, 0.0, 0.0, level).unwrap_err();
    assert_eq!(name(e), "reset_position");
    let ok = SearchProblem::new(full("linear", 1.0, 0.5, 1.0, 0.0, 0.0), 0.0, 0.0, level).unwrap();
    let tiny = BackwardOptions {
        max_work: 1e3,
        ..BackwardOptions::default()
    };
    let e = solve(&ok, &tiny).unwrap_err();
    assert!(
        matches!(
            e,
            Error::TooCostly {
                limit_name: "max_work",
                ..
            }
        ),
        "{e}"
    );
    let tiny = RenewalOptions {
        max_memory: 1e3,
        ..RenewalOptions::default()
    };
    let e = renewal::solve(&ok, &WaitingTime::Poisson { rate: 1.0 }, &tiny).unwrap_err();
    match e {
        Error::TooCostly {
            limit_name,
            drivers,
            ..
        } => assert!(limit_name == "max_memory" && drivers.contains(&"steps")),
        other => panic!("{other}"),
    }
    // The default options fit the default budgets.
    let cost = estimate(&ok, &BackwardOptions::default()).unwrap();
    assert!(
        cost.work > 1e3 && cost.work < 1e11 && cost.memory < 4e9,
        "{cost:?}"
    );
    let poisson = WaitingTime::Poisson { rate: 1.0 };
    let cost = renewal::estimate(&ok, &poisson, &RenewalOptions::default()).unwrap();
    assert!(cost.work < 1e11 && cost.memory < 4e9, "{cost:?}");
}

/// Full resetting with another protocol: the direct solve and the renewal
/// route on one mesh agree (as in `direct_vs_renewal`).
fn routes_agree(p: Params, target: PositionTarget) -> f64 {
    let problem = SearchProblem::new(p.clone(), 0.0, 0.0, target).unwrap();
    let d = solve(
        &problem,
        &BackwardOptions {
            refine: false,
            ..BackwardOptions::with_cells(16, 8)
        },
    )
    .unwrap();
    let opts = RenewalOptions {
        cells_x: 16,
        cells_v: 8,
        refine: false,
        steps: 100,
        ..Default::default()
    };
    let s = renewal::solve(&problem, &WaitingTime::of(&p).unwrap(), &opts).unwrap();
    let diff = (s.tau - d.tau).abs();
    let allowed = s.time_error + s.tail_bound + s.truncation_error + d.truncation_error;
    eprintln!("direct {d:?}\nrenewal {s:?}\ndiff {diff:e} allowed {allowed:e}");
    assert!(diff <= allowed, "{diff} > {allowed}");
    d.tau
}

/// Noise re-drawn at a reset: the periods are independent, so the textbook
/// renewal formula is exact (to the route's own time error).
#[test]
fn redrawn_noise_routes_agree() {
    let p = full("linear", 1.0, 0.5, 0.3, 0.0, 0.0)
        .with_reset(Target::point(0.0), NoiseAtReset::Redrawn)
        .unwrap();
    let problem = SearchProblem::new(p.clone(), 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    routes_agree(p.clone(), PositionTarget::Level(1.0));
    let opts = RenewalOptions {
        cells_x: 16,
        cells_v: 8,
        refine: false,
        steps: 100,
        ..Default::default()
    };
    let s = renewal::solve(&problem, &WaitingTime::of(&p).unwrap(), &opts).unwrap();
    assert!((s.textbook - s.tau).abs() <= 1e-10 * s.tau, "{s:?}");
}

/// A random velocity target: the routes agree; a Gaussian much narrower
/// than a cell is the point target at its centre (hat weights: all but
/// O(std/h) on the centre node, the rest split evenly between its
/// neighbours, so T moves by O(std h T_vv): 7.7e-6 relative at std = 1e-4,
/// below 1e-6 at std = 1e-6).
#[test]
fn random_target_routes_agree() {
    let level = PositionTarget::Level(1.0);
    let uniform = full("tanh", 0.6, 0.5, 1.0, 0.0, 0.0)
        .with_reset(Target::uniform(-0.3, 0.4), NoiseAtReset::Kept)
        .unwrap();
    routes_agree(uniform, level);
    let point = full("linear", 1.0, 0.5, 1.0, 0.0, 0.1);
    let narrow = point
        .with_reset(Target::gauss(0.1, 1e-6), NoiseAtReset::Kept)
        .unwrap();
    let (tp, tn) = (routes_agree(point, level), routes_agree(narrow, level));
    assert!((tp - tn).abs() <= 1e-6 * tp, "{tp} {tn}");
    // Velocity-only resetting to an interval takes it too.
    let v_only = Params::new(DragLaw::Linear, 1.0, 0.5, 1.0, 0.0)
        .unwrap()
        .with_reset(Target::uniform(-0.3, 0.4), NoiseAtReset::Redrawn)
        .unwrap();
    let pr = SearchProblem::new(v_only, 0.0, 0.0, PositionTarget::Interval(-0.5, 1.0)).unwrap();
    let s = solve(&pr, &BackwardOptions::with_cells(16, 16)).unwrap();
    assert!(s.tau > 0.5 && s.error_estimate < 0.1 * s.tau, "{s:?}");
}

/// x -> -x, v -> -v, eta -> -eta maps the level 1 to the level -1 (odd
/// drag, x_r = v_r = 0): tau± swap, on both routes; without resets an
/// interval still has a finite mean, and no reset values.
#[test]
fn mirror_symmetry_and_no_resets() {
    let p = full("tan", 3.0, 0.5, 1.0, 0.0, 0.0);
    let opts = BackwardOptions::with_cells(16, 8);
    let up = SearchProblem::new(p.clone(), 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    let down = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(-1.0)).unwrap();
    let (u, d) = (solve(&up, &opts).unwrap(), solve(&down, &opts).unwrap());
    assert!(
        (u.tau_plus - d.tau_minus).abs() <= 1e-9 * u.tau,
        "{u:?} {d:?}"
    );
    assert!((u.tau_minus - d.tau_plus).abs() <= 1e-9 * u.tau);
    let ropts = RenewalOptions {
        cells_x: 16,
        cells_v: 8,
        refine: false,
        ..Default::default()
    };
    let poisson = WaitingTime::Poisson { rate: 1.0 };
    let ru = renewal::solve(&up, &poisson, &ropts).unwrap();
    let rd = renewal::solve(&down, &poisson, &ropts).unwrap();
    assert!((ru.tau - rd.tau).abs() <= 1e-9 * ru.tau);
    let free = Params::new(DragLaw::Tanh, 0.6, 0.5, 0.0, 0.0).unwrap();
    let pr =
        SearchProblem::new(free.clone(), 0.1, 0.2, PositionTarget::Interval(-0.5, 0.5)).unwrap();
    assert!(pr.mean_is_finite());
    let s = solve(&pr, &BackwardOptions::with_cells(16, 16)).unwrap();
    assert!(s.reset_values.is_none() && s.truncation_error == 0.0);
    assert!(
        s.tau >= 0.4 / free.v_upper() && s.error_estimate < 0.1 * s.tau,
        "{s:?}"
    );
}

/// A far side cut short: the reported truncation error bounds the change
/// against the default cut (where truncation dominates the difference:
/// at tol = 0.5, 0.2 the cut is at 0.7, 1.6 while the default is at 18).
#[test]
fn truncation_error_bounds_a_short_cut() {
    let p = full("linear", 1.0, 0.5, 1.0, 0.0, 0.0);
    let problem = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    let reference = solve(&problem, &BackwardOptions::with_cells(16, 8)).unwrap();
    for tol in [0.5, 0.2] {
        let opts = BackwardOptions {
            truncation: tol,
            ..BackwardOptions::with_cells(16, 8)
        };
        let s = solve(&problem, &opts).unwrap();
        let actual = (s.tau - reference.tau).abs();
        eprintln!(
            "tol {tol}: truncation error {} actual {actual}",
            s.truncation_error
        );
        assert!(
            actual <= s.truncation_error,
            "tol {tol}: {actual} > {}",
            s.truncation_error
        );
    }
}
