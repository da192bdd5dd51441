//! Any drag law written as an expression in v: `expr:v + 0.3*v^3`,
//! `expr:sinh(v)`, `expr:tan(v)`.
//!
//! The expression is parsed by the `exmex` crate (operators `+ - * / ^`,
//! the functions sin, cos, tan, asin, acos, atan, sinh, cosh, tanh, asinh,
//! acosh, atanh, exp, ln, log, log2, log10, sqrt; the
//! constants PI, E, TAU) and differentiated symbolically by it, so g' is
//! exact (abs, signum, floor, min, max have no symbolic derivative in
//! exmex and are refused). Checks, each one line naming `--drag` (or `--sigma`):
//!
//! - when parsed ([`Expr::parse`]): its size (at most 4000 characters,
//!   200 operations, parentheses 50 deep), the syntax, the one variable v,
//!   the function names, a derivative in closed form, and oddness
//!   (g(-v) = -g(v) to 1e-10 relative at 81 points from 1e-4 to 1e4, where
//!   g is finite; g(0) = 0);
//! - for a given Sigma ([`Drag::admissible`], called by
//!   [`crate::Params::new`]): v_u with g(v_u) = Sigma exists (bracketed by
//!   doubling, then a safeguarded Newton root of [`crate::numerics::root`];
//!   if g stays below Sigma for every v the error names `--sigma` and the
//!   supremum of g), g is finite and strictly increasing on [0, v_u]
//!   (g' >= 0 and g rising at 4097 points, where the first violation is
//!   named: g' may vanish at an isolated point, as v^3 at 0), and g
//!   reaches Sigma continuously.
//!
//! The law runs through the generic path: [`TabulatedFlow`] and the
//! potential table, so the exact sampler evaluates the expression only
//! while it builds its tables; the Euler scheme evaluates it every step.
//!
//! A parsed expression is shared while in use (`model::shared`): [`Expr`]
//! holds an `Arc` of it, so copies of a [`super::DragLaw`] and of
//! [`crate::Params`] share one compilation and one inverse cache, and the
//! law is freed with its last copy. Two specs with the same canonical text
//! (whitespace runs collapsed to one space) parsed while one lives share
//! one law, which is what [`Expr`]'s equality compares.

use super::spec::SpecLaw;
use super::{Drag, TabulatedFlow};
use crate::error::{Error, Result};
use crate::model::shared::Shared;
use crate::numerics::root;
use exmex::prelude::*;
use std::fmt;
use std::sync::{Arc, Mutex};

/// The spec prefix: `expr:...`.
const NAME: &str = "expr";

/// A drag law g(v) given by an expression in v (see the module docs).
#[derive(Clone)]
pub struct Expr {
    law: Arc<Compiled>,
    /// (|s|, |v*|) of the flow this copy was made for ([`Drag::flow`]):
    /// [`Drag::inverse`] at ±|s| is then a lookup (the tabulated flow asks
    /// for v* at every drift evaluation while it builds its tables).
    pin: (f64, f64),
}

/// A parsed, checked expression and its symbolic derivative.
struct Compiled {
    /// The canonical expression text (no `expr:` prefix).
    text: String,
    /// `expr:` and the text.
    spec: String,
    g: FlatEx<f64>,
    dg: FlatEx<f64>,
    /// The last root of g(v) = f computed for an unpinned copy, (f, v):
    /// methods that hold the law itself (the r = 0 density asks for
    /// v* = g⁻¹(Sigma) at every point) then solve once.
    last_inverse: Mutex<(f64, f64)>,
    /// [`Drag::evaluation_weight`].
    weight: f64,
}

impl Expr {
    /// The law of an expression in v (the part after `expr:`), checked as
    /// in the module docs; errors name `drag` and the violation.
    pub fn parse(text: &str) -> Result<Expr> {
        let text = canonical(text);
        LAWS.get_or_compile(&text, || compile(&text)).map(Expr::of)
    }

    fn of(law: Arc<Compiled>) -> Expr {
        Expr {
            law,
            pin: (f64::NAN, f64::NAN),
        }
    }

    /// The expression text (canonical form, without `expr:`).
    pub fn text(&self) -> &str {
        &self.law.text
    }

