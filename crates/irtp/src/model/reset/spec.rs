//! The compact reset spec `target[,noise=kept|redrawn]` that names a
//! resetting protocol on the command line (`--reset-to`, `--reset-noise`)
//! and in every provenance file: `point:v=0.2,noise=redrawn`.
//!
//! Written with every key, each value in Rust's shortest round-trip form, so
//! the written spec parses back to the same rule bit for bit. Parsing
//! accepts the keys in any order; an unknown, repeated or missing key and a
//! value that is not a number are each one error naming the flag. The kinds
//! and their keys come from the target registry ([`super::target`]).

use super::{NoiseAtReset, Target};
use crate::error::{Error, Result};
use crate::model::drag::spec::number;

/// `point:v=0.2,noise=redrawn`: the canonical spec of a target and noise rule.
pub fn write(target: &Target, noise: NoiseAtReset) -> String {
    let values: Vec<String> = target
        .keyed_values()
        .into_iter()
        .map(|(k, v)| format!("{k}={}", number(v)))
        .collect();
    format!(
        "{}:{},noise={}",
        target.kind(),
        values.join(","),
        noise.name()
    )
}

/// Parse a spec: the target (its keys) and the noise rule, if the spec
/// names one. Range checks against the velocity interval are the
/// caller's ([`crate::Params::with_reset`]), which also sets the
/// truncation of a Gaussian (left at ±∞ here).
pub fn parse(spec: &str) -> Result<(Target, Option<NoiseAtReset>)> {
    let bad = |what: String| {
        Error::invalid(
            "reset_to",
            spec,
            crate::model::keys::reason(
                "--reset-to",
                spec,
                &what,
                &format!("{}[,noise=kept|redrawn]", Target::usage()),
            ),
        )
    };
    let (kind, args) = spec.trim().split_once(':').unwrap_or((spec.trim(), ""));
    let keys = Target::parse_kind(kind).map_err(bad)?;
    let mut names = keys.to_vec();
    names.push("noise");
    let mut texts = crate::model::keys::pairs(args, &names).map_err(bad)?;
    let noise = match texts.pop().flatten() {
        Some(value) => Some(
            value
                .parse::<NoiseAtReset>()
                .map_err(|_| bad(format!("noise=kept or noise=redrawn, not '{value}'")))?,
        ),
        None => None,
    };
    let mut values: Vec<Option<f64>> = vec![None; keys.len()];
    for (i, text) in texts.into_iter().enumerate() {
        let Some(value) = text else { continue };
        let key = keys[i];
        let x: f64 = value
            .parse()
            .map_err(|_| bad(format!("a number for {key}, not '{value}'")))?;
        values[i] = Some(x);
    }
    let mut out = Vec::with_capacity(keys.len());
    for (k, v) in keys.iter().zip(values) {
        out.push(v.ok_or_else(|| bad(format!("a value for {k} (required)")))?);
    }
    let target = Target::build(kind, &out).expect("a kind of the registry");
    Ok((target, noise))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let s = write(&Target::point(0.2), NoiseAtReset::Redrawn);
        assert_eq!(s, "point:v=0.2,noise=redrawn");
        assert_eq!(
            parse(&s).unwrap(),
            (Target::point(0.2), Some(NoiseAtReset::Redrawn))
        );
        assert_eq!(
            parse("point:v=-1e-3").unwrap(),
            (Target::point(-1e-3), None)
        );
        for t in [Target::gauss(0.1, 0.3), Target::uniform(-0.2, 0.5)] {
            let s = write(&t, NoiseAtReset::Kept);
            assert_eq!(parse(&s).unwrap(), (t, Some(NoiseAtReset::Kept)), "{s}");
        }
        for bad in [
            "",
            "dirac:v=0",
            "point",
            "point:v=x",
            "point:v=0,v=1",
            "point:w=0",
            "point:v=0,noise=maybe",
        ] {
            let e = parse(bad).unwrap_err().to_string();
            assert!(e.starts_with("invalid reset_to"), "{bad}: {e}");
        }
    }
}
