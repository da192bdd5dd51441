//! Renewal reset clocks: the law of the waiting time between resets
//! (`--reset-clock SPEC`). One file per law behind [`Law`], one registry
//! line in [`clock_laws!`](crate::clock_laws):
//!
//! - `exp:rate=R` ([`exp`]): the Poisson clock as a renewal clock;
//! - `gamma:k=K,theta=TH` ([`gamma`]);
//! - `weibull:k=K,scale=L` ([`weibull`]);
//! - `pareto:alpha=A,scale=X` ([`pareto`]): Pareto I, support t ≥ X, a
//!   power-law tail, infinite mean for A ≤ 1;
//! - `fixed:t=T` ([`fixed`]): deterministic, sharp resetting;
//! - `table:T0:W0;T1:W1;...` ([`table`]): a tabulated survival W(t),
//!   linear between the points;
//! - `hazard:EXPR` ([`hazard`]): an age-dependent rate r(a) written in the
//!   age a since the last reset.
//!
//! The clock restarts at every reset (at the end of the refractory period
//! when there is one): the next reset comes a drawn waiting time later
//! (docs/equations.md, "Renewal resetting"). The process starts at age 0
//! (a reset at t = 0), as a periodic clock does.
//!
//! A spec is written with every key, numbers in Rust's shortest round-trip
//! form, so a written spec parses back bit for bit. Every error names
//! `reset_clock` and the supported range.
//!
//! The laws are `Clone` (as [`crate::Params`] is): a table and a hazard
//! expression are shared by the copies of their law and freed with the
//! last (`model::shared`), as the `expr:` drag law is.

pub mod exp;
pub mod fixed;
pub mod gamma;
pub mod hazard;
pub mod pareto;
pub mod special;
pub mod table;
pub mod weibull;

use crate::error::{Error, Result};
use crate::numerics::quad;
use rand::Rng;
use std::fmt;

/// The flag (parameter name) of every clock error.
pub const FLAG: &str = "reset_clock";

/// A law of the waiting time R between resets.
pub trait Law: Clone + fmt::Debug + PartialEq + Send + Sync + Sized {
    /// The kind as spelled in a spec (`gamma`).
    const KIND: &'static str;
    /// The keys and their ranges, for messages (`gamma:k=K,theta=TH (K, TH > 0)`).
    const USAGE: &'static str;
    /// Parse the part after `kind:`; errors name [`FLAG`] and the whole
    /// `spec`.
    fn parse(args: &str, spec: &str) -> Result<Self>;
    /// The canonical spec (parses back bit for bit).
    fn spec(&self) -> String;
    /// One waiting time (exact in distribution).
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64;
    /// Survival W(t) = P(R > t).
    fn survival(&self, t: f64) -> f64;
    /// F(t) = P(R ≤ t).
    fn cdf(&self, t: f64) -> f64 {
        1.0 - self.survival(t)
    }
    /// The density rho(t), where the law has one.
    fn density(&self, t: f64) -> Option<f64>;
    /// E(R) (∞ for a law without a finite mean).
    fn mean(&self) -> f64;
    /// The same shape with mean `mean` (a rescaling of time); refused for
    /// a law without a finite mean.
    fn with_mean(&self, mean: f64) -> Result<Self>;
    /// ∫_t^∞ W(s) ds (∞ for a law without a finite mean).
    fn tail_integral(&self, t: f64) -> f64;
    /// ∫_a^b W(s) ds (a ≤ b), by G7/K15 quadrature unless the law has a
    /// closed form (W is continuous, so one K15 panel per renewal step is
    /// accurate far below the steps' own error).
    fn survival_integral(&self, a: f64, b: f64) -> f64 {
        quad::gk15(&|s| self.survival(s), a, b).kronrod
    }
    /// ∫_a^b W(s) (s - a) ds: the first-moment part of product integration.
    fn survival_moment(&self, a: f64, b: f64) -> f64 {
        quad::gk15(&|s| self.survival(s) * (s - a), a, b).kronrod
    }
    /// The smallest t with W(t) ≤ `tail` (bisection on W by default).
    fn horizon(&self, tail: f64) -> f64 {
        horizon_by_bisection(|t| self.survival(t), tail)
    }
    /// Product-integration weights on t_n = n t_max / steps of ∫ W f and
    /// ∫ rho f over [0, t_max] for f linear between the t_n, and
    /// W(t_max) = P(R > t_max) (docs/equations.md, (S7')): on a step
    /// [t_n, t_n+1] with s = (t - t_n)/dt, ∫ rho (1 - s) and ∫ rho s are
    /// F(t_n+1) - F(t_n) - i1 and i1 = ∫W/dt - W(t_n+1) (by parts), exact
    /// for the law's CDF; ∫ W (1 - s) and ∫ W s from
    /// [`Law::survival_integral`] and [`Law::survival_moment`].
    fn renewal_weights(&self, t_max: f64, steps: usize) -> (Vec<f64>, Vec<f64>, f64) {
        product_weights(self, t_max, steps)
    }
    /// The end of the support: the longest possible waiting time (∞ for
    /// an unbounded law).
    fn support_end(&self) -> f64 {
        f64::INFINITY
    }
    /// The next reset time when the clock restarts at `free`.
    #[inline]
    fn next_after<R: Rng + ?Sized>(&self, free: f64, rng: &mut R) -> f64 {
        free + self.draw(rng)
    }
}

