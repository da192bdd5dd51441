//! A martingale control variate for exact first passages.
//!
//! Flips (rate lambda) and Poisson resets (rate r) are the jumps of a marked
//! point process whose compensator is known. For any bounded function u(v, s)
//! of the state,
//!
//! M_T = Σ_jumps [u(after) - u(before)] - ∫_0^T (J u)(v(t), s(t)) dt,
//! J u(v, s) = lambda [u(v, -s) - u(v, s)] + r [E u(v_r', s') - u(v, s)],
//!
//! and with a noise model (any finite-state noise at T = 0, the N-state
//! walks of [`super::exact`]) J u(v, s) = Σ_j q_sj [u(v, j) - u(v, s)] +
//! r [E u(v_r', s') - u(v, s)], u(·, s) the N-state backward solution T_s
//! (Eqs. (N30)-(N31)); their start state s_0 is drawn from π, and M_T also
//! holds the mean-zero start term u(v_0, s_0) - Σ_s π_s u(v_0, s), so that
//! T - M_T = Σ_s π_s T_s(v_0) = τ for u = T_s;
//!
//! is a martingale with M_0 = 0 (no smoothness of u is needed: only the jump
//! rates enter), so E\[M_T\] = 0 at the passage time T, and the pairs (T, M_T)
//! give the control-variate estimate of tau = E\[T\] ([`PairAcc::controlled`]
//! with the exact mean 0; docs/equations.md, (D4)). When u is the solution
//! tau±(v) of the backward equations (Eqs. (26)-(27) with the drifts of the
//! simulated process), T - M_T = tau(v_0) for every path
//! (Dynkin's formula with L tau = -1, tau = 0 at the target): the closer u is
//! to it, the smaller the residual variance. The estimate stays unbiased for
//! *any* u; a poor u only costs variance, and the fitted coefficient makes it
//! never much worse than the plain mean.
//!
//! Here u is piecewise constant on N uniform cells of [v_l, v_t], with the
//! backward solution at each cell's midpoint. Along a flow segment the
//! integral of J u is then a sum of (constant × time spent in a cell):
//! prefix sums of the cells' exact flow-crossing times give it in O(1) per
//! segment with one flow-time evaluation (exact to rounding); a state's
//! flow rises through the cells below its fixed point and falls through
//! those above it. Periodic, renewal and refractory schedules are not
//! Poisson clocks and are refused (with a noise model by the sampler,
//! naming their flags).

use super::backward::{self, BackwardOptions, Profile};
use super::exact::{FirstPassage, Passage, Tally};
use super::Problem;
use crate::error::{Error, Result};
use crate::model::drag::FlowMap;
use crate::model::noise::chain::Chain;
use crate::model::reset::{NoiseAtReset, Reset, Schedule};
use crate::parallel::{self, Progress};
use crate::rng;
use crate::stats::{Controlled, PairAcc};
use serde::{Deserialize, Serialize};

/// Default number of cells of the control function.
pub const CONTROL_CELLS: usize = 2048;

/// The piecewise-constant control function u on [v_l, v_t] of one upward
/// (canonical) problem, with the tables that integrate J u along the flows.
/// Noise states are indices (the paper's: 0 = +Sigma, 1 = -Sigma).
#[derive(Clone, Debug)]
pub struct PassageControl {
    /// Cell edges w_0 = v_l < ... < w_N = v_t.
    w: Vec<f64>,
    /// 1 / cell width.
    inv_h: f64,
    /// u on each cell, per state.
    u: Vec<Vec<f64>>,
    /// J u without its reset-influx term, per state s:
    /// Σ_{j≠s} q_sj u(j) - (q_s + r) u(s).
    c: Vec<Vec<f64>>,
    /// Prefix sums over cells of c × the cell's crossing time by the
    /// state's flow (0 for the cell of its fixed point, never crossed).
    ct: Vec<Vec<f64>>,
    /// The same prefix sums of the crossing times alone.
    t: Vec<Vec<f64>>,
    /// r E[u(v_r', s') | s]: the reset influx of J u in state s.
    influx: Vec<f64>,
    /// π, for the start term of a walk started from it.
    pi: Vec<f64>,
    /// The walk's start state is drawn from π (a noise model's), so its
    /// start term enters M_T; the paper's start is stratified (none).
    drawn_start: bool,
}

