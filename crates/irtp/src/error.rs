//! Error type shared by the whole library. The binary maps every variant to a
//! one-line message and an exit code: 2 for bad input (a parameter out of
//! range, a run over its work or memory budget), 4 for a numerical failure,
//! 1 for i/o (see docs/output-formats.md, "Exit codes").
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
    /// A method does not run a combination of model and protocol (the
    /// table of [`crate::capability`]): refused before any work, naming
    /// the flag, the method and the methods that run it.
    #[error("invalid {flag} = {value}: {feature} not run by {method}; runs in {runners}")]
    Unsupported {
        /// The parameter that asks for it, in snake_case (`noise`, `refractory`).
        flag: &'static str,
        /// Its value, formatted.
        value: String,
        /// What is refused, in words (`thermal noise (T > 0)`).
        feature: &'static str,
        /// The method that refuses it (`mfpt --method exact`).
        method: String,
        /// The methods that run it (`simulate, fp, mfpt (backward, euler)`).
        runners: String,
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
    /// The work or memory a run is estimated to need exceeds its budget
    /// (`max_work`, `max_memory`): refused before it starts.
    #[error(
        "too costly: estimated {estimate:.2e} {unit} from {}, above {limit_name} = {limit:e}; \
         reduce them or raise {limit_name}",
        drivers.join(", ")
    )]
    TooCostly {
        /// What is counted: "particle events", "cell updates", "bytes of memory", ...
        unit: &'static str,
        /// The estimate.
        estimate: f64,
        /// The parameters the estimate grows with (library names).
        drivers: Vec<&'static str>,
        /// The budget parameter (`max_work` or `max_memory`).
        limit_name: &'static str,
        /// Its value.
        limit: f64,
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
            value: echo(&short_number(value.to_string())),
            allowed: short_numbers(&allowed.into()),
        }
    }

    /// Build an [`Error::Unsupported`]: `method` refuses `feature`, asked
    /// for by `flag` = `value`; `runners` run it.
    pub fn unsupported(
        flag: &'static str,
        value: impl std::fmt::Display,
        feature: &'static str,
        method: impl Into<String>,
        runners: impl Into<String>,
    ) -> Self {
        Error::Unsupported {
            flag,
            value: echo(&short_number(value.to_string())),
            feature,
            method: method.into(),
            runners: runners.into(),
        }
    }

    /// The parameter a refusal names: the `name` of an
    /// [`Error::InvalidParameter`], the `flag` of an [`Error::Unsupported`];
    /// None for any other error.
    pub fn parameter(&self) -> Option<&'static str> {
        match self {
            Error::InvalidParameter { name, .. } => Some(name),
            Error::Unsupported { flag, .. } => Some(flag),
            _ => None,
        }
    }

    /// True for a numerical failure of a method (exit code 4): no answer it
    /// could verify.
    pub fn is_numerical(&self) -> bool {
        matches!(
            self,
            Error::Overflow { .. }
                | Error::NotConverged { .. }
                | Error::NonFinite { .. }
                | Error::Numerical { .. }
        )
    }

    /// True for errors caused by bad user input (exit code 2).
    pub fn is_input_error(&self) -> bool {
        matches!(
            self,
            Error::InvalidParameter { .. } | Error::Unsupported { .. } | Error::TooCostly { .. }
        )
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
            } => format!(
                "invalid {} = {value}: allowed {}",
                rename(name),
                rename_parameters(allowed, &rename)
            ),
            Error::Unsupported {
                flag,
                value,
                feature,
                method,
                runners,
            } => format!(
                "invalid {} = {value}: {feature} not run by {method}; runs in {runners}",
                rename(flag)
            ),
            Error::TooCostly {
                unit,
                estimate,
                drivers,
                limit_name,
                limit,
            } => {
                let names: Vec<String> = drivers.iter().map(|d| rename(d)).collect();
                let budget = rename(limit_name);
                format!(
                    "too costly: estimated {estimate:.2e} {unit} from {}, above {budget} = \
                     {limit:e}; reduce them or raise {budget}",
                    names.join(", ")
                )
            }
            other => short_numbers(&other.to_string()),
        }
    }
}

