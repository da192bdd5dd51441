//! Exact event-driven sampler: no time step, no discretisation bias.
//!
//! The process is piecewise deterministic: noise flips (rate lambda) and
//! velocity resets (rate r, v → v_r, noise state kept) happen at the events
//! of a Poisson process of rate lambda + r; in between, v follows the flow
//! dv/dt = s - g(v), s = ±Sigma (paper Eq. (5)), solved exactly by
//! [`Drag::flow_time`] / [`Drag::flow_velocity`]. Position and the
//! time integrals of v and v² along a flow segment are
//! ∫ v dt = v* Δ - I1 and ∫ v² dt = v*² Δ - 2 v* I1 + I2 with the deficit
//! integrals I_k = ∫ (v* - v)^k dt = ∫ (v* - v)^k / (s - g(v)) dv, whose
//! integrands are smooth up to the fixed point v*. Along a segment the flow
//! potential Φ falls at the constant rate g'(v*), so the sampler carries Φ
//! with v and reads the velocity and the deficit antiderivatives after time
//! t from one [`PotentialTable`] lookup at Φ - g'(v*) t (a sum of three
//! degree-11 polynomials and one exponential; tables built once per run,
//! agreeing with the iterative flow to rounding). An event then costs one
//! exponential variate, one uniform, that lookup, and after a noise flip
//! the new flow's potential (closed form) and a second lookup; a reset
//! starts from the precomputed point at v_r. A flow that does not fit in
//! the tables (tanh within ~1e-6 of Sigma = 1, tan at huge Sigma) runs the
//! iterative solve instead ([`Drag::flow_velocity`]'s guided Halley step
//! with deficit tables in v, [`DeficitTable`]). Occupation times come from
//! the flow potential at precomputed bin edges (bins crossed in full are
//! counted in a difference array and weighted by their exact crossing time
//! at the end of the particle).
//!
//! Paper references: flow Eq. (5), reset rule Eq. (3) (here to v_r, noise kept),
//! velocity bounds Eqs. (8)-(10); the Euler scheme it replaces is Eqs. (30)-(32).
//!
//! Estimators are exact functionals of each path: moments at the grid times
//! (flow evaluated inside the segment), time averages of v and v² and the
//! occupation time of every histogram bin over [burn_in, t_max] (bin edges
//! crossed in full contribute the precomputed flow time across the bin).
//!
//! The noise's state space is a type parameter of the one event loop
//! (`Sampler` over [`ExactNoise`], shared with the first-passage and
//! search samplers), dispatched once per run: the paper's two-state noise
//! ([`Telegraph`], its random draws bit for bit) or any finite-state noise
//! at T = 0 (docs/equations.md Eqs. (N10)-(N12): per level its own
//! segments, fixed point (possibly interior) and crossing times, events at
//! rate q_s + r in state s). Both share the per-state tables (`Tables`)
//! and the segment code (`Segments`, `flow_segment`, the occupation and
//! crossing times).
//!
//! The modifiers of the resetting rule ([`crate::model::reset::Schedule`])
//! run in a second step function of that loop, chosen once per run (the
//! paper's protocol keeps its own step, bit for bit), for every
//! finite-state noise: the next event is the earliest of the
//! exponential clock (noise jumps at rate q_s, the paper's flips at rate
//! lambda, plus Poisson resets at rate r outside a refractory period), the
//! next scheduled reset time (resets at
//! T, 2T, ... from t = 0 with a periodic clock; with a renewal clock a
//! waiting time drawn at each reset, or at the end of its refractory
//! period, from the clock's law) and the end of a refractory period. A reset sends
//! x to x_r with position resetting; a refractory period is a held segment:
//! v constant at the reset velocity, x linear in t, the occupation of the
//! held velocity's bin and the time averages exact; the noise jumps during
//! it (state-dependent rate q_s), reset-clock events are ignored (the periodic times inside it or at
//! its end skipped), and the flow resumes from the held velocity with the
//! noise state of that moment. An event at t acts just after t: a
//! recording time equal to a periodic reset time sees the state before it.
//!
//! With thermal noise (T > 0) and linear drag a second loop, `ou`, runs the
//! same event clock with exact Ornstein-Uhlenbeck segments in between
//! (Eqs. (N40)-(N45)), Poisson resetting only (a schedule modifier is
//! refused naming its flag); any other drag at T > 0 is refused naming
//! `temperature`.

use crate::error::{Error, Result};
use crate::model::drag::{FlowMap, FlowPoint, PotentialTable};
use crate::model::noise::chain::Chain;
use crate::model::reset::{Refractory, Reset, ResetRule, Schedule, Solver};
use crate::model::{Drag, Params};
use crate::numerics::chebyshev::{
    self, clenshaw, clenshaw2, Adaptive, Piece, Refine, Unresolved, NC,
};
use crate::parallel::Progress;
use crate::rng::{self, Rng};
use crate::sim::{Observables, Part, SimSpec};
use rand::Rng as _;
use std::ops::Range;

mod noise;
mod ou;
pub(crate) mod passage;

pub use noise::{ExactNoise, Telegraph};

/// Antiderivatives Ψ_k(v) = ∫_{lo}^{v} (v* - v')^k / (s - g(v')) dv', k = 1, 2,
/// for one noise state s on [lo, hi], as piecewise Chebyshev series on
/// adaptively refined pieces (refined until the last coefficients of the
/// integrand fall below 1e-14 of its size, the rounding-noise level of the sampled values).
#[derive(Clone, Debug)]
pub struct DeficitTable {
    /// Fixed point v* = g⁻¹(s).
    vs: f64,
    /// Piece boundaries (strictly increasing, first = lo, last = hi).
    bounds: Vec<f64>,
    /// Per piece: antiderivative coefficients of k = 1 and k = 2, interleaved
    /// (`[j][k]`) so both series are summed in one Clenshaw pass.
    coef: Vec<[[f64; 2]; NC]>,
    /// Per piece: Ψ_k at the piece's left end.
    offset: Vec<[f64; 2]>,
}

