//! The N-state forward operator for any finite-state noise and thermal
//! noise (docs/equations.md, "Fokker-Planck with N states", Eqs.
//! (N20)-(N29)): the chain space of the stationary and transient engines
//! ([`super::stationary`], [`super::transient`]) and of the moment chain
//! of [`super::msd`].
//!
//! Forward equations of N coupled densities p_s(v, t) (Eq. (N20)):
//!   ∂_t p_s = -∂_v[(a_s - g) p_s] + T ∂_v² p_s + Σ_s' Q_s's p_s' - r p_s
//!             + r [W M(t)]_s δ(v - v_r),
//! M_s = ∫ p_s dv, W the reset's noise rule (kept: identity; re-drawn:
//! π 1ᵀ), no flux through the domain's ends. The operator is assembled as
//! a band matrix (N sub- and super-diagonals) and solved by the shared
//! [`crate::numerics::band`] LU, its mesh built from the two-state
//! solver's graded [`super::grid`] pieces, its time stepping the shared
//! TR-BDF2.

mod held;
mod held_chain;
mod mesh;
mod operator;

pub(crate) use held::{k_times, HeldFactor, Hold};
pub(crate) use held_chain::HeldBlocks;
pub use operator::NoiseOperator;
pub(crate) use operator::{observe, operator, Blocks};
