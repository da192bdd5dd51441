//! `table:T0:W0;T1:W1;...`: a tabulated survival W(t) = P(R > t), linear
//! between the points (a piecewise-constant density), so the law is exact
//! for what it says: the CDF, the mean (trapezoid sums) and the draws
//! (inversion of the linear pieces at a uniform U: W(R) = U) hold for the
//! interpolated W to rounding.
//!
//! The points: T0 = 0 with W0 = 1, T strictly increasing and finite, W in
//! [0, 1] and nonincreasing, the last W = 0 (the reset comes by the last
//! T; a tail is written as points), at most [`MAX_POINTS`]. The app layer
//! reads them from a CSV file (`table:file=PATH`) and writes this inline
//! spelling into every provenance file, so a run is reproducible from its
//! provenance alone. A table is shared by the copies of its law and freed
//! with the last (`model::shared`).

use super::{bad, check_mean, Law};
use crate::error::Result;
use crate::model::drag::spec::number;
use crate::model::shared::Shared;
use rand::Rng;
use std::sync::Arc;

/// The most points a table takes.
pub const MAX_POINTS: usize = 100_000;

/// A tabulated survival function.
#[derive(Clone, Debug)]
pub struct TableClock {
    data: Arc<Data>,
}

#[derive(Debug)]
struct Data {
    spec: String,
    t: Vec<f64>,
    w: Vec<f64>,
    /// ∫_0^{t_i} W.
    cum: Vec<f64>,
}

/// The tables in use, by their spec.
static TABLES: Shared<Data> = Shared::new();

impl PartialEq for TableClock {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.data, &other.data)
    }
}

impl TableClock {
    /// The law of validated points (t_i, W_i) (module docs); errors name
    /// `reset_clock`.
    pub fn new(t: Vec<f64>, w: Vec<f64>) -> Result<Self> {
        let spec = write(&t, &w);
        check(&t, &w, &spec)?;
        let data = TABLES.get_or_compile(&spec, || {
            let mut cum = vec![0.0; t.len()];
            for i in 1..t.len() {
                cum[i] = cum[i - 1] + 0.5 * (w[i - 1] + w[i]) * (t[i] - t[i - 1]);
            }
            Ok(Data {
                spec: spec.clone(),
                t,
                w,
                cum,
            })
        })?;
        Ok(TableClock { data })
    }

    /// The points (t_i, W_i).
    pub fn points(&self) -> (&[f64], &[f64]) {
        (&self.data.t, &self.data.w)
    }

    /// The segment i with t_i ≤ t < t_{i+1} (t inside the table).
    fn segment(&self, t: f64) -> usize {
        let ts = &self.data.t;
        ts.partition_point(|&x| x <= t)
            .saturating_sub(1)
            .min(ts.len() - 2)
    }

    /// ∫_0^t W.
    fn antiderivative(&self, t: f64) -> f64 {
        let d = &self.data.clone();
        let last = d.t.len() - 1;
        if t >= d.t[last] {
            return d.cum[last];
        }
        if t <= 0.0 {
            return 0.0;
        }
        let i = self.segment(t);
        d.cum[i] + 0.5 * (d.w[i] + self.survival(t)) * (t - d.t[i])
    }
}

const USAGE: &str = "table:T0:W0;T1:W1;... (T0 = 0, W0 = 1, T increasing, W nonincreasing \
                     in [0, 1], last W = 0; or table:file=PATH of 't,W' lines)";

fn write(t: &[f64], w: &[f64]) -> String {
    let pts: Vec<String> = t
        .iter()
        .zip(w)
        .map(|(a, b)| format!("{}:{}", number(*a), number(*b)))
        .collect();
    format!("table:{}", pts.join(";"))
}

fn check(t: &[f64], w: &[f64], spec: &str) -> Result<()> {
    let n = t.len();
    if n != w.len() || !(2..=MAX_POINTS).contains(&n) {
        return Err(bad(spec, format!("2 to {MAX_POINTS} points"), USAGE));
    }
    if t[0] != 0.0 || w[0] != 1.0 {
        return Err(bad(spec, "a first point 0:1 (W(0) = 1)", USAGE));
    }
    for i in 1..n {
        if !(t[i] > t[i - 1] && t[i].is_finite()) {
            return Err(bad(
                spec,
                format!("increasing finite times (at point {i})"),
                USAGE,
            ));
        }
        if !(w[i] <= w[i - 1] && w[i] >= 0.0) {
            return Err(bad(
                spec,
                format!("W nonincreasing in [0, 1] (at point {i})"),
                USAGE,
            ));
        }
    }
    if w[n - 1] != 0.0 {
        return Err(bad(
            spec,
            "a last W = 0 (the reset must come: write the tail as points)",
            USAGE,
        ));
    }
    Ok(())
}

impl Law for TableClock {
    const KIND: &'static str = "table";
    const USAGE: &'static str = USAGE;
    fn parse(args: &str, spec: &str) -> Result<Self> {
        let (mut t, mut w) = (Vec::new(), Vec::new());
        for pair in args.split(';').filter(|p| !p.trim().is_empty()) {
            let num = |s: &str| -> Result<f64> {
                s.trim().parse::<f64>().map_err(|_| {
                    bad(
                        spec,
                        format!("T:W pairs of numbers, not '{}'", pair.trim()),
                        USAGE,
                    )
                })
            };
            let (a, b) = pair
                .split_once(':')
                .ok_or_else(|| bad(spec, format!("T:W pairs, not '{}'", pair.trim()), USAGE))?;
            t.push(num(a)?);
            w.push(num(b)?);
        }
        check(&t, &w, spec)?;
        TableClock::new(t, w)
    }
    fn spec(&self) -> String {
        self.data.spec.clone()
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let u: f64 = rng.gen();
        let d = &self.data.clone();
        // The first i with W_i ≤ u: R lies in (t_{i-1}, t_i].
        let i = d.w.partition_point(|&x| x > u).max(1);
        let (w0, w1) = (d.w[i - 1], d.w[i]);
        d.t[i - 1] + (w0 - u) / (w0 - w1) * (d.t[i] - d.t[i - 1])
    }
    fn survival(&self, t: f64) -> f64 {
        let d = &self.data.clone();
        if t <= 0.0 {
            return 1.0;
        }
        if t >= d.t[d.t.len() - 1] {
            return 0.0;
        }
        let i = self.segment(t);
        let s = (t - d.t[i]) / (d.t[i + 1] - d.t[i]);
        d.w[i] + s * (d.w[i + 1] - d.w[i])
    }
    fn density(&self, t: f64) -> Option<f64> {
        let d = &self.data.clone();
        if t < 0.0 || t >= d.t[d.t.len() - 1] {
            return Some(0.0);
        }
        let i = self.segment(t);
        Some((d.w[i] - d.w[i + 1]) / (d.t[i + 1] - d.t[i]))
    }
    /// The first point with W = 0.
    fn support_end(&self) -> f64 {
        self.data.t[self.data.w.partition_point(|&w| w > 0.0)]
    }
    fn mean(&self) -> f64 {
        self.data.cum[self.data.cum.len() - 1]
    }
    fn with_mean(&self, mean: f64) -> Result<Self> {
        let c = check_mean(mean)? / self.mean();
        TableClock::new(
            self.data.t.iter().map(|t| t * c).collect(),
            self.data.w.clone(),
        )
    }
    fn tail_integral(&self, t: f64) -> f64 {
        self.mean() - self.antiderivative(t)
    }
    fn survival_integral(&self, a: f64, b: f64) -> f64 {
        self.antiderivative(b) - self.antiderivative(a)
    }
}
