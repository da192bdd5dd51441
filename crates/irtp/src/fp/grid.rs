//! Finite-volume meshes on (v_l, v_u) and the upwind transport rates.
//!
//! Every node stores its distances to both edges, xl = v - v_l and
//! xu = v_u - v, computed exactly from the edge it is graded towards, so that
//! cells of width 1e-100 next to a singular edge are represented without
//! cancellation, and the drifts there are evaluated from the distance
//! (see [`edge_drift`]).

use crate::error::{Error, Result};
use crate::model::reset::{NoiseAtReset, Reset};
use crate::model::{Drag, DragLaw, Params};
use crate::numerics::root;
use serde::{Deserialize, Serialize};

/// How cells are placed on (v_l, v_u).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Mesh {
    /// Equal cells (the paper's finite-difference grid, Sec. 3).
    Uniform,
    /// Cells graded algebraically towards both edges with the exponent taken
    /// from the edge singularity P ~ (v_u - v)^a, and logarithmically towards
    /// v_r at large r; v_r is a node. Where g'(0) = ∞ (g ~ |v|^n, n < 1:
    /// the power law with n < 1) v = 0 is a node too and cells are graded
    /// towards it from both sides, |v| ~ s^(1/n) (see `kink_grading`).
    ///
    /// Why: on a uniform mesh the edge cell of a singular density (a < 0)
    /// holds a finite share of the mass and its error does not shrink, so the
    /// cell masses converge like h^(1+a) (measured L1 order 0.05 for tan,
    /// Sigma = 3, lambda = 0.5) and, with v_r inside a cell, <v²> converges
    /// erratically. Grading x ~ s^q with q = 1/(1+a) makes the density smooth
    /// in the mesh parameter s: first order in L1 and in <v²>, with a clean
    /// error expansion that Richardson extrapolation turns into second order.
    /// (A change of variables would do the same; grading keeps the plain
    /// conservative upwind scheme and its Markov-chain structure.) At a kink
    /// g ~ |v|^n the state densities have a |v|^n kink: unresolved, the
    /// cells next to 0 err by O(h^n) (power n = 0.5, Sigma = 3, lambda = 1,
    /// r = 0: 1.8e-2, 1.4e-2, 1.0e-2 of the peak at N = 1000, 2000, 4000);
    /// graded, the largest error is first order (2.2e-3, 1.1e-3, 5.5e-4).
    #[default]
    Graded,
}

impl Mesh {
    /// Name as typed on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Mesh::Uniform => "uniform",
            Mesh::Graded => "graded",
        }
    }
}

/// Smallest number of cells accepted.
pub const MIN_CELLS: usize = 16;
/// Largest number of cells accepted (memory: ~100 bytes per cell).
pub const MAX_CELLS: usize = 50_000_000;

/// Width of the graded edge layer as a fraction of the half interval.
pub(crate) const LAYER: f64 = 0.2;
/// Largest grading exponent (a -> -1 would ask for q -> infinity).
pub(crate) const MAX_GRADING: f64 = 40.0;

/// Σ - g(v_u - x) for 0 ≤ x ≤ v_u, free of cancellation as x -> 0: the
/// law's [`Drag::edge_drift`].
pub(crate) fn edge_drift(drag: &DragLaw, sigma: f64, x: f64) -> f64 {
    drag.edge_drift(sigma, x)
}

/// A mesh with its upwind rates. Cell i is `[edges[i], edges[i+1]]`.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    pub edges: Vec<f64>,
    pub widths: Vec<f64>,
    pub centres: Vec<f64>,
    /// α_i: rate at which + mass leaves cell i to the right
    /// (drift at its right edge / width; 0 in the last cell: no flux).
    pub out_plus: Vec<f64>,
    /// β_i: rate at which - mass leaves cell i to the left (0 in cell 0).
    pub out_minus: Vec<f64>,
    /// Cell receiving reset (and initial) + mass.
    pub reset_plus: usize,
    /// Cell receiving reset (and initial) - mass.
    pub reset_minus: usize,
    /// Grading exponent q (1 for a uniform mesh).
    pub grading: f64,
    /// What a reset does to the noise state: the reset outflux of the two
    /// states re-enters the target cells through [`Grid::reinject`].
    pub noise: NoiseAtReset,
    /// A random target's cell masses (sum 1), where reset mass re-enters
    /// spread over the mesh; None for a point target (the cells
    /// `reset_plus`, `reset_minus`).
    pub spread: Option<Vec<f64>>,
}

