//! Shared test models and helpers of the irtp test suites (in the spirit of
//! diffsol's `test_models`): [`laws`] lists the drag laws of the
//! cross-method conformance suite, [`models`] holds the paper's parameter sets and
//! the linear-drag cases with closed-form answers, [`linear_protocols`] the
//! linear-drag closed forms of the reset-protocol modifiers, [`spectral`] an
//! independent spectral reference, [`stats`] the tolerances of statistical
//! tests, [`noises`] the noise models and [`protocols`] the reset protocols of
//! their cross-method suites. Each test binary uses a subset.
#![allow(dead_code)]

pub mod laws;
pub mod linear_protocols;
pub mod models;
pub mod noises;
pub mod protocols;
pub mod spectral;
pub mod stats;
