//! The state-resolved renewal route for full resetting (docs/equations.md,
//! "Search: the 2-D backward equation and the renewal route", (S5)-(S7)).
//!
//! A reset puts the particle back at (x_r, v_r) but keeps the noise state,
//! so the periods between resets are not independent of each other: the
//! textbook `T_r = E[min(T0, R)] / P(T0 < R)` (one start law for every
//! period) is wrong. Resolved by the noise state the renewal is exact:
//!
//!   T_s = a_s + Σ_s' B_ss' Σ_s'' mix(s', s'') T_s''(x_r, v_r),
//!   a_s = ∫ w(t) S_s(t) dt,  B_ss' = ∫ rho(t) P(T0 > t, eta(t) = s' | s) dt,
//!
//! over the waiting-time law of the resets (density rho, survival w: any
//! law of [`crate::model::reset::clock`], docs/equations.md (S5')-(S7');
//! the Poisson clock is `exp:rate=r`, periodic resetting `fixed:t=T`, a
//! point mass), with S and P(...) those of the
//! reset-free search started from (x_r, v_r, s) (from (x0, v0, s) for the
//! first period). mix is the noise rule (identity when kept, every row π
//! when re-drawn). A finite-state noise model runs alike over its N states
//! (B is N × N, solved by the elimination of [`super::backward`]); tau is
//! Σ_s π_s T_s, the start's state drawn from the stationary law π (the
//! paper's noise: π = (1/2, 1/2)). A random velocity target weighs the
//! reset-point quantities by its node weights.
//!
//! P(T0 > t, eta(t) = s' | start) = Q_s'(t) solves the reset-free backward
//! equation ∂t Q = L0 Q with Q(0) = 1[eta = s'] and Q = 0 on the target:
//! integrated for every s' on the upwind mesh of the direct solver
//! ([`super::backward`]) by TR-BDF2 with a fixed step (the stepper of
//! [`super::distribution`]; one factorisation of
//! `I - (γ/2) dt A`, γ = 2 - √2), on the steps dt and dt/2 (Richardson,
//! second order), and on the meshes h and h/2 (first order). The integrals
//! stop at the horizon t_max where w(t_max) is below `tail` (at the latest
//! at the end of a bounded law's support: the period); the neglected tail
//! is bounded by the law's ∫_{t_max}^∞ w and w(t_max) (S, Q ≤ 1) and
//! reported. A level under a law of infinite mean is reported infinite
//! (the exact sampler's verdict, [`SearchProblem::infinite_mean_reason`]);
//! an interval under such a law is refused naming `reset_clock` (the
//! neglected tail has no finite bound). The integrals are product integration
//! from the law's CDF (exact for Q linear between steps),
//! and the escape chances P(T0 < R) = ∫ rho (1 - S) + P(R > t_max) are
//! integrated directly: 1 - Σ B would cancel when the target is rarely
//! reached between resets (about 2e-3 at r = 3 in the tests).

use super::backward::{
    build, check_budget, cost_of, factor, mesh_drivers, mesh_info, renew as renew_states,
    truncation_factor, verify, with_check, Cost, Ladder, MeshInfo, Plan, Resetting, Setup, Watch,
};
use super::distribution::Stepper;
use super::mesh::{Generator, Mesh};
use super::yes;
use super::SearchProblem;
use crate::error::{Error, Result};
use crate::model::reset::clock::{Clock, ExpClock, FixedClock};
use crate::model::reset::{Periodic, Schedule};
use crate::parallel::{NoProgress, Progress};
use crate::Params;
use serde::{Deserialize, Serialize};

/// The clock of the resets: which [`Clock`] law the renewal integrals run
/// over (one home for every law: [`crate::model::reset::clock`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum WaitingTime {
    /// Poisson clock of rate r (`--rate`): the law `exp:rate=r`.
    Poisson {
        /// Rate r > 0.
        rate: f64,
    },
    /// Periodic (sharp) resetting every T (`--reset-period`): the law
    /// `fixed:t=T`.
    Periodic {
        /// Period T > 0.
        period: f64,
    },
    /// A renewal clock (`--reset-clock`).
    Renewal {
        /// The waiting-time law.
        clock: Clock,
    },
}