    /// g(v) and g'(v), NaN where undefined.
    #[inline]
    fn eval(e: &FlatEx<f64>, v: f64) -> f64 {
        e.eval(&[v]).unwrap_or(f64::NAN)
    }
}

/// The expression laws in use, by canonical text.
static LAWS: Shared<Compiled> = Shared::new();

impl PartialEq for Expr {
    /// The same expression (shared: the same canonical text).
    fn eq(&self, other: &Expr) -> bool {
        Arc::ptr_eq(&self.law, &other.law)
    }
}

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Expr({:?})", self.law.text)
    }
}

/// Whitespace runs collapsed to one space, trimmed (`sin 4` stays `sin 4`:
/// exmex reads it as sin(4), while `sin4` would be a variable).
fn canonical(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The error of a bad expression: names `drag`, the spec and what is wrong.
fn bad(text: &str, what: impl fmt::Display) -> Error {
    Error::invalid(
        "drag",
        format!("{NAME}:{text}"),
        format!("an odd, increasing g(v) ({what})"),
    )
}

/// The functions with a symbolic derivative in exmex (abs, signum, floor,
/// min, max and the like have none, so they are not accepted).
const FUNCTIONS: [&str; 18] = [
    "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh",
    "exp", "ln", "log", "log2", "log10", "sqrt",
];

/// The constants exmex knows.
const CONSTANTS: [&str; 6] = ["PI", "π", "E", "e", "TAU", "τ"];

/// The accepted function and constant names, for messages.
fn known_names() -> String {
    format!(
        "{}; constants {}",
        FUNCTIONS.join(", "),
        CONSTANTS.join(", ")
    )
}

/// A parse error of exmex in a message: its first clause, cut as an echo
/// is ([`crate::error::echo`]), so the message stays one short line.
pub(crate) fn parse_error(e: &impl std::fmt::Display) -> String {
    let text = e.to_string();
    let first = text.split([',', ';']).next().unwrap_or_default();
    format!("parse error: {}", crate::error::echo(first.trim()))
}

/// The error builder of an expression's checks: (text, what is wrong).
pub(crate) type Bad<'a> = &'a dyn Fn(&str, String) -> Error;

/// Every name in the text is `var` or a known function or constant: the
/// first other one is an error naming it (exmex would take an unknown name
/// for a second variable, or fail with a message about parentheses).
pub(crate) fn check_names(text: &str, var: &str, bad: Bad) -> Result<()> {
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_ascii_digit() || c == '.' {
            i = number_end(&chars, i).1;
        } else if c.is_alphabetic() || c == '_' || c == '{' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let name: String = chars[start..i.max(start + 1)].iter().collect();
            let name = name.as_str();
            if name != var && !FUNCTIONS.contains(&name) && !CONSTANTS.contains(&name) {
                return Err(bad(
                    text,
                    format!("unknown name '{name}' (the variable is {var}; functions: --help)"),
                ));
            }
            i = i.max(start + 1);
        } else {
            i += 1;
        }
    }
    Ok(())
}

/// The largest expression accepted: characters, operations (operators and
/// function calls) and parenthesis depth. exmex parses and differentiates
/// recursively; these bounds keep that recursion far inside the stack of
/// the thread that compiles (measured: `v+v+...+v` overflowed an 8 MiB
/// stack between 60 and 100 terms, so [`COMPILE_STACK`] holds about 30
/// times the largest accepted expression).
const MAX_CHARS: usize = 4000;
const MAX_OPERATIONS: usize = 200;
const MAX_DEPTH: usize = 50;
/// The stack of the thread that parses and differentiates (virtual memory,
/// committed only as used).
const COMPILE_STACK: usize = 256 << 20;