/// The library's parameter names that a range in a message may mention
/// (`t_max >= dt`): [`Error::message_with`] spells them as the front end
/// does wherever they stand next to a comparison.
pub const PARAMETER_NAMES: &[&str] = &[
    "atol",
    "bins",
    "burn_in",
    "cells",
    "cells_v",
    "cells_x",
    "cfl",
    "control_cells",
    "cpus_per_task",
    "dt",
    "events",
    "grid_points",
    "lambda",
    "large_tau_ratio",
    "max_array",
    "max_tasks",
    "particles",
    "points",
    "points_per_task",
    "r_max",
    "r_min",
    "rate",
    "reset_period",
    "reset_position",
    "reset_velocity",
    "rtol",
    "samples",
    "sigma",
    "t_max",
    "t_min",
    "tail",
    "throttle",
    "v0",
    "vt",
];

/// `text` with every name of [`PARAMETER_NAMES`] that stands next to a
/// comparison (`<`, `>`, `=`, `≤`, `≥`, `≠`, spaces between allowed)
/// replaced by `rename(name)`; every other word unchanged (`mean < 1` in a
/// reset spec's range is a key, not a parameter, and so is `sigma=S`, a
/// key of a spec's syntax).
fn rename_parameters(text: &str, rename: &impl Fn(&str) -> String) -> String {
    let is_word = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let is_cmp = |c: Option<char>| matches!(c, Some('<' | '>' | '=' | '≤' | '≥' | '≠'));
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(is_word) {
        let (before, word_on) = rest.split_at(start);
        let end = word_on.find(|c: char| !is_word(c)).unwrap_or(word_on.len());
        let (word, after) = word_on.split_at(end);
        let prev = before
            .chars()
            .rev()
            .chain(out.chars().rev())
            .find(|c| *c != ' ');
        let next = after.chars().find(|c| *c != ' ');
        out.push_str(before);
        // `sigma=S` in a spec's syntax is a key, not a flag.
        let key = after.starts_with('=') && !after[1..].starts_with([' ', '=']);
        if PARAMETER_NAMES.contains(&word) && !key && (is_cmp(prev) || is_cmp(next)) {
            out.push_str(&rename(word));
        } else {
            out.push_str(word);
        }
        rest = after;
    }
    out.push_str(rest);
    out
}

/// A number printed by `Display` in full (`1e300` as 301 digits) in
/// scientific notation instead; any other text unchanged.
fn short_number(s: String) -> String {
    match s.parse::<f64>() {
        Ok(x) if s.len() > 17 && x.is_finite() => format!("{x:e}"),
        _ => s,
    }
}

/// `x` in at most 6 significant digits: plain from 1e-4 to 1e6
/// (`0.785398`, `1250`), else in scientific notation (`1e-300`,
/// `1.23457e300`); the form every message prints a number in.
pub fn short(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-4..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.')
        } else {
            &s
        };
        return s.to_string();
    }
    let s = format!("{x:.5e}");
    let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    format!("{mantissa}e{exponent}")
}

/// Longest echo of a user's value in a message (then cut to [`ECHO_CUT`]
/// characters and `…`).
const ECHO_MAX: usize = 48;
/// Characters of a long echoed value kept.
const ECHO_CUT: usize = 40;

/// A value as a message echoes it: its first `ECHO_CUT` characters and
/// `…` when it is longer than `ECHO_MAX` (a table or an expression of
/// megabytes is not printed back whole).
pub fn echo(value: &str) -> String {
    if value.chars().count() <= ECHO_MAX {
        return value.to_string();
    }
    let cut: String = value.chars().take(ECHO_CUT).collect();
    format!("{cut}…")
}