impl WaitingTime {
    /// The clock of `p`: its period if periodic, its renewal clock, else
    /// its Poisson rate (refused if 0: no resets).
    pub fn of(p: &Params) -> Result<Self> {
        match (p.schedule().periodic, p.schedule().clock.clone()) {
            (Some(t), _) => Ok(WaitingTime::Periodic { period: t.period }),
            (None, Some(clock)) => Ok(WaitingTime::Renewal { clock }),
            (None, None) if p.rate() > 0.0 => Ok(WaitingTime::Poisson { rate: p.rate() }),
            (None, None) => Err(Error::invalid(
                "rate",
                p.rate(),
                "rate > 0 (or a reset period or clock)",
            )),
        }
    }

    /// The waiting-time law.
    pub fn law(&self) -> Clock {
        match *self {
            WaitingTime::Poisson { rate } => Clock::Exp(ExpClock { rate }),
            WaitingTime::Periodic { period } => Clock::Fixed(FixedClock { t: period }),
            WaitingTime::Renewal { ref clock } => clock.clone(),
        }
    }

    /// A finite, positive rate or period; a law whose neglected tail has a
    /// finite bound at the horizon of `tail` (refused by name otherwise:
    /// an infinite mean leaves ∫_t^∞ W unbounded).
    fn validate(&self, tail: f64) -> Result<()> {
        let (name, x) = match *self {
            WaitingTime::Poisson { rate } => ("rate", rate),
            WaitingTime::Periodic { period } => ("reset_period", period),
            WaitingTime::Renewal { ref clock } => {
                let t = clock.horizon(tail);
                if !(t.is_finite() && clock.tail_integral(t).is_finite()) {
                    return Err(Error::invalid(
                        "reset_clock",
                        clock.spec(),
                        "a law with a finite mean for the renewal route (the part of the \
                         integrals beyond the horizon, bounded by the tail integral of W, is \
                         infinite for an infinite mean; the exact sampler runs it)",
                    ));
                }
                return Ok(());
            }
        };
        if !(x > 0.0 && x.is_finite()) {
            return Err(Error::invalid(name, x, "a positive finite number"));
        }
        Ok(())
    }

    /// Where the integrals stop: the smallest t with W(t) ≤ `tail`
    /// (the period, or the end of a bounded law's support, at the latest).
    pub fn horizon(&self, tail: f64) -> f64 {
        let law = self.law();
        law.horizon(tail).min(law.support_end())
    }

    /// Bounds on what the integrals miss beyond `t`: (∫_t^∞ w, w(t)), the
    /// largest possible parts of a_s and of Σ_s' B_ss' (S, Q ≤ 1).
    pub fn tail(&self, t: f64) -> (f64, f64) {
        let law = self.law();
        (law.tail_integral(t), law.survival(t))
    }

    /// Weights on t_n = n t_max / steps of ∫ w f dt and ∫ rho f dt for f
    /// linear between the t_n (product integration: exact for such f, so
    /// the rho weights sum to P(R ≤ t_max) exactly), and P(R > t_max).
    fn weights(&self, t_max: f64, steps: usize) -> (Vec<f64>, Vec<f64>, f64) {
        self.law().renewal_weights(t_max, steps)
    }

    /// Whether the law's support is unbounded (the far cut of a one-sided
    /// level then scales with the horizon, as for a Poisson clock).
    fn unbounded(&self) -> bool {
        !self.law().support_end().is_finite()
    }
}

/// Options of the renewal route.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenewalOptions {
    /// Cells of the coarse mesh across the near part of x (as
    /// [`super::backward::BackwardOptions::cells_x`]).
    pub cells_x: usize,
    /// Cells of the coarse mesh on (v_l, v_u).
    pub cells_v: usize,
    /// Solve on the mesh halved too and extrapolate (first order).
    pub refine: bool,
    /// As [`super::backward::BackwardOptions::climb`]: a mesh sequence
    /// that is not asymptotic refined within the budgets or refused;
    /// without it returned with `asymptotic` false and its error NaN.
    #[serde(default = "yes")]
    pub climb: bool,
    /// Time steps to the horizon (also run with twice as many).
    pub steps: usize,
    /// Poisson horizon: w(t_max) ≤ tail; the far side of a one-sided level
    /// is cut at X = v_u t_max (checked by a solve at 1.5 X).
    pub tail: f64,
    /// Refuse a solve estimated above this many floating-point operations.
    pub max_work: f64,
    /// Refuse a solve estimated above this many bytes.
    pub max_memory: f64,
}

