//! Fokker-Planck solvers for P±(v, t) (paper Eqs. (11)-(12)).
//!
//! Forward equations of the simulated process (drift ±Σ - g(v), flips at rate
//! λ, state-preserving reset to v_r at rate r):
//!   ∂_t P+ = -∂_v[(Σ - g) P+] + λ (P- - P+) - r P+ + r m+(t) δ(v - v_r),
//!   ∂_t P- = -∂_v[(-Σ - g) P-] + λ (P+ - P-) - r P- + r m-(t) δ(v - v_r),
//! with m± = ∫ P± dv and no flux through v_l, v_u. The paper's Eqs. (11)-(12)
//! write the transport term as ∂_v[(g ∓ Σ) P±] (the same thing) and the
//! source as (r/2) δ(v): identical for v_r = 0 and m± = ½, which holds in the
//! stationary state and for all t from the paper's symmetric initial condition.
//!
//! Discretisation: finite volumes with upwind fluxes. The + state only moves
//! right and the - state only left (Σ - g(v) > 0 inside the interval), so the
//! upwind scheme is the generator of a Markov jump process on (cell, state):
//! it conserves mass and positivity exactly, and its adjoint is the discrete
//! backward operator used for D_eff.
//!
//! - [`stationary()`]: direct O(N) solve of the stationary equations, graded
//!   mesh for the singular edges, Richardson extrapolation; exact discrete
//!   Green-Kubo D_eff.
//! - [`msd()`]: `<x>(t)`, `<x v>(t)`, `<x²>(t)` without sampling, from the
//!   chain of x-weighted densities (TR-BDF2 on [`ForwardOperator`]).
//! - [`transient()`]: time stepping from the paper's initial condition:
//!   adaptive TR-BDF2 on the graded mesh ([`ForwardOperator`]), or the
//!   paper's explicit scheme on a uniform mesh.

mod extrapolate;
mod grid;
mod moments;
mod nstate;
mod operator;
mod position;
mod refractory;
mod solve;
mod stationary;
mod transient;

pub use extrapolate::extrapolation_error;
pub use grid::Mesh;
pub use moments::{moments as msd, MomentSeries, MsdOptions, MAX_LEVELS, MAX_MSD_CELLS};
pub use nstate::NoiseOperator;
pub use operator::ForwardOperator;
pub use stationary::{
    stationary, Moments, NoiseMoments, NoiseSummary, Stationary, StationaryOptions, MAX_CELLS,
    MIN_CELLS,
};
pub use transient::{
    plan as transient_plan, transient, transient_with_progress, trbdf2_step_bound,
    Plan as TransientPlan, Scheme, Snapshot, Transient, TransientOptions, DEFAULT_ATOL,
    DEFAULT_RTOL, TRBDF2_STEP_CAP, TRBDF2_UPDATES_PER_STEP,
};