/// [`Law::renewal_weights`] for any law.
pub fn product_weights<L: Law>(law: &L, t_max: f64, steps: usize) -> (Vec<f64>, Vec<f64>, f64) {
    let dt = t_max / steps as f64;
    let (mut wq, mut rq) = (vec![0.0; steps + 1], vec![0.0; steps + 1]);
    let mut w0 = law.survival(0.0);
    for n in 0..steps {
        let (a, b) = (n as f64 * dt, (n + 1) as f64 * dt);
        let w1 = law.survival(b);
        let int = law.survival_integral(a, b);
        let moment = law.survival_moment(a, b) / dt;
        wq[n] += int - moment;
        wq[n + 1] += moment;
        let i0 = w0 - w1;
        let i1 = (int / dt - w1).clamp(0.0, i0);
        rq[n] += i0 - i1;
        rq[n + 1] += i1;
        w0 = w1;
    }
    (wq, rq, law.survival(t_max))
}

/// The smallest t with `w(t) ≤ tail` of a nonincreasing `w` to rounding:
/// bracketed by doubling from 1e-300 (∞ when w stays above tail up to
/// 1e300), then bisected.
pub fn horizon_by_bisection(w: impl Fn(f64) -> f64, tail: f64) -> f64 {
    if w(0.0) <= tail {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 1e-300_f64);
    while w(hi) > tail {
        lo = hi;
        hi *= 2.0;
        if hi > 1e300 {
            return f64::INFINITY;
        }
    }
    for _ in 0..2100 {
        let mid = 0.5 * (lo + hi);
        if !(mid > lo && mid < hi) {
            break;
        }
        if w(mid) > tail {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The error of a bad spec: names [`FLAG`], the spec and `what` is wrong
/// in `usage`.
pub fn bad(spec: &str, what: impl fmt::Display, usage: &str) -> Error {
    let what = what.to_string();
    Error::invalid(
        FLAG,
        spec,
        crate::model::keys::reason("--reset-clock", spec, &what, usage),
    )
}

/// The values of `keys` in `args` (`k=2,theta=0.5`, any order, each once),
/// each a finite number; errors name [`FLAG`].
pub fn keyed(args: &str, spec: &str, keys: &[&str], usage: &str) -> Result<Vec<f64>> {
    let texts = crate::model::keys::pairs(args, keys).map_err(|what| bad(spec, what, usage))?;
    let mut values: Vec<Option<f64>> = vec![None; keys.len()];
    for (i, text) in texts.into_iter().enumerate() {
        let Some(value) = text else { continue };
        let key = keys[i];
        let x: f64 = value
            .parse()
            .map_err(|_| bad(spec, format!("a number for {key}, not '{value}'"), usage))?;
        if !x.is_finite() {
            return Err(bad(spec, format!("a finite {key}"), usage));
        }
        values[i] = Some(x);
    }
    keys.iter()
        .zip(values)
        .map(|(k, v)| v.ok_or_else(|| bad(spec, format!("a value for {k} (required)"), usage)))
        .collect()
}

/// A mean for [`Law::with_mean`]: finite and > 0, else an error naming
/// `mean`.
pub fn check_mean(mean: f64) -> Result<f64> {
    if !(mean > 0.0 && mean.is_finite()) {
        return Err(Error::invalid(
            "mean",
            mean,
            "a mean waiting time > 0, finite",
        ));
    }
    Ok(mean)
}

/// The list: `Variant => module::Type`. A new law is one file plus one line.
#[doc(hidden)]
#[macro_export]
macro_rules! clock_laws {
    ($cb:ident) => {
        $crate::$cb! {
            Exp => exp::ExpClock,
            Gamma => gamma::GammaClock,
            Weibull => weibull::WeibullClock,
            Pareto => pareto::ParetoClock,
            Fixed => fixed::FixedClock,
            Table => table::TableClock,
            Hazard => hazard::HazardClock,
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __clock_registry {
    ($($variant:ident => $m:ident :: $ty:ident,)+) => {
        /// A renewal reset clock: any law of the registry (module docs).
        #[derive(Clone, Debug, PartialEq)]
        pub enum Clock {
            $(
                #[doc = concat!("[`", stringify!($ty), "`]")]
                $variant($m::$ty),
            )+
        }

        $(pub use $m::$ty;)+

        $(
            impl From<$m::$ty> for Clock {
                fn from(l: $m::$ty) -> Clock {
                    Clock::$variant(l)
                }
            }
        )+

        impl Clock {
            /// Every kind with its keys, for messages.
            pub fn usage() -> String {
                [$(<$m::$ty as Law>::USAGE,)+].join("; ")
            }

            /// Parse `kind:args`; every error names [`FLAG`].
            pub fn parse(spec: &str) -> Result<Clock> {
                let trimmed = spec.trim();
                let (kind, args) = trimmed.split_once(':').unwrap_or((trimmed, ""));
                $(
                    if kind == <$m::$ty as Law>::KIND {
                        return Ok(Clock::$variant(<$m::$ty as Law>::parse(args, spec)?));
                    }
                )+
                Err(Error::invalid(
                    FLAG,
                    spec,
                    format!("a kind of: {}", Clock::usage()),
                ))
            }

            fn kind_of(&self) -> &'static str {
                match self { $(Clock::$variant(_) => <$m::$ty as Law>::KIND,)+ }
            }
        }

        /// `with_law!(clock, |l| expr)`: `expr` with `l` bound to the law's
        /// own type.
        macro_rules! with_law {
            ($clock:expr, |$l:ident| $body:expr) => {
                match $clock {
                    $(Clock::$variant(ref $l) => $body,)+
                }
            };
        }
    };
}

clock_laws!(__clock_registry);

impl Clock {
    /// The kind (`gamma`).
    pub fn kind(&self) -> &'static str {
        self.kind_of()
    }
    /// The canonical spec.
    pub fn spec(&self) -> String {
        with_law!(self, |l| l.spec())
    }
    /// One waiting time.
    #[inline]
    pub fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        with_law!(self, |l| l.draw(rng))
    }
    /// The next reset time when the clock restarts at `free`.
    #[inline]
    pub fn next_after<R: Rng + ?Sized>(&self, free: f64, rng: &mut R) -> f64 {
        with_law!(self, |l| l.next_after(free, rng))
    }
    /// W(t).
    pub fn survival(&self, t: f64) -> f64 {
        with_law!(self, |l| l.survival(t))
    }
    /// F(t).
    pub fn cdf(&self, t: f64) -> f64 {
        with_law!(self, |l| l.cdf(t))
    }
    /// rho(t), where it exists.
    pub fn density(&self, t: f64) -> Option<f64> {
        with_law!(self, |l| l.density(t))
    }
    /// E(R) (∞ when infinite).
    pub fn mean(&self) -> f64 {
        with_law!(self, |l| l.mean())
    }
    /// The same shape with mean `mean`.
    pub fn with_mean(&self, mean: f64) -> Result<Clock> {
        with_law!(self, |l| l.with_mean(mean).map(Clock::from))
    }
    /// ∫_t^∞ W.
    pub fn tail_integral(&self, t: f64) -> f64 {
        with_law!(self, |l| l.tail_integral(t))
    }
    /// ∫_a^b W.
    pub fn survival_integral(&self, a: f64, b: f64) -> f64 {
        with_law!(self, |l| l.survival_integral(a, b))
    }
    /// ∫_a^b W(s) (s - a) ds.
    pub fn survival_moment(&self, a: f64, b: f64) -> f64 {
        with_law!(self, |l| l.survival_moment(a, b))
    }
    /// The longest possible waiting time (∞ for an unbounded law).
    pub fn support_end(&self) -> f64 {
        with_law!(self, |l| l.support_end())
    }
    /// [`Law::renewal_weights`].
    pub fn renewal_weights(&self, t_max: f64, steps: usize) -> (Vec<f64>, Vec<f64>, f64) {
        with_law!(self, |l| l.renewal_weights(t_max, steps))
    }
    /// The smallest t with W(t) ≤ tail.
    pub fn horizon(&self, tail: f64) -> f64 {
        with_law!(self, |l| l.horizon(tail))
    }
}

impl std::str::FromStr for Clock {
    type Err = Error;
    fn from_str(s: &str) -> Result<Clock> {
        Clock::parse(s)
    }
}

impl fmt::Display for Clock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.spec())
    }
}

impl serde::Serialize for Clock {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.spec())
    }
}

impl<'de> serde::Deserialize<'de> for Clock {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Clock, D::Error> {
        let s = String::deserialize(d)?;
        Clock::parse(&s).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_round_trip() {
        for s in [
            "exp:rate=2",
            "gamma:k=0.5,theta=3",
            "weibull:k=1.5,scale=0.7",
            "pareto:alpha=2.5,scale=0.1",
            "fixed:t=1.25",
            "table:0:1;0.5:0.25;2:0",
            "hazard:2*a",
        ] {
            let c = Clock::parse(s).unwrap();
            assert_eq!(c.spec(), s);
            assert_eq!(Clock::parse(&c.spec()).unwrap(), c);
        }
        let e = Clock::parse("poisson:rate=1").unwrap_err().to_string();
        assert!(e.starts_with("invalid reset_clock"), "{e}");
    }
}
