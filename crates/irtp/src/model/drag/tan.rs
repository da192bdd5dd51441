//! g(v) = tan(v): the paper's shear-thickening medium (Table 1), any Sigma > 0.

use super::closed::{Canonical, ClosedFlow, ClosedForm, InverseGuide, Solve};
use super::{Drag, FlowMap};
use crate::numerics::{fastmath, root};

/// g(v) = tan(v), v_u = atan(Sigma).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Tan;

impl Drag for Tan {
    type Flow = ClosedFlow<Tan>;

    fn name(&self) -> &'static str {
        "tan"
    }
    #[inline]
    fn force(&self, v: f64) -> f64 {
        v.tan()
    }
    #[inline]
    fn derivative(&self, v: f64) -> f64 {
        let t = v.tan();
        1.0 + t * t
    }
    fn flow(&self, s: f64) -> ClosedFlow<Tan> {
        ClosedFlow::new(Tan, s)
    }
    fn description(&self) -> &'static str {
        "shear-thickening, g = tan v"
    }
    /// tan' = 1 + tan².
    fn two_sided_flow(&self) -> bool {
        true
    }
    /// T <= 1: above it the thermal particle reaches the bound ±π/2.
    fn thermal_backward(&self) -> Option<f64> {
        Some(1.0)
    }
    fn riccati(&self) -> Option<f64> {
        Some(1.0)
    }
    /// (i)-(iv): thresholds g'(0) = 1, g'(v_u) = 1+Sigma² and twice that.
    fn regime_label(&self, sigma: f64, lambda: f64) -> Option<(&'static str, String)> {
        let gp = 1.0 + sigma * sigma;
        let two = 2.0 * gp;
        Some(if lambda <= 1.0 {
            ("i", "lambda <= 1".to_string())
        } else if lambda < gp {
            ("ii", format!("1 < lambda < 1+Sigma^2 = {gp}"))
        } else if lambda <= two {
            (
                "iii",
                format!("1+Sigma^2 <= lambda <= 2(1+Sigma^2) = {two}"),
            )
        } else {
            ("iv", format!("lambda > 2(1+Sigma^2) = {two}"))
        })
    }
    /// Exactly odd, so v*(-Sigma) = -v*(Sigma) = v_l to the bit.
    #[inline]
    fn inverse(&self, f: f64) -> f64 {
        f.abs().atan().copysign(f)
    }
    /// g' = 1 + tan² is largest at the edges, where tan = ±Sigma.
    fn max_derivative(&self, sigma: f64) -> f64 {
        1.0 + sigma * sigma
    }
    #[inline(always)]
    fn fast_force(&self, v: f64) -> f64 {
        fastmath::tan(v)
    }
    #[inline]
    fn drift(&self, s: f64, v: f64) -> f64 {
        self.drift_at_distance(s, self.inverse(s) - v)
    }
    /// s - tan(v* - u) = sqrt(1+s²) sin u / cos v, exact to rounding as u → 0.
    #[inline]
    fn drift_at_distance(&self, s: f64, u: f64) -> f64 {
        s.hypot(1.0) * u.sin() / (s.atan() - u).cos()
    }
    /// Sigma - tan(v_u - x) = (1+Sigma²) tan x / (1 + Sigma tan x).
    #[inline]
    fn edge_drift(&self, sigma: f64, x: f64) -> f64 {
        let t = x.tan();
        (1.0 + sigma * sigma) * t / (1.0 + sigma * t)
    }
    fn flow_time(&self, s: f64, va: f64, vb: f64) -> f64 {
        self.flow(s).time(va, vb)
    }
    fn flow_velocity(&self, s: f64, v0: f64, t: f64) -> f64 {
        self.flow(s).velocity(v0, t)
    }
}

impl ClosedForm for Tan {
    fn fixed_point_rate(&self, s: f64) -> f64 {
        1.0 + s * s
    }

    /// t = [ln(sin ua / sin ub) + s d] / (1 + s²) (integrate
    /// 1/(s - tan v) = cos v* cos v / sin u in u), the log of the ratio as
    /// ln1p((sin ua - sin ub)/sin ub) with sin ua - sin ub =
    /// 2 cos((ua+ub)/2) sin(d/2): full relative accuracy for short segments
    /// and next to v*.
    #[inline]
    fn time_canonical(&self, c: &Canonical, ua: f64, ub: f64, d: f64) -> f64 {
        let m = 0.5 * (ua + ub);
        let ratio = 2.0 * m.cos() * (0.5 * d).sin() / ub.sin();
        (ratio.ln_1p() + c.s * d) / c.k
    }

    /// Φ = ln|sin u| + s u.
    #[inline]
    fn potential_canonical(&self, c: &Canonical, u: f64) -> f64 {
        u.abs().sin().ln() + c.s * u
    }

    fn potential_slope(&self, c: &Canonical, u: f64) -> f64 {
        1.0 / u.tan() + c.s
    }

    fn small_u_coefficient(&self, c: &Canonical) -> f64 {
        -c.s
    }

    /// Φ(u) = Φ(ua) - k t in the unknown δ = ln|u/ua|: Φ = δ + ln|ua| + O(u),
    /// nearly linear, exactly linear as v → v*. Halley steps inside a rigorous
    /// bracket (from bounds on Φ(u) - ln|u|), started from the guide, the
    /// linearisation at ua (short times) or the asymptotic solution.
    fn velocity_canonical(&self, c: &Canonical, q: &Solve, guide: Option<&InverseGuide>) -> f64 {
        let (s, sg, a, wa) = (c.s, q.sg, q.a, q.wa);
        let sa = a.sin();
        let ln_sa = sa.ln();
        let cc = ln_sa + s * q.ua - q.kt;
        let r0 = wa - ln_sa; // -ln(sin a / a) ≥ 0
        let (lo, hi) = if sg > 0.0 {
            (cc - s * a, cc + r0)
        } else {
            (cc, cc + r0 + 1.0)
        };
        let hi = hi.min(wa);
        if hi < c.tiny_w {
            return c.vs;
        }
        let guess = match guide {
            Some(g) if sg > 0.0 => g.ln_u(cc) - wa,
            _ if q.precise => -q.kt / (a * a.cos() / sa + s * sg * a),
            _ => cc - wa,
        };
        let h = |dl: f64| {
            let e = a * dl.exp();
            // sin and cot from one tan(e/2) (e ∈ (0, π)).
            let th = (0.5 * e).tan();
            let sn = 2.0 * th / (1.0 + th * th);
            let cot = (1.0 - th * th) / (2.0 * th);
            let dh = e * cot + s * sg * e;
            let d2 = e * (cot - e / (sn * sn) + s * sg);
            if q.precise {
                let du = a * dl.exp_m1(); // |u| - |ua|
                let diff = 2.0 * (0.5 * (e + a)).cos() * (0.5 * du).sin() / sa;
                (diff.ln_1p() + s * sg * du + q.kt, dh, d2)
            } else {
                (sn.ln() + s * sg * e - cc, dh, d2)
            }
        };
        let dl = root::solve_increasing(&h, lo.max(-745.0) - wa, hi - wa, guess, 1e-6, 0.0);
        // The bracket is rigorous, so a failure means non-finite input: NaN
        // (the samplers check their outputs), never a last iterate.
        dl.map_or(f64::NAN, |dl| q.finish(c.vs, dl))
    }
}