impl Grid {
    pub fn cells(&self) -> usize {
        self.widths.len()
    }

    /// Reset influx into the (+, -) target cells from the reset outflux
    /// (a, b) of the (+, -) states ([`NoiseAtReset::mix`]).
    #[inline]
    pub fn reinject(&self, a: f64, b: f64) -> (f64, f64) {
        self.noise.mix(a, b)
    }

    /// Add the reset influx (ip, im) of the (+, -) states to `b`: into the
    /// target cells of a point target, spread by the target's cell masses
    /// for a random one.
    pub fn add_reset(&self, b: &mut [[f64; 2]], ip: f64, im: f64) {
        match &self.spread {
            None => {
                b[self.reset_plus][0] += ip;
                b[self.reset_minus][1] += im;
            }
            Some(q) => {
                for (c, &w) in b.iter_mut().zip(q) {
                    c[0] += ip * w;
                    c[1] += im * w;
                }
            }
        }
    }

    /// [`Grid::add_reset`] on flat interleaved cell values (m+_0, m-_0, ...).
    pub fn add_reset_flat(&self, b: &mut [f64], ip: f64, im: f64) {
        match &self.spread {
            None => {
                b[2 * self.reset_plus] += ip;
                b[2 * self.reset_minus + 1] += im;
            }
            Some(q) => {
                for (c, &w) in b.chunks_exact_mut(2).zip(q) {
                    c[0] += ip * w;
                    c[1] += im * w;
                }
            }
        }
    }

    /// Uniform mesh of `n` cells. Reset target: the cell containing v_r; if v_r
    /// is a node, + mass enters the cell to its right and - mass the cell to
    /// its left (the direction each state moves in).
    pub fn uniform(p: &Params, n: usize) -> Grid {
        let (vl, vu) = p.bounds();
        let dv = (vu - vl) / n as f64;
        let xl: Vec<f64> = (0..=n).map(|i| i as f64 * dv).collect();
        let xu: Vec<f64> = (0..=n).map(|i| (n - i) as f64 * dv).collect();
        let widths = vec![dv; n];
        let (rp, rm) = uniform_target(n, vl, vu, p.reset_velocity());
        Grid::build(p, xl, xu, widths, rp, rm, 1.0)
    }

    /// Graded mesh of `nl + nu` cells: `nl` on (v_l, v_r), `nu` on (v_r, v_u).
    /// Within each part the node distance x from the edge solves
    /// s(x) = x + (θX)^(1-1/q) x^(1/q) [+ log clustering at v_r, see `HalfMap`]
    /// = k Δs for equally spaced s, i.e. the mesh equidistributes the monitor
    /// 1 + c x^(1/q - 1): cells shrink like x ~ s^q next to the edge (layer of
    /// width θX) and are uniform inside.
    /// With q = 1/(1+a) the singular density (v_u - v)^a carries the same mass
    /// in every edge cell (it is smooth in s), so first-order upwind converges
    /// like O(1/N) with a smooth error expansion, and Richardson extrapolation
    /// over nested meshes (nl, nu) -> (2nl, 2nu) is valid.
    /// Fails if the Newton solve for a node does not converge.
    pub fn graded(p: &Params, nl: usize, nu: usize) -> Result<Grid> {
        let (vl, vu) = p.bounds();
        let vr = p.reset_velocity();
        let (lo_map, up_map) = half_maps(p);
        let low = lo_map.distances(nl)?;
        let up = up_map.distances(nu)?;
        let n = nl + nu;
        let mut xl = Vec::with_capacity(n + 1);
        let mut xu = Vec::with_capacity(n + 1);
        let mut widths = Vec::with_capacity(n);
        let total = vu - vl;
        for (k, &x) in low.iter().enumerate() {
            xl.push(x);
            xu.push(if k == nl { vu - vr } else { total - x });
        }
        for k in (0..nu).rev() {
            let x = up[k];
            xu.push(x);
            xl.push(total - x);
        }
        for k in 0..nl {
            widths.push(low[k + 1] - low[k]);
        }
        for k in (0..nu).rev() {
            widths.push(up[k + 1] - up[k]);
        }
        Ok(Grid::build(
            p,
            xl,
            xu,
            widths,
            nl,
            nl.saturating_sub(1),
            lo_map.q,
        ))
    }

