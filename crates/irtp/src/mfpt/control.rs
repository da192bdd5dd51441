//! A martingale control variate for exact first passages.
//!
//! Flips (rate lambda) and Poisson resets (rate r) are the jumps of a marked
//! point process whose compensator is known. For any bounded function u(v, s)
//! of the state,
//!
//! M_T = Σ_jumps [u(after) - u(before)] - ∫_0^T (J u)(v(t), s(t)) dt,
//! J u(v, s) = lambda [u(v, -s) - u(v, s)] + r [E u(v_r', s') - u(v, s)],
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
//! segment with one flow-time evaluation (exact to rounding). Periodic,
//! renewal and refractory schedules are not Poisson clocks and are refused.

use super::backward::{self, BackwardOptions, Profile};
use super::exact::{FirstPassage, Tally};
use super::Problem;
use crate::error::{Error, Result};
use crate::model::drag::FlowMap;
use crate::model::reset::{NoiseAtReset, Reset};
use crate::parallel::{self, Progress};
use crate::rng;
use crate::stats::{Controlled, PairAcc};
use serde::{Deserialize, Serialize};

/// Default number of cells of the control function.
pub const CONTROL_CELLS: usize = 2048;

/// The piecewise-constant control function u on [v_l, v_t] of one upward
/// (canonical) problem, with the tables that integrate J u along the flows.
#[derive(Clone, Debug)]
pub struct PassageControl {
    /// Cell edges w_0 = v_l < ... < w_N = v_t.
    w: Vec<f64>,
    /// 1 / cell width.
    inv_h: f64,
    /// u on each cell, for the + and - states.
    u: [Vec<f64>; 2],
    /// J u without its reset-influx term: lambda u(-s) - (lambda + r) u(s).
    c: [Vec<f64>; 2],
    /// Prefix sums over cells (in the direction of each flow) of c × the
    /// cell's crossing time, and of the crossing times alone.
    ct: [Vec<f64>; 2],
    /// See `ct`.
    t: [Vec<f64>; 2],
    /// r E[u(v_r', s') | s]: the reset influx of J u in state s.
    influx: [f64; 2],
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
        let (lambda, r, reset, scheduled) = fpt.rates();
        if scheduled {
            return Err(Error::invalid(
                "reset",
                "periodic, renewal or refractory",
                "a Poisson reset clock for the passage-time control variate",
            ));
        }
        if !(2..=1 << 22).contains(&cells) {
            return Err(Error::invalid(
                "control_cells",
                cells,
                "2 <= cells <= 4194304",
            ));
        }
        let h = (vt - vl) / cells as f64;
        let mut w: Vec<f64> = (0..=cells).map(|i| vl + h * i as f64).collect();
        w[cells] = vt;
        let mid = |i: usize| 0.5 * (w[i] + w[i + 1]);
        let u: [Vec<f64>; 2] = [true, false].map(|p| (0..cells).map(|i| u(mid(i), p)).collect());
        if let Some(bad) = u.iter().flatten().find(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                method: "passage-time control variate",
                at: *bad,
            });
        }
        let q = lambda + r;
        let c: [Vec<f64>; 2] = [0, 1].map(|k| {
            (0..cells)
                .map(|i| lambda * u[1 - k][i] - q * u[k][i])
                .collect()
        });
        let flows = fpt.flows();
        // Crossing times: + flow upwards through every cell; - flow
        // downwards through cells 1.. (cell 0 holds its fixed point v_l).
        let cross_up: Vec<f64> = (0..cells).map(|i| flows[0].time(w[i], w[i + 1])).collect();
        let cross_down: Vec<f64> = (0..cells)
            .map(|i| {
                if i == 0 {
                    0.0
                } else {
                    flows[1].time(w[i + 1], w[i])
                }
            })
            .collect();
        let prefix = |d: &[f64], c: &[f64]| {
            let (mut s, mut sc) = (vec![0.0; cells + 1], vec![0.0; cells + 1]);
            for i in 0..cells {
                s[i + 1] = s[i] + d[i];
                sc[i + 1] = sc[i] + c[i] * d[i];
            }
            (s, sc)
        };
        let (t0, ct0) = prefix(&cross_up, &c[0]);
        let (t1, ct1) = prefix(&cross_down, &c[1]);
        let mut ctl = PassageControl {
            w,
            inv_h: 1.0 / h,
            u,
            c,
            ct: [ct0, ct1],
            t: [t0, t1],
            influx: [0.0; 2],
        };
        ctl.influx = [0, 1].map(|k| r * ctl.reset_mean(reset, k == 0));
        Ok(ctl)
    }

    /// E[u(v_r', s') | s before the reset]: the target's mass per cell
    /// (u = 0 beyond v_t, where the reset is the passage).
    fn reset_mean<R: Reset>(&self, reset: &R, plus: bool) -> f64 {
        let target = reset.target();
        let n = self.w.len() - 1;
        let (mut total, mut sum) = (target.mass(f64::NEG_INFINITY, f64::INFINITY), 0.0);
        if total == 0.0 {
            total = 1.0;
        }
        for i in 0..n {
            let m = target.mass(self.w[i], self.w[i + 1]);
            if m > 0.0 {
                let k = usize::from(!plus);
                let v = match reset.noise() {
                    NoiseAtReset::Kept => self.u[k][i],
                    NoiseAtReset::Redrawn => 0.5 * (self.u[0][i] + self.u[1][i]),
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

    /// u(v, plus).
    #[inline(always)]
    fn value(&self, v: f64, plus: bool) -> f64 {
        self.u[usize::from(!plus)][self.cell(v)]
    }

    /// ∫ J u dt along a flow segment (module docs).
    #[inline(always)]
    fn integral<F: FlowMap>(&self, flows: &[F; 2], plus: bool, va: f64, vb: f64, dt: f64) -> f64 {
        let k = usize::from(!plus);
        let (c, ct, t) = (&self.c[k], &self.ct[k], &self.t[k]);
        let n = self.w.len() - 1;
        let ia = self.cell(va);
        // The last + segment ends exactly at v_t = w_N: no partial cell.
        let ib = if plus && vb >= self.w[n] {
            n
        } else {
            self.cell(vb)
        };
        let inner = if ia == ib {
            c[ia] * dt
        } else if plus {
            let t1 = flows[0].time(va, self.w[ia + 1]);
            let last = if ib < n {
                c[ib] * (dt - t1 - (t[ib] - t[ia + 1]))
            } else {
                0.0
            };
            c[ia] * t1 + (ct[ib] - ct[ia + 1]) + last
        } else {
            let t1 = flows[1].time(va, self.w[ia]);
            let last = c[ib] * (dt - t1 - (t[ia] - t[ib + 1]));
            c[ia] * t1 + (ct[ia] - ct[ib + 1]) + last
        };
        inner + self.influx[k] * dt
    }
}

/// The running martingale of one walk: its jump sum and its compensator.
struct Martingale<'a, F> {
    ctl: &'a PassageControl,
    flows: &'a [F; 2],
    jumps: f64,
    compensator: f64,
}

impl<F: FlowMap> Tally for Martingale<'_, F> {
    #[inline(always)]
    fn flow(&mut self, plus: bool, va: f64, vb: f64, dt: f64) {
        self.compensator += self.ctl.integral(self.flows, plus, va, vb, dt);
    }
    #[inline(always)]
    fn jump(&mut self, v: f64, plus: bool, after: Option<(f64, bool)>) {
        let to = after.map_or(0.0, |(w, p)| self.ctl.value(w, p));
        self.jumps += to - self.ctl.value(v, plus);
    }
}

/// One walk of `fpt` with the martingale alongside: (passage time or None
/// past t_max, M_T, events).
pub fn controlled_walk<F: FlowMap>(
    fpt: &FirstPassage<F>,
    ctl: &PassageControl,
    (v0, vt, start_plus, t_max): (f64, f64, bool, f64),
    rng: &mut rng::Rng,
) -> (Option<f64>, f64, u64) {
    let mut m = Martingale {
        ctl,
        flows: fpt.flows(),
        jumps: 0.0,
        compensator: 0.0,
    };
    let (time, events) = fpt.walk(v0, vt, start_plus, t_max, rng, &mut m);
    (time, m.jumps - m.compensator, events)
}

/// Mergeable sums of a controlled first-passage run, split by starting
/// noise state (even particle index: +Sigma).
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
        let x = &profile.v;
        let j = x.partition_point(|&a| a <= v).clamp(1, x.len() - 1);
        let s = ((v - x[j - 1]) / (x[j] - x[j - 1])).clamp(0.0, 1.0);
        tau[j - 1] + s * (tau[j] - tau[j - 1])
    }
}

