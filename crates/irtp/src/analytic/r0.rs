//! Exact stationary velocity density without resetting (r = 0), its moments,
//! CDF and the paper's regime classification (Sec. 3, Eqs. (34), (35)).
//!
//! # Derivation (from the generator of the simulated process)
//! L f(v, ±) = (±Σ - g) ∂_v f(v, ±) + λ [f(v, ∓) - f(v, ±)]; its adjoint gives
//! 0 = -∂_v[(Σ - g) P₊] + λ (P₋ - P₊),   0 = -∂_v[(-Σ - g) P₋] + λ (P₊ - P₋).
//! With P = P₊ + P₋ and D = P₊ - P₋:
//! - sum: the probability flux J = (Σ - g)P₊ + (-Σ - g)P₋ = ΣD - gP is constant,
//!   and no flux through the edges v_l, v_u gives J = 0, i.e. D = g P / Σ;
//! - difference: ∂_v[ΣP - gD] = -2λ D, i.e. ∂_v[(Σ² - g²) P] = -2λ g P.
//!
//! Hence P_s(v) ∝ 1/(Σ² - g²) · exp(-2λ ∫₀^v g/(Σ² - g²) dv') for every drag
//! law, and P± = P (1 ± g/Σ)/2. Near the edges Σ - g(v) ≈ g'(v_u)(v_u - |v|),
//! so P ~ (v_u - |v|)^a with a = c - 1, c = λ / g'(v_u).
//!
//! For a law with g' = 1 + κ g² ([`Drag::riccati`]) the substitution t = g(v),
//! dv = dt/(1 + κt²), makes the integral elementary (partial fractions):
//! P ∝ (Σ² - t²)^{c-1} (1 + κt²)^{-c} with c = λ/(1 + κΣ²):
//! - tan  (κ = 1):  P ∝ (Σ² - t²)^{c-1} (1 + t²)^{-c},  c = λ/(1+Σ²);
//! - tanh (κ = -1): P ∝ (Σ² - t²)^{c-1} (1 - t²)^{-c},  c = λ/(1-Σ²);
//! - linear (κ = 0): P ∝ (Σ² - v²)^{λ-1} (a symmetric Beta law, c = λ).
//!
//! These coincide with the paper's Eq. (34) (tan) and Eq. (35) (tanh; its
//! absolute value is immaterial since both factors are positive inside the
//! interval): the paper's r = 0 closed forms are correct for the simulated process
//! (tested in `tests/analytic.rs`, also against an independent simulation of the
//! process). The drift-sign slip of the paper's Sec. 2.2 does not enter: its FP
//! Eqs. (11)-(12) carry ∂_v[(g ∓ Σ)P±] = -∂_v[(±Σ - g)P±], as derived here.
//! Paper Fig. 2a: tan, Σ = 3, λ = 0.9 gives a = -0.91. Linear drag:
//! <v²> = Σ²/(1 + 2λ), as [`crate::analytic::linear::v2`] at r = 0.
//! Any other law: the exponent is integrated numerically with its logarithmic
//! edge singularity split off exactly (`r0_exponent`).
//!
//! Extrema: d ln P/dv = 2g (g' - λ)/(Σ² - g²), so the interior extrema are v = 0
//! and the solutions of g'(v) = λ.
//!
//! # Numerics
//! The density is evaluated through w = v_u - |v| (distance to the edge) using
//! cancellation-free forms of Σ - g(v_u - w) near the edge (the addition
//! theorem of tan/tanh, or the law's [`Drag::edge_drift`]), so it keeps full
//! relative precision at distances far below the spacing of doubles near v_u;
//! in the bulk (w > v_u/2) ln(1 - g²/Σ²) via ln_1p keeps huge exponents c
//! accurate. The half-interval w ∈ (0, v_u] is integrated in u = w^m,
//! m = min(c, 1): for c < 1 (divergent edges) the integrand becomes
//! (1/c) (v_u - |v|)^{-a} P, bounded and smooth up to u^{1/c} terms, so the
//! mass hidden within 10⁻²⁰ of the edge is captured. Globally adaptive
//! Gauss–Kronrod (G7/K15) panels are kept, so the CDF is a table look-up plus
//! one 15-point rule (~1 µs).

