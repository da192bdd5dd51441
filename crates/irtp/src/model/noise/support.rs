//! Which method runs which noise model: the noise dimension of the support
//! table of docs/reference/support.md (docs/equations.md, "Noise kinds").
//!
//! Every engine runs the paper's symmetric telegraph noise without thermal
//! noise, which [`crate::Params`] carries as its default; the Euler schemes
//! (`simulate --method euler`, `mfpt --method euler`) run every noise model
//! (docs/equations.md, "Euler schemes with a noise model"). Any other
//! noise model is refused by [`check`], called from
//! [`crate::Params::require`], with one line naming the flag and what runs
//! it. Besides the Euler schemes, what runs it is [`crate::analytic::noise`] (`irtp analytic`):
//! linear drag with any noise model and Poisson velocity resetting to a
//! point (Eqs. (N3)-(N6)), and any drag with an asymmetric telegraph noise
//! at r = 0 (Eq. (N8)), and the exact sampler (`simulate --method exact`,
//! [`crate::sim::exact`]): any finite-state noise at T = 0 (Eqs.
//! (N10)-(N12)) and with linear drag at any T (Eqs. (N40)-(N45)), and the Fokker-Planck solvers [`crate::fp`] (any drag,
//! any finite-state noise, any T, Eqs. (N20)-(N29)), and the backward
//! equations [`crate::mfpt`] (`mfpt --method backward`, scan, optimize:
//! any finite-state noise; with T > 0 linear, tanh and tan drags, Eqs.
//! (N30)-(N36)), and the first-passage-time distribution
//! [`crate::mfpt::distribution()`] (`mfpt distribution --method backward`:
//! any finite-state noise at T = 0, Eqs. (N37)-(N39); with T > 0 linear,
//! tanh and tan drags as the backward equations, Eq. (N49)), and the exact
//! first-passage sampler (`mfpt --method exact` and `mfpt distribution
//! --method exact`, [`crate::mfpt::exact`]): any finite-state noise at
//! T = 0 (Eqs. (N46)-(N48)), with every schedule modifier; T > 0 refused naming
//! `temperature` (no exact flow with thermal noise), and the search's 2-D
//! backward equation and two samplers (`mfpt --xt` or `--interval` with
//! `--method backward`, `exact` or `euler`, [`crate::search::backward`],
//! [`crate::search::exact`], [`crate::search::euler`]): any finite-state
//! noise at T = 0, the renewal route and the distribution refusing it at
//! one gate (`crate::search::noise_gate`).

use super::NoiseModel;
use crate::error::{Error, Result};
use crate::model::reset::Solver;

/// What runs a noise model other than the paper's, for messages.
pub const RUNNERS: &str = "analytic (linear drag: any noise and temperature, Poisson resetting \
    to a point; any drag: an asymmetric telegraph noise at temperature 0 and r = 0); simulate \
    --method exact (any finite-state noise at temperature 0, every protocol; linear drag at any \
    temperature, Poisson resetting); \
    simulate --method euler (any drag, noise and temperature, every protocol); mfpt --method \
    euler (any drag, noise and temperature, Poisson resetting without schedule modifiers); fp stationary, fp transient, fp msd (any \
    drag, any noise and temperature, Poisson resetting); mfpt --method backward, mfpt scan, mfpt optimize \
    (any noise at temperature 0; with a temperature: linear, tanh and tan (T <= 1) drags; \
    Poisson resetting); mfpt distribution --method backward (any finite-state noise at \
    temperature 0; with a temperature: linear, tanh and tan (T <= 1) drags; Poisson resetting); \
    mfpt --method exact, mfpt distribution --method exact (any finite-state noise at \
    temperature 0, every protocol); the search \
    (mfpt --xt or --interval) with --method backward, exact or euler, and mfpt scan and optimize \
    with --xt (any finite-state noise at temperature 0, every protocol the method runs)";

/// What the closed forms of `irtp analytic` run of a noise model other
/// than the paper's: [`supports`] answers `false` for them, as
/// [`crate::analytic::noise`] checks its own cases.
pub const CLOSED_FORMS: &str = "linear drag; T = 0, r = 0: asymmetric telegraph";

