//! `hazard:EXPR`: an age-dependent reset rate r(a), written as an
//! expression in the age a since the last reset (the expression engine of
//! the `expr:` drag law: `hazard:2*a`, `hazard:0.5/sqrt(a)`,
//! `hazard:1+sin(a)^2`). W(t) = exp(-H(t)), H(t) = ∫_0^t r(a) da.
//!
//! At construction H is tabulated on panels [a_i, a_{i+1}] that start at
//! width 1e-6, double after each accepted panel and halve until the G7/K15
//! error of ∫ r over the panel is below 1e-13 (absolute, in units of H), up
//! to H ≥ [`H_END`] (W < 2e-22). Refused, each naming `reset_clock`: r < 0
//! or not finite at a quadrature node (a negative hazard is no rate), and
//! H below [`H_END`] at a = [`A_MAX`] (the cumulative hazard does not
//! diverge, or too slowly to tabulate: the reset may never come). Past the
//! last panel r is taken constant at its last value (W < 2e-22 there).
//!
//! Draws invert the cumulative hazard: R solves H(R) = E with E ~ Exp(1)
//! (`rand_distr::Exp1`): the panel from the table, then safeguarded Newton
//! (H' = r) and bisection inside it, H between nodes by one K15 panel,
//! until the step is below 4 ulp of R: R is exact to the rounding of H,
//! about 1e-13 relative in W.
//!
//! The compiled expression and its table are shared by the copies of the
//! law and freed with the last (`model::shared`).

use super::{bad, check_mean, Law};
use crate::error::{Error, Result};
use crate::model::drag::expr::{check_names, check_size, on_big_stack, plain_numbers};
use crate::model::drag::spec::number;
use crate::model::shared::Shared;
use crate::numerics::quad::gk15;
use exmex::prelude::*;
use rand::Rng;
use std::cell::Cell;
use std::sync::Arc;

/// The cumulative hazard the table reaches.
pub const H_END: f64 = 50.0;
/// The largest age the table extends to.
pub const A_MAX: f64 = 1e15;
const USAGE: &str = "hazard:EXPR (a rate r(a) >= 0 in the age a, whose integral diverges)";

/// An age-dependent reset rate.
#[derive(Clone, Debug)]
pub struct HazardClock {
    law: Arc<Compiled>,
}

struct Compiled {
    text: String,
    r: FlatEx<f64>,
    /// Panel edges a_0 = 0 < a_1 < ...
    edges: Vec<f64>,
    /// H(a_i).
    cum: Vec<f64>,
    /// ∫ W over panel i.
    w_int: Vec<f64>,
    /// r at the last edge (the rate beyond it).
    r_end: f64,
    /// E(R).
    mean: f64,
}

impl std::fmt::Debug for Compiled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "hazard({:?})", self.text)
    }
}

/// The hazard laws in use, by their text.
static LAWS: Shared<Compiled> = Shared::new();

impl PartialEq for HazardClock {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.law, &other.law)
    }
}

impl HazardClock {
    /// The law of an expression in a (module docs).
    pub fn new(text: &str) -> Result<Self> {
        let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
        let law = LAWS.get_or_compile(&text, || compile(&text))?;
        Ok(HazardClock { law })
    }

    /// The expression text.
    pub fn text(&self) -> &str {
        &self.law.text
    }

    /// r(a) (NaN where undefined).
    #[inline]
    pub fn rate(&self, a: f64) -> f64 {
        eval(&self.law.r, a)
    }

    /// H(t) = ∫_0^t r.
    pub fn cumulative(&self, t: f64) -> f64 {
        self.law.cumulative(t)
    }
}

impl Compiled {
    fn rate(&self, a: f64) -> f64 {
        eval(&self.r, a)
    }

    /// The panel i with a_i ≤ t < a_{i+1} (None past the table).
    fn panel(&self, t: f64) -> Option<usize> {
        let e = &self.edges;
        if t >= e[e.len() - 1] {
            return None;
        }
        Some(e.partition_point(|&x| x <= t).saturating_sub(1))
    }

    /// H(t).
    fn cumulative(&self, t: f64) -> f64 {
        if t <= 0.0 {
            return 0.0;
        }
        match self.panel(t) {
            Some(i) => self.cum[i] + gk15(&|a| self.rate(a), self.edges[i], t).kronrod,
            None => {
                let n = self.edges.len() - 1;
                self.cum[n] + self.r_end * (t - self.edges[n])
            }
        }
    }

    /// ∫_a^b e^{-H} on one panel (K15).
    fn w_integral(&self, a: f64, b: f64) -> f64 {
        gk15(&|s| (-self.cumulative(s)).exp(), a, b).kronrod
    }

    /// The age with H = e (module docs).
    fn invert(&self, e: f64) -> f64 {
        let n = self.edges.len() - 1;
        if e >= self.cum[n] {
            return self.edges[n] + (e - self.cum[n]) / self.r_end;
        }
        let i = self
            .cum
            .partition_point(|&h| h <= e)
            .saturating_sub(1)
            .min(n - 1);
        let (mut lo, mut hi) = (self.edges[i], self.edges[i + 1]);
        let mut t = 0.5 * (lo + hi);
        for _ in 0..200 {
            let f = self.cum[i] + gk15(&|a| self.rate(a), self.edges[i], t).kronrod - e;
            if f > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let r = self.rate(t);
            let newton = t - f / r;
            let next = if r > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            let tol = 4.0 * f64::EPSILON * t.abs();
            let done = (next - t).abs() <= tol || hi - lo <= 4.0 * f64::EPSILON * hi;
            t = next;
            if done {
                break;
            }
        }
        t
    }
}

