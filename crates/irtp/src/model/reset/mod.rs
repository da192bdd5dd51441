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
//! - [`gaussian`]: Poissonian resetting to a velocity drawn from a Gaussian
//!   truncated to the velocity interval.
//! - [`uniform`]: Poissonian resetting to a velocity drawn uniformly from
//!   [a, b].
//! - [`registry`]: [`ResetRule`] and the dispatch
//!   [`with_reset!`](crate::with_reset).
//!
//! Three modifiers combine with any rule ([`Schedule`]): [`periodic`]
//! (resets every T instead of at Poisson times), [`position`] (x → x_r
//! with the velocity) and [`refractory`] (velocity held at v_r for a while
//! after a reset). [`support`] is the table of which method runs which.

pub mod gaussian;
pub mod periodic;
pub mod poisson;
pub mod position;
pub mod redrawn;
pub mod refractory;
pub mod registry;
pub mod spec;
pub mod support;
pub mod uniform;

pub use gaussian::GaussianReset;
pub use periodic::Periodic;
pub use poisson::PoissonReset;
pub use position::PositionReset;
pub use redrawn::RedrawnReset;
pub use refractory::Refractory;
pub use registry::ResetRule;
pub use support::{Feature, Solver};
pub use uniform::UniformReset;

use rand::Rng;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Where a reset sends the velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A fixed velocity v_r.
    Point(f64),
    /// A Gaussian N(mean, std²) truncated to (lo, hi), the admissible
    /// velocity interval (-v_u, v_u).
    Gaussian {
        /// Mean of the untruncated Gaussian (inside (lo, hi)).
        mean: f64,
        /// Its standard deviation (> 0).
        std: f64,
        /// Lower truncation point.
        lo: f64,
        /// Upper truncation point.
        hi: f64,
    },
    /// Uniform on [a, b], inside the admissible interval.
    Uniform {
        /// Left end.
        a: f64,
        /// Right end (> a).
        b: f64,
    },
}

