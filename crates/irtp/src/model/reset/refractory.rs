//! A refractory period after each reset: the velocity is held at the value
//! the reset gave it (v_r), resets are ignored, the noise keeps flipping and
//! the position moves at v_r; when the period ends the flow resumes from
//! v_r with the noise state of that moment.
//!
//! - `exp:mean=M`: exponentially distributed duration of mean M (Markovian:
//!   one extra state per noise value, which the Fokker-Planck and backward
//!   solvers carry as a point mass / an extra unknown; it leaves at rate
//!   1/M).
//! - `fixed:t=T`: every period lasts exactly T (particle methods only).
//!
//! Spec written with every key, values in Rust's shortest round-trip form,
//! so a written spec parses back bit for bit.

use crate::error::{Error, Result};
use crate::model::drag::spec::number;
use serde::{Deserialize, Serialize};

/// The kinds and their keys, for messages.
pub const USAGE: &str = "exp:mean=M or fixed:t=T (M, T > 0)";

/// Duration law of the refractory period.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Refractory {
    /// Exponential with the given mean (leaves at rate 1/mean).
    Exp {
        /// Mean duration M > 0.
        mean: f64,
    },
    /// Fixed duration.
    Fixed {
        /// Duration T > 0.
        duration: f64,
    },
}

impl Refractory {
    /// Mean duration.
    pub fn mean(&self) -> f64 {
        match *self {
            Refractory::Exp { mean } => mean,
            Refractory::Fixed { duration } => duration,
        }
    }

    /// A duration drawn for one period.
    #[inline]
    pub fn draw<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            Refractory::Exp { mean } => mean * rng.sample::<f64, _>(rand_distr::Exp1),
            Refractory::Fixed { duration } => duration,
        }
    }

    /// The canonical spec (`exp:mean=0.5`, `fixed:t=0.5`).
    pub fn spec(&self) -> String {
        match *self {
            Refractory::Exp { mean } => format!("exp:mean={}", number(mean)),
            Refractory::Fixed { duration } => format!("fixed:t={}", number(duration)),
        }
    }
}

impl std::str::FromStr for Refractory {
    type Err = Error;
    fn from_str(spec: &str) -> Result<Self> {
        let bad = |what: String| {
            let reason = crate::model::keys::reason("--refractory", spec, &what, USAGE);
            Error::invalid("refractory", spec, reason)
        };
        let (kind, arg) = spec.trim().split_once(':').unwrap_or((spec.trim(), ""));
        let key = match kind {
            "exp" => "mean",
            "fixed" => "t",
            _ => return Err(bad(format!("a kind exp or fixed (not '{kind}')"))),
        };
        let v = crate::model::keys::pairs(arg, &[key])
            .map_err(bad)?
            .pop()
            .flatten()
            .ok_or_else(|| bad(format!("{key}=VALUE")))?;
        let x: f64 = v
            .trim()
            .parse()
            .map_err(|_| bad(format!("a number for {key}, not '{}'", v.trim())))?;
        if !(x > 0.0 && x.is_finite()) {
            return Err(bad(format!("{key} > 0, finite")));
        }
        Ok(match kind {
            "exp" => Refractory::Exp { mean: x },
            _ => Refractory::Fixed { duration: x },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        for s in ["exp:mean=0.5", "fixed:t=2"] {
            let r: Refractory = s.parse().unwrap();
            assert_eq!(r.spec(), s);
        }
        for bad in [
            "",
            "exp",
            "exp:mean=0",
            "exp:mean=-1",
            "exp:mean=nan",
            "exp:mean=inf",
            "fixed:mean=1",
            "gamma:k=1",
            "exp:mean=1,t=2",
        ] {
            let e = bad.parse::<Refractory>().unwrap_err().to_string();
            assert!(e.starts_with("invalid refractory"), "{bad}: {e}");
        }
    }
}