impl Default for RenewalOptions {
    fn default() -> Self {
        RenewalOptions {
            cells_x: 32,
            cells_v: 16,
            refine: true,
            climb: true,
            steps: 100,
            tail: 1e-8,
            max_work: 1e11,
            max_memory: 4e9,
        }
    }
}

impl RenewalOptions {
    /// 2 ≤ cells ≤ 10⁵, 4 ≤ steps ≤ 10⁶, 0 < tail < 1, positive budgets.
    pub fn validate(&self) -> Result<()> {
        for (name, c) in [("cells_x", self.cells_x), ("cells_v", self.cells_v)] {
            if !(2..=100_000).contains(&c) {
                return Err(Error::invalid(name, c, format!("2 <= {name} <= 100000")));
            }
        }
        if !(4..=1_000_000).contains(&self.steps) {
            return Err(Error::invalid("steps", self.steps, "4 <= steps <= 1000000"));
        }
        if !(self.tail > 0.0 && self.tail < 1.0) {
            return Err(Error::invalid("tail", self.tail, "0 < tail < 1"));
        }
        for (name, b) in [("max_work", self.max_work), ("max_memory", self.max_memory)] {
            if !(b > 0.0) {
                return Err(Error::invalid(name, b, "a positive budget"));
            }
        }
        Ok(())
    }
}

/// Mean first-passage time by the renewal route.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenewalSolution {
    /// tau = Σ_s π_s T(x0, v0, s): the noise state at the start drawn from
    /// the stationary law π (the paper's noise: (tau+ + tau-)/2).
    pub tau: f64,
    /// Start in the +Sigma state (the paper's noise; NaN for another noise
    /// model: see `tau_states`).
    pub tau_plus: f64,
    /// Start in the -Sigma state (the paper's noise; NaN for another noise
    /// model: see `tau_states`).
    pub tau_minus: f64,
    /// T(x0, v0, s) for each state s of a noise model other than the
    /// paper's, in the model's state order; absent for the paper's noise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_states: Option<Vec<f64>>,
    /// T(x_r, v_r, ±) (the paper's noise; NaN for another noise model: see
    /// `reset_states`).
    pub reset_values: [f64; 2],
    /// T(x_r, v_r, s) for each state s of a noise model other than the
    /// paper's; absent for the paper's noise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reset_states: Option<Vec<f64>>,
    /// Error estimate of tau: mesh + time + truncation + tail (NaN without
    /// refinement).
    pub error_estimate: f64,
    /// |T_{h/2} - T_h| of tau (NaN without refinement).
    pub mesh_error: f64,
    /// |T_{dt/2} - T_dt| / 3 of tau (finest mesh).
    pub time_error: f64,
    /// |T_{1.5X} - T_X| of tau on the coarse mesh (0 without truncation).
    pub truncation_error: f64,
    /// Bound on what the horizon cuts off (0 for a periodic clock).
    pub tail_bound: f64,
    /// The textbook formula E[min(T0, R)] / P(T0 < R) for a start at the
    /// reset point with a random noise state, each period started afresh
    /// (wrong when the noise state is kept).
    pub textbook: f64,
    /// The finest mesh.
    pub mesh: MeshInfo,
    /// The mean search time is infinite
    /// ([`SearchProblem::infinite_mean_reason`]): tau = +∞, nothing solved.
    #[serde(default)]
    pub infinite_mean: bool,
    /// As [`super::backward::SearchSolution::asymptotic`].
    #[serde(default = "yes")]
    pub asymptotic: bool,
    /// Floating-point operations done, as
    /// [`super::backward::SearchSolution::work`] (what [`estimate`]
    /// predicts).
    #[serde(default)]
    pub work: f64,
}

impl RenewalSolution {
    /// The answer of a problem whose mean is infinite: tau = +∞, errors NaN.
    fn infinite() -> Self {
        let (inf, nan) = (f64::INFINITY, f64::NAN);
        RenewalSolution {
            tau: inf,
            tau_plus: inf,
            tau_minus: inf,
            tau_states: None,
            reset_values: [inf; 2],
            reset_states: None,
            error_estimate: nan,
            mesh_error: nan,
            time_error: nan,
            truncation_error: nan,
            tail_bound: nan,
            textbook: nan,
            mesh: MeshInfo::none(),
            infinite_mean: true,
            asymptotic: true,
            work: 0.0,
        }
    }
}

