//! A finite-state noise chain with thermal noise in
//! [`super::transient`] (Eqs. (N28)-(N29)): the densities from v = 0 with
//! the noise state drawn from π, on the N-state operator
//! ([`crate::fp::nstate`]); `<v>` and `<v²>` extrapolated with their
//! observed order (Eq. (N27)), the held atoms (Eq. (N52)) split off the
//! fine mesh's cells. Periodic resetting moves all mass to the reset
//! target at every kT ([`TransientSpace::reset`]); an exponential
//! refractory period adds one held mass per noise state after the cells
//! ([`ChainOp`], docs/equations.md (R10)); at a point target their sum is
//! an atom at v_r beside the states' atoms.

use super::{
    integrate_levels, Scheme, Snapshot, Transient, TransientOptions, TransientSpace,
    MASS_TOLERANCE, MESH_LEVELS,
};
use crate::error::{Error, Result};
use crate::fp::extrapolate::richardson;
use crate::fp::nstate::{k_times, observe, operator, Blocks, HeldFactor, Hold, NoiseOperator};
use crate::fp::Mesh;
use crate::model::atoms::transient_atom_states;
use crate::model::noise::chain;
use crate::model::reset::Reset;
use crate::model::{Params, VelocityAtom};
use crate::numerics::trbdf2::{ShiftedLinear, Tolerances};
use crate::numerics::Failure;
use crate::parallel::Progress;

/// The held masses' solves, named in a failure.
const HELD: &str = "fp transient (held masses)";

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
    /// The current mesh's held block (an exponential refractory period).
    hold: Option<Hold>,
}

impl TransientSpace for ChainSpace<'_> {
    type Op = ChainOp;

    /// The mesh's operator and initial state: mass at v = 0 by π, nothing
    /// held.
    fn mesh(&mut self, level: usize) -> Result<(ChainOp, Vec<f64>)> {
        let op = operator(self.p, self.base, level, true)?;
        self.hold = Hold::of(self.p, &op);
        let b = Blocks::new(op, 1);
        self.cells = atom_cells(self.p, &b.op, &self.held);
        let mut u = b.initial()?;
        let held = self.hold.as_ref().map_or(0, |h| h.q.len());
        u.resize(u.len() + held, 0.0);
        self.v = b.v.clone();
        self.op = Some(b.op.clone());
        self.obs.push(vec![[0.0; 6]; self.all.len()]);
        self.atom_rows.push(vec![Vec::new(); self.all.len()]);
        let hold = self.hold.clone();
        Ok((
            ChainOp {
                b,
                hold,
                factor: None,
            },
            u,
        ))
    }

    /// A periodic reset at kT: each state's mass goes to the reset
    /// target's cells of the state the noise rule gives (kept: the same
    /// state; re-drawn: spread by π), as the Poisson reset re-injects it
    /// (Eq. (N20)).
    fn reset(&self, u: &mut [f64]) {
        let op = self.op.as_ref().expect("a reset comes after the mesh");
        let u = &mut u[..self.v.len()];
        let sums = op.state_sums(u);
        let mixed = op.noise.mix_states(&sums, &op.chain.pi);
        u.fill(0.0);
        op.add_target(&mixed, u);
    }

    /// Mass, `<v>`, `<v²>` with the held masses at their velocities, and
    /// the held mass (entry 3).
    fn observe(&mut self, level: usize, k: usize, u: &[f64]) -> Result<()> {
        let (u, q) = u.split_at(self.v.len());
        let mut o = observe(&self.v, 1, u);
        if let Some(h) = &self.hold {
            let (m, (a, b)) = (q.iter().sum::<f64>(), h.velocity_moments());
            o[0] += m;
            o[1] += m * a;
            o[2] += m * b;
            o[3] = m;
        }
        self.obs[level][k] = o;
        let arow: Vec<f64> = self.cells.iter().map(|c| held_mass(u, c)).collect();
        if level + 1 == MESH_LEVELS {
            let x: Vec<[f64; 3]> = (0..self.held.len())
                .map(|j| [self.atom_rows[0][k][j], self.atom_rows[1][k][j], arow[j]])
                .collect();
            let (split, rest) = split_held(u, &self.cells, &x);
            let hold = self.hold_atom(o[3], self.obs[level - 1][k][3]);
            let off_atom = if hold.is_some() { 0.0 } else { o[3] };
            self.fine_rows[k] = FineAtoms {
                split,
                hold,
                total: rest.iter().sum::<f64>() + off_atom,
            };
            if self.snaps.contains(&self.all[k]) {
                self.snapshots.push((self.all[k], rest));
            }
        }
        self.atom_rows[level][k] = arow;
        Ok(())
    }
}