/// `text` with every number of more than 12 digits (`Display` of an f64
/// such as 1e300 or 1e-300 in full) printed by [`short`], and every word
/// (a run without spaces) longer than 80 characters cut as [`echo`] cuts
/// it: a message stays one short line whatever it quotes.
pub fn short_numbers(text: &str) -> String {
    let is_num = |c: char| c.is_ascii_digit() || c == '.';
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        let (before, from) = rest.split_at(start);
        let mut end = from.find(|c: char| !is_num(c)).unwrap_or(from.len());
        // An exponent: e, an optional sign, digits.
        let tail = &from[end..];
        if let Some(exp) = tail.strip_prefix(['e', 'E']) {
            let unsigned = exp.strip_prefix(['-', '+']).unwrap_or(exp);
            let digits = unsigned
                .find(|c: char| !c.is_ascii_digit())
                .unwrap_or(unsigned.len());
            if digits > 0 {
                end += 1 + (exp.len() - unsigned.len()) + digits;
            }
        }
        let (token, after) = from.split_at(end);
        out.push_str(before);
        let digits = token.chars().filter(char::is_ascii_digit).count();
        match token.parse::<f64>() {
            Ok(x) if digits > 12 && x.is_finite() => out.push_str(&short(x)),
            _ => out.push_str(token),
        }
        rest = after;
    }
    out.push_str(rest);
    let words: Vec<String> = out
        .split(' ')
        .map(|w| {
            if w.chars().count() > 80 {
                echo(w)
            } else {
                w.to_string()
            }
        })
        .collect();
    words.join(" ")
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
    fn short_prints_at_most_six_significant_digits() {
        let cases = [
            (std::f64::consts::FRAC_PI_4, "0.785398"),
            (1250.0, "1250"),
            (-0.25, "-0.25"),
            (1e-300, "1e-300"),
            (1.234567891e300, "1.23457e300"),
            (123456789.0, "1.23457e8"),
            (0.0, "0"),
            (f64::INFINITY, "inf"),
        ];
        for (x, s) in cases {
            assert_eq!(short(x), s);
        }
        let long = format!("T = {} and t = {}, 12 and 1e-3", 1e300, 1e-300);
        assert_eq!(
            short_numbers(&long),
            "T = 1e300 and t = 1e-300, 12 and 1e-3"
        );
    }

    #[test]
    fn message_with_renames_only_the_parameter() {
        let e = Error::invalid("t_max", -1, "t_max > 0");
        assert_eq!(e.to_string(), "invalid t_max = -1: allowed t_max > 0");
        assert_eq!(e.message_with(|n| n.to_string()), e.to_string());
        assert_eq!(
            e.message_with(|n| format!("--{}", n.replace('_', "-"))),
            "invalid --t-max = -1: allowed --t-max > 0"
        );
        let e = Error::invalid("t_max", -1, "t_max >= dt = 0.001, mean < 1, the rate");
        assert_eq!(
            e.message_with(|n| format!("--{}", n.replace('_', "-"))),
            "invalid --t-max = -1: allowed --t-max >= --dt = 0.001, mean < 1, the rate"
        );
        let e = Error::invalid("noise", "x", "telegraph:sigma=S,lambda=L (sigma > 0)");
        assert_eq!(
            e.message_with(|n| format!("--{n}")),
            "invalid --noise = x: allowed telegraph:sigma=S,lambda=L (--sigma > 0)"
        );
        let n = Error::NotConverged {
            method: "m",
            iterations: 3,
            residual: 0.5,
            tolerance: 1e-9,
        };
        assert_eq!(n.message_with(|_| unreachable!()), n.to_string());
        let e = Error::invalid(
            "sigma",
            1e-300,
            format!("sigma < {} or {}", 1e300, "x".repeat(99)),
        );
        assert_eq!(
            e.to_string().len(),
            "invalid sigma = 1e-300: allowed sigma < 1e300 or ".len() + 43
        );
        assert!(e.to_string().contains("sigma < 1e300 or xxxx"));
        assert_eq!(echo(&"y".repeat(1000)), format!("{}…", "y".repeat(40)));
        assert!(!n.is_input_error() && e.is_input_error());
    }
}
