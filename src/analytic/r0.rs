//! Exact stationary velocity density without resetting (r = 0), its moments,
//! CDF and the paper's regime classification (Sec. 3, Eqs. Neqn17, apeqn18a).
//!
//! # Derivation (from the generator of the simulated process)
//! L f(v, ±) = (±Σ - g) ∂_v f(v, ±) + λ [f(v, ∓) - f(v, ±)]; its adjoint gives
//! 0 = -∂_v[(Σ - g) P₊] + λ (P₋ - P₊),   0 = -∂_v[(-Σ - g) P₋] + λ (P₊ - P₋).
//! With P = P₊ + P₋ and D = P₊ - P₋:
//! - sum: the probability flux J = (Σ - g)P₊ + (-Σ - g)P₋ = ΣD - gP is constant,
//!   and no flux through the edges v_l, v_u gives J = 0, i.e. D = g P / Σ;
//! - difference: ∂_v[ΣP - gD] = -2λ D, i.e. ∂_v[(Σ² - g²) P] = -2λ g P.
//!
//! Hence P_s(v) ∝ 1/(Σ² - g²) · exp(-2λ ∫₀^v g/(Σ² - g²) dv'), and P± = P (1 ± g/Σ)/2.
//! With t = g(v) the integral is elementary:
//! - tan  (dv = dt/(1+t²)):  P ∝ (Σ² - t²)^{c-1} (1 + t²)^{-c},  c = λ/(1+Σ²);
//! - tanh (dv = dt/(1-t²)):  P ∝ (Σ² - t²)^{c-1} (1 - t²)^{-c},  c = λ/(1-Σ²);
//! - linear:                 P ∝ (Σ² - v²)^{λ-1} (a symmetric Beta law, c = λ).
//!
//! These coincide with the paper's Eq. Neqn17 (tan) and Eq. apeqn18a (tanh; its
//! absolute value is immaterial since both factors are positive inside the
//! interval): the paper's r = 0 closed forms are correct for the simulated process
//! (tested in `tests/analytic.rs`, also against an independent simulation of the
//! process). The drift-sign slip of the paper's Sec. 2.2 does not enter: its FP
//! Eqs. p2c4eqn11-12 carry ∂_v[(g ∓ Σ)P±] = -∂_v[(±Σ - g)P±], as derived here.
//! In all three cases c = λ / g'(v_u), and near the edges P ~ (v_u - |v|)^a with
//! a = c - 1 (paper Fig. 2a: tan, Σ = 3, λ = 0.9 gives a = -0.91). Linear drag:
//! <v²> = Σ²/(1 + 2λ), as [`crate::analytic::linear::v2`] at r = 0.
//!
//! Extrema: d ln P/dv = 2g (g' - λ)/(Σ² - g²), so the interior extrema are v = 0
//! and the solutions of g'(v) = λ.
//!
//! # Numerics
//! The density is evaluated through w = v_u - |v| (distance to the edge) using
//! exact identities for Σ - g(v_u - w) near the edge, so it keeps full relative
//! precision at distances far below the spacing of doubles near v_u; in the bulk
//! (w > v_u/2) ln(1 - g²/Σ²) via ln_1p keeps huge exponents c accurate. The
//! half-interval w ∈ (0, v_u] is integrated in u = w^m, m = min(c, 1): for c < 1
//! (divergent edges) the integrand becomes (1/c) (v_u - |v|)^{-a} P, bounded and
//! smooth up to u^{1/c} terms, so the mass hidden within 10⁻²⁰ of the edge is
//! captured. Globally adaptive Gauss–Kronrod (G7/K15) panels are kept, so the
//! CDF is a table look-up plus one 15-point rule (~1 µs).

use crate::error::{Error, Result};
use crate::model::{DragLaw, Params};
use crate::numerics::quad::{self, Panels};
use serde::{Deserialize, Serialize};

/// Relative tolerance of the normalisation and moment quadratures.
const REL_TOL: f64 = 1e-14;
/// Tails P(V > v_u - w) with w below this fraction of v_u are integrated afresh
/// with a relative tolerance (see [`R0Density::edge_mass`]).
const EDGE_FRACTION: f64 = 0.01;
/// Panel budget of the adaptive quadrature.
const MAX_PANELS: usize = 20_000;

