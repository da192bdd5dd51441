//! Which method runs which noise model: the noise dimension of
//! [`crate::capability`] (docs/equations.md, "Noise kinds";
//! docs/reference/support.md). Every engine runs the paper's symmetric
//! telegraph noise without thermal noise, which [`crate::Params`] carries
//! as its default; which runs another is [`crate::capability::noise_runs`].

use super::NoiseModel;
use crate::capability::{self, NoiseClass};
use crate::error::Result;
use crate::model::reset::Solver;

/// What the closed forms of `irtp analytic` run of a noise model other
/// than the paper's: [`supports`] answers `false` for them, as
/// [`crate::analytic::noise`] checks its own cases.
pub const CLOSED_FORMS: &str = "linear drag; T = 0, r = 0: asymmetric telegraph";

/// Whether `solver` runs `noise` (a model other than the paper's default),
/// as [`capability::noise_runs`] says for its class.
pub fn supports(solver: Solver, noise: &NoiseModel) -> bool {
    capability::noise_runs(solver, NoiseClass::of_model(noise))
}

/// Refuse a noise model that `solver` does not run
/// ([`capability::check_model`]).
pub fn check(solver: Solver, noise: &NoiseModel) -> Result<()> {
    capability::check_model(solver, noise)
}

/// The refusal of a noise model by `method`, a routine that runs the
/// paper's noise only (a command or routine, for the message): names
/// `temperature` for the paper's noise with T > 0, else `noise`, and lists
/// the methods that run its class.
pub fn refuse(method: &str, noise: &NoiseModel) -> Result<()> {
    let c = NoiseClass::of_model(noise);
    let (name, value) = blamed(noise);
    Err(capability::fitted(
        name,
        value,
        c.describe(),
        method,
        capability::noise_runners(c),
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
