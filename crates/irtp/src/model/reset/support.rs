//! Which method runs which resetting protocol: the protocol dimension of
//! [`crate::capability`], re-exported here where the protocols live.

pub use crate::capability::{runners, supports, Feature, Solver};
