//! The one integration-test binary of the core library (model, numerics, samplers, Fokker-Planck, first passage, closed forms).
//! Each module is one former test file; shared helpers live in `common`.

mod analytic;
mod architecture;
mod clock;
mod common;
mod conformance;
mod control_variate;
mod exact_flow;
mod exact_fp;
mod exact_fpt;
mod exact_mfpt;
mod exact_r0;
mod exact_sim;
mod fp_linear;
mod fp_r0;
mod fp_sim;
mod fp_transient;
mod mfpt_backward;
mod mfpt_control;
mod mfpt_sim;
mod models;
mod msd_fit;
mod noise;
mod noise_backward;
mod power_kink;
mod search_backward;
mod search_cross;
mod search_exact;
mod search_methods;
mod search_optimize;
mod shards;
mod sim_euler;
mod support_matrix;
mod tabulated_flow;