/// The noise state space a [`PassageControl`] is built for: per state its
/// flow and fixed point, the jump rates q_sj (s ≠ j) and exit rates q_s,
/// the stationary law π, the Poisson reset rate r and the rule.
struct Space<'a, F, R> {
    flows: &'a [F],
    stars: Vec<f64>,
    q: Vec<Vec<f64>>,
    exit: Vec<f64>,
    pi: Vec<f64>,
    rate: f64,
    reset: &'a R,
}

/// Refuse a periodic, renewal or refractory schedule: the compensator
/// of the control variate is that of a Poisson reset clock.
fn poisson_clock(schedule: &Schedule) -> Result<()> {
    if schedule.scheduled_clock() || schedule.refractory.is_some() {
        return Err(Error::invalid(
            "reset",
            "periodic, renewal or refractory",
            "a Poisson reset clock for the passage-time control variate",
        ));
    }
    Ok(())
}

impl PassageControl {
    /// Tables for `fpt` (the sampler of the canonical problem on [vl, vt])
    /// with u(v, plus) = `u(v, plus)` at the midpoints of `cells` uniform
    /// cells. Refused under a periodic, renewal or refractory schedule.
    pub fn new<F: FlowMap>(
        fpt: &FirstPassage<F>,
        vl: f64,
        vt: f64,
        cells: usize,
        u: impl Fn(f64, bool) -> f64,
    ) -> Result<Self> {
        poisson_clock(fpt.schedule())?;
        let (lambda, r, reset) = fpt.rates();
        // The + flow rises through every cell, the - flow falls to v_l.
        let space = Space {
            flows: fpt.parts().0,
            stars: vec![f64::INFINITY, vl],
            q: vec![vec![0.0, lambda], vec![lambda, 0.0]],
            exit: vec![lambda, lambda],
            pi: vec![0.5, 0.5],
            rate: r,
            reset,
        };
        Self::build(&space, vl, vt, cells, |v, k| u(v, k == 0), false)
    }

    /// Tables for the N-state sampler `fpt` of a noise model (the
    /// canonical problem on [vl, vt]) with u(v, s) = `u(v, s)` at the
    /// midpoints of `cells` uniform cells.
    pub(super) fn for_states<F: FlowMap>(
        fpt: &Passage<F, Chain>,
        vl: f64,
        vt: f64,
        cells: usize,
        u: impl Fn(f64, usize) -> f64,
    ) -> Result<Self> {
        poisson_clock(fpt.schedule())?;
        let (flows, stars, chain, reset) = fpt.parts();
        let space = Space {
            flows,
            stars: stars.to_vec(),
            q: chain.q.clone(),
            exit: chain.exit.clone(),
            pi: chain.pi.clone(),
            rate: reset.rate(),
            reset,
        };
        Self::build(&space, vl, vt, cells, u, true)
    }