/// The most Chebyshev pieces of a [`DeficitTable`].
const MAX_PIECES: usize = 4096;

impl DeficitTable {
    /// Build the table for drag `drag`, noise value `s` on [lo, hi].
    pub fn new<D: Drag>(drag: &D, s: f64, lo: f64, hi: f64) -> Result<Self> {
        let vs = drag.inverse(s);
        let g1 = drag.derivative(vs);
        let f = |v: f64| -> [f64; 2] {
            let u = vs - v;
            let f1 = if u == 0.0 {
                1.0 / g1
            } else {
                u / drag.drift_at_distance(s, u)
            };
            [f1, u * f1]
        };
        let (min_width, kink_width) = ((hi - lo) * 1e-9, (hi - lo) * 1e-15);
        // A piece at a kink of g with infinite slope (the power law with
        // n < 1 at v = 0): the series cannot decay to rounding, but the
        // integrand f is bounded and f(0) + c |v|^n across it, so the
        // pieces at the kink are halved down to 1e-15 of the table (one
        // piece per halving) and the last is kept: its antiderivative
        // error is below its width times the variation of f on it. The
        // time average of v² is v*² t - 2 v* I_1 + I_2, which cancels
        // when v* ≫ |v| (n = 0.1 at Sigma = 3: v* = 3^10), so I_1 must be
        // accurate to far better than 1/v*: a floor of 1e-9 of the table
        // gave <v²> = 2.58 ± 0.01 there against the FP solver's 1.33.
        let kink = |a: f64, b: f64| kink_inside(drag, a, b);
        let floor = |a: f64, b: f64| if kink(a, b) { kink_width } else { min_width };
        let resolved = |fit: &chebyshev::Fit<2>, a: f64, b: f64| {
            fit.resolved_to_noise(1e-14, a.abs().max(b.abs()).max(vs.abs()))
        };
        let opts = Adaptive {
            resolved: &resolved,
            refine: Refine::Bisect {
                min_width: &floor,
                keep_at_floor: &kink,
            },
            // A bound on the work (a table of the shipped laws has tens of
            // pieces): an integrand no polynomial pieces resolve, as that of
            // an expression law growing like cosh(asinh(v)^5) at Sigma =
            // 5e206, is refused within a second or two instead of after
            // minutes of bisection.
            max_pieces: MAX_PIECES,
        };
        let pieces =
            chebyshev::fit_adaptive(&f, &initial_pieces(drag, lo, hi), &opts).map_err(|e| {
                let at = match e {
                    Unresolved::Piece { a, .. } => format!("near v = {a:.6e}"),
                    _ => format!("in {MAX_PIECES} pieces"),
                };
                Error::Numerical {
                    method: "exact sampler table",
                    reason: format!(
                        "deficit integrand not resolved {at} (Sigma = {:.6e})",
                        s.abs()
                    ),
                }
            })?;
        let mut bounds = vec![lo];
        let mut coef = Vec::with_capacity(pieces.len());
        let mut offset = Vec::with_capacity(pieces.len());
        let mut acc = [0.0, 0.0];
        for Piece { b, fit, .. } in pieces {
            let c = fit.anti;
            bounds.push(b);
            offset.push(acc);
            for k in 0..2 {
                acc[k] += clenshaw(&c[k], 1.0);
            }
            let mut inter = [[0.0; 2]; NC];
            for (j, cj) in inter.iter_mut().enumerate() {
                *cj = [c[0][j], c[1][j]];
            }
            coef.push(inter);
        }
        Ok(DeficitTable {
            vs,
            bounds,
            coef,
            offset,
        })
    }

    /// Fixed point v* of this noise state.
    pub fn fixed_point(&self) -> f64 {
        self.vs
    }

    /// Number of Chebyshev pieces.
    pub fn pieces(&self) -> usize {
        self.coef.len()
    }

    /// (Ψ_1(v), Ψ_2(v)); v is clamped into the table range.
    #[inline]
    pub fn psi(&self, v: f64) -> [f64; 2] {
        let n = self.coef.len();
        let p = self.bounds[1..n].partition_point(|&b| b <= v);
        let (a, b) = (self.bounds[p], self.bounds[p + 1]);
        let x = chebyshev::to_unit(v, a, b);
        let c = &self.coef[p];
        let o = &self.offset[p];
        let r = clenshaw2(c, x);
        [o[0] + r[0], o[1] + r[1]]
    }

    /// Deficit integrals (I1, I2) along the flow from va to vb
    /// (same meaning as [`Drag::flow_deficits`]).
    #[inline]
    pub fn deficits(&self, va: f64, vb: f64) -> (f64, f64) {
        let (a, b) = (self.psi(va), self.psi(vb));
        (b[0] - a[0], b[1] - a[1])
    }
}

/// The deficit table's first pieces: [lo, hi] in 8 equal parts, refined by
/// coefficient decay from there. Where g jumps at v = 0 (Coulomb friction)
/// so does the integrand: v = 0 is made a piece boundary.
fn initial_pieces<D: Drag>(drag: &D, lo: f64, hi: f64) -> Vec<(f64, f64)> {
    let init = 8;
    let jump = drag.static_friction() > 0.0;
    let mut out = Vec::with_capacity(init + 1);
    for i in 0..init {
        let a = lo + (hi - lo) * i as f64 / init as f64;
        let b = if i + 1 == init {
            hi
        } else {
            lo + (hi - lo) * (i + 1) as f64 / init as f64
        };
        if jump && a < 0.0 && 0.0 < b {
            out.extend([(a, 0.0), (0.0, b)]);
        } else {
            out.push((a, b));
        }
    }
    out
}