/// What a refusal of a noise model says runs it (one line; [`RUNNERS`],
/// the full list, is in `--help` of `--noise` and docs/reference/support.md).
pub const RUNS_IT: &str = "simulate and fp run any noise (see --help of --noise)";

/// Whether `solver` runs `noise` (a model other than the paper's default),
/// one line per method (docs/reference/support.md). The exact sampler runs
/// any finite-state noise at T = 0, and at T > 0 with linear drag (its
/// constructor refuses another drag at T > 0 naming `temperature`, and, naming
/// `noise`, a level whose fixed point sits at a kink of the drag, and for a
/// tabulated law a level whose fixed point is not the interval's farthest
/// edge; at T > 0 the schedule modifiers by their flags); the Euler schemes run
/// every one (Eqs. (N15)-(N19)). The closed forms of `irtp analytic` for
/// such models are in [`crate::analytic::noise`], which checks its own
/// cases.
pub fn supports(solver: Solver, noise: &NoiseModel) -> bool {
    // One line per method: an engine that learns to run a noise model
    // says which here (docs/reference/support.md follows this match).
    match solver {
        // Any finite-state noise at T = 0 (sim::exact); with T > 0 linear
        // drag (exact Ornstein-Uhlenbeck segments), the engine refusing the
        // other drags by name (sim::exact::ou).
        Solver::Exact => true,
        // Any finite-state noise at any T (sim::euler::noise).
        Solver::Euler => true,
        // The N-state forward solvers (crate::fp, Eqs. (N20)-(N29)): any
        // finite-state noise, any T >= 0 (a truncated domain for an
        // unbounded drag at T > 0, with its tail mass checked).
        Solver::FpStationary => true,
        Solver::FpTransient => true,
        Solver::FpMsd => true,
        // N coupled equations; thermal: linear, tanh, tan (T <= 1) drags,
        // the engine refusing the others by name (mfpt::nstate).
        Solver::Backward => true,
        // N coupled survival equations, the atoms split off at T = 0;
        // thermal: the backward equations' drags (linear, tanh, tan with
        // T <= 1), the engine refusing the others by name (mfpt::ndist).
        Solver::FptDistribution => true,
        Solver::MfptOptimize => true,
        // Any finite-state noise at T = 0 (mfpt::exact's N-state loop);
        // with T > 0 there is no exact flow: refused naming `temperature`
        // ([`check`]).
        Solver::MfptExact => noise.temperature() == 0.0,
        // Any finite-state noise at any T (mfpt::euler's noise kernel).
        Solver::MfptEuler => true,
        Solver::ClosedForm => false,
    }
}

/// Refuse a noise model that `solver` does not run ([`refuse`]); the exact
/// first-passage sampler refuses thermal noise naming `temperature` (it
/// runs every finite-state noise at T = 0).
pub fn check(solver: Solver, noise: &NoiseModel) -> Result<()> {
    if supports(solver, noise) {
        return Ok(());
    }
    if solver == Solver::MfptExact && noise.temperature() > 0.0 {
        return Err(Error::invalid(
            "temperature",
            noise.temperature(),
            format!(
                "temperature 0 for {} (no exact flow with thermal noise); {RUNS_IT}",
                solver.command()
            ),
        ));
    }
    refuse(solver.command(), noise)
}

/// The refusal of a noise model by `method` (a command, for the message):
/// names `temperature` for the paper's noise with T > 0, else `noise`, and
/// lists [`RUNNERS`] (the search's methods decide at their own gate,
/// `crate::search::noise_gate`). The message
/// says what runs it in one line ([`RUNS_IT`]).
pub fn refuse(method: &str, noise: &NoiseModel) -> Result<()> {
    let (name, value) = blamed(noise);
    Err(Error::invalid(
        name,
        value,
        format!("the paper's noise at T = 0 for {method}; {RUNS_IT}"),
    ))
}

/// The flag a refusal of `noise` names, and its value: `temperature` for
/// the paper's noise with T > 0 (only the temperature was asked for), else
/// `noise` and its spec.
pub fn blamed(noise: &NoiseModel) -> (&'static str, String) {
    if noise.temperature() > 0.0 && noise.kind().symmetric_telegraph().is_some() {
        ("temperature", noise.temperature().to_string())
    } else {
        ("noise", noise.spec())
    }
}
