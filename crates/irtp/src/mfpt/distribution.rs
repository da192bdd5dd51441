//! The first-passage-time distribution from the time-dependent backward
//! equations.
//!
//! The survival probabilities S±(v, t) = P(T > t | v(0) = v, eta(0) = ±Sigma)
//! obey dS/dt = L S with the generator L of [`crate::mfpt`] (the simulated
//! drifts), S+(v_t, t) = 0 and regularity at v_l, S(v, 0) = 1 below v_t;
//! f = -dS/dt is the first-passage-time density.
//!
//! The distribution has an atom: a particle started in the state driving
//! it towards the target arrives, with probability e^{-(lambda + r) T_f}, at
//! exactly the deterministic flow time T_f from v_0 to v_t (no flip and no
//! reset before). It is split off analytically and reported as a point mass
//! ([`Distribution::atom_time`], [`Distribution::atom_mass`]); S includes it
//! (S+ drops by the atom's mass at T_f), f is the density of the rest.
//! The rest solves the survival equations with a bounded forcing, on the
//! monotone upwind scheme of `mfpt/upwind.rs` (no oscillation: S stays a
//! probability, f >= 0 up to the integration tolerance) integrated in time
//! by the adaptive L-stable TR-BDF2 of [`crate::numerics::trbdf2`], landing
//! on T_f(v_r) where the forcing jumps (a random reset target: the reset
//! terms weigh the target's node weights, and the forcing is continuous; see
//! `mfpt/upwind.rs`). Four extra unknowns at v_0 carry the
//! running integrals I± = ∫_0^t S± ds and J± = ∫_0^t I± ds, so
//! E(T) = ∫ S dt = I and E(T²) = 2 ∫ t S dt = 2 (t I - J); the atom's share
//! is added in closed form.
//!
//! The scheme is first order in the mesh: it runs on the mesh of
//! [`super::backward`] with `cells / 2` cells and on its midpoint
//! refinement; S and the moments are the Richardson extrapolation
//! 2 X_fine - X_coarse, f is the finer mesh's (see
//! [`Distribution::atom_spread`]). The largest |S_fine - S_coarse| is
//! reported as [`Distribution::mesh_error`] (the error of the finer run,
//! an upper estimate of the extrapolated one). The stationary moments of
//! the box scheme on the full mesh ([`Distribution::moments`]) are computed
//! alongside: the distribution's own mean must agree with them.
//!
//! After the output grid the integration continues, in doubling windows,
//! until S±(v_0) < `tail` or [`DistributionOptions::t_stop`]; the survival
//! left there, `tail_mass`, is the unresolved probability (reported).
//!
//! An exponential refractory period (paper's noise, docs/equations.md,
//! (R12); a noise model, (R15)) adds the held survival H± (H_s) to the
//! upwind system (`mfpt/upwind.rs`, `distribution/finite.rs`); the box
//! scheme then gives the mean only ((R6), (R11)), the reported second
//! moments are the distribution's own.
//!
//! One driver runs every noise over its state space (the `Space`s of
//! [`super::backward`]): the paper's `Telegraph` by the two-state upwind
//! operator above, a noise model's `Finite` chain by the N-state
//! operator of `distribution/finite.rs` (Eqs. (N37)-(N39), (N49)). Each
//! space supplies its moments, coarse mesh and one mesh's run (the trait
//! `Survival`); the refinement, the time loop past the grid, the
//! extrapolation, the π-mixture and the checks are shared.

mod finite;

use super::backward::{
    self, mesh, target_weights, BackwardOptions, DriftSign, Finite, Mesh, Moments, Space, Telegraph,
};
use super::upwind::{exp_moments, AtomProbe, UpwindOperator};
use super::Problem;
use crate::error::{Error, Result};
use crate::model::noise::chain::Chain;
use crate::model::reset::Solver;
use crate::model::Drag;
use crate::numerics::trbdf2::{self, Stats, Tolerances};
use serde::{Deserialize, Serialize};

/// Options of [`distribution`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistributionOptions {
    /// Mesh (cells, drift convention) of the backward equations.
    pub backward: BackwardOptions,
    /// Relative tolerance of the time integration.
    pub rtol: f64,
    /// Absolute tolerance of S (probabilities).
    pub atol: f64,
    /// Integrate on after the output grid until S±(v_0) < tail ...
    pub tail: f64,
    /// ... or until this time (in units of tau when `None`: 1e3 tau).
    pub t_stop: Option<f64>,
}

impl Default for DistributionOptions {
    fn default() -> Self {
        DistributionOptions {
            backward: BackwardOptions::default(),
            rtol: 1e-4,
            atol: 1e-7,
            tail: 1e-10,
            t_stop: None,
        }
    }
}

