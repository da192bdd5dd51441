//! Error type shared by the whole library. The binary maps every variant to a
//! one-line message and exit code 2 (bad input) or 1 (runtime failure).
//!
//! Parameters are named as the library names them (`sigma`, `t_max`,
//! `reset_velocity`); the binary translates those names to its flags.

use thiserror::Error;

/// Library error.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A parameter is outside its admissible range (or not finite).
    #[error("invalid {name} = {value}: allowed {allowed}")]
    InvalidParameter {
        /// The library's parameter name in snake_case (e.g. `sigma`, `t_max`).
        name: &'static str,
        /// The offending value, formatted.
        value: String,
        /// Human-readable admissible range.
        allowed: String,
    },
    /// A result exceeds the f64 range (~1e308), e.g. a mean first-passage time
    /// under resetting so frequent that the target is practically never reached.
    #[error("numerical failure in {method}: {quantity} exceeds the f64 range (~1e308): {meaning}")]
    Overflow {
        /// Which solver.
        method: &'static str,
        /// What overflowed, in words.
        quantity: &'static str,
        /// What the overflow means for the user.
        meaning: &'static str,
    },
    /// An iterative routine stopped before meeting its tolerance.
    #[error(
        "numerical failure in {method}: no convergence after {iterations} iterations \
         (residual {residual:e}, tolerance {tolerance:e})"
    )]
    NotConverged {
        /// Which routine.
        method: &'static str,
        /// Iterations spent (steps, sweeps or panels, as the routine counts them).
        iterations: usize,
        /// What was left: last step, bracket width or error estimate, as the
        /// routine measures convergence.
        residual: f64,
        /// The tolerance `residual` had to meet.
        tolerance: f64,
    },
    /// A function evaluated by a numerical routine returned NaN or ±∞.
    #[error("numerical failure in {method}: non-finite value near x = {at}")]
    NonFinite {
        /// Which routine.
        method: &'static str,
        /// Argument (or panel midpoint) where it happened.
        at: f64,
    },
    /// A numerical method failed to produce a trustworthy answer.
    #[error("numerical failure in {method}: {reason}")]
    Numerical {
        /// Which solver.
        method: &'static str,
        /// What went wrong.
        reason: String,
    },
    /// The caller asked the computation to stop (Ctrl-C in Python, see
    /// [`crate::parallel::Progress::cancelled`]); nothing was written.
    #[error("interrupted: the computation was cancelled and nothing was written")]
    Interrupted,
    /// Input/output failure (writing results).
    #[error("i/o error on {path}: {reason}")]
    Io {
        /// Path involved.
        path: String,
        /// OS error text.
        reason: String,
    },
}

impl Error {
    /// Build an [`Error::InvalidParameter`] from any displayable value.
    pub fn invalid(
        name: &'static str,
        value: impl std::fmt::Display,
        allowed: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
            name,
            value: value.to_string(),
            allowed: allowed.into(),
        }
    }

    /// True for errors caused by bad user input (exit code 2).
    pub fn is_input_error(&self) -> bool {
        matches!(self, Error::InvalidParameter { .. })
    }

    /// The message, with the parameter name of an [`Error::InvalidParameter`]
    /// shown as `rename(name)` (a front end passes its own spelling, e.g. a
    /// command-line flag); every other variant reads as its `Display`.
    pub fn message_with(&self, rename: impl Fn(&str) -> String) -> String {
        match self {
            Error::InvalidParameter {
                name,
                value,
                allowed,
            } => format!("invalid {} = {value}: allowed {allowed}", rename(name)),
            other => other.to_string(),
        }
    }
}

/// Library result alias.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Reject NaN and infinities: `finite("sigma", x)?`.
pub fn finite(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, "a finite number"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn message_with_renames_only_the_parameter() {
        let e = Error::invalid("t_max", -1, "t_max > 0");
        assert_eq!(e.to_string(), "invalid t_max = -1: allowed t_max > 0");
        assert_eq!(e.message_with(|n| n.to_string()), e.to_string());
        assert_eq!(
            e.message_with(|n| format!("--{}", n.replace('_', "-"))),
            "invalid --t-max = -1: allowed t_max > 0"
        );
        let n = Error::NotConverged {
            method: "m",
            iterations: 3,
            residual: 0.5,
            tolerance: 1e-9,
        };
        assert_eq!(n.message_with(|_| unreachable!()), n.to_string());
        assert!(!n.is_input_error() && e.is_input_error());
    }
}
