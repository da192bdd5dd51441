//! Time-dependent forward equations, the paper's way (Sec. 3): explicit
//! upwind finite volumes on a uniform mesh, no-flux edges, the initial
//! condition P±(v, 0) = ½ δ(v) placed in the cell of v = 0.

use super::grid::{uniform_target, Grid};
use super::stationary::{MAX_CELLS, MIN_CELLS};
use crate::error::{finite, Error, Result};
use crate::model::Params;
use crate::parallel::{NoProgress, Progress};
use serde::{Deserialize, Serialize};

/// Options of [`transient`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TransientOptions {
    /// Number of uniform cells on (v_l, v_u) (paper: 2000 for tan, 1000 for tanh).
    pub cells: usize,
    /// Final time.
    pub t_max: f64,
    /// Times in [0, t_max] at which `<v>`, `<v²>` and the mass are recorded
    /// (empty: t_max only).
    pub times: Vec<f64>,
    /// Times in [0, t_max] at which the density P(v, t) is stored.
    pub snapshot_times: Vec<f64>,
    /// Courant number in (0, 1]: dt = cfl / max_i (outflow + flip + reset rate
    /// of cell i) ≤ cfl Δv / max|drift|. cfl ≤ 1 keeps every cell mass ≥ 0.
    pub cfl: f64,
}

impl Default for TransientOptions {
    fn default() -> Self {
        TransientOptions {
            cells: 2000,
            t_max: 10.0,
            times: Vec::new(),
            snapshot_times: Vec::new(),
            cfl: 0.5,
        }
    }
}

impl TransientOptions {
    /// Options recording `<v²>` at `samples` equally spaced times in
    /// [0, t_max] and the density at `snapshots` equally spaced times in
    /// (0, t_max] (both grids end exactly at t_max). Validates `t_max` and
    /// `samples` here; [`transient`] validates the rest.
    pub fn sampled(
        cells: usize,
        t_max: f64,
        samples: usize,
        snapshots: usize,
        cfl: f64,
    ) -> Result<Self> {
        let times = crate::numerics::time_grid::TimeGrid::linear(t_max, samples)?
            .times()
            .to_vec();
        let snapshot_times =
            crate::numerics::grid::linspace(0.0, t_max, snapshots.saturating_add(1)).split_off(1);
        Ok(TransientOptions {
            cells,
            t_max,
            times,
            snapshot_times,
            cfl,
        })
    }
}

/// Density at one time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Snapshot {
    /// Time.
    pub t: f64,
    /// Total density P(v, t) at the cell centres.
    pub p: Vec<f64>,
    /// + state density.
    pub p_plus: Vec<f64>,
    /// - state density.
    pub p_minus: Vec<f64>,
}

/// Result of [`transient`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Transient {
    /// Parameters.
    pub params: Params,
    /// Number of cells.
    pub cells: usize,
    /// Time step used (steps landing on a requested time are shortened).
    pub dt: f64,
    /// Number of steps taken.
    pub steps: u64,
    /// Cell centres.
    pub v: Vec<f64>,
    /// Recording times.
    pub times: Vec<f64>,
    /// `<v>(t)`.
    pub v_mean: Vec<f64>,
    /// `<v²>(t)` (paper Fig. 1).
    pub v2: Vec<f64>,
    /// Σ P Δv at the recording times.
    pub mass: Vec<f64>,
    /// max over all steps of |Σ P Δv - 1|.
    pub mass_error_max: f64,
    /// Density snapshots.
    pub snapshots: Vec<Snapshot>,
}

fn check_times(name: &'static str, ts: &[f64], t_max: f64) -> Result<Vec<f64>> {
    let mut out = Vec::with_capacity(ts.len());
    for &t in ts {
        let t = finite(name, t)?;
        if !(t >= 0.0 && t <= t_max) {
            return Err(Error::invalid(
                name,
                t,
                format!("0 <= t <= t_max = {t_max}"),
            ));
        }
        out.push(t);
    }
    out.sort_by(|a, b| a.total_cmp(b));
    out.dedup();
    Ok(out)
}

/// The time step and the number of steps of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan {
    /// Time step: the Courant number over the largest total outflow rate.
    pub dt: f64,
    /// Steps to t_max.
    pub steps: u64,
}

