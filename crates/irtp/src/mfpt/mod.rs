//! Mean first-passage time (MFPT) to a target velocity v_t (paper Sec. 2.2, Fig. 7).
//!
//! The particle starts at v_0 with eta(0) = ±Sigma (equally likely) and the
//! first-passage time is the first t with v(t) = v_t. Conditional means
//! tau±(v_0) solve the backward equations of the *simulated* process, whose
//! generator is L f(v,±) = (±Sigma - g(v)) f' + lambda [f(v,∓) - f(v,±)]
//! + r [f(v_r,±) - f(v,±)]; L tau± = -1 gives, on (v_l, v_t),
//!
//! (Sigma - g) tau+' + lambda (tau- - tau+) + r (tau+(v_r) - tau+) = -1,
//! (-Sigma - g) tau-' + lambda (tau+ - tau-) + r (tau-(v_r) - tau-) = -1,
//!
//! with tau+(v_t) = 0 and regularity at v_l, where the - drift vanishes.
//! The paper's Eqs. (26)-(27) print the drifts as g ± Sigma (the sign of g
//! flipped); [`backward::DriftSign::PaperPrinted`] solves that printed form so
//! tests can show it disagrees with the particle simulation.
//!
//! Targets below v_0 are handled by the reflection v → -v (g is odd, the
//! noise symmetric): tau±(v_0; v_t, v_r) = tau∓(-v_0; -v_t, -v_r).
//!
//! One home for the first-passage problem: [`Problem`], the estimators and
//! all three methods behind one entry point, [`solve`] with a [`Method`].
//!
//! - [`backward`]: direct O(N) second-order solve of the backward equations,
//!   one engine for the paper's noise and a noise model (N states, thermal
//!   noise).
//! - [`exact`]: exact event-driven particles (the sampler of [`crate::sim::exact`]).
//! - [`control`]: the martingale control variate of exact passages, from an
//!   approximate backward solution.
//! - [`euler`]: Euler particles (the step of [`crate::sim::euler`]).
//! - [`estimator`]: first-passage statistics of any particle method.
//! - [`survival`]: the Kaplan-Meier survival curve of censored passage times.
//! - [`method`]: [`Method`], [`solve`] and its [`MfptResult`].
//! - [`optimize`]: scans and the optimal resetting rate.

pub mod backward;
pub mod control;
pub mod distribution;
pub mod estimator;
pub mod euler;
pub mod exact;
pub mod method;
pub mod optimize;
pub mod survival;
mod upwind;

use crate::error::{finite, Error, Result};
use crate::model::reset::Reset;
use crate::model::Params;
use serde::{Deserialize, Serialize};

pub use backward::{BackwardOptions, BackwardSolution, DriftSign, Moments};
pub use distribution::{distribution, Atom, Distribution, DistributionOptions};
pub use estimator::{first_passage_stats, FptSample, FptStats, FptSummary};
pub use euler::EulerFpt;
pub use exact::FirstPassage;
pub use method::{assemble, particle_units, solve, Method, MfptResult, ParticleOptions};
pub use optimize::{optimize_rate, scan, OptimizeOptions, Optimum, ScanAxis, ScanPoint};
pub use survival::SurvivalCurve;

/// A validated first-passage problem: model parameters, start v_0, target v_t.
/// Built with [`Problem::new`] (also on deserialisation), so always admissible.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawProblem", into = "RawProblem")]
pub struct Problem {
    params: Params,
    v0: f64,
    vt: f64,
}

/// Unvalidated mirror of [`Problem`] for (de)serialisation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RawProblem {
    /// Model parameters.
    pub params: Params,
    /// Initial velocity v_0.
    pub v0: f64,
    /// Target velocity v_t.
    pub vt: f64,
}

impl TryFrom<RawProblem> for Problem {
    type Error = Error;
    fn try_from(r: RawProblem) -> Result<Self> {
        Problem::new(r.params, r.v0, r.vt)
    }
}

impl From<Problem> for RawProblem {
    fn from(p: Problem) -> Self {
        RawProblem {
            params: p.params,
            v0: p.v0,
            vt: p.vt,
        }
    }
}