    fn build<F: FlowMap, R: Reset>(
        space: &Space<'_, F, R>,
        vl: f64,
        vt: f64,
        cells: usize,
        u: impl Fn(f64, usize) -> f64,
        drawn_start: bool,
    ) -> Result<Self> {
        if !(2..=1 << 22).contains(&cells) {
            return Err(Error::invalid(
                "control_cells",
                cells,
                "2 <= cells <= 4194304",
            ));
        }
        let ns = space.flows.len();
        let h = (vt - vl) / cells as f64;
        let mut w: Vec<f64> = (0..=cells).map(|i| vl + h * i as f64).collect();
        w[cells] = vt;
        let mid = |i: usize| 0.5 * (w[i] + w[i + 1]);
        let u: Vec<Vec<f64>> = (0..ns)
            .map(|k| (0..cells).map(|i| u(mid(i), k)).collect())
            .collect();
        if let Some(bad) = u.iter().flatten().find(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                method: "passage-time control variate",
                at: *bad,
            });
        }
        let c: Vec<Vec<f64>> = (0..ns)
            .map(|k| {
                let out = space.exit[k] + space.rate;
                (0..cells)
                    .map(|i| {
                        let into = (0..ns)
                            .filter(|&j| j != k)
                            .fold(0.0, |a, j| a + space.q[k][j] * u[j][i]);
                        into - out * u[k][i]
                    })
                    .collect()
            })
            .collect();
        let (t, ct): (Vec<_>, Vec<_>) = (0..ns)
            .map(|k| prefix(&crossings(&w, &space.flows[k], space.stars[k]), &c[k]))
            .unzip();
        let mut ctl = PassageControl {
            w,
            inv_h: 1.0 / h,
            u,
            c,
            ct,
            t,
            influx: Vec::new(),
            pi: space.pi.clone(),
            drawn_start,
        };
        ctl.influx = (0..ns)
            .map(|k| space.rate * ctl.reset_mean(space.reset, k))
            .collect();
        Ok(ctl)
    }

    /// E[u(v_r', s') | s before the reset]: the target's mass per cell
    /// (u = 0 beyond v_t, where the reset is the passage).
    fn reset_mean<R: Reset>(&self, reset: &R, k: usize) -> f64 {
        let target = reset.target();
        let n = self.w.len() - 1;
        let (mut total, mut sum) = (target.mass(f64::NEG_INFINITY, f64::INFINITY), 0.0);
        if total == 0.0 {
            total = 1.0;
        }
        for i in 0..n {
            let m = target.mass(self.w[i], self.w[i + 1]);
            if m > 0.0 {
                let v = match reset.noise() {
                    NoiseAtReset::Kept => self.u[k][i],
                    NoiseAtReset::Redrawn => {
                        (0..self.u.len()).fold(0.0, |a, j| a + self.pi[j] * self.u[j][i])
                    }
                };
                sum += m * v;
            }
        }
        sum / total
    }

    /// The cell i with w_i ≤ v < w_{i+1} (clamped to the cells).
    #[inline(always)]
    fn cell(&self, v: f64) -> usize {
        let n = self.w.len() - 1;
        let mut i = (((v - self.w[0]) * self.inv_h) as usize).min(n - 1);
        // The multiplication may round across an edge: settle on the table.
        if v < self.w[i] && i > 0 {
            i -= 1;
        } else if v >= self.w[i + 1] && i + 1 < n {
            i += 1;
        }
        i
    }

    /// u(v, s).
    #[inline(always)]
    fn value(&self, v: f64, k: usize) -> f64 {
        self.u[k][self.cell(v)]
    }

    /// Σ_s π_s u(v, s) - u(v, s0): the mean-zero start term of a walk
    /// started in s0 drawn from π.
    fn start_term(&self, v: f64, k: usize) -> f64 {
        if !self.drawn_start {
            return 0.0;
        }
        let i = self.cell(v);
        let mean = (0..self.u.len()).fold(0.0, |a, j| a + self.pi[j] * self.u[j][i]);
        self.u[k][i] - mean
    }

    /// ∫ J u dt along a flow segment of state k (module docs): the
    /// velocity moves monotonically from va to vb, upwards when it leaves
    /// its cell upwards.
    #[inline(always)]
    fn integral<F: FlowMap>(&self, flow: &F, k: usize, va: f64, vb: f64, dt: f64) -> f64 {
        let (c, ct, t) = (&self.c[k], &self.ct[k], &self.t[k]);
        let n = self.w.len() - 1;
        let ia = self.cell(va);
        // A segment ending at v_t = w_N (the passage): no partial cell.
        let ib = if vb >= self.w[n] { n } else { self.cell(vb) };
        let inner = if ia == ib {
            c[ia] * dt
        } else if ib > ia {
            let t1 = flow.time(va, self.w[ia + 1]);
            let last = if ib < n {
                c[ib] * (dt - t1 - (t[ib] - t[ia + 1]))
            } else {
                0.0
            };
            c[ia] * t1 + (ct[ib] - ct[ia + 1]) + last
        } else {
            let t1 = flow.time(va, self.w[ia]);
            let last = c[ib] * (dt - t1 - (t[ia] - t[ib + 1]));
            c[ia] * t1 + (ct[ia] - ct[ib + 1]) + last
        };
        inner + self.influx[k] * dt
    }
}