/// The step and step count [`transient`] will use (O(cells), no
/// integration): for estimating the cost before a run.
pub fn plan(params: &Params, opts: &TransientOptions) -> Result<Plan> {
    validate(opts)?;
    plan_on(params, opts, &Grid::uniform(params, opts.cells))
}

fn plan_on(params: &Params, opts: &TransientOptions, g: &Grid) -> Result<Plan> {
    let (lambda, r) = (params.lambda(), params.rate());
    let max_rate = (0..opts.cells)
        .map(|i| g.out_plus[i].max(g.out_minus[i]) + lambda + r)
        .fold(0.0, f64::max);
    let dt = opts.cfl / max_rate;
    let steps = (opts.t_max / dt).ceil();
    if !(steps <= 1e12) {
        return Err(Error::invalid(
            "t_max",
            opts.t_max,
            format!("t_max / dt <= 1e12 steps (dt = {dt:.3e})"),
        ));
    }
    Ok(Plan {
        dt,
        steps: steps as u64,
    })
}

/// Integrate the forward equations from the paper's initial condition.
pub fn transient(params: &Params, opts: &TransientOptions) -> Result<Transient> {
    transient_with_progress(params, opts, &NoProgress)
}

/// [`transient`] reporting steps done to `progress`.
pub fn transient_with_progress(
    params: &Params,
    opts: &TransientOptions,
    progress: &dyn Progress,
) -> Result<Transient> {
    let n = opts.cells;
    let (times, snaps) = validate(opts)?;
    let g = Grid::uniform(params, n);
    let Plan {
        dt,
        steps: total_steps,
    } = plan_on(params, opts, &g)?;
    let (lambda, r) = (params.lambda(), params.rate());

    let (vl, vu) = params.bounds();
    let (i0p, i0m) = uniform_target(n, vl, vu, 0.0);
    let mut m = vec![[0.0f64; 2]; n];
    m[i0p][0] += 0.5;
    m[i0m][1] += 0.5;
    let mut next = vec![[0.0f64; 2]; n];

    let mut out = Transient {
        params: *params,
        cells: n,
        dt,
        steps: 0,
        v: g.centres.clone(),
        times: Vec::with_capacity(times.len()),
        v_mean: Vec::with_capacity(times.len()),
        v2: Vec::with_capacity(times.len()),
        mass: Vec::with_capacity(times.len()),
        mass_error_max: 0.0,
        snapshots: Vec::with_capacity(snaps.len()),
    };
    let (mut ti, mut si) = (0usize, 0usize);
    let mut t = 0.0f64;
    let report_every = (total_steps / 200).max(1);
    loop {
        while ti < times.len() && times[ti] <= t {
            out.record_moments(times[ti], &m, &g);
            ti += 1;
        }
        while si < snaps.len() && snaps[si] <= t {
            out.record_snapshot(snaps[si], &m, &g);
            si += 1;
        }
        let target = match (times.get(ti), snaps.get(si)) {
            (Some(&a), Some(&b)) => a.min(b),
            (Some(&a), None) => a,
            (None, Some(&b)) => b,
            (None, None) => break,
        };
        // Step to `target`, the last step shortened to land on it exactly.
        while t < target {
            let h = if t + dt >= target - 1e-9 * dt {
                target - t
            } else {
                dt
            };
            let err = step(&g, lambda, r, h, &m, &mut next);
            std::mem::swap(&mut m, &mut next);
            out.mass_error_max = out.mass_error_max.max(err);
            out.steps += 1;
            t = if h == dt { t + dt } else { target };
            if out.steps % report_every == 0 {
                report(progress, out.steps, total_steps)?;
            }
        }
    }
    progress.update(total_steps, total_steps);
    Ok(out)
}

/// Report `steps` of `total` done; [`Error::Interrupted`] when the caller
/// asked to stop.
fn report(progress: &dyn Progress, steps: u64, total: u64) -> Result<()> {
    progress.update(steps.min(total), total);
    if progress.cancelled() {
        return Err(Error::Interrupted);
    }
    Ok(())
}

