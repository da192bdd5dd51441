//! Reproduction of the paper's figures (1, 2, 3, 5, 6, 7): parameter sets,
//! computations through the library's solvers, plots and numeric claims.

pub mod plot;
