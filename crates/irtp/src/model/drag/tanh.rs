//! g(v) = tanh(v): the paper's shear-thinning medium (Table 1), 0 < Sigma < 1.

use super::closed::{Canonical, ClosedFlow, ClosedForm, InverseGuide, Solve};
use super::{Drag, FlowMap};
use crate::numerics::{fastmath, root};

/// g(v) = tanh(v), bounded by 1: v_u = atanh(Sigma) needs Sigma < 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Tanh;

impl Drag for Tanh {
    type Flow = ClosedFlow<Tanh>;

    fn name(&self) -> &'static str {
        "tanh"
    }
    #[inline]
    fn force(&self, v: f64) -> f64 {
        v.tanh()
    }
    #[inline]
    fn derivative(&self, v: f64) -> f64 {
        let c = v.cosh();
        1.0 / (c * c)
    }
    fn flow(&self, s: f64) -> ClosedFlow<Tanh> {
        ClosedFlow::new(Tanh, s)
    }
    fn description(&self) -> &'static str {
        "shear-thinning, g = tanh v"
    }
    /// tanh' = 1 - tanh².
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
        Some(-1.0)
    }
    /// (a)-(d): thresholds g'(v_u) = 1-Sigma², g'(0) = 1 and 2 g'(v_u); (c)
    /// as corrected in [`crate::analytic::r0::regime`].
    fn regime_label(&self, sigma: f64, lambda: f64) -> Option<(&'static str, String)> {
        let gp = 1.0 - sigma * sigma;
        let two = 2.0 * gp;
        Some(if lambda <= gp {
            ("a", format!("lambda <= 1-Sigma^2 = {gp}"))
        } else if lambda < 1.0 {
            ("b", format!("1-Sigma^2 = {gp} < lambda < 1"))
        } else if lambda <= two {
            ("c", format!("1 <= lambda <= 2(1-Sigma^2) = {two}"))
        } else {
            (
                "d",
                format!("lambda >= 1 and lambda > 2(1-Sigma^2) = {two}"),
            )
        })
    }
    /// Exactly odd (libm's atanh(-x) can differ from -atanh(x) in the last bit).
    #[inline]
    fn inverse(&self, f: f64) -> f64 {
        f.abs().atanh().copysign(f)
    }
    fn force_limit(&self) -> f64 {
        1.0
    }
    /// g' = sech² is largest at v = 0.
    fn max_derivative(&self, _sigma: f64) -> f64 {
        1.0
    }
    #[inline(always)]
    fn fast_force(&self, v: f64) -> f64 {
        fastmath::tanh(v)
    }
    #[inline]
    fn drift(&self, s: f64, v: f64) -> f64 {
        self.drift_at_distance(s, self.inverse(s) - v)
    }
    /// s - tanh(v* - u) = sqrt(1-s²) sinh u / cosh v, exact to rounding as u → 0.
    #[inline]
    fn drift_at_distance(&self, s: f64, u: f64) -> f64 {
        ((1.0 - s) * (1.0 + s)).sqrt() * u.sinh() / (s.atanh() - u).cosh()
    }
    /// Sigma - tanh(v_u - x) = (1-Sigma²) tanh x / (1 - Sigma tanh x).
    #[inline]
    fn edge_drift(&self, sigma: f64, x: f64) -> f64 {
        let t = x.tanh();
        (1.0 - sigma * sigma) * t / (1.0 - sigma * t)
    }
    fn flow_time(&self, s: f64, va: f64, vb: f64) -> f64 {
        self.flow(s).time(va, vb)
    }
    fn flow_velocity(&self, s: f64, v0: f64, t: f64) -> f64 {
        self.flow(s).velocity(v0, t)
    }
}

impl ClosedForm for Tanh {
    fn fixed_point_rate(&self, s: f64) -> f64 {
        (1.0 - s) * (1.0 + s)
    }

    /// t = [ln(sinh ua / sinh ub) - s d] / (1 - s²), the log of the ratio in
    /// the cancellation-free form of [`super::tan::Tan`]'s.
    #[inline]
    fn time_canonical(&self, c: &Canonical, ua: f64, ub: f64, d: f64) -> f64 {
        let m = 0.5 * (ua + ub);
        let ratio = 2.0 * m.cosh() * (0.5 * d).sinh() / ub.sinh();
        (ratio.ln_1p() - c.s * d) / c.k
    }

    /// Φ = ln|sinh u| - s u.
    #[inline]
    fn potential_canonical(&self, c: &Canonical, u: f64) -> f64 {
        u.abs().sinh().ln() - c.s * u
    }

    fn potential_slope(&self, c: &Canonical, u: f64) -> f64 {
        1.0 / u.tanh() - c.s
    }

    fn small_u_coefficient(&self, c: &Canonical) -> f64 {
        c.s
    }

    /// As [`super::tan::Tan`]'s, with Φ = ln|sinh u| - s u.
    fn velocity_canonical(&self, c: &Canonical, q: &Solve, guide: Option<&InverseGuide>) -> f64 {
        let (s, sg, a, wa) = (c.s, q.sg, q.a, q.wa);
        let sa = a.sinh();
        let cc = sa.ln() - s * q.ua - q.kt;
        let (lo, hi) = if sg > 0.0 {
            (cc - (1.0 - s) * a, cc + s * a)
        } else {
            (cc - (1.0 + s) * a, cc)
        };
        let hi = hi.min(wa);
        if hi < c.tiny_w {
            return c.vs;
        }
        let guess = match guide {
            Some(g) if sg > 0.0 => g.ln_u(cc) - wa,
            _ if q.precise => -q.kt / (a / a.tanh() - s * sg * a),
            _ => cc - wa,
        };
        let h = |dl: f64| {
            let e = a * dl.exp();
            // sinh and coth from one expm1 (accurate for tiny e).
            let m = e.exp_m1();
            let sh = m * (m + 2.0) / (2.0 * (m + 1.0));
            let coth = ((m + 1.0) * (m + 1.0) + 1.0) / (m * (m + 2.0));
            let dh = e * coth - s * sg * e;
            let d2 = e * (coth - e / (sh * sh) - s * sg);
            if q.precise {
                let du = a * dl.exp_m1();
                let diff = 2.0 * (0.5 * (e + a)).cosh() * (0.5 * du).sinh() / sa;
                (diff.ln_1p() - s * sg * du + q.kt, dh, d2)
            } else {
                (sh.ln() - s * sg * e - cc, dh, d2)
            }
        };
        let dl = root::solve_increasing(&h, lo.max(-745.0) - wa, hi - wa, guess, 1e-6, 0.0);
        // The bracket is rigorous, so a failure means non-finite input: NaN
        // (the samplers check their outputs), never a last iterate.
        dl.map_or(f64::NAN, |dl| q.finish(c.vs, dl))
    }
}
