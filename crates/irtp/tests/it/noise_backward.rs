//! The backward equations of first passage in velocity with a noise model
//! (`irtp::mfpt::backward`, docs/equations.md Eqs. (N30)-(N36)), checked once
//! over `irtp_testkit::noises::NOISE_CASES`: the paper's noise spelt as a
//! generator against the two-state solver, pure Ornstein-Uhlenbeck against
//! the Siegert formula and its renewal formula with resetting, T → 0
//! continuity, the truncation of the thermal domain moved, the lower bound
//! and monotonicity in v_t, and dτ/dr at 0 against a difference quotient.

use irtp::mfpt::backward::{self, NoiseSolution};
use irtp::mfpt::{BackwardOptions, Problem};
use irtp::model::noise::NoiseModel;
use irtp::numerics::quad;
use irtp::{DragLaw, Params};
use irtp_testkit::noises::{NoiseCase, NOISE_CASES, PAPER_AS_STATES};

/// The interval a case's targets are chosen in: the noise's velocity
/// interval, cut to ±3 (thermal noise on an unbounded line).
fn interval(c: &NoiseCase) -> (f64, f64) {
    let (lo, hi) = c.params().bounds();
    (lo.max(-3.0), hi.min(3.0))
}

/// v_0 = v_r, v_t 60 % of the way to the upper edge.
fn upward(c: &NoiseCase) -> Problem {
    let (_, hi) = interval(c);
    let v0 = c.reset_velocity;
    Problem::new(c.params(), v0, v0 + 0.6 * (hi - v0)).expect("upward problem")
}

/// v_0 = v_r, v_t 40 % of the way to the lower edge.
fn downward(c: &NoiseCase) -> Problem {
    let (lo, _) = interval(c);
    let v0 = c.reset_velocity;
    Problem::new(c.params(), v0, v0 + 0.4 * (lo - v0)).expect("downward problem")
}

fn solve(p: &Problem, cells: usize) -> NoiseSolution {
    backward::solve_states(p, &BackwardOptions::with_cells(cells)).expect("backward solve")
}

/// The paper's noise spelt as a 2-state generator runs the N-state solver
/// and agrees with the two-state solver to 1e-8 (both directions).
#[test]
fn paper_as_states_matches_the_two_state_solver() {
    for c in NOISE_CASES.iter().filter(|c| c.noise == PAPER_AS_STATES) {
        let drag: DragLaw = c.drag.parse().unwrap();
        let two = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
        for p in [upward(c), downward(c)] {
            let q = Problem::new(two.clone(), p.v0(), p.vt()).unwrap();
            let opts = BackwardOptions::with_cells(20_000);
            let reference = irtp::mfpt::backward::solve(&q, &opts).unwrap();
            let n = solve(&p, 20_000);
            let rel = |a: f64, b: f64| (a - b).abs() / b;
            eprintln!(
                "{} vt={}: N-state {:.15} two-state {:.15} rel {:e} (est {:e})",
                c.name,
                p.vt(),
                n.tau,
                reference.tau,
                rel(n.tau, reference.tau),
                n.error_estimate
            );
            assert!(rel(n.tau, reference.tau) < 1e-8, "{}", c.name);
            let s = n.summary();
            assert!(rel(s.tau_plus, reference.tau_plus) < 1e-8, "{}", c.name);
            assert!(rel(s.tau_minus, reference.tau_minus) < 1e-8, "{}", c.name);
        }
    }
}

/// The same with re-drawn noise at a reset and with a random (uniform)
/// target: the reset values go through the N-state bordering with π and
/// with node weights.
#[test]
fn paper_as_states_matches_with_redrawn_noise_and_a_random_target() {
    use irtp::model::reset::{NoiseAtReset, Target};
    let c = NOISE_CASES
        .iter()
        .find(|c| c.noise == PAPER_AS_STATES && c.drag == "tan")
        .unwrap();
    let drag: DragLaw = c.drag.parse().unwrap();
    let two = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
    for (target, rule) in [
        (Target::point(c.reset_velocity), NoiseAtReset::Redrawn),
        (Target::uniform(-0.3, 0.4), NoiseAtReset::Kept),
        (Target::uniform(-0.3, 0.4), NoiseAtReset::Redrawn),
    ] {
        let n = Problem::new(c.params().with_reset(target, rule).unwrap(), 0.1, 0.5).unwrap();
        let q = Problem::new(two.with_reset(target, rule).unwrap(), 0.1, 0.5).unwrap();
        let opts = BackwardOptions::with_cells(20_000);
        let reference = irtp::mfpt::backward::solve(&q, &opts).unwrap();
        let got = solve(&n, 20_000);
        let rel = (got.tau - reference.tau).abs() / reference.tau;
        eprintln!(
            "{target:?} {rule:?}: N-state {} two-state {} rel {rel:e}",
            got.tau, reference.tau
        );
        assert!(rel < 1e-8, "{target:?} {rule:?}");
    }
}