    /// Graded mesh of `n << refine` cells with a node at v = 0, where
    /// g'(0) = ∞: the pieces of [`kink_pieces`] with cells in proportion to
    /// their mesh parameter (from the base count `n`, so that meshes nest),
    /// each node's distance solved from its piece's nearer end and widths
    /// taken from those distances (no cancellation next to v = 0 either).
    pub(crate) fn kinked(p: &Params, q0: f64, n: usize, refine: usize) -> Result<Grid> {
        let (vl, vu) = p.bounds();
        let vr = p.reset_velocity();
        let q = grading_exponent(p);
        let pieces = kink_pieces(p, q, q0);
        let counts = piece_counts(&pieces, n);
        let cells = n << refine;
        let (mut xl, mut xu) = (Vec::with_capacity(cells + 1), Vec::with_capacity(cells + 1));
        let mut widths = Vec::with_capacity(cells);
        let mut reset = 0;
        for (piece, &m) in pieces.iter().zip(&counts) {
            let m = m << refine;
            let (a, b) = (piece.a, piece.a + piece.len);
            if a == vr {
                reset = widths.len();
            }
            let nodes = piece.nodes(m)?;
            let skip = usize::from(!xl.is_empty());
            for &(x, y) in &nodes[skip..] {
                if x <= y {
                    xl.push((a - vl) + x);
                    xu.push((vu - a) - x);
                } else {
                    xu.push((vu - b) + y);
                    xl.push((b - vl) - y);
                }
            }
            for k in 0..m {
                let ((x0, y0), (x1, y1)) = (nodes[k], nodes[k + 1]);
                widths.push(if x1 <= y1 {
                    x1 - x0
                } else if x0 >= y0 {
                    y0 - y1
                } else {
                    piece.len - x0 - y1
                });
            }
        }
        Ok(Grid::build(
            p,
            xl,
            xu,
            widths,
            reset,
            reset.saturating_sub(1),
            q,
        ))
    }

    fn build(
        p: &Params,
        xl: Vec<f64>,
        xu: Vec<f64>,
        widths: Vec<f64>,
        reset_plus: usize,
        reset_minus: usize,
        grading: f64,
    ) -> Grid {
        let (drag, sigma) = (p.drag(), p.sigma());
        let (vl, vu) = p.bounds();
        let n = widths.len();
        let edges: Vec<f64> = xl
            .iter()
            .zip(&xu)
            .map(|(&a, &b)| if a <= b { vl + a } else { vu - b })
            .collect();
        let centres = (0..n)
            .map(|i| {
                if xl[i] <= xu[i + 1] {
                    vl + 0.5 * (xl[i] + xl[i + 1])
                } else {
                    vu - 0.5 * (xu[i] + xu[i + 1])
                }
            })
            .collect();
        // Drift of + at node j: Σ - g(v_j) > 0; of - : -(Σ + g(v_j)) < 0.
        // Where g jumps at a node v = 0 (Coulomb friction), the flux leaves
        // the upwind cell, so the drift is its limit from the upwind side:
        // Σ - g(0-) = Σ + g(0+) for + (from v < 0), the same for -.
        let jump = drag.static_friction();
        let at_jump = |j: usize| jump > 0.0 && edges[j] == 0.0;
        let plus = |j: usize| {
            if at_jump(j) {
                sigma + jump
            } else if xu[j] <= xl[j] {
                edge_drift(&drag, sigma, xu[j])
            } else {
                sigma - drag.force(edges[j])
            }
        };
        let minus = |j: usize| {
            if at_jump(j) {
                sigma + jump
            } else if xl[j] <= xu[j] {
                edge_drift(&drag, sigma, xl[j])
            } else {
                sigma + drag.force(edges[j])
            }
        };
        let out_plus = (0..n)
            .map(|i| {
                if i + 1 == n {
                    0.0
                } else {
                    plus(i + 1) / widths[i]
                }
            })
            .collect();
        let out_minus = (0..n)
            .map(|i| if i == 0 { 0.0 } else { minus(i) / widths[i] })
            .collect();
        let spread = spread(p, &edges);
        Grid {
            edges,
            widths,
            centres,
            out_plus,
            out_minus,
            reset_plus,
            reset_minus,
            grading,
            noise: p.reset().noise(),
            spread,
        }
    }
}

