//! The one integration-test binary of the `irtp` program, run as a user runs it (flags, outputs, exit codes), and the cross-method checks that go through it.
//! Each module is one former test file; shared helpers live in `common`.

mod atoms;
mod censoring;
mod cli_analytic;
mod cli_errors;
mod cli_simulate;
mod clock_cli;
#[allow(dead_code)]
mod common;
mod counts;
mod data_safety;
mod docs;
mod drag_specs;
mod euler_noise_schedule_cli;
mod exact_cli;
mod fp_cli;
mod fp_msd;
mod fp_protocols_transient;
mod fpt_distribution;
mod help;
mod hostile;
#[cfg(unix)]
mod interrupt;
mod messages;
mod mfpt_cli;
mod mfpt_euler_noise_schedule_cli;
mod noise_backward_cli;
mod noise_cli;
mod noise_euler_cli;
mod noise_exact_cli;
mod noise_fp_cli;
mod noise_fpt_dist_exact_cli;
mod noise_fpt_exact_cli;
mod noise_fpt_schedule_cli;
mod plot;
mod progress;
mod protocol_samplers;
mod protocol_solvers;
mod random_target_fpt;
mod reproduce;
mod reset_protocols;
mod search_cli;
mod search_guards;
mod search_hostile;
mod sim_noise_schedule;
mod sweep;
mod value_stability;
mod verified;
