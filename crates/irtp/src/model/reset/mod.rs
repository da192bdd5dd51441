//! Resetting rules behind the [`Reset`] trait: one file per rule, one registry.
//!
//! A rule carries everything a method needs: the rate of the Poisson clock,
//! the target (a point or a law to sample and to spread over a mesh), the
//! target's moments for the closed forms, and what happens to the noise
//! state. Engines call [`Reset::draw_velocity`] and [`Reset::draw_telegraph`]
//! (the paper's noise) or [`Reset::draw_noise_state`] (a noise model) at a
//! reset event and never write the rule themselves. Meshes, backward
//! equations and closed forms read a target only through the [`TargetLaw`]
//! interface (its mass on a cell, its moments, its support), so every method
//! picks up a new kind of target; a method that needs a point target asks
//! [`crate::Params::point_target`], which refuses the others by name.
//!
//! - [`poisson`]: Poissonian resetting to a fixed v_r, noise state kept
//!   (the paper's Eq. (3)).
//! - [`redrawn`]: Poissonian resetting to a fixed v_r, noise state re-drawn
//!   (±Sigma with probability ½ each).
//! - [`random`]: Poissonian resetting to a velocity drawn from a random
//!   target ([`target`]: one file per target law behind [`TargetLaw`],
//!   one registry line).
//! - [`registry`]: [`ResetRule`] and the dispatch
//!   [`with_reset!`](crate::with_reset).
//!
//! Four modifiers combine with any rule ([`Schedule`]): [`periodic`]
//! (resets every T instead of at Poisson times), [`clock`] (a renewal
//! clock: waiting times between resets drawn from a law), [`position`]
//! (x → x_r with the velocity) and [`refractory`] (velocity held at v_r for
//! a while after a reset). [`support`] is the table of which method runs
//! which.

pub mod clock;
pub mod periodic;
pub mod poisson;
pub mod position;
pub mod random;
pub mod redrawn;
pub mod refractory;
pub mod registry;
pub mod spec;
pub mod support;
pub mod target;

pub use clock::Clock;
pub use periodic::Periodic;
pub use poisson::PoissonReset;
pub use position::PositionReset;
pub use random::RandomReset;
pub use redrawn::RedrawnReset;
pub use refractory::Refractory;
pub use registry::ResetRule;
pub use support::{Feature, Solver};
pub use target::{Target, TargetLaw};

use rand::Rng;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The modifiers of a resetting rule: when resets happen, whether the
/// position resets too, and a refractory period after each reset. The
/// default is the paper's: Poisson clock, position kept, no refractory
/// period.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    /// Resets every T (the rule's Poisson rate is then 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periodic: Option<Periodic>,
    /// A renewal clock: resets a drawn waiting time after the last one
    /// (after the end of its refractory period). The rule's Poisson rate is
    /// then 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clock: Option<Clock>,
    /// Position reset to x_r at every reset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<PositionReset>,
    /// Refractory period after every reset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refractory: Option<Refractory>,
}

impl Schedule {
    /// The features in use (beyond the paper's protocol).
    pub fn features(&self) -> Vec<Feature> {
        let mut f = Vec::new();
        if self.periodic.is_some() {
            f.push(Feature::Periodic);
        }
        if self.clock.is_some() {
            f.push(Feature::Renewal);
        }
        if self.position.is_some() {
            f.push(Feature::Position);
        }
        match self.refractory {
            Some(Refractory::Exp { .. }) => f.push(Feature::RefractoryExp),
            Some(Refractory::Fixed { .. }) => f.push(Feature::RefractoryFixed),
            None => {}
        }
        f
    }

    /// Validate the modifiers from their flags (`--reset-period`,
    /// `--reset-position`, `--refractory`).
    pub fn parse(
        period: Option<f64>,
        position: Option<f64>,
        refractory: Option<&str>,
    ) -> crate::error::Result<Self> {
        Ok(Schedule {
            periodic: period.map(Periodic::new).transpose()?,
            clock: None,
            position: position.map(PositionReset::new).transpose()?,
            refractory: refractory.map(str::parse).transpose()?,
        })
    }