/// The time the flow of fixed point `star` takes to cross each cell of
/// the edges `w` in its direction (up below `star`, down above it); 0 for
/// the cell holding `star` and where the time is not finite (a cell the
/// flow never crosses).
fn crossings<F: FlowMap>(w: &[f64], flow: &F, star: f64) -> Vec<f64> {
    (0..w.len() - 1)
        .map(|i| {
            let d = if w[i] <= star && star <= w[i + 1] {
                0.0
            } else if star > w[i + 1] {
                flow.time(w[i], w[i + 1])
            } else {
                flow.time(w[i + 1], w[i])
            };
            if d.is_finite() {
                d
            } else {
                0.0
            }
        })
        .collect()
}

/// Prefix sums of the crossing times `d` and of `c` × `d` over the cells.
fn prefix(d: &[f64], c: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let cells = d.len();
    let (mut s, mut sc) = (vec![0.0; cells + 1], vec![0.0; cells + 1]);
    for i in 0..cells {
        s[i + 1] = s[i] + d[i];
        sc[i + 1] = sc[i] + c[i] * d[i];
    }
    (s, sc)
}

/// The running martingale of one walk: its jump sum and its compensator.
struct Martingale<'a, F> {
    ctl: &'a PassageControl,
    flows: &'a [F],
    jumps: f64,
    compensator: f64,
}

impl<'a, F> Martingale<'a, F> {
    fn new(ctl: &'a PassageControl, flows: &'a [F]) -> Self {
        Martingale {
            ctl,
            flows,
            jumps: 0.0,
            compensator: 0.0,
        }
    }
}

impl<F: FlowMap> Tally for Martingale<'_, F> {
    #[inline(always)]
    fn start(&mut self, v: f64, s: usize) {
        self.jumps += self.ctl.start_term(v, s);
    }
    #[inline(always)]
    fn flow(&mut self, s: usize, va: f64, vb: f64, dt: f64) {
        self.compensator += self.ctl.integral(&self.flows[s], s, va, vb, dt);
    }
    #[inline(always)]
    fn jump(&mut self, v: f64, s: usize, after: Option<(f64, usize)>) {
        let to = after.map_or(0.0, |(w, j)| self.ctl.value(w, j));
        self.jumps += to - self.ctl.value(v, s);
    }
}

/// One walk of `fpt` from noise state `start` (0: +Sigma, 1: -Sigma)
/// with the martingale alongside: (passage time or None past t_max, M_T,
/// events).
pub fn controlled_walk<F: FlowMap>(
    fpt: &FirstPassage<F>,
    ctl: &PassageControl,
    (v0, vt, start, t_max): (f64, f64, usize, f64),
    rng: &mut rng::Rng,
) -> (Option<f64>, f64, u64) {
    let mut m = Martingale::new(ctl, fpt.parts().0);
    let (time, events) = fpt.walk(v0, vt, start, t_max, rng, &mut m);
    (time, m.jumps - m.compensator, events)
}

/// Mergeable sums of a controlled first-passage run, split by starting
/// noise state (stratum 0, even particle index: +Sigma; stratum 1: -Sigma).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ControlledStats {
    /// (T, M_T) of the particles started in +Sigma.
    pub plus: PairAcc,
    /// (T, M_T) of the particles started in -Sigma.
    pub minus: PairAcc,
    /// Particles not arrived by t_max.
    pub censored: u64,
    /// Events in all.
    pub events: u64,
}

