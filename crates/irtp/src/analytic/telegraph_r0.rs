//! The r = 0 stationary velocity density for two-state (asymmetric)
//! telegraph noise, levels +P and -M, leaving +P at rate k₊ and -M at rate
//! k₋, and any drag law, by quadrature (Bena 2006, "Dichotomous Markov
//! noise: exact results for out-of-equilibrium systems",
//! cond-mat/0606116; docs/equations.md, (N8)).
//!
//! # Derivation (from the generator)
//! With f₊ = P - g(v) and f₋ = -M - g(v), the stationary forward equations
//! of L f(v, ±) = f_± ∂_v f + k_± [f(v, ∓) - f(v, ±)] are
//! 0 = -∂_v(f₊ p₊) - k₊ p₊ + k₋ p₋ and 0 = -∂_v(f₋ p₋) + k₊ p₊ - k₋ p₋.
//! Their sum says the flux J = f₊ p₊ + f₋ p₋ is constant, and 0 at the
//! edges v_l = g⁻¹(-M), v_u = g⁻¹(P) (nothing leaves the interval), so
//! u := f₊ p₊ = -f₋ p₋. The first equation then reads
//! u' = -(k₊/f₊ + k₋/f₋) u, and p = p₊ + p₋ = u (1/f₊ - 1/f₋):
//!
//! ```text
//! p(v) ∝ 1 / (f₊ |f₋|) · exp(-∫_{v_c}^v [k₊/f₊ + k₋/f₋] dv'),   p₊ = p |f₋|/(P + M),  p₋ = p f₊/(P + M).
//! ```
//!
//! Symmetric (P = M = Σ, k± = λ): k/f₊ + k/f₋ = -2λg/(Σ² - g²), the
//! paper's density ([`super::r0`], Eqs. (34)-(35)). Near v_u, f₊ ≈
//! g'(v_u)(v_u - v), so p ~ (v_u - v)^{c₊ - 1}, c₊ = k₊/g'(v_u); near v_l,
//! p ~ (v - v_l)^{c₋ - 1}, c₋ = k₋/g'(v_l).
//!
//! # Numerics
//! The interval is split at v_c (0 when inside, where a law with static
//! friction jumps; else the midpoint). On each half, with w the distance to
//! its edge and D(w) > 0 the drift towards the edge (the law's
//! cancellation-free [`Drag::drift_at_distance`]), the exponent's
//! logarithmic singularity is split off exactly as in [`super::r0`]:
//! ∫ = c ln(W/w) + Q(W) - Q(w), Q = ∫₀^w ρ, ρ = k_e/D - k_e/(k w) - k_o/(P + M - D)
//! bounded and smooth, tabulated by the same piecewise Chebyshev fit
//! (`r0_exponent`). Each half is integrated by adaptive Gauss-Kronrod in
//! u = w^m, m = min(c, 1), which removes a divergent edge's singularity.

use super::r0::breakpoints;
use super::r0_exponent::EdgeIntegral;
use crate::error::{Error, Result};
use crate::model::noise::{Noise, NoiseKind, NoiseModel, Telegraph};
use crate::model::{Drag, DragLaw};
use crate::numerics::quad::{self, Panels};

/// Relative tolerance of the quadratures.
const REL_TOL: f64 = 1e-13;
/// Panel budget of each adaptive quadrature.
const MAX_PANELS: usize = 20_000;
/// Tolerance of the invariants checked after normalising (mass in the +
/// state and `<g(v)>` against their exact values).
const CHECK_TOL: f64 = 1e-10;

/// One half of the interval, parametrised by the distance w ∈ (0, W] from
/// its edge.
#[derive(Clone, Debug)]
struct Half {
    drag: DragLaw,
    /// The level whose fixed point is this edge (P or -M).
    level: f64,
    /// +1 for the upper half (v = edge - w), -1 for the lower (v = edge + w).
    sign: f64,
    edge: f64,
    width: f64,
    /// P + M.
    gap: f64,
    /// c = k_e/g'(edge), m = min(c, 1).
    c: f64,
    m: f64,
    table: EdgeIntegral,
    /// ln of the unnormalised density's constant: -c ln W - Q(W).
    shift: f64,
    panels: Panels,
}