    /// The same schedule with the renewal clock of `spec`
    /// (`--reset-clock`), refused with a periodic clock (two clocks).
    pub fn with_clock(self, spec: Option<&str>) -> crate::error::Result<Self> {
        let Some(spec) = spec else {
            return Ok(self);
        };
        let clock = Clock::parse(spec)?;
        if let Some(p) = self.periodic {
            return Err(crate::error::Error::invalid(
                "reset_clock",
                spec,
                format!(
                    "no --reset-clock with --reset-period {} (one clock: fixed:t=T is the \
                     periodic clock as a renewal clock)",
                    p.period
                ),
            ));
        }
        Ok(Schedule {
            clock: Some(clock),
            ..self
        })
    }

    /// The first scheduled reset time of a particle starting at age 0 (∞
    /// without a periodic or renewal clock); draws from `rng` for a random
    /// waiting time only.
    #[inline]
    pub fn first_reset<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.next_reset(0.0, rng)
    }

    /// The next scheduled reset time when the clock restarts at `free`
    /// (a reset, or the end of its refractory period): the first multiple
    /// of T after it (periodic, and a fixed renewal clock without a
    /// refractory period, whose restarts are the multiples of T: see
    /// [`clock::fixed`]), free plus a drawn waiting time (renewal), ∞
    /// without either.
    #[inline]
    pub fn next_reset<R: Rng + ?Sized>(&self, free: f64, rng: &mut R) -> f64 {
        match (self.periodic, self.clock.clone()) {
            (Some(p), _) => p.next_after(free),
            (None, Some(Clock::Fixed(f))) if self.refractory.is_none() => {
                Periodic { period: f.t }.next_after(free)
            }
            (None, Some(c)) => c.next_after(free, rng),
            (None, None) => f64::INFINITY,
        }
    }

    /// Whether resets come at scheduled times (periodic or renewal clock).
    pub fn scheduled_clock(&self) -> bool {
        self.periodic.is_some() || self.clock.is_some()
    }

    /// The value of the flag behind `feature`, for messages.
    pub fn spec_of(&self, feature: Feature) -> String {
        match feature {
            Feature::Periodic => self.periodic.map(|p| p.period.to_string()),
            Feature::Renewal => self.clock.as_ref().map(|c| c.spec()),
            Feature::Position => self.position.map(|p| p.x.to_string()),
            Feature::RefractoryExp | Feature::RefractoryFixed => self.refractory.map(|r| r.spec()),
        }
        .unwrap_or_default()
    }

    /// An upper bound on the exact samplers' events per unit time: flips
    /// (`lambda`), resets (the Poisson `rate`, 1/T for a periodic clock,
    /// the long-time rate 1/E(R) of a renewal clock) and, with a refractory period, the end of each one (one more
    /// event per reset). For cost estimates before a run.
    pub fn event_rate_bound(&self, lambda: f64, rate: f64) -> f64 {
        let resets = rate
            + self.periodic.map_or(0.0, |p| 1.0 / p.period)
            + self.clock.as_ref().map_or(0.0, |c| 1.0 / c.mean());
        let per_reset = if self.refractory.is_some() { 2.0 } else { 1.0 };
        lambda + resets * per_reset
    }

    /// The parameters of this schedule a run's cost grows with, beyond the
    /// Poisson `rate` (a periodic clock's `reset_period`, a renewal clock's
    /// `reset_clock`: each period is one more event), for the refusal of a
    /// costly run to name them.
    pub fn cost_drivers(&self) -> Vec<&'static str> {
        let mut d: Vec<&'static str> = self.periodic.map(|_| "reset_period").into_iter().collect();
        d.extend(self.clock.as_ref().map(|_| "reset_clock"));
        d
    }

    /// Whether it is the paper's (no modifier).
    pub fn is_plain(&self) -> bool {
        *self == Schedule::default()
    }
}

/// What a reset does to the noise state eta = ±Sigma.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NoiseAtReset {
    /// Kept (the paper's state-preserving resetting).
    Kept,
    /// Re-drawn: ±Sigma with probability ½ each, independently of the state
    /// before the reset.
    Redrawn,
}

