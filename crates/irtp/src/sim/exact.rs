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
//! A particle is one walk of the event-to-event kernel the first-passage
//! and search samplers also run (`passage`: `Clocks::walk`) with this
//! sampler's observer (`Recorder`, the kernel's record mode: its own
//! random stream, bit for bit). The noise's state space is a type
//! parameter, dispatched once per run: the paper's two-state noise
//! ([`Telegraph`], its random draws bit for bit) or any finite-state noise
//! at T = 0 (docs/equations.md Eqs. (N10)-(N12): per level its own
//! segments, fixed point (possibly interior) and crossing times, events at
//! rate q_s + r in state s). Both share the per-state tables (`Tables`)
//! and the segment code (`Segments`, the recorder's segment, the
//! occupation and crossing times).
//!
//! The modifiers of the resetting rule ([`crate::model::reset::Schedule`])
//! are the kernel's: the next event is the earliest of the exponential
//! clock (noise jumps at rate q_s, the paper's flips at rate lambda, plus
//! Poisson resets at rate r outside a refractory period), the next
//! scheduled reset time (resets at T, 2T, ... from t = 0 with a periodic
//! clock; with a renewal clock a waiting time from the clock's law, drawn
//! at each reset and counted from it or from the end of its refractory
//! period) and the end of a refractory period. A reset sends x to x_r
//! with position resetting; a refractory period is a held segment: v
//! constant at the reset velocity, x linear in t, the occupation of the
//! held velocity's bin and the time averages exact; the noise jumps during
//! it (state-dependent rate q_s), reset-clock events are ignored (the
//! periodic times inside it or at its end skipped), and the flow resumes
//! from the held velocity with the noise state of that moment. An event
//! at t acts just after t: a recording time equal to a periodic reset
//! time sees the state before it.
//!
//! With thermal noise (T > 0) and linear drag a second loop, `ou`, runs the
//! same event clock with exact Ornstein-Uhlenbeck segments in between
//! (Eqs. (N40)-(N45)), Poisson resetting only (a schedule modifier is
//! refused naming its flag); any other drag at T > 0 is refused naming
//! `temperature`.

use crate::error::{Error, Result};
use crate::model::drag::{FlowMap, FlowPoint, PotentialTable};
use crate::model::noise::chain::Chain;
use crate::model::reset::{Reset, Solver};
use crate::model::{Drag, Params};
use crate::numerics::chebyshev::{
    self, clenshaw, clenshaw2, Adaptive, Piece, Refine, Unresolved, NC,
};
use crate::parallel::Progress;
use crate::rng::{self, Rng};
use crate::sim::{Observables, Part, SimSpec};
use passage::{Clocks, Flow, Mode, Observer};
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

/// Everything fixed for a run: the noise's clocks and the resetting
/// protocol ([`Clocks`]), the tables, the recording window.
pub(crate) struct Sampler<F, N> {
    clocks: Clocks<N>,
    tab: Tables<F>,
    /// The segment start at the point target v_r, per noise state.
    at_vr: Option<Vec<FlowPoint>>,
    times: Vec<f64>,
    burn_in: f64,
    t_max: f64,
    seed: u64,
    /// Position resetting: x_r.
    x_reset: Option<f64>,
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
        let reset = params.reset();
        Ok(Sampler {
            at_vr: reset
                .point()
                .map(|vr| tab.segs.iter().map(|s| s.at(vr)).collect()),
            clocks: Clocks::new(noise, params),
            tab,
            x_reset: params.schedule().position.map(|p| p.x),
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
            cross: vec![vec![0; bins]; self.tab.segs.len()],
        }
    }

    /// Particles `ids` one after the other, each a walk of the kernel
    /// ([`Clocks::walk`]) from v = 0 in a drawn noise state with its
    /// [`Recorder`]. (Interleaving four particles per thread, one event of
    /// each in turn, measured no faster: the event's chain is short next
    /// to its instruction count.)
    pub(crate) fn particles(&self, ids: Range<u64>, obs: &mut Observables, sc: &mut Scratch) {
        for i in ids {
            let mut rng = rng::stream(self.seed, i);
            let s = self.clocks.noise.start(None, &mut rng);
            let mut rec = Recorder {
                sampler: self,
                obs: &mut *obs,
                sc: &mut *sc,
                a: self.tab.segs[s].at(0.0),
                x: 0.0,
                k: 0,
                int_v: 0.0,
                int_v2: 0.0,
                msd: 0.0,
                at_atom: 0.0,
            };
            let (_, events) = self.clocks.walk(s, self.t_max, &mut rng, &mut rec);
            rec.finish(events);
        }
    }
}

/// The simulation's observer of the walk kernel ([`passage`],
/// [`Mode::Record`]): one particle's moments at the grid times, its time
/// averages and occupation times over [burn_in, t_max] (or its time at
/// the law's atom), and x; a reset sends x to x_r with position
/// resetting, a hold is v constant, x linear in t.
struct Recorder<'a, F, N> {
    sampler: &'a Sampler<F, N>,
    obs: &'a mut Observables,
    sc: &'a mut Scratch,
    /// The start of the current segment (its end after a Moved; the held
    /// velocity's point during a hold).
    a: FlowPoint,
    x: f64,
    /// Next grid time index.
    k: usize,
    int_v: f64,
    int_v2: f64,
    msd: f64,
    /// Time in the window spent exactly at the law's atom.
    at_atom: f64,
}

