//! The paper's two-state noise in [`super::transient`]: the TR-BDF2 space
//! of [`ForwardOperator`] (refractory pairs, twice-extrapolated moments)
//! and the paper's explicit scheme on a uniform mesh.

use super::{
    integrate_levels, merged, report, reset_times, trbdf2_step_bound, Plan, Scheme, Snapshot,
    Transient, TransientOptions, TransientSpace, MESH_LEVELS, TRBDF2_STEP_CAP,
};
use crate::error::{Error, Result};
use crate::fp::extrapolate::extrapolation_error;
use crate::fp::grid::{uniform_target, Grid, Mesh};
use crate::fp::operator::ForwardOperator;
use crate::model::reset::Reset;
use crate::model::{Params, VelocityAtom};
use crate::numerics::trbdf2::Tolerances;
use crate::parallel::Progress;

pub(super) fn plan_on(params: &Params, opts: &TransientOptions, g: &Grid) -> Result<Plan> {
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
        dt: Some(dt),
        steps: steps as u64,
        work: opts.cells as f64 * steps,
    })
}

/// A periodic reset of the flat interleaved cell masses (m+_0, m-_0, ...):
/// all the mass of each noise state moves to the target (the reset cells of
/// a point target, spread by the target's cell masses for a random one),
/// the noise state kept or re-drawn by [`Grid::reinject`].
fn periodic_reset(g: &Grid, u: &mut [f64]) {
    let (mut a, mut b) = (0.0, 0.0);
    for c in u.chunks_exact_mut(2) {
        a += c[0];
        b += c[1];
        c.fill(0.0);
    }
    let (ip, im) = g.reinject(a, b);
    g.add_reset_flat(u, ip, im);
}

/// The exponential refractory period runs in [`Scheme::TrBdf2`] only (the
/// held pairs of [`ForwardOperator`]; with periodic resetting it is refused
/// before, by `capability::combination_runs`).
pub(super) fn require_held(params: &Params, scheme: Scheme) -> Result<()> {
    let Some(r) = params.schedule().refractory else {
        return Ok(());
    };
    if scheme == Scheme::Paper {
        return Err(Error::invalid(
            "refractory",
            r.spec(),
            "none with --scheme paper (the refractory period runs in --scheme trbdf2)",
        ));
    }
    Ok(())
}

/// The snapshots' densities with the round-off negatives of the solves (at
/// most [`NEGATIVE_TOLERANCE`] of the snapshot's largest density in
/// magnitude) set to 0; a larger negative density means the integration
/// lost positivity (TR-BDF2's second stage has a right-hand side of mixed
/// sign), and the answer is refused.
pub(super) fn nonnegative(mut out: Transient) -> Result<Transient> {
    for snap in &mut out.snapshots {
        let scale = snap.p.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let floor = -NEGATIVE_TOLERANCE * scale;
        for col in [&mut snap.p_plus, &mut snap.p_minus] {
            if let Some(x) = col.iter().find(|&&x| !(x >= floor)) {
                return Err(Error::Numerical {
                    method: "fp transient",
                    reason: format!(
                        "a density of {x:e} at t = {} (largest {scale:e}): the time \
                         integration lost positivity; raise --cells or lower --rtol",
                        snap.t
                    ),
                });
            }
            col.iter_mut().filter(|x| **x < 0.0).for_each(|x| *x = 0.0);
        }
        for ((p, a), b) in snap.p.iter_mut().zip(&snap.p_plus).zip(&snap.p_minus) {
            *p = a + b;
        }
    }
    Ok(out)
}

/// How negative a snapshot's density may come out (relative to its largest
/// value) and still count as round-off, reported as 0.
pub const NEGATIVE_TOLERANCE: f64 = 1e-12;

