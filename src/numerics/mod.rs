//! Small hand-written numerical kernels shared by the model (exact flow) and
//! the closed-form densities: Gauss–Kronrod quadrature, a safeguarded root
//! finder and point grids. Neutral ground so that `model` does not depend on
//! `analytic`.

pub mod chebyshev;
pub mod fastmath;
pub mod grid;
pub mod quad;
pub mod root;