impl DistributionOptions {
    /// Mesh valid; 1e-12 <= rtol <= 1e-2; 0 < atol, tail < 1.
    pub fn validate(&self) -> Result<()> {
        self.backward.validate()?;
        if !(self.rtol >= 1e-12 && self.rtol <= 1e-2) {
            return Err(Error::invalid("rtol", self.rtol, "1e-12 <= rtol <= 1e-2"));
        }
        if !(self.atol > 0.0 && self.atol < 1.0) {
            return Err(Error::invalid("atol", self.atol, "0 < atol < 1"));
        }
        if !(self.tail > 0.0 && self.tail < 1.0) {
            return Err(Error::invalid("tail", self.tail, "0 < tail < 1"));
        }
        Ok(())
    }
}

/// S±(v_0, t) and f±(v_0, t) on an output grid, with the moments.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Distribution {
    /// Output times.
    pub t: Vec<f64>,
    /// S = (S+ + S-)/2: survival of a uniformly random initial state.
    pub survival: Vec<f64>,
    /// S+ (start in +Sigma).
    pub survival_plus: Vec<f64>,
    /// S- (start in -Sigma).
    pub survival_minus: Vec<f64>,
    /// f = -dS/dt.
    pub density: Vec<f64>,
    /// f+ = -dS+/dt.
    pub density_plus: Vec<f64>,
    /// f- = -dS-/dt.
    pub density_minus: Vec<f64>,
    /// The stationary moments of the box scheme on the full mesh
    /// (L T1 = -1, L T2 = -2 T1), an independent discretisation.
    pub moments: Moments,
    /// E(T) = ∫_0^∞ S dt of the distribution (atom included), exact in
    /// time for the semi-discrete equations, extrapolated in the mesh.
    pub mean: f64,
    /// Starting in +Sigma.
    pub mean_plus: f64,
    /// Starting in -Sigma.
    pub mean_minus: f64,
    /// E(T²) = 2 ∫_0^∞ t S dt, as [`Distribution::mean`].
    pub second: f64,
    /// Where the time integration stopped.
    pub t_end: f64,
    /// S(v_0, t_end): probability not resolved by the time integration
    /// (the mean misses about tail_mass times the decay time).
    pub tail_mass: f64,
    /// The deterministic flow time T_f from v_0 to v_t, where the atom sits
    /// (with a noise model the earliest of [`Distribution::atoms`]; 0 with
    /// thermal noise, which leaves no atom).
    pub atom_time: f64,
    /// Its mass in the mixture: half the mass of the driving start state
    /// (with a noise model the π-weighted sum over the atoms; 0 at T > 0).
    pub atom_mass: f64,
    /// Its mass starting in +Sigma (e^{-(lambda + r) T_f} for an upward
    /// target, 0 for a downward one).
    pub atom_mass_plus: f64,
    /// Its mass starting in -Sigma (0 for an upward target).
    pub atom_mass_minus: f64,
    /// Time steps taken (accepted).
    pub steps: usize,
    /// Steps rejected by the error control.
    pub rejected: usize,
    /// max over the output times of |S_fine - S_coarse| (see the module
    /// doc): the discretisation error of the finer mesh.
    pub mesh_error: f64,
    /// max of |f_fine - f_coarse| over the output times outside
    /// [`Distribution::smeared`]: the same for f.
    pub mesh_error_density: f64,
    /// The spread in time over which the scheme smears the atom's arrival
    /// (the standard deviation of its discrete flow time from v_0). Within
    /// atom_time ± [`ATOM_WINDOW`] spreads the kink that the atom leaves in
    /// the rest of the distribution is smeared too: f there is a local
    /// average, first order in the mesh, and may dip below 0 by a few per
    /// cent of its scale (S is unaffected beyond `mesh_error`).
    pub atom_spread: f64,
    /// ∫_0^t_end S dt from the time integration: equals [`Distribution::mean`]
    /// up to the integration error and the tail (a check of S(t)).
    pub mean_time_integral: f64,
    /// 2 ∫_0^t_end t S dt from the time integration.
    pub second_time_integral: f64,
    /// |E(T)_fine - E(T)_coarse| of the two meshes: the discretisation
    /// error of the finer one, an upper estimate of the extrapolated
    /// [`Distribution::mean`]'s.
    #[serde(default)]
    pub mean_error: f64,
    /// With a noise model (`distribution/finite.rs`): one atom per state whose flow
    /// reaches v_t, each at its own flow time. Empty for the paper's noise,
    /// whose one atom is [`Distribution::atom_time`],
    /// [`Distribution::atom_mass`].
    #[serde(default)]
    pub atoms: Vec<Atom>,
}

