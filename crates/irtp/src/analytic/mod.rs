//! Closed-form results: the Newtonian (linear-drag) reference case, the
//! r = 0 stationary densities of the paper (Eqs. (34), (35)) and of any
//! other drag law (by quadrature), and the cusp of the stationary density
//! at the reset velocity (Eq. (18)). For the noise kinds of
//! [`crate::model::noise`]: linear drag with any finite-state and thermal
//! noise ([`linear_noise`], Eqs. (N3)-(N6)) and the r = 0 density of
//! asymmetric telegraph noise with any drag ([`telegraph_r0`], Eq. (N8)),
//! both from [`crate::Params`] in [`noise`].

pub mod cusp;
pub mod linear;
pub mod linear_moments;
pub mod linear_noise;
pub mod noise;
pub mod r0;
mod r0_exponent;
pub mod telegraph_r0;