/// The paper's explicit upwind scheme on a uniform mesh.
pub(super) fn paper(
    params: &Params,
    opts: &TransientOptions,
    times: &[f64],
    snaps: &[f64],
    progress: &dyn Progress,
) -> Result<Transient> {
    let n = opts.cells;
    let g = Grid::uniform(params, n);
    let plan = plan_on(params, opts, &g)?;
    let (dt, total_steps) = (plan.dt.expect("explicit step"), plan.steps);
    let (lambda, r) = (params.lambda(), params.rate());

    let (vl, vu) = params.bounds();
    let (i0p, i0m) = uniform_target(n, vl, vu, 0.0);
    let mut m = vec![[0.0f64; 2]; n];
    m[i0p][0] += 0.5;
    m[i0m][1] += 0.5;
    let mut next = vec![[0.0f64; 2]; n];

    let mut out = Transient::empty(
        params,
        Scheme::Paper,
        Some(dt),
        &g,
        times.len(),
        snaps.len(),
    );
    let resets = reset_times(params, times, snaps);
    let (mut ti, mut si) = (0usize, 0usize);
    let mut t = 0.0f64;
    let report_every = (total_steps / 200).max(1);
    for target in merged(&merged(times, snaps), &resets) {
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
        if resets.binary_search_by(|x| x.total_cmp(&t)).is_ok() {
            periodic_reset(&g, m.as_flattened_mut());
        }
        while ti < times.len() && times[ti] <= t {
            out.record_moments(times[ti], &m, &g.centres, n);
            ti += 1;
        }
        while si < snaps.len() && snaps[si] <= t {
            out.record_snapshot(snaps[si], &m, &g);
            si += 1;
        }
    }
    progress.update(total_steps, total_steps);
    Ok(out)
}

/// TR-BDF2 on the nested graded meshes of `cells/4`, `cells/2` and `cells`
/// cells; moments Richardson-extrapolated twice at t > 0 (see
/// [`extrapolate`]).
pub(super) fn trbdf2(
    params: &Params,
    opts: &TransientOptions,
    times: &[f64],
    snaps: &[f64],
    progress: &dyn Progress,
) -> Result<Transient> {
    let all = merged(times, snaps);
    let bound = trbdf2_step_bound(params, opts, all.len());
    let tol = Tolerances {
        rtol: opts.rtol,
        atol: opts.atol,
        h0: None,
        h_max: f64::INFINITY,
        max_steps: usize::try_from(bound.saturating_mul(TRBDF2_STEP_CAP)).unwrap_or(usize::MAX),
    };
    let mut space = TwoState {
        params,
        base: opts.cells / 4,
        times,
        snaps,
        all: &all,
        runs: Vec::with_capacity(MESH_LEVELS),
    };
    let resets = reset_times(params, times, snaps);
    let effort = integrate_levels(&mut space, &tol, &all, &resets, progress)?;
    let mut runs: Vec<Transient> = space.runs.into_iter().map(|r| r.t).collect();
    let fine = runs.pop().expect("three meshes");
    let (half, quarter) = (&runs[1], &runs[0]);
    let (mut v2, v2_mesh_error) = extrapolate(times, &fine.v2, &half.v2, &quarter.v2);
    check_resolved(params, times, &mut v2, &v2_mesh_error)?;
    Ok(Transient {
        params: params.clone(),
        scheme: Scheme::TrBdf2,
        mesh: Mesh::Graded,
        cells: opts.cells,
        dt: None,
        steps: effort.steps as u64,
        rejected: effort.rejected as u64,
        extrapolated: true,
        v: fine.v,
        times: times.to_vec(),
        v_mean: extrapolate(times, &fine.v_mean, &half.v_mean, &quarter.v_mean).0,
        v2,
        v2_mesh_error,
        mass: fine.mass,
        refractory_mass: fine.refractory_mass,
        atoms: held_errors(fine.atoms, &half.atoms),
        mass_error_max: fine
            .mass_error_max
            .max(half.mass_error_max)
            .max(quarter.mass_error_max),
        snapshots: fine
            .snapshots
            .into_iter()
            .zip(&half.snapshots)
            .map(|(s, h)| Snapshot {
                atoms: held_errors(vec![s.atoms], std::slice::from_ref(&h.atoms)).remove(0),
                ..s
            })
            .collect(),
    })
}

/// The refractory atoms of the fine mesh with their error estimates: the
/// change from the mesh of cells/2 (as the stationary solver's), at least
/// 1e-14 of the mass.
fn held_errors(fine: Vec<Vec<VelocityAtom>>, half: &[Vec<VelocityAtom>]) -> Vec<Vec<VelocityAtom>> {
    fine.into_iter()
        .zip(half)
        .map(|(f, h)| {
            f.into_iter()
                .zip(h)
                .map(|(a, b)| VelocityAtom {
                    err: (a.mass - b.mass).abs().max(1e-14 * a.mass),
                    ..a
                })
                .collect()
        })
        .collect()
}

