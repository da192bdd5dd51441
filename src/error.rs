//! Error type shared by the whole library. The binary maps every variant to a
//! one-line message and exit code 2 (bad input) or 1 (runtime failure).

use thiserror::Error;

/// Library error.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A parameter is outside its admissible range (or not finite).
    #[error("invalid {name} = {value}: allowed {allowed}")]
    InvalidParameter {
        /// Parameter name as the user types it (e.g. `--sigma`).
        name: &'static str,
        /// The offending value, formatted.
        value: String,
        /// Human-readable admissible range.
        allowed: String,
    },
    /// A numerical method failed to produce a trustworthy answer.
    #[error("numerical failure in {method}: {reason}")]
    Numerical {
        /// Which solver.
        method: &'static str,
        /// What went wrong.
        reason: String,
    },
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
}

/// Library result alias.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Reject NaN and infinities: `finite("--sigma", x)?`.
pub fn finite(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, "a finite number"))
    }
}