/// A point mass of the first-passage time with a noise model: started in
/// `state`, the particle arrives at its deterministic flow time with
/// probability `mass` (no jump and no reset before); its share of the
/// mixture is `weight` · `mass`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Atom {
    /// The noise state (in the noise's order).
    pub state: usize,
    /// Its level a_s (user's frame).
    pub level: f64,
    /// T_f,s = ∫_{v_0}^{v_t} dv / (a_s - g): where the atom sits.
    pub time: f64,
    /// e^{-(q_s + r) T_f,s}: its mass starting in the state.
    pub mass: f64,
    /// π_s: the probability of starting in the state.
    pub weight: f64,
    /// The scheme's spread of this arrival in time (as
    /// [`Distribution::atom_spread`]).
    pub spread: f64,
}

impl Distribution {
    /// Whether f at time t lies in the window around the atom's flow time
    /// where the scheme smears it ([`Distribution::atom_spread`]).
    pub fn smeared(&self, t: f64) -> bool {
        if self.atoms.is_empty() {
            return (t - self.atom_time).abs() < ATOM_WINDOW * self.atom_spread;
        }
        self.atoms
            .iter()
            .any(|a| (t - a.time).abs() < ATOM_WINDOW * a.spread)
    }
}

/// Validate output times: finite, >= 0, increasing.
fn check_times(times: &[f64]) -> Result<()> {
    if times.is_empty() {
        return Err(Error::invalid("points", 0, "at least one output time"));
    }
    let ok =
        times.iter().all(|t| t.is_finite() && *t >= 0.0) && times.windows(2).all(|w| w[0] < w[1]);
    if !ok {
        return Err(Error::invalid(
            "t",
            format!("{:?}..", times[0]),
            "finite output times >= 0, increasing",
        ));
    }
    Ok(())
}

/// The midpoint refinement of a mesh of `cp` (v_0, v_r stay nodes; a
/// random target's weights are recomputed on it).
pub(super) fn refine(cp: &Problem, m: &Mesh) -> Mesh {
    let mut v = Vec::with_capacity(2 * m.v.len() - 1);
    for w in m.v.windows(2) {
        v.extend([w[0], 0.5 * (w[0] + w[1])]);
    }
    v.push(m.v[m.v.len() - 1]);
    Mesh {
        weights: target_weights(cp, &v),
        v,
        start: 2 * m.start,
        reset: 2 * m.reset,
    }
}

/// Where a run stops: past the grid until every S_s(v_0) is below `tail`
/// (or at `t_stop`), or at a given time.
#[derive(Clone, Copy)]
enum Stop {
    Tail { tail: f64, t_stop: f64 },
    At(f64),
}

impl Stop {
    /// Integrate on from t, the end of the grid: `top` is the largest
    /// S_s(v_0) at a time, `step` integrates from a time to the next; the
    /// first window past the grid reaches `horizon`, then they double.
    /// Returns where it stopped.
    fn finish<C>(
        self,
        ctx: &mut C,
        mut t: f64,
        horizon: f64,
        top: impl Fn(&C, f64) -> f64,
        mut step: impl FnMut(&mut C, f64, f64) -> Result<Stats>,
    ) -> Result<(f64, Stats)> {
        let mut stats = Stats::default();
        match self {
            Stop::Tail { tail, t_stop } => {
                let t_stop = t_stop.max(t);
                while top(ctx, t) >= tail && t < t_stop {
                    let next = (2.0 * t)
                        .max(horizon.min(t_stop))
                        .min(t_stop)
                        .max(t + f64::EPSILON * t);
                    stats += step(ctx, t, next)?;
                    t = next;
                }
            }
            Stop::At(end) if end > t => {
                stats += step(ctx, t, end)?;
                t = end;
            }
            Stop::At(_) => {}
        }
        Ok((t, stats))
    }
}

/// What one mesh's run integrates: the output times, the tolerances,
/// where it stops and the scales (τ, E(T²)) of the integrals' errors.
#[derive(Clone, Copy)]
struct Plan<'a> {
    times: &'a [f64],
    tol: &'a Tolerances,
    stop: Stop,
    scales: (f64, f64),
}

/// An atom of one mesh's run: started in state `s`, the flow reaches v_t
/// at `time` with no jump and no reset before (decay `kill` = q_s + r);
/// `spread`: the scheme's spread of that arrival on the mesh.
struct RunAtom {
    s: usize,
    time: f64,
    kill: f64,
    spread: f64,
}