impl ControlledStats {
    fn merge(&mut self, o: &ControlledStats) {
        self.plus.merge(&o.plus);
        self.minus.merge(&o.minus);
        self.censored += o.censored;
        self.events += o.events;
    }

    /// Particles run.
    pub fn particles(&self) -> u64 {
        self.plus.n + self.minus.n + self.censored
    }

    /// The estimate of tau = (tau+ + tau-)/2, or an error when a particle was
    /// censored (the mean of the arrived ones is biased low).
    pub fn summary(&self) -> Result<ControlledPassage> {
        if self.censored > 0 {
            return Err(Error::Numerical {
                method: "controlled exact first passage",
                reason: format!(
                    "{} of {} particles had not arrived by t_max; raise t_max",
                    self.censored,
                    self.particles()
                ),
            });
        }
        let (p, m) = (self.plus.controlled(0.0), self.minus.controlled(0.0));
        let se = 0.5 * p.se.hypot(m.se);
        let plain_se = 0.5 * p.plain_se.hypot(m.plain_se);
        let n = (self.plus.n + self.minus.n) as f64;
        Ok(ControlledPassage {
            tau: 0.5 * (p.mean + m.mean),
            tau_err: se,
            plain: 0.5 * (p.plain + m.plain),
            plain_err: plain_se,
            equivalent_samples: n * (plain_se / se).powi(2),
            particles: self.particles(),
            events: self.events,
            plus: p,
            minus: m,
        })
    }
}

/// The controlled estimate of one first-passage problem.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ControlledPassage {
    /// tau = (tau+ + tau-)/2.
    pub tau: f64,
    /// Its standard error.
    pub tau_err: f64,
    /// The plain mean of the same passages.
    pub plain: f64,
    /// Its standard error.
    pub plain_err: f64,
    /// Plain (stratified) passages with the same standard error:
    /// particles × (plain_err / tau_err)².
    pub equivalent_samples: f64,
    /// Particles run.
    pub particles: u64,
    /// Events in all.
    pub events: u64,
    /// The + half.
    pub plus: Controlled,
    /// The - half.
    pub minus: Controlled,
}

/// u from a backward-equation profile of the user's problem, read in the
/// canonical frame (v → -v and the states swapped when the target lies
/// below v_0): linear interpolation between the profile's nodes.
fn profile_value(profile: &Profile, swapped: bool) -> impl Fn(f64, bool) -> f64 + '_ {
    move |v, plus| {
        let (v, plus) = if swapped { (-v, !plus) } else { (v, plus) };
        let tau = if plus {
            &profile.tau_plus
        } else {
            &profile.tau_minus
        };
        interpolate(&profile.v, tau, v)
    }
}

/// Controlled exact first passages of `problem`: `particles` walks
/// (particle i: stream (seed, i), +Sigma for even i; with a noise model the
/// N-state walks of [`super::exact`], started from π), each with the
/// martingale of a u taken from the backward equations on `backward_cells`
/// cells and held piecewise constant on `cells` cells. Bit-identical for
/// any thread count; the passage times are those of the plain sampler.
pub fn run(
    problem: &Problem,
    (particles, seed, t_max): (u64, u64, f64),
    cells: usize,
    backward_cells: usize,
    progress: &dyn Progress,
) -> Result<ControlledStats> {
    if problem.params().noise().is_some() {
        return run_states(
            problem,
            (particles, seed, t_max),
            cells,
            backward_cells,
            progress,
        );
    }
    let profile = backward::profile(problem, &BackwardOptions::with_cells(backward_cells))?;
    let (cp, swapped) = problem.canonical();
    let (vl, _) = cp.params().bounds();
    crate::with_drag!(cp.params().drag(), |d| {
        let fpt = FirstPassage::for_drag(d, cp.params());
        let ctl = PassageControl::new(&fpt, vl, cp.vt(), cells, profile_value(&profile, swapped))?;
        let start = (cp.v0(), cp.vt(), swapped);
        Ok(run_with(
            &fpt,
            &ctl,
            start,
            (particles, seed, t_max),
            progress,
        ))
    })
}

