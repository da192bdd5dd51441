//! # irtp
//!
//! Inertial run-and-tumble particles (IRTP) with stochastic velocity resetting
//! in non-Newtonian media, after Howlader, Mondal & Das, "Velocity resetting of inertial
//! run-and-tumble particles in non-Newtonian media".
//!
//! dv/dt = -g(v) + eta(t), dx/dt = v; eta = ±Sigma flips at rate lambda;
//! at rate r the velocity is reset to v_r (position and noise state kept).
//!
//! The core of the irtp workspace. Crates, with dependencies running one way
//! (enforced by Cargo): irtp-python → irtp-cli (the `irtp` command line:
//! the binary, and the library function the wheel's `irtp` console script
//! runs) → irtp-paper (the paper's figures, `irtp reproduce`) → irtp-app (the
//! commands as library calls, output directories with provenance, sweeps) →
//! this crate. Modules here, one per concept ({search, mfpt, fp, sim, analytic} →
//! model → numerics):
//! - [`model`]: drag laws g(v) (Table 1), one file each behind the
//!   [`Drag`] trait with the [`DragLaw`] registry and [`with_drag!`]
//!   dispatch; noise kinds behind [`model::Noise`] with the
//!   [`model::NoiseKind`] registry and [`with_noise!`] dispatch (which
//!   method runs which: [`capability`]); resetting rules behind [`model::Reset`]; validated [`Params`]
//!   and velocity bounds (Eqs. (8)-(10)).
//! - [`sim`]: particle samplers (exact event-driven sampler; the paper's
//!   Euler scheme, Eqs. (30)-(32)) and their mergeable observables.
//! - [`fp`]: Fokker-Planck equations (Eqs. (11)-(12)): stationary and
//!   transient densities, <v²> and the exact D_eff.
//! - [`mfpt`]: first passage to a target velocity: the problem, the backward
//!   equations (Sec. 2.2 with the generator's signs), particle estimators,
//!   scans and the optimal resetting rate.
//! - [`search`]: first passage in position (the search problem): a level
//!   or an interval, by the exact event-driven sampler, the 2-D backward
//!   equation, the renewal route of full resetting or the Euler scheme; the
//!   tail exponent where the mean search time is infinite.
//! - [`analytic`]: closed forms (linear drag; r = 0 densities, Eqs. (34)-(35)).
//! - [`numerics`]: quadrature, root finding, Chebyshev tables, fast
//!   elementary functions, point grids.
//! - [`rng`], [`parallel`], [`stats`], [`memo`]: per-particle streams,
//!   deterministic parallel reduction, mergeable estimators, shared tables.
//! - [`error`]: the typed library error.
//!
//! Equations are cited by the paper's printed numbers; `docs/equations.md`
//! maps each to its code. The library never prints and never exits; it
//! returns plain, serialisable result structs.

pub mod analytic;
pub use model::capability;
pub mod error;
pub mod fp;
pub mod memo;
pub mod mfpt;
pub mod model;
pub mod numerics;
pub mod parallel;
pub mod rng;
pub mod search;
pub mod sim;
pub mod stats;
pub mod stop;

pub use error::{Error, Result};
pub use model::{Drag, DragLaw, Params};