/// One mesh's run, per state: S_s(v_0) (atoms included) and f_s(v_0) at
/// the output times, the moments of the time integration and of the
/// semi-discrete system exactly in time (the time integration's where a
/// space computes no other), the end, the survival left there.
struct Run {
    s: Vec<Vec<f64>>,
    f: Vec<Vec<f64>>,
    mean: Vec<f64>,
    second: Vec<f64>,
    exact_mean: Vec<f64>,
    exact_second: Vec<f64>,
    t_end: f64,
    tail: Vec<f64>,
    stats: Stats,
    atoms: Vec<RunAtom>,
}

impl Run {
    /// The states renumbered by `to` (canonical to user's frame; its own
    /// inverse: a reflection swaps ±Sigma, a chain keeps its order).
    fn renumber(mut self, to: impl Fn(usize) -> usize) -> Run {
        let order = |x: &mut Vec<f64>| *x = (0..x.len()).map(|u| x[to(u)]).collect();
        let (m, m2, e, e2) = (
            &mut self.mean,
            &mut self.second,
            &mut self.exact_mean,
            &mut self.exact_second,
        );
        let rows = self.s.iter_mut().chain(self.f.iter_mut());
        rows.chain([m, m2, e, e2, &mut self.tail]).for_each(order);
        self.atoms.iter_mut().for_each(|a| a.s = to(a.s));
        self
    }
}

/// The survival equations as a state space runs them: the paper's noise
/// ([`Telegraph`], the two-state upwind scheme of `mfpt/upwind.rs`) or a
/// noise model's chain ([`Finite`], `distribution/finite.rs`). The driver
/// ([`distribution`]) is one for both.
trait Survival: Space {
    /// The box scheme's moments; the mixture over the `user` chain's π,
    /// ± its states of highest and lowest level.
    fn moments(&self, p: &Problem, opts: &BackwardOptions, user: &Chain) -> Result<Moments>;
    /// The coarse mesh on `cells` cells of the canonical problem `cp`.
    fn coarse(&self, cp: &Problem, cells: usize) -> Result<Mesh>;
    /// One mesh's run (canonical frame, the chain's state order).
    fn run(&self, cp: &Problem, m: &Mesh, plan: &Plan) -> Result<Run>;
    /// Whether [`Distribution::atoms`] lists the atoms.
    fn lists_atoms(&self) -> bool;
    /// How far E(T) may lie from the box scheme's τ.
    fn mean_tolerance(&self, d: &Distribution) -> f64;
}

impl Survival for Telegraph {
    fn moments(&self, p: &Problem, opts: &BackwardOptions, _: &Chain) -> Result<Moments> {
        if p.params().schedule().refractory.is_some() {
            return held_moments(p, opts);
        }
        backward::moments(p, opts)
    }
    fn coarse(&self, cp: &Problem, cells: usize) -> Result<Mesh> {
        mesh(cp, cells)
    }
    fn run(&self, cp: &Problem, m: &Mesh, plan: &Plan) -> Result<Run> {
        run(cp, m, plan)
    }
    fn lists_atoms(&self) -> bool {
        false
    }
    fn mean_tolerance(&self, d: &Distribution) -> f64 {
        1e-3 * d.moments.tau
    }
}

/// The box scheme's moments with an exponential refractory period: it
/// gives the mean only (docs/equations.md, (R6)); the second moments are
/// set from the means by [`with_second`] (2 tau², the exponential law's,
/// the scale of the integrals' error weights) until the distribution's
/// own replace them ([`drive`]).
fn held_moments(p: &Problem, opts: &BackwardOptions) -> Result<Moments> {
    let b = backward::solve(p, opts)?;
    let t = [b.tau, b.tau_plus, b.tau_minus];
    Ok(with_second(
        Moments {
            tau: b.tau,
            tau_plus: b.tau_plus,
            tau_minus: b.tau_minus,
            cells: b.cells,
            // All set by with_second.
            second: f64::NAN,
            second_plus: f64::NAN,
            second_minus: f64::NAN,
            variance: f64::NAN,
            variance_plus: f64::NAN,
            variance_minus: f64::NAN,
            cv: f64::NAN,
            cv_plus: f64::NAN,
            cv_minus: f64::NAN,
        },
        t.map(|x| 2.0 * x * x),
    ))
}

/// `m` with the second moments (mixture, +, -) `t2` and the variances and
/// coefficients of variation that follow.
fn with_second(m: Moments, t2: [f64; 3]) -> Moments {
    let var = |m2: f64, t: f64| m2 - t * t;
    let (v, vp, vm) = (
        var(t2[0], m.tau),
        var(t2[1], m.tau_plus),
        var(t2[2], m.tau_minus),
    );
    Moments {
        second: t2[0],
        second_plus: t2[1],
        second_minus: t2[2],
        variance: v,
        variance_plus: vp,
        variance_minus: vm,
        cv: v.sqrt() / m.tau,
        cv_plus: vp.sqrt() / m.tau_plus,
        cv_minus: vm.sqrt() / m.tau_minus,
        ..m
    }
}

