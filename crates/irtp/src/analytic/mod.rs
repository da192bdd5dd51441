//! Closed-form results: the Newtonian (linear-drag) reference case, and the
//! r = 0 stationary densities of the paper (Eqs. (34), (35)) and of any
//! other drag law (by quadrature).

pub mod linear;
pub mod linear_moments;
pub mod r0;
mod r0_exponent;
