//! Time-dependent N-state solutions (Eqs. (N28)-(N29)): the densities from
//! v = 0 with the noise state drawn from π, and the position-moment chain
//! dM_0/dt = A M_0, dM_k/dt = A M_k + k v∘M_{k-1} (k = 1, 2; a reset keeps
//! x, so every block has the same A), by the shared TR-BDF2 on the
//! operator's shifted solve.

use super::super::grid::MIN_CELLS;
use super::super::moments::MsdOptions;
use super::super::transient::{
    merged, Scheme, Snapshot, Transient, TransientOptions, MASS_TOLERANCE,
};
use super::super::Mesh;
use super::operator::{operator, NoiseOperator};
use crate::error::{Error, Result};
use crate::fp::extrapolate::richardson;
use crate::model::atoms::transient_atom_states;
use crate::model::reset::Reset;
use crate::model::{Params, VelocityAtom};
use crate::numerics::trbdf2::{integrate, ShiftedLinear, Tolerances};
use crate::numerics::Failure;

/// `blocks` copies of the operator coupled by the moment chain.
pub(crate) struct Blocks {
    pub op: NoiseOperator,
    pub blocks: usize,
    /// The velocity of every unknown (its cell centre).
    pub v: Vec<f64>,
    tmp: Vec<f64>,
}

impl Blocks {
    pub(crate) fn new(op: NoiseOperator, blocks: usize) -> Self {
        let ns = op.mesh.states;
        let v: Vec<f64> = op
            .mesh
            .centres
            .iter()
            .flat_map(|&c| std::iter::repeat(c).take(ns))
            .collect();
        let tmp = vec![0.0; v.len()];
        Blocks { op, blocks, v, tmp }
    }

    /// Mass at v = 0 in the states drawn from π (Eq. (N28)), later blocks 0.
    pub(crate) fn initial(&self) -> Result<Vec<f64>> {
        let m = &self.op.mesh;
        if m.origin.is_empty() {
            return Err(Error::invalid(
                "noise",
                format!("levels {:?}", self.op.chain.levels),
                "a velocity interval containing v = 0 (the initial velocity of fp transient and fp msd)",
            ));
        }
        let mut u = vec![0.0; self.blocks * self.v.len()];
        for (s, cells) in m.origin.iter().enumerate() {
            for &(i, w) in cells {
                u[i * m.states + s] += w * self.op.chain.pi[s];
            }
        }
        Ok(u)
    }
}

impl ShiftedLinear for Blocks {
    fn dim(&self) -> usize {
        self.blocks * self.v.len()
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        let d = self.v.len();
        for k in 0..self.blocks {
            self.op
                .apply(&u[k * d..(k + 1) * d], &mut out[k * d..(k + 1) * d]);
            if k > 0 {
                for i in 0..d {
                    out[k * d + i] += k as f64 * self.v[i] * u[(k - 1) * d + i];
                }
            }
        }
    }

    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        // Block lower triangular: forward substitution, block k with the
        // source c k v∘x_{k-1} moved to its right side.
        let d = self.v.len();
        for k in 0..self.blocks {
            self.tmp.copy_from_slice(&b[k * d..(k + 1) * d]);
            let (prev, rest) = x.split_at_mut(k * d);
            if k > 0 {
                let ck = c * k as f64;
                for (i, t) in self.tmp.iter_mut().enumerate() {
                    *t += ck * self.v[i] * prev[(k - 1) * d + i];
                }
            }
            self.op.solve_shifted(c, &self.tmp, &mut rest[..d])?;
        }
        Ok(())
    }
}

/// Observables at one time of `blocks` blocks with unknown velocities
/// `v`: mass, `<v>`, `<v²>`, then `<x>`, `<x v>`, `<x²>` (3 blocks).
pub(crate) fn observe(v: &[f64], blocks: usize, u: &[f64]) -> [f64; 6] {
    let d = v.len();
    let sum = |k: usize, pow: i32| -> f64 {
        u[k * d..(k + 1) * d]
            .iter()
            .zip(v)
            .map(|(x, v)| x * v.powi(pow))
            .sum()
    };
    let mut o = [sum(0, 0), sum(0, 1), sum(0, 2), 0.0, 0.0, 0.0];
    if blocks == 3 {
        o[3] = sum(1, 0);
        o[4] = sum(1, 1);
        o[5] = sum(2, 0);
    }
    o
}

/// Integrate `blocks` blocks of the operator of `p` on the mesh of
/// `n << refine` cells to every time of `times` (sorted), calling
/// `each(k, v, u)` at times[k] (v: the unknowns' velocities); returns the
/// accepted steps and the operator.
pub(crate) fn run(
    p: &Params,
    n: usize,
    refine: usize,
    blocks: usize,
    times: &[f64],
    tol: &Tolerances,
    mut each: impl FnMut(usize, &[f64], &[f64]) -> Result<()>,
) -> Result<(usize, NoiseOperator)> {
    let mut b = Blocks::new(operator(p, n, refine, true)?, blocks);
    let mut u = b.initial()?;
    let v = b.v.clone();
    let stats = integrate(&mut b, &mut u, times, tol, |k, _, u| each(k, &v, u))?;
    Ok((stats.steps, b.op))
}

