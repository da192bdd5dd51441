//! Drag laws g(v) (paper Table 1) behind the [`Drag`] trait.
//!
//! Between noise flips and resets the velocity follows the deterministic flow
//! dv/dt = s - g(v) with s = ±Sigma (paper Eq. 5). Its fixed point v* = g⁻¹(s)
//! bounds the velocity: v ∈ (-g⁻¹(Sigma), g⁻¹(Sigma)) (paper Eqs. 8-10).

use crate::numerics::{quad, root};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// A velocity-dependent drag force g(v): odd, smooth, strictly increasing,
/// g'(v) > 0. Everything the solvers need about a medium lives here.
pub trait Drag: Copy + Send + Sync + fmt::Debug {
    /// Short name (`tan`, `tanh`, `linear`).
    fn name(&self) -> &'static str;
    /// The drag force g(v).
    fn force(&self, v: f64) -> f64;
    /// Its derivative g'(v).
    fn derivative(&self, v: f64) -> f64;
    /// The inverse g⁻¹(f): the fixed point of dv/dt = f - g(v).
    fn inverse(&self, f: f64) -> f64;
    /// sup_v g(v): the noise amplitude Sigma must stay strictly below it
    /// (1 for tanh, +∞ for tan and linear).
    fn force_limit(&self) -> f64;
    /// max of g'(v) over the admissible interval [-g⁻¹(Sigma), g⁻¹(Sigma)].
    /// Sets the Euler stability limit dt < 1/max g' and the FP CFL number.
    fn max_derivative(&self, sigma: f64) -> f64;

    // ---- Exact deterministic flow dv/dt = s - g(v) between events (issue 6) ----
    //
    // Defaults work for any smooth increasing drag by quadrature in the
    // variable w = ln|v* - v| (the approach to v* = g⁻¹(s) is exponential, so
    // every integrand is smooth and bounded in w); [`DragLaw`] overrides them
    // with closed forms.

    /// The drift s - g(v). Override with a form that stays accurate near the
    /// fixed point v* = g⁻¹(s), where s - g(v) ≈ g'(v*) (v* - v) cancels.
    #[inline]
    fn drift(&self, s: f64, v: f64) -> f64 {
        s - self.force(v)
    }

    /// The drift s - g(v* - u) at distance u from the fixed point. Quadratures
    /// near v* use this form: v* - u itself rounds (u is known more exactly
    /// than v), so drift(s, v) alone cannot resolve u below ulp(v*).
    #[inline]
    fn drift_at_distance(&self, s: f64, u: f64) -> f64 {
        self.drift(s, self.inverse(s) - u)
    }

    /// Flow time t(va → vb) = ∫_{va}^{vb} dv / (s - g(v)); 0 if vb = va and
    /// +∞ if vb is not reached by the forward flow from va (behind va, at or
    /// beyond the fixed point v*).
    fn flow_time(&self, s: f64, va: f64, vb: f64) -> f64 {
        let vs = self.inverse(s);
        let (ua, ub) = (vs - va, vs - vb);
        if vb == va {
            return 0.0;
        }
        if !reachable(ua, ub) {
            return f64::INFINITY;
        }
        // t = ∫_{wb}^{wa} u / (s - g(v* - u)) dw, u = ±e^w: bounded, smooth.
        let sg = ua.signum();
        let f = |w: f64| {
            let u = sg * w.exp();
            u / self.drift_at_distance(s, u)
        };
        // The trait returns f64: a failed quadrature reads as NaN.
        quad::integrate(&f, ub.abs().ln(), ua.abs().ln(), 1e-14).unwrap_or(f64::NAN)
    }

    /// Velocity after flowing for time t ≥ 0 from v0 (inverse of
    /// [`Drag::flow_time`]; monotone in t, tends to v* but, in exact
    /// arithmetic, never reaches it).
    fn flow_velocity(&self, s: f64, v0: f64, t: f64) -> f64 {
        let vs = self.inverse(s);
        let ua = vs - v0;
        if t <= 0.0 || ua == 0.0 {
            return v0;
        }
        let sg = ua.signum();
        let wa = ua.abs().ln();
        // H(w) = t - t(v0 → v(w)) increases with w = ln|v* - v| (H(wa) = t > 0),
        // H'(w) = u / (s - g(v)); safeguarded Newton.
        let h = |w: f64| {
            let u = sg * w.exp();
            let v = vs - u;
            let tt = self.flow_time(s, v0, v);
            (t - tt, u / self.drift_at_distance(s, u), 0.0)
        };
        let g1 = self.derivative(vs).max(f64::MIN_POSITIVE);
        // The trait returns f64: a failed root search reads as NaN.
        root::solve_increasing(&h, -745.0, wa, wa - g1 * t, 1e-9, 1e-15)
            .map_or(f64::NAN, |w| vs - sg * w.exp())
    }

