//! The shared test models ([`irtp_testkit`]).
pub use irtp_testkit::*;