/// The renewal quantities at (x_r, v_r) and at (x0, v0) on one mesh and
/// time step, for N noise states.
#[derive(Clone, Debug, PartialEq)]
struct Periods {
    /// a_s at the reset point, then at the start.
    a: [Vec<f64>; 2],
    /// B_ss' (N × N) at the reset point, then at the start.
    b: [Vec<Vec<f64>>; 2],
    /// e_s = 1 - Σ_s' B_ss' = P(T0 < R), integrated as ∫ rho (1 - S) dt +
    /// P(R > t_max) (no cancellation when it is small), at the reset point.
    e: Vec<f64>,
}

/// The answer of one mesh and step: T(x0, v0, s), T(x_r, v_r, s), the
/// stationary law π, textbook, tail bound.
#[derive(Clone, Debug, PartialEq)]
struct Answer {
    tau: Vec<f64>,
    reset: Vec<f64>,
    pi: Vec<f64>,
    textbook: f64,
    tail: f64,
}

/// Σ_s π_s x_s, summed in state order (the paper's noise: 0.5 x+ + 0.5 x-,
/// which is (x+ + x-)/2 to the bit: halving is exact).
fn weighed(pi: &[f64], x: &[f64]) -> f64 {
    let mut terms = pi.iter().zip(x).map(|(p, x)| p * x);
    let first = terms.next().unwrap_or(0.0);
    terms.fold(first, |a, b| a + b)
}

impl Answer {
    fn mean(&self) -> f64 {
        weighed(&self.pi, &self.tau)
    }
    /// c0 self + c1 other, componentwise.
    fn combine(&self, c0: f64, other: &Answer, c1: f64) -> Answer {
        let f = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(x, y)| c0 * x + c1 * y).collect();
        Answer {
            tau: f(&self.tau, &other.tau),
            reset: f(&self.reset, &other.reset),
            pi: self.pi.clone(),
            textbook: c0 * self.textbook + c1 * other.textbook,
            tail: self.tail.max(other.tail),
        }
    }
}

/// The meshes of [`solve`] and the truncation distance.
fn meshes(setup: &Setup, waiting: &WaitingTime, opts: &RenewalOptions) -> Vec<Plan> {
    let x = setup.params.v_upper() * waiting.horizon(opts.tail);
    let layout = setup.layout((opts.cells_x, opts.cells_v), x);
    let mut out = vec![(layout.clone(), 0)];
    if opts.refine {
        out.push((layout.clone(), 1));
    }
    if setup.truncated() {
        out.push((layout.widened(1.5), 0));
    }
    out
}

/// Whether the mean search time is finite with the resets at the renewal
/// times of `waiting` ([`SearchProblem::infinite_mean_reason`] of the
/// problem with that clock): the verdict of the exact sampler.
fn finite_under(problem: &SearchProblem, waiting: &WaitingTime) -> bool {
    if WaitingTime::of(problem.params()).ok() == Some(waiting.clone()) {
        return problem.mean_is_finite();
    }
    let p = problem.params();
    let bare = Schedule {
        periodic: None,
        clock: None,
        ..*p.schedule()
    };
    let (rate, clocked) = match *waiting {
        WaitingTime::Poisson { rate } => (rate, bare.clone()),
        WaitingTime::Periodic { period } => (
            0.0,
            Schedule {
                periodic: Some(Periodic { period }),
                ..bare.clone()
            },
        ),
        WaitingTime::Renewal { ref clock } => (
            0.0,
            Schedule {
                clock: Some(clock.clone()),
                ..bare.clone()
            },
        ),
    };
    let q = p
        .with_schedule(bare)
        .and_then(|q| q.with_rate(rate))
        .and_then(|q| q.with_schedule(clocked));
    match q.and_then(|q| SearchProblem::new(q, problem.x0(), problem.v0(), problem.target())) {
        Ok(other) => other.mean_is_finite(),
        Err(_) => problem.mean_is_finite(),
    }
}