/// The cell masses of a random reset target on the mesh with `edges`
/// (normalised to sum 1); None for a point target.
fn spread(p: &Params, edges: &[f64]) -> Option<Vec<f64>> {
    let t = p.reset().target();
    if p.reset().point().is_some() {
        return None;
    }
    let mut q: Vec<f64> = edges.windows(2).map(|e| t.mass(e[0], e[1])).collect();
    let total: f64 = q.iter().sum();
    q.iter_mut().for_each(|x| *x /= total);
    Some(q)
}

/// Cells of a uniform mesh that receive + and - mass placed at velocity w:
/// the cell containing w, or, if w is a node, the cell on the side each state
/// moves to (right for +, left for -), which respects the symmetry
/// (v, +) <-> (-v, -) of the model.
pub(crate) fn uniform_target(n: usize, vl: f64, vu: f64, w: f64) -> (usize, usize) {
    let dv = (vu - vl) / n as f64;
    let pos = (w - vl) / dv;
    let k = pos.round();
    if (pos - k).abs() < 1e-9 && k >= 1.0 && k <= (n - 1) as f64 {
        (k as usize, k as usize - 1)
    } else {
        let j = (pos.floor().max(0.0) as usize).min(n - 1);
        (j, j)
    }
}

/// The mesh maps of (v_l, v_r) and (v_r, v_u).
fn half_maps(p: &Params) -> (HalfMap, HalfMap) {
    let (vl, vu) = p.bounds();
    let vr = p.reset_velocity();
    let q = grading_exponent(p);
    let (s, gr) = (p.sigma(), p.drag().force(vr));
    let rate = p.lambda() + p.rate();
    // Cells cluster at a point target (the density's cusp); a random
    // target's smooth injection needs no clustering.
    let r_on = if p.rate() > 0.0 && p.reset().point().is_some() {
        rate
    } else {
        0.0
    };
    (
        HalfMap::new(vr - vl, q, s + gr, r_on),
        HalfMap::new(vu - vr, q, s - gr, r_on),
    )
}

/// Cells (nl, nu) of a graded mesh of n cells, in proportion to the mesh
/// parameter length of each half (so that doubling both nests the meshes).
pub(crate) fn graded_split(p: &Params, n: usize) -> (usize, usize) {
    let (a, b) = half_maps(p);
    let frac = a.s_total() / (a.s_total() + b.s_total());
    let nl = ((n as f64 * frac).round() as usize).clamp(1, n - 1);
    (nl, n - nl)
}

/// q = 1/(1+a) for a singular edge (a < 0), capped at [`MAX_GRADING`]; 1 otherwise.
pub(crate) fn grading_exponent(p: &Params) -> f64 {
    let a = p.edge_exponent();
    if a < 0.0 {
        (1.0 / (1.0 + a)).min(MAX_GRADING)
    } else {
        1.0
    }
}

/// Mesh parameter of one half (edge at distance 0, v_r at distance `len`):
/// s(x) = x + K x^(1/q) + β ℓ [ln(1 + len/ℓ) - ln(1 + (len - x)/ℓ)].
/// The second term grades towards the edge (monitor ~ x^(1/q - 1)); the third
/// clusters cells logarithmically at v_r on the scale ℓ = |drift(v_r)|/(λ + r),
/// the distance travelled between events, which at large r is the width of
/// the density peak at v_r (β = 0 unless ℓ < len/10).
#[derive(Clone, Copy, Debug)]
struct HalfMap {
    len: f64,
    q: f64,
    k: f64,
    ell: f64,
    beta: f64,
}

impl HalfMap {
    fn new(len: f64, q: f64, drift_at_vr: f64, rate: f64) -> Self {
        let k = (LAYER * len).powf(1.0 - 1.0 / q);
        let ell = if rate > 0.0 {
            drift_at_vr / rate
        } else {
            f64::INFINITY
        };
        let w = 1.0 - 10.0 * ell / len;
        let beta = if w > 0.0 {
            0.5 * len / (ell * (1.0 + len / ell).ln()) * w
        } else {
            0.0
        };
        HalfMap {
            len,
            q,
            k,
            ell,
            beta,
        }
    }

