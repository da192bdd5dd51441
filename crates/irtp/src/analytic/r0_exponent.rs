//! The exponent of the r = 0 density of a law given only by g and g'
//! (no Riccati closed form), tabulated once per (Sigma, lambda).
//!
//! With 2g/(Σ² - g²) = 1/(Σ - g) - 1/(Σ + g), at distance w = v_u - v from
//! the edge, D(w) = Σ - g(v_u - w) (the law's cancellation-free
//! [`Drag::edge_drift`]) and k = g'(v_u), D ~ k w as w → 0, so
//!
//! -2λ ∫₀^v g/(Σ² - g²) dv' = c ln(w/v_u) + λ [Q(w) - Q(v_u)],  c = λ/k,
//!
//! Q(w) = ∫₀^w ρ,  ρ(w) = 1/D - 1/(k w) - 1/(2Σ - D):
//! the logarithmic edge singularity is split off exactly and ρ is bounded
//! and smooth (ρ(0+) = g''(v_u)/(2k²) - 1/(2Σ)). ρ is fitted by piecewise
//! Chebyshev series (dyadic pieces towards w = 0, adaptive pieces elsewhere)
//! and integrated exactly; below w_min = 1e-9 v_u, Q is linear. As in
//! [`crate::model::drag::TabulatedFlow`], the cancellation in 1/D - 1/(k w) costs
//! about 1e-16/(k w) absolute in ρ, i.e. 1e-16/k in Q per dyadic piece.

use crate::model::Drag;
use crate::numerics::chebyshev::{self, clenshaw, Piece, NC};

/// Largest number of pieces (a law this rough is rejected).
const MAX_PIECES: usize = 4096;

/// Q(w) on piecewise Chebyshev series (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct EdgeIntegral {
    /// Piece boundaries, increasing: w_min, ..., v_u.
    bounds: Vec<f64>,
    /// Per piece: antiderivative series of ρ, zero at the left end.
    anti: Vec<[f64; NC]>,
    /// Q at each piece's left end.
    offset: Vec<f64>,
    /// ρ(w_min): Q(w) = ρ(w_min) w below w_min.
    slope_min: f64,
    /// Q(v_u).
    total: f64,
}

impl EdgeIntegral {
    /// Tabulate Q for `drag` at noise amplitude `sigma` (v_u = g⁻¹(Σ),
    /// k = g'(v_u) > 0), resolving λ Q to about 1e-15 per piece. None if ρ is
    /// not finite or too rough to tabulate.
    pub(crate) fn build<D: Drag>(
        drag: &D,
        sigma: f64,
        lambda: f64,
        vu: f64,
        k: f64,
    ) -> Option<Self> {
        let rho = |w: f64| {
            let d = drag.edge_drift(sigma, w);
            [1.0 / d - 1.0 / (k * w) - 1.0 / (2.0 * sigma - d)]
        };
        Self::from_rho(&rho, lambda, vu)
    }

    /// Tabulate Q(w) = ∫₀^w ρ for w ∈ [0, `top`] for any bounded, smooth ρ
    /// on (0, top], resolving `scale` Q to about 1e-15 per piece (the
    /// symmetric density's ρ above with scale λ; the asymmetric
    /// telegraph's, [`crate::analytic::telegraph_r0`], with its rates inside ρ and
    /// scale 1). None if ρ is not finite or too rough to tabulate.
    pub(crate) fn from_rho(rho: &dyn Fn(f64) -> [f64; 1], lambda: f64, vu: f64) -> Option<Self> {
        let w_min = 1e-9 * vu;
        // Resolved when the truncation error of λ Q over the piece is below
        // 1e-15, absolute or relative to the piece's contribution.
        let resolved = |f: &chebyshev::Fit<1>, pa: f64, pb: f64| {
            let err = lambda * f.tail[0] * (pb - pa);
            f.finite && err <= 1e-15 * (lambda * f.scale[0] * (pb - pa)).max(1.0)
        };
        let range = (w_min, 0.5 * vu);
        let pieces =
            chebyshev::fit_towards_zero(rho, range, &[vu], &resolved, 1e-12 * vu, MAX_PIECES)
                .ok()?;
        let slope_min = clenshaw(&pieces[0].fit.series[0], -1.0);
        let mut t = EdgeIntegral {
            bounds: vec![w_min],
            anti: Vec::with_capacity(pieces.len()),
            offset: Vec::with_capacity(pieces.len()),
            slope_min,
            total: 0.0,
        };
        let mut acc = slope_min * w_min;
        for Piece { b, fit: f, .. } in pieces {
            t.bounds.push(b);
            t.offset.push(acc);
            acc += clenshaw(&f.anti[0], 1.0);
            t.anti.push(f.anti[0]);
        }
        t.total = acc;
        acc.is_finite().then_some(t)
    }

    /// Q(w) for 0 ≤ w ≤ v_u.
    pub(crate) fn eval(&self, w: f64) -> f64 {
        if w < self.bounds[0] {
            return self.slope_min * w;
        }
        let n = self.anti.len();
        let p = self.bounds[1..n].partition_point(|&b| b <= w);
        let x = chebyshev::to_unit(w, self.bounds[p], self.bounds[p + 1]);
        self.offset[p] + clenshaw(&self.anti[p], x)
    }

    /// Q(v_u).
    pub(crate) fn total(&self) -> f64 {
        self.total
    }
}
