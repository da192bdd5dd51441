//! The search problem: first passage in *position*.
//!
//! The particle starts at (x_0, v_0) with eta(0) = ±Sigma (equally likely;
//! with a noise model, its state drawn from the stationary law, which
//! `--method backward` runs at temperature 0: Eq. (S12)) and the search ends the first time x(t) reaches a level L
//! ([`PositionTarget::Level`], one-sided) or leaves an interval (a, b)
//! ([`PositionTarget::Interval`]). Every resetting protocol of the model
//! runs: velocity resetting (x kept), full resetting (`--reset-position`:
//! x → x_r with the velocity), periodic and renewal clocks, refractory
//! periods, random velocity targets and re-drawn noise.
//!
//! With velocity-only resetting the position is unbounded: a one-sided
//! level is reached with a survival that decays as a power law
//! (S(t) ~ t^(-1/2) when the stationary mean velocity is zero), so the mean
//! search time is infinite; [`SearchProblem::mean_is_finite`] says when it
//! is finite, and [`tail`] fits the exponent of S(t) where it is not.
//!
//! - [`exact`]: the exact event-driven sampler (flow segments, the crossing
//!   of x found by a safeguarded root on each monotone piece).
//! - [`backward`]: the 2-D backward equation for T(x, v, eta) on an upwind
//!   mesh, Richardson-extrapolated with an error estimate.
//! - [`renewal`]: the state-resolved renewal route for full resetting, from
//!   the reset-free survival resolved by the final noise state, over any
//!   waiting-time law of the resets.
//! - [`clock_optimize`]: the renewal clock's best mean waiting time (its
//!   shape fixed) by the renewal route.
//! - [`euler`]: the Euler scheme's passage at dt and dt/2, extrapolated.
//! - [`distribution`]: S(t) and f(t) by the time-dependent backward
//!   equation with resets.
//! - [`tail`]: the power-law tail exponent of the Kaplan-Meier survival.
//! - [`optimize`]: tau against r, x_0 or L, and the optimal reset rate.
//! - [`solve`] with a [`SearchMethod`]: the one entry point. A particle
//!   method's run is cut into units of particles ([`particle_units`]) that
//!   [`assemble`] merges into the whole run's result, bit for bit.

pub mod backward;
pub mod clock_optimize;
pub mod distribution;
pub mod euler;
pub mod exact;
mod mesh;
pub mod optimize;
pub mod renewal;
pub mod tail;

use crate::error::{finite, Error, Result};
use crate::mfpt::estimator::{merge_units, FptStats};
use crate::mfpt::euler::{extrapolate, verify_extrapolation, Extrapolated};
use crate::mfpt::ParticleOptions;
use crate::model::reset::{NoiseAtReset, Refractory, Reset};
use crate::model::{Drag, Params};
use crate::parallel::Progress;
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// `true`: the serde default of a flag added to serialised options and
/// solutions (older files read as they were written).
pub(crate) fn yes() -> bool {
    true
}

pub use tail::{fit_tail, TailFit};

/// Where the search ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum PositionTarget {
    /// The first time x reaches the level L (one-sided; L > x0 or L < x0).
    Level(f64),
    /// The first exit of x from the open interval (a, b), a < x0 < b.
    Interval(f64, f64),
}

impl PositionTarget {
    /// The absorbing boundaries (lo, hi): the search runs while
    /// lo < x < hi (an unbounded side is ∓∞). `x0` picks the side of a level.
    pub fn bounds(&self, x0: f64) -> (f64, f64) {
        match *self {
            PositionTarget::Level(l) if l > x0 => (f64::NEG_INFINITY, l),
            PositionTarget::Level(l) => (l, f64::INFINITY),
            PositionTarget::Interval(a, b) => (a, b),
        }
    }
}

/// A validated search problem (build with SearchProblem::new).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawSearchProblem", into = "RawSearchProblem")]
pub struct SearchProblem {
    params: Params,
    x0: f64,
    v0: f64,
    target: PositionTarget,
}

/// Unvalidated mirror of [`SearchProblem`] for (de)serialisation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RawSearchProblem {
    /// Model parameters.
    pub params: Params,
    /// Initial position x_0.
    pub x0: f64,
    /// Initial velocity v_0.
    pub v0: f64,
    /// Where the search ends.
    pub target: PositionTarget,
}