    /// Deficit integrals along the flow from va to vb:
    /// (∫ (v* - v) dt, ∫ (v* - v)² dt) = ∫_{va}^{vb} (v* - v)^k / (s - g(v)) dv,
    /// k = 1, 2. Their integrands are smooth up to v* (→ 1/g'(v*) and → 0),
    /// so they stay accurate even when vb rounds to v*.
    fn flow_deficits(&self, s: f64, va: f64, vb: f64) -> (f64, f64) {
        quadrature_deficits(self, s, va, vb)
    }

    /// Displacement ∫_0^t v dt' along the flow from v0 = v(0):
    /// x = v* t - ∫ (v* - v) dt (machine-precision form, no large cancellation).
    fn flow_displacement(&self, s: f64, v0: f64, t: f64) -> f64 {
        let vs = self.inverse(s);
        let vb = self.flow_velocity(s, v0, t);
        vs * t - self.flow_deficits(s, v0, vb).0
    }
}

/// [`Drag::flow_deficits`] by adaptive quadrature in v with the accurate drift
/// (the default, and the tan and tanh laws).
fn quadrature_deficits<D: Drag>(d: &D, s: f64, va: f64, vb: f64) -> (f64, f64) {
    let vs = d.inverse(s);
    if vb == va {
        return (0.0, 0.0);
    }
    let f1 = |v: f64| {
        let u = vs - v;
        if u == 0.0 {
            1.0 / d.derivative(vs)
        } else {
            u / d.drift_at_distance(s, u)
        }
    };
    let f2 = |v: f64| (vs - v) * f1(v);
    // The trait returns f64: a failed quadrature reads as NaN.
    (
        quad::integrate(&f1, va, vb, 1e-14).unwrap_or(f64::NAN),
        quad::integrate(&f2, va, vb, 1e-14).unwrap_or(f64::NAN),
    )
}

/// Is vb (distance ub to v*) reached by the flow from va (distance ua)?
#[inline]
fn reachable(ua: f64, ub: f64) -> bool {
    ua != 0.0 && ub != 0.0 && ua.signum() == ub.signum() && ub.abs() <= ua.abs()
}

/// The drag laws shipped with irtp.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DragLaw {
    /// g(v) = tan(v): shear-thickening medium (any Sigma > 0).
    Tan,
    /// g(v) = tanh(v): shear-thinning medium (needs 0 < Sigma < 1).
    Tanh,
    /// g(v) = v: Newtonian medium, the exactly solvable reference case.
    Linear,
}

impl DragLaw {
    /// All drag laws, for iteration in tests and sweeps.
    pub const ALL: [DragLaw; 3] = [DragLaw::Tan, DragLaw::Tanh, DragLaw::Linear];
}

