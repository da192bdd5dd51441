//! Noise models eta(t) behind the [`Noise`] trait: one file per kind, one
//! registry (docs/equations.md, "Noise kinds").
//!
//! A noise kind is a finite-state Markov jump process: N levels a_s and a
//! generator Q (Q_ss' ≥ 0 the rate of s → s' for s ≠ s', rows summing to
//! 0), so that the velocity obeys dv = (a_η - g(v)) dt between jumps of η
//! (Eq. (N1)). Its generator part is Σ_s' Q_ss' [f(s') - f(s)]; its
//! stationary law π solves Qᵀ π = 0, Σ π = 1 (Eq. (N2)).
//!
//! - [`telegraph`]: two levels, +P and -M, leaving +P at rate k₊ and -M at
//!   rate k₋; with P = M = Sigma and k₊ = k₋ = lambda the paper's symmetric
//!   telegraph noise (Eq. (6)).
//! - [`rpt`]: run-pause-tumble, ±S → 0 at rate alpha, 0 → ±S at rate beta/2
//!   each.
//! - [`states`]: any irreducible finite-state Markov noise, levels and
//!   generator given.
//! - [`none`]: no active noise (one state at level 0), for thermal noise
//!   alone.
//! - [`chain`]: the numerics of a finite chain (validation, stationary
//!   law, mirror symmetry, the Poisson equation of Q).
//! - [`spec`]: the compact spec (`telegraph:sigma=3,lambda=0.5`) every kind
//!   is written in.
//! - [`registry`]: [`NoiseKind`] (parse, serialise) and the one dispatch
//!   [`with_noise!`](crate::with_noise).
//! - [`support`]: which method runs which noise (every engine runs every
//!   finite-state noise at T = 0; with T > 0 all but `mfpt --method exact`,
//!   some only for some drags; the search any finite-state noise at T = 0
//!   by its backward equation and samplers (`--method backward`, `exact`,
//!   `euler`), its renewal route and distribution only the paper's noise;
//!   `irtp analytic` runs the closed forms (N3)-(N8)).
//! - [`noise_model`]: [`NoiseModel`], a kind plus the temperature T of the
//!   thermal noise sqrt(2T) dW added to it (Eq. (N1)).
//!
//! A new kind is one new file implementing [`Noise`] plus one line in the
//! registry.

pub mod chain;
pub mod noise_model;
pub mod none;
pub mod registry;
pub mod rpt;
pub mod spec;
pub mod states;
pub mod support;
pub mod telegraph;

pub use noise_model::NoiseModel;
pub use none::NoNoise;
pub use registry::NoiseKind;
pub use rpt::RunPauseTumble;
pub use states::States;
pub use telegraph::Telegraph;

use crate::error::Result;
use std::fmt;

/// A finite-state Markov noise: its levels, its generator and its spec.
/// A kind must give [`Noise::levels`], [`Noise::generator`] and its spec
/// functions; the stationary law and the mirror map have numerical
/// defaults ([`chain`]) that kinds with closed forms override.
pub trait Noise: Clone + Send + Sync + fmt::Debug + PartialEq + 'static {
    /// The kind's name in a spec (`telegraph`).
    const NAME: &'static str;

    /// The levels a_s, one per state.
    fn levels(&self) -> Vec<f64>;
    /// The generator Q (N×N, Q_ss' ≥ 0 off the diagonal, rows summing to 0
    /// to rounding).
    fn generator(&self) -> Vec<Vec<f64>>;

    /// The stationary law π of the noise: Qᵀ π = 0, Σ π = 1 (Eq. (N2)),
    /// checked. Default: [`chain::stationary`].
    fn stationary(&self) -> Result<Vec<f64>> {
        chain::stationary(&self.generator())
    }
    /// The mirror map: a permutation m of the states with a_{m(s)} = -a_s
    /// and Q_{m(s) m(s')} = Q_ss' (the process is then symmetric under
    /// v → -v for an odd drag), or None. Default: [`chain::mirror`].
    fn mirror(&self) -> Option<Vec<usize>> {
        chain::mirror(&self.levels(), &self.generator())
    }
    /// (Sigma, lambda) when this is the paper's symmetric telegraph noise
    /// ±Sigma flipping at rate lambda, the noise every engine runs today.
    /// Default: None.
    fn symmetric_telegraph(&self) -> Option<(f64, f64)> {
        None
    }

    /// A representative value, for help texts and listings.
    fn example() -> Self;
    /// How to write the spec, for messages (`rpt:sigma=S,alpha=A,beta=B`).
    fn usage() -> &'static str;
    /// The kind of a spec: `args` is the part after `name:` (None when the
    /// spec has no `:`), `spec` the whole spec, for messages. Errors name
    /// `noise`.
    fn parse(spec: &str, args: Option<&str>) -> Result<Self>;
    /// The canonical spec, which parses back to the same value bit for bit.
    fn write(&self) -> String;
}