/// Estimated cost of [`solve`]: per mesh two factorisations (steps dt and
/// dt/2) and 2 × N × 3 `steps` band solves (two stages, N final states).
pub fn estimate(
    problem: &SearchProblem,
    waiting: &WaitingTime,
    opts: &RenewalOptions,
) -> Result<Cost> {
    opts.validate()?;
    let setup = Setup::new(problem, super::RENEWAL, true)?;
    if !finite_under(problem, waiting) {
        return Ok(Cost::NOTHING);
    }
    waiting.validate(opts.tail)?;
    let m = with_check(&setup, meshes(&setup, waiting, opts), opts.refine);
    let solves = cost_of(&m, per_step(&setup) * opts.steps as f64);
    // The clock's product-integration weights: two series of 2 steps + 1.
    let weights = 2.0 * 8.0 * (2.0 * opts.steps as f64 + 1.0);
    Ok(Cost {
        work: solves.work + cost_of(&m, 0.0).work,
        memory: solves.memory + weights,
    })
}

/// Mean first-passage time to the position target under full resetting
/// with resets at the renewal times of `waiting` (module docs; the clock of
/// the parameters is [`WaitingTime::of`]). Refuses (typed) velocity-only
/// resetting, refractory periods and a solve above the
/// budgets of `opts` ([`estimate`]).
pub fn solve(
    problem: &SearchProblem,
    waiting: &WaitingTime,
    opts: &RenewalOptions,
) -> Result<RenewalSolution> {
    solve_watched(problem, waiting, opts, &NoProgress)
}

/// [`solve`], its progress reported to `progress` in millions of
/// operations of the estimate (as [`super::backward::solve_watched`]).
pub fn solve_watched(
    problem: &SearchProblem,
    waiting: &WaitingTime,
    opts: &RenewalOptions,
    progress: &dyn Progress,
) -> Result<RenewalSolution> {
    let cost = estimate(problem, waiting, opts)?;
    check_budget(
        &cost,
        (opts.max_work, opts.max_memory),
        mesh_drivers(problem, &["steps", "tail"]),
    )?;
    if !finite_under(problem, waiting) {
        return Ok(RenewalSolution::infinite());
    }
    let watch = Watch::new(progress, cost.work);
    let setup = Setup::new(problem, super::RENEWAL, true)?;
    let plans = with_check(&setup, meshes(&setup, waiting, opts), opts.refine);
    let meshes = build(&plans);
    let t_max = waiting.horizon(opts.tail);
    let on = |m: &Mesh, steps: usize| answer(&setup, m, waiting, (t_max, steps), &watch);
    let in_time = |m: &Mesh| -> Result<(Answer, f64)> {
        let (a1, a2) = (on(m, opts.steps)?, on(m, 2 * opts.steps)?);
        let err = (a2.mean() - a1.mean()).abs() / 3.0;
        Ok((a2.combine(4.0 / 3.0, &a1, -1.0 / 3.0), err))
    };
    let (coarse, coarse_time) = in_time(&meshes[0])?;
    let (best, mesh_error, time_error, finest, asymptotic) = if opts.refine {
        let rungs = vec![
            in_time(&meshes[meshes.len() - 1])?,
            (coarse.clone(), coarse_time),
            in_time(&meshes[1])?,
        ];
        let ladder = Ladder {
            layout: &plans[0].0,
            cells: (opts.cells_x, opts.cells_v),
            budget: (opts.max_work, opts.max_memory),
            spent: cost.work,
            climb: opts.climb,
            method: METHOD,
            watch: &watch,
        };
        // The mesh differences are resolved down to the time errors.
        let top = ladder.climb(
            rungs,
            meshes[1].clone(),
            in_time,
            |(a, time)| (a.mean(), 3.0 * time),
            |p| level_cost(p, per_step(&setup) * opts.steps as f64),
        )?;
        let ((c, _), (f, fine_time)) = top.last_two();
        let e = top.factor.unwrap_or(1.0) * (f.mean() - c.mean()).abs();
        let best = f.combine(2.0, c, -1.0);
        (best, e, *fine_time, top.finest, top.factor.is_some())
    } else {
        (coarse, f64::NAN, coarse_time, meshes[0].clone(), true)
    };
    let truncation_error = if setup.truncated() {
        // The coarse mesh widened to 1.5 X follows the coarse and fine ones.
        let wide = on(&meshes[1 + opts.refine as usize], opts.steps)?;
        let diff = (wide.mean() - on(&meshes[0], opts.steps)?.mean()).abs();
        // Poisson: X = v_u ln(1/tail) / r, as for the direct solve; a
        // period T: X = v_u T is beyond the reach of the reset-free
        // particle, only the mesh's numerical spreading is cut.
        // A renewal law: as the Poisson clock when its support is
        // unbounded, as the period when bounded.
        if waiting.unbounded() {
            diff * truncation_factor(opts.tail)
        } else {
            diff
        }
    } else {
        0.0
    };
    // The extrapolated values pass the same checks as each mesh's.
    verify(
        &best.tau,
        &best.tau,
        &setup,
        "the renewal route (--method renewal, extrapolated)",
    )?;
    let error_estimate = mesh_error + time_error + truncation_error + best.tail;
    let paper = problem.params().noise().is_none();
    let pair = |v: &[f64]| if paper { [v[0], v[1]] } else { [f64::NAN; 2] };
    let [tau_plus, tau_minus] = pair(&best.tau);
    Ok(RenewalSolution {
        tau: best.mean(),
        tau_plus,
        tau_minus,
        tau_states: (!paper).then(|| best.tau.clone()),
        reset_values: pair(&best.reset),
        reset_states: (!paper).then(|| best.reset.clone()),
        error_estimate: if opts.refine && asymptotic {
            error_estimate
        } else {
            f64::NAN
        },
        mesh_error,
        time_error,
        truncation_error,
        tail_bound: best.tail,
        textbook: best.textbook,
        mesh: mesh_info(&finest),
        infinite_mean: false,
        asymptotic,
        work: watch.done(),
    })
}

