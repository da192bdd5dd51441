//! Validated recording times of a time-dependent run: linear, logarithmic
//! or explicit ([`TimeGrid`]; re-exported as `sim::TimeGrid`).

use crate::error::{finite, Error, Result};
use serde::{Deserialize, Serialize};

/// Times at which ensemble moments are recorded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TimeGrid {
    times: Vec<f64>,
}

impl TimeGrid {
    /// `samples` equally spaced times 0 = t_0 < ... < t_{K-1} = t_max.
    pub fn linear(t_max: f64, samples: usize) -> Result<Self> {
        check_t_max(t_max)?;
        if samples < 2 {
            return Err(Error::invalid("samples", samples, "samples >= 2"));
        }
        let times = super::grid::linspace(0.0, t_max, samples);
        Ok(TimeGrid { times })
    }

    /// t = 0 followed by `samples - 1` log-spaced times from `t_min` to `t_max`
    /// (for log-log plots of <x²>(t)).
    pub fn log(t_min: f64, t_max: f64, samples: usize) -> Result<Self> {
        check_t_max(t_max)?;
        let t_min = finite("t_min", t_min)?;
        if !(t_min > 0.0 && t_min < t_max) {
            return Err(Error::invalid(
                "t_min",
                t_min,
                format!("0 < t_min < t_max = {t_max}"),
            ));
        }
        if samples < 3 {
            return Err(Error::invalid(
                "samples",
                samples,
                "samples >= 3 for a log grid",
            ));
        }
        let m = samples - 1;
        let (a, b) = (t_min.ln(), t_max.ln());
        let mut times = vec![0.0];
        times.extend((0..m).map(|k| (a + (b - a) * k as f64 / (m - 1) as f64).exp()));
        *times.last_mut().expect("non-empty") = t_max;
        Ok(TimeGrid { times })
    }

    /// Explicit, strictly increasing, non-negative, finite times.
    pub fn from_times(times: Vec<f64>) -> Result<Self> {
        if times.is_empty() {
            return Err(Error::invalid("times", "[]", "at least one time"));
        }
        for w in times.windows(2) {
            if !(w[1] > w[0]) {
                return Err(Error::invalid(
                    "times",
                    format!("{:?}", w),
                    "strictly increasing times",
                ));
            }
        }
        if !(times[0] >= 0.0) || !times.iter().all(|t| t.is_finite()) {
            return Err(Error::invalid("times", times[0], "finite times >= 0"));
        }
        Ok(TimeGrid { times })
    }

    /// The times.
    pub fn times(&self) -> &[f64] {
        &self.times
    }
    /// Last time.
    pub fn t_max(&self) -> f64 {
        *self.times.last().expect("non-empty grid")
    }
    /// Number of times.
    pub fn len(&self) -> usize {
        self.times.len()
    }
    /// Never true (a grid has at least one time).
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}

fn check_t_max(t_max: f64) -> Result<f64> {
    let t = finite("t_max", t_max)?;
    if !(t > 0.0) {
        return Err(Error::invalid("t_max", t, "t_max > 0"));
    }
    Ok(t)
}
