//! A heat map layer of a [`super::Panel`]: one scalar over a grid of
//! cells whose edges lie on the panel's axes in data units (between the
//! values of a sweep's axes: geometric means on a log axis, arithmetic
//! ones on a linear axis, [`edges`]), each cell coloured by its value on
//! the viridis scale (linear, or logarithmic in the value), with a colour
//! bar right of the plotting area. Cells without a value (a failed point,
//! a `nan`) are drawn light grey.
//!
//! The model needs no plotting library; rendering is the panel's (cargo
//! feature `plot`).

use serde::Serialize;

/// A value per cell of an `x` × `y` grid.
#[derive(Clone, Debug, Serialize)]
pub struct Heat {
    /// Cell edges along x in data units (one more than the columns).
    pub x_edges: Vec<f64>,
    /// Cell edges along y in data units (one more than the rows).
    pub y_edges: Vec<f64>,
    /// `values[row][column]`; `None` or non-finite: no value.
    pub values: Vec<Vec<Option<f64>>>,
    /// Name of the coloured quantity (the colour bar's label, `_{...}`
    /// subscripts allowed).
    pub label: String,
    /// The colour scale's ends; `None`: the finite values' own (small
    /// multiples share one).
    pub range: Option<(f64, f64)>,
    /// Logarithmic colour scale (positive values only).
    pub log: bool,
}

/// Viridis at five stops (0, 1/4, 1/2, 3/4, 1), interpolated linearly.
const VIRIDIS: [(f64, f64, f64); 5] = [
    (68.0, 1.0, 84.0),
    (59.0, 82.0, 139.0),
    (33.0, 145.0, 140.0),
    (94.0, 201.0, 98.0),
    (253.0, 231.0, 37.0),
];

/// The viridis colour of `t` in [0, 1] (clamped).
pub fn viridis(t: f64) -> (u8, u8, u8) {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: f64, q: f64| (p + f * (q - p)).round() as u8;
    (mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Cell edges around the centres `c` (increasing): midpoints between
/// neighbours (geometric means when `log`), the outer edges half a step
/// beyond the end values; one cell of a single value spans a factor 2
/// (log) or ±0.5 around it.
pub fn edges(c: &[f64], log: bool) -> Vec<f64> {
    type Map = fn(f64) -> f64;
    let (f, g): (Map, Map) = if log {
        (f64::log10, |u| 10f64.powf(u))
    } else {
        (|v| v, |u| u)
    };
    let u: Vec<f64> = c.iter().map(|&v| f(v)).collect();
    let n = u.len();
    if n == 0 {
        return Vec::new();
    }
    if n == 1 {
        let h = if log { 0.15 } else { 0.5 * (1.0 + u[0].abs()) };
        return vec![g(u[0] - h), g(u[0] + h)];
    }
    let mut e = Vec::with_capacity(n + 1);
    e.push(u[0] - 0.5 * (u[1] - u[0]));
    e.extend(u.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    e.push(u[n - 1] + 0.5 * (u[n - 1] - u[n - 2]));
    e.into_iter().map(g).collect()
}

/// Whether `vals` (at least three, increasing) are evenly spaced in their
/// logarithm rather than in value (a plan's `spacing = "log"`, or a list
/// like 0.1, 1, 10); two positive values a factor 10 or more apart count
/// as log-spaced too.
pub fn log_spaced(vals: &[f64]) -> bool {
    if vals.len() < 2 || vals.iter().any(|&v| !(v > 0.0 && v.is_finite())) {
        return false;
    }
    let (lo, hi) = (vals[0], vals[vals.len() - 1]);
    if vals.len() == 2 {
        return hi / lo >= 10.0;
    }
    let even = |u: &[f64]| {
        let d: Vec<f64> = u.windows(2).map(|w| w[1] - w[0]).collect();
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        d.iter().all(|x| (x - mean).abs() <= 0.02 * mean.abs())
    };
    let logs: Vec<f64> = vals.iter().map(|v| v.log10()).collect();
    hi / lo >= 4.0 && !even(vals) && (even(&logs) || hi / lo >= 100.0)
}

impl Heat {
    /// The colour scale's ends: the given range, else the smallest and
    /// largest finite value (positive ones on a log scale); `None` when
    /// there is none.
    pub fn value_range(&self) -> Option<(f64, f64)> {
        if let Some(r) = self.range {
            return Some(r);
        }
        let finite = self.values.iter().flatten().flatten().copied();
        let (lo, hi) = finite
            .filter(|v| v.is_finite() && (!self.log || *v > 0.0))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        (lo <= hi).then_some((lo, hi))
    }

    /// Where `v` lies on the colour scale, 0 to 1 (0.5 when its ends are
    /// equal).
    pub fn level(&self, v: f64) -> f64 {
        let t = |x: f64| if self.log { x.log10() } else { x };
        match self.value_range() {
            Some((lo, hi)) if hi > lo => (t(v) - t(lo)) / (t(hi) - t(lo)),
            _ => 0.5,
        }
    }
}