/// The size bounds above, before anything is parsed (the message shows
/// the start of an expression over them).
pub(crate) fn check_size(text: &str, bad: Bad) -> Result<()> {
    let shown = match text.char_indices().nth(40) {
        Some((i, _)) => format!("{}...", &text[..i]),
        None => text.to_string(),
    };
    if text.len() > MAX_CHARS {
        let n = text.len();
        return Err(bad(&shown, format!("{n} characters, at most {MAX_CHARS}")));
    }
    // Operators, and function calls: a '(' right after a name.
    let chars: Vec<char> = text.chars().collect();
    let calls = chars
        .windows(2)
        .filter(|w| w[1] == '(' && w[0].is_alphanumeric())
        .count();
    let ops = chars.iter().filter(|c| "+-*/^".contains(**c)).count() + calls;
    if ops > MAX_OPERATIONS {
        return Err(bad(
            &shown,
            format!("{ops} operations, at most {MAX_OPERATIONS}"),
        ));
    }
    let mut depth = 0usize;
    let mut deepest = 0usize;
    for c in text.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            _ => {}
        }
        deepest = deepest.max(depth);
    }
    if deepest > MAX_DEPTH {
        return Err(bad(
            &shown,
            format!("parentheses nested {deepest} deep, at most {MAX_DEPTH}"),
        ));
    }
    Ok(())
}

/// The number starting at `chars[i]`, with its exponent (`1e-3`, `2.5E+4`):
/// (the end of its mantissa, the end of the number).
fn number_end(chars: &[char], mut i: usize) -> (usize, usize) {
    while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
        i += 1;
    }
    let mantissa_end = i;
    if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
        let sign = i + 1 < chars.len() && matches!(chars[i + 1], '+' | '-');
        let digit_at = if sign { i + 2 } else { i + 1 };
        if digit_at < chars.len() && chars[digit_at].is_ascii_digit() {
            i = digit_at;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
        }
    }
    (mantissa_end, i)
}

/// The text with every number in exponent notation (`1e-3`, `2.5E+4`),
/// which exmex does not read, written out as a plain decimal of the same
/// double (`0.001`, `25000`; Rust prints the shortest digits that round-trip
/// and never an exponent).
pub(crate) fn plain_numbers(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < chars.len() {
        let starts_number = (chars[i].is_ascii_digit() || chars[i] == '.')
            && (i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '_'));
        if !starts_number {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let start = i;
        let (mantissa_end, end) = number_end(&chars, i);
        i = end;
        let token: String = chars[start..i].iter().collect();
        match (i > mantissa_end, token.parse::<f64>()) {
            (true, Ok(x)) if x.is_finite() => out.push_str(&format!("{x}")),
            _ => out.push_str(&token),
        }
    }
    out
}

/// `work` on a thread with a stack of [`COMPILE_STACK`] (exmex parses
/// recursively; the caller's may be a small worker stack), or here when no
/// thread is to be had (the size bounds still hold).
pub(crate) fn on_big_stack<T: Send>(
    work: impl Fn() -> Result<T> + Sync,
    failed: impl FnOnce() -> Error,
) -> Result<T> {
    std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .stack_size(COMPILE_STACK)
            .spawn_scoped(scope, &work);
        match spawned {
            Ok(handle) => handle.join().unwrap_or_else(|_| Err(failed())),
            Err(_) => work(),
        }
    })
}

/// g and g' parsed and differentiated by exmex, on a thread with a stack
/// of [`COMPILE_STACK`] (the caller's may be a small worker stack).
fn parse_and_differentiate(text: &str) -> Result<(FlatEx<f64>, FlatEx<f64>)> {
    let plain = plain_numbers(text);
    let work = || -> Result<(FlatEx<f64>, FlatEx<f64>)> {
        let g = exmex::parse::<f64>(&plain).map_err(|e| bad(text, parse_error(&e)))?;
        if g.var_names() != ["v".to_string()] {
            return Err(bad(text, "it must depend on v"));
        }
        let dg = g
            .clone()
            .partial(0)
            .map_err(|e| bad(text, format!("no symbolic derivative: {e}")))?;
        Ok((g, dg))
    };
    std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .stack_size(COMPILE_STACK)
            .spawn_scoped(scope, work);
        match spawned {
            Ok(handle) => handle
                .join()
                .unwrap_or_else(|_| Err(bad(text, "the expression could not be compiled"))),
            // No thread to be had: compile here (the size bounds still hold).
            Err(_) => work(),
        }
    })
}