/// Does [a, b] contain v = 0 where g' is infinite or g jumps (a law with a
/// kink at 0: the power law with n < 1, Coulomb friction)?
fn kink_inside<D: Drag>(drag: &D, a: f64, b: f64) -> bool {
    a <= 0.0 && 0.0 <= b && (!drag.derivative(0.0).is_finite() || drag.static_friction() > 0.0)
}

/// Smallest relaxation rate g'(v*) at the fixed point v* = v_u the tables
/// resolve: below it (tanh within ~5e-11 of Sigma = 1, where g'(v_u) =
/// 1 - Sigma²) the approach to v_u is so slow that the flow tables lose
/// their precision (measured: <v²> 2.8 standard errors off the FP answer at
/// 1 - Sigma = 1e-12, negative at 1e-14).
pub(crate) const MIN_RELAXATION_RATE: f64 = 1e-10;

pub(crate) fn check_relaxation<D: Drag>(drag: &D, sigma: f64, vu: f64) -> Result<()> {
    let rate = drag.derivative(vu);
    if !(rate >= MIN_RELAXATION_RATE) {
        return Err(Error::invalid(
            "sigma",
            sigma,
            format!(
                "g'(v_u) >= {MIN_RELAXATION_RATE:e} for the exact sampler (here g'(v_u) = \
                 {rate:e}; tanh: Sigma <= 1 - 5e-11); the Fokker-Planck solvers cover it"
            ),
        ));
    }
    Ok(())
}

/// Largest relative rounding of the time averages the exact sampler
/// accepts (see [`check_cancellation`]).
const MAX_CANCELLATION: f64 = 1e-6;

/// The time average of v² over a segment is v*² Δt - 2 v* I_1 + I_2, from
/// deficit antiderivatives of size up to ~v_u³/Sigma. Where v_u is far above
/// Sigma (a law growing slower than linearly at large Sigma: the power law
/// with n < 1, Carreau with n < 1), the particle lives at velocities of
/// order V = min(v_u, Sigma) and the rounding ε v_u³/Sigma of the tables
/// swamps <v²> ~ V². Refused when ε v_u³ / (Sigma V²) > [`MAX_CANCELLATION`]:
/// power:n=0.1 at Sigma = 3 (v_u = 3^10, ratio 1.6e-3; measured <v²> 8 %
/// off the FP solver's) is refused, power:n=0.15 (2.9e-8) agrees with it
/// (1.3 standard errors). A law with v_u <= Sigma has ratio ε v_u / Sigma.
fn check_cancellation(params: &Params) -> Result<()> {
    let (sigma, vu) = (params.sigma(), params.v_upper());
    let v = vu.min(sigma);
    let ratio = f64::EPSILON * vu * (vu / sigma) * (vu / v) / v;
    if ratio > MAX_CANCELLATION {
        return Err(Error::invalid(
            "drag",
            params.drag(),
            format!(
                "with the exact sampler, v_u not far above Sigma (here v_u = {vu:e} at \
                 Sigma = {sigma}: its time averages would lose their precision, relative \
                 rounding {ratio:.1e} > {MAX_CANCELLATION:e}); the Fokker-Planck solvers and \
                 the Euler scheme cover it"
            ),
        ));
    }
    Ok(())
}

/// The flow segments of one noise state: table lookups in the flow
/// potential ([`PotentialTable`]) where the flow fits in its tables, else the
/// iterative velocity solve with the deficit table in v (the same answers
/// to rounding).
#[derive(Clone)]
pub enum Segments<F> {
    Table(PotentialTable<F>),
    /// A fixed point inside the velocity interval (or a side longer than
    /// the paper's 2 |v*|): one table per side of v*, the one below it
    /// first ([`PotentialTable::side`]); a flow never crosses v*.
    Sides(Box<[PotentialTable<F>; 2]>, f64),
    Solve(F, DeficitTable),
}

impl<F: FlowMap> Segments<F> {
    /// The segment start at velocity v.
    #[inline]
    pub(crate) fn at(&self, v: f64) -> FlowPoint {
        match self {
            Segments::Table(t) => t.at(v),
            Segments::Sides(t, vs) => t[usize::from(v > *vs)].at(v),
            Segments::Solve(f, d) => {
                let psi = d.psi(v);
                FlowPoint {
                    v,
                    phi: f.potential(v),
                    q: [-psi[0], -psi[1]],
                }
            }
        }
    }

    /// The point reached from p after time dt ≥ 0.
    #[inline]
    pub(crate) fn advance(&self, p: &FlowPoint, dt: f64) -> FlowPoint {
        match self {
            Segments::Table(t) => t.advance(p, dt),
            Segments::Sides(t, vs) => t[usize::from(p.v > *vs)].advance(p, dt),
            Segments::Solve(f, d) => {
                if !(dt > 0.0) {
                    return *p;
                }
                let v = f.velocity(p.v, dt);
                let psi = d.psi(v);
                FlowPoint {
                    v,
                    phi: p.phi - f.rate() * dt,
                    q: [-psi[0], -psi[1]],
                }
            }
        }
    }
}

/// The part of a [`Sampler`] that the law, the levels and the number of
/// bins fix (no rate enters): per state the flow segments, fixed point,
/// 1/g'(v*), the bins' crossing times and edge potentials. Built once per
/// process for each (noise kind, law, levels, bins) and shared through
/// [`crate::memo`], so the points of a sweep over the rates do not rebuild
/// the tables (for a law on the generic path, tens of milliseconds).
#[derive(Clone)]
struct Tables<F> {
    segs: Vec<Segments<F>>,
    vs: Vec<f64>,
    inv_rate: Vec<f64>,
    /// Flow time across bin k in full (0 where never crossed).
    tau: Vec<Vec<f64>>,
    /// Flow potential (see [`FlowMap::potential`]) at every edge.
    phi_edges: Vec<Vec<f64>>,
}