impl Drag for DragLaw {
    fn name(&self) -> &'static str {
        match self {
            DragLaw::Tan => "tan",
            DragLaw::Tanh => "tanh",
            DragLaw::Linear => "linear",
        }
    }

    #[inline]
    fn force(&self, v: f64) -> f64 {
        match self {
            DragLaw::Tan => v.tan(),
            DragLaw::Tanh => v.tanh(),
            DragLaw::Linear => v,
        }
    }

    #[inline]
    fn derivative(&self, v: f64) -> f64 {
        match self {
            DragLaw::Tan => {
                let t = v.tan();
                1.0 + t * t
            }
            DragLaw::Tanh => {
                let c = v.cosh();
                1.0 / (c * c)
            }
            DragLaw::Linear => 1.0,
        }
    }

    /// Exactly odd (libm's atanh(-x) can differ from -atanh(x) in the last
    /// bit), so v*(-Sigma) = -v*(Sigma) = v_l to the bit.
    #[inline]
    fn inverse(&self, f: f64) -> f64 {
        let a = f.abs();
        let r = match self {
            DragLaw::Tan => a.atan(),
            DragLaw::Tanh => a.atanh(),
            DragLaw::Linear => a,
        };
        r.copysign(f)
    }

    fn force_limit(&self) -> f64 {
        match self {
            DragLaw::Tanh => 1.0,
            DragLaw::Tan | DragLaw::Linear => f64::INFINITY,
        }
    }

    fn max_derivative(&self, sigma: f64) -> f64 {
        match self {
            // g' = 1 + tan² is largest at the edges, where tan = ±Sigma.
            DragLaw::Tan => 1.0 + sigma * sigma,
            // g' = sech² is largest at v = 0.
            DragLaw::Tanh | DragLaw::Linear => 1.0,
        }
    }

    /// With u = v* - v: s - tan v = sqrt(1+s²) sin u / cos v and
    /// s - tanh v = sqrt(1-s²) sinh u / cosh v, exact to rounding even as u → 0.
    #[inline]
    fn drift(&self, s: f64, v: f64) -> f64 {
        match self {
            DragLaw::Linear => s - v,
            _ => self.drift_at_distance(s, self.inverse(s) - v),
        }
    }

    #[inline]
    fn drift_at_distance(&self, s: f64, u: f64) -> f64 {
        match self {
            DragLaw::Tan => s.hypot(1.0) * u.sin() / (s.atan() - u).cos(),
            DragLaw::Tanh => ((1.0 - s) * (1.0 + s)).sqrt() * u.sinh() / (s.atanh() - u).cosh(),
            DragLaw::Linear => u,
        }
    }

    /// Closed forms, see [`Flow::time`].
    fn flow_time(&self, s: f64, va: f64, vb: f64) -> f64 {
        Flow::new(*self, s).time(va, vb)
    }

    /// Closed form or safeguarded Halley iteration, see [`Flow::velocity`].
    fn flow_velocity(&self, s: f64, v0: f64, t: f64) -> f64 {
        Flow::new(*self, s).velocity(v0, t)
    }

    /// Linear: ∫ u/u dv = vb - va and ∫ u dv = (ua² - ub²)/2 exactly; tan and
    /// tanh use the default adaptive quadrature with the accurate drift.
    fn flow_deficits(&self, s: f64, va: f64, vb: f64) -> (f64, f64) {
        match self {
            DragLaw::Linear => {
                let (ua, ub) = (s - va, s - vb);
                let d = vb - va;
                (d, 0.5 * d * (ua + ub))
            }
            _ => quadrature_deficits(self, s, va, vb),
        }
    }
}

/// The exact flow dv/dt = s - g(v) of a [`DragLaw`] for one noise value s,
/// with its constants precomputed (the hot-loop form of [`Drag::flow_time`]
/// and [`Drag::flow_velocity`], which build one per call).
///
/// All three laws are odd, so s < 0 is mapped to s > 0 by v → -v; below,
/// s ≥ 0, v* = g⁻¹(s) and u = v* - v.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flow {
    law: DragLaw,
    /// +1, or -1 when s < 0 was reflected.
    refl: f64,
    /// |s|.
    s: f64,
    /// Canonical fixed point g⁻¹(|s|).
    vs: f64,
    /// g'(v*): 1 + s² (tan), 1 - s² (tanh), 1 (linear).
    k: f64,
    /// ln of a quarter ulp of v*: below it v* - v rounds to 0.
    tiny_w: f64,
}

impl Flow {
    /// Flow of `law` with noise value `s`.
    pub fn new(law: DragLaw, s: f64) -> Self {
        let a = s.abs();
        let vs = law.inverse(a);
        let k = match law {
            DragLaw::Tan => 1.0 + a * a,
            DragLaw::Tanh => (1.0 - a) * (1.0 + a),
            DragLaw::Linear => 1.0,
        };
        Flow {
            law,
            refl: if s < 0.0 { -1.0 } else { 1.0 },
            s: a,
            vs,
            k,
            tiny_w: (vs * f64::EPSILON * 0.25).max(1e-300).ln(),
        }
    }

    /// The fixed point v* = g⁻¹(s) (signed).
    pub fn fixed_point(&self) -> f64 {
        self.refl * self.vs
    }