    fn log_term(&self, x: f64) -> f64 {
        if self.beta == 0.0 {
            0.0
        } else {
            self.beta
                * self.ell
                * ((self.len / self.ell).ln_1p() - ((self.len - x) / self.ell).ln_1p())
        }
    }

    fn s_total(&self) -> f64 {
        self.len + self.k * self.len.powf(1.0 / self.q) + self.log_term(self.len)
    }

    /// Distances 0 = x_0 < x_1 < ... < x_n = len at equally spaced s. A
    /// Newton solve per node is a second's work at millions of cells, so a
    /// stop request is polled every `STOP_POLL_NODES` nodes.
    fn distances(&self, n: usize) -> Result<Vec<f64>> {
        const STOP_POLL_NODES: usize = 1 << 14;
        let s_tot = self.s_total();
        let mut out = Vec::with_capacity(n + 1);
        out.push(0.0);
        for k in 1..n {
            if k % STOP_POLL_NODES == 0 {
                crate::stop::check_stop()?;
            }
            out.push(self.distance_at(s_tot * k as f64 / n as f64)?);
        }
        out.push(self.len);
        Ok(out)
    }

    /// The distance x with s(x) = s: solves
    /// f(u) = u^q + K u + log_term(u^q) - s = 0 for u = x^(1/q).
    /// f is increasing and convex on u > 0, so Newton
    /// from a point with f >= 0 converges monotonically from above; a NaN step
    /// or 500 steps without convergence are reported.
    fn distance_at(&self, s: f64) -> Result<f64> {
        const STEPS: usize = 500;
        let (q, kq, len) = (self.q, self.k, self.len);
        let mut u = (s / kq).min(s.powf(1.0 / q)).min(len.powf(1.0 / q));
        let mut du = f64::INFINITY;
        for _ in 0..STEPS {
            let uq1 = u.powf(q - 1.0);
            let x = u * uq1;
            let f = x + kq * u + self.log_term(x) - s;
            let dlog = if self.beta == 0.0 {
                0.0
            } else {
                self.beta * self.ell / (self.ell + len - x)
            };
            du = f / (q * uq1 * (1.0 + dlog) + kq);
            if du.is_nan() {
                return Err(Error::NonFinite {
                    method: "fp graded mesh (Newton)",
                    at: u.powf(q),
                });
            }
            // Stop at convergence or when rounding makes f <= 0.
            if !(du > 4e-16 * u) {
                return Ok(u.powf(q).min(len));
            }
            u -= du;
        }
        Err(Error::NotConverged {
            method: "fp graded mesh (Newton)",
            iterations: STEPS,
            residual: du,
            tolerance: 4e-16 * u,
        })
    }
}

/// The grading exponent q₀ of the mesh at v = 0 where g'(0) = ∞ (None
/// where g'(0) is finite, and for a force that jumps at 0: there the mesh
/// is not graded at 0).
///
/// Near such a kink g(v) ≈ c sign(v) |v|^n with 0 < n < 1. The zero-flux
/// stationary state at r = 0, (Σ - g) P+ = (Σ + g) P-, gives
/// P± = P (Σ ± g) / (2Σ) with P ∝ (Σ² - g²)⁻¹ exp(-2λ ∫ g / (Σ² - g²) dv):
/// the flux (Σ² - g²) P / (2Σ) = const · (1 - 2λ c |v|^(1+n) / ((1+n) Σ²) + …)
/// is C¹, the total density P = P(0) (1 + c² |v|^(2n) / Σ² + …) has a
/// |v|^(2n) cusp (a corner for n = 1/2, an infinite slope for n < 1/2), and
/// each state's density P± = P(0)/2 (1 ± c sign(v) |v|^n / Σ + …) a
/// |v|^n kink; resetting adds smooth terms. All of them are smooth functions
/// of g itself, so a mesh with |v| ~ s^q₀, q₀ = 1/n, next to 0 (cells
/// uniform in the force g) makes the densities and the drift smooth in the
/// mesh parameter s, and the upwind scheme first order with a clean error
/// expansion again (on a mesh not graded at 0 the cell next to 0 errs by
/// O(h^n)). n is [`Params::kink_exponent`]; q₀ is capped at
/// [`MAX_GRADING`]. Fails (typed) if that exponent is not in (0, 1).
pub(crate) fn kink_grading(p: &Params) -> Result<Option<f64>> {
    Ok(p.kink_exponent()?.map(|n| (1.0 / n).min(MAX_GRADING)))
}

