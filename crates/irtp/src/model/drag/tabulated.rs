//! The flow of a law that gives only g and g': tabulated once per noise
//! value, then exact to about 1e-14 at the cost of a few polynomial sums.
//!
//! In the canonical frame (s ≥ 0, u = v* - v ≥ 0) the flow potential is
//! Φ(u) = ln u + R(u), t(va → vb) = (Φ(ua) - Φ(ub)) / k with k = g'(v*), and
//! R'(u) = k / (s - g(v* - u)) - 1/u is bounded and smooth (the approach to
//! v* is exponential, so the log singularity is all of Φ's). R' is fitted by
//! piecewise Chebyshev series on [u_min, 2 v*] (dyadic pieces towards 0,
//! adaptive pieces elsewhere, a break at v = 0 where g may be non-smooth) and
//! integrated exactly; below u_min = 1e-9 v*, R is linear. A velocity solve
//! is a safeguarded Newton iteration in δ = ln(u/ua) on
//! δ + R(ua e^δ) - R(ua) + k t = 0, whose slope 1 + u R'(u) = u k / drift lies
//! in (0, ∞). [`FlowMap::accelerated`] tabulates the inverse of Φ (Newton
//! starting points good to ~1e-11), so a solve costs two table evaluations
//! (R at the start, one Newton step); without it, from the linearised or
//! asymptotic start, about five.
//! Velocities outside [-|v*|, |v*|] (never reached when |s| = Sigma) fall
//! back to the trait's quadrature.

use super::closed::InverseGuide;
use super::{quadrature_time, quadrature_velocity, reachable, Drag, FlowMap};
use crate::numerics::chebyshev::{self, clenshaw, clenshaw2, Piece, NC};
use crate::numerics::root;
use std::sync::Arc;

/// Largest number of pieces (a law this rough is rejected).
const MAX_PIECES: usize = 4096;

/// R(u) and R'(u) on piecewise Chebyshev series.
#[derive(Debug)]
struct Table {
    /// Piece boundaries, increasing: u_min, ..., 2 v*.
    bounds: Vec<f64>,
    /// Per piece: the R antiderivative and R' series, interleaved
    /// (`[j] = [anti_j, slope_j]`) to be summed in one Clenshaw pass.
    coef: Vec<[[f64; 2]; NC]>,
    /// R at each piece's left end.
    offset: Vec<f64>,
    /// R'(u_min): R(u) = R'(u_min) u below u_min.
    slope_min: f64,
    /// max |R| over the table (bracket for the velocity solve).
    r_max: f64,
}

impl Table {
    fn build<D: Drag>(drag: &D, s: f64, vs: f64, k: f64) -> Option<Table> {
        let r1 = |u: f64| [k / drag.drift_at_distance(s, u) - 1.0 / u];
        let u_min = 1e-9 * vs;
        // Resolved when the series' truncation error, integrated over the
        // piece, is below 1e-15 absolute in R.
        let resolved = |f: &chebyshev::Fit<1>, pa: f64, pb: f64| {
            f.finite && f.tail[0] * (pb - pa) <= 1e-15 * f.scale[0].max(1.0)
        };
        let range = (u_min, 0.5 * vs);
        let pieces = chebyshev::fit_towards_zero(
            &r1,
            range,
            &[vs, 2.0 * vs],
            &resolved,
            1e-12 * vs,
            MAX_PIECES,
        )
        .ok()?;
        let slope_min = clenshaw(&pieces[0].fit.series[0], -1.0);
        let mut t = Table {
            bounds: vec![u_min],
            coef: Vec::with_capacity(pieces.len()),
            offset: Vec::with_capacity(pieces.len()),
            slope_min,
            r_max: (slope_min * u_min).abs(),
        };
        let mut acc = slope_min * u_min;
        for Piece { b, fit: f, .. } in pieces {
            t.bounds.push(b);
            t.offset.push(acc);
            acc += clenshaw(&f.anti[0], 1.0);
            t.r_max = t.r_max.max(acc.abs());
            let mut c = [[0.0; 2]; NC];
            for (j, cj) in c.iter_mut().enumerate() {
                *cj = [f.anti[0][j], f.series[0][j]];
            }
            t.coef.push(c);
        }
        t.r_max = t.r_max.max(acc.abs());
        Some(t)
    }

