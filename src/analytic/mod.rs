//! Closed-form results: the Newtonian (linear-drag) reference case, and the
//! r = 0 stationary densities of the paper (Eqs. Neqn17, apeqn18a).

pub mod linear;
pub mod quad;
pub mod r0;
