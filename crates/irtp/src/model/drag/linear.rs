//! g(v) = v: the Newtonian medium, the exactly solvable reference.

use super::closed::{Canonical, ClosedFlow, ClosedForm, InverseGuide, Solve};
use super::{Drag, FlowMap};

/// g(v) = v, v_u = Sigma.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Linear;

impl Drag for Linear {
    type Flow = ClosedFlow<Linear>;

    fn name(&self) -> &'static str {
        "linear"
    }
    #[inline(always)]
    fn force(&self, v: f64) -> f64 {
        v
    }
    #[inline]
    fn derivative(&self, _v: f64) -> f64 {
        1.0
    }
    fn flow(&self, s: f64) -> ClosedFlow<Linear> {
        ClosedFlow::new(Linear, s)
    }
    fn description(&self) -> &'static str {
        "Newtonian, g = v"
    }
    /// g' = 1.
    fn newtonian(&self) -> bool {
        true
    }
    fn two_sided_flow(&self) -> bool {
        true
    }
    fn explicit_thermal_step(&self) -> bool {
        true
    }
    fn thermal_backward(&self) -> Option<f64> {
        Some(f64::INFINITY)
    }
    fn riccati(&self) -> Option<f64> {
        Some(0.0)
    }
    /// The paper classifies no linear density; irtp's labels follow tan's:
    /// (i) lambda < 1 (U-shaped), uniform at lambda = 1, (iii) up to
    /// lambda = 2 (edges vanish with finite or infinite slope), (iv) beyond.
    fn regime_label(&self, _sigma: f64, lambda: f64) -> Option<(&'static str, String)> {
        Some(if lambda < 1.0 {
            ("i", "lambda < 1".to_string())
        } else if lambda == 1.0 {
            ("uniform", "lambda = 1".to_string())
        } else if lambda <= 2.0 {
            ("iii", "1 < lambda <= 2".to_string())
        } else {
            ("iv", "lambda > 2".to_string())
        })
    }
    #[inline]
    fn inverse(&self, f: f64) -> f64 {
        f.abs().copysign(f)
    }
    fn max_derivative(&self, _sigma: f64) -> f64 {
        1.0
    }
    #[inline]
    fn drift(&self, s: f64, v: f64) -> f64 {
        s - v
    }
    #[inline]
    fn drift_at_distance(&self, _s: f64, u: f64) -> f64 {
        u
    }
    #[inline]
    fn edge_drift(&self, _sigma: f64, x: f64) -> f64 {
        x
    }
    fn flow_time(&self, s: f64, va: f64, vb: f64) -> f64 {
        self.flow(s).time(va, vb)
    }
    fn flow_velocity(&self, s: f64, v0: f64, t: f64) -> f64 {
        self.flow(s).velocity(v0, t)
    }
    /// ∫ u/u dv = vb - va and ∫ u dv = (ua² - ub²)/2, exactly.
    fn flow_deficits(&self, s: f64, va: f64, vb: f64) -> (f64, f64) {
        let (ua, ub) = (s - va, s - vb);
        let d = vb - va;
        (d, 0.5 * d * (ua + ub))
    }
}

impl ClosedForm for Linear {
    fn fixed_point_rate(&self, _s: f64) -> f64 {
        1.0
    }
    /// t = ln(ua/ub) = ln1p(d/ub).
    #[inline]
    fn time_canonical(&self, _c: &Canonical, _ua: f64, ub: f64, d: f64) -> f64 {
        (d / ub).ln_1p()
    }
    /// Φ = ln|u|.
    #[inline]
    fn potential_canonical(&self, _c: &Canonical, u: f64) -> f64 {
        u.abs().ln()
    }
    fn potential_slope(&self, _c: &Canonical, u: f64) -> f64 {
        1.0 / u
    }
    fn small_u_coefficient(&self, _c: &Canonical) -> f64 {
        0.0
    }
    /// v = v* - (v* - v0) e^{-t}.
    fn velocity_canonical(&self, c: &Canonical, q: &Solve, _guide: Option<&InverseGuide>) -> f64 {
        if q.t < 1.0 {
            q.v0 - q.ua * (-q.t).exp_m1()
        } else {
            c.vs - q.ua * (-q.t).exp()
        }
    }
}