/// The graded mesh of `n << refine` cells ([`Mesh::Graded`]): the mesh of
/// [`Grid::graded`] split by [`graded_split`], or, where g'(0) = ∞
/// ([`kink_grading`]), [`Grid::kinked`]. Doubling `refine` nests the meshes.
pub(crate) fn graded_mesh(p: &Params, n: usize, refine: usize) -> Result<Grid> {
    match kink_grading(p)? {
        None => {
            let (nl, nu) = graded_split(p, n);
            Grid::graded(p, nl << refine, nu << refine)
        }
        Some(q0) => Grid::kinked(p, q0, n, refine),
    }
}

/// What a piece of the kinked mesh does at one of its ends, as a term e(d)
/// of its mesh parameter in the distance d from that end (increasing,
/// e(0) = 0): algebraic grading K d^(1/q) (edge or kink) and/or
/// logarithmic clustering β ℓ ln(1 + d/ℓ) at v_r (see [`HalfMap`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct End {
    /// (q, K) of the grading term, None for none.
    pub grade: Option<(f64, f64)>,
    /// (β, ℓ) of the clustering term, None for none.
    pub cluster: Option<(f64, f64)>,
}

impl End {
    /// (e(d), e'(d)).
    fn term(&self, d: f64) -> (f64, f64) {
        let (mut e, mut de) = (0.0, 0.0);
        if let Some((q, k)) = self.grade {
            let p = d.powf(1.0 / q);
            e += k * p;
            de += k * p / (q * d);
        }
        if let Some((beta, ell)) = self.cluster {
            e += beta * ell * (d / ell).ln_1p();
            de += beta * ell / (ell + d);
        }
        (e, de)
    }
}

/// One piece [a, a + len] of the kinked mesh, with mesh parameter
/// s(x) = x + e_a(x) + e_b(len) - e_b(len - x) (x: distance from a; e_a,
/// e_b: its [`End`]s at a and b = a + len).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Piece {
    pub a: f64,
    pub len: f64,
    pub ends: [End; 2],
}

impl Piece {
    pub fn s_total(&self) -> f64 {
        self.len + self.ends[0].term(self.len).0 + self.ends[1].term(self.len).0
    }

    /// Distance d ∈ [0, len/2] from end `near` (0: a, 1: b) at which the
    /// mesh parameter counted from that end is `target`: safeguarded Newton
    /// in u = d^(1/q) (q: that end's grading, 1 if none), in which the
    /// parameter is smooth at d = 0, so that d keeps full relative accuracy.
    fn distance(&self, near: usize, target: f64) -> Result<f64> {
        let (en, ef) = (self.ends[near], self.ends[1 - near]);
        let q = en.grade.map_or(1.0, |g| g.0);
        let far_len = ef.term(self.len).0;
        let h = |u: f64| {
            let d = u.powf(q);
            if d == 0.0 {
                return (-target, f64::INFINITY, 0.0);
            }
            let (e, de) = en.term(d);
            let (f, df) = ef.term(self.len - d);
            let dd = q * d / u;
            (d + e + far_len - f - target, (1.0 + de + df) * dd, 0.0)
        };
        let hi = (0.5 * self.len).powf(1.0 / q);
        let guess = target.min(0.5 * self.len).powf(1.0 / q);
        let u = root::solve_increasing(&h, 0.0, hi, guess, 1e-13, 0.0)?;
        Ok(u.powf(q).min(0.5 * self.len))
    }

    /// Node distances of `m` cells at equally spaced s: (from a, from b),
    /// each node solved from its nearer end (in s).
    pub fn nodes(&self, m: usize) -> Result<Vec<(f64, f64)>> {
        let s_tot = self.s_total();
        let mid = {
            let (e, _) = self.ends[0].term(0.5 * self.len);
            let (f0, _) = self.ends[1].term(self.len);
            let (f1, _) = self.ends[1].term(0.5 * self.len);
            0.5 * self.len + e + f0 - f1
        };
        let mut out = Vec::with_capacity(m + 1);
        out.push((0.0, self.len));
        for k in 1..m {
            let s = s_tot * k as f64 / m as f64;
            out.push(if s <= mid {
                let x = self.distance(0, s)?;
                (x, self.len - x)
            } else {
                let y = self.distance(1, s_tot - s)?;
                (self.len - y, y)
            });
        }
        out.push((self.len, 0.0));
        Ok(out)
    }
}