/// Check the options; returns the recording times (t_max when none) and
/// the snapshot times.
fn validate(opts: &TransientOptions) -> Result<(Vec<f64>, Vec<f64>)> {
    let n = opts.cells;
    if !(MIN_CELLS..=MAX_CELLS).contains(&n) {
        return Err(Error::invalid(
            "cells",
            n,
            format!("{MIN_CELLS} <= cells <= {MAX_CELLS}"),
        ));
    }
    let t_max = finite("t_max", opts.t_max)?;
    if !(t_max > 0.0) {
        return Err(Error::invalid("t_max", t_max, "t_max > 0"));
    }
    let cfl = finite("cfl", opts.cfl)?;
    if !(cfl > 0.0 && cfl <= 1.0) {
        return Err(Error::invalid("cfl", cfl, "0 < cfl <= 1"));
    }
    let mut times = check_times("times", &opts.times, t_max)?;
    if times.is_empty() {
        times.push(t_max);
    }
    let snaps = check_times("snapshot_times", &opts.snapshot_times, t_max)?;
    Ok((times, snaps))
}

impl Transient {
    /// Record mass, `<v>` and `<v²>` of the cell masses `m` at time t.
    fn record_moments(&mut self, t: f64, m: &[[f64; 2]], g: &Grid) {
        let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
        for (c, &v) in m.iter().zip(&g.centres) {
            let w = c[0] + c[1];
            s0 += w;
            s1 += w * v;
            s2 += w * v * v;
        }
        self.times.push(t);
        self.mass.push(s0);
        self.v_mean.push(s1);
        self.v2.push(s2);
    }

    /// Record the densities P, P+ and P- of the cell masses `m` at time t.
    fn record_snapshot(&mut self, t: f64, m: &[[f64; 2]], g: &Grid) {
        let pp: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[0] / h).collect();
        let pm: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[1] / h).collect();
        self.snapshots.push(Snapshot {
            t,
            p: pp.iter().zip(&pm).map(|(a, b)| a + b).collect(),
            p_plus: pp,
            p_minus: pm,
        });
    }
}

/// One explicit step in conservative form: every transfer (flux through an
/// edge, flip, reset) is subtracted from one cell and added to another, so the
/// total mass changes by rounding only. Returns |Σ m - 1| after the step.
fn step(g: &Grid, lambda: f64, r: f64, h: f64, m: &[[f64; 2]], next: &mut [[f64; 2]]) -> f64 {
    let n = m.len();
    let (al, be) = (&g.out_plus, &g.out_minus);
    let (mut reset_p, mut reset_m) = (0.0, 0.0);
    let mut in_p = 0.0; // + flux entering cell i from i-1
    let mut out_m_next = h * be[0] * m[0][1]; // - flux leaving cell i leftwards
    for i in 0..n {
        let [mp, mm] = m[i];
        let op = h * al[i] * mp;
        let om = out_m_next;
        let in_m = if i + 1 < n {
            out_m_next = h * be[i + 1] * m[i + 1][1];
            out_m_next
        } else {
            0.0
        };
        let fl = h * lambda * (mm - mp);
        let (rp, rm) = (h * r * mp, h * r * mm);
        reset_p += rp;
        reset_m += rm;
        next[i] = [mp - op - rp + fl + in_p, mm - om - rm - fl + in_m];
        in_p = op;
    }
    next[g.reset_plus][0] += reset_p;
    next[g.reset_minus][1] += reset_m;
    let total: f64 = next.iter().map(|c| c[0] + c[1]).sum();
    (total - 1.0).abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_grids() {
        let o = TransientOptions::sampled(100, 2.0, 5, 4, 0.5).unwrap();
        assert_eq!(o.times, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(o.snapshot_times, vec![0.5, 1.0, 1.5, 2.0]);
        // Both grids end exactly at t_max, also where t·n/n would round.
        let t = 0.1 + 0.2;
        let o = TransientOptions::sampled(100, t, 7, 3, 0.5).unwrap();
        assert_eq!((o.times[6], o.snapshot_times[2]), (t, t));
        let o = TransientOptions::sampled(100, 1.0, 2, 0, 0.5).unwrap();
        assert!(o.snapshot_times.is_empty());
    }

    #[test]
    fn sampled_validates_t_max_then_samples() {
        let name = |r: Result<TransientOptions>| match r.unwrap_err() {
            Error::InvalidParameter { name, .. } => name,
            e => panic!("{e}"),
        };
        assert_eq!(
            name(TransientOptions::sampled(100, f64::NAN, 1, 1, 0.5)),
            "t_max"
        );
        assert_eq!(
            name(TransientOptions::sampled(100, 0.0, 5, 1, 0.5)),
            "t_max"
        );
        assert_eq!(
            name(TransientOptions::sampled(100, 1.0, 1, 1, 0.5)),
            "samples"
        );
    }
}