    /// (R(u), R'(u)) for 0 ≤ u ≤ 2 v*.
    #[inline]
    fn eval(&self, u: f64) -> (f64, f64) {
        if u < self.bounds[0] {
            return (self.slope_min * u, self.slope_min);
        }
        let n = self.coef.len();
        let p = self.bounds[1..n].partition_point(|&b| b <= u);
        let x = chebyshev::to_unit(u, self.bounds[p], self.bounds[p + 1]);
        let [r, r1] = clenshaw2(&self.coef[p], x);
        (self.offset[p] + r, r1)
    }

    /// The inverse of Φ(u) = ln u + R(u) as Newton starting points: ln u on
    /// a uniform Φ grid from u = 1e-6 v* to 2 v* (cubic Hermite, ~1e-11),
    /// ln u ≈ Φ - R'(0) e^Φ below. None if a node does not converge.
    fn guide(&self, vs: f64) -> Option<InverseGuide> {
        const NODES: usize = 2048;
        let phi = |u: f64| u.ln() + self.eval(u).0;
        let phi0 = phi(1e-6 * vs);
        let h = (phi(2.0 * vs) - phi0) / (NODES - 1) as f64;
        let mut lnu = Vec::with_capacity(NODES);
        let mut dlnu = Vec::with_capacity(NODES);
        let mut w = (1e-6 * vs).ln();
        for i in 0..NODES {
            let target = phi0 + h * i as f64;
            // G(w) = w + R(e^w) - Φ increases; |R| ≤ r_max brackets the root.
            let g = |w: f64| {
                let u = w.exp();
                let (r, r1) = self.eval(u);
                (w + r - target, 1.0 + u * r1, 0.0)
            };
            let span = self.r_max + 1.0;
            w = root::solve_increasing(&g, target - span, target + span, w, 0.0, 1e-10).ok()?;
            let u = w.exp();
            lnu.push(w);
            dlnu.push(1.0 / (1.0 + u * self.eval(u).1));
        }
        Some(InverseGuide::from_nodes(
            phi0,
            h,
            lnu,
            dlnu,
            -self.slope_min,
        ))
    }
}

/// The flow of a law without closed forms (see the module docs).
#[derive(Clone, Debug)]
pub struct TabulatedFlow<D> {
    drag: D,
    /// The signed noise value.
    s: f64,
    /// +1, or -1 when s < 0 was reflected.
    refl: f64,
    /// Canonical fixed point g⁻¹(|s|) > 0.
    vs: f64,
    /// g'(v*).
    k: f64,
    /// ln of a quarter ulp of v*: below it v* - v rounds to 0.
    tiny_w: f64,
    /// None when s = 0 or the law is too rough to tabulate: every call then
    /// uses the trait's quadrature.
    table: Option<Arc<Table>>,
    /// Tabulated inverse potential (Newton starting points), once built by
    /// [`FlowMap::accelerated`].
    guide: Option<Arc<InverseGuide>>,
}

impl<D: Drag> TabulatedFlow<D> {
    /// Tabulate the flow of `drag` with noise value `s`.
    pub fn new(drag: D, s: f64) -> Self {
        let a = s.abs();
        let vs = drag.inverse(a);
        let k = drag.derivative(vs);
        let usable = vs > 0.0 && vs.is_finite() && k > 0.0 && k.is_finite();
        let table = if usable {
            Table::build(&drag, a, vs, k).map(Arc::new)
        } else {
            None
        };
        TabulatedFlow {
            drag,
            s,
            refl: if s < 0.0 { -1.0 } else { 1.0 },
            vs,
            k,
            tiny_w: (vs * f64::EPSILON * 0.25).max(1e-300).ln(),
            table,
            guide: None,
        }
    }

    /// The table, if v (canonical distance u) lies on it.
    #[inline]
    fn on_table(&self, u: f64) -> Option<&Table> {
        self.table
            .as_deref()
            .filter(|_| u >= 0.0 && u <= 2.0 * self.vs)
    }

