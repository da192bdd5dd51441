//! A finite-state noise chain with thermal noise in
//! [`super::transient`] (Eqs. (N28)-(N29)): the densities from v = 0 with
//! the noise state drawn from π, on the N-state operator
//! ([`crate::fp::nstate`]); `<v>` and `<v²>` extrapolated with their
//! observed order (Eq. (N27)), the held atoms (Eq. (N52)) split off the
//! fine mesh's cells. Periodic resetting moves all mass to the reset
//! target at every kT ([`TransientSpace::reset`]).

use super::{
    integrate_levels, Scheme, Snapshot, Transient, TransientOptions, TransientSpace,
    MASS_TOLERANCE, MESH_LEVELS,
};
use crate::error::{Error, Result};
use crate::fp::extrapolate::richardson;
use crate::fp::nstate::{observe, operator, Blocks, NoiseOperator};
use crate::fp::Mesh;
use crate::model::atoms::transient_atom_states;
use crate::model::reset::Reset;
use crate::model::{Params, VelocityAtom};
use crate::numerics::trbdf2::Tolerances;
use crate::parallel::Progress;

/// The chain on the nested meshes of `base` << level cells: per mesh the
/// rows of [`observe`] and the held cells' masses at every output time;
/// on the fine mesh the atoms split off and the snapshots' states.
struct ChainSpace<'a> {
    p: &'a Params,
    base: usize,
    all: &'a [f64],
    snaps: &'a [f64],
    held: Vec<(f64, usize)>,
    obs: Vec<Vec<[f64; 6]>>,
    atom_rows: Vec<Vec<Vec<f64>>>,
    fine_rows: Vec<FineAtoms>,
    snapshots: Vec<(f64, Vec<f64>)>,
    /// The current mesh's unknown velocities and held cells.
    v: Vec<f64>,
    cells: Vec<Vec<(usize, f64)>>,
    /// The current mesh's operator (for the fine mesh's densities).
    op: Option<NoiseOperator>,
}

impl TransientSpace for ChainSpace<'_> {
    type Op = Blocks;

    fn mesh(&mut self, level: usize) -> Result<(Blocks, Vec<f64>)> {
        let b = Blocks::new(operator(self.p, self.base, level, true)?, 1);
        self.cells = atom_cells(self.p, &b.op, &self.held);
        let u = b.initial()?;
        self.v = b.v.clone();
        self.op = Some(b.op.clone());
        self.obs.push(vec![[0.0; 6]; self.all.len()]);
        self.atom_rows.push(vec![Vec::new(); self.all.len()]);
        Ok((b, u))
    }

    /// A periodic reset at kT: each state's mass goes to the reset
    /// target's cells of the state the noise rule gives (kept: the same
    /// state; re-drawn: spread by π), as the Poisson reset re-injects it
    /// (Eq. (N20)).
    fn reset(&self, u: &mut [f64]) {
        let op = self.op.as_ref().expect("a reset comes after the mesh");
        let sums = op.state_sums(u);
        let mixed = op.noise.mix_states(&sums, &op.chain.pi);
        u.fill(0.0);
        op.add_target(&mixed, u);
    }

    fn observe(&mut self, level: usize, k: usize, u: &[f64]) -> Result<()> {
        self.obs[level][k] = observe(&self.v, 1, u);
        let arow: Vec<f64> = self.cells.iter().map(|c| held_mass(u, c)).collect();
        if level + 1 == MESH_LEVELS {
            let x: Vec<[f64; 3]> = (0..self.held.len())
                .map(|j| [self.atom_rows[0][k][j], self.atom_rows[1][k][j], arow[j]])
                .collect();
            let (split, rest) = split_held(u, &self.cells, &x);
            self.fine_rows[k] = FineAtoms {
                split,
                total: rest.iter().sum(),
            };
            if self.snaps.contains(&self.all[k]) {
                self.snapshots.push((self.all[k], rest));
            }
        }
        self.atom_rows[level][k] = arow;
        Ok(())
    }
}

/// [`crate::fp::transient`] for a noise model at the recording times
/// `rec` and snapshot times `snaps` (validated): TR-BDF2 on the meshes of
/// cells/4, cells/2, cells cells, `<v>` and `<v²>` extrapolated with
/// their observed order (Eq. (N27)), snapshots of the fine mesh.
pub(super) fn transient(
    p: &Params,
    o: &TransientOptions,
    rec: &[f64],
    snaps: &[f64],
    progress: &dyn Progress,
) -> Result<Transient> {
    if o.scheme != Scheme::TrBdf2 {
        return Err(Error::invalid(
            "scheme",
            o.scheme.name(),
            "trbdf2 with a noise model (the paper's explicit scheme runs the paper's noise only)",
        ));
    }
    let times = super::merged(rec, snaps);
    let tol = Tolerances {
        rtol: o.rtol,
        atol: o.atol,
        ..Tolerances::default()
    };
    let mut c = ChainSpace {
        p,
        base: o.cells / 4,
        all: &times,
        snaps,
        held: transient_atom_states(p),
        obs: Vec::new(),
        atom_rows: Vec::new(),
        fine_rows: vec![FineAtoms::default(); times.len()],
        snapshots: Vec::new(),
        v: Vec::new(),
        cells: Vec::new(),
        op: None,
    };
    let resets = super::reset_times(p, rec, snaps);
    let steps = integrate_levels(&mut c, &tol, &times, &resets, progress)?.steps as u64;
    let mass_err = c
        .obs
        .iter()
        .flatten()
        .fold(0.0f64, |m, r| m.max((r[0] - 1.0).abs()));
    let op = c.op.take().expect("three meshes");
    let obs = &c.obs;
    let pick = |k: usize, j: usize| richardson(obs[0][k][j], obs[1][k][j], obs[2][k][j]);
    let atoms = |k: usize| merge_atoms(&c.held, &c.fine_rows[k].split);
    check_balance(&times, &c.fine_rows, &atoms)?;
    let idx: Vec<usize> = rec
        .iter()
        .map(|t| times.iter().position(|x| x == t).expect("a recording time"))
        .collect();
    let snapshots = std::mem::take(&mut c.snapshots);
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
        times: rec.to_vec(),
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