    /// Flow time from va to vb (+∞ if not reached, 0 if equal). Closed forms
    /// with u = v* - v, d = vb - va = ua - ub:
    /// linear t = ln(ua/ub);
    /// tan  t = [ln(sin ua / sin ub) + s d] / (1 + s²);
    /// tanh t = [ln(sinh ua / sinh ub) - s d] / (1 - s²)
    /// (integrate 1/(s - tan v) = cos v* cos v / sin u, resp.
    /// cosh v* cosh v / sinh u, in u). The log of the ratio is evaluated as
    /// ln1p((sin ua - sin ub)/sin ub) with sin ua - sin ub = 2 cos((ua+ub)/2)
    /// sin(d/2) (sinh/cosh alike), so short segments and segments ending next
    /// to v* keep full relative accuracy.
    #[inline]
    pub fn time(&self, va: f64, vb: f64) -> f64 {
        let (va, vb) = (self.refl * va, self.refl * vb);
        let (s, vs) = (self.s, self.vs);
        let (ua, ub) = (vs - va, vs - vb);
        if vb == va {
            return 0.0;
        }
        if !reachable(ua, ub) {
            return f64::INFINITY;
        }
        let d = vb - va;
        let m = 0.5 * (ua + ub);
        match self.law {
            DragLaw::Linear => (d / ub).ln_1p(),
            DragLaw::Tan => {
                let ratio = 2.0 * m.cos() * (0.5 * d).sin() / ub.sin();
                (ratio.ln_1p() + s * d) / self.k
            }
            DragLaw::Tanh => {
                let ratio = 2.0 * m.cosh() * (0.5 * d).sinh() / ub.sinh();
                (ratio.ln_1p() - s * d) / self.k
            }
        }
    }

    /// g'(v*), the rate of the exponential approach to v*.
    pub fn rate(&self) -> f64 {
        self.k
    }

    /// The flow potential Φ with t(va → vb) = (Φ(va) - Φ(vb)) / g'(v*) for any
    /// vb reached from va: Φ = ln|u| (linear), ln|sin u| + s u (tan),
    /// ln|sinh u| - s u (tanh), u = v* - v in the reflected (s ≥ 0) frame;
    /// -∞ at v*. A difference of potentials loses ~1e-16 |Φ| absolute
    /// accuracy ([`Flow::time`] does not), which is harmless for occupation
    /// times; one potential per velocity replaces a time per pair.
    #[inline]
    pub fn potential(&self, v: f64) -> f64 {
        let u = self.vs - self.refl * v;
        let a = u.abs();
        match self.law {
            DragLaw::Linear => a.ln(),
            DragLaw::Tan => a.sin().ln() + self.s * u,
            DragLaw::Tanh => a.sinh().ln() - self.s * u,
        }
    }

    /// Velocity after time t ≥ 0 from v0. Linear: v = v* - (v* - v0) e^{-t}.
    /// tan/tanh: the time formula reads Φ(u) = Φ(ua) - g'(v*) t with
    /// Φ(u) = ln|sin u| + s u (tan) or ln|sinh u| - s u (tanh). In the unknown
    /// δ = ln|u/ua|, Φ = δ + ln|ua| + O(u): nearly linear, and exactly linear
    /// as v → v* (where the approach is exponential). Solved by Halley steps
    /// inside a rigorous bracket (from bounds on Φ(u) - ln|u|), starting
    /// from the asymptotic solution or, for short times, the linearisation at
    /// ua. Short segments (g'(v*) t < 1/2) use the cancellation-free
    /// difference Φ(u) - Φ(ua) and return v0 - (u - ua), so v keeps full
    /// accuracy for any t; otherwise v = v* - u keeps full relative accuracy in
    /// v* - v down to ulp(v*).
    #[inline]
    pub fn velocity(&self, v0: f64, t: f64) -> f64 {
        let v0r = self.refl * v0;
        self.refl * self.velocity_canonical(v0r, t, None)
    }

    /// [`Flow::velocity`] started from the tabulated inverse of the potential
    /// (`guide` built for this flow): the first Halley step then already
    /// converges, about three times cheaper. Same result to rounding.
    #[inline]
    pub fn velocity_guided(&self, v0: f64, t: f64, guide: &InverseGuide) -> f64 {
        let v0r = self.refl * v0;
        self.refl * self.velocity_canonical(v0r, t, Some(guide))
    }