/// Behaviour of P_s at the edges v → ±v_u, from the exponent a of (v_u - |v|)^a.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeBehaviour {
    /// a < 0: integrable divergence.
    Diverges,
    /// a = 0: finite, non-zero limit.
    Finite,
    /// 0 < a < 1: vanishes with infinite slope (cusp).
    Cusp,
    /// a = 1: vanishes linearly (finite slope).
    Linear,
    /// a > 1: vanishes with zero slope.
    Smooth,
}

impl EdgeBehaviour {
    /// Classify an edge exponent.
    pub fn from_exponent(a: f64) -> Self {
        if a < 0.0 {
            EdgeBehaviour::Diverges
        } else if a == 0.0 {
            EdgeBehaviour::Finite
        } else if a < 1.0 {
            EdgeBehaviour::Cusp
        } else if a == 1.0 {
            EdgeBehaviour::Linear
        } else {
            EdgeBehaviour::Smooth
        }
    }

    fn describe(self) -> &'static str {
        match self {
            EdgeBehaviour::Diverges => "diverges at the edges",
            EdgeBehaviour::Finite => "tends to a finite non-zero value at the edges",
            EdgeBehaviour::Cusp => "vanishes at the edges with infinite slope (cusp)",
            EdgeBehaviour::Linear => "vanishes linearly at the edges",
            EdgeBehaviour::Smooth => "vanishes at the edges with zero slope",
        }
    }
}

/// Kind of an interior extremum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExtremumKind {
    /// Local maximum.
    Maximum,
    /// Local minimum.
    Minimum,
}

/// An interior extremum of P_s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Extremum {
    /// Location.
    pub v: f64,
    /// Maximum or minimum.
    pub kind: ExtremumKind,
}

/// Shape regime of the r = 0 density (paper Sec. 3: tan (i)-(iv), tanh (a)-(d)).
///
/// Labels follow the paper's λ thresholds; the description is derived from the
/// actual density (extrema from g'(v) = λ, edge behaviour from the exponent) and
/// corrects the paper where it is wrong (see [`regime`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Regime {
    /// "i".."iv" (tan), "a".."d" (tanh); linear: "i", "uniform", "iii", "iv".
    pub label: String,
    /// One line: the λ range and the shape.
    pub description: String,
    /// a in P ~ (v_u - |v|)^a.
    pub edge_exponent: f64,
    /// Edge behaviour implied by `edge_exponent`.
    pub edge: EdgeBehaviour,
    /// Interior extrema, ascending in v (empty for the uniform linear case).
    pub extrema: Vec<Extremum>,
}

/// g'(v_u) from Sigma alone: 1 + Σ² (tan), 1 - Σ² (tanh), 1 (linear).
fn edge_slope(drag: DragLaw, sigma: f64) -> f64 {
    match drag {
        DragLaw::Tan => 1.0 + sigma * sigma,
        DragLaw::Tanh => 1.0 - sigma * sigma,
        DragLaw::Linear => 1.0,
    }
}