/// The atom's part of S+(v_0, t): e^{-k t} for t < T_f.
fn atom_survival(k: f64, tf: f64, t: f64) -> f64 {
    if t < tf {
        (-k * t).exp()
    } else {
        0.0
    }
}

/// Integrate from `op.t0` through the absolute times `targets`
/// (increasing, > op.t0), landing on T_f(v_r) where the + forcing
/// switches off; `observe` sees every target.
fn advance(
    op: &mut UpwindOperator,
    view: &mut UpwindOperator,
    u: &mut [f64],
    targets: &[f64],
    tol: &Tolerances,
    observe: &mut dyn FnMut(f64, &UpwindOperator, &[f64]),
) -> Result<Stats> {
    let mut stats = Stats::default();
    let mut rest = targets;
    while !rest.is_empty() {
        let t0 = op.t0;
        let tr = op.reset_atom_time();
        let on = t0 < tr;
        // This segment: targets up to T_f(v_r) while the forcing is on.
        let cut = if on {
            rest.partition_point(|&t| t <= tr)
        } else {
            rest.len()
        };
        let mut rel: Vec<f64> = rest[..cut].iter().map(|t| t - t0).collect();
        // Targets remain past T_f(v_r): land on it first.
        let lands = on && cut < rest.len() && rel.last().map_or(true, |&t| t < tr - t0);
        if lands {
            rel.push(tr - t0);
        }
        op.set_reset_atom(on);
        view.set_reset_atom(on);
        view.t0 = t0;
        let st = trbdf2::integrate(op, u, &rel, tol, |k, t, x| {
            if k < cut {
                observe(t0 + t, view, x);
            }
            Ok(())
        })?;
        stats += st;
        op.t0 = t0 + rel.last().copied().unwrap_or(0.0);
        rest = &rest[cut..];
    }
    if let Some(&t) = targets.last() {
        op.t0 = t;
    }
    Ok(stats)
}

/// The survival equations on one mesh (see the module doc).
fn run(cp: &Problem, m: &Mesh, plan: &Plan) -> Result<Run> {
    let Plan {
        times,
        tol,
        stop,
        scales,
    } = *plan;
    let par = cp.params();
    let k = par.lambda() + par.rate();
    let tf = par.drag().flow_time(par.sigma(), cp.v0(), cp.vt());
    let mut op = UpwindOperator::new(cp, m);
    op.scales = scales;
    let mut view = UpwindOperator::new(cp, m);
    let mut u = op.initial();
    let (p, q) = (2 * op.start, 2 * op.start + 1);
    let (mut s, mut f) = (Vec::new(), Vec::new());
    let positive: Vec<f64> = times.iter().copied().filter(|&t| t > 0.0).collect();
    let (dp, dm) = view.rate_at_start(&u, 0.0);
    for _ in 0..times.len() - positive.len() {
        s.push((1.0, 1.0));
        f.push((k - dp, -dm));
    }
    // Steps land on HIDDEN points across [0, 2 T_f] and, denser, across the
    // smeared kink of S_c at T_f (a few of the scheme's spreads wide), so it
    // is resolved in time whatever the output grid, by both integrations.
    let probe = AtomProbe::new(cp, m);
    let spread = probe.spread();
    let kink = (0..=2 * HIDDEN).map(|j| tf + 6.0 * spread * (j as f64 / HIDDEN as f64 - 1.0));
    let all = landing_points(&positive, hidden(tf).chain(kink));
    let targets: Vec<f64> = all.iter().map(|a| a.0).collect();
    let mut shown = all.iter().map(|a| a.1);
    let mut observe = |t: f64, v: &UpwindOperator, x: &[f64]| {
        if shown.next() == Some(true) {
            let (dp, dm) = v.rate_at_start(x, t);
            s.push((x[p] + atom_survival(k, tf, t), x[q]));
            f.push((-dp, -dm));
        }
    };
    let mut stats = advance(&mut op, &mut view, &mut u, &targets, tol, &mut observe)?;
    // The atom's continuous share of f+, smeared as the scheme smears S_c+.
    let mut probe = probe;
    let mut q0 = probe.initial();
    let mut smeared = Vec::with_capacity(positive.len());
    let st = trbdf2::integrate(&mut probe, &mut q0, &targets, tol, |j, t, x| {
        if all[j].1 {
            smeared.push(k * (-k * t).exp() * x[0]);
        }
        Ok(())
    })?;
    stats += st;
    let zeros = f.len() - smeared.len();
    for (fi, a) in f[zeros..].iter_mut().zip(smeared) {
        fi.0 += a;
    }
    let survival = |u: &[f64], t: f64| (u[p] + atom_survival(k, tf, t), u[q]);
    let t = op.t0;
    let mut ctx = (op, view, u);
    let (t, st) = stop.finish(
        &mut ctx,
        t,
        tf,
        |c, t| {
            let (a, b) = survival(&c.2, t);
            a.max(b)
        },
        |c, _, next| {
            advance(
                &mut c.0,
                &mut c.1,
                &mut c.2,
                &[next],
                tol,
                &mut |_, _, _| {},
            )
        },
    )?;
    stats += st;
    let (op, _, u) = ctx;
    let n = op.n;
    // The atom's share of ∫ S+ and ∫ t S+, in closed form.
    let (ia, ja) = exp_moments(k, tf.min(t));
    let (xa, ya) = exp_moments(k, tf);
    let (x1, x2) = op.stationary_integrals()?;
    let second = |i: f64, j: f64| 2.0 * (t * i - j);
    let pairs = |x: Vec<(f64, f64)>| x.into_iter().map(|(a, b)| vec![a, b]).collect();
    let tail = survival(&u, t);
    Ok(Run {
        s: pairs(s),
        f: pairs(f),
        mean: vec![u[n] + ia, u[n + 1]],
        second: vec![
            second(u[n], u[n + 2]) + 2.0 * ja,
            second(u[n + 1], u[n + 3]),
        ],
        exact_mean: vec![x1.0 + xa, x1.1],
        exact_second: vec![2.0 * (x2.0 + ya), 2.0 * x2.1],
        t_end: t,
        tail: vec![tail.0, tail.1],
        stats,
        atoms: vec![RunAtom {
            s: 0,
            time: tf,
            kill: k,
            spread,
        }],
    })
}