impl TryFrom<RawSearchProblem> for SearchProblem {
    type Error = Error;
    fn try_from(r: RawSearchProblem) -> Result<Self> {
        SearchProblem::new(r.params, r.x0, r.v0, r.target)
    }
}

impl From<SearchProblem> for RawSearchProblem {
    fn from(p: SearchProblem) -> Self {
        RawSearchProblem {
            params: p.params,
            x0: p.x0,
            v0: p.v0,
            target: p.target,
        }
    }
}

/// Validate the target against the start: a level finite and not at x0
/// (`xt`), an interval finite with a < x0 < b (`interval`).
fn check_target(x0: f64, target: PositionTarget) -> Result<()> {
    match target {
        PositionTarget::Level(l) => {
            if !(l.is_finite() && l != x0) {
                return Err(Error::invalid(
                    "xt",
                    l,
                    format!("a finite level L != x0 = {x0}"),
                ));
            }
        }
        PositionTarget::Interval(a, b) => {
            if !(a.is_finite() && b.is_finite() && a < x0 && x0 < b) {
                return Err(Error::invalid(
                    "interval",
                    format!("{a},{b}"),
                    format!(
                        "finite A,B with A < x0 = {x0} < B (a non-empty interval around the start)"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A reset position must lie strictly on the start side of the target: a
/// full reset must not jump across (or onto) it.
fn check_reset_position(x0: f64, target: PositionTarget, xr: f64) -> Result<()> {
    let ok = match target {
        PositionTarget::Level(l) => (xr < l) == (x0 < l) && xr != l,
        PositionTarget::Interval(a, b) => a < xr && xr < b,
    };
    if ok {
        return Ok(());
    }
    let allowed = match target {
        PositionTarget::Level(l) => {
            let side = if x0 < l { "<" } else { ">" };
            format!("x_r {side} L = {l}, on the side of x0 = {x0} (a reset cannot jump across the target)")
        }
        PositionTarget::Interval(a, b) => {
            format!("{a} < x_r < {b}, inside the interval (a reset cannot jump out of it)")
        }
    };
    Err(Error::invalid("reset_position", xr, allowed))
}

impl SearchProblem {
    /// Validate: a noise model at temperature 0 only (a temperature is
    /// refused, naming `temperature`); x0, L, a, b finite; L != x0; a < x0 < b; v0 inside
    /// (v_l, v_u); a reset position strictly on the start side (the same
    /// side of L as x0, or inside (a, b)). NaN fails every check. A noise
    /// model is admitted here and gated per method by `noise_gate`.
    pub fn new(params: Params, x0: f64, v0: f64, target: PositionTarget) -> Result<Self> {
        if let Some(m) = params.noise().filter(|m| m.temperature() > 0.0) {
            return Err(Error::invalid(
                "temperature",
                m.temperature(),
                "temperature 0 for a search (--xt, --interval): no search method runs thermal noise",
            ));
        }
        let x0 = finite("x0", x0)?;
        let v0 = finite("v0", v0)?;
        let (vl, vu) = params.bounds();
        if !(v0 > vl && v0 < vu) {
            return Err(Error::invalid(
                "v0",
                v0,
                format!("{vl:.6} < v0 < {vu:.6} (the open velocity interval)"),
            ));
        }
        check_target(x0, target)?;
        if let Some(p) = params.schedule().position {
            check_reset_position(x0, target, p.x)?;
        }
        Ok(SearchProblem {
            params,
            x0,
            v0,
            target,
        })
    }

    /// Model parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }
    /// Initial position x_0.
    pub fn x0(&self) -> f64 {
        self.x0
    }
    /// Initial velocity v_0.
    pub fn v0(&self) -> f64 {
        self.v0
    }
    /// Where the search ends.
    pub fn target(&self) -> PositionTarget {
        self.target
    }

    /// Same problem with another reset rate (validated).
    pub fn with_rate(&self, rate: f64) -> Result<Self> {
        SearchProblem::new(self.params.with_rate(rate)?, self.x0, self.v0, self.target)
    }

    /// Same problem from another start position (validated).
    pub fn with_start(&self, x0: f64) -> Result<Self> {
        SearchProblem::new(self.params.clone(), x0, self.v0, self.target)
    }

    /// Same problem with another target (validated).
    pub fn with_target(&self, target: PositionTarget) -> Result<Self> {
        SearchProblem::new(self.params.clone(), self.x0, self.v0, target)
    }

    /// True when the mean search time is finite: see
    /// [`SearchProblem::infinite_mean_reason`], None exactly when finite.
    pub fn mean_is_finite(&self) -> bool {
        self.infinite_mean_reason().is_none()
    }

    /// Why the mean search time is infinite, in one line (None when it is
    /// finite). Finite: an interval target, or full resetting
    /// (params.schedule().position is Some) with a reset rate/period/clock.
    /// Refinements, each a case where the particle can never arrive with
    /// positive probability: a level needs a velocity towards it (with a
    /// noise model, a level whose fixed point is on its side of 0:
    /// `moves_towards`); a level with the paper's noise kept at resets needs
    /// lambda > 0 (else a particle in the state pointing away never turns);
    /// a clock of bounded support (a period, or a bounded law, Poisson
    /// resets added or not) needs the target within reach of its longest
    /// period from x_r (`reachable_within`), else the walk
    /// restarts before it can get there, forever (unless every path from
    /// the start arrives before the first reset: `arrives_surely`); a
    /// level with a clock of infinite mean waiting time is infinite.
    /// With velocity-only resetting and a level, S(t) decays as a power law
    /// (or tends to a constant): infinite, unless the resets give the
    /// velocity a stationary mean towards the level (`drifts_towards`):
    /// then x moves ballistically on average and the mean is finite. With
    /// a noise model without mirror symmetry the sign of the mean velocity
    /// is not decided here: such a level search is treated as infinite
    /// (tau not reported, the tail exponent fitted).
    pub fn infinite_mean_reason(&self) -> Option<&'static str> {
        let p = &self.params;
        let sched = p.schedule();
        if let PositionTarget::Level(l) = self.target {
            if !self.moves_towards(l) {
                return Some(AWAY_REASON);
            }
        }
        let Some(pos) = sched.position else {
            return match self.target {
                PositionTarget::Level(_) if !self.mirrored() => Some(ASYMMETRIC_NOISE_REASON),
                PositionTarget::Level(l) if !self.drifts_towards(l) => Some(INFINITE_MEAN_REASON),
                _ => None,
            };
        };
        let resets = p.rate() > 0.0 || sched.scheduled_clock();
        // A noise model's chain is irreducible: with two states or more
        // every state is left, so a particle always turns.
        let turns = p.lambda() > 0.0
            || p.noise().is_some_and(|m| m.levels().len() > 1)
            || p.reset().noise() == NoiseAtReset::Redrawn;
        // A failed period of a level search lasts the waiting time R:
        // E(R) = ∞ makes the mean search time infinite.
        let heavy = sched.clock.as_ref().is_some_and(|c| !c.mean().is_finite());
        let level = matches!(self.target, PositionTarget::Level(_));
        if level && !resets {
            return Some(NO_RESETS_REASON);
        }
        if level && !turns {
            return Some(NO_TURNS_REASON);
        }
        if level && heavy {
            return Some(HEAVY_CLOCK_REASON);
        }
        let longest = self.longest_period();
        if longest.is_finite() && !self.reachable_within(pos.x, longest) && !self.arrives_surely() {
            return Some(OUT_OF_REACH_REASON);
        }
        None
    }

    /// The longest time the particle can move freely between two position
    /// resets: the period T (with a fixed refractory period, the whole
    /// cycle), the end of a renewal law's support (plus a fixed refractory
    /// period: the clock restarts at its end), ∞ for a Poisson clock alone
    /// or an exponential refractory period.
    fn longest_period(&self) -> f64 {
        let sched = self.params.schedule();
        let hold = match sched.refractory {
            Some(Refractory::Exp { .. }) => return f64::INFINITY,
            Some(Refractory::Fixed { duration }) => duration,
            None => 0.0,
        };
        match (sched.periodic, sched.clock.clone()) {
            (Some(per), _) => per.cycle(sched.refractory),
            (None, Some(c)) => c.support_end() + hold,
            (None, None) => f64::INFINITY,
        }
    }

    /// Whether every path from the start leaves through the target before
    /// the first reset of a periodic clock alone (no Poisson resets: they
    /// may come at any time): the slowest path towards an end (the flow in
    /// the state pointing away, never flipping: every path lies between the
    /// two flows, the flow being monotone in eta) reaches it within T. The
    /// flows' extremes are sampled at 64 times, a lower bound of the reach.
    fn arrives_surely(&self) -> bool {
        let p = &self.params;
        let Some(per) = p.schedule().periodic else {
            return false;
        };
        if p.rate() > 0.0 {
            return false;
        }
        let (lo, hi) = self.target.bounds(self.x0);
        let (amin, amax) = self.extreme_levels();
        let (mut low_max, mut high_min) = (f64::NEG_INFINITY, f64::INFINITY);
        for k in 1..=64 {
            let t = per.period * k as f64 / 64.0;
            let (down, up) = crate::with_drag!(p.drag(), |d| (
                d.flow_displacement(amin, self.v0, t),
                d.flow_displacement(amax, self.v0, t)
            ));
            low_max = low_max.max(down);
            high_min = high_min.min(up);
        }
        self.x0 + low_max >= hi || self.x0 + high_min <= lo
    }

    /// The lowest and highest noise levels (-Sigma, Sigma for the paper's
    /// noise): the flow is monotone in the level, so every path lies
    /// between the flows of these two.
    fn extreme_levels(&self) -> (f64, f64) {
        let p = &self.params;
        match p.noise() {
            None => (-p.sigma(), p.sigma()),
            Some(m) => m
                .levels()
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &l| {
                    (a.min(l), b.max(l))
                }),
        }
    }

    /// Whether the velocity can point towards the level `l` (the velocity
    /// interval (v_l, v_u) reaches the side of 0 towards l): always for the
    /// paper's noise; with a noise model whose levels all push away from
    /// l, x never moves towards it.
    fn moves_towards(&self, l: f64) -> bool {
        let (vl, vu) = self.params.bounds();
        if l > self.x0 {
            vu > 0.0
        } else {
            vl < 0.0
        }
    }

    /// Whether the noise is mirror-symmetric (the paper's, or a model with
    /// a mirror map of its states: a_m(s) = -a_s, the same rates).
    fn mirrored(&self) -> bool {
        self.params
            .noise()
            .map_or(true, |m| m.kind().mirror().is_some())
    }

    /// Whether resets (Poisson or periodic) to a target whose mean <v_r>
    /// is not 0 drive x towards the level `l`. The noise is symmetric (the
    /// caller checks it: [`Self::mirrored`]) and g odd, so <v_r> = 0 gives <v> = 0 by mirror symmetry, and the flow
    /// is monotone in its start, so a reset distribution shifted up (down)
    /// gives a larger (smaller) stationary velocity: <v> has the sign of
    /// <v_r>.
    fn drifts_towards(&self, l: f64) -> bool {
        let p = &self.params;
        let resets = p.rate() > 0.0 || p.schedule().scheduled_clock();
        let (mean_vr, _) = p.reset().target().moments();
        resets && mean_vr != 0.0 && (l - self.x0) * mean_vr > 0.0
    }

    /// Whether a particle reset to `xr` can reach the target within the
    /// free time `period` between position resets ([`Self::longest_period`]):
    /// an upper bound of the reach, the farthest displacement being the ±
    /// flow from the extreme reset velocity with no flip (every path lies
    /// between the two flows; re-drawn noise changes nothing); with a
    /// refractory period, v_max over the whole time (the hold's velocity
    /// is inside the bounds); an exponential one is taken as reaching.
    fn reachable_within(&self, xr: f64, period: f64) -> bool {
        let p = &self.params;
        let (lo, hi) = self.target.bounds(self.x0);
        let (up, down) = match p.schedule().refractory {
            // An exponential hold is unbounded: held at a nonzero velocity
            // the particle reaches any level.
            Some(Refractory::Exp { .. }) => return true,
            Some(_) => {
                let reach = p.v_upper().max(-p.v_lower()) * period;
                (reach, -reach)
            }
            None => {
                let (vlo, vhi) = p.reset().target().support();
                let (amin, amax) = self.extreme_levels();
                crate::with_drag!(p.drag(), |d| (
                    d.flow_displacement(amax, vhi, period),
                    d.flow_displacement(amin, vlo, period)
                ))
            }
        };
        xr + up >= hi || xr + down <= lo
    }
}

/// The search methods that run a noise model other than the paper's at
/// T = 0, as a refusal lists them ([`crate::capability::runners_where`]):
/// every one.
pub const NOISE_RUNNERS: &str = "mfpt --xt, mfpt distribution --xt";
/// The backward solver's name in [`noise_gate`].
pub(crate) const BACKWARD: &str = "--method backward";
/// The exact sampler's name in [`noise_gate`].
pub(crate) const EXACT: &str = "--method exact";
/// The Euler scheme's name in [`noise_gate`].
pub(crate) const EULER: &str = "--method euler";
/// The renewal route's name in [`noise_gate`].
pub(crate) const RENEWAL: &str = "--method renewal";
/// The distribution's name in [`noise_gate`].
pub(crate) const DISTRIBUTION: &str = "mfpt distribution --xt";
/// The paper-noise constructor of the exact sampler, for [`noise_gate`].
pub(crate) const PAPER_NOISE_ONLY: &str =
    "SearchSampler::new (SearchSampler::with_chain runs a noise)";

/// The noise gate of the search: the method's name mapped to its
/// [`crate::capability::Solver`], whose table decides
/// ([`crate::capability::check_noise`]: a noise model at T = 0 runs in
/// every search method, [`NOISE_RUNNERS`]); a routine of the
/// paper's noise only ([`PAPER_NOISE_ONLY`]) refuses every noise model.
pub(crate) fn noise_gate(problem: &SearchProblem, method: &str) -> Result<()> {
    match solver_of(method) {
        Some(solver) => crate::capability::check_noise(solver, problem.params()),
        None => match problem.params().noise() {
            Some(m) => crate::model::noise::support::refuse(method, m),
            None => Ok(()),
        },
    }
}

/// The [`crate::capability::Solver`] of a search method's name (None for
/// [`PAPER_NOISE_ONLY`]).
pub(crate) fn solver_of(method: &str) -> Option<crate::capability::Solver> {
    use crate::capability::Solver;
    Some(match method {
        BACKWARD => Solver::SearchBackward,
        EXACT => Solver::SearchExact,
        EULER => Solver::SearchEuler,
        RENEWAL => Solver::SearchRenewal,
        DISTRIBUTION => Solver::SearchDistribution,
        _ => return None,
    })
}

/// How a search problem is solved. The one dispatch point: a deterministic
/// method joins as a variant here and an arm in [`solve`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "lowercase")]
pub enum SearchMethod {
    /// Exact event-driven particles (see [`exact`]).
    Exact(ParticleOptions),
    /// The 2-D backward equation (see [`backward`]).
    Backward(backward::BackwardOptions),
    /// The state-resolved renewal route of full resetting, over the
    /// parameters' own reset clock (see [`renewal`]).
    Renewal(renewal::RenewalOptions),
    /// Euler particles at `dt` and `dt/2`, extrapolated to dt → 0 (see
    /// [`euler`]).
    Euler {
        /// The coarser time step.
        dt: f64,
        /// Particles (per step), time cap and seed (both steps).
        #[serde(flatten)]
        run: ParticleOptions,
    },
}

impl SearchMethod {
    /// Short name (`exact`, `backward`, `renewal`, `euler`).
    pub fn name(&self) -> &'static str {
        match self {
            SearchMethod::Exact(_) => "exact",
            SearchMethod::Backward(_) => "backward",
            SearchMethod::Renewal(_) => "renewal",
            SearchMethod::Euler { .. } => "euler",
        }
    }

    /// The particle options of a particle method.
    pub fn particles(&self) -> Option<&ParticleOptions> {
        match self {
            SearchMethod::Exact(run) | SearchMethod::Euler { run, .. } => Some(run),
            _ => None,
        }
    }

    /// The units of particles ([`crate::parallel::UNIT`] each) of a
    /// particle method's run, the grain of cutting it into parts: those of
    /// its particles, twice over for Euler (units of the run at dt, then
    /// of the run at dt/2); None for a deterministic method.
    pub fn unit_count(&self) -> Option<u64> {
        let per_run = crate::parallel::unit_count(self.particles()?.particles);
        match self {
            SearchMethod::Euler { .. } => Some(2 * per_run),
            _ => Some(per_run),
        }
    }

    /// Work and memory of a deterministic method (its refusals of a
    /// problem it cannot solve, first); None for particles.
    pub fn cost(&self, problem: &SearchProblem) -> Result<Option<backward::Cost>> {
        match self {
            SearchMethod::Exact(_) | SearchMethod::Euler { .. } => Ok(None),
            SearchMethod::Backward(o) => backward::estimate(problem, o).map(Some),
            SearchMethod::Renewal(o) => {
                let waiting = renewal::WaitingTime::of(problem.params())?;
                renewal::estimate(problem, &waiting, o).map(Some)
            }
        }
    }

    /// Validate before anything runs: at least 4 particles (two per
    /// starting state), t_max > 0, and a finite t_max where the mean search
    /// time is infinite (some particles would never stop).
    pub fn check(&self, problem: &SearchProblem) -> Result<()> {
        match *self {
            SearchMethod::Backward(_) | SearchMethod::Renewal(_) => self.cost(problem).map(|_| ()),
            SearchMethod::Euler { dt, run } => {
                if run.particles < 4 {
                    return Err(Error::invalid("particles", run.particles, "particles >= 4"));
                }
                euler::SearchEuler::new(problem, dt, run.t_max).map(drop)
            }
            SearchMethod::Exact(run) => {
                noise_gate(problem, EXACT)?;
                if run.particles < 4 {
                    return Err(Error::invalid("particles", run.particles, "particles >= 4"));
                }
                crate::mfpt::exact::check_t_max(run.t_max)?;
                if run.t_max.is_infinite() && !problem.mean_is_finite() {
                    return Err(Error::invalid(
                        "t_max",
                        run.t_max,
                        "a finite t_max: the mean search time of this problem is infinite \
                         (see infinite_mean_reason in the report of a finite t_max), so some \
                         particles would never stop",
                    ));
                }
                Ok(())
            }
        }
    }
}

/// A particle estimate of a search problem.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParticleSearch {
    /// Mergeable first-passage statistics (the Kaplan-Meier curve included).
    pub stats: FptStats,
    /// Whether the mean search time is finite ([`SearchProblem::mean_is_finite`]).
    pub mean_is_finite: bool,
    /// Where the mean is infinite: the fitted tail exponent of S(t)
    /// (`None` where the curve has too few resolved points).
    pub tail: Option<TailFit>,
}

/// The result of [`solve`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", content = "result", rename_all = "lowercase")]
pub enum SearchResult {
    /// From particles.
    Particles(ParticleSearch),
    /// From the 2-D backward equation.
    Backward(backward::SearchSolution),
    /// From the renewal route.
    Renewal(renewal::RenewalSolution),
    /// From Euler particles at two steps.
    Euler(EulerSearch),
}

/// An Euler estimate of a search problem: the runs at dt and dt/2 and
/// their extrapolation to dt → 0 ([`euler`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EulerSearch {
    /// The coarser step.
    pub dt: f64,
    /// The run at dt.
    pub coarse: FptStats,
    /// The run at dt/2 (its Kaplan-Meier curve is the reported one).
    pub fine: FptStats,
    /// 2 T(dt/2) - T(dt), with its standard-error bound.
    pub extrapolated: Extrapolated,
    /// Whether the mean search time is finite (else tau is NaN).
    pub mean_is_finite: bool,
    /// Where the mean is infinite: the tail exponent of the run at dt/2.
    pub tail: Option<TailFit>,
}

impl SearchResult {
    /// (tau, tau+, tau-) and the error of tau: a standard error for
    /// particles, an error estimate for the deterministic routes (NaN where
    /// the mean is infinite or particles were censored).
    pub fn tau(&self) -> (f64, f64, f64, f64) {
        match self {
            SearchResult::Particles(p) => {
                let s = p.stats.summary();
                (p.tau(), s.tau_plus, s.tau_minus, s.tau_err)
            }
            SearchResult::Backward(b) => (b.tau, b.tau_plus, b.tau_minus, b.error_estimate),
            SearchResult::Renewal(r) => (r.tau, r.tau_plus, r.tau_minus, r.error_estimate),
            SearchResult::Euler(e) => {
                let x = &e.extrapolated;
                let m = |v: f64| if e.mean_is_finite { v } else { f64::NAN };
                (m(x.tau), m(x.tau_plus), m(x.tau_minus), m(x.tau_err))
            }
        }
    }
}

impl ParticleSearch {
    /// tau = (tau+ + tau-)/2, or NaN where the mean is infinite or any
    /// particle was censored.
    pub fn tau(&self) -> f64 {
        if self.mean_is_finite {
            self.stats.summary().tau
        } else {
            f64::NAN
        }
    }
}

/// Why tau is not reported for a problem with an infinite mean, in one
/// line: velocity-only resetting and a one-sided level (the other causes:
/// [`SearchProblem::infinite_mean_reason`]).
pub const INFINITE_MEAN_REASON: &str = "the mean search time is infinite: with velocity-only \
     resetting (no position reset) x is unbounded and a one-sided level is reached with a \
     power-law survival S(t) ~ t^-theta (theta = 1/2 with zero mean velocity) or, out of reach, \
     never; the tail exponent is reported instead";

/// A level that no velocity moves towards.
const AWAY_REASON: &str = "the mean search time is infinite: every level of the noise drives \
     the velocity away from the target level, so x never moves towards it";

/// Velocity-only resetting to a level with an asymmetric noise model.
const ASYMMETRIC_NOISE_REASON: &str = "the mean search time is treated as infinite: with \
     velocity-only resetting and a noise without mirror symmetry the sign of the mean velocity \
     is not decided, so tau is not reported; the tail exponent is reported instead";

/// Full resetting without any reset (no rate, period or clock).
const NO_RESETS_REASON: &str = "the mean search time is infinite: the position is never reset \
     (no --rate, --reset-period or --reset-clock), so x is unbounded and a one-sided level is \
     reached with a power-law survival or never";

/// A level with lambda = 0 and the noise kept at resets.
const NO_TURNS_REASON: &str = "the mean search time is infinite: with lambda = 0 and the noise \
     kept at resets a particle in the state pointing away from the level never reaches it";

/// A level with a clock of infinite mean waiting time.
const HEAVY_CLOCK_REASON: &str = "the mean search time is infinite: the reset clock's mean \
     waiting time is infinite, and a failed period lasts one waiting time";

/// A bounded clock whose longest period is too short to reach the target.
const OUT_OF_REACH_REASON: &str = "the mean search time is infinite: the target is out of reach \
     between resets (the fastest path from the reset point cannot get there within the longest \
     period of the clock), so the search restarts forever";

/// Solve `problem` by `method`, validated first ([`SearchMethod::check`]).
/// The exact sampler runs every resetting protocol and drag law. Particle
/// estimates are bit-identical for any thread count.
pub fn solve(
    problem: &SearchProblem,
    method: &SearchMethod,
    progress: &dyn Progress,
) -> Result<SearchResult> {
    method.check(problem)?;
    match (*method, method.unit_count()) {
        (SearchMethod::Backward(o), _) => {
            backward::solve_watched(problem, &o, progress).map(SearchResult::Backward)
        }
        (SearchMethod::Renewal(o), _) => {
            let waiting = renewal::WaitingTime::of(problem.params())?;
            renewal::solve_watched(problem, &waiting, &o, progress).map(SearchResult::Renewal)
        }
        (_, Some(all)) => assemble(
            problem,
            method,
            &particle_units(problem, method, 0..all, progress)?,
        ),
        (_, None) => unreachable!("a particle method has units"),
    }
}

/// The unit totals of units `units` (inside `0..unit_count`) of a particle
/// method's run, validated first: computed anywhere, [`assemble`]d from all
/// units in order they give [`solve`]'s result bit for bit. Euler's units
/// are those of the run at dt, then those of the run at dt/2.
pub fn particle_units(
    problem: &SearchProblem,
    method: &SearchMethod,
    units: Range<u64>,
    progress: &dyn Progress,
) -> Result<Vec<FptStats>> {
    method.check(problem)?;
    crate::mfpt::method::check_units(method.unit_count(), &units)?;
    match *method {
        SearchMethod::Exact(run) => {
            exact::units(problem, run.t_max, run.particles, run.seed, units, progress)
        }
        SearchMethod::Euler { dt, run } => {
            let per = crate::parallel::unit_count(run.particles);
            let mut out = Vec::new();
            for (k, step) in [dt, 0.5 * dt].into_iter().enumerate() {
                let base = k as u64 * per;
                let lo = units.start.clamp(base, base + per) - base;
                let hi = units.end.clamp(base, base + per) - base;
                let e = euler::SearchEuler::new(problem, step, run.t_max)?;
                out.extend(e.units(run.particles, lo..hi, run.seed, progress));
            }
            Ok(out)
        }
        _ => unreachable!("checked: a particle method"),
    }
}

/// The result of a particle method's run from the totals of all its units
/// ([`particle_units`], in unit order), its invariants checked.
pub fn assemble(
    problem: &SearchProblem,
    method: &SearchMethod,
    units: &[FptStats],
) -> Result<SearchResult> {
    let (Some(run), Some(all)) = (method.particles(), method.unit_count()) else {
        return Err(Error::invalid(
            "method",
            method.name(),
            "a particle method (only particles are cut into units)",
        ));
    };
    if units.len() as u64 != all {
        return Err(Error::invalid(
            "units",
            units.len(),
            format!("all {all} units of the run, in order"),
        ));
    }
    let finite = problem.mean_is_finite();
    let tail_of = |s: &FptStats| if finite { None } else { fit_tail(s) };
    let result = match *method {
        SearchMethod::Euler { dt, .. } => {
            let half = units.len() / 2;
            let coarse = merge_units(run.t_max, &units[..half]);
            let fine = merge_units(run.t_max, &units[half..]);
            SearchResult::Euler(EulerSearch {
                dt,
                extrapolated: extrapolate(&coarse.summary(), &fine.summary()),
                mean_is_finite: finite,
                tail: tail_of(&fine),
                coarse,
                fine,
            })
        }
        _ => {
            let stats = merge_units(run.t_max, units);
            SearchResult::Particles(ParticleSearch {
                tail: tail_of(&stats),
                stats,
                mean_is_finite: finite,
            })
        }
    };
    verify_particles(problem, &result, run.t_max)?;
    // An infinite mean has no extrapolation to verify (tau is not reported).
    match &result {
        SearchResult::Euler(e) if e.mean_is_finite => {
            verify_extrapolation(&e.coarse.summary(), &e.fine.summary(), least_time(problem))?
        }
        _ => {}
    }
    Ok(result)
}

/// The least search time: the distance to the target from the start (or
/// from x_r after a full reset) at the largest speed max |v|, slightly
/// lowered against rounding.
fn least_time(problem: &SearchProblem) -> f64 {
    let (lo, hi) = problem.target().bounds(problem.x0());
    let gap = |x: f64| (x - lo).min(hi - x);
    let p = problem.params();
    let mut distance = gap(problem.x0());
    if let Some(pos) = p.schedule().position {
        distance = distance.min(gap(pos.x));
    }
    let (vl, vu) = p.bounds();
    distance / vl.abs().max(vu.abs()) * (1.0 - 1e-12)
}

/// Every passage covers the distance to the target from the start (or
/// from x_r after a full reset) at a speed of at most max |v|: the
/// restricted means of both starting states must respect it (on the
/// Euler grid as well: x moves at most max |v| dt per step), or the
/// sampler lost precision and the answer is refused. The restricted means
/// are E[min(T, t_max)]: the bound is min(distance / max |v|, t_max).
fn verify_particles(problem: &SearchProblem, result: &SearchResult, t_max: f64) -> Result<()> {
    let bound = least_time(problem).min(t_max * (1.0 - 1e-12));
    let runs: Vec<&FptStats> = match result {
        SearchResult::Particles(r) => vec![&r.stats],
        SearchResult::Euler(e) => vec![&e.coarse, &e.fine],
        _ => vec![],
    };
    for s in runs.iter().map(|r| r.summary()) {
        for (name, m) in [("rmst_plus", s.rmst_plus), ("rmst_minus", s.rmst_minus)] {
            if !(m >= bound) {
                return Err(Error::Numerical {
                    method: "the search sampler (--method exact or euler)",
                    reason: format!(
                        "{name} = {m:e} is below the least search time {bound:e} (distance / \
                         max |v|, at most t_max): the sampler lost precision; refused"
                    ),
                });
            }
        }
    }
    Ok(())
}