impl<F: FlowMap, N: ExactNoise> Observer for Recorder<'_, F, N> {
    const MODE: Mode = Mode::Record;
    #[inline(always)]
    fn flow(&mut self, s: usize, t: f64, _: f64, end: f64, t_max: f64) -> Flow {
        let t_end = end.min(t_max);
        self.segment(s, t, t_end);
        if t_end >= t_max {
            Flow::Done(None)
        } else {
            Flow::Moved
        }
    }
    #[inline(always)]
    fn jump(&mut self, _: usize, j: usize) {
        self.a = self.sampler.tab.segs[j].at(self.a.v);
    }
    #[inline(always)]
    fn reset(&mut self, _: f64, v: f64, _: usize, after: usize) -> Option<f64> {
        self.a = self.sampler.reset_point(after, v);
        if let Some(x) = self.sampler.x_reset {
            self.x = x;
        }
        None
    }
    fn held(&mut self, t: f64, end: f64, t_max: f64) -> Flow {
        let t_end = end.min(t_max);
        self.hold_to(t, t_end);
        if t_end >= t_max {
            Flow::Done(None)
        } else {
            Flow::Moved
        }
    }
    #[inline(always)]
    fn resume(&mut self, _: f64, s: usize, held: Option<f64>) {
        if held.is_some() {
            self.a = self.sampler.tab.segs[s].at(self.a.v);
        }
    }
}

impl<F: FlowMap, N> Recorder<'_, F, N> {
    /// The flow segment from `t` to `t_end` in noise state `si`: moments
    /// at the grid times inside (t, t_end], the window integrals and
    /// occupation times, the position; the end point becomes the start.
    #[inline(always)]
    fn segment(&mut self, si: usize, t: f64, t_end: f64) {
        let (tab, a) = (&self.sampler.tab, self.a);
        let (seg, vs) = (&tab.segs[si], tab.vs[si]);
        let (times, burn_in) = (&self.sampler.times, self.sampler.burn_in);
        // Moments at grid times inside (t, t_end].
        while self.k < times.len() && times[self.k] <= t_end {
            let dt = times[self.k] - t;
            let pk = seg.advance(&a, dt);
            let xk = self.x + vs * dt - (a.q[0] - pk.q[0]);
            self.obs.record(self.k, pk.v, xk);
            self.msd += self.obs.msd_term(self.k, xk);
            self.k += 1;
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
            self.int_v += vs * dw - j1;
            self.int_v2 += vs * vs * dw - 2.0 * vs * j1 + j2;
            // Resting exactly at the law's atom: its own account, no bin.
            if w.v == b.v && self.obs.is_atom(b.v) {
                self.at_atom += dw;
            } else {
                occupy(tab, self.obs, self.sc, si, &w, b.v, dw);
            }
        }
        self.x += vs * dt - (a.q[0] - b.q[0]);
        self.a = b;
    }

    /// A held piece (refractory period) from `t` to `t_end`: v constant at
    /// the held velocity, x linear in t, its bin (or its atom) occupied.
    fn hold_to(&mut self, t: f64, t_end: f64) {
        let (v, times, burn_in) = (self.a.v, &self.sampler.times, self.sampler.burn_in);
        while self.k < times.len() && times[self.k] <= t_end {
            let xk = self.x + v * (times[self.k] - t);
            self.obs.record(self.k, v, xk);
            self.msd += self.obs.msd_term(self.k, xk);
            self.k += 1;
        }
        if t_end > burn_in {
            let dw = t_end - t.max(burn_in);
            self.int_v += v * dw;
            self.int_v2 += v * v * dw;
            if self.obs.is_atom(v) {
                self.at_atom += dw;
            } else {
                self.sc.occ[self.obs.bin_of(v)] += dw;
            }
        }
        self.x += v * (t_end - t);
    }

    /// Close the particle after `events` events: full bin crossings
    /// (occupation += crossings × tau) and its contribution to the
    /// observables.
    fn finish(self, events: u64) {
        let (sc, obs) = (self.sc, self.obs);
        for (cross, tau) in sc.cross.iter_mut().zip(&self.sampler.tab.tau) {
            add_crossings(cross, &mut sc.occ, tau);
        }
        let window = self.sampler.t_max - self.sampler.burn_in;
        obs.finish_particle(
            self.int_v / window,
            self.int_v2 / window,
            &mut sc.occ,
            window,
            self.a.v,
            self.msd,
        );
        obs.finish_atom(self.at_atom, window, self.a.v);
        obs.record_final_position(self.x);
        obs.steps += events;
    }
}

/// Add the occupation times of a flow segment a → b of duration dt in
/// noise state si: partial first and last bins from flow potentials (time
/// to an edge = (Φ(va) - Φ(edge)) / g'(v*), edge potentials precomputed),
/// bins crossed in full via the difference array of crossings.
#[inline]
fn occupy<F>(
    tab: &Tables<F>,
    obs: &Observables,
    sc: &mut Scratch,
    si: usize,
    a: &FlowPoint,
    vb: f64,
    dt: f64,
) {
    let (ka, kb) = (obs.bin_of(a.v), obs.bin_of(vb));
    if ka == kb {
        sc.occ[ka] += dt;
        return;
    }
    let (pa, inv_k) = (a.phi, tab.inv_rate[si]);
    let phi = &tab.phi_edges[si];
    // Time to reach edge e (clamped into [0, dt] against rounding).
    let to = |e: usize| ((pa - phi[e]) * inv_k).clamp(0.0, dt);
    let (first, last, from, to_last) = if kb > ka {
        (ka + 1, kb, to(ka + 1), to(kb))
    } else {
        (kb + 1, ka, to(ka), to(kb + 1))
    };
    sc.occ[ka] += from;
    if last > first {
        let cross = &mut sc.cross[si];
        cross[first] += 1;
        cross[last] -= 1;
    }
    sc.occ[kb] += dt - to_last;
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