/// Half-width, in spreads, of the window around the atom's flow time where
/// f is smeared ([`Distribution::atom_spread`]).
pub const ATOM_WINDOW: f64 = 6.0;

/// Hidden landing points of the time stepping across [0, 2 max T_f,s].
const HIDDEN: usize = 64;

/// [`HIDDEN`] points evenly across (0, 2 `tf`].
fn hidden(tf: f64) -> impl Iterator<Item = f64> {
    (1..=HIDDEN).map(move |j| 2.0 * tf * j as f64 / HIDDEN as f64)
}

/// The output times (flagged true) merged with the `extra` points inside
/// (0, last time) that are none of them (flagged false), sorted.
fn landing_points(times: &[f64], extra: impl Iterator<Item = f64>) -> Vec<(f64, bool)> {
    let last = times.last().copied().unwrap_or(0.0);
    let mut all: Vec<(f64, bool)> = times.iter().map(|&t| (t, true)).collect();
    all.extend(
        extra
            .filter(|&t| t > 0.0 && t < last)
            .filter(|&t| times.binary_search_by(|x| x.total_cmp(&t)).is_err())
            .map(|t| (t, false)),
    );
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    all.dedup_by(|a, b| a.0 == b.0);
    all
}

/// What [`distribution`] refuses in the problem itself, before any solve
/// (for a caller to refuse early): a noise the method does not run, and
/// with a noise model what the N-state backward equations refuse (with
/// thermal noise a drag other than linear, tanh and tan, naming `drag`,
/// and tan above T = 1, naming `temperature`).
pub fn check_problem(problem: &Problem) -> Result<()> {
    problem.params().require(Solver::FptDistribution)?;
    space_of(problem).map(|_| ())
}

/// The state space of `problem` (canonical frame) and its chain in the
/// user's frame; with a noise model what the backward equations refuse.
fn space_of(problem: &Problem) -> Result<(Box<dyn Survival>, Chain)> {
    let (cp, _) = problem.canonical();
    Ok(match problem.params().noise() {
        None => (
            Box::new(Telegraph::of(&cp)),
            Telegraph::of(problem).chain().clone(),
        ),
        Some(_) => {
            let user = finite::admissible(problem)?;
            (Box::new(Finite(cp.params().chain()?)), user)
        }
    })
}