/// v0 and v_r on opposite sides of vt. v0 is always given explicitly and
/// v_r is often left at its default 0: blame v0 then, else v_r.
fn wrong_side(v0: f64, vt: f64, vr: f64) -> Error {
    let why = "a reset cannot jump across the target";
    if vr == 0.0 {
        let (side, start) = if vr < vt {
            ("<", "above")
        } else {
            (">", "below")
        };
        Error::invalid(
            "v0",
            v0,
            format!(
                "v0 {side} vt = {vt}, on the side of the reset velocity v_r = {vr} ({why}); \
                 to start {start} vt, choose v_r {start} vt too"
            ),
        )
    } else {
        let side = if v0 < vt { "<" } else { ">" };
        Error::invalid(
            "reset_velocity",
            vr,
            format!("v_r {side} vt = {vt}, on the side of v0 = {v0} ({why})"),
        )
    }
}

impl Problem {
    /// Validate: lambda > 0 for the
    /// paper's noise (else the - state never arrives), v_l < v_t < v_u
    /// (the ± state only approaches v_u / v_l asymptotically, so a target
    /// there is never reached), v_0 and v_r strictly on the same side of v_t
    /// (a reset must not jump across the target) and inside (v_l, v_u).
    pub fn new(params: Params, v0: f64, vt: f64) -> Result<Self> {
        // Each method refuses what it does not run (`Params::require`);
        // every noise class runs in `mfpt --method backward` or `euler`
        // (crate::capability::noise_runs).
        let v0 = finite("v0", v0)?;
        let vt = finite("vt", vt)?;
        let (vl, vu) = params.bounds();
        if params.noise().is_none() && !(params.lambda() > 0.0) {
            return Err(Error::invalid(
                "lambda",
                params.lambda(),
                "lambda > 0 for first passage (with lambda = 0 a particle in the -Sigma state never reaches the target)",
            ));
        }
        if !(vt > vl && vt < vu) {
            return Err(Error::invalid(
                "vt",
                vt,
                format!(
                    "{vl} < vt < {vu} (the velocity interval's edges are approached only asymptotically, never reached)"
                ),
            ));
        }
        let vr = params.reset_velocity();
        let up = v0 < vt;
        if !(v0 > vl && v0 < vu) || v0 == vt {
            return Err(Error::invalid(
                "v0",
                v0,
                format!("{vl} < v0 < {vu} and v0 != vt"),
            ));
        }
        // A random target may land beyond v_t: that reset is the passage
        // (the particle methods count it at the reset instant).
        let point = params.reset().point().is_some();
        if point && ((up && !(vr < vt)) || (!up && !(vr > vt))) {
            return Err(wrong_side(v0, vt, vr));
        }
        Ok(Problem { params, v0, vt })
    }

    /// Model parameters (rate r and reset velocity v_r included).
    pub fn params(&self) -> &Params {
        &self.params
    }
    /// Initial velocity v_0.
    pub fn v0(&self) -> f64 {
        self.v0
    }
    /// Target velocity v_t.
    pub fn vt(&self) -> f64 {
        self.vt
    }

    /// Same problem with another reset rate (validated).
    pub fn with_rate(&self, rate: f64) -> Result<Self> {
        Problem::new(self.params.with_rate(rate)?, self.v0, self.vt)
    }

    /// Same problem with another target (validated).
    pub fn with_target(&self, vt: f64) -> Result<Self> {
        Problem::new(self.params.clone(), self.v0, vt)
    }

    /// True when the target lies above the start (the + state drives into it).
    pub fn upward(&self) -> bool {
        self.v0 < self.vt
    }

    /// The equivalent upward problem (v → -v when the target is below v_0),
    /// and whether the ± labels were swapped.
    pub fn canonical(&self) -> (Problem, bool) {
        if self.upward() {
            (self.clone(), false)
        } else {
            let p = self.params.mirrored_reset();
            (
                Problem {
                    params: p,
                    v0: -self.v0,
                    vt: -self.vt,
                },
                true,
            )
        }
    }
}