fn err(text: &str, what: impl std::fmt::Display) -> Error {
    bad(&format!("hazard:{text}"), what, USAGE)
}

/// Parse, then tabulate H (module docs).
fn compile(text: &str) -> Result<Compiled> {
    if text.is_empty() {
        return Err(err(text, "an expression"));
    }
    let e = |t: &str, w: String| err(t, w);
    check_size(text, &e)?;
    check_names(text, "a", &e)?;
    let plain = plain_numbers(text);
    let r = on_big_stack(
        || {
            let r = exmex::parse::<f64>(&plain)
                .map_err(|x| err(text, crate::model::drag::expr::parse_error(&x)))?;
            if r.var_names().len() > 1 || r.var_names().iter().any(|v| v != "a") {
                return Err(err(text, "an expression in a"));
            }
            Ok(r)
        },
        || err(text, "an expression that compiles"),
    )?;
    let mut law = Compiled {
        text: text.to_string(),
        r,
        edges: vec![0.0],
        cum: vec![0.0],
        w_int: Vec::new(),
        r_end: 0.0,
        mean: 0.0,
    };
    tabulate(&mut law)?;
    Ok(law)
}

/// r at `a`, from an expression that may be constant (no variable).
fn eval(r: &FlatEx<f64>, a: f64) -> f64 {
    if r.var_names().is_empty() {
        r.eval(&[]).unwrap_or(f64::NAN)
    } else {
        r.eval(&[a]).unwrap_or(f64::NAN)
    }
}

/// The panels of H up to [`H_END`] (module docs), then ∫ W per panel.
fn tabulate(law: &mut Compiled) -> Result<()> {
    let text = law.text.clone();
    let worst = Cell::new(None::<(f64, f64)>);
    let r = |a: f64| {
        let v = eval(&law.r, a);
        if !(v >= 0.0 && v.is_finite()) && worst.get().is_none() {
            worst.set(Some((a, v)));
        }
        v
    };
    let (mut t, mut h, mut big_h) = (0.0_f64, 1e-6_f64, 0.0_f64);
    let (mut edges, mut cum) = (vec![0.0], vec![0.0]);
    let mut tries = 0usize;
    while big_h < H_END {
        tries += 1;
        if t > A_MAX || tries > 200_000 {
            return Err(err(
                &text,
                format!(
                    "a cumulative hazard that diverges: H(a) = {big_h:.6} at a = {t:e} has not \
                     reached {H_END} (the reset may never come)"
                ),
            ));
        }
        let q = gk15(&r, t, t + h);
        if let Some((a, v)) = worst.get() {
            return Err(err(&text, format!("r(a) >= 0 and finite (r({a}) = {v})")));
        }
        if q.error <= 1e-13 {
            t += h;
            big_h += q.kronrod;
            edges.push(t);
            cum.push(big_h);
            h *= 2.0;
        } else {
            h *= 0.5;
            if !(h > t * 1e-15 && h > 1e-300) {
                return Err(err(&text, format!("a rate integrable near a = {t}")));
            }
        }
    }
    let r_end = eval(&law.r, t);
    if !(r_end > 0.0 && r_end.is_finite()) {
        return Err(err(
            &text,
            format!("r > 0 at a = {t} (where H reaches {H_END})"),
        ));
    }
    law.edges = edges;
    law.cum = cum;
    law.r_end = r_end;
    let w_int: Vec<f64> = (0..law.edges.len() - 1)
        .map(|i| law.w_integral(law.edges[i], law.edges[i + 1]))
        .collect();
    let n = law.edges.len() - 1;
    law.mean = w_int.iter().sum::<f64>() + (-law.cum[n]).exp() / r_end;
    law.w_int = w_int;
    Ok(())
}

impl Law for HazardClock {
    const KIND: &'static str = "hazard";
    const USAGE: &'static str = USAGE;
    fn parse(args: &str, _spec: &str) -> Result<Self> {
        HazardClock::new(args)
    }
    fn spec(&self) -> String {
        format!("hazard:{}", self.law.text)
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.law.invert(rng.sample::<f64, _>(rand_distr::Exp1))
    }
    fn survival(&self, t: f64) -> f64 {
        (-self.law.cumulative(t)).exp()
    }
    fn density(&self, t: f64) -> Option<f64> {
        Some(if t < 0.0 {
            0.0
        } else {
            self.rate(t) * self.survival(t)
        })
    }
    fn mean(&self) -> f64 {
        self.law.mean
    }
    /// r_c(a) = r(a/c)/c with c = mean / E(R): the text with every a
    /// written (a/c), divided by c.
    fn with_mean(&self, mean: f64) -> Result<Self> {
        let c = check_mean(mean)? / self.law.mean;
        let scaled = substitute(&self.law.text, &format!("(a/{})", number(c)));
        HazardClock::new(&format!("({scaled})/{}", number(c)))
    }
    fn tail_integral(&self, t: f64) -> f64 {
        let l = &self.law.clone();
        let n = l.edges.len() - 1;
        let beyond = (-l.cum[n]).exp() / l.r_end;
        match l.panel(t.max(0.0)) {
            None => self.survival(t) / l.r_end,
            Some(i) => {
                l.w_integral(t.max(0.0), l.edges[i + 1])
                    + l.w_int[i + 1..].iter().sum::<f64>()
                    + beyond
            }
        }
    }
}

/// `text` with every name `a` (not part of a longer name or a number)
/// replaced by `with`.
fn substitute(text: &str, with: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let in_number = i > 0 && (chars[i - 1].is_ascii_digit() || chars[i - 1] == '.');
        if (c.is_alphabetic() || c == '_') && !in_number {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let name: String = chars[start..i].iter().collect();
            out.push_str(if name == "a" { with } else { &name });
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}
