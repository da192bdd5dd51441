//! The closed-form flow of a law whose flow time has an elementary
//! antiderivative (tan, tanh, linear): [`ClosedForm`] gives the law's
//! formulas in a canonical frame, [`ClosedFlow`] does the rest.
//!
//! Every law is odd, so s < 0 is mapped to s > 0 by v → -v; in the
//! canonical frame s ≥ 0, v* = g⁻¹(s) and u = v* - v.

use super::{reachable, Drag, FlowMap};
use std::sync::Arc;

/// Constants of one canonical flow (s ≥ 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Canonical {
    /// |s|.
    pub s: f64,
    /// Canonical fixed point g⁻¹(|s|).
    pub vs: f64,
    /// g'(v*).
    pub k: f64,
    /// ln of a quarter ulp of v*: below it v* - v rounds to 0.
    pub tiny_w: f64,
}

/// One velocity solve in the canonical frame: start v0 at distance
/// ua = v* - v0 (sign sg, size a, ln a = wa), time t with k t = kt.
#[derive(Clone, Copy, Debug)]
pub struct Solve {
    /// Start velocity.
    pub v0: f64,
    /// Flow time.
    pub t: f64,
    /// v* - v0.
    pub ua: f64,
    /// sign of ua.
    pub sg: f64,
    /// |ua|.
    pub a: f64,
    /// ln |ua|.
    pub wa: f64,
    /// g'(v*) t.
    pub kt: f64,
    /// Short segment (kt < 1/2): the cancellation-free form is used.
    pub precise: bool,
}

impl Solve {
    /// The velocity from the solution δ = ln|u/ua|: short segments return
    /// v0 - (u - ua) (full accuracy in v for any t), others v* - u (full
    /// relative accuracy in v* - v down to ulp(v*)).
    #[inline]
    pub fn finish(&self, vs: f64, dl: f64) -> f64 {
        if self.precise {
            self.v0 - self.sg * self.a * dl.exp_m1()
        } else {
            vs - self.sg * self.a * dl.exp()
        }
    }
}

/// A law's flow in closed form, in the canonical frame (s ≥ 0).
pub trait ClosedForm: Drag {
    /// g'(v*) at v* = g⁻¹(s), s ≥ 0.
    fn fixed_point_rate(&self, s: f64) -> f64;
    /// Flow time from distance ua to ub (ub reached from ua, d = vb - va ≠ 0).
    fn time_canonical(&self, c: &Canonical, ua: f64, ub: f64, d: f64) -> f64;
    /// Flow potential Φ(u), t = (Φ(ua) - Φ(ub)) / g'(v*).
    fn potential_canonical(&self, c: &Canonical, u: f64) -> f64;
    /// dΦ/du for u > 0 (builds the [`InverseGuide`]).
    fn potential_slope(&self, c: &Canonical, u: f64) -> f64;
    /// c with ln u ≈ Φ + c e^Φ for small u > 0.
    fn small_u_coefficient(&self, c: &Canonical) -> f64;
    /// The velocity after time t (t > 0, ua ≠ 0), optionally started from the
    /// tabulated inverse potential.
    fn velocity_canonical(&self, c: &Canonical, q: &Solve, guide: Option<&InverseGuide>) -> f64;
}

/// The exact flow of a [`ClosedForm`] law for one noise value s.
#[derive(Clone, Debug)]
pub struct ClosedFlow<L> {
    law: L,
    /// +1, or -1 when s < 0 was reflected.
    refl: f64,
    c: Canonical,
    /// Tabulated inverse potential (Newton starting points), once built.
    guide: Option<Arc<InverseGuide>>,
}

impl<L: ClosedForm> ClosedFlow<L> {
    /// Flow of `law` with noise value `s`.
    pub fn new(law: L, s: f64) -> Self {
        let a = s.abs();
        let vs = law.inverse(a);
        let k = law.fixed_point_rate(a);
        ClosedFlow {
            refl: if s < 0.0 { -1.0 } else { 1.0 },
            c: Canonical {
                s: a,
                vs,
                k,
                tiny_w: (vs * f64::EPSILON * 0.25).max(1e-300).ln(),
            },
            law,
            guide: None,
        }
    }