    /// Velocity in the canonical frame from distance ua ∈ (0, 2 v*]: Newton
    /// on F(δ) (module docs) inside a rigorous bracket, from the guide's
    /// estimate (error ~1e-11, so one step) or, without guide or for very
    /// short times, the linearised or asymptotic solution.
    fn velocity_canonical(&self, tb: &Table, v0: f64, ua: f64, t: f64) -> f64 {
        let kt = self.k * t;
        let (r_a, r1_a) = tb.eval(ua);
        let wa = ua.ln();
        // F(δ) = δ + R(ua e^δ) - R(ua) + k t, increasing; F(0) = k t > 0 and
        // F(lo) < 0 since |R| ≤ r_max.
        let f = |dl: f64| {
            let u = ua * dl.exp();
            let (r, r1) = tb.eval(u);
            (dl + (r - r_a) + kt, 1.0 + u * r1, 0.0)
        };
        let mut lo = -kt - 2.0 * tb.r_max - 1.0;
        if lo + wa < self.tiny_w {
            if f(self.tiny_w - wa).0 >= 0.0 {
                return self.vs; // the answer is within rounding of v*
            }
            lo = self.tiny_w - wa;
        }
        let guess = match self.guide.as_deref() {
            Some(g) if kt >= 1e-5 => g.ln_u(wa + r_a - kt) - wa,
            _ if kt < 0.5 => -kt / (1.0 + ua * r1_a),
            _ => r_a - kt,
        };
        // Newton steps: one below 1e-10 leaves ~1e-20 by quadratic
        // convergence. Failure (non-finite input) is NaN, never a guess.
        let dl = root::solve_increasing(&f, lo, 0.0, guess.min(0.0), 0.0, 1e-10);
        dl.map_or(f64::NAN, |dl| {
            if kt < 0.5 {
                v0 - ua * dl.exp_m1()
            } else {
                self.vs - ua * dl.exp()
            }
        })
    }
}

impl<D: Drag> FlowMap for TabulatedFlow<D> {
    fn fixed_point(&self) -> f64 {
        self.refl * self.vs
    }

    fn rate(&self) -> f64 {
        self.k
    }

    fn time(&self, va: f64, vb: f64) -> f64 {
        let (ca, cb) = (self.refl * va, self.refl * vb);
        let (ua, ub) = (self.vs - ca, self.vs - cb);
        if vb == va {
            return 0.0;
        }
        if !reachable(ua, ub) {
            return f64::INFINITY;
        }
        match (self.on_table(ua), self.on_table(ub)) {
            (Some(tb), Some(_)) => {
                let (ra, rb) = (tb.eval(ua).0, tb.eval(ub).0);
                (((cb - ca) / ub).ln_1p() + ra - rb) / self.k
            }
            _ => quadrature_time(&self.drag, self.s, va, vb),
        }
    }

    fn potential(&self, v: f64) -> f64 {
        let u = self.vs - self.refl * v;
        match self.on_table(u) {
            Some(tb) => u.ln() + tb.eval(u).0,
            // Off the table: Φ(v) = Φ(v_ref) + k t(v → v_ref), v_ref = ∓v*
            // the table's far end, reached from v (below v*) in time t.
            None if u > 2.0 * self.vs && self.table.is_some() => {
                let v_far = -self.refl * self.vs;
                self.potential(v_far) + self.k * quadrature_time(&self.drag, self.s, v, v_far)
            }
            None => f64::NAN,
        }
    }

    fn potential_at_distance(&self, u: f64) -> f64 {
        match self.on_table(u) {
            Some(tb) => u.ln() + tb.eval(u).0,
            None => self.potential(self.fixed_point() - self.refl * u),
        }
    }

    /// Builds the tabulated inverse potential (Newton starting points).
    fn accelerated(mut self) -> Self {
        if self.guide.is_none() {
            if let Some(tb) = self.table.as_deref() {
                self.guide = tb.guide(self.vs).map(Arc::new);
            }
        }
        self
    }

    fn velocity(&self, v0: f64, t: f64) -> f64 {
        let c0 = self.refl * v0;
        let ua = self.vs - c0;
        if !(t > 0.0) || ua == 0.0 {
            return v0;
        }
        match self.on_table(ua) {
            Some(tb) => self.refl * self.velocity_canonical(tb, c0, ua, t),
            None => quadrature_velocity(&self.drag, self.s, v0, t),
        }
    }
}
