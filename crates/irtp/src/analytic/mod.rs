//! Closed-form results: the Newtonian (linear-drag) reference case, the
//! r = 0 stationary densities of the paper (Eqs. (34), (35)) and of any
//! other drag law (by quadrature), and the cusp of the stationary density
//! at the reset velocity (Eq. (18)).

pub mod cusp;
pub mod linear;
pub mod linear_moments;
pub mod linear_noise;
pub mod r0;
mod r0_exponent;
pub mod telegraph_r0;
