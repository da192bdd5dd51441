//! Resetting rules behind the [`Reset`] trait: one file per rule, one registry.
//!
//! A rule carries everything a method needs: the rate of the Poisson clock,
//! the target (a point, later a distribution to sample and to inject into a
//! Fokker-Planck mesh), the target's moments for the closed forms, and what
//! happens to the noise state. Engines call [`Reset::draw_velocity`] and
//! [`Reset::draw_noise`] at a reset event and never write the rule
//! themselves. Methods that need a point target (the Fokker-Planck mesh, the
//! backward equations, the closed forms) read it through an exhaustive match
//! on [`Target`], so a new kind of target cannot slip past them unhandled.
//!
//! - [`poisson`]: Poissonian resetting to a fixed v_r, noise state kept
//!   (the paper's Eq. (3)).
//! - [`redrawn`]: Poissonian resetting to a fixed v_r, noise state re-drawn
//!   (±Sigma with probability ½ each).
//! - [`registry`]: [`ResetRule`] and the dispatch
//!   [`with_reset!`](crate::with_reset).

pub mod poisson;
pub mod redrawn;
pub mod registry;
pub mod spec;

pub use poisson::PoissonReset;
pub use redrawn::RedrawnReset;
pub use registry::ResetRule;

use rand::Rng;
use std::fmt;

/// Where a reset sends the velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A fixed velocity v_r.
    Point(f64),
}

impl Target {
    /// (<v_r>, <v_r²>): the moments of the target that closed forms need.
    pub fn moments(&self) -> (f64, f64) {
        match *self {
            Target::Point(v) => (v, v * v),
        }
    }

    /// The target under v → -v.
    pub fn mirrored(&self) -> Target {
        match *self {
            Target::Point(v) => Target::Point(-v),
        }
    }
}

/// What a reset does to the noise state eta = ±Sigma.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
    fn draw_velocity<R: Rng + ?Sized>(&self, _rng: &mut R) -> f64 {
        match self.target() {
            Target::Point(v) => v,
        }
    }

    /// The noise state after a reset (`plus`: eta = +Sigma before it).
    #[inline]
    fn draw_noise<R: Rng + ?Sized>(&self, plus: bool, rng: &mut R) -> bool {
        match self.noise() {
            NoiseAtReset::Kept => plus,
            NoiseAtReset::Redrawn => rng.gen::<bool>(),
        }
    }

    /// The fixed target velocity, for methods that need a point target.
    fn point(&self) -> Option<f64> {
        match self.target() {
            Target::Point(v) => Some(v),
        }
    }
}