/// The pieces of the kinked mesh between the breakpoints v_l < {0, v_r} <
/// v_u (one piece less where v_r = 0): graded like [`HalfMap`] at the edges
/// (exponent `q`) and clustered at a point target v_r, and graded with
/// exponent `q0` towards v = 0 from both sides ([`kink_grading`]).
fn kink_pieces(p: &Params, q: f64, q0: f64) -> Vec<Piece> {
    let (vl, vu) = p.bounds();
    let vr = p.reset_velocity();
    let (s, gr) = (p.sigma(), p.drag().force(vr));
    let rate = p.lambda() + p.rate();
    let clustered = p.rate() > 0.0 && p.reset().point().is_some();
    let mut pts = vec![vl, vr.min(0.0), vr.max(0.0), vu];
    pts.dedup();
    let grade = |q: f64, len: f64| (q > 1.0).then(|| (q, (LAYER * len).powf(1.0 - 1.0 / q)));
    // The clustering of [`HalfMap::new`] on the scale ℓ = drift / rate.
    let cluster = |drift: f64, len: f64| {
        let ell = drift / rate;
        let w = 1.0 - 10.0 * ell / len;
        (clustered && w > 0.0).then(|| (0.5 * len / (ell * (1.0 + len / ell).ln()) * w, ell))
    };
    let end = |at: f64, len: f64, drift: f64| End {
        grade: if at == vl || at == vu {
            grade(q, len)
        } else if at == 0.0 {
            grade(q0, len)
        } else {
            None
        },
        cluster: if at == vr { cluster(drift, len) } else { None },
    };
    pts.windows(2)
        .map(|w| {
            let len = w[1] - w[0];
            Piece {
                a: w[0],
                len,
                ends: [end(w[0], len, s - gr), end(w[1], len, s + gr)],
            }
        })
        .collect()
}