/// The standard normal density.
fn phi(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

impl Target {
    /// (<v_r>, <v_r²>): the moments of the target that closed forms need;
    /// exact for the truncated Gaussian (its normalisation Z by adaptive
    /// Gauss-Kronrod to 1e-14, the rest in closed form:
    /// <v_r> = m + s (φ(α) - φ(β))/Z, Var = s² [1 + (α φ(α) - β φ(β))/Z
    /// - ((φ(α) - φ(β))/Z)²], α, β = (lo - m)/s, (hi - m)/s).
    pub fn moments(&self) -> (f64, f64) {
        match *self {
            Target::Point(v) => (v, v * v),
            Target::Uniform { a, b } => (0.5 * (a + b), (a * a + a * b + b * b) / 3.0),
            Target::Gaussian { mean, std, lo, hi } => {
                let (al, be) = ((lo - mean) / std, (hi - mean) / std);
                let z = normal_mass(al, be);
                let d = (phi(al) - phi(be)) / z;
                let var = std * std * (1.0 + (al * phi(al) - be * phi(be)) / z - d * d);
                let m1 = mean + std * d;
                (m1, var + m1 * m1)
            }
        }
    }

    /// The target under v → -v.
    pub fn mirrored(&self) -> Target {
        match *self {
            Target::Point(v) => Target::Point(-v),
            Target::Gaussian { mean, std, lo, hi } => Target::Gaussian {
                mean: -mean,
                std,
                lo: -hi,
                hi: -lo,
            },
            Target::Uniform { a, b } => Target::Uniform { a: -b, b: -a },
        }
    }

    /// The point, the mean of the untruncated Gaussian, or the middle of
    /// the uniform's support: where meshes put a node.
    pub fn centre(&self) -> f64 {
        match *self {
            Target::Point(v) => v,
            Target::Gaussian { mean, .. } => mean,
            Target::Uniform { a, b } => 0.5 * (a + b),
        }
    }

    /// The (unnormalised) probability of [x0, x1]: for a point, 1 when it
    /// lies inside; meshes normalise the cell masses by their sum.
    pub fn mass(&self, x0: f64, x1: f64) -> f64 {
        match *self {
            Target::Point(v) => f64::from(u8::from(x0 <= v && v < x1)),
            Target::Uniform { a, b } => (x1.min(b) - x0.max(a)).max(0.0) / (b - a),
            Target::Gaussian { mean, std, lo, hi } => {
                let (u0, u1) = (x0.max(lo), x1.min(hi));
                if u1 > u0 {
                    normal_mass((u0 - mean) / std, (u1 - mean) / std)
                } else {
                    0.0
                }
            }
        }
    }

    /// ∫_{x0}^{x1} (v - x0) dQ(v), unnormalised like [`Target::mass`]: with
    /// it, meshes weigh a random target by hat functions (exact for a
    /// piecewise-linear integrand). Closed forms: for the truncated
    /// Gaussian (m - x0) Z + s (φ(α0) - φ(α1)) on the clipped interval.
    pub fn moment_from(&self, x0: f64, x1: f64) -> f64 {
        match *self {
            Target::Point(v) => (v - x0) * self.mass(x0, x1),
            Target::Uniform { a, b } => {
                let (u0, u1) = (x0.max(a), x1.min(b));
                let d = (u1 - u0).max(0.0);
                d * (0.5 * (u0 + u1) - x0) / (b - a)
            }
            Target::Gaussian { mean, std, lo, hi } => {
                let (u0, u1) = (x0.max(lo), x1.min(hi));
                if u1 > u0 {
                    let (a0, a1) = ((u0 - mean) / std, (u1 - mean) / std);
                    (mean - x0) * normal_mass(a0, a1) + std * (phi(a0) - phi(a1))
                } else {
                    0.0
                }
            }
        }
    }

    /// A velocity drawn from the target: the truncated Gaussian by
    /// rejection (from the Gaussian itself when std ≤ half the interval,
    /// acceptance ≥ 0.34 since the mean is inside; else from the uniform
    /// on (lo, hi) with acceptance e^{-(v-m)²/2s²} ≥ e^{-2}).
    pub fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            Target::Point(v) => v,
            Target::Uniform { a, b } => a + (b - a) * rng.gen::<f64>(),
            Target::Gaussian { mean, std, lo, hi } => loop {
                let v = if std <= 0.5 * (hi - lo) {
                    let z: f64 = rng.sample(rand_distr::StandardNormal);
                    let v = mean + std * z;
                    if v > lo && v < hi {
                        return v;
                    }
                    continue;
                } else {
                    lo + (hi - lo) * rng.gen::<f64>()
                };
                let u = (v - mean) / std;
                if v > lo && rng.gen::<f64>() < (-0.5 * u * u).exp() {
                    return v;
                }
            },
        }
    }
}

/// ∫_α^β φ by adaptive Gauss-Kronrod (relative 1e-14; the crate has no
/// erfc accurate to the last digits).
fn normal_mass(al: f64, be: f64) -> f64 {
    crate::numerics::quad::integrate(&phi, al, be, 1e-14).unwrap_or(f64::NAN)
}

/// The modifiers of a resetting rule: when resets happen, whether the
/// position resets too, and a refractory period after each reset. The
/// default is the paper's: Poisson clock, position kept, no refractory
/// period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    /// Resets every T (the rule's Poisson rate is then 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periodic: Option<Periodic>,
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
            position: position.map(PositionReset::new).transpose()?,
            refractory: refractory.map(str::parse).transpose()?,
        })
    }

    /// The value of the flag behind `feature`, for messages.
    pub fn spec_of(&self, feature: Feature) -> String {
        match feature {
            Feature::Periodic => self.periodic.map(|p| p.period.to_string()),
            Feature::Position => self.position.map(|p| p.x.to_string()),
            Feature::RefractoryExp | Feature::RefractoryFixed => self.refractory.map(|r| r.spec()),
        }
        .unwrap_or_default()
    }

    /// An upper bound on the exact samplers' events per unit time: flips
    /// (`lambda`), resets (the Poisson `rate`, or 1/T for a periodic
    /// clock) and, with a refractory period, the end of each one (one more
    /// event per reset). For cost estimates before a run.
    pub fn event_rate_bound(&self, lambda: f64, rate: f64) -> f64 {
        let resets = rate + self.periodic.map_or(0.0, |p| 1.0 / p.period);
        let per_reset = if self.refractory.is_some() { 2.0 } else { 1.0 };
        lambda + resets * per_reset
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
        match self.target() {
            Target::Point(v) => v,
            t => t.draw(rng),
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
            Target::Gaussian { .. } | Target::Uniform { .. } => None,
        }
    }
}