impl Half {
    fn new(
        drag: DragLaw,
        level: f64,
        sign: f64,
        rates: (f64, f64),
        gap: f64,
        vc: f64,
    ) -> Result<Self> {
        let edge = drag.inverse(level);
        let width = (edge - vc).abs();
        let k = drag.derivative(edge);
        if !(k > 0.0 && k.is_finite() && width > 0.0 && width.is_finite()) {
            return Err(Error::Numerical {
                method: "telegraph r0 density",
                reason: format!(
                    "g'({edge}) = {k}, half width {width}: the edge exponent needs 0 < g' < inf"
                ),
            });
        }
        let (ke, ko) = rates;
        let drift = |w: f64| sign * drag.drift_at_distance(level, sign * w);
        let rho = |w: f64| {
            let d = drift(w);
            [ke / d - ke / (k * w) - ko / (gap - d)]
        };
        let table = EdgeIntegral::from_rho(&rho, 1.0, width).ok_or_else(|| Error::Numerical {
            method: "telegraph r0 density",
            reason: "the integrand of the exponent is not finite or too rough to tabulate".into(),
        })?;
        let c = ke / k;
        let shift = -c * width.ln() - table.total();
        let empty = Panels {
            edges: vec![],
            values: vec![],
            error: 0.0,
        };
        let mut h = Half {
            drag,
            level,
            sign,
            edge,
            width,
            gap,
            c,
            m: c.min(1.0),
            table,
            shift,
            panels: empty,
        };
        let n0 = (16.0 * ke.max(ko).sqrt().max(1.0)).min(4096.0) as usize;
        let start = breakpoints(width, n0, h.m);
        h.panels = h.integrate(&|_| 1.0, &start)?;
        Ok(h)
    }

    /// D(w) > 0, the drift towards the edge at distance w.
    fn drift(&self, w: f64) -> f64 {
        self.sign * self.drag.drift_at_distance(self.level, self.sign * w)
    }

    /// ln φ(w) = ln p(w) - (c - 1) ln w (unnormalised), bounded as w → 0.
    fn ln_phi(&self, w: f64) -> f64 {
        let d = self.drift(w);
        -(d / w).ln() - (self.gap - d).ln() + self.shift + self.table.eval(w)
    }

    /// ln p(w), unnormalised (the same constant on both halves: the
    /// exponent's reference point is v_c).
    fn ln_p(&self, w: f64) -> f64 {
        self.ln_phi(w) + (self.c - 1.0) * w.ln()
    }

    fn velocity(&self, w: f64) -> f64 {
        self.edge - self.sign * w
    }

    fn w_of_u(&self, u: f64) -> f64 {
        if self.m < 1.0 {
            u.powf(1.0 / self.m)
        } else {
            u
        }
    }

    /// ∫ h(v) p(v) dv over the half (unnormalised), in u = w^m.
    fn integrate(&self, h: &dyn Fn(f64) -> f64, start: &[f64]) -> Result<Panels> {
        let f = |u: f64| {
            let w = self.w_of_u(u);
            let density = if self.m < 1.0 {
                self.ln_phi(w).exp() / self.c
            } else {
                self.ln_p(w).exp()
            };
            density * h(self.velocity(w))
        };
        let rough: f64 = start
            .windows(2)
            .map(|x| quad::gk15(&f, x[0], x[1]).kronrod.abs())
            .sum();
        let tol = REL_TOL * rough.max(f64::MIN_POSITIVE);
        quad::adaptive(&f, start, tol, MAX_PANELS)
            .map_err(|e| Error::from(e.in_method("telegraph r0 density")))
    }

    /// (p₊, p₋) / p at distance w: the edge's own state carries |f_other| / (P + M).
    fn state_shares(&self, w: f64) -> (f64, f64) {
        let d = self.drift(w);
        let (own, other) = ((self.gap - d) / self.gap, d / self.gap);
        if self.sign > 0.0 {
            (own, other)
        } else {
            (other, own)
        }
    }
}

/// The normalised r = 0 stationary density of telegraph noise with any drag.
#[derive(Clone, Debug)]
pub struct TelegraphR0Density {
    noise: Telegraph,
    lower: Half,
    upper: Half,
    /// ln of the total unnormalised mass.
    ln_norm: f64,
    mass: f64,
}

impl TelegraphR0Density {
    /// Build, normalise and check: the + state's mass against π₊ =
    /// k₋/(k₊ + k₋) and `<g(v)>` against `<a>` = π₊ P - π₋ M (the
    /// stationary mean of L v = a_η - g(v)), both to 1e-10. The levels are
    /// checked against the drag ([`NoiseModel::check_drag`], errors name
    /// `noise`).
    pub fn new(drag: DragLaw, noise: Telegraph) -> Result<Self> {
        NoiseModel::new(NoiseKind::Telegraph(noise), 0.0)?.check_drag(&drag)?;
        let (p, m, kp, km) = noise.values();
        let (vl, vu) = (drag.inverse(-m), drag.inverse(p));
        let vc = if vl < 0.0 && vu > 0.0 {
            0.0
        } else {
            0.5 * (vl + vu)
        };
        let gap = p + m;
        let upper = Half::new(drag.clone(), p, 1.0, (kp, km), gap, vc)?;
        let lower = Half::new(drag, -m, -1.0, (km, kp), gap, vc)?;
        let mass = upper.panels.total() + lower.panels.total();
        let err = upper.panels.error + lower.panels.error;
        if !(mass > 0.0 && mass.is_finite() && err <= 1e-11 * mass) {
            return Err(Error::Numerical {
                method: "telegraph r0 density normalisation",
                reason: format!("the integral is {mass} (error bound {err})"),
            });
        }
        let d = TelegraphR0Density {
            noise,
            lower,
            upper,
            ln_norm: mass.ln(),
            mass,
        };
        d.check()?;
        Ok(d)
    }