/// Parse, differentiate and check oddness (see the module docs).
fn compile(text: &str) -> Result<Compiled> {
    if text.is_empty() {
        return Err(bad(text, "empty"));
    }
    let err = |t: &str, w: String| bad(t, w);
    check_size(text, &err)?;
    check_names(text, "v", &err)?;
    let (g, dg) = parse_and_differentiate(text)?;
    let chars = g.unparse().len() + dg.unparse().len();
    let law = Compiled {
        weight: (chars as f64 / 40.0).max(1.0),
        text: text.to_string(),
        spec: format!("{NAME}:{text}"),
        g,
        dg,
        last_inverse: Mutex::new((f64::NAN, f64::NAN)),
    };
    check_odd(&law)?;
    Ok(law)
}

/// g(-v) = -g(v) to 1e-10 relative at 0 and 81 points from 1e-4 to 1e4
/// (where both are finite; finite on one side only is not odd).
fn check_odd(law: &Compiled) -> Result<()> {
    let g = |v: f64| Expr::eval(&law.g, v);
    let g0 = g(0.0);
    if g0 != 0.0 {
        return Err(bad(&law.text, format!("not odd: g(0) = {g0}, not 0")));
    }
    for i in 0..=80 {
        let v = 1e-4 * 10f64.powf(i as f64 / 10.0);
        let (gp, gm) = (g(v), g(-v));
        if !gp.is_finite() && !gm.is_finite() {
            continue;
        }
        let tol = 1e-10 * gp.abs().max(gm.abs());
        if !((gp + gm).abs() <= tol) {
            return Err(bad(
                &law.text,
                format!("not odd: g(-{v}) = {gm:e} but -g({v}) = {:e}", -gp),
            ));
        }
    }
    Ok(())
}

impl Drag for Expr {
    type Flow = TabulatedFlow<Expr>;

    fn name(&self) -> &'static str {
        NAME
    }
    #[inline]
    fn force(&self, v: f64) -> f64 {
        Expr::eval(&self.law.g, v)
    }
    /// The symbolic derivative.
    #[inline]
    fn derivative(&self, v: f64) -> f64 {
        Expr::eval(&self.law.dg, v)
    }
    fn flow(&self, s: f64) -> TabulatedFlow<Expr> {
        let a = s.abs();
        let pinned = Expr {
            law: Arc::clone(&self.law),
            pin: (a, increasing_root(self, a)),
        };
        TabulatedFlow::new(pinned, s)
    }
    /// By the length of g and g' as evaluated (measured: a 61-factor
    /// product, g' 11335 characters, costs 14.6 µs per g and g', ~300x a
    /// shipped law; one weight per 40 characters).
    fn evaluation_weight(&self) -> f64 {
        self.law.weight
    }
    /// The same for every expression (the spec carries the formula).
    fn description(&self) -> &'static str {
        "any odd, strictly increasing g written as an expression in v"
    }
    /// The first root of g(v) = |f| from 0 (bracketed by doubling,
    /// narrowed where g stops increasing, then safeguarded Newton), exactly
    /// odd.
    fn inverse(&self, f: f64) -> f64 {
        let a = f.abs();
        if a == self.pin.0 {
            return self.pin.1.copysign(f);
        }
        let cache = &self.law.last_inverse;
        if let Ok(last) = cache.try_lock() {
            if last.0 == a {
                return last.1.copysign(f);
            }
        }
        let root = increasing_root(self, a);
        if let Ok(mut last) = cache.try_lock() {
            *last = (a, root);
        }
        root.copysign(f)
    }
    fn admissible(&self, sigma: f64) -> Result<()> {
        check_interval(self, sigma)
    }
    /// The largest secant slope (Sigma - g(v)) / (v_u - v) over 4096 points
    /// of [v_l, v_u) and its limit g'(v_u), plus 1 % for the slope between
    /// samples.
    fn euler_slope(&self, sigma: f64) -> f64 {
        let vu = self.inverse(sigma);
        let n = 4096;
        let mut m = self.derivative(vu);
        for i in 0..n {
            let v = -vu + 2.0 * vu * i as f64 / n as f64;
            m = m.max((sigma - self.force(v)) / (vu - v));
        }
        1.01 * m
    }
}