/// Moments on the nested meshes of N, N/2 and N/4 cells, extrapolated twice:
/// the upwind fluxes are first order, X_N = X + a/N + b/N² + ..., so
/// X₂ = 2 X_N - X_{N/2} removes the 1/N term and
/// X₃ = (4 X₂(N) - X₂(N/2)) / 3 = (8 X_N - 6 X_{N/2} + X_{N/4}) / 3 the 1/N²
/// term. Returns X₃ and the estimate of its error: the bound on X₂'s error
/// from the three meshes ([`extrapolation_error`], Eq. (N27)) plus the change
/// |X₃ - X₂| made by the second extrapolation. Three meshes cannot show that
/// the 1/N² term is asymptotic (it is not while the initial delta's front
/// or the reset point sits between few cells: linear drag, t = 0.5, 200
/// cells, X₃ was 7.0e-5 off against |X₃ - X₂| = 2.1e-5), so the estimate
/// bounds X₂ and the step to X₃ rather than trusting the second term.
///
/// At t = 0 the moments are those of the initial delta placed in a cell
/// (O(Δv²), not a first-order mesh error): reported from the fine mesh, not
/// extrapolated (2 X_N - X_{N/2} would give <v²> = -Δv²/2 < 0 there). The
/// same holds while the front of the delta has crossed few cells; an
/// extrapolated <v²> outside its range there is refused by
/// [`check_resolved`].
fn extrapolate(times: &[f64], n: &[f64], half: &[f64], quarter: &[f64]) -> (Vec<f64>, Vec<f64>) {
    times
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            if t > 0.0 {
                let x2 = 2.0 * n[k] - half[k];
                let x3 = (8.0 * n[k] - 6.0 * half[k] + quarter[k]) / 3.0;
                let bound = extrapolation_error(quarter[k], half[k], n[k]);
                (x3, (x3 - x2).abs() + bound)
            } else {
                (n[k], 0.0)
            }
        })
        .unzip()
}

/// 0 <= <v²>(t) <= max(v_l², v_u²) for the extrapolated values, or the
/// answer is refused (as the stationary solver does): a violation means the
/// meshes do not resolve the density (e.g. a peak narrower than a cell at
/// fast flips), where Richardson extrapolation is not valid. A value
/// outside the range by no more than its error estimate `err` is within
/// its error of the range and is moved to the bound: just after a periodic
/// reset to v_r = 0 the extrapolation cancels the Δv² of the delta placed
/// in a cell up to rounding (measured -5.6e-11, estimate above 1e-7).
fn check_resolved(params: &Params, times: &[f64], v2: &mut [f64], err: &[f64]) -> Result<()> {
    let (lo, hi) = params.bounds();
    let v2_max = lo.powi(2).max(hi.powi(2));
    for (k, x) in v2.iter_mut().enumerate() {
        if *x >= 0.0 && *x <= v2_max {
            continue;
        }
        let bound = x.clamp(0.0, v2_max);
        if (*x - bound).abs() <= err[k] {
            *x = bound;
            continue;
        }
        return Err(Error::Numerical {
            method: "fp transient (TR-BDF2)",
            reason: format!(
                "extrapolated <v^2>(t = {}) = {:e} outside [0, {v2_max:e}]: the mesh does not \
                 resolve the density at lambda = {}, rate = {} (at early times: the initial \
                 delta has crossed few cells); refused (use more --cells or later times)",
                times[k],
                *x,
                params.lambda(),
                params.rate()
            ),
        });
    }
    Ok(())
}

/// One mesh's record, its grid and the velocity of each (cell or held)
/// pair of unknowns.
struct MeshRun {
    t: Transient,
    g: Grid,
    pair_v: Vec<f64>,
}

/// The paper's two states on the nested graded meshes of `base` << level
/// cells ([`ForwardOperator`]), from the paper's initial condition: moments
/// at `times`, densities at `snaps` (`all`: their sorted union).
struct TwoState<'a> {
    params: &'a Params,
    base: usize,
    times: &'a [f64],
    snaps: &'a [f64],
    all: &'a [f64],
    runs: Vec<MeshRun>,
}

