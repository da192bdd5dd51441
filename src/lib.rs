//! # irtp
//!
//! Inertial run-and-tumble particles (IRTP) with stochastic velocity resetting
//! in non-Newtonian media, after Howlader, Mondal & Das (`shared/seed/paper.tex`).
//!
//! dv/dt = -g(v) + eta(t), dx/dt = v; eta = ±Sigma flips at rate lambda;
//! at rate r the velocity is reset to v_r (position and noise state kept).
//!
//! Modules, one per concept:
//! - [`analytic`]: closed forms (linear drag, r = 0 densities).
//! - [`model`]: drag laws g(v) (Table 1), parameters, velocity bounds (Eqs. 8-10).
//! - [`rng`], [`parallel`], [`stats`]: per-particle streams, deterministic
//!   parallel reduction, mergeable estimators.
//! - [`sim`]: particle simulation (Euler Eqs. 14-16, exact sampler) and observables.
//! - [`io`]: atomic output directories with provenance.
//! - [`numerics`]: shared quadrature and root-finding kernels.
//!
//! The library never prints and never exits; it returns plain, serialisable
//! result structs. The `irtp` binary is a thin layer over it.

pub mod analytic;
pub mod error;
pub mod figures;
pub mod fp;
pub mod io;
pub mod mfpt;
pub mod model;
pub mod numerics;
pub mod parallel;
pub mod rng;
pub mod sim;
pub mod stats;

pub use error::{Error, Result};
pub use model::{Drag, DragLaw, Params};