impl ChainSpace<'_> {
    /// The held masses at a point target v_r as one atom (Eqs. (R10),
    /// (N53)):
    /// the fine mesh's total `fine`, its error the change from the mesh
    /// cells/2's `half` (as [`super::two_state`]'s hold), at least 1e-14
    /// of the mass. None without a hold or with a random target (its held
    /// mass is spread over the target's cells).
    fn hold_atom(&self, fine: f64, half: f64) -> Option<VelocityAtom> {
        let v = self.p.reset().point()?;
        self.hold.as_ref().map(|_| VelocityAtom {
            v,
            mass: fine,
            err: (fine - half).abs().max(1e-14 * fine),
        })
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
        hold: None,
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
    let atoms = |k: usize| merge_atoms(&c.held, &c.fine_rows[k]);
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
        params: p.clone(),
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
        refractory_mass: idx.iter().map(|&k| obs[2][k][3]).collect(),
        atoms: idx.iter().map(|&k| atoms(k)).collect(),
        mass_error_max: mass_err,
        snapshots: snaps,
    })
}

/// The fine mesh's atoms at one time: per held (velocity, state) the
/// extrapolated mass and its error, the refractory hold at a point target,
/// and the mass of the rest (the cells without the atoms, and the held
/// masses of a random target).
#[derive(Clone, Debug, Default)]
struct FineAtoms {
    split: Vec<(f64, f64)>,
    hold: Option<VelocityAtom>,
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

/// The atoms of one time: the held (velocity, state) masses and the
/// refractory hold summed per velocity, their errors added.
fn merge_atoms(held: &[(f64, usize)], fine: &FineAtoms) -> Vec<VelocityAtom> {
    let mut out: Vec<VelocityAtom> = Vec::new();
    let split = held
        .iter()
        .zip(&fine.split)
        .map(|(&(v, _), &(m, e))| (v, m, e));
    let hold = fine.hold.iter().map(|a| (a.v, a.mass, a.err));
    for (v, mass, err) in split.chain(hold) {
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

/// The chain's operator: the N-state operator ([`Blocks`], one block)
/// and, with an exponential refractory period, one held mass q_s per
/// noise state after the cells (docs/equations.md, (R10)):
/// dq/dt = W r M − K q, K = κI − Qᵀ, the cells gaining κ q_s at state s's
/// target cells instead of the reset influx.
pub(super) struct ChainOp {
    b: Blocks,
    hold: Option<Hold>,
    factor: Option<HeldFactor>,
}

impl ChainOp {
    fn ns(&self) -> usize {
        self.b.op.mesh.states
    }

    fn factorise(&self, c: f64, kappa: f64) -> Result<HeldFactor> {
        HeldFactor::new(&self.b.op, c, kappa, HELD)
    }

    /// The held masses of `u` (after the cells) and the cells.
    fn split<'u>(&self, u: &'u [f64]) -> (&'u [f64], &'u [f64]) {
        u.split_at(self.b.op.dim())
    }

    fn solve_held(&mut self, kappa: f64, c: f64, b: &[f64], x: &mut [f64]) -> Result<()> {
        if !matches!(&self.factor, Some(f) if f.c == c) {
            self.factor = Some(self.factorise(c, kappa)?);
        }
        let (op, f) = (&self.b.op, self.factor.as_ref().expect("factorised above"));
        let d = op.dim();
        let (bx, bq) = b.split_at(d);
        let mut rhs = bx.to_vec();
        let lq = chain::solve(&f.ik, bq, HELD)?;
        op.add_target(
            &lq.iter().map(|y| c * kappa * y).collect::<Vec<_>>(),
            &mut rhs,
        );
        f.band.solve(&mut rhs);
        let t = f.g_times(op, kappa, &op.state_sums(&rhs), HELD)?;
        let u = chain::solve(
            &f.cap,
            &t.iter().map(|y| c * y).collect::<Vec<_>>(),
            "fp transient (capacitance)",
        )?;
        for (zs, us) in f.z.iter().zip(&u) {
            for (xi, zi) in rhs.iter_mut().zip(zs) {
                *xi += zi * us;
            }
        }
        let inf = op.influx(&op.state_sums(&rhs));
        let dq: Vec<f64> = bq.iter().zip(&inf).map(|(d, r)| d + c * r).collect();
        let q = chain::solve(&f.ik, &dq, HELD)?;
        x[..d].copy_from_slice(&rhs);
        x[d..].copy_from_slice(&q);
        Ok(())
    }
}

impl ShiftedLinear for ChainOp {
    fn dim(&self) -> usize {
        self.b.dim() + if self.hold.is_some() { self.ns() } else { 0 }
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        let Some(h) = &self.hold else {
            return self.b.apply(u, out);
        };
        let op = &self.b.op;
        let (x, q) = self.split(u);
        let d = x.len();
        op.apply(x, &mut out[..d]);
        let inf = op.influx(&op.state_sums(x));
        let back: Vec<f64> = q.iter().zip(&inf).map(|(q, r)| h.kappa * q - r).collect();
        op.add_target(&back, &mut out[..d]);
        let kq = k_times(&self.b.op.chain, h.kappa, q);
        for (s, o) in out[d..].iter_mut().enumerate() {
            *o = inf[s] - kq[s];
        }
    }

    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        let Some(kappa) = self.hold.as_ref().map(|h| h.kappa) else {
            return self.b.solve_shifted(c, b, x);
        };
        let fail =
            Failure::shifted_solve("fp shifted solve (I - cA) x = b (N states, held masses)", c)?;
        match self.solve_held(kappa, c, b, x) {
            Ok(()) if x.iter().all(|v| v.is_finite()) => Ok(()),
            _ => Err(fail),
        }
    }
}