/// The first-passage-time distribution of `problem` at the output `times`
/// (see the module doc). Errors: invalid options or times; the paper's
/// printed drift (only the simulated process has a distribution); with a
/// noise model what [`super::backward`] refuses (with T > 0 a drag other
/// than linear, tanh, tan, naming `drag`); [`Error::Overflow`] where the
/// moments exceed the f64 range; a numerical failure of the time
/// integration or of the checks.
pub fn distribution(
    problem: &Problem,
    times: &[f64],
    opts: &DistributionOptions,
) -> Result<Distribution> {
    problem.params().require(Solver::FptDistribution)?;
    opts.validate()?;
    check_times(times)?;
    if opts.backward.drift != DriftSign::Simulated {
        return Err(Error::invalid(
            "drift",
            "paper-printed",
            "the simulated drift",
        ));
    }
    let (space, user) = space_of(problem)?;
    drive(&*space, problem, times, opts, &user)
}

/// The two meshes' runs of `space` and what they report (the states in
/// the `user` chain's order; `survival_plus` / `survival_minus` the states
/// of highest / lowest level), checked by [`verify`].
fn drive(
    space: &dyn Survival,
    problem: &Problem,
    times: &[f64],
    opts: &DistributionOptions,
    user: &Chain,
) -> Result<Distribution> {
    let (hi, lo) = backward::extreme_states(&user.levels);
    let moments = space.moments(problem, &opts.backward, user)?;
    let (cp, swapped) = problem.canonical();
    let coarse = space.coarse(&cp, (opts.backward.cells / 2).max(8))?;
    let fine_mesh = refine(&cp, &coarse);
    let tol = Tolerances {
        rtol: opts.rtol,
        atol: opts.atol,
        ..Tolerances::default()
    };
    let mut plan = Plan {
        times,
        tol: &tol,
        stop: Stop::Tail {
            tail: opts.tail,
            t_stop: opts.t_stop.unwrap_or(1e3 * moments.tau),
        },
        scales: (moments.tau, moments.second),
    };
    let to = |s| space.user_state(s, swapped);
    let fine = space.run(&cp, &fine_mesh, &plan)?.renumber(to);
    plan.stop = Stop::At(fine.t_end);
    let rough = space.run(&cp, &coarse, &plan)?.renumber(to);
    let thermal = space.chain().temperature > 0.0;
    let mut d = report(times, user, (hi, lo), moments, &fine, &rough, thermal)?;
    if problem.params().schedule().refractory.is_some() {
        // The box scheme gave the mean only: the second moments are the
        // distribution's own (exact in time, extrapolated in the mesh).
        let ex = |s: usize| 2.0 * fine.exact_second[s] - rough.exact_second[s];
        d.moments = with_second(d.moments, [d.second, ex(hi), ex(lo)]);
    }
    verify(&d, opts.rtol, space.mean_tolerance(&d))?;
    if !space.lists_atoms() {
        d.atoms.clear();
    }
    Ok(d)
}

/// Per output time, the π-mixture and the states `hi`, `lo` of a per-state
/// table.
fn columns(rows: &[Vec<f64>], pi: &[f64], hi: usize, lo: usize) -> [Vec<f64>; 3] {
    let mix = rows
        .iter()
        .map(|r| r.iter().zip(pi).map(|(a, b)| a * b).sum())
        .collect();
    [
        mix,
        rows.iter().map(|r| r[hi]).collect(),
        rows.iter().map(|r| r[lo]).collect(),
    ]
}

/// max over rows and states of |a - b|, over the rows `keep` admits.
fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>], keep: impl Fn(usize) -> bool) -> f64 {
    (0..a.len())
        .filter(|&i| keep(i))
        .flat_map(|i| a[i].iter().zip(&b[i]).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max)
}

/// The earliest atom's (time, spread): (0, 0) with T > 0, where there is
/// none (as [`Distribution::smeared`] then flags no time); at T = 0 an
/// error where no state's flow reaches the target.
fn earliest_atom(atoms: &[Atom], thermal: bool) -> Result<(f64, f64)> {
    match atoms.iter().min_by(|a, b| a.time.total_cmp(&b.time)) {
        Some(a) => Ok((a.time, a.spread)),
        None if thermal => Ok((0.0, 0.0)),
        None => Err(Error::Numerical {
            method: "first-passage distribution",
            reason: "no state's flow reaches the target".into(),
        }),
    }
}