impl<F: FlowMap> Tables<F> {
    fn new<D: Drag<Flow = F>, N: ExactNoise>(
        drag: &D,
        noise: &N,
        params: &Params,
        b: usize,
    ) -> Result<Self> {
        let (lo, hi) = params.bounds();
        let mut edges: Vec<f64> = (0..=b)
            .map(|k| lo + (hi - lo) * k as f64 / b as f64)
            .collect();
        edges[b] = hi;
        let mut out = Tables {
            segs: noise.segments(drag, params)?,
            vs: Vec::new(),
            inv_rate: Vec::new(),
            tau: Vec::new(),
            phi_edges: Vec::new(),
        };
        for &a in noise.levels() {
            let flow = drag.flow(a);
            out.vs.push(flow.fixed_point());
            out.inv_rate.push(1.0 / flow.rate());
            out.tau.push(crossing_times(drag, a, &edges)?);
            out.phi_edges
                .push(edges.iter().map(|&e| flow.potential(e)).collect());
        }
        Ok(out)
    }
}

/// Everything fixed for a run: the noise and its tables and clock, the
/// resetting protocol, the recording window.
pub(crate) struct Sampler<F, N> {
    noise: N,
    tab: Tables<F>,
    /// Per state: the event clock q_s + r, its inverse, and 1/q_s (0 where
    /// q_s = 0: the clock of a refractory period).
    total: Vec<f64>,
    inv_total: Vec<f64>,
    inv_exit: Vec<f64>,
    /// The segment start at the point target v_r, per noise state.
    at_vr: Option<Vec<FlowPoint>>,
    /// The resetting rule (rate, target, noise state at a reset).
    reset: ResetRule,
    times: Vec<f64>,
    burn_in: f64,
    t_max: f64,
    seed: u64,
    /// The paper's protocol (no modifier): the plain step runs.
    plain: bool,
    /// The schedule (its periodic or renewal clock).
    schedule: Schedule,
    /// Position resetting: x_r.
    x_reset: Option<f64>,
    /// Refractory period after each reset.
    refractory: Option<Refractory>,
}

/// What ends a segment of the scheduled event loop.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Edge {
    /// The exponential clock: a flip, or a Poisson reset.
    Clock,
    /// A periodic reset time.
    Periodic,
    /// The end of a refractory period.
    Release,
}

/// Per-chunk scratch: occupation times and full-crossing counts
/// (difference arrays, so a segment crossing many bins costs O(1)), one
/// per noise state.
pub(crate) struct Scratch {
    occ: Vec<f64>,
    cross: Vec<Vec<i64>>,
}

/// The segments of noise value s: tables when they fit, else the solve.
/// (A jump of g at v = 0, or an infinite slope there as for the power law
/// with n < 1, is a kink of Φ at a known potential, which the table makes
/// a cell boundary, tabulating the cells next to an infinite slope in a
/// variable that resolves it.)
pub(crate) fn segments<D: Drag>(drag: &D, s: f64, lo: f64, hi: f64) -> Result<Segments<D::Flow>> {
    let table = PotentialTable::new(drag, s);
    Ok(match table {
        Some(t) => Segments::Table(t),
        None => Segments::Solve(
            drag.flow(s).accelerated(),
            DeficitTable::new(drag, s, lo, hi)?,
        ),
    })
}

/// Bin crossing times of the flow of noise value s (0 where a bin is never
/// crossed in full): a bin below the fixed point v* = g⁻¹(s) is crossed
/// upward, one above it downward, and the bin holding v* never in full (for
/// s = ±Sigma, v* is the interval's edge: every bin is crossed toward it).
fn crossing_times<D: Drag>(drag: &D, s: f64, edges: &[f64]) -> Result<Vec<f64>> {
    let vs = drag.inverse(s);
    // Crossing time of a bin: +∞ (bin not crossed) counts 0; NaN means
    // the flow-time quadrature failed.
    let fin = |t: f64, at: f64| match t {
        t if t.is_nan() => Err(Error::NonFinite {
            method: "exact sampler bin crossing time",
            at,
        }),
        t if t.is_finite() => Ok(t),
        _ => Ok(0.0),
    };
    (0..edges.len() - 1)
        .map(|k| {
            let (a, b) = if edges[k + 1] <= vs {
                (edges[k], edges[k + 1])
            } else if edges[k] >= vs {
                (edges[k + 1], edges[k])
            } else {
                return Ok(0.0);
            };
            fin(drag.flow_time(s, a, b), edges[k])
        })
        .collect()
}

impl<F: FlowMap, N: ExactNoise> Sampler<F, N> {
    /// The sampler of `params` with the noise `N` (its tables built or
    /// shared through [`crate::memo`]); refused naming `noise` where the
    /// velocity interval does not hold the start v = 0.
    pub(crate) fn new<D: Drag<Flow = F>>(
        drag: &D,
        params: &Params,
        spec: &SimSpec,
    ) -> Result<Self> {
        params.require(Solver::Exact)?;
        super::check_period_window(params, spec)?;
        let noise = N::of(params)?;
        let (lo, hi) = params.bounds();
        if !(lo < hi && lo <= 0.0 && 0.0 <= hi) {
            return Err(Error::invalid(
                "noise",
                params.noise_model()?.spec(),
                format!(
                    "levels of both signs (or zero) and at least two distinct levels for the \
                     exact sampler: the particle starts at v = 0 (here the velocity interval is \
                     [{lo}, {hi}])"
                ),
            ));
        }
        let bits: Vec<String> = noise
            .levels()
            .iter()
            .map(|a| format!("{:x}", a.to_bits()))
            .collect();
        let kind = std::any::type_name::<N>();
        let key = format!(
            "exact sampler {kind} {drag:?} {} {}",
            bits.join(","),
            spec.bins
        );
        let tab =
            (*crate::memo::shared(key, || Tables::new(drag, &noise, params, spec.bins))?).clone();
        if params.noise().is_none() {
            check_cancellation(params)?;
        }
        let schedule = params.schedule();
        let reset = *params.reset();
        let total = noise.clocks(reset.rate());
        let inv_exit = (0..total.len())
            .map(|s| match noise.exit(s) {
                q if q > 0.0 => 1.0 / q,
                _ => 0.0,
            })
            .collect();
        Ok(Sampler {
            at_vr: reset
                .point()
                .map(|vr| tab.segs.iter().map(|s| s.at(vr)).collect()),
            inv_total: total.iter().map(|t| 1.0 / t).collect(),
            inv_exit,
            total,
            noise,
            tab,
            plain: schedule.is_plain(),
            schedule: schedule.clone(),
            x_reset: schedule.position.map(|p| p.x),
            refractory: schedule.refractory,
            reset,
            times: spec.grid.times().to_vec(),
            burn_in: spec.burn_in,
            t_max: spec.grid.t_max(),
            seed: spec.seed,
        })
    }

