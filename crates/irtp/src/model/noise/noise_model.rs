//! [`NoiseModel`]: a noise kind plus thermal noise of temperature T ≥ 0,
//! dv = (a_η - g(v)) dt + sqrt(2T) dW (Eq. (N1)); the value provenance
//! records (`{"noise": "telegraph:sigma=3,lambda=0.5", "temperature": 0}`).

use super::registry::NoiseKind;
use super::telegraph::Telegraph;
use crate::error::{Error, Result};
use crate::model::Drag;
use serde::{Deserialize, Serialize};

/// A noise kind and the temperature of the thermal noise added to it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawNoiseModel", into = "RawNoiseModel")]
pub struct NoiseModel {
    kind: NoiseKind,
    temperature: f64,
}

/// The serialised form of a [`NoiseModel`] (validated on the way in).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RawNoiseModel {
    /// The kind's spec.
    pub noise: NoiseKind,
    /// T (0 when absent).
    #[serde(default)]
    pub temperature: f64,
}

impl TryFrom<RawNoiseModel> for NoiseModel {
    type Error = Error;
    fn try_from(r: RawNoiseModel) -> Result<Self> {
        NoiseModel::new(r.noise, r.temperature)
    }
}

impl From<NoiseModel> for RawNoiseModel {
    fn from(m: NoiseModel) -> Self {
        RawNoiseModel {
            noise: m.kind,
            temperature: m.temperature,
        }
    }
}

impl NoiseModel {
    /// The kind with thermal noise of temperature T: finite and ≥ 0, and
    /// positive with `none` (without either noise the velocity relaxes to
    /// rest); errors name `temperature`.
    pub fn new(kind: NoiseKind, temperature: f64) -> Result<Self> {
        if !(temperature >= 0.0 && temperature.is_finite()) {
            return Err(Error::invalid(
                "temperature",
                temperature,
                "temperature >= 0, finite",
            ));
        }
        if matches!(kind, NoiseKind::None(_)) && !(temperature > 0.0) {
            return Err(Error::invalid(
                "temperature",
                temperature,
                "temperature > 0 with noise none (without either noise the velocity relaxes to 0 and stays)",
            ));
        }
        Ok(NoiseModel { kind, temperature })
    }

    /// The paper's noise ±Sigma flipping at rate lambda, no thermal noise.
    pub fn telegraph(sigma: f64, lambda: f64) -> Result<Self> {
        Self::new(
            NoiseKind::Telegraph(Telegraph::symmetric(sigma, lambda)?),
            0.0,
        )
    }

    /// From a noise spec and a temperature (the flags `noise` and
    /// `temperature`).
    pub fn parse(noise: &str, temperature: f64) -> Result<Self> {
        Self::new(noise.parse()?, temperature)
    }

    /// The noise under v → -v: the same generator with every level
    /// negated, state for state (state s of the mirror is state s here), as
    /// a `states` noise (`none` is its own mirror). Downward first
    /// passages run in the mirrored frame.
    pub fn mirrored(&self) -> Result<Self> {
        if self.kind.levels().len() < 2 {
            return Ok(self.clone());
        }
        let levels = self
            .kind
            .levels()
            .iter()
            .map(|&a| if a == 0.0 { 0.0 } else { -a })
            .collect();
        let kind = NoiseKind::States(super::States::new(levels, self.kind.generator())?);
        NoiseModel::new(kind, self.temperature)
    }

    /// The kind.
    pub fn kind(&self) -> &NoiseKind {
        &self.kind
    }
    /// T.
    pub fn temperature(&self) -> f64 {
        self.temperature
    }
    /// The kind's canonical spec.
    pub fn spec(&self) -> String {
        self.kind.spec()
    }
    /// The levels a_s.
    pub fn levels(&self) -> Vec<f64> {
        self.kind.levels()
    }
    /// The generator Q.
    pub fn generator(&self) -> Vec<Vec<f64>> {
        self.kind.generator()
    }
    /// The stationary law π of the noise state (Eq. (N2)).
    pub fn stationary(&self) -> Result<Vec<f64>> {
        self.kind.stationary()
    }
    /// Whether the process is symmetric under v → -v for an odd drag (the
    /// thermal noise is).
    pub fn is_mirror_symmetric(&self) -> bool {
        self.kind.mirror().is_some()
    }
    /// `<a>` = Σ π_s a_s, the stationary mean force of the noise.
    pub fn mean_level(&self) -> Result<f64> {
        let pi = self.stationary()?;
        Ok(pi.iter().zip(self.levels()).map(|(p, a)| p * a).sum())
    }

    /// Check the noise against a drag law: every level strictly inside the
    /// force range (-sup g, sup g), the law admissible up to the largest
    /// |level| ([`Drag::admissible`], its `sigma` renamed `noise`), and
    /// with static friction mu > 0 no level in [-mu, mu] (such a state
    /// holds a particle at v = 0 with a point mass). Errors name `noise`.
    pub fn check_drag<D: Drag>(&self, drag: &D) -> Result<()> {
        let (lim, mu) = (drag.force_limit(), drag.static_friction());
        let spec = self.spec();
        for a in self.levels() {
            if !(a.abs() < lim) {
                return Err(Error::invalid(
                    "noise",
                    &spec,
                    format!(
                        "levels inside (-{lim}, {lim}), the force range of drag {} (level {a})",
                        drag.name()
                    ),
                ));
            }
            if mu > 0.0 && !(a.abs() > mu) {
                return Err(Error::invalid(
                    "noise",
                    &spec,
                    format!("levels with |level| > mu = {mu}, the static friction of drag {} (level {a} sticks the particle at v = 0)", drag.name()),
                ));
            }
        }
        let top = self.levels().iter().fold(0.0f64, |m, a| m.max(a.abs()));
        if top > 0.0 {
            drag.admissible(top).map_err(|e| match e {
                Error::InvalidParameter {
                    name: "sigma",
                    value,
                    allowed,
                } => Error::InvalidParameter {
                    name: "noise",
                    value,
                    allowed,
                },
                other => other,
            })?;
        }
        Ok(())
    }

    /// The velocity interval: without thermal noise (g⁻¹(min a), g⁻¹(max a))
    /// (every flow tends to some g⁻¹(a_s), Eq. (N1)); with T > 0 the drag's
    /// own domain (-g⁻¹(sup g), g⁻¹(sup g)) (±∞ for an unbounded law).
    pub fn velocity_interval<D: Drag>(&self, drag: &D) -> (f64, f64) {
        if self.temperature > 0.0 {
            let top = drag.inverse(drag.force_limit());
            return (-top, top);
        }
        let levels = self.levels();
        let lo = levels.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (drag.inverse(lo), drag.inverse(hi))
    }
}
