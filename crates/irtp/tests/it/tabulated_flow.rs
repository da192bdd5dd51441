//! A drag law given only by g and g': [`TabulatedFlow`], the flow of such a
//! law, against the closed-form flows of tan, tanh and linear seen through g
//! and g' alone (every other trait method, the inverse and slope bound
//! included, left at its default). The registered laws themselves (cubic,
//! the expression law, ...) run through every method in the conformance
//! suite (`conformance.rs`).

use irtp::model::drag::{AnyFlow, TabulatedFlow};
use irtp::model::{Drag, DragLaw, FlowMap};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use std::sync::OnceLock;

/// `cases` cases from a fixed seed: the same inputs on every run.
fn fixed(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(0x9e7e_41c0),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// A law seen only through g and g': the defaults of every other method run.
#[derive(Clone, Debug)]
struct OnlyG(DragLaw);

impl Drag for OnlyG {
    type Flow = TabulatedFlow<OnlyG>;
    fn name(&self) -> &'static str {
        "only-g"
    }
    fn force(&self, v: f64) -> f64 {
        self.0.force(v)
    }
    fn derivative(&self, v: f64) -> f64 {
        self.0.derivative(v)
    }
    fn flow(&self, s: f64) -> TabulatedFlow<OnlyG> {
        TabulatedFlow::new(self.clone(), s)
    }
}

const CASES: [(DragLaw, f64); 6] = [
    (DragLaw::Tan, 3.0),
    (DragLaw::Tan, 0.4),
    (DragLaw::Tan, 30.0),
    (DragLaw::Tanh, 0.6),
    (DragLaw::Tanh, 0.97),
    (DragLaw::Linear, 2.0),
];

/// Per case and noise sign: (closed-form flow, tabulated flow, accelerated
/// tabulated flow), built once.
fn flows(
    case: usize,
    plus: bool,
) -> &'static (AnyFlow, TabulatedFlow<OnlyG>, TabulatedFlow<OnlyG>) {
    type Flows = (AnyFlow, TabulatedFlow<OnlyG>, TabulatedFlow<OnlyG>);
    static ALL: OnceLock<Vec<Flows>> = OnceLock::new();
    let all = ALL.get_or_init(|| {
        CASES
            .iter()
            .flat_map(|&(ref d, sigma)| {
                [sigma, -sigma].map(|s| {
                    let t = OnlyG(d.clone()).flow(s);
                    (d.flow(s), t.clone(), t.accelerated())
                })
            })
            .collect()
    });
    &all[2 * case + usize::from(!plus)]
}

/// A start va in the interval and a target vb between va and v*, with
/// v* - vb down to 1e-14 |v* - va| (log-uniform), i.e. within 1e-12 of v*.
fn setup(case: usize, plus: bool, xa: f64, ld: f64) -> (f64, f64) {
    let (d, sigma) = CASES[case].clone();
    let vu = d.inverse(sigma);
    let vs = flows(case, plus).0.fixed_point();
    let va = -vu + 2.0 * vu * xa;
    (va, vs - (vs - va) * 10f64.powf(-ld))
}

/// The two flows' fixed points may differ by an ulp (bisection vs libm's
/// atan/atanh); a time to vb near v* moves by |Δv*| / (k |v* - vb|) then.
fn fixed_point_slack(case: usize, plus: bool, vb: f64) -> f64 {
    let (c, t, _) = flows(case, plus);
    let dvs = (c.fixed_point() - t.fixed_point()).abs();
    if dvs == 0.0 {
        0.0
    } else {
        2.0 * dvs / (c.rate() * (c.fixed_point() - vb).abs())
    }
}

proptest! {
    // A fixed number of cases (the flows are exact to ~1e-14, so any
    // failure is a bug, not a rare statistical event).
    #![proptest_config(fixed(1500))]

    /// Flow time: 1e-12 relative (the flows' accuracy standard) plus the
    /// fixed-point slack.
    #[test]
    fn time_matches_closed_form(case in 0usize..6, plus: bool, xa in 0.0005f64..0.9995, ld in 0.0f64..14.0) {
        let (va, vb) = setup(case, plus, xa, ld);
        let (c, t, _) = flows(case, plus);
        prop_assume!(vb != c.fixed_point());
        let (a, b) = (c.time(va, vb), t.time(va, vb));
        prop_assert!(a.is_finite() && a >= 0.0);
        let tol = 1e-12 * a + 1e-15 + fixed_point_slack(case, plus, vb);
        prop_assert!((a - b).abs() <= tol, "{:?} {va}->{vb}: {a} vs {b}", CASES[case]);
    }

    /// Potential differences (t = ΔΦ / k): 1e-12 relative plus the rounding
    /// of the potentials themselves (4 ulp of |Φ|, see `FlowMap::potential`).
    #[test]
    fn potential_differences_match_closed_form(case in 0usize..6, plus: bool, xa in 0.0005f64..0.9995, ld in 0.0f64..14.0) {
        let (va, vb) = setup(case, plus, xa, ld);
        let (c, t, _) = flows(case, plus);
        prop_assume!(vb != c.fixed_point());
        let dc = (c.potential(va) - c.potential(vb)) / c.rate();
        let dt = (t.potential(va) - t.potential(vb)) / t.rate();
        let round = |f: &dyn Fn(f64) -> f64, k: f64| 4.0 * f64::EPSILON * (f(va).abs() + f(vb).abs()) / k;
        let tol = 1e-12 * dc
            + round(&|v| c.potential(v), c.rate())
            + round(&|v| t.potential(v), t.rate())
            + fixed_point_slack(case, plus, vb);
        prop_assert!((dc - dt).abs() <= tol, "{:?} {va}->{vb}: {dc} vs {dt}", CASES[case]);
    }

    /// Velocity after time t (1e-12 .. 50, so also rounded onto v*), plain
    /// and accelerated: 1e-12 relative to the velocity scale max(|v|, |v*|),
    /// plus the fixed points' difference.
    #[test]
    fn velocity_matches_closed_form(case in 0usize..6, plus: bool, xa in 0.0005f64..0.9995, lt in -12.0f64..1.7) {
        let (d, sigma) = CASES[case].clone();
        let vu = d.inverse(sigma);
        let va = -vu + 2.0 * vu * xa;
        let t = 10f64.powf(lt);
        let (c, plain, fast) = flows(case, plus);
        let v = c.velocity(va, t);
        let dvs = (c.fixed_point() - plain.fixed_point()).abs();
        let tol = 1e-12 * v.abs().max(vu) + dvs;
        for (name, f) in [("plain", plain), ("accelerated", fast)] {
            let w = f.velocity(va, t);
            prop_assert!((v - w).abs() <= tol, "{d} {sigma} {name} va={va} t={t}: {v} vs {w}");
        }
    }
}