    /// The segment start in state s after a reset to velocity v.
    #[inline(always)]
    fn reset_point(&self, si: usize, v: f64) -> FlowPoint {
        match &self.at_vr {
            Some(at) => at[si],
            None => self.tab.segs[si].at(v),
        }
    }

    /// Empty scratch for `bins` bins.
    pub(crate) fn scratch(&self, bins: usize) -> Scratch {
        Scratch {
            occ: vec![0.0; bins],
            cross: vec![vec![0; bins]; self.total.len()],
        }
    }

    /// A particle at t = 0 (v = 0, noise state drawn).
    fn start(&self, i: u64) -> Lane {
        let mut rng = rng::stream(self.seed, i);
        let si = self.noise.start(None, &mut rng);
        let next_periodic = self.schedule.first_reset(&mut rng);
        Lane {
            rng,
            si,
            a: self.tab.segs[si].at(0.0),
            t: 0.0,
            x: 0.0,
            k: 0,
            int_v: 0.0,
            int_v2: 0.0,
            msd: 0.0,
            at_atom: 0.0,
            events: 0,
            done: false,
            held: false,
            hold_until: f64::INFINITY,
            next_periodic,
        }
    }

    /// One flow segment of a particle up to its next event (or t_max), then
    /// the event (the paper's protocol).
    #[inline]
    fn step(&self, p: &mut Lane, obs: &mut Observables, sc: &mut Scratch) {
        let (rate, inv) = (self.total[p.si], self.inv_total[p.si]);
        let gap = if rate > 0.0 {
            // Exp(rate) by a product with 1/rate (the division sits on the
            // event's dependency chain).
            p.rng.sample::<f64, _>(rand_distr::Exp1) * inv
        } else {
            f64::INFINITY
        };
        let t_end = (p.t + gap).min(self.t_max);
        let b = flow_segment(self, p, obs, sc, t_end);
        if t_end >= self.t_max {
            p.done = true;
            return;
        }
        p.events += 1;
        match self.noise.event(p.si, p.rng.gen::<f64>() * rate) {
            Some(j) => {
                p.si = j;
                p.a = self.tab.segs[j].at(b.v);
            }
            None => {
                let v = self.draw_reset(p);
                p.a = self.reset_point(p.si, v);
            }
        }
    }

    /// The velocity after a reset (drawn for a random target) and the noise
    /// state (kept or re-drawn), stored in the lane.
    #[inline(always)]
    fn draw_reset(&self, p: &mut Lane) -> f64 {
        let v = self.reset.draw_velocity(&mut p.rng);
        p.si = self.noise.after_reset(p.si, &self.reset, &mut p.rng);
        v
    }

    /// [`Sampler::step`] with the schedule's modifiers (see the module
    /// docs): the segment ends at the exponential clock, the next periodic
    /// reset time or the end of the refractory period, whichever is first.
    fn step_scheduled(&self, p: &mut Lane, obs: &mut Observables, sc: &mut Scratch) {
        // Inside a refractory period only the noise's jumps run (rate q_s).
        let si = p.si;
        let (rate, inv) = if p.held {
            (self.noise.exit(si), self.inv_exit[si])
        } else {
            (self.total[si], self.inv_total[si])
        };
        let gap = if rate > 0.0 {
            p.rng.sample::<f64, _>(rand_distr::Exp1) * inv
        } else {
            f64::INFINITY
        };
        let (mut t_end, mut edge) = (p.t + gap, Edge::Clock);
        let (at, kind) = if p.held {
            (p.hold_until, Edge::Release)
        } else {
            (p.next_periodic, Edge::Periodic)
        };
        if at <= t_end {
            (t_end, edge) = (at, kind);
        }
        let t_end = t_end.min(self.t_max);
        if p.held {
            self.hold_to(p, obs, sc, t_end);
        } else {
            flow_segment(self, p, obs, sc, t_end);
        }
        if t_end >= self.t_max {
            p.done = true;
            return;
        }
        p.events += 1;
        match edge {
            Edge::Release => {
                p.held = false;
                p.a = self.tab.segs[p.si].at(p.a.v);
            }
            Edge::Periodic => self.reset_scheduled(p),
            Edge::Clock if p.held => p.si = self.noise.draw_jump(si, &mut p.rng),
            Edge::Clock => match self.noise.event(si, p.rng.gen::<f64>() * rate) {
                Some(j) => {
                    p.si = j;
                    p.a = self.tab.segs[j].at(p.a.v);
                }
                None => self.reset_scheduled(p),
            },
        }
    }