/// Cells per piece for `n` cells in all, in proportion to the pieces'
/// mesh parameter lengths, at least one each.
pub(crate) fn piece_counts(pieces: &[Piece], n: usize) -> Vec<usize> {
    let total: f64 = pieces.iter().map(Piece::s_total).sum();
    let (mut cum, mut prev) = (0.0, 0);
    let mut out = Vec::with_capacity(pieces.len());
    for (i, piece) in pieces.iter().enumerate() {
        cum += piece.s_total();
        let left = pieces.len() - 1 - i;
        let c = if left == 0 {
            n
        } else {
            ((n as f64 * cum / total).round() as usize).clamp(prev + 1, n - left)
        };
        out.push(c - prev);
        prev = c;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_drift_matches_direct_formula() {
        for (d, s) in [
            (DragLaw::Tan, 3.0),
            (DragLaw::Tanh, 0.6),
            (DragLaw::Linear, 1.5),
        ] {
            let vu = d.inverse(s);
            for &x in &[0.01, 0.3 * vu, 0.9 * vu] {
                let direct = s - d.force(vu - x);
                assert!((edge_drift(&d, s, x) - direct).abs() < 1e-12 * (1.0 + direct));
            }
        }
    }

    #[test]
    fn graded_mesh_is_monotone_and_spans_interval() {
        let p = Params::new(DragLaw::Tan, 3.0, 0.5, 0.0, 0.3).unwrap();
        let g = Grid::graded(&p, 300, 500).unwrap();
        assert_eq!(g.cells(), 800);
        assert!(g.grading > 19.0);
        assert!(g.widths.iter().all(|&h| h > 0.0));
        let total: f64 = g.widths.iter().sum();
        assert!((total - 2.0 * 3f64.atan()).abs() < 1e-12);
        assert!((g.edges[300] - 0.3).abs() < 1e-15);
        assert!(g.widths[0] < 1e-30 && g.widths[799] < 1e-30);
        assert!(g.out_plus.iter().all(|a| a.is_finite() && *a >= 0.0));
    }

    #[test]
    fn large_rate_clusters_cells_at_reset_velocity() {
        let p = Params::new(DragLaw::Tanh, 0.6, 0.5, 1000.0, 0.1).unwrap();
        let (nl, nu) = graded_split(&p, 2000);
        let g = Grid::graded(&p, nl, nu).unwrap();
        assert!((g.edges[nl] - 0.1).abs() < 1e-15);
        let mean = (g.edges[2000] - g.edges[0]) / 2000.0;
        // Cells next to v_r are far below the mean width (peak width ~ Σ/r).
        assert!(g.widths[nl] < 0.05 * mean && g.widths[nl - 1] < 0.05 * mean);
        let total: f64 = g.widths.iter().sum();
        assert!((total - 2.0 * 0.6f64.atanh()).abs() < 1e-12);
        assert!(g.widths.iter().all(|&h| h > 0.0));
    }

    /// g'(0) = ∞ (power n = 0.5, 0.3): v = 0 and v_r are nodes, the cells
    /// next to 0 shrink like N^-(1/n) (cells uniform in g there) and the
    /// meshes nest; a law with finite g'(0) keeps the two-part mesh.
    #[test]
    fn kinked_mesh_has_node_at_zero_graded_towards_it() {
        for (spec, vr) in [
            ("power:n=0.5", 0.0),
            ("power:n=0.3", 2.0),
            ("power:n=0.5", -1.0),
        ] {
            let d: DragLaw = spec.parse().unwrap();
            let p = Params::new(d.clone(), 3.0, 0.5, 1.0, vr).unwrap();
            let q0 = kink_grading(&p).unwrap().unwrap();
            let n = 1.0 / q0;
            let (a, b) = (
                graded_mesh(&p, 500, 0).unwrap(),
                graded_mesh(&p, 500, 1).unwrap(),
            );
            for g in [&a, &b] {
                assert!(g.edges.contains(&0.0), "{spec}: node at 0");
                assert!(g.edges.contains(&vr), "{spec}: v_r node");
                assert!(g.widths.iter().all(|&h| h > 0.0));
                assert!(g.edges.windows(2).all(|e| e[1] >= e[0]));
                let total: f64 = g.widths.iter().sum();
                assert!((total - 2.0 * p.v_upper()).abs() < 1e-12 * total);
                assert_eq!(g.edges[g.reset_plus], vr);
                assert_eq!(g.reset_minus + 1, g.reset_plus);
            }
            // nested: every other node of the refined mesh is a coarse node
            for (k, &e) in a.edges.iter().enumerate() {
                assert!(
                    (b.edges[2 * k] - e).abs() <= 1e-13 * (1.0 + e.abs()),
                    "{spec} node {k}"
                );
            }
            // Cells uniform in g next to 0 (on the side away from v_r, the
            // longer piece): g at the second node from 0 is twice g at the
            // first, up to the O(1/N) linear part of the map; refining
            // shrinks the cell next to 0 by 2^(1/n).
            let next = |g: &Grid| {
                let z = g.edges.iter().position(|&e| e == 0.0).unwrap();
                if vr > 0.0 {
                    (g.widths[z - 1], g.widths[z - 2])
                } else {
                    (g.widths[z], g.widths[z + 1])
                }
            };
            let dev = |g: &Grid| {
                let (h1, h2) = next(g);
                (d.force(h1 + h2) / d.force(h1) - 2.0).abs()
            };
            assert!(
                dev(&a) < 0.1 && dev(&b) < 0.6 * dev(&a),
                "{spec}: {} {}",
                dev(&a),
                dev(&b)
            );
            let shrink = next(&a).0 / next(&b).0;
            assert!(
                (shrink / 2f64.powf(1.0 / n) - 1.0).abs() < 0.1,
                "{spec}: {shrink}"
            );
        }
        let p = Params::new(DragLaw::Tan, 3.0, 0.5, 1.0, 0.3).unwrap();
        assert!(kink_grading(&p).unwrap().is_none());
        let (nl, nu) = graded_split(&p, 800);
        let (g, h) = (
            graded_mesh(&p, 800, 1).unwrap(),
            Grid::graded(&p, 2 * nl, 2 * nu).unwrap(),
        );
        assert_eq!(g.edges, h.edges);
        assert_eq!(g.widths, h.widths);
    }
}
