//! The noise models of the cross-method suite (docs/equations.md, "Noise
//! kinds"): every engine that runs a noise model checks itself over
//! [`NOISE_CASES`] (those whose temperature it runs), against the closed
//! forms for linear drag and against the other methods for tan and tanh.
//! A new case is one line here; each method's test reads the list.

use irtp::model::noise::NoiseModel;
use irtp::{DragLaw, Params};

/// One noise test model: a drag, a noise spec, a temperature, a Poisson
/// resetting rate to the point target `reset_velocity` (noise kept).
#[derive(Clone, Copy, Debug)]
pub struct NoiseCase {
    /// Short name for messages.
    pub name: &'static str,
    /// The drag spec (`tan`, `tanh`, `linear`).
    pub drag: &'static str,
    /// The noise spec.
    pub noise: &'static str,
    /// T of the thermal noise.
    pub temperature: f64,
    /// Resetting rate r.
    pub rate: f64,
    /// Reset velocity v_r.
    pub reset_velocity: f64,
}

impl NoiseCase {
    /// The validated parameters.
    pub fn params(&self) -> Params {
        let drag: DragLaw = self.drag.parse().expect("drag spec");
        let noise = NoiseModel::parse(self.noise, self.temperature).expect("noise spec");
        Params::with_noise(drag, noise, self.rate, self.reset_velocity).expect("noise case")
    }
    /// The same case at another rate.
    pub fn at_rate(&self, rate: f64) -> NoiseCase {
        NoiseCase { rate, ..*self }
    }
    /// Whether the case has thermal noise.
    pub fn thermal(&self) -> bool {
        self.temperature > 0.0
    }
    /// Whether the drag is linear (closed forms: `irtp::analytic::linear_noise`).
    pub fn linear(&self) -> bool {
        self.drag == "linear"
    }
}

const fn case(
    name: &'static str,
    drag: &'static str,
    noise: &'static str,
    temperature: f64,
    rate: f64,
    reset_velocity: f64,
) -> NoiseCase {
    NoiseCase {
        name,
        drag,
        noise,
        temperature,
        rate,
        reset_velocity,
    }
}

/// Asymmetric telegraph noise: levels +1.5 and -0.75, leaving +1.5 at rate
/// 0.8 and -0.75 at rate 0.4 (<a> ≠ 0: the velocity has a mean, x drifts).
pub const ASYM: &str = "telegraph:plus=1.5,minus=0.75,rate_plus=0.8,rate_minus=0.4";
/// Run-pause-tumble: ±1.2 → 0 at rate 1, 0 → ±1.2 at rate 0.5 each.
pub const RPT: &str = "rpt:sigma=1.2,alpha=1,beta=1";
/// A three-state noise with no symmetry (levels -0.6, 0.3, 1.1).
pub const THREE: &str =
    "states:levels=[-0.6,0.3,1.1],rates=[[-1,0.6,0.4],[0.5,-0.8,0.3],[0.2,0.9,-1.1]]";
/// The paper's noise as a two-state generator (Sigma = 1, lambda = 0.5),
/// run through the N-state engines (not normalised to the default path:
/// `states` is never normalised).
pub const PAPER_AS_STATES: &str = "states:levels=[1,-1],rates=[[-0.5,0.5],[0.5,-0.5]]";
/// The paper's noise as a telegraph spec with Sigma = 1, lambda = 0.5.
pub const PAPER_TELEGRAPH: &str = "telegraph:sigma=1,lambda=0.5";

/// The cross-method list: linear drag (closed forms), tan and tanh (no
/// closed form: the methods against each other), each under the
/// asymmetric, run-pause-tumble and three-state noises, thermal noise
/// alone and added to the telegraph noise, and the paper's noise spelt as
/// a generator.
pub const NOISE_CASES: [NoiseCase; 14] = [
    case("linear-asym", "linear", ASYM, 0.0, 0.5, 0.1),
    case("linear-rpt", "linear", RPT, 0.0, 0.5, 0.2),
    case("linear-three", "linear", THREE, 0.0, 0.7, 0.0),
    case("linear-thermal", "linear", "none", 0.5, 0.5, 0.3),
    case(
        "linear-telegraph-thermal",
        "linear",
        PAPER_TELEGRAPH,
        0.2,
        0.5,
        0.0,
    ),
    case(
        "linear-paper-as-states",
        "linear",
        PAPER_AS_STATES,
        0.0,
        1.0,
        0.2,
    ),
    case("tan-asym", "tan", ASYM, 0.0, 0.5, 0.1),
    case("tan-rpt", "tan", RPT, 0.0, 0.5, 0.2),
    case("tan-three", "tan", THREE, 0.0, 0.7, 0.0),
    case(
        "tan-telegraph-thermal",
        "tan",
        PAPER_TELEGRAPH,
        0.2,
        0.5,
        0.0,
    ),
    case(
        "tanh-asym",
        "tanh",
        "telegraph:plus=0.6,minus=0.3,rate_plus=0.8,rate_minus=0.4",
        0.0,
        0.5,
        0.1,
    ),
    case(
        "tanh-rpt",
        "tanh",
        "rpt:sigma=0.6,alpha=1,beta=1",
        0.0,
        0.5,
        0.2,
    ),
    case("tanh-thermal", "tanh", "none", 0.1, 0.5, 0.0),
    case("tan-paper-as-states", "tan", PAPER_AS_STATES, 0.0, 1.0, 0.2),
];

/// The cases a method without thermal noise runs.
pub fn athermal() -> impl Iterator<Item = &'static NoiseCase> {
    NOISE_CASES.iter().filter(|c| !c.thermal())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_is_admissible() {
        for c in &NOISE_CASES {
            let p = c.params();
            assert!(p.noise().is_some(), "{} normalised to the default", c.name);
        }
    }
}
