//! Laws with parameters: [`ParamLaw`] and the compact spec
//! `name:key=value,...` (`power:n=0.5,k=1`) that names such a law on the
//! command line, in sweep plans and in every provenance file.
//!
//! A spec is written with every key, in the law's key order, each value in
//! Rust's shortest round-trip form, so the written spec parses back to the
//! same law bit for bit. Parsing accepts the keys in any order and fills in
//! defaults; an unknown, repeated or missing key, a value that is not a
//! number, and a value outside its range are each one error naming the key.

use super::Drag;
use crate::error::{Error, Result};

/// One parameter of a [`ParamLaw`].
#[derive(Clone, Copy, Debug)]
pub struct Key {
    /// The key in the spec (`n`).
    pub name: &'static str,
    /// Its default, or None when the spec must give it.
    pub default: Option<f64>,
    /// What it is and its admissible range in words
    /// (`flow index n > 0, finite`).
    pub meaning: &'static str,
}

/// A drag law with parameters, carried by its [`super::DragLaw`] variant
/// (`DragLaw::Power(Power)`). Its spec is `name:key=value,...`.
pub trait ParamLaw: Drag + Copy + PartialEq {
    /// Its parameters in spec order.
    const KEYS: &'static [Key];
    /// The law at the given values (in [`ParamLaw::KEYS`] order), validated:
    /// an error names the first parameter out of range.
    fn from_values(values: &[f64]) -> Result<Self>;
    /// Its values in [`ParamLaw::KEYS`] order.
    fn values(&self) -> Vec<f64>;
    /// A representative law, for help texts and listings.
    fn example() -> Self;
}

/// A law named by a spec `name:...` whose [`super::DragLaw`] variant
/// carries its value: every [`ParamLaw`] (`power:n=0.5,k=1`, through the
/// functions of this module) and the expression law (`expr:v + v^3/3`).
pub trait SpecLaw: Drag + PartialEq {
    /// A representative law, for help texts and listings.
    fn example() -> Self;
    /// The law of a spec: `args` is the part after `name:` (None when the
    /// spec has no `:`), `spec` the whole spec, for messages.
    fn parse(spec: &str, args: Option<&str>) -> Result<Self>;
    /// Its canonical spec, which parses back to the same law.
    fn write(&self) -> String;
    /// How to write the spec, for messages (`power:n=N[,k=K]`).
    fn usage() -> String;
    /// Its parameters in words, for help texts.
    fn keys_help() -> String;
}

impl<L: ParamLaw> SpecLaw for L {
    fn example() -> Self {
        <L as ParamLaw>::example()
    }
    fn parse(spec: &str, args: Option<&str>) -> Result<Self> {
        parse::<L>(spec, args)
    }
    fn write(&self) -> String {
        write(self)
    }
    fn usage() -> String {
        usage::<L>()
    }
    fn keys_help() -> String {
        keys_help::<L>()
    }
}

/// The spec of a law: `power:n=0.5,k=1` (every key).
pub fn write<L: ParamLaw>(law: &L) -> String {
    let pairs: Vec<String> = L::KEYS
        .iter()
        .zip(law.values())
        .map(|(k, v)| format!("{}={}", k.name, number(v)))
        .collect();
    format!("{}:{}", law.name(), pairs.join(","))
}

/// A value in the shortest form that parses back to it: `0.5`, `1`,
/// `1e-7`, `3.5e200` (the shorter of the plain and the exponent form, the
/// plain one on a tie).
pub(crate) fn number(x: f64) -> String {
    let (plain, exp) = (format!("{x}"), format!("{x:e}"));
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

/// How to write a law's spec, for messages: `power:n=N[,k=K]`.
pub fn usage<L: ParamLaw>() -> String {
    let mut s = format!("{}:", L::example().name());
    for (i, k) in L::KEYS.iter().enumerate() {
        let sep = if i == 0 { "" } else { "," };
        let value = k.name.to_uppercase();
        match k.default {
            None => s += &format!("{sep}{}={value}", k.name),
            Some(_) => s += &format!("[{sep}{}={value}]", k.name),
        }
    }
    s
}

/// The keys, their meaning and defaults in words (for help texts).
pub fn keys_help<L: ParamLaw>() -> String {
    let parts: Vec<String> = L::KEYS
        .iter()
        .map(|k| match k.default {
            None => format!("{}: {}, required", k.name, k.meaning),
            Some(d) => format!("{}: {}, default {d}", k.name, k.meaning),
        })
        .collect();
    parts.join("; ")
}

/// Parse the part after `name:` of a spec (`args`; None when the spec has
/// no `:`). `spec` is the whole spec, for messages.
pub fn parse<L: ParamLaw>(spec: &str, args: Option<&str>) -> Result<L> {
    let names: Vec<&str> = L::KEYS.iter().map(|k| k.name).collect();
    let texts = crate::model::keys::pairs(args.unwrap_or(""), &names)
        .map_err(|what| bad::<L>(spec, what))?;
    let mut values: Vec<Option<f64>> = vec![None; L::KEYS.len()];
    for (i, text) in texts.into_iter().enumerate() {
        let Some(value) = text else { continue };
        let key = L::KEYS[i].name;
        let x: f64 = value.parse().map_err(|_| {
            bad::<L>(
                spec,
                format!("a number for {key} ({}), not '{value}'", L::KEYS[i].meaning),
            )
        })?;
        values[i] = Some(x);
    }
    let mut out = Vec::with_capacity(L::KEYS.len());
    for (k, v) in L::KEYS.iter().zip(values) {
        match v.or(k.default) {
            Some(x) => out.push(x),
            None => {
                return Err(bad::<L>(
                    spec,
                    format!("a value for {} (required; {})", k.name, k.meaning),
                ))
            }
        }
    }
    L::from_values(&out)
}

/// The error of a malformed spec: names `drag`, the spec and how to write it.
fn bad<L: ParamLaw>(spec: &str, what: String) -> Error {
    let reason = crate::model::keys::reason("--drag", spec, &what, &usage::<L>());
    Error::invalid("drag", spec, reason)
}

/// Validate one parameter: finite and > 0, else an error naming it
/// (`key`), its value and its meaning.
pub fn positive<L: ParamLaw>(key: &'static str, x: f64) -> Result<f64> {
    if x > 0.0 && x.is_finite() {
        return Ok(x);
    }
    Err(out_of_range::<L>(key, x))
}

/// Validate one parameter: finite and >= 0, else an error naming it
/// (`key`), its value and its meaning.
pub fn non_negative<L: ParamLaw>(key: &'static str, x: f64) -> Result<f64> {
    if x >= 0.0 && x.is_finite() {
        return Ok(x);
    }
    Err(out_of_range::<L>(key, x))
}

/// The error of a parameter out of range: names `drag`, the law with the
/// value (`power with n=0`), the key's meaning and how to write the spec.
fn out_of_range<L: ParamLaw>(key: &'static str, x: f64) -> Error {
    let meaning = L::KEYS
        .iter()
        .find(|k| k.name == key)
        .map_or("", |k| k.meaning);
    let name = L::example().name();
    Error::invalid(
        "drag",
        format!("{name} with {key}={x}"),
        format!("{meaning}, in {}", usage::<L>()),
    )
}