use super::r0_exponent::EdgeIntegral;
use crate::error::{Error, Result};
use crate::model::reset::Solver;
use crate::model::{Drag, DragLaw, Params};
use crate::numerics::quad::{self, Panels};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Relative tolerance of the normalisation and moment quadratures.
const REL_TOL: f64 = 1e-14;
/// Tails P(V > v_u - w) with w below this fraction of v_u are integrated afresh
/// with a relative tolerance (see [`R0Density::edge_mass`]).
const EDGE_FRACTION: f64 = 0.01;
/// Above this edge exponent c the r = 0 density of a Riccati law is
/// evaluated in its cancellation-free form ([`R0Density::stable_ln_unnorm`]);
/// below, the paper's form, whose rounding c·1e-16·|ln q| is harmless.
const STABLE_FORM_C: f64 = 1e4;
/// Panel budget of the adaptive quadrature.
const MAX_PANELS: usize = 20_000;
/// Solutions of g'(v) = λ on (0, v_u) are bracketed on this many grid
/// intervals, then bisected (a generic law; Riccati laws solve it exactly).
const ROOT_GRID: usize = 4096;

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

    /// One word (the serialised name).
    pub fn short(self) -> &'static str {
        match self {
            EdgeBehaviour::Diverges => "diverges",
            EdgeBehaviour::Finite => "finite",
            EdgeBehaviour::Cusp => "cusp",
            EdgeBehaviour::Linear => "linear",
            EdgeBehaviour::Smooth => "smooth",
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
    /// "i".."iv" (tan), "a".."d" (tanh); linear: "i", "uniform", "iii", "iv";
    /// any other law: `edge/centre/n` from the shape (e.g. `diverges/minimum/0`).
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

/// g'(v_u): 1 + κΣ² for a Riccati law (exactly, from Sigma alone), else
/// the law's derivative at v_u = g⁻¹(Σ).
fn edge_slope(drag: DragLaw, sigma: f64) -> f64 {
    match drag.riccati() {
        Some(kappa) => {
            let d = 1.0 + kappa * sigma * sigma;
            if kappa < 0.0 && d < 1e-3 {
                // Σ → 1/√|κ| (tanh: Σ → 1): 1 - |κ|Σ² carries the rounding
                // of Σ² relative to d; (1 - √|κ|Σ)(1 + √|κ|Σ) does not.
                let r = (-kappa).sqrt() * sigma;
                (1.0 - r) * (1.0 + r)
            } else {
                d
            }
        }
        None => drag.derivative(drag.inverse(sigma)),
    }
}

/// Kind of the extremum at v = 0: d ln P/dv has the sign of g'(v) - λ just
/// right of 0, that is of g'(0) - λ, or at equality of g'' near 0 (the
/// first grid point where g'(v) ≠ λ). None where g' = λ throughout (the
/// uniform linear density).
fn centre_kind(drag: DragLaw, vu: f64, lambda: f64) -> Option<ExtremumKind> {
    let f = |v: f64| drag.derivative(v) - lambda;
    let f0 = f(0.0);
    let sign = if f0 != 0.0 {
        f0
    } else {
        (1..=ROOT_GRID)
            .map(|i| f(vu * i as f64 / ROOT_GRID as f64))
            .find(|x| *x != 0.0)?
    };
    Some(if sign > 0.0 {
        ExtremumKind::Minimum
    } else {
        ExtremumKind::Maximum
    })
}

/// The off-centre extrema on (0, v_u): solutions of g'(v) = λ where g' - λ
/// changes sign (- to +: P turns up, a minimum). Riccati law: g' = λ means
/// g = √((λ-1)/κ), one solution when λ lies strictly between g'(0) = 1 and
/// g'(v_u). Other laws: sign changes on a grid, bisected to the last bit.
fn off_centre_extrema(drag: DragLaw, sigma: f64, vu: f64, lambda: f64) -> Vec<Extremum> {
    if let Some(kappa) = drag.riccati() {
        let gp = edge_slope(drag.clone(), sigma);
        if lambda > gp.min(1.0) && lambda < gp.max(1.0) {
            let kind = if kappa > 0.0 {
                ExtremumKind::Minimum
            } else {
                ExtremumKind::Maximum
            };
            let v = drag.inverse(((lambda - 1.0) / kappa).sqrt());
            return vec![Extremum { v, kind }];
        }
        return Vec::new();
    }
    numeric_extrema(drag, vu, lambda)
}

/// The off-centre extrema of any law: sign changes of g'(v) - λ on a grid
/// of [0, v_u], each bisected to adjacent doubles.
fn numeric_extrema(drag: DragLaw, vu: f64, lambda: f64) -> Vec<Extremum> {
    let f = |v: f64| drag.derivative(v) - lambda;
    let grid = (0..=ROOT_GRID).map(|i| {
        let v = vu * i as f64 / ROOT_GRID as f64;
        (v, f(v))
    });
    let mut out = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    for (v, fv) in grid.filter(|p| p.1 != 0.0 && p.1.is_finite()) {
        if let Some((pv, pf)) = prev {
            if (pf < 0.0) != (fv < 0.0) {
                let kind = if pf < 0.0 {
                    ExtremumKind::Minimum
                } else {
                    ExtremumKind::Maximum
                };
                out.push(Extremum {
                    v: bisect(&f, pv, v),
                    kind,
                });
            }
        }
        prev = Some((v, fv));
    }
    out
}

/// A root of f bracketed by [lo, hi] (f(lo), f(hi) of opposite signs), to
/// adjacent doubles.
fn bisect(f: &dyn Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let neg_lo = f(lo) < 0.0;
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return mid;
        }
        let fm = f(mid);
        if fm == 0.0 {
            return mid;
        }
        if (fm < 0.0) == neg_lo {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// Label of a law without its own labels ([`Drag::regime_label`]): built
/// from the shape, `edge/centre/n` (e.g. `diverges/minimum/2`: divergent
/// edges, a minimum at v = 0, two off-centre extrema), and the λ range as
/// the comparison with g'(0) and g'(v_u).
fn shape_label(
    drag: DragLaw,
    sigma: f64,
    lambda: f64,
    edge: EdgeBehaviour,
    extrema: &[Extremum],
) -> (String, String) {
    let centre = match extrema.iter().find(|e| e.v == 0.0).map(|e| e.kind) {
        Some(ExtremumKind::Minimum) => "minimum",
        Some(ExtremumKind::Maximum) => "maximum",
        None => "flat",
    };
    let off = extrema.iter().filter(|e| e.v != 0.0).count();
    let label = format!("{}/{centre}/{off}", edge.short());
    let range = format!(
        "lambda = {lambda}, g'(0) = {}, g'(v_u) = {}",
        drag.derivative(0.0),
        edge_slope(drag, sigma)
    );
    (label, range)
}

/// Classify the r = 0 density. Boundary values of λ go to the regime whose
/// description still holds; the description is always computed from the density.
/// Laws with their own labels ([`Drag::regime_label`]: tan, tanh, linear) keep
/// them; any other law is labelled by its shape, `edge/centre/n` (e.g.
/// `diverges/minimum/2`: divergent edges, a minimum at v = 0, two
/// off-centre extrema).
///
/// Corrections to the paper (verified in `tests/analytic.rs`):
/// - tanh (b): the maxima sit at v = ±atanh(√(1-λ)), not ±atanh(1-λ), and v = 0
///   is only a local minimum (P → 0 at the edges since a > 0 there);
/// - tanh (b) and (c) overlap as printed; (c) is 1 ≤ λ ≤ 2(1-Σ²), empty when
///   Σ² > 1/2, and for Σ² > 1/2, 2(1-Σ²) < λ < 1 the density has two maxima
///   *and* zero-slope edges: labelled (b), edge "smooth";
/// - tan (ii)/(iii) at λ = 1+Σ²: a = 0, monotone with a finite edge value.
pub fn regime(drag: DragLaw, sigma: f64, lambda: f64) -> Regime {
    let a = lambda / edge_slope(drag.clone(), sigma) - 1.0;
    let edge = EdgeBehaviour::from_exponent(a);
    let vu = drag.inverse(sigma);
    let mut extrema = Vec::new();
    if let Some(kind) = centre_kind(drag.clone(), vu, lambda) {
        let off = off_centre_extrema(drag.clone(), sigma, vu, lambda);
        extrema.extend(off.iter().rev().map(|e| Extremum { v: -e.v, ..*e }));
        extrema.push(Extremum { v: 0.0, kind });
        extrema.extend(off);
    }
    let (label, range) = match drag.regime_label(sigma, lambda) {
        Some((label, range)) => (label.to_string(), range),
        None => shape_label(drag.clone(), sigma, lambda, edge, &extrema),
    };
    let description = format!(
        "({label}) {drag} drag, {range}: {}; P {} (a = {a:.6}, v_u = {vu:.6})",
        describe_shape(&extrema),
        edge.describe()
    );
    Regime {
        label,
        description,
        edge_exponent: a,
        edge,
        extrema,
    }
}

/// The extrema in words (v ≥ 0; the density is even).
fn describe_shape(extrema: &[Extremum]) -> String {
    if extrema.is_empty() {
        return "uniform on the interval".to_string();
    }
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
}

/// The paper's unnormalised r = 0 density exactly as printed, Eq. (34) (tan)
/// and Eq. (35) (tanh, with its absolute value), written for any Riccati
/// law g' = 1 + κg² as ((Σ² - g²)/(1 + κg²))^c / (Σ² - g²), c = λ/(1 + κΣ²)
/// (linear drag: the Beta law (Σ² - v²)^{λ-1}, which the paper does not
/// print). Zero outside the open velocity interval; NaN for a law without a
/// Riccati form. Kept for the record and for tests.
pub fn paper_formula(drag: DragLaw, sigma: f64, lambda: f64, v: f64) -> f64 {
    let vu = drag.inverse(sigma);
    if !(v.abs() < vu) {
        return if v.is_nan() { f64::NAN } else { 0.0 };
    }
    let Some(kappa) = drag.riccati() else {
        return f64::NAN;
    };
    let s2 = sigma * sigma;
    let t2 = drag.force(v).powi(2);
    ((s2 - t2) / (1.0 + kappa * t2))
        .abs()
        .powf(lambda / (1.0 + kappa * s2))
        / (s2 - t2)
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

/// How ln P is evaluated.
#[derive(Clone, Debug)]
enum Form {
    /// g' = 1 + κg²: P ∝ s^a q^{-c}, s = 1 - g²/Σ², q = 1 + κg².
    Riccati(f64),
    /// Any other law: ln P = -ln s + c ln(w/v_u) + λ Q(w) + shift, with
    /// Q tabulated (`r0_exponent`) and shift = -λ Q(v_u), so P(0) = 1.
    Tabulated {
        table: Arc<EdgeIntegral>,
        shift: f64,
        ln_vu: f64,
    },
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
    /// Closed form or tabulated exponent.
    form: Form,
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

/// ((Σ - g(v_u - w))/w, g(v_u - w)) for g' = 1 + κg² from the addition
/// theorem of g = tan(√κ v)/√κ: with C = cos(√κ w), S = sin(√κ w)/√κ
/// (cosh and sinh for κ < 0), g(v_u - w) = (Σ C - S)/(C + κΣS) and
/// Σ - g(v_u - w) = (1 + κΣ²) S/(C + κΣS); κ = 0: (1, Σ - w).
fn riccati_edge(kappa: f64, s: f64, w: f64) -> (f64, f64) {
    if kappa == 0.0 {
        return (1.0, s - w);
    }
    let r = kappa.abs().sqrt();
    let x = r * w;
    let (sn_over_x, sn, cs) = if kappa > 0.0 {
        let (sn, cs) = x.sin_cos();
        (sinc(x), sn, cs)
    } else {
        (sinhc(x), x.sinh(), x.cosh())
    };
    let big_s = sn / r;
    let den = cs + kappa * s * big_s;
    (
        sn_over_x * (1.0 + kappa * s * s) / den,
        (s * cs - big_s) / den,
    )
}

/// ln q = ln(1 + κg²) (= ln g'(v)) of a Riccati law.
#[inline]
fn ln_q(kappa: f64, g: f64) -> f64 {
    (kappa * g * g).ln_1p()
}

/// Panel boundaries in u = w^p for w ∈ [0, w_top]: n uniform steps in w plus
/// w_top/n · 2^{-k}, k = 1..40, mapped to u. Mapping from w matters for tiny p
/// (λ ≪ g'(v_u)), where all of w ≳ 1e-300 is squeezed into a sliver of width
/// ~p next to u_top that a partition uniform in u would never sample.
pub(super) fn breakpoints(w_top: f64, n: usize, p: f64) -> Vec<f64> {
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
    /// the velocity piles up at the edges and no density exists). Closed form
    /// for a Riccati law ([`Drag::riccati`]), tabulated exponent otherwise.
    pub fn new(drag: DragLaw, sigma: f64, lambda: f64) -> Result<Self> {
        Self::build(drag.clone(), sigma, lambda, drag.riccati())
    }

    /// [`R0Density::new`] by the quadrature of a law without closed form,
    /// whatever the law (for tests of that path against the closed forms).
    #[doc(hidden)]
    pub fn by_quadrature(drag: DragLaw, sigma: f64, lambda: f64) -> Result<Self> {
        Self::build(drag, sigma, lambda, None)
    }

    fn build(drag: DragLaw, sigma: f64, lambda: f64, kappa: Option<f64>) -> Result<Self> {
        Params::new(drag.clone(), sigma, lambda, 0.0, 0.0)?;
        if !(lambda > 0.0) {
            return Err(Error::invalid(
                "lambda",
                lambda,
                "lambda > 0 (at lambda = 0 there is no stationary density)",
            ));
        }
        let vu = drag.inverse(sigma);
        let (c, form) = match kappa {
            Some(kappa) => (
                lambda / edge_slope(drag.clone(), sigma),
                Form::Riccati(kappa),
            ),
            None => Self::quadrature_form(drag.clone(), sigma, lambda, vu)?,
        };
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
            form,
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
        d.normalise()?;
        Ok(d)
    }

    /// c = λ/g'(v_u) and the tabulated exponent of a law without closed form.
    fn quadrature_form(drag: DragLaw, sigma: f64, lambda: f64, vu: f64) -> Result<(f64, Form)> {
        let k = drag.derivative(vu);
        if !(k > 0.0 && k.is_finite() && vu > 0.0 && vu.is_finite()) {
            return Err(Error::Numerical {
                method: "r0 density exponent",
                reason: format!(
                    "g'(v_u) = {k} at v_u = {vu}: the edge exponent needs 0 < g'(v_u) < inf"
                ),
            });
        }
        let table = crate::with_drag!(drag, |d| EdgeIntegral::build(d, sigma, lambda, vu, k))
            .ok_or_else(|| Error::Numerical {
                method: "r0 density exponent",
                reason: "the integrand of the exponent is not finite or too rough to tabulate"
                    .into(),
            })?;
        let c = lambda / k;
        let shift = -lambda * table.total();
        let ln_vu = vu.ln();
        Ok((
            c,
            Form::Tabulated {
                table: Arc::new(table),
                shift,
                ln_vu,
            },
        ))
    }

    /// Normalise on adaptive panels in u, keep the cumulative masses and <v²>.
    fn normalise(&mut self) -> Result<()> {
        // Initial partition: uniform in w, fine enough to see a peak of width
        // ~ 1/√λ at v = 0, plus geometric points toward the edge.
        let n0 = (16.0 * self.lambda.sqrt().max(1.0)).min(4096.0) as usize;
        let start = breakpoints(self.vu, n0, self.m);
        let g = |u: f64| self.integrand(u);
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
        self.panels = panels;
        self.cum = cum;
        self.half = half;
        self.ln_norm = (2.0 * half).ln();
        self.v2 = self.moment_checked(2)?;
        Ok(())
    }

    /// From validated parameters; requires rate = 0.
    pub fn from_params(p: &Params) -> Result<Self> {
        p.require(Solver::ClosedForm)?;
        if let Some(t) = p.schedule().periodic {
            return Err(Error::invalid(
                "reset_period",
                t.period,
                "none (the closed-form density exists only without resetting)",
            ));
        }
        if p.rate() != 0.0 {
            return Err(Error::invalid(
                "rate",
                p.rate(),
                "0 (the closed-form density exists only without resetting; with linear drag the \
                 moments at any r)",
            ));
        }
        Self::new(p.drag(), p.sigma(), p.lambda())
    }

    /// Near-edge terms of a Riccati law at v = v_u - w: (ln(s/w), ln q) with
    /// s = 1 - g²/Σ² and q = 1 + κg². Uses Σ - g(v_u - w) = w·(D/w) from exact
    /// identities in Σ and w, so there is no cancellation at the edge.
    fn edge_terms(&self, kappa: f64, w: f64) -> (f64, f64) {
        let s = self.sigma;
        let (d_over_w, g) = riccati_edge(kappa, s, w);
        let dd = w * d_over_w;
        let s_over_w = d_over_w * (2.0 * s - dd) / (s * s);
        (s_over_w.ln(), ln_q(kappa, g))
    }

    /// (Σ - g(v_u - w))/w without cancellation.
    fn drift_over_w(&self, w: f64) -> f64 {
        match self.form {
            Form::Riccati(kappa) => riccati_edge(kappa, self.sigma, w).0,
            Form::Tabulated { .. } => self.drag.edge_drift(self.sigma, w) / w,
        }
    }

    /// Bulk terms of a Riccati law (ln s, ln q) from g(v) directly:
    /// ln s = ln(1 - g²/Σ²) via ln_1p keeps c·ln s accurate when c = λ/g'(v_u)
    /// is huge.
    fn bulk_terms(&self, kappa: f64, w: f64) -> (f64, f64) {
        let g = self.drag.force(self.vu - w);
        let r = g / self.sigma;
        ((-r * r).ln_1p(), ln_q(kappa, g))
    }

    /// ln P (unnormalised, 0 at v = 0) of a Riccati law whose exponent
    /// c = λ/D, D = 1 + κΣ², is huge (tanh with Σ → 1). The paper's form
    /// a ln s - c ln q subtracts two terms of size c·|ln q|, whose rounding
    /// alone (c·1e-16·|ln q|) swamps ln P. Exactly, a ln s - c ln q =
    /// c ln(s/q) - ln s with s/q = 1 - y, y = g²D/(Σ²q), so where y < 1/2
    /// ln P = (λ/D) ln_1p(-y) - ln s, free of cancellation (→ -λg²/(Σ²q) as
    /// D → 0); closer to the edge (q ~ D, where P is already negligible)
    /// ln(s/q) = ln s - ln q is accurate. ln q = -2 ln cosh(√|κ| v) for κ < 0
    /// (no cancellation in 1 - |κ|g²).
    fn stable_ln_unnorm(&self, kappa: f64, w: f64) -> f64 {
        let v = self.vu - w;
        let (s2, d) = (
            self.sigma * self.sigma,
            edge_slope(self.drag.clone(), self.sigma),
        );
        let g = self.drag.force(v);
        let lq = if kappa < 0.0 {
            let x = ((-kappa).sqrt() * v).abs();
            -2.0 * (x + (-2.0 * x).exp().ln_1p() - std::f64::consts::LN_2)
        } else {
            ln_q(kappa, g)
        };
        let ls = if self.in_bulk(w) {
            (-g * g / s2).ln_1p()
        } else {
            self.edge_terms(kappa, w).0 + w.ln()
        };
        let y = g * g * d / (s2 * lq.exp());
        let ln_ratio = if y < 0.5 { (-y).ln_1p() } else { ls - lq };
        self.c * ln_ratio - ls
    }

    /// The bulk formulas are used for w > v_u/2, the edge identities below.
    fn in_bulk(&self, w: f64) -> bool {
        w > 0.5 * self.vu
    }

    /// A law without closed form: (ln(s/w), λ Q(w) + shift), from the law's
    /// cancellation-free edge drift D = Σ - g(v_u - w): s = D (2Σ - D)/Σ².
    fn tabulated_terms(&self, table: &EdgeIntegral, shift: f64, w: f64) -> (f64, f64) {
        let s = self.sigma;
        let dd = self.drag.edge_drift(s, w);
        let s_over_w = (dd / w) * (2.0 * s - dd) / (s * s);
        (s_over_w.ln(), self.lambda * table.eval(w) + shift)
    }

    /// ln φ(w) with φ = P_unnorm / w^a (= (s/w)^a q^{-c} for a Riccati law).
    fn ln_phi(&self, w: f64) -> f64 {
        match &self.form {
            Form::Riccati(kappa) if self.c > STABLE_FORM_C => {
                self.stable_ln_unnorm(*kappa, w) - self.a * w.ln()
            }
            Form::Riccati(kappa) if self.in_bulk(w) => {
                let (ls, lq) = self.bulk_terms(*kappa, w);
                self.a * (ls - w.ln()) - self.c * lq
            }
            Form::Riccati(kappa) => {
                let (lsw, lq) = self.edge_terms(*kappa, w);
                self.a * lsw - self.c * lq
            }
            Form::Tabulated {
                table,
                shift,
                ln_vu,
            } => {
                let (lsw, e) = self.tabulated_terms(table, *shift, w);
                e - lsw - self.c * ln_vu
            }
        }
    }

    /// ln of the unnormalised density (= 1 at v = 0) at distance w from the
    /// edge.
    fn ln_unnorm(&self, w: f64) -> f64 {
        match &self.form {
            Form::Riccati(kappa) if self.c > STABLE_FORM_C => self.stable_ln_unnorm(*kappa, w),
            Form::Riccati(kappa) if self.in_bulk(w) => {
                let (ls, lq) = self.bulk_terms(*kappa, w);
                self.a * ls - self.c * lq
            }
            Form::Riccati(kappa) => {
                let (lsw, lq) = self.edge_terms(*kappa, w);
                if self.a == 0.0 {
                    -self.c * lq
                } else {
                    self.a * (lsw + w.ln()) - self.c * lq
                }
            }
            Form::Tabulated { table, shift, .. } => {
                let (lsw, e) = self.tabulated_terms(table, *shift, w);
                e - (lsw + w.ln()) + self.c * (w / self.vu).ln()
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
        let d = w * self.drift_over_w(w);
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
        regime(self.drag.clone(), self.sigma, self.lambda)
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
        self.drag.clone()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's parameter sets and extremes (tiny and huge c).
    const CASES: [(DragLaw, f64, f64); 9] = [
        (DragLaw::Tan, 3.0, 0.5),
        (DragLaw::Tan, 3.0, 7.0),
        (DragLaw::Tan, 3.0, 25.0),
        (DragLaw::Tan, 0.5, 300.0),
        (DragLaw::Tanh, 0.6, 0.85),
        (DragLaw::Tanh, 0.6, 3.0),
        (DragLaw::Tanh, 0.95, 0.02),
        (DragLaw::Linear, 1.3, 0.3),
        (DragLaw::Linear, 1.0, 2.5),
    ];

    /// Relative difference (0 when equal, e.g. both underflowed to 0).
    fn rel(a: f64, b: f64) -> f64 {
        if a == b {
            0.0
        } else {
            ((a - b) / b).abs()
        }
    }

    /// The quadrature path of a generic law reproduces the closed forms of
    /// tan, tanh and linear: moments, density (down to w = 1e-15 from the
    /// edge), CDF and state densities. Tolerances: the tabulated exponent is
    /// resolved to ~1e-15 per piece and the normalisation to 1e-14, so 1e-11
    /// relative leaves room for the c-fold amplification at λ = 300.
    #[test]
    fn quadrature_matches_closed_forms() {
        for (drag, s, l) in CASES {
            let exact = R0Density::new(drag.clone(), s, l).unwrap();
            let quad = R0Density::by_quadrature(drag.clone(), s, l).unwrap();
            assert!(matches!(quad.form, Form::Tabulated { .. }));
            assert!(rel(quad.v2(), exact.v2()) < 1e-12, "{drag} {s} {l} v2");
            assert!(
                rel(quad.moment(4), exact.moment(4)) < 1e-12,
                "{drag} {s} {l} v4"
            );
            let vu = exact.bounds().1;
            for w in [1e-15, 1e-9, 1e-3 * vu, 0.3 * vu, 0.7 * vu, vu] {
                let (pe, pq) = (exact.pdf_at_edge_distance(w), quad.pdf_at_edge_distance(w));
                assert!(rel(pq, pe) < 1e-11, "{drag} {s} {l} w={w}: {pq} vs {pe}");
                let v = vu - w;
                assert!((quad.cdf(-v) - exact.cdf(-v)).abs() < 1e-13, "{drag} cdf");
                let (a, b) = (quad.state_pdf(v), exact.state_pdf(v));
                assert!(rel(a.1, b.1) < 1e-11, "{drag} {s} {l} w={w} minority");
            }
            assert!(rel(quad.edge_mass(1e-6 * vu), exact.edge_mass(1e-6 * vu)) < 1e-11);
        }
    }

    /// Grid + bisection finds the closed-form solutions of g'(v) = λ.
    #[test]
    fn numeric_extrema_match_riccati_roots() {
        for (drag, s, l) in [
            (DragLaw::Tan, 3.0, 7.0),
            (DragLaw::Tan, 3.0, 1.0001),
            (DragLaw::Tanh, 0.6, 0.85),
            (DragLaw::Tanh, 0.8, 0.8),
        ] {
            let vu = drag.inverse(s);
            let closed = off_centre_extrema(drag.clone(), s, vu, l);
            let numeric = numeric_extrema(drag.clone(), vu, l);
            assert_eq!(closed.len(), 1);
            assert_eq!(numeric.len(), 1);
            assert_eq!(numeric[0].kind, closed[0].kind, "{drag} {s} {l}");
            assert!((numeric[0].v - closed[0].v).abs() < 1e-14, "{drag} {s} {l}");
        }
        // No solution outside (1, g'(v_u)), none for linear drag.
        let vu = 3f64.atan();
        assert!(numeric_extrema(DragLaw::Tan, vu, 0.5).is_empty());
        assert!(numeric_extrema(DragLaw::Tan, vu, 12.0).is_empty());
        assert!(numeric_extrema(DragLaw::Linear, 1.0, 1.0).is_empty());
    }

    /// Cubic g = v + v³/3: g' = 1 + v² = λ at v = √(λ-1), a minimum; the
    /// generic label names the shape.
    #[test]
    fn cubic_regime_from_the_shape() {
        let r = regime(DragLaw::Cubic, 3.0, 2.0);
        assert_eq!(r.label, "diverges/maximum/2");
        assert_eq!(r.extrema.len(), 3);
        assert!((r.extrema[2].v - 1.0).abs() < 1e-15);
        assert_eq!(r.extrema[2].kind, ExtremumKind::Minimum);
        let r = regime(DragLaw::Cubic, 3.0, 0.5);
        assert_eq!(r.label, "diverges/minimum/0");
        let vu = DragLaw::Cubic.inverse(3.0);
        let r = regime(DragLaw::Cubic, 3.0, 3.0 * (1.0 + vu * vu));
        assert_eq!(r.label, "smooth/maximum/0");
        assert!(paper_formula(DragLaw::Cubic, 3.0, 1.0, 0.1).is_nan());
    }
}
