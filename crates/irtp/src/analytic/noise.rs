//! The closed forms for a noise model other than the paper's, from
//! [`Params`] (what `irtp analytic` runs; docs/equations.md, "Noise
//! kinds"): linear drag g = v with any noise model and Poisson velocity
//! resetting to a point ([`LinearNoise`], Eqs. (N3)-(N6)); any drag with an
//! asymmetric telegraph noise at temperature 0 and r = 0
//! ([`TelegraphR0Density`], Eq. (N8)). Both apply to linear drag with an
//! asymmetric telegraph noise at r = 0. Anything else is refused by name.

use super::linear_noise::{LinearNoise, NoiseMoments};
use super::telegraph_r0::TelegraphR0Density;
use crate::capability::{noise_runners, NoiseClass};
use crate::error::{Error, Result};
use crate::model::noise::{support::blamed, NoiseKind, NoiseModel};
use crate::model::{Drag, Params};

/// What the closed forms give for one set of parameters.
#[derive(Clone, Debug)]
pub struct NoiseClosedForm {
    /// The noise model.
    pub noise: NoiseModel,
    /// Linear drag: `<v>`, `<v²>`, the drift and D_eff, Eqs. (N3)-(N6).
    pub moments: Option<NoiseMoments>,
    /// An asymmetric telegraph noise at r = 0: the stationary density,
    /// Eq. (N8).
    pub density: Option<TelegraphR0Density>,
}

/// The closed forms for `p`'s noise model ([`Params::noise`]; the paper's
/// symmetric telegraph noise of `sigma`, `lambda` when None, so that both
/// spellings of one process take one route): refused with an error naming
/// the flag when the protocol is not the paper's Poisson clock to a point
/// with the noise kept, or when neither closed form applies.
pub fn solve(p: &Params) -> Result<NoiseClosedForm> {
    let paper;
    let noise = match p.noise() {
        Some(n) => n,
        None => {
            paper = crate::model::noise::NoiseModel::telegraph(p.sigma(), p.lambda())?;
            &paper
        }
    };
    if let Some(f) = p.schedule().features().into_iter().next() {
        return Err(Error::invalid(
            f.flag(),
            p.schedule().spec_of(f),
            format!(
                "the Poisson clock without modifiers with noise {}",
                noise.spec()
            ),
        ));
    }
    if let Some(s) = p.reset_spec() {
        return Err(Error::invalid(
            "reset_to",
            s,
            format!("a point target, noise kept, with noise {}", noise.spec()),
        ));
    }
    let moments = match p.drag().newtonian() {
        true => {
            let v_r = p.point_target("the linear-drag noise moments")?;
            Some(LinearNoise::new(1.0, noise.clone(), p.rate(), v_r)?.moments()?)
        }
        false => None,
    };
    let density = match noise.kind() {
        NoiseKind::Telegraph(t) if noise.temperature() == 0.0 && p.rate() == 0.0 => {
            Some(TelegraphR0Density::new(p.drag(), *t)?)
        }
        _ => None,
    };
    if moments.is_none() && density.is_none() {
        let (name, value) = blamed(noise);
        let class = match noise.temperature() > 0.0 {
            true => NoiseClass::Thermal,
            false => NoiseClass::FiniteState,
        };
        let method = format!("analytic with drag {} at r = {}", p.drag(), p.rate());
        return Err(crate::capability::fitted(
            name,
            value,
            "a closed form of this noise",
            &method,
            noise_runners(class),
        ));
    }
    Ok(NoiseClosedForm {
        noise: noise.clone(),
        moments,
        density,
    })
}