/// [`run`] with a noise model (any finite-state noise at T = 0): the
/// compensator J u(v, s) = Σ_j q_sj [u(v, j) - u(v, s)] + r [E u(v_r', s') -
/// u(v, s)], u(·, s) the N-state backward solution T_s (Eqs. (N30)-(N31))
/// in the canonical frame, and the start term Σ_s π_s u(v_0, s) - u(v_0,
/// s_0) of the drawn start state, so that T - M_T = τ for u = T_s.
fn run_states(
    problem: &Problem,
    (particles, seed, t_max): (u64, u64, f64),
    cells: usize,
    backward_cells: usize,
    progress: &dyn Progress,
) -> Result<ControlledStats> {
    super::exact::check_problem(problem)?;
    let (cp, _) = problem.canonical();
    let (v, per_state) = super::backward::canonical_states(problem, backward_cells)?;
    let (vl, _) = cp.params().bounds();
    let u = |x: f64, s: usize| interpolate(&v, &per_state[s], x);
    crate::with_drag!(cp.params().drag(), |d| {
        let fpt = Passage::<_, Chain>::build(d, cp.params())?;
        let ctl = PassageControl::for_states(&fpt, vl, cp.vt(), cells, u)?;
        let (flows, ..) = fpt.parts();
        Ok(reduce(particles, seed, progress, |_, rng| {
            let mut m = Martingale::new(&ctl, flows);
            let (time, events) = fpt.walk(cp.v0(), cp.vt(), 0, t_max, rng, &mut m);
            (time, m.jumps - m.compensator, events)
        }))
    })
}

/// y(x) by linear interpolation between the nodes (x_k, y_k), held
/// constant beyond them.
fn interpolate(x: &[f64], y: &[f64], v: f64) -> f64 {
    let j = x.partition_point(|&a| a <= v).clamp(1, x.len() - 1);
    let s = ((v - x[j - 1]) / (x[j] - x[j - 1])).clamp(0.0, 1.0);
    y[j - 1] + s * (y[j] - y[j - 1])
}

/// [`run`] with a given sampler and control, both of the canonical problem
/// from v0 to vt; `swapped`: the user's states are the canonical ones
/// swapped (the + and - halves are the user's).
pub fn run_with<F: FlowMap>(
    fpt: &FirstPassage<F>,
    ctl: &PassageControl,
    (v0, vt, swapped): (f64, f64, bool),
    (particles, seed, t_max): (u64, u64, f64),
    progress: &dyn Progress,
) -> ControlledStats {
    reduce(particles, seed, progress, |k, rng| {
        let start = if swapped { 1 - k } else { k };
        controlled_walk(fpt, ctl, (v0, vt, start, t_max), rng)
    })
}

/// `particles` controlled walks (particle i: stream (seed, i), `walk`
/// given its stratum i mod 2), stratum 0 (even i) in the `plus` half.
fn reduce(
    particles: u64,
    seed: u64,
    progress: &dyn Progress,
    walk: impl Fn(usize, &mut rng::Rng) -> (Option<f64>, f64, u64) + Sync,
) -> ControlledStats {
    parallel::reduce(
        particles,
        ControlledStats::default,
        |i, acc: &mut ControlledStats| {
            let mut rng = rng::stream(seed, i);
            let k = (i % 2) as usize;
            let (time, m, events) = walk(k, &mut rng);
            acc.events += events;
            match time {
                Some(t) if k == 0 => acc.plus.push(t, m),
                Some(t) => acc.minus.push(t, m),
                None => acc.censored += 1,
            }
        },
        |a, b| a.merge(&b),
        progress,
    )
}