/// [`crate::fp::transient`] for a noise model: TR-BDF2 on the meshes of
/// cells/4, cells/2, cells cells, `<v>` and `<v²>` extrapolated with
/// their observed order (Eq. (N27)), snapshots of the fine mesh.
pub(crate) fn transient(p: &Params, o: &TransientOptions) -> Result<Transient> {
    if o.scheme != Scheme::TrBdf2 {
        return Err(Error::invalid(
            "scheme",
            o.scheme.name(),
            "trbdf2 with a noise model (the paper's explicit scheme runs the paper's noise only)",
        ));
    }
    if !(o.cells % 4 == 0 && o.cells >= MIN_CELLS) {
        return Err(Error::invalid(
            "cells",
            o.cells,
            format!("a multiple of 4, at least {MIN_CELLS}, with a noise model"),
        ));
    }
    let rec = if o.times.is_empty() {
        vec![o.t_max]
    } else {
        o.times.clone()
    };
    let times = merged(&rec, &o.snapshot_times);
    let tol = Tolerances {
        rtol: o.rtol,
        atol: o.atol,
        ..Tolerances::default()
    };
    let held = transient_atom_states(p);
    let mut obs = Vec::new();
    let mut atom_rows: Vec<Vec<Vec<f64>>> = Vec::new();
    let (mut steps, mut snapshots, mut mass_err) = (0u64, Vec::new(), 0.0f64);
    let mut fine_rows = vec![FineAtoms::default(); times.len()];
    let mut last = None;
    for refine in 0..3 {
        let fine = refine == 2;
        let mut rows = vec![[0.0; 6]; times.len()];
        let mut arows = vec![Vec::new(); times.len()];
        let mut b = Blocks::new(operator(p, o.cells / 4, refine, true)?, 1);
        let cells = atom_cells(p, &b.op, &held);
        let mut u = b.initial()?;
        let v = b.v.clone();
        let stats = integrate(&mut b, &mut u, &times, &tol, |k, _, u| {
            rows[k] = observe(&v, 1, u);
            arows[k] = cells.iter().map(|c| held_mass(u, c)).collect();
            if fine {
                let x: Vec<[f64; 3]> = (0..held.len())
                    .map(|j| [atom_rows[0][k][j], atom_rows[1][k][j], arows[k][j]])
                    .collect();
                let (split, rest) = split_held(u, &cells, &x);
                fine_rows[k] = FineAtoms {
                    split,
                    total: rest.iter().sum(),
                };
                if o.snapshot_times.contains(&times[k]) {
                    snapshots.push((times[k], rest));
                }
            }
            Ok(())
        })?;
        mass_err = rows.iter().fold(mass_err, |m, r| m.max((r[0] - 1.0).abs()));
        steps += stats.steps as u64;
        obs.push(rows);
        atom_rows.push(arows);
        last = Some(b.op);
    }
    let op = last.expect("three meshes");
    let pick = |k: usize, j: usize| richardson(obs[0][k][j], obs[1][k][j], obs[2][k][j]);
    let atoms = |k: usize| merge_atoms(&held, &fine_rows[k].split);
    check_balance(&times, &fine_rows, &atoms)?;
    let idx: Vec<usize> = rec
        .iter()
        .map(|t| times.iter().position(|x| x == t).expect("a recording time"))
        .collect();
    let snaps = snapshots
        .into_iter()
        .map(|(t, u)| {
            let k = times.iter().position(|x| *x == t).expect("a snapshot time");
            snapshot(&op, t, &u, atoms(k))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Transient {
        params: *p,
        scheme: o.scheme,
        mesh: Mesh::Graded,
        cells: o.cells,
        dt: None,
        steps,
        rejected: 0,
        extrapolated: true,
        v: op.mesh.centres.clone(),
        times: rec,
        v_mean: idx.iter().map(|&k| pick(k, 1).0).collect(),
        v2: idx.iter().map(|&k| pick(k, 2).0).collect(),
        v2_mesh_error: idx.iter().map(|&k| pick(k, 2).1).collect(),
        mass: idx.iter().map(|&k| obs[2][k][0]).collect(),
        refractory_mass: vec![0.0; idx.len()],
        atoms: idx.iter().map(|&k| atoms(k)).collect(),
        mass_error_max: mass_err,
        snapshots: snaps,
    })
}

/// The fine mesh's atoms at one time: per held (velocity, state) the
/// extrapolated mass and its error, and the cell masses without them.
#[derive(Clone, Debug, Default)]
struct FineAtoms {
    split: Vec<(f64, f64)>,
    total: f64,
}

/// The flat indices (cell i, state s: i N + s) and weights of the cells
/// that hold each (velocity, state) of `held` (Eq. (N52)): the reset
/// target's cells for v_r, the start's for v = 0.
fn atom_cells(p: &Params, op: &NoiseOperator, held: &[(f64, usize)]) -> Vec<Vec<(usize, f64)>> {
    let m = &op.mesh;
    held.iter()
        .map(|&(v, s)| {
            let cells = if p.reset().point() == Some(v) {
                &m.target[s]
            } else {
                &m.origin[s]
            };
            cells.iter().map(|&(i, f)| (i * m.states + s, f)).collect()
        })
        .collect()
}

/// The mass of the cells `c` (one state's).
fn held_mass(u: &[f64], c: &[(usize, f64)]) -> f64 {
    c.iter().map(|&(k, _)| u[k]).sum()
}

/// Each held (velocity, state)'s mass Richardson-extrapolated from its
/// cells' masses `x` on the meshes N/4, N/2, N (Eq. (N27)), with its error,
/// and the fine cell masses `u` less it: each cell gives up its share of
/// the atom (at most its mass), as the stationary split does.
fn split_held(
    u: &[f64],
    cells: &[Vec<(usize, f64)>],
    x: &[[f64; 3]],
) -> (Vec<(f64, f64)>, Vec<f64>) {
    let mut rest = u.to_vec();
    let split = cells
        .iter()
        .zip(x)
        .map(|(c, x)| {
            let (value, err, _) = richardson(x[0], x[1], x[2]);
            for &(k, f) in c {
                rest[k] -= (value * f).min(rest[k]).max(0.0);
            }
            (value, err)
        })
        .collect();
    (split, rest)
}

/// The atoms of one time: the held (velocity, state) masses summed per
/// velocity, their errors added.
fn merge_atoms(held: &[(f64, usize)], split: &[(f64, f64)]) -> Vec<VelocityAtom> {
    let mut out: Vec<VelocityAtom> = Vec::new();
    for (&(v, _), &(mass, err)) in held.iter().zip(split) {
        match out.iter_mut().find(|a| a.v == v) {
            Some(a) => {
                a.mass += mass;
                a.err += err;
            }
            None => out.push(VelocityAtom { v, mass, err }),
        }
    }
    out
}

/// Density mass + atoms = 1 at every time within the atoms' error and
/// [`MASS_TOLERANCE`] (the integration's conservation), or refused: a
/// cell that holds less than its share of an atom means the atom is not
/// resolved.
fn check_balance(
    times: &[f64],
    fine: &[FineAtoms],
    atoms: &dyn Fn(usize) -> Vec<VelocityAtom>,
) -> Result<()> {
    for (k, (t, f)) in times.iter().zip(fine).enumerate() {
        let a = atoms(k);
        let (mass, err) = a
            .iter()
            .fold((0.0, 0.0), |(m, e), a| (m + a.mass, e + a.err));
        let total = f.total + mass;
        if !((total - 1.0).abs() <= err + MASS_TOLERANCE) {
            return Err(Error::Numerical {
                method: "fp transient",
                reason: format!(
                    "at t = {t} the density ({:e}) and the atoms ({mass:e}) add up to {total}, not 1 \
                     within the atoms' error {err:e}; raise --cells",
                    f.total
                ),
            });
        }
    }
    Ok(())
}

/// The fine mesh's densities at time t, per state (round-off negatives
/// down to 1e-9 of the largest density set to 0; a larger one refused).
fn snapshot(op: &NoiseOperator, t: f64, u: &[f64], atoms: Vec<VelocityAtom>) -> Result<Snapshot> {
    let (ns, w) = (op.mesh.states, &op.mesh.widths);
    let scale = u
        .iter()
        .enumerate()
        .fold(0.0f64, |m, (k, x)| m.max(x.abs() / w[k / ns]));
    let mut states: Vec<Vec<f64>> = vec![Vec::with_capacity(w.len()); ns];
    for (k, &x) in u.iter().enumerate() {
        let d = x / w[k / ns];
        if !(d >= -1e-9 * scale) {
            return Err(Error::Numerical {
                method: "fp transient",
                reason: format!("a density of {d:e} at t = {t} (largest {scale:e}): the time integration lost positivity; raise --cells or lower --rtol"),
            });
        }
        states[k % ns].push(d.max(0.0));
    }
    let p = (0..w.len())
        .map(|i| states.iter().map(|s| s[i]).sum())
        .collect();
    Ok(Snapshot {
        t,
        p,
        p_plus: Vec::new(),
        p_minus: Vec::new(),
        states,
        atoms,
    })
}

/// One level of [`crate::fp::msd`] for a noise model: the moment chain
/// on the mesh refined `refine` times, the rows of [`observe`] at `times`
/// and the number of steps.
pub(crate) fn msd_level(
    p: &Params,
    o: &MsdOptions,
    times: &[f64],
    refine: usize,
) -> Result<(Vec<[f64; 6]>, usize)> {
    let tol = Tolerances {
        rtol: o.rtol,
        atol: o.rtol,
        ..Tolerances::default()
    };
    let mut rows = vec![[0.0; 6]; times.len()];
    let (steps, _) = run(p, o.cells, refine, 3, times, &tol, |k, v, u| {
        rows[k] = observe(v, 3, u);
        Ok(())
    })?;
    Ok((rows, steps))
}
