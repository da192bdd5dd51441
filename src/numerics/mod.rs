//! Small hand-written numerical kernels shared by the model (exact flow) and
//! the closed-form densities: Gauss–Kronrod quadrature and a safeguarded
//! root finder. Neutral ground so that `model` does not depend on `analytic`.

pub mod quad;
pub mod root;