    /// A reset with the schedule's modifiers at p.t: velocity and noise by
    /// the rule, x → x_r with position resetting, then a refractory period
    /// (held at the reset velocity) if any; the next periodic time is the
    /// first one after the reset, or after the refractory period.
    fn reset_scheduled(&self, p: &mut Lane) {
        let v = self.draw_reset(p);
        p.a = self.reset_point(p.si, v);
        if let Some(x) = self.x_reset {
            p.x = x;
        }
        let mut free = p.t;
        if let Some(r) = self.refractory {
            p.held = true;
            p.hold_until = p.t + r.draw(&mut p.rng);
            free = p.hold_until;
        }
        if self.schedule.scheduled_clock() {
            p.next_periodic = self.schedule.next_reset(free, &mut p.rng);
        }
    }

    /// A held segment (refractory period) from p.t to `t_end`: v constant
    /// at p.a.v, x linear in t, the held velocity's bin (or its atom)
    /// occupied.
    fn hold_to(&self, p: &mut Lane, obs: &mut Observables, sc: &mut Scratch, t_end: f64) {
        let (t, v) = (p.t, p.a.v);
        while p.k < self.times.len() && self.times[p.k] <= t_end {
            let xk = p.x + v * (self.times[p.k] - t);
            obs.record(p.k, v, xk);
            p.msd += obs.msd_term(p.k, xk);
            p.k += 1;
        }
        if t_end > self.burn_in {
            let dw = t_end - t.max(self.burn_in);
            p.int_v += v * dw;
            p.int_v2 += v * v * dw;
            if obs.is_atom(v) {
                p.at_atom += dw;
            } else {
                sc.occ[obs.bin_of(v)] += dw;
            }
        }
        p.x += v * (t_end - t);
        p.t = t_end;
    }

    /// Close a particle: full bin crossings (occupation += crossings × tau)
    /// and its contribution to the observables.
    fn finish(&self, p: &Lane, obs: &mut Observables, sc: &mut Scratch) {
        for (cross, tau) in sc.cross.iter_mut().zip(&self.tab.tau) {
            add_crossings(cross, &mut sc.occ, tau);
        }
        close_particle(p, obs, &mut sc.occ, self.t_max - self.burn_in);
    }

    /// Particles `ids` one after the other. (Interleaving four particles
    /// per thread, one event of each in turn, measured no faster: the
    /// event's chain is short next to its instruction count.)
    pub(crate) fn particles(&self, ids: Range<u64>, obs: &mut Observables, sc: &mut Scratch) {
        for i in ids {
            let mut p = self.start(i);
            if self.plain {
                while !p.done {
                    self.step(&mut p, obs, sc);
                }
            } else {
                while !p.done {
                    self.step_scheduled(&mut p, obs, sc);
                }
            }
            self.finish(&p, obs, sc);
        }
    }
}

/// The per-state tables as the segment code reads them, by noise state:
/// its segments, fixed point v*, 1/g'(v*) and the flow potential at the
/// bin edges, and the recording window ([`Sampler`] reads them from its
/// `Tables`); each entry is read where the segment code needs it (measured:
/// building a per-state view up front cost the two-state loop 3 % CPU
/// time).
trait StateTables<F> {
    fn seg(&self, si: usize) -> &Segments<F>;
    fn fixed_point(&self, si: usize) -> f64;
    fn inv_rate(&self, si: usize) -> f64;
    fn phi_edges(&self, si: usize) -> &[f64];
    /// (grid times, burn-in).
    fn window(&self) -> (&[f64], f64);
}

/// Occupation times and per-state crossing difference arrays of a chunk.
trait Occupation {
    fn occ(&mut self) -> &mut [f64];
    fn cross(&mut self, si: usize) -> &mut [i64];
}

/// The flow segment of a particle from p.t to `t_end` under its noise
/// state: moments at the grid times inside (p.t, t_end], the window
/// integrals and occupation times, the position; returns (and stores) the
/// end point.
#[inline(always)]
fn flow_segment<F: FlowMap, T: StateTables<F>, S: Occupation>(
    tab: &T,
    p: &mut Lane,
    obs: &mut Observables,
    sc: &mut S,
    t_end: f64,
) -> FlowPoint {
    let (t, si, a) = (p.t, p.si, p.a);
    let seg = tab.seg(si);
    let vs = tab.fixed_point(si);
    let (times, burn_in) = tab.window();
    // Moments at grid times inside (t, t_end].
    while p.k < times.len() && times[p.k] <= t_end {
        let dt = times[p.k] - t;
        let pk = seg.advance(&a, dt);
        let xk = p.x + vs * dt - (a.q[0] - pk.q[0]);
        obs.record(p.k, pk.v, xk);
        p.msd += obs.msd_term(p.k, xk);
        p.k += 1;
    }
    let dt = t_end - t;
    let b = seg.advance(&a, dt);
    // Stationary window [burn_in, t_max].
    if t_end > burn_in {
        let (w, dw) = if t < burn_in {
            (seg.advance(&a, burn_in - t), t_end - burn_in)
        } else {
            (a, dt)
        };
        let (j1, j2) = (w.q[0] - b.q[0], w.q[1] - b.q[1]);
        p.int_v += vs * dw - j1;
        p.int_v2 += vs * vs * dw - 2.0 * vs * j1 + j2;
        // Resting exactly at the law's atom: its own account, no bin.
        if w.v == b.v && obs.is_atom(b.v) {
            p.at_atom += dw;
        } else {
            occupy(tab, obs, sc, si, &w, b.v, dw);
        }
    }
    p.x += vs * dt - (a.q[0] - b.q[0]);
    p.t = t_end;
    p.a = b;
    b
}