    fn velocity_canonical(&self, v0: f64, t: f64, guide: Option<&InverseGuide>) -> f64 {
        let (s, vs, k) = (self.s, self.vs, self.k);
        let ua = vs - v0;
        if !(t > 0.0) || ua == 0.0 {
            return v0;
        }
        let sg = ua.signum();
        let a = ua.abs();
        let wa = a.ln();
        let kt = k * t;
        let precise = kt < 0.5;
        let finish = |dl: f64| {
            if precise {
                v0 - sg * a * dl.exp_m1()
            } else {
                vs - sg * a * dl.exp()
            }
        };
        match self.law {
            DragLaw::Linear if t < 1.0 => v0 - ua * (-t).exp_m1(),
            DragLaw::Linear => vs - ua * (-t).exp(),
            DragLaw::Tan => {
                let sa = a.sin();
                let ln_sa = sa.ln();
                let phi_a = ln_sa + s * ua;
                let c = phi_a - kt;
                let r0 = wa - ln_sa; // -ln(sin a / a) ≥ 0
                let (lo, hi) = if sg > 0.0 {
                    (c - s * a, c + r0)
                } else {
                    (c, c + r0 + 1.0)
                };
                let hi = hi.min(wa);
                if hi < self.tiny_w {
                    return vs;
                }
                let guess = match guide {
                    Some(g) if sg > 0.0 => g.ln_u(c) - wa,
                    _ if precise => -kt / (a * a.cos() / sa + s * sg * a),
                    _ => c - wa,
                };
                let h = |dl: f64| {
                    let e = a * dl.exp();
                    // sin and cot from one tan(e/2) (e ∈ (0, π)).
                    let th = (0.5 * e).tan();
                    let sn = 2.0 * th / (1.0 + th * th);
                    let cot = (1.0 - th * th) / (2.0 * th);
                    let dh = e * cot + s * sg * e;
                    let d2 = e * (cot - e / (sn * sn) + s * sg);
                    if precise {
                        let du = a * dl.exp_m1(); // |u| - |ua|
                        let diff = 2.0 * (0.5 * (e + a)).cos() * (0.5 * du).sin() / sa;
                        (diff.ln_1p() + s * sg * du + kt, dh, d2)
                    } else {
                        (sn.ln() + s * sg * e - c, dh, d2)
                    }
                };
                // A failed root search reads as NaN (the hot loop returns f64).
                root::solve_increasing(&h, lo.max(-745.0) - wa, hi - wa, guess, 1e-6, 0.0)
                    .map_or(f64::NAN, finish)
            }
            DragLaw::Tanh => {
                let sa = a.sinh();
                let phi_a = sa.ln() - s * ua;
                let c = phi_a - kt;
                let (lo, hi) = if sg > 0.0 {
                    (c - (1.0 - s) * a, c + s * a)
                } else {
                    (c - (1.0 + s) * a, c)
                };
                let hi = hi.min(wa);
                if hi < self.tiny_w {
                    return vs;
                }
                let guess = match guide {
                    Some(g) if sg > 0.0 => g.ln_u(c) - wa,
                    _ if precise => -kt / (a / a.tanh() - s * sg * a),
                    _ => c - wa,
                };
                let h = |dl: f64| {
                    let e = a * dl.exp();
                    // sinh and coth from one expm1 (accurate for tiny e).
                    let m = e.exp_m1();
                    let sh = m * (m + 2.0) / (2.0 * (m + 1.0));
                    let coth = ((m + 1.0) * (m + 1.0) + 1.0) / (m * (m + 2.0));
                    let dh = e * coth - s * sg * e;
                    let d2 = e * (coth - e / (sh * sh) - s * sg);
                    if precise {
                        let du = a * dl.exp_m1();
                        let diff = 2.0 * (0.5 * (e + a)).cosh() * (0.5 * du).sinh() / sa;
                        (diff.ln_1p() - s * sg * du + kt, dh, d2)
                    } else {
                        (sh.ln() - s * sg * e - c, dh, d2)
                    }
                };
                // A failed root search reads as NaN (the hot loop returns f64).
                root::solve_increasing(&h, lo.max(-745.0) - wa, hi - wa, guess, 1e-6, 0.0)
                    .map_or(f64::NAN, finish)
            }
        }
    }
}