/// Pure OU with g = v: the Siegert formula
/// τ = (1/T) ∫_{v0}^{vt} dy ∫_{-∞}^{y} e^{(Φ(y) - Φ(z))/T} dz, Φ = v²/2,
/// by nested adaptive quadrature.
fn siegert(t: f64, v0: f64, vt: f64) -> f64 {
    let cut = 14.0 * t.sqrt();
    let inner = |y: f64| {
        let f = |z: f64| ((y * y - z * z) / (2.0 * t)).exp();
        quad::integrate(&f, y - cut.max(y.abs() + cut), y, 1e-13).unwrap()
    };
    quad::integrate(&inner, v0, vt, 1e-12).unwrap() / t
}

/// The Laplace transform f̃(s) of the r = 0 first-passage density of OU
/// (g = v) from v0 to vt > v0: u(v0)/u(vt) for the solution of
/// T u'' - v u' - s u = 0 that stays bounded as v → -∞ (u ~ |v|^{-s}
/// there), by RK4 shooting upwards from far below (the other solution,
/// e^{v²/2T}, dies out going up).
fn laplace_ou(t: f64, s: f64, v0: f64, vt: f64) -> f64 {
    let start = v0.min(0.0) - 14.0 * t.sqrt() - 2.0;
    let f = |v: f64, y: [f64; 2]| [y[1], (v * y[1] + s * y[0]) / t];
    let rk4 = |mut y: [f64; 2], a: f64, b: f64, steps: usize| {
        let h = (b - a) / steps as f64;
        for k in 0..steps {
            let v = a + k as f64 * h;
            let k1 = f(v, y);
            let k2 = f(
                v + h / 2.0,
                [y[0] + h / 2.0 * k1[0], y[1] + h / 2.0 * k1[1]],
            );
            let k3 = f(
                v + h / 2.0,
                [y[0] + h / 2.0 * k2[0], y[1] + h / 2.0 * k2[1]],
            );
            let k4 = f(v + h, [y[0] + h * k3[0], y[1] + h * k3[1]]);
            for i in 0..2 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        y
    };
    // Started on the decaying solution's leading term |v|^{-s}.
    let y0 = [(-start).powf(-s), s * (-start).powf(-s - 1.0)];
    let at_v0 = rk4(y0, start, v0, 400_000);
    let at_vt = rk4(at_v0, v0, vt, 100_000);
    at_v0[0] / at_vt[0]
}

fn ou(t: f64, rate: f64, v0: f64) -> Params {
    let noise = NoiseModel::parse("none", t).unwrap();
    Params::with_noise(DragLaw::Linear, noise, rate, v0).unwrap()
}

/// OU at r = 0 against Siegert, and with r > 0, v_r = v_0 against the
/// renewal formula τ_r = (1 - f̃(r)) / (r f̃(r)) with f̃ from RK4 shooting:
/// within the solver's error estimate (and 1e-5 relative).
#[test]
fn thermal_ou_against_siegert_and_renewal() {
    let (t, v0, vt) = (0.5, -0.2, 0.8);
    // v0 on a node spacing of the RK4 grid: start + k h.
    let p0 = Problem::new(ou(t, 0.0, v0), v0, vt).unwrap();
    let s0 = solve(&p0, 40_000);
    let reference = siegert(t, v0, vt);
    let err = (s0.tau - reference).abs();
    eprintln!(
        "OU r=0: backward {:.12} Siegert {:.12} |diff| {:e} estimate {:e}",
        s0.tau, reference, err, s0.error_estimate
    );
    assert!(err <= s0.error_estimate.max(1e-8 * reference), "Siegert");
    assert!(err < 1e-5 * reference);
    let r = 0.7;
    let pr = Problem::new(ou(t, r, v0), v0, vt).unwrap();
    let sr = solve(&pr, 40_000);
    let ft = laplace_ou(t, r, v0, vt);
    let renewal = (1.0 - ft) / (r * ft);
    let err = (sr.tau - renewal).abs();
    eprintln!(
        "OU r={r}: backward {:.12} renewal {:.12} |diff| {:e} estimate {:e}",
        sr.tau, renewal, err, sr.error_estimate
    );
    assert!(err <= sr.error_estimate.max(1e-8 * renewal), "renewal");
    assert!(err < 1e-5 * renewal);
    // Consistency of the shooting reference itself: f̃(0) = 1 and
    // -f̃'(0) = τ(r = 0) (Siegert).
    let d = 1e-5;
    let slope = (1.0 - laplace_ou(t, d, v0, vt)) / d;
    assert!(
        (slope - reference).abs() < 1e-3 * reference,
        "{slope} {reference}"
    );
}

/// Every thermal case: moving the truncation (barrier 40 T → 30 T and
/// 50 T) changes τ by less than the discretisation error estimates (the
/// mesh moves with it).
#[test]
fn thermal_truncation_does_not_matter() {
    for c in NOISE_CASES.iter().filter(|c| c.thermal()) {
        for p in [upward(c), downward(c)] {
            let base = solve(&p, 20_000);
            for b in [30.0, 50.0] {
                let fine = backward::solve_on(&p, 20_000, b).unwrap();
                let coarse = backward::solve_on(&p, 10_000, b).unwrap();
                let estimate = (fine.tau - coarse.tau).abs();
                let rel = (fine.tau - base.tau).abs() / base.tau;
                eprintln!(
                    "{} vt={}: barrier {b}: truncation {} (base {}) tau {} rel {rel:e} estimates {:e} {:e}",
                    c.name,
                    p.vt(),
                    fine.truncation,
                    base.truncation,
                    fine.tau,
                    estimate / base.tau,
                    base.error_estimate / base.tau
                );
                assert!(
                    (fine.tau - base.tau).abs() <= estimate + base.error_estimate,
                    "{} {b}",
                    c.name
                );
            }
        }
    }
}

/// Every athermal case: T = 1e-6 against T = 0, within the two error
/// estimates (the fitted scheme is first order there).
#[test]
fn small_temperature_is_continuous() {
    for c in NOISE_CASES.iter().filter(|c| !c.thermal()) {
        let warm = NoiseCase {
            temperature: 1e-6,
            ..*c
        };
        for p in [upward(c), downward(c)] {
            let q = Problem::new(warm.params(), p.v0(), p.vt()).unwrap();
            let cold = solve(&p, 20_000);
            let hot = solve(&q, 20_000);
            let diff = (hot.tau - cold.tau).abs();
            let tol = 2.0 * (hot.error_estimate + cold.error_estimate) + 1e-6 * cold.tau;
            eprintln!(
                "{} vt={}: T=0 {} (est {:e}) T=1e-6 {} (est {:e}) diff {diff:e}",
                c.name,
                p.vt(),
                cold.tau,
                cold.error_estimate,
                hot.tau,
                hot.error_estimate
            );
            assert!(diff <= tol, "{}", c.name);
        }
    }
}

/// Every case: τ ≥ the flow-time bound, each T_s ≥ 0, τ increasing in the
/// distance to an upward target, and the error estimate small.
#[test]
fn bounds_monotonicity_and_estimates() {
    for c in NOISE_CASES.iter() {
        let p = upward(c);
        let (_, hi) = interval(c);
        let mut last = 0.0;
        for frac in [0.2, 0.4, 0.6, 0.8] {
            let vt = p.v0() + frac * (hi - p.v0());
            let q = p.with_target(vt).unwrap();
            let s = solve(&q, 4_000);
            let bound = backward::lower_bound(&q);
            assert!(s.tau >= bound, "{} {vt}", c.name);
            assert!(s.per_state.iter().all(|&t| t >= 0.0), "{}", c.name);
            assert!(s.tau > last, "{}: not increasing at {vt}", c.name);
            assert!(
                s.error_estimate < 1e-3 * s.tau,
                "{} {:e}",
                c.name,
                s.error_estimate
            );
            last = s.tau;
        }
    }
}

/// dτ/dr at r = 0 (the adjoint solve) against difference quotients of
/// τ(r) at r = 0 and small r (on one mesh the discrete derivative is what
/// the adjoint solve gives, up to rounding), over every third case, target
/// 30 % of the way up. Step: τ changes by ~1e-4 relative, and r stays
/// below 1e-2 / τ (the rate scale). Tolerance: the solves' rounding,
/// ~1e-9 τ (condition number ~ cells² with thermal noise), amplified by
/// the quotients' weights (≤ 8/h), times 10, plus 1e-6 |slope|.
#[test]
fn rate_derivative_matches_difference_quotient() {
    for c in NOISE_CASES.iter().step_by(3) {
        let (_, hi) = interval(c);
        let v0 = c.reset_velocity;
        let p = Problem::new(c.at_rate(0.0).params(), v0, v0 + 0.3 * (hi - v0)).unwrap();
        let opts = BackwardOptions::with_cells(4_000);
        let (tau0, slope) = backward::rate_derivative_at_zero(&p, &opts).unwrap();
        let zero = backward::solve_on(&p, 4_000, backward::BARRIER).unwrap();
        assert!((zero.tau - tau0).abs() <= 1e-12 * tau0, "{}", c.name);
        let h = (1e-4 * tau0 / slope.abs()).min(1e-2 / tau0);
        let at = |r: f64| {
            backward::solve_on(&p.with_rate(r).unwrap(), 4_000, backward::BARRIER)
                .unwrap()
                .tau
        };
        // Forward quotients D(h), D(2h), D(4h), Richardson-combined to O(h³).
        let d = |k: f64| (at(k * h) - tau0) / (k * h);
        let (d1, d2, d4) = (d(1.0), d(2.0), d(4.0));
        let (r1, r2) = (2.0 * d1 - d2, 2.0 * d2 - d4);
        let quotient = (4.0 * r1 - r2) / 3.0;
        let tol = 10.0 * 8.0 * 1e-9 * tau0 / h + 1e-6 * slope.abs();
        eprintln!(
            "{}: tau0 {tau0} slope {slope} quotient {quotient} h {h:e} diff {:e} tol {tol:e}",
            c.name,
            (quotient - slope).abs()
        );
        assert!((quotient - slope).abs() < tol, "{}", c.name);
    }
}
