//! Closed-form results: the Newtonian (linear-drag) reference case, and the
//! r = 0 stationary densities of the paper (Eqs. (34)-(35)).

pub mod linear;
pub mod r0;
