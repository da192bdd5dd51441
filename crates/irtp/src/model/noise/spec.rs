//! The compact spec of a noise kind: `name:key=value,...`, where a value is
//! a number, a list `[a,b,...]` or a list of lists `[[..],[..]]`
//! (`states:levels=[1,-1],rates=[[-2,2],[3,-3]]`).
//!
//! Kinds write every key, each number in Rust's shortest round-trip form
//! (as drag specs do, [`crate::model::drag::spec`]), so a written spec
//! parses back to the same value bit for bit. Parsing accepts the keys in
//! any order; an unknown or repeated key and a value that is not a finite
//! number are each one error naming `noise`, the spec and its usage.

use crate::error::{Error, Result};

/// A number in the shortest form that parses back to it (`0.5`, `1e-7`).
pub fn number(x: f64) -> String {
    crate::model::drag::spec::number(x)
}

/// `[a,b,...]` with each entry by [`number`].
pub fn list(xs: &[f64]) -> String {
    let parts: Vec<String> = xs.iter().map(|&x| number(x)).collect();
    format!("[{}]", parts.join(","))
}

/// The error of a malformed or out-of-range spec: names `noise`, the spec
/// and what is allowed.
pub fn bad(spec: &str, what: impl std::fmt::Display, usage: &str) -> Error {
    let what = what.to_string();
    Error::invalid(
        "noise",
        spec,
        crate::model::keys::reason("--noise", spec, &what, usage),
    )
}

/// The comma-separated parts of `text` outside brackets, none empty.
fn split_top(text: &str) -> Vec<&str> {
    crate::model::keys::split_top(text)
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .collect()
}

/// The values of `keys` in a spec's arguments (None for a key not given):
/// every pair `key=value`, each key known and at most once, no empty item
/// ([`crate::model::keys::pairs`]).
pub fn pairs<'a>(
    spec: &str,
    args: Option<&'a str>,
    keys: &[&str],
    usage: &str,
) -> Result<Vec<Option<&'a str>>> {
    crate::model::keys::pairs(args.unwrap_or(""), keys).map_err(|what| bad(spec, what, usage))
}

/// A finite number for `key`.
pub fn finite_number(spec: &str, key: &str, text: &str, usage: &str) -> Result<f64> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(bad(
            spec,
            format!("a finite number for {key}, not '{}'", text.trim()),
            usage,
        )),
    }
}

/// A list `[a,b,...]` of finite numbers for `key`.
pub fn number_list(spec: &str, key: &str, text: &str, usage: &str) -> Result<Vec<f64>> {
    let inner = brackets(spec, key, text, usage)?;
    split_top(inner)
        .into_iter()
        .map(|x| finite_number(spec, key, x, usage))
        .collect()
}

/// A list of lists `[[..],[..]]` of finite numbers for `key`.
pub fn number_matrix(spec: &str, key: &str, text: &str, usage: &str) -> Result<Vec<Vec<f64>>> {
    let inner = brackets(spec, key, text, usage)?;
    split_top(inner)
        .into_iter()
        .map(|row| number_list(spec, key, row, usage))
        .collect()
}

/// The text inside the outer brackets of `text`.
fn brackets<'a>(spec: &str, key: &str, text: &'a str, usage: &str) -> Result<&'a str> {
    let t = text.trim();
    t.strip_prefix('[')
        .and_then(|t| t.strip_suffix(']'))
        .ok_or_else(|| {
            bad(
                spec,
                format!("a bracketed list for {key}, not '{t}'"),
                usage,
            )
        })
}

/// A value that must be given.
pub fn required<'a>(spec: &str, key: &str, value: Option<&'a str>, usage: &str) -> Result<&'a str> {
    value.ok_or_else(|| bad(spec, format!("a value for {key} (required)"), usage))
}

/// A finite value for `key`, else an error naming `noise`.
pub fn finite(spec: &str, key: &str, x: f64, usage: &str) -> Result<f64> {
    if x.is_finite() {
        return Ok(x);
    }
    Err(bad(spec, format!("a finite {key} ({key} = {x})"), usage))
}

/// A rate: finite and > 0, else an error naming `noise`, the key and its
/// value.
pub fn positive(spec: &str, key: &str, x: f64, usage: &str) -> Result<f64> {
    if x > 0.0 && x.is_finite() {
        return Ok(x);
    }
    Err(bad(
        spec,
        format!("{key} > 0 and finite ({key} = {x})"),
        usage,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_outside_brackets() {
        assert_eq!(
            split_top("levels=[1,-1],rates=[[-1,1],[2,-2]]"),
            vec!["levels=[1,-1]", "rates=[[-1,1],[2,-2]]"]
        );
        let m = number_matrix("s", "rates", "[[-1, 1], [2,-2]]", "u").unwrap();
        assert_eq!(m, vec![vec![-1.0, 1.0], vec![2.0, -2.0]]);
        assert!(number_list("s", "levels", "1,2", "u").is_err());
        assert!(finite_number("s", "a", "inf", "u").is_err());
    }
}