impl NoiseAtReset {
    /// Name as written in a reset spec (`kept`, `redrawn`).
    pub fn name(&self) -> &'static str {
        match self {
            NoiseAtReset::Kept => "kept",
            NoiseAtReset::Redrawn => "redrawn",
        }
    }

    /// The N-state form of [`NoiseAtReset::mix`]: the reset outflux `w`
    /// of each noise state re-enters as `w` when kept and as (Σ w) π (the
    /// noise's stationary law) when re-drawn.
    pub fn mix_states(&self, w: &[f64], pi: &[f64]) -> Vec<f64> {
        match self {
            NoiseAtReset::Kept => w.to_vec(),
            NoiseAtReset::Redrawn => {
                let total: f64 = w.iter().sum();
                pi.iter().map(|p| total * p).collect()
            }
        }
    }

    /// The reset influx into the (+, -) states of the reset outflux (a, b)
    /// of the (+, -) states: (a, b) when the state is kept, both halves of
    /// a + b when it is re-drawn. Forward equations re-inject through it;
    /// backward equations weigh the two states' values at the target with
    /// the same shares (the matrix is symmetric).
    #[inline]
    pub fn mix(&self, a: f64, b: f64) -> (f64, f64) {
        match self {
            NoiseAtReset::Kept => (a, b),
            NoiseAtReset::Redrawn => {
                let h = 0.5 * (a + b);
                (h, h)
            }
        }
    }
}

impl std::str::FromStr for NoiseAtReset {
    type Err = crate::error::Error;
    fn from_str(s: &str) -> crate::error::Result<Self> {
        match s {
            "kept" => Ok(NoiseAtReset::Kept),
            "redrawn" => Ok(NoiseAtReset::Redrawn),
            _ => Err(crate::error::Error::invalid(
                "reset_noise",
                s,
                "kept or redrawn",
            )),
        }
    }
}

/// A resetting protocol: at the events of a Poisson clock of rate
/// [`Reset::rate`], the velocity jumps to the target and the noise state
/// follows [`Reset::noise`]; position is kept.
pub trait Reset: Clone + Send + Sync + fmt::Debug {
    /// Short name (`poisson`).
    fn name(&self) -> &'static str;
    /// Rate r of the reset clock.
    fn rate(&self) -> f64;
    /// Where the velocity goes.
    fn target(&self) -> Target;
    /// What happens to the noise state.
    fn noise(&self) -> NoiseAtReset;
    /// The same rule under v → -v (downward first passages run mirrored).
    fn mirrored(&self) -> Self;
    /// The same rule with another rate.
    fn with_rate(&self, rate: f64) -> Self;

    /// The velocity after a reset (draws from `rng` only for random targets).
    #[inline]
    fn draw_velocity<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.target().draw(rng)
    }

    /// The paper's noise state (0: +Sigma, 1: -Sigma) after a reset from
    /// state `s`: kept, or redrawn ±Sigma with probability ½ each (one
    /// boolean, true: +Sigma).
    #[inline]
    fn draw_telegraph<R: Rng + ?Sized>(&self, s: usize, rng: &mut R) -> usize {
        match self.noise() {
            NoiseAtReset::Kept => s,
            NoiseAtReset::Redrawn => usize::from(!rng.gen::<bool>()),
        }
    }

    /// The noise state (of N) after a reset from state `s`: kept, or
    /// re-drawn from the stationary law of `chain` (one uniform).
    #[inline]
    fn draw_noise_state<R: Rng + ?Sized>(
        &self,
        s: usize,
        chain: &crate::model::noise::chain::Chain,
        rng: &mut R,
    ) -> usize {
        match self.noise() {
            NoiseAtReset::Kept => s,
            NoiseAtReset::Redrawn => chain.draw_stationary(rng.gen::<f64>()),
        }
    }

    /// The fixed target velocity, for methods that need a point target.
    fn point(&self) -> Option<f64> {
        self.target().point_velocity()
    }
}
