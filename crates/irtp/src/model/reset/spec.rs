//! The compact reset spec `target[,noise=kept|redrawn]` that names a
//! resetting protocol on the command line (`--reset-to`, `--reset-noise`)
//! and in every provenance file: `point:v=0.2,noise=redrawn`.
//!
//! Written with every key, each value in Rust's shortest round-trip form, so
//! the written spec parses back to the same rule bit for bit. Parsing
//! accepts the keys in any order; an unknown, repeated or missing key and a
//! value that is not a number are each one error naming the flag.

use super::{NoiseAtReset, Target};
use crate::error::{Error, Result};
use crate::model::drag::spec::number;

/// The target kinds and their keys, for messages.
pub const USAGE: &str = "point:v=V, gauss:mean=M,std=S or uniform:a=A,b=B";

/// `point:v=0.2,noise=redrawn`: the canonical spec of a target and noise rule.
pub fn write(target: &Target, noise: NoiseAtReset) -> String {
    let t = match *target {
        Target::Point(v) => format!("point:v={}", number(v)),
        Target::Gaussian { mean, std, .. } => {
            format!("gauss:mean={},std={}", number(mean), number(std))
        }
        Target::Uniform { a, b } => format!("uniform:a={},b={}", number(a), number(b)),
    };
    format!("{t},noise={}", noise.name())
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
            format!("{what}, in {USAGE}[,noise=kept|redrawn]"),
        )
    };
    let (kind, args) = spec.trim().split_once(':').unwrap_or((spec.trim(), ""));
    let keys: &[&str] = match kind {
        "point" => &["v"],
        "gauss" => &["mean", "std"],
        "uniform" => &["a", "b"],
        _ => {
            return Err(bad(format!(
                "a target kind point, gauss or uniform (not '{kind}')"
            )))
        }
    };
    let mut values: Vec<Option<f64>> = vec![None; keys.len()];
    let mut noise = None;
    for pair in args.split(',').filter(|p| !p.trim().is_empty()) {
        let (key, value) = pair
            .split_once('=')
            .ok_or_else(|| bad(format!("key=value pairs, not '{}'", pair.trim())))?;
        let (key, value) = (key.trim(), value.trim());
        if key == "noise" {
            if noise.is_some() {
                return Err(bad("each key once ('noise' repeated)".into()));
            }
            noise = Some(
                value
                    .parse::<NoiseAtReset>()
                    .map_err(|_| bad(format!("noise=kept or noise=redrawn, not '{value}'")))?,
            );
            continue;
        }
        let i = keys.iter().position(|k| *k == key).ok_or_else(|| {
            bad(format!(
                "the keys {} (unknown key '{key}')",
                keys.join(", ")
            ))
        })?;
        if values[i].is_some() {
            return Err(bad(format!("each key once ('{key}' repeated)")));
        }
        let x: f64 = value
            .parse()
            .map_err(|_| bad(format!("a number for {key}, not '{value}'")))?;
        values[i] = Some(x);
    }
    let mut out = Vec::with_capacity(keys.len());
    for (k, v) in keys.iter().zip(values) {
        out.push(v.ok_or_else(|| bad(format!("a value for {k} (required)")))?);
    }
    let target = match kind {
        "point" => Target::Point(out[0]),
        "gauss" => Target::Gaussian {
            mean: out[0],
            std: out[1],
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
        },
        _ => Target::Uniform {
            a: out[0],
            b: out[1],
        },
    };
    Ok((target, noise))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let s = write(&Target::Point(0.2), NoiseAtReset::Redrawn);
        assert_eq!(s, "point:v=0.2,noise=redrawn");
        assert_eq!(
            parse(&s).unwrap(),
            (Target::Point(0.2), Some(NoiseAtReset::Redrawn))
        );
        assert_eq!(
            parse("point:v=-1e-3").unwrap(),
            (Target::Point(-1e-3), None)
        );
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