/// Add the occupation times of a flow segment a → b of duration dt:
/// partial first and last bins from flow potentials (time to an edge =
/// (Φ(va) - Φ(edge)) / g'(v*), edge potentials precomputed), bins crossed
/// in full via the difference array of crossings.
#[inline]
fn occupy<F, T: StateTables<F>, S: Occupation>(
    tab: &T,
    obs: &Observables,
    sc: &mut S,
    si: usize,
    a: &FlowPoint,
    vb: f64,
    dt: f64,
) {
    let (ka, kb) = (obs.bin_of(a.v), obs.bin_of(vb));
    if ka == kb {
        sc.occ()[ka] += dt;
        return;
    }
    let (pa, inv_k) = (a.phi, tab.inv_rate(si));
    let phi = tab.phi_edges(si);
    // Time to reach edge e (clamped into [0, dt] against rounding).
    let to = |e: usize| ((pa - phi[e]) * inv_k).clamp(0.0, dt);
    let (first, last, from, to_last) = if kb > ka {
        (ka + 1, kb, to(ka + 1), to(kb))
    } else {
        (kb + 1, ka, to(ka), to(kb + 1))
    };
    sc.occ()[ka] += from;
    if last > first {
        let cross = sc.cross(si);
        cross[first] += 1;
        cross[last] -= 1;
    }
    sc.occ()[kb] += dt - to_last;
}

/// Add the full bin crossings of one noise state to the occupation times
/// (occupation += crossings × tau) and clear its difference array.
#[inline]
fn add_crossings(cross: &mut [i64], occ: &mut [f64], tau: &[f64]) {
    let mut n = 0i64;
    // Branch-free: n × tau adds an exact 0 where no crossing is counted.
    for ((c, o), tau) in cross.iter_mut().zip(occ.iter_mut()).zip(tau) {
        n += *c;
        *c = 0;
        *o += n as f64 * tau;
    }
}

/// A particle's contribution to the observables, its crossings already in
/// `occ`; `window` = t_max - burn_in.
fn close_particle(p: &Lane, obs: &mut Observables, occ: &mut [f64], window: f64) {
    obs.finish_particle(
        p.int_v / window,
        p.int_v2 / window,
        occ,
        window,
        p.a.v,
        p.msd,
    );
    obs.finish_atom(p.at_atom, window, p.a.v);
    obs.record_final_position(p.x);
    obs.steps += p.events;
}

/// One particle in flight.
struct Lane {
    rng: Rng,
    /// Noise state (the paper's: 0 for +Sigma, 1 for -Sigma).
    si: usize,
    /// The start of the current segment.
    a: FlowPoint,
    t: f64,
    x: f64,
    /// Next grid time index.
    k: usize,
    int_v: f64,
    int_v2: f64,
    msd: f64,
    /// Time in the window spent exactly at the law's atom.
    at_atom: f64,
    events: u64,
    done: bool,
    /// Inside a refractory period (v held at p.a.v until `hold_until`).
    held: bool,
    hold_until: f64,
    /// The next periodic reset time (∞ without a periodic clock).
    next_periodic: f64,
}

impl<F, N> StateTables<F> for Sampler<F, N> {
    #[inline(always)]
    fn seg(&self, si: usize) -> &Segments<F> {
        &self.tab.segs[si]
    }
    #[inline(always)]
    fn fixed_point(&self, si: usize) -> f64 {
        self.tab.vs[si]
    }
    #[inline(always)]
    fn inv_rate(&self, si: usize) -> f64 {
        self.tab.inv_rate[si]
    }
    #[inline(always)]
    fn phi_edges(&self, si: usize) -> &[f64] {
        &self.tab.phi_edges[si]
    }
    #[inline(always)]
    fn window(&self) -> (&[f64], f64) {
        (&self.times, self.burn_in)
    }
}

impl Occupation for Scratch {
    #[inline(always)]
    fn occ(&mut self) -> &mut [f64] {
        &mut self.occ
    }
    #[inline(always)]
    fn cross(&mut self, si: usize) -> &mut [i64] {
        &mut self.cross[si]
    }
}

/// Exp(rate) waiting time (∞ for rate 0), by the ziggurat sampler of
/// `rand_distr::Exp1` (exact in distribution, cheaper than -ln U).
#[inline]
pub fn exp_gap(rng: &mut Rng, rate: f64) -> f64 {
    if rate > 0.0 {
        let e: f64 = rng.sample(rand_distr::Exp1);
        e / rate
    } else {
        f64::INFINITY
    }
}

/// Simulate `spec.particles` particles exactly (no time step). Same
/// observables as the Euler method; `steps` counts events (flips + resets).
/// Bit-identical for any thread count.
pub fn simulate(params: &Params, spec: &SimSpec, progress: &dyn Progress) -> Result<Observables> {
    Ok(simulate_part(params, spec, Part::Whole, progress)?.remove(0))
}

/// The unit totals of units `units` of [`simulate`]'s run (see
/// [`crate::sim::simulate_units`]).
pub fn simulate_units(
    params: &Params,
    spec: &SimSpec,
    units: Range<u64>,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    simulate_part(params, spec, Part::Units(units), progress)
}

fn simulate_part(
    params: &Params,
    spec: &SimSpec,
    part: Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    // Thermal noise: the Ornstein-Uhlenbeck segments of linear drag (the
    // constructor refuses any other drag, naming `temperature`).
    if params.noise().is_some_and(|m| m.temperature() > 0.0) {
        return ou::simulate(params, spec, part, progress);
    }
    crate::with_drag!(params.drag(), |d| simulate_drag(
        d, params, spec, part, progress
    ))
}

/// [`simulate_part`] for one law's type (monomorphised): the noise is
/// dispatched here, once, to the one event loop over its states (the
/// paper's two-state noise, or a finite-state chain).
fn simulate_drag<D: Drag>(
    drag: &D,
    params: &Params,
    spec: &SimSpec,
    part: Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    if params.noise().is_some() {
        run_noise::<D, Chain>(drag, params, spec, part, progress)
    } else {
        run_noise::<D, Telegraph>(drag, params, spec, part, progress)
    }
}