/// The distribution from the runs on the finer and the coarser mesh (user's
/// state order): S and the moments extrapolated 2 fine - coarse, f the
/// finer mesh's (the scheme smears the kinks of S_c over widths that
/// differ between the meshes, and the derivative of 2 fine - coarse
/// overshoots there, f < 0); the atoms the finer mesh's.
fn report(
    times: &[f64],
    user: &Chain,
    (hi, lo): (usize, usize),
    moments: Moments,
    fine: &Run,
    rough: &Run,
    thermal: bool,
) -> Result<Distribution> {
    let ex =
        |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| 2.0 * x - y).collect() };
    let s: Vec<Vec<f64>> = fine.s.iter().zip(&rough.s).map(|(a, b)| ex(a, b)).collect();
    let [survival, survival_plus, survival_minus] = columns(&s, &user.pi, hi, lo);
    let [density, density_plus, density_minus] = columns(&fine.f, &user.pi, hi, lo);
    let mean = ex(&fine.exact_mean, &rough.exact_mean);
    let second = ex(&fine.exact_second, &rough.exact_second);
    let (mean_t, second_t) = (ex(&fine.mean, &rough.mean), ex(&fine.second, &rough.second));
    let mix = |x: &[f64]| -> f64 { x.iter().zip(&user.pi).map(|(a, b)| a * b).sum() };
    let atoms: Vec<Atom> = fine
        .atoms
        .iter()
        .map(|a| Atom {
            state: a.s,
            level: user.levels[a.s],
            time: a.time,
            mass: (-a.kill * a.time).exp(),
            weight: user.pi[a.s],
            spread: a.spread,
        })
        .collect();
    let smeared = |i: usize| {
        let t = times[i];
        atoms
            .iter()
            .zip(&rough.atoms)
            .any(|(a, w)| (t - a.time).abs() < ATOM_WINDOW * w.spread)
    };
    let mass_of = |s: usize| atoms.iter().find(|a| a.state == s).map_or(0.0, |a| a.mass);
    let (atom_time, atom_spread) = earliest_atom(&atoms, thermal)?;
    Ok(Distribution {
        t: times.to_vec(),
        survival,
        survival_plus,
        survival_minus,
        density,
        density_plus,
        density_minus,
        mean: mix(&mean),
        mean_plus: mean[hi],
        mean_minus: mean[lo],
        second: mix(&second),
        t_end: fine.t_end,
        tail_mass: mix(&fine.tail),
        atom_time,
        // A fold from +0 (an empty f64 sum is -0): 0 where there is no atom.
        atom_mass: atoms.iter().fold(0.0, |m, a| m + a.weight * a.mass),
        atom_mass_plus: mass_of(hi),
        atom_mass_minus: mass_of(lo),
        steps: fine.stats.steps + rough.stats.steps,
        rejected: fine.stats.rejected + rough.stats.rejected,
        mesh_error: max_diff(&fine.s, &rough.s, |_| true),
        mesh_error_density: max_diff(&fine.f, &rough.f, |i| !smeared(i)),
        atom_spread,
        mean_time_integral: mix(&mean_t),
        second_time_integral: mix(&second_t),
        mean_error: (mix(&fine.exact_mean) - mix(&rough.exact_mean)).abs(),
        moments,
        atoms,
    })
}
/// The invariants of a survival function, to the accuracy the run reports:
/// 0 <= S <= 1 and S non-increasing (each within 10 rtol + mesh_error),
/// f >= 0 outside the smeared window around the atom's flow time (within
/// 10 rtol max f + mesh_error_density), and the mean within
/// `mean_tol` of the box scheme's tau (an independent discretisation;
/// 1e-3 tau for the paper's noise). The π-mixture is checked as the
/// states are.
pub(super) fn verify(d: &Distribution, rtol: f64, mean_tol: f64) -> Result<()> {
    let slack = 10.0 * rtol + d.mesh_error;
    let fmax = d
        .density
        .iter()
        .fold(1.0 / d.moments.tau, |a: f64, &b| a.max(b));
    let fslack = 10.0 * rtol * fmax + d.mesh_error_density;
    let fail = |reason: String| {
        Err(Error::Numerical {
            method: "first-passage distribution",
            reason,
        })
    };
    for s in [&d.survival_plus, &d.survival_minus, &d.survival] {
        if let Some(i) = (0..s.len()).find(|&i| !(s[i] >= -slack && s[i] <= 1.0 + slack)) {
            return fail(format!(
                "S = {} at t = {} is not a probability",
                s[i], d.t[i]
            ));
        }
        if let Some(i) = (1..s.len()).find(|&i| !(s[i] <= s[i - 1] + slack)) {
            return fail(format!("S increases at t = {}", d.t[i]));
        }
    }
    for f in [&d.density_plus, &d.density_minus, &d.density] {
        if let Some(i) = (0..f.len()).find(|&i| !(d.smeared(d.t[i]) || f[i] >= -fslack)) {
            return fail(format!("f = {} < 0 at t = {}", f[i], d.t[i]));
        }
    }
    let tau = d.moments.tau;
    if !((d.mean - tau).abs() <= mean_tol) {
        return fail(format!(
            "E(T) = {} disagrees with the stationary tau = {tau}",
            d.mean
        ));
    }
    Ok(())
}