/// The bracket of the first root of g(v) = a ≥ 0 on v > 0: doubling from
/// 2^-16 while g stays finite, below a and increasing; None if g stays
/// below a (and increasing) up to the largest double. A bracket that ends
/// where g stops increasing or is not finite is narrowed to the first of
/// 64 sub-intervals that does (repeatedly), so the root found is the first
/// crossing, not one past a non-monotone stretch. Returns (lo, hi, g(lo)).
fn bracket(d: &Expr, a: f64) -> Option<(f64, f64, f64)> {
    let (mut lo, mut g_lo) = (0.0f64, 0.0f64);
    let mut hi = 1.0 / 65536.0;
    loop {
        let g = d.force(hi);
        if g >= a {
            return Some((lo, hi, g_lo));
        }
        if !(g.is_finite() && g >= g_lo) {
            return Some(narrow(d, a, lo, g_lo, hi));
        }
        (lo, g_lo) = (hi, g);
        hi *= 2.0;
        if !hi.is_finite() {
            return None;
        }
    }
}

/// The first of 64 sub-intervals of [lo, hi] whose right end has g ≥ a or
/// g not finite or decreasing (g(lo) = g_lo < a), narrowed 4 times.
fn narrow(d: &Expr, a: f64, mut lo: f64, mut g_lo: f64, mut hi: f64) -> (f64, f64, f64) {
    for _ in 0..4 {
        let (base, h) = (lo, (hi - lo) / 64.0);
        for i in 1..=64 {
            let x = if i == 64 { hi } else { base + h * i as f64 };
            let g = d.force(x);
            if g >= a || !(g.is_finite() && g >= g_lo) {
                hi = x;
                break;
            }
            (lo, g_lo) = (x, g);
        }
    }
    (lo, hi, g_lo)
}

/// The first root of g(v) = a ≥ 0 on v ≥ 0 ([`bracket`], then the
/// safeguarded Newton solver on it, bisection if that fails); +∞ if g stays
/// below a.
fn increasing_root(d: &Expr, a: f64) -> f64 {
    if !(a > 0.0) {
        return if a == 0.0 { 0.0 } else { f64::NAN };
    }
    let Some((lo, hi, g_lo)) = bracket(d, a) else {
        return f64::INFINITY;
    };
    // H = g - a, and +1 past the end of the increasing branch (g not finite
    // or below g(lo): tan(v) past its pole). There, and where g' is not
    // finite and positive (g' = ∞ at v = 0 of a power-like law), the slope
    // is NaN, which makes the solver bisect instead of stepping.
    let h = |x: f64| {
        let g = d.force(x);
        let g1 = d.derivative(x);
        if !(g.is_finite() && g >= g_lo) {
            return (1.0, f64::NAN, 0.0);
        }
        (
            g - a,
            if g1 > 0.0 && g1.is_finite() {
                g1
            } else {
                f64::NAN
            },
            0.0,
        )
    };
    root::solve_increasing(&h, lo, hi, 0.5 * (lo + hi), 1e-15, 0.0)
        .unwrap_or_else(|_| bisect(d, a, (lo, hi), g_lo))
}

/// g(v) = a on [lo, hi] by bisection to adjacent doubles (past the end of
/// the branch, g < g_lo or not finite, counts as above).
fn bisect(d: &Expr, a: f64, (mut lo, mut hi): (f64, f64), g_lo: f64) -> f64 {
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return lo;
        }
        let g = d.force(mid);
        if g >= a || !(g.is_finite() && g >= g_lo) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
}