    fn check(&self) -> Result<()> {
        let pi = self.noise.stationary()?;
        let (p, m, _, _) = self.noise.values();
        let plus = self.expect_split(&|_| 1.0)?.0;
        let drag = &self.upper.drag.clone();
        let mean_g = self.expect(&|v| drag.force(v))?;
        let mean_a = pi[0] * p - pi[1] * m;
        let scale = p.abs().max(m.abs());
        if (plus - pi[0]).abs() <= CHECK_TOL && (mean_g - mean_a).abs() <= CHECK_TOL * scale {
            return Ok(());
        }
        Err(Error::Numerical {
            method: "telegraph r0 density",
            reason: format!(
                "mass in + is {plus} (exact {}), <g> = {mean_g} (exact {mean_a})",
                pi[0]
            ),
        })
    }

    /// E[h(v)] under the density.
    pub fn expect(&self, h: &dyn Fn(f64) -> f64) -> Result<f64> {
        let (a, b) = self.expect_split(h)?;
        Ok(a + b)
    }

    /// (E[h(v) 1{+}], E[h(v) 1{-}]).
    /// The stationary mass in each state (+, -): (π₊, π₋) of Eq. (N2) to
    /// quadrature accuracy (Eq. (N8)).
    pub fn state_mass(&self) -> Result<(f64, f64)> {
        self.expect_split(&|_| 1.0)
    }

    fn expect_split(&self, h: &dyn Fn(f64) -> f64) -> Result<(f64, f64)> {
        let mut out = (0.0, 0.0);
        for half in [&self.lower, &self.upper] {
            let (plus, minus) = (
                |v: f64| h(v) * half.state_shares(half.sign * (half.edge - v)).0,
                |v: f64| h(v) * half.state_shares(half.sign * (half.edge - v)).1,
            );
            out.0 += half.integrate(&plus, &half.panels.edges)?.total() / self.mass;
            out.1 += half.integrate(&minus, &half.panels.edges)?.total() / self.mass;
        }
        Ok(out)
    }

    /// `<v^k>`.
    pub fn moment(&self, k: i32) -> Result<f64> {
        self.expect(&|v| v.powi(k))
    }

    /// The normalised density p(v); 0 outside (v_l, v_u).
    pub fn pdf(&self, v: f64) -> f64 {
        let (vl, vu) = self.bounds();
        if v.is_nan() {
            return f64::NAN;
        }
        if !(v > vl && v < vu) {
            return 0.0;
        }
        let half = self.half_of(v);
        (half.ln_p(half.sign * (half.edge - v)) - self.ln_norm).exp()
    }

    /// (p₊, p₋), p₊ = p |f₋|/(P + M), p₋ = p f₊/(P + M).
    pub fn state_pdf(&self, v: f64) -> (f64, f64) {
        let p = self.pdf(v);
        if !(p > 0.0) {
            return (0.0, 0.0);
        }
        let half = self.half_of(v);
        let (a, b) = half.state_shares(half.sign * (half.edge - v));
        (p * a, p * b)
    }

    fn half_of(&self, v: f64) -> &Half {
        if v >= self.upper.edge - self.upper.width {
            &self.upper
        } else {
            &self.lower
        }
    }

    /// (v_l, v_u) = (g⁻¹(-M), g⁻¹(P)).
    pub fn bounds(&self) -> (f64, f64) {
        (self.lower.edge, self.upper.edge)
    }

    /// The edge exponents (a₋, a₊) in p ~ (v - v_l)^{a₋}, (v_u - v)^{a₊}:
    /// a = k/g'(edge) - 1 with the rate of leaving that edge's level.
    pub fn edge_exponents(&self) -> (f64, f64) {
        (self.lower.c - 1.0, self.upper.c - 1.0)
    }

    /// The noise.
    pub fn noise(&self) -> Telegraph {
        self.noise
    }
}