/// Band solves per time step of `steps`: 2 × N × 3 (two stages, N final
/// states, the runs at dt and dt/2: 3 steps for each of `steps`).
fn per_step(setup: &Setup) -> f64 {
    6.0 * setup.noise.states() as f64
}

/// The cost of one more level of the ladder: the answers at `steps` and
/// twice as many time steps (two factorisations, `solves` band solves).
fn level_cost(plan: &Plan, solves: f64) -> Cost {
    let plan = std::slice::from_ref(plan);
    let c = cost_of(plan, solves);
    Cost {
        work: c.work + cost_of(plan, 0.0).work,
        memory: c.memory,
    }
}

/// The renewal answer on one mesh with `steps` time steps to `t_max`. The
/// reset-point quantities are weighed by the target's node weights
/// (a_s(x_r) = Σ_j w_j a_s(x_r, v_j), likewise B and e: the reset lands on
/// v_j with probability w_j), so random targets need nothing else.
fn answer(
    setup: &Setup,
    mesh: &Mesh,
    waiting: &WaitingTime,
    (t_max, steps): (f64, usize),
    watch: &Watch,
) -> Result<Answer> {
    let Resetting::Full { x: xr, v: vr } = setup.resetting else {
        unreachable!("Setup::new with renewal = true makes full resetting");
    };
    let ir = mesh.node(xr, vr)?.0;
    let (i0, j0) = mesh.node(setup.x0, setup.v0)?;
    // Watched points: the start (weight 1), then the reset target.
    let start = vec![(i0, j0, 1.0)];
    let target: Vec<_> = mesh
        .target_weights(&setup.params)?
        .into_iter()
        .map(|(j, w)| (ir, j, w))
        .collect();
    let g = Generator::assemble(mesh, &setup.params, &setup.noise, None);
    let (wq, rq, beyond) = waiting.weights(t_max, steps);
    let ns = mesh.states;
    let mut p = Periods {
        a: [vec![0.0; ns], vec![0.0; ns]],
        b: [vec![vec![0.0; ns]; ns], vec![vec![0.0; ns]; ns]],
        e: vec![beyond; ns],
    };
    survival_series(&g, ns, t_max, steps, |n, q| {
        watch.tick();
        for (at, points) in [&target, &start].into_iter().enumerate() {
            for s in 0..ns {
                for &(i, j, w) in points {
                    let k = mesh.idx(i, j, s);
                    // S_s = Σ_s' Q_s' and 1 - S_s, summed in state order.
                    let survival = (1..ns).fold(q[0][k], |acc, s2| acc + q[s2][k]);
                    p.a[at][s] += w * wq[n] * survival;
                    for (s2, qs) in q.iter().enumerate() {
                        p.b[at][s][s2] += w * rq[n] * qs[k];
                    }
                    if at == 0 {
                        let hit = q.iter().fold(1.0, |acc, qs| acc - qs[k]);
                        p.e[s] += w * rq[n] * hit;
                    }
                }
            }
        }
    })?;
    renew(setup, &p, waiting.tail(t_max))
}