    /// Velocity in the canonical frame, with or without the guide.
    fn velocity_in_frame(&self, v0: f64, t: f64, guide: Option<&InverseGuide>) -> f64 {
        let c = &self.c;
        let ua = c.vs - v0;
        if !(t > 0.0) || ua == 0.0 {
            return v0;
        }
        let a = ua.abs();
        let kt = c.k * t;
        let q = Solve {
            v0,
            t,
            ua,
            sg: ua.signum(),
            a,
            wa: a.ln(),
            kt,
            precise: kt < 0.5,
        };
        self.law.velocity_canonical(c, &q, guide)
    }
}

impl<L: ClosedForm> FlowMap for ClosedFlow<L> {
    fn fixed_point(&self) -> f64 {
        self.refl * self.c.vs
    }

    fn rate(&self) -> f64 {
        self.c.k
    }

    #[inline]
    fn time(&self, va: f64, vb: f64) -> f64 {
        let (va, vb) = (self.refl * va, self.refl * vb);
        let (ua, ub) = (self.c.vs - va, self.c.vs - vb);
        if vb == va {
            return 0.0;
        }
        if !reachable(ua, ub) {
            return f64::INFINITY;
        }
        self.law.time_canonical(&self.c, ua, ub, vb - va)
    }

    #[inline]
    fn potential(&self, v: f64) -> f64 {
        self.law
            .potential_canonical(&self.c, self.c.vs - self.refl * v)
    }

    #[inline]
    fn potential_at_distance(&self, u: f64) -> f64 {
        self.law.potential_canonical(&self.c, u)
    }

    #[inline]
    fn velocity(&self, v0: f64, t: f64) -> f64 {
        let v0r = self.refl * v0;
        self.refl * self.velocity_in_frame(v0r, t, self.guide.as_deref())
    }

    fn accelerated(mut self) -> Self {
        if self.guide.is_none() {
            self.guide = Some(Arc::new(InverseGuide::new(&self)));
        }
        self
    }
}

/// Tabulated inverse of the flow potential for one [`ClosedFlow`] on the
/// velocity interval (-|v*|, |v*|): ln u as a function of Φ (canonical
/// frame), by cubic Hermite interpolation on a uniform Φ grid (nodes solved
/// once with the law's iteration), and the small-u expansion
/// ln u = Φ + c e^Φ + O(u²) below it. Used only as a starting guess (error
/// ~1e-9), so a guided velocity does not depend on its accuracy.
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

    /// Build for `flow` (linear gets the exact ln u = Φ).
    pub fn new<L: ClosedForm>(flow: &ClosedFlow<L>) -> Self {
        let (c, law) = (&flow.c, &flow.law);
        let vs = c.vs;
        // Φ at the velocity v* - u, as FlowMap::potential sees it (the
        // distance v* - (v* - u) rounds like the sampler's).
        let pot = |u: f64| law.potential_canonical(c, vs - (vs - u));
        let u_far = 2.0 * vs;
        let phi_max = pot(u_far);
        let phi0 = pot(1e-3_f64.min(0.5 * u_far));
        let n = Self::NODES;
        let h = (phi_max - phi0) / (n - 1) as f64;
        let mut lnu = Vec::with_capacity(n);
        let mut dlnu = Vec::with_capacity(n);
        for i in 0..n {
            let phi = phi0 + h * i as f64;
            let t = ((phi_max - phi) / c.k).max(0.0);
            let u = vs - flow.velocity_in_frame(-vs, t, None);
            lnu.push(u.ln());
            dlnu.push(1.0 / (u * law.potential_slope(c, u)));
        }
        InverseGuide {
            phi0,
            h,
            inv_h: 1.0 / h,
            lnu,
            dlnu,
            small: law.small_u_coefficient(c),
        }
    }

    /// A guide from nodes ln u_i at Φ_i = phi0 + i h (at least two), their
    /// slopes d ln u/dΦ, and the small-u coefficient c of
    /// ln u ≈ Φ + c e^Φ below phi0 (for flows other than [`ClosedFlow`]).
    pub(crate) fn from_nodes(phi0: f64, h: f64, lnu: Vec<f64>, dlnu: Vec<f64>, small: f64) -> Self {
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