/// Classify the r = 0 density. Boundary values of λ go to the regime whose
/// description still holds; the description is always computed from the density.
///
/// Corrections to the paper (verified in `tests/analytic.rs`):
/// - tanh (b): the maxima sit at v = ±atanh(√(1-λ)), not ±atanh(1-λ), and v = 0
///   is only a local minimum (P → 0 at the edges since a > 0 there);
/// - tanh (b) and (c) overlap as printed; (c) is 1 ≤ λ ≤ 2(1-Σ²), empty when
///   Σ² > 1/2, and for Σ² > 1/2, 2(1-Σ²) < λ < 1 the density has two maxima
///   *and* zero-slope edges: labelled (b), edge "smooth";
/// - tan (ii)/(iii) at λ = 1+Σ²: a = 0, monotone with a finite edge value.
pub fn regime(drag: DragLaw, sigma: f64, lambda: f64) -> Regime {
    let gp = edge_slope(drag, sigma);
    let a = lambda / gp - 1.0;
    let edge = EdgeBehaviour::from_exponent(a);
    let vu = crate::model::Drag::inverse(&drag, sigma);
    // Interior solution of g'(v) = λ in (0, v_u), if any.
    let v_star = match drag {
        DragLaw::Tan if lambda > 1.0 && lambda < gp => Some((lambda - 1.0).sqrt().atan()),
        DragLaw::Tanh if lambda > gp && lambda < 1.0 => Some((1.0 - lambda).sqrt().atanh()),
        _ => None,
    };
    // Sign of d ln P/dv just right of 0 is the sign of g'(0) - λ = 1 - λ, except
    // at λ = 1 where it is the sign of g'' near 0: + (tan), - (tanh), 0 (linear).
    let centre = if lambda < 1.0 {
        Some(ExtremumKind::Minimum)
    } else if lambda > 1.0 {
        Some(ExtremumKind::Maximum)
    } else {
        match drag {
            DragLaw::Tan => Some(ExtremumKind::Minimum),
            DragLaw::Tanh => Some(ExtremumKind::Maximum),
            DragLaw::Linear => None,
        }
    };
    let mut extrema = Vec::new();
    if let Some(kind) = centre {
        extrema.push(Extremum { v: 0.0, kind });
        if let Some(vs) = v_star {
            let other = match kind {
                ExtremumKind::Minimum => ExtremumKind::Maximum,
                ExtremumKind::Maximum => ExtremumKind::Minimum,
            };
            extrema.insert(
                0,
                Extremum {
                    v: -vs,
                    kind: other,
                },
            );
            extrema.push(Extremum { v: vs, kind: other });
        }
    }
    let two = 2.0 * gp;
    let (label, range) = match drag {
        DragLaw::Tan => {
            if lambda <= 1.0 {
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
            }
        }
        DragLaw::Tanh => {
            if lambda <= gp {
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
            }
        }
        DragLaw::Linear => {
            if lambda < 1.0 {
                ("i", "lambda < 1".to_string())
            } else if lambda == 1.0 {
                ("uniform", "lambda = 1".to_string())
            } else if lambda <= 2.0 {
                ("iii", "1 < lambda <= 2".to_string())
            } else {
                ("iv", "lambda > 2".to_string())
            }
        }
    };
    let shape = if extrema.is_empty() {
        "uniform on the interval".to_string()
    } else {
        extrema
            .iter()
            .filter(|e| e.v >= 0.0)
            .map(|e| {
                let (one, two) = match e.kind {
                    ExtremumKind::Maximum => ("maximum", "maxima"),
                    ExtremumKind::Minimum => ("minimum", "minima"),
                };
                if e.v == 0.0 {
                    format!("local {one} at v = 0")
                } else {
                    format!("local {two} at v = ±{:.6}", e.v)
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let description = format!(
        "({label}) {drag} drag, {range}: {shape}; P {} (a = {a:.6}, v_u = {vu:.6})",
        edge.describe()
    );
    Regime {
        label: label.to_string(),
        description,
        edge_exponent: a,
        edge,
        extrema,
    }
}

/// The paper's unnormalised r = 0 density exactly as printed: Eq. Neqn17 (tan),
/// Eq. apeqn18a (tanh, with its absolute value); for linear drag the paper prints
/// none and this returns the Beta-law limit (Σ² - v²)^{λ-1}. Zero outside the
/// open velocity interval. Kept for the record and for tests.
pub fn paper_formula(drag: DragLaw, sigma: f64, lambda: f64, v: f64) -> f64 {
    let vu = crate::model::Drag::inverse(&drag, sigma);
    if !(v.abs() < vu) {
        return if v.is_nan() { f64::NAN } else { 0.0 };
    }
    let s2 = sigma * sigma;
    match drag {
        DragLaw::Tan => {
            let t2 = v.tan().powi(2);
            ((s2 - t2) / (1.0 + t2)).powf(lambda / (1.0 + s2)) / (s2 - t2)
        }
        DragLaw::Tanh => {
            let t2 = v.tanh().powi(2);
            ((s2 - t2) / (1.0 - t2)).abs().powf(lambda / (1.0 - s2)) / (s2 - t2)
        }
        DragLaw::Linear => (s2 - v * v).powf(lambda - 1.0),
    }
}

/// Normalisation details, for provenance and `irtp analytic --json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Normalisation {
    /// ∫ over (v_l, v_u) of the unnormalised density s^a q^{-c} (equal to 1 at v = 0).
    pub integral: f64,
    /// Pessimistic error bound Σ|K15 - G7| relative to `integral`.
    pub relative_error_bound: f64,
    /// Number of Gauss–Kronrod panels on the half-interval.
    pub panels: usize,
    /// Exponent m of the substitution u = (v_u - |v|)^m.
    pub substitution_exponent: f64,
    /// Method, in words.
    pub method: String,
}

/// Exact r = 0 stationary density P_s(v) of the simulated process.
#[derive(Clone, Debug)]
pub struct R0Density {
    drag: DragLaw,
    sigma: f64,
    lambda: f64,
    vu: f64,
    /// c = λ / g'(v_u); edge exponent a = c - 1.
    c: f64,
    a: f64,
    /// Substitution exponent m = min(c, 1).
    m: f64,
    /// Panels in u on the half-interval, u = 0 at the edge.
    panels: Panels,
    /// Cumulative unnormalised mass from the edge to each panel boundary.
    cum: Vec<f64>,
    /// ∫_0^{v_u} of the unnormalised density.
    half: f64,
    ln_norm: f64,
    v2: f64,
}

#[inline]
fn sinc(w: f64) -> f64 {
    if w.abs() < 1e-4 {
        1.0 - w * w / 6.0 * (1.0 - w * w / 20.0)
    } else {
        w.sin() / w
    }
}

#[inline]
fn sinhc(w: f64) -> f64 {
    if w.abs() < 1e-4 {
        1.0 + w * w / 6.0 * (1.0 + w * w / 20.0)
    } else {
        w.sinh() / w
    }
}

/// Panel boundaries in u = w^p for w ∈ [0, w_top]: n uniform steps in w plus
/// w_top/n · 2^{-k}, k = 1..40, mapped to u. Mapping from w matters for tiny p
/// (λ ≪ g'(v_u)), where all of w ≳ 1e-300 is squeezed into a sliver of width
/// ~p next to u_top that a partition uniform in u would never sample.
fn breakpoints(w_top: f64, n: usize, p: f64) -> Vec<f64> {
    let mut ws: Vec<f64> = (1..=n).map(|j| w_top * j as f64 / n as f64).collect();
    ws.extend((1..=40).map(|k| w_top / n as f64 * 0.5f64.powi(k)));
    ws.sort_by(f64::total_cmp);
    let mut us = vec![0.0];
    for w in ws {
        let u = if p == 1.0 { w } else { w.powf(p) };
        if u > *us.last().unwrap() {
            us.push(u);
        }
    }
    us
}

impl R0Density {
    /// Build and normalise. Sigma rules as [`Params`]; λ > 0 and finite (at λ = 0
    /// the velocity piles up at the edges and no density exists).
    pub fn new(drag: DragLaw, sigma: f64, lambda: f64) -> Result<Self> {
        Params::new(drag, sigma, lambda, 0.0, 0.0)?;
        if !(lambda > 0.0) {
            return Err(Error::invalid(
                "lambda",
                lambda,
                "lambda > 0 (at lambda = 0 there is no stationary density)",
            ));
        }
        let vu = crate::model::Drag::inverse(&drag, sigma);
        let c = lambda / edge_slope(drag, sigma);
        let a = c - 1.0;
        let m = c.min(1.0);
        let mut d = R0Density {
            drag,
            sigma,
            lambda,
            vu,
            c,
            a,
            m,
            panels: Panels {
                edges: vec![],
                values: vec![],
                error: 0.0,
            },
            cum: vec![],
            half: 0.0,
            ln_norm: 0.0,
            v2: 0.0,
        };
        // Initial partition: uniform in w, fine enough to see a peak of width
        // ~ 1/√λ at v = 0, plus geometric points toward the edge.
        let n0 = (16.0 * lambda.sqrt().max(1.0)).min(4096.0) as usize;
        let start = breakpoints(vu, n0, m);
        let g = |u: f64| d.integrand(u);
        let rough: f64 = start
            .windows(2)
            .map(|w| quad::gk15(&g, w[0], w[1]).kronrod)
            .sum();
        let panels = quad::adaptive(&g, &start, REL_TOL * rough, MAX_PANELS)
            .map_err(|f| f.in_method("r0 density normalisation"))?;
        let half = panels.total();
        if !(half > 0.0) || !half.is_finite() {
            return Err(Error::Numerical {
                method: "r0 density normalisation",
                reason: format!("the integral is {half} (error bound {})", panels.error),
            });
        }
        let mut cum = Vec::with_capacity(panels.edges.len());
        let mut acc = 0.0;
        cum.push(0.0);
        for v in &panels.values {
            acc += v;
            cum.push(acc);
        }
        d.panels = panels;
        d.cum = cum;
        d.half = half;
        d.ln_norm = (2.0 * half).ln();
        d.v2 = d.moment_checked(2)?;
        Ok(d)
    }

    /// From validated parameters; requires rate = 0.
    pub fn from_params(p: &Params) -> Result<Self> {
        if p.rate() != 0.0 {
            return Err(Error::invalid(
                "rate",
                p.rate(),
                "0 (the closed-form density exists only without resetting)",
            ));
        }
        Self::new(p.drag(), p.sigma(), p.lambda())
    }

    /// Near-edge terms at v = v_u - w: (ln(s/w), ln q) with s = 1 - g²/Σ² and
    /// q = 1 + g² (tan), 1 - g² (tanh), 1 (linear). Uses Σ - g(v_u - w) = w·(D/w)
    /// from exact identities in Σ and w, so there is no cancellation at the edge.
    fn edge_terms(&self, w: f64) -> (f64, f64) {
        let s = self.sigma;
        let (d_over_w, g) = self.edge_identities(w);
        let dd = w * d_over_w;
        let s_over_w = d_over_w * (2.0 * s - dd) / (s * s);
        (s_over_w.ln(), self.ln_q(g))
    }

    /// ((Σ - g(v_u - w))/w, g(v_u - w)) from exact identities in Σ and w.
    fn edge_identities(&self, w: f64) -> (f64, f64) {
        let s = self.sigma;
        match self.drag {
            DragLaw::Tan => {
                let (sw, cw) = w.sin_cos();
                let den = cw + s * sw;
                (sinc(w) * (1.0 + s * s) / den, (s * cw - sw) / den)
            }
            DragLaw::Tanh => {
                let (sh, ch) = (w.sinh(), w.cosh());
                let den = ch - s * sh;
                (sinhc(w) * (1.0 - s * s) / den, (s * ch - sh) / den)
            }
            DragLaw::Linear => (1.0, s - w),
        }
    }

    /// Bulk terms (ln s, ln q) from g(v) directly: ln s = ln(1 - g²/Σ²) via
    /// ln_1p keeps c·ln s accurate when c = λ/g'(v_u) is huge.
    fn bulk_terms(&self, w: f64) -> (f64, f64) {
        let g = crate::model::Drag::force(&self.drag, self.vu - w);
        let r = g / self.sigma;
        ((-r * r).ln_1p(), self.ln_q(g))
    }

    fn ln_q(&self, g: f64) -> f64 {
        match self.drag {
            DragLaw::Tan => (g * g).ln_1p(),
            DragLaw::Tanh => (-g * g).ln_1p(),
            DragLaw::Linear => 0.0,
        }
    }

    /// The bulk formulas are used for w > v_u/2, the edge identities below.
    fn in_bulk(&self, w: f64) -> bool {
        w > 0.5 * self.vu
    }

    /// ln φ(w) with φ = P_unnorm / w^a = (s/w)^a q^{-c}.
    fn ln_phi(&self, w: f64) -> f64 {
        if self.in_bulk(w) {
            let (ls, lq) = self.bulk_terms(w);
            self.a * (ls - w.ln()) - self.c * lq
        } else {
            let (lsw, lq) = self.edge_terms(w);
            self.a * lsw - self.c * lq
        }
    }

    /// ln of the unnormalised density s^a q^{-c} (= 1 at v = 0) at distance w
    /// from the edge.
    fn ln_unnorm(&self, w: f64) -> f64 {
        if self.in_bulk(w) {
            let (ls, lq) = self.bulk_terms(w);
            self.a * ls - self.c * lq
        } else {
            let (lsw, lq) = self.edge_terms(w);
            if self.a == 0.0 {
                -self.c * lq
            } else {
                self.a * (lsw + w.ln()) - self.c * lq
            }
        }
    }

    /// Integrand in u = w^m on the half-interval.
    fn integrand(&self, u: f64) -> f64 {
        if self.m < 1.0 {
            let w = u.powf(1.0 / self.m);
            self.ln_phi(w).exp() / self.c
        } else {
            self.ln_unnorm(u).exp()
        }
    }

    fn u_to_v(&self, u: f64) -> f64 {
        let w = if self.m < 1.0 {
            u.powf(1.0 / self.m)
        } else {
            u
        };
        self.vu - w
    }

    /// <v^k> by adaptive quadrature on the stored partition (0 for odd k).
    fn moment_checked(&self, k: u32) -> Result<f64> {
        if k % 2 == 1 {
            return Ok(0.0);
        }
        if k == 0 {
            return Ok(1.0);
        }
        let f = |u: f64| self.integrand(u) * self.u_to_v(u).powi(k as i32);
        let e = &self.panels.edges;
        let rough: f64 = e
            .windows(2)
            .map(|w| quad::gk15(&f, w[0], w[1]).kronrod)
            .sum();
        let p = quad::adaptive(&f, e, REL_TOL * rough, MAX_PANELS)
            .map_err(|f| f.in_method("r0 density moment"))?;
        Ok(p.total() / self.half)
    }

    /// Normalised density P_s(v); 0 outside the open interval (v_l, v_u).
    pub fn pdf(&self, v: f64) -> f64 {
        if v.is_nan() {
            return f64::NAN;
        }
        if !(v.abs() < self.vu) {
            return 0.0;
        }
        self.pdf_at_edge_distance(self.vu - v.abs())
    }

    /// Normalised density at distance w ∈ (0, v_u] from either edge, i.e. at
    /// v = ±(v_u - w); exact even for w far below the double spacing at v_u.
    pub fn pdf_at_edge_distance(&self, w: f64) -> f64 {
        if !(w > 0.0 && w <= self.vu) {
            return if w.is_nan() { f64::NAN } else { 0.0 };
        }
        (self.ln_unnorm(w) - self.ln_norm).exp()
    }

    /// State-resolved densities (P₊, P₋) with P± = P (1 ± g/Σ)/2 (zero-flux condition).
    /// The minority state near an edge (P₋ at v_u) keeps full relative accuracy.
    pub fn state_pdf(&self, v: f64) -> (f64, f64) {
        let p = self.pdf(v);
        if !(p > 0.0) {
            return (0.5 * p, 0.5 * p);
        }
        let w = self.vu - v.abs();
        // Σ - g(|v|) without cancellation near the edge.
        let d = w * self.edge_identities(w).0;
        let minority = 0.5 * p * d / self.sigma;
        let majority = p - minority;
        if v >= 0.0 {
            (majority, minority)
        } else {
            (minority, majority)
        }
    }

    /// Unnormalised mass between the edge and distance w from it (w ∈ [0, v_u]),
    /// from the table (absolute ~1e-16, ~1 µs).
    fn tail(&self, w: f64) -> f64 {
        if !(w > 0.0) {
            return 0.0;
        }
        let u = if self.m < 1.0 { w.powf(self.m) } else { w };
        let e = &self.panels.edges;
        if u >= e[e.len() - 1] {
            return self.half;
        }
        // Last boundary ≤ u.
        let i = e.partition_point(|&x| x <= u) - 1;
        let g = |x: f64| self.integrand(x);
        let part = if u > e[i] {
            quad::gk15(&g, e[i], u).kronrod
        } else {
            0.0
        };
        self.cum[i] + part
    }

    /// [`R0Density::tail`], but near the edge integrated afresh to a
    /// tolerance relative to the tail itself (slower, ~50 µs), so tiny tail
    /// masses keep their relative accuracy.
    fn tail_relative(&self, w: f64) -> Result<f64> {
        if !(w > 0.0 && w <= EDGE_FRACTION * self.vu) {
            return Ok(self.tail(w));
        }
        // Divergent edge (c < 1): in t = w^c, where the integrand (1/c)
        // φ(t^{1/c}) tends to a constant; otherwise the density is bounded:
        // directly in w.
        let (h, p): (Box<dyn Fn(f64) -> f64 + '_>, f64) = if self.c < 1.0 {
            (
                Box::new(|t: f64| self.ln_phi(t.powf(1.0 / self.c)).exp() / self.c),
                self.c,
            )
        } else {
            (Box::new(|x: f64| self.ln_unnorm(x).exp()), 1.0)
        };
        let start = breakpoints(w, 4, p);
        let rough: f64 = start
            .windows(2)
            .map(|x| quad::gk15(&h, x[0], x[1]).kronrod)
            .sum();
        let panels = quad::adaptive(&h, &start, REL_TOL * rough, 4000)
            .map_err(|f| f.in_method("r0 density edge mass"))?;
        Ok(panels.total())
    }

    /// Cumulative distribution F(v) = P(V ≤ v), accurate to ~1e-14 absolute.
    pub fn cdf(&self, v: f64) -> f64 {
        if v.is_nan() {
            return f64::NAN;
        }
        if v <= -self.vu {
            return 0.0;
        }
        if v >= self.vu {
            return 1.0;
        }
        let t = self.tail(self.vu - v.abs()) / (2.0 * self.half);
        if v < 0.0 {
            t
        } else {
            1.0 - t
        }
    }

    /// Upper tail mass P(V ≥ v_u - w) for w ∈ [0, v_u], without cancellation:
    /// ~1e-14 absolute, and ~1e-12 relative for w < 0.01 v_u, even far below
    /// the double spacing at v_u (as long as the mass itself is a normal double).
    /// Costs ~50 µs near the edge; [`R0Density::cdf`] is a ~1 µs table look-up.
    /// NaN if the quadrature fails (see [`R0Density::try_edge_mass`]).
    pub fn edge_mass(&self, w: f64) -> f64 {
        self.try_edge_mass(w).unwrap_or(f64::NAN)
    }

    /// [`R0Density::edge_mass`], or an error if the adaptive quadrature near
    /// the edge does not converge.
    pub fn try_edge_mass(&self, w: f64) -> Result<f64> {
        Ok(self.tail_relative(w.min(self.vu))? / (2.0 * self.half))
    }

    /// Probabilities of the bins [e_i, e_{i+1}) (edges ascending; clamped to the
    /// interval; outer edges should be exactly ±v_u to cover all the mass).
    /// Each edge is evaluated once, as a lower tail P(V ≤ e) for e < 0 and an
    /// upper tail P(V > e) for e ≥ 0, so no bin suffers 1 - 1 cancellation.
    pub fn bin_probabilities(&self, edges: &[f64]) -> Vec<f64> {
        let tails: Vec<f64> = edges
            .iter()
            .map(|&e| {
                if e >= self.vu {
                    0.0
                } else if e >= 0.0 {
                    self.tail(self.vu - e) / (2.0 * self.half)
                } else {
                    self.cdf(e)
                }
            })
            .collect();
        edges
            .windows(2)
            .zip(tails.windows(2))
            .map(|(e, t)| {
                let p = if e[0] >= 0.0 {
                    t[0] - t[1]
                } else if e[1] < 0.0 {
                    t[1] - t[0]
                } else {
                    1.0 - t[0] - t[1]
                };
                p.max(0.0)
            })
            .collect()
    }

    /// <v^k>; odd moments vanish by symmetry. Relative accuracy ~1e-13; NaN if
    /// the quadrature fails (see [`R0Density::try_moment`]).
    pub fn moment(&self, k: u32) -> f64 {
        self.try_moment(k).unwrap_or(f64::NAN)
    }

    /// <v^k>, or an [`Error::NotConverged`] / [`Error::NonFinite`] if the
    /// adaptive quadrature fails.
    pub fn try_moment(&self, k: u32) -> Result<f64> {
        if k == 2 {
            return Ok(self.v2);
        }
        self.moment_checked(k)
    }

    /// Stationary <v²>.
    pub fn v2(&self) -> f64 {
        self.v2
    }

    /// Regime of the density (see [`regime`]).
    pub fn regime(&self) -> Regime {
        regime(self.drag, self.sigma, self.lambda)
    }

    /// a = λ/g'(v_u) - 1 in P ~ (v_u - |v|)^a.
    pub fn edge_exponent(&self) -> f64 {
        self.a
    }

    /// (v_l, v_u).
    pub fn bounds(&self) -> (f64, f64) {
        (-self.vu, self.vu)
    }

    /// Drag law.
    pub fn drag(&self) -> DragLaw {
        self.drag
    }
    /// Sigma.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
    /// lambda.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }

    /// Normalisation details.
    pub fn normalisation(&self) -> Normalisation {
        Normalisation {
            integral: 2.0 * self.half,
            relative_error_bound: self.panels.error / self.half,
            panels: self.panels.values.len(),
            substitution_exponent: self.m,
            method:
                "adaptive Gauss-Kronrod G7/K15 in u = (v_u - |v|)^m, m = min(1, lambda/g'(v_u))"
                    .into(),
        }
    }
}