impl TransientSpace for TwoState<'_> {
    type Op = ForwardOperator;

    fn mesh(&mut self, level: usize) -> Result<(ForwardOperator, Vec<f64>)> {
        let op = ForwardOperator::refined(self.params, Mesh::Graded, self.base, level)?;
        let u = op.point_mass(0.0);
        let (nt, ns) = (self.times.len(), self.snaps.len());
        self.runs.push(MeshRun {
            t: Transient::empty(self.params, Scheme::TrBdf2, None, op.grid(), nt, ns),
            g: op.grid().clone(),
            pair_v: op.velocities().iter().step_by(2).copied().collect(),
        });
        Ok((op, u))
    }

    fn reset(&self, u: &mut [f64]) {
        periodic_reset(&self.runs.last().expect("a mesh").g, u);
    }

    fn observe(&mut self, level: usize, k: usize, u: &[f64]) -> Result<()> {
        let t = self.all[k];
        let run = &mut self.runs[level];
        let m: Vec<[f64; 2]> = u.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let mass: f64 = u.iter().sum();
        run.t.mass_error_max = run.t.mass_error_max.max((mass - 1.0).abs());
        if self.times.binary_search_by(|x| x.total_cmp(&t)).is_ok() {
            run.t.record_moments(t, &m, &run.pair_v, run.g.cells());
        }
        if self.snaps.binary_search_by(|x| x.total_cmp(&t)).is_ok() {
            run.t.record_snapshot(t, &m, &run.g);
        }
        Ok(())
    }
}

impl Transient {
    /// The record of one run of `scheme` (time step `dt`) on the grid `g`,
    /// before any time: room for `nt` recording and `ns` snapshot times.
    fn empty(
        params: &Params,
        scheme: Scheme,
        dt: Option<f64>,
        g: &Grid,
        nt: usize,
        ns: usize,
    ) -> Self {
        Transient {
            params: params.clone(),
            scheme,
            mesh: scheme.mesh(),
            cells: g.cells(),
            dt,
            steps: 0,
            rejected: 0,
            extrapolated: false,
            v: g.centres.clone(),
            times: Vec::with_capacity(nt),
            v_mean: Vec::with_capacity(nt),
            v2: Vec::with_capacity(nt),
            v2_mesh_error: Vec::new(),
            mass: Vec::with_capacity(nt),
            refractory_mass: Vec::with_capacity(nt),
            atoms: Vec::with_capacity(nt),
            mass_error_max: 0.0,
            snapshots: Vec::with_capacity(ns),
        }
    }

    /// Record mass, `<v>` and `<v²>` of the pairs `m` (the cell masses,
    /// then from index `cells` on the held pairs) at velocities `v` at time
    /// t, and the held mass.
    fn record_moments(&mut self, t: f64, m: &[[f64; 2]], v: &[f64], cells: usize) {
        let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
        for (c, &v) in m.iter().zip(v) {
            let w = c[0] + c[1];
            s0 += w;
            s1 += w * v;
            s2 += w * v * v;
        }
        self.times.push(t);
        self.mass.push(s0);
        let held: f64 = m[cells..].iter().map(|c| c[0] + c[1]).sum();
        self.refractory_mass.push(held);
        self.atoms.push(self.held_atoms(held));
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
            states: Vec::new(),
            atoms: self.held_atoms(m[g.cells()..].iter().map(|c| c[0] + c[1]).sum()),
        });
    }

    /// The refractory hold at a point target v_r as an atom of mass `held`
    /// (error set by [`held_errors`]); none without an exponential
    /// refractory period or with a random target (its held mass is spread
    /// over the target's cells' velocities).
    fn held_atoms(&self, held: f64) -> Vec<VelocityAtom> {
        match (
            self.params.schedule().refractory,
            self.params.reset().point(),
        ) {
            (Some(_), Some(v)) => vec![VelocityAtom {
                v,
                mass: held,
                err: 0.0,
            }],
            _ => Vec::new(),
        }
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
    let (ip, im) = g.reinject(reset_p, reset_m);
    g.add_reset(next, ip, im);
    let total: f64 = next.iter().map(|c| c[0] + c[1]).sum();
    (total - 1.0).abs()
}