/// Tabulated inverse of the flow potential for one [`Flow`] on the velocity
/// interval (-|v*|, |v*|): ln u as a function of Φ (canonical frame), by cubic
/// Hermite interpolation on a uniform Φ grid (nodes solved once with the
/// Halley iteration), and the small-u expansion ln u = Φ ∓ s e^Φ + O(u²)
/// below it. Used only as a starting guess (error ~1e-9), so the result of
/// [`Flow::velocity_guided`] does not depend on its accuracy.
#[derive(Clone, Debug)]
pub struct InverseGuide {
    /// Φ at the first node (u = 1e-3).
    phi0: f64,
    /// Node spacing and its inverse.
    h: f64,
    inv_h: f64,
    /// ln u and d ln u / dΦ at the nodes.
    lnu: Vec<f64>,
    dlnu: Vec<f64>,
    /// Coefficient c of ln u ≈ Φ + c e^Φ for small u.
    small: f64,
}

impl InverseGuide {
    /// Nodes on the uniform Φ grid.
    const NODES: usize = 1024;

    /// Build for `flow` (any law; linear gets the exact ln u = Φ).
    pub fn new(flow: &Flow) -> Self {
        let (s, vs) = (flow.s, flow.vs);
        let dphi = |u: f64| match flow.law {
            DragLaw::Linear => 1.0 / u,
            DragLaw::Tan => 1.0 / u.tan() + s,
            DragLaw::Tanh => 1.0 / u.tanh() - s,
        };
        let small = match flow.law {
            DragLaw::Linear => 0.0,
            DragLaw::Tan => -s,
            DragLaw::Tanh => s,
        };
        let pot = |u: f64| flow.potential(flow.refl * (vs - u));
        let u_far = 2.0 * vs;
        let phi_max = pot(u_far);
        let phi0 = pot(1e-3_f64.min(0.5 * u_far));
        let n = Self::NODES;
        let h = (phi_max - phi0) / (n - 1) as f64;
        let mut lnu = Vec::with_capacity(n);
        let mut dlnu = Vec::with_capacity(n);
        for i in 0..n {
            let phi = phi0 + h * i as f64;
            let t = ((phi_max - phi) / flow.k).max(0.0);
            let u = vs - flow.velocity_canonical(-vs, t, None);
            lnu.push(u.ln());
            dlnu.push(1.0 / (u * dphi(u)));
        }
        InverseGuide {
            phi0,
            h,
            inv_h: 1.0 / h,
            lnu,
            dlnu,
            small,
        }
    }

    /// Estimate of ln u at potential Φ.
    #[inline]
    pub fn ln_u(&self, phi: f64) -> f64 {
        if !(phi >= self.phi0) {
            return phi + self.small * phi.exp();
        }
        let x = (phi - self.phi0) * self.inv_h;
        let i = (x as usize).min(self.lnu.len() - 2);
        let tt = x - i as f64;
        let (y0, y1) = (self.lnu[i], self.lnu[i + 1]);
        let (m0, m1) = (self.dlnu[i] * self.h, self.dlnu[i + 1] * self.h);
        let t2 = tt * tt;
        let t3 = t2 * tt;
        (2.0 * t3 - 3.0 * t2 + 1.0) * y0
            + (t3 - 2.0 * t2 + tt) * m0
            + (-2.0 * t3 + 3.0 * t2) * y1
            + (t3 - t2) * m1
    }
}

impl fmt::Display for DragLaw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DragLaw {
    type Err = crate::Error;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "tan" => Ok(DragLaw::Tan),
            "tanh" => Ok(DragLaw::Tanh),
            "linear" => Ok(DragLaw::Linear),
            _ => Err(crate::Error::invalid("drag", s, "one of tan, tanh, linear")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_finite_difference() {
        for d in DragLaw::ALL {
            for &v in &[-0.9, -0.3, 0.0, 0.2, 0.7] {
                let h = 1e-6;
                let fd = (d.force(v + h) - d.force(v - h)) / (2.0 * h);
                assert!((fd - d.derivative(v)).abs() < 1e-8, "{d} at {v}");
            }
        }
    }

    #[test]
    fn inverse_is_inverse() {
        for d in DragLaw::ALL {
            for &f in &[-0.9, -0.1, 0.0, 0.4, 0.95] {
                assert!((d.force(d.inverse(f)) - f).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn max_derivative_bounds_derivative_on_interval() {
        for (d, sigma) in [
            (DragLaw::Tan, 3.0),
            (DragLaw::Tanh, 0.6),
            (DragLaw::Linear, 2.0),
        ] {
            let vu = d.inverse(sigma);
            let m = d.max_derivative(sigma);
            for i in 0..=100 {
                let v = -vu + 2.0 * vu * i as f64 / 100.0;
                assert!(d.derivative(v) <= m * (1.0 + 1e-12));
            }
        }
    }
}