/// Controlled exact first passages of `problem`: `particles` walks
/// (particle i: stream (seed, i), +Sigma for even i), each with the
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
    // The martingale is that of the two-state flips; a noise model's
    // passages run in the N-state sampler, which has no control.
    if let Some(m) = problem.params().noise() {
        return Err(Error::invalid(
            "noise",
            m.spec(),
            "the paper's symmetric telegraph noise for the passage-time control variate (its \
             martingale is that of the two-state flips; mfpt --method exact runs a noise model \
             without it)",
        ));
    }
    let profile = backward::profile(problem, &BackwardOptions::with_cells(backward_cells))?;
    let (cp, swapped) = problem.canonical();
    let (vl, _) = cp.params().bounds();
    crate::with_drag!(cp.params().drag(), |d| {
        let fpt = FirstPassage::for_drag(d, cp.params(), true);
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
    parallel::reduce(
        particles,
        ControlledStats::default,
        |i, acc: &mut ControlledStats| {
            let mut rng = rng::stream(seed, i);
            let plus = i % 2 == 0;
            let start = (v0, vt, plus != swapped, t_max);
            let (time, m, events) = controlled_walk(fpt, ctl, start, &mut rng);
            acc.events += events;
            match time {
                Some(t) if plus => acc.plus.push(t, m),
                Some(t) => acc.minus.push(t, m),
                None => acc.censored += 1,
            }
        },
        |a, b| a.merge(&b),
        progress,
    )
}