/// The run's particles with the noise states `N`. The accumulator carries
/// the per-chunk [`Scratch`]; only its observables are the result.
fn run_noise<D: Drag, N: ExactNoise>(
    drag: &D,
    params: &Params,
    spec: &SimSpec,
    part: Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    let sampler = Sampler::<D::Flow, N>::new(drag, params, spec)?;
    Ok(reduce_particles(
        (params, spec),
        part,
        progress,
        || sampler.scratch(spec.bins),
        |ids, obs, sc| sampler.particles(ids, obs, sc),
    ))
}

/// The observables of the run's particles (`spec.first_particle` on, in
/// `part`'s units), each chunk with its own observables and the sampler's
/// scratch from `scratch`, `run` simulating a range of particle indices;
/// merged from sums (the reduction every exact loop shares).
pub(super) fn reduce_particles<Sc, I, R>(
    (params, spec): (&Params, &SimSpec),
    part: Part,
    progress: &dyn Progress,
    scratch: I,
    run: R,
) -> Vec<Observables>
where
    Sc: Send,
    I: Fn() -> Sc + Sync,
    R: Fn(Range<u64>, &mut Observables, &mut Sc) + Sync,
{
    let template = Observables::new(spec, params);
    let first = spec.first_particle;
    let totals = part.reduce(
        spec.particles,
        || (template.clone(), scratch()),
        |lo, hi, (obs, sc)| run(first + lo..first + hi, obs, sc),
        |a, b| a.0.merge(&b.0),
        progress,
    );
    totals.into_iter().map(|(obs, _)| obs).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    /// The two segment kinds (tables in Φ, iterative solve) agree to
    /// rounding: velocity, potential and deficit integrals (also for the
    /// power law with n < 1, g'(0) = ∞).
    #[test]
    fn table_and_solve_segments_agree() {
        let power = |n: f64| DragLaw::Power(crate::model::drag::Power::new(n, 1.0).unwrap());
        // Velocity tolerance in units of 1 + v_u: the power law's table
        // is resolved to the noise of its values, ε |Φ| |dv/dΦ| with
        // |dv/dΦ| up to 260 (see the potential table's own test).
        for (d, sg, tol) in [
            (DragLaw::Tan, 3.0, 1e-14),
            (DragLaw::Tanh, 0.6, 1e-14),
            (DragLaw::Cubic, 3.0, 1e-14),
            (power(0.5), 3.0, 1e-13),
            (power(0.3), 3.0, 1e-13),
        ] {
            let p = Params::new(d.clone(), sg, 1.0, 0.0, 0.0).unwrap();
            let (lo, hi) = p.bounds();
            for s in [sg, -sg] {
                let table = Segments::Table(PotentialTable::new(&d, s).unwrap());
                let solve = Segments::Solve(
                    d.flow(s).accelerated(),
                    DeficitTable::new(&d, s, lo, hi).unwrap(),
                );
                for i in 0..=16 {
                    let v = lo + (hi - lo) * i as f64 / 16.0 * 0.999;
                    let (a, b) = (table.at(v), solve.at(v));
                    for dt in [0.0, 1e-6, 0.1, 1.0, 10.0] {
                        let (ta, sa) = (table.advance(&a, dt), solve.advance(&b, dt));
                        let (ja, jb) = (
                            [a.q[0] - ta.q[0], a.q[1] - ta.q[1]],
                            [b.q[0] - sa.q[0], b.q[1] - sa.q[1]],
                        );
                        assert!((ta.v - sa.v).abs() < tol * (1.0 + hi), "{d} {s} {v} {dt}");
                        assert!(
                            ta.phi == sa.phi
                                || (ta.phi - sa.phi).abs() < 1e-14 * (1.0 + a.phi.abs()),
                            "{d} {s} {v} {dt}: {} {}",
                            ta.phi,
                            sa.phi
                        );
                        // Each path's deficit is a difference of its own
                        // antiderivatives, which round at ε of their size
                        // (the solve's Ψ reach 5e4 for the power law n = 0.3).
                        for k in 0..2 {
                            let scale = 1.0 + a.q[k].abs() + b.q[k].abs();
                            assert!(
                                (ja[k] - jb[k]).abs() < 1e-13 * scale,
                                "{d} {s} {v} {dt} {k}: {} {}",
                                ja[k],
                                jb[k]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn table_matches_quadrature() {
        // Extreme parameters (g'(v*) ~ 1e6 or 1e-6) lose a few digits: the
        // integrand spans many orders of magnitude.
        for (d, sg, tol) in [
            (DragLaw::Tan, 3.0, 1e-13),
            (DragLaw::Tan, 30.0, 1e-13),
            (DragLaw::Tanh, 0.6, 1e-13),
            (DragLaw::Tanh, 0.99, 1e-13),
            (DragLaw::Linear, 2.0, 1e-13),
            (DragLaw::Tan, 1000.0, 1e-11),
            (DragLaw::Tanh, 0.999999, 1e-11),
        ] {
            let p = Params::new(d.clone(), sg, 1.0, 0.0, 0.0).unwrap();
            let (lo, hi) = p.bounds();
            for s in [sg, -sg] {
                let tab = DeficitTable::new(&d, s, lo, hi).unwrap();
                for i in 0..=40 {
                    for j in [0, 7, 40] {
                        let va = lo + (hi - lo) * i as f64 / 40.0;
                        let vb = lo + (hi - lo) * j as f64 / 40.0;
                        let (a1, a2) = tab.deficits(va, vb);
                        let (b1, b2) = d.flow_deficits(s, va, vb);
                        let scale = 1.0 + b1.abs() + b2.abs();
                        assert!(
                            (a1 - b1).abs() < tol * scale && (a2 - b2).abs() < tol * scale,
                            "{d} s={s} {va}->{vb}: {a1} {b1} / {a2} {b2} ({} pieces)",
                            tab.pieces()
                        );
                    }
                }
            }
        }
    }
}