/// The route's name in its refusals.
const METHOD: &str = "the renewal route (--method renewal)";

/// Solve the renewal equations (module docs) from the period integrals,
/// with the bound on the cut-off tail `(tail_a, tail_b)`, verified.
fn renew(setup: &Setup, p: &Periods, (tail_a, tail_b): (f64, f64)) -> Result<Answer> {
    let mix = &setup.mix;
    let ns = p.e.len();
    // M = B(x_r) mix: T_r = a_r + M T_r; mix keeps the rows' sums, so the
    // escape chances of M are those of B.
    let m: Vec<Vec<f64>> = (0..ns)
        .map(|s| {
            (0..ns)
                .map(|u| (0..ns).map(|s2| p.b[0][s][s2] * mix[s2][u]).sum::<f64>())
                .collect()
        })
        .collect();
    // (I - M)⁻¹ f: the 2 × 2 capacitance, or the N-state elimination
    // (non-negative terms; refused unless every e_s > 0).
    let solve = |f: &[f64]| renew_states(&m, &p.e, f, METHOD);
    let reset = solve(&p.a[0])?;
    let next: Vec<f64> = (0..ns)
        .map(|u| (0..ns).map(|s2| mix[u][s2] * reset[s2]).sum::<f64>())
        .collect();
    let tau: Vec<f64> = (0..ns)
        .map(|s| (0..ns).fold(p.a[1][s], |acc, s2| acc + p.b[1][s][s2] * next[s2]))
        .collect();
    let pi = &setup.noise.pi;
    let (a_bar, e_bar) = (weighed(pi, &p.a[0]), weighed(pi, &p.e));
    // ‖(I - M)⁻¹‖∞ from its columns: the tail's effect on T_r.
    let cols = (0..ns)
        .map(|c| {
            solve(
                &(0..ns)
                    .map(|i| f64::from(u8::from(i == c)))
                    .collect::<Vec<_>>(),
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let norm = (0..ns)
        .map(|i| (1..ns).fold(cols[0][i].abs(), |a, c| a + cols[c][i].abs()))
        .fold(0.0, f64::max);
    let largest = reset.iter().copied().fold(reset[0], f64::max);
    let per = tail_a + tail_b * largest;
    let tail = per + norm * per;
    let all: Vec<f64> = tau.iter().chain(&reset).copied().collect();
    verify(&all, &tau, setup, METHOD)?;
    Ok(Answer {
        tau,
        reset,
        pi: pi.clone(),
        textbook: a_bar / e_bar,
        tail,
    })
}

/// Q_s'(t_n), n = 0..=steps, for each of the `ns` states s' (Q(0) = 1 in
/// state s' off the target), handed to `record(n, [Q_0, .., Q_{N-1}])`:
/// TR-BDF2 with a fixed step on `I - d dt A`.
fn survival_series(
    g: &Generator,
    ns: usize,
    t_max: f64,
    steps: usize,
    mut record: impl FnMut(usize, &[Vec<f64>]),
) -> Result<()> {
    const METHOD: &str = "the renewal route (--method renewal, reset-free survival)";
    let dt = t_max / steps as f64;
    let stepper = Stepper::new(dt);
    let band = factor(g, 1.0, stepper.d(), METHOD)?;
    let n = g.dim();
    let mut q: Vec<Vec<f64>> = (0..ns)
        .map(|s2| {
            (0..n)
                .map(|k| {
                    if !g.absorbing[k] && k % ns == s2 {
                        1.0
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    record(0, &q);
    let (mut au, mut star) = (vec![0.0; n], vec![0.0; n]);
    for step in 1..=steps {
        crate::parallel::check_stop()?;
        for u in q.iter_mut() {
            stepper.step(
                u,
                (&mut au, &mut star),
                |x, y| g.apply(x, y),
                |y| band.solve(y),
            );
        }
        if q.iter().flatten().any(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                method: METHOD,
                at: dt * step as f64,
            });
        }
        record(step, &q);
    }
    Ok(())
}