/// [`Drag::admissible`] for an expression law (see the module docs).
fn check_interval(d: &Expr, sigma: f64) -> Result<()> {
    let vu = increasing_root(d, sigma);
    if vu.is_infinite() {
        return Err(bounded(d, sigma));
    }
    const N: usize = 4096;
    let mut g_prev = 0.0;
    for i in 0..=N {
        let v = vu * i as f64 / N as f64;
        let (g, g1) = (d.force(v), d.derivative(v));
        if !g.is_finite() || g1.is_nan() {
            return Err(bad(
                d.text(),
                format!("g(v) = {g}, g'(v) = {g1} at v = {v} inside the velocity interval of sigma = {sigma}"),
            ));
        }
        // Strictly increasing: g' >= 0 everywhere and g rising from sample
        // to sample, so g' may vanish at isolated points (v^3 at v = 0) but
        // not on an interval.
        if !(g1 >= 0.0) {
            return Err(bad(
                d.text(),
                format!("g must increase strictly from 0 up to g(v_u) = sigma = {sigma}: g' < 0 at v = {v} (g' = {g1:e})"),
            ));
        }
        if i > 0 && !(g > g_prev) {
            return Err(bad(
                d.text(),
                format!("g must increase strictly from 0 up to g(v_u) = sigma = {sigma}: g does not rise from v = {} to {v}", vu * (i - 1) as f64 / N as f64),
            ));
        }
        g_prev = g;
    }
    let g_vu = d.force(vu);
    if !((g_vu - sigma).abs() <= 1e-9 * sigma) {
        return Err(bad(
            d.text(),
            format!("g stops short of sigma = {sigma} at v = {vu} (g = {g_vu}): it jumps or stops increasing there"),
        ));
    }
    Ok(())
}

/// The error of a Sigma the law never reaches: names `sigma` and the
/// supremum of g (its largest value at the doubling points, where it
/// stays increasing up to the largest double).
fn bounded(d: &Expr, sigma: f64) -> Error {
    let mut sup = 0.0f64;
    let mut v = 1.0f64 / 65536.0;
    while v.is_finite() {
        sup = sup.max(d.force(v));
        v *= 2.0;
    }
    Error::invalid(
        "sigma",
        sigma,
        format!(
            "0 < sigma < {sup} for {} drag (g stays below sigma for every v; its supremum, estimated numerically, is {sup})",
            d.law.spec
        ),
    )
}

impl SpecLaw for Expr {
    fn example() -> Self {
        Expr::parse("v + 0.3*v^3").expect("the example expression is a valid law")
    }
    fn parse(spec: &str, args: Option<&str>) -> Result<Self> {
        match args {
            Some(text) => Expr::parse(text),
            None => Err(Error::invalid(
                "drag",
                spec,
                "an expression in v after 'expr:' (expr:v + 0.3*v^3)",
            )),
        }
    }
    fn write(&self) -> String {
        self.law.spec.clone()
    }
    fn usage() -> String {
        format!("{NAME}:EXPRESSION")
    }
    fn keys_help() -> String {
        format!(
            "EXPRESSION: odd and increasing in v, with + - * / ^ and the functions {}",
            known_names()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(text: &str) -> Expr {
        Expr::parse(text).unwrap()
    }

    /// The inverse of `tan(v)` is atan (the bracket from doubling ends past
    /// the pole, where tan turns negative, and is narrowed to the branch
    /// through 0), exactly odd.
    #[test]
    fn inverse_finds_the_branch_through_zero() {
        let d = law("tan(v)");
        for f in [1e-9, 1e-3, 0.5, 3.0, 1e3, 1e8] {
            let v = d.inverse(f);
            assert!((v - f.atan()).abs() <= 4e-16 * f.atan(), "f={f}: {v}");
            assert_eq!(d.inverse(-f), -v);
        }
        // v - v^3 rises to 2/(3√3) = 0.3849 at 1/√3 and falls after: the
        // root of g = 0.38 is the first crossing, below 1/√3.
        let d = law("v - v^3");
        let v = d.inverse(0.38);
        assert!(
            v < 3f64.sqrt().recip() && (d.force(v) - 0.38).abs() < 1e-15,
            "{v}"
        );
        assert!(d.inverse(0.5).is_finite() && d.admissible(0.5).is_err());
        assert!(d.admissible(0.38).is_ok());
    }

    /// One shared law per canonical text while a copy lives; the flow's
    /// pinned fixed point is the plain inverse.
    #[test]
    fn shared_by_canonical_text() {
        let (a, b) = (law("v +  v^3"), law(" v + v^3 "));
        assert!(Arc::ptr_eq(&a.law, &b.law) && a == b);
        assert_ne!(law("v+v^3"), a);
        let pinned = Expr {
            law: Arc::clone(&a.law),
            pin: (2.0, increasing_root(&a, 2.0)),
        };
        assert_eq!(pinned.inverse(-2.0), a.inverse(-2.0));
        assert_eq!(pinned, a);
    }
}
