//! The first-passage-time distribution of a noise model, at temperature 0
//! and with thermal noise (docs/equations.md, "Backward equations for a
//! noise model", Eqs. (N37)-(N39) and (N49)-(N51)).
//!
//! The survival probabilities S_s(v, t) = P(T > t | v(0) = v, eta(0) = a_s)
//! obey the N coupled equations (N37)
//! dS_s/dt = (a_s - g) ∂_v S_s + Σ_s' Q_ss' (S_s' - S_s) - r S_s + r R_s,
//! R_s = S_s(v_r) (noise kept at a reset) or Σ_s' π_s' S_s'(v_r) (re-drawn;
//! a random target: the reset values weighted over its nodes), with
//! S_s(v_t, t) = 0 in the states whose flow crosses v_t (a_s > g(v_t), the
//! absorbed states of Eq. (N31)) and S(v, 0) = 1 below v_t. The reported
//! survival is S = Σ_s π_s S_s(v_0, t), f = -dS/dt.
//!
//! Atoms (Eq. (N38)): a particle started in an absorbed state s reaches
//! v_t at exactly its flow time T_f,s = ∫_{v_0}^{v_t} dv / (a_s - g) with
//! probability m_s = e^{-(q_s + r) T_f,s} (no jump, no reset before). With
//! A_s(v, t) = e^{-(q_s + r) t} H(T_f,s(v) - t) split off (exactly:
//! (∂_t - b_s ∂_v) A_s = -(q_s + r) A_s), the rest C = S - A obeys the same
//! equations with the bounded forcing (N39)
//! F_s = Σ_{s' ≠ s} Q_ss' A_s' + r R_s(A) and C_s(v, 0) = 1 - A_s(v, 0).
//! On the mesh each H(T_f,s'(v_i) - t) is averaged over node i's dual cell
//! (a linear ramp in t), so F is continuous in time.
//!
//! C is discretised by the monotone upwind scheme of the two-state code
//! (`mfpt/upwind.rs`): each state's row differences towards where its
//! drift b_s(v_i) = a_s - g(v_i) comes from (at a node where g jumps, the
//! side the state moves to), so S stays a probability; integrated in time
//! by the adaptive TR-BDF2 of [`crate::numerics::trbdf2`] (the reset values
//! by an N×N bordering, as Eq. (N35)). 2N extra unknowns carry
//! I_s = ∫_0^t C_s(v_0) ds and J_s = ∫_0^t I_s ds, so E(T_s) and E(T_s²)
//! follow from the time integration (the atoms' shares in closed form):
//! [`Distribution::mean`] and [`Distribution::mean_time_integral`] are
//! here the same number. The meshes, extrapolation, mixture and checks
//! are the driver's ([`super::distribution`]).
//!
//! An exponential refractory period of mean 1/κ (docs/equations.md,
//! (R15)) adds N held survivals H_s(t) after the integrals: a reset sends
//! the particle into the held phase (the noise rule applied), which the
//! noise leaves jumping and ends at rate κ in the state it has then, at the
//! reset velocity: dH_s/dt = Σ_s' Q_ss' (H_s' - H_s) + κ (ℓ_s(S) - H_s),
//! H_s(0) = W (the target's mass below v_t), and the reset values of the
//! free rows are H (kept) or Σ π H (re-drawn) instead of ℓ(S). The atoms'
//! reset share forces the H rows (κ ℓ_s(A)) instead of the free rows. The
//! shifted solve eliminates H = K_c⁻¹ (b_H + cκ ℓ(C)),
//! K_c = (1 + cκ) I - c Q: the border columns become U cκ K_c⁻¹.
//!
//! With thermal noise (T > 0, Eq. (N49)) the same time loop runs the
//! second-order equations dS_s/dt = T ∂²_v S_s + (a_s - g) ∂_v S_s +
//! Σ_s' Q_ss' (S_s' - S_s) - r S_s + r R_s, absorbed at v_t in every
//! state (diffusion reaches the target continuously: no atoms, no
//! forcing) and reflecting at the truncation of the mean solver (Eq.
//! (N33)). The rows are the mean
//! solver's exponentially fitted generator (`backward::thermal_generator`,
//! Eq. (N34)) on its mesh of cells / 2 (`backward::thermal_mesh`) and the
//! midpoint refinement; the v_t rows are algebraic (S_s = 0). On each mesh
//! the semi-discrete E(T) is the mean solver's τ on that mesh (Eq. (N50));
//! the extrapolated E(T) is checked against τ on `cells` cells within
//! 1e-3 τ + 2 `mean_error`. `atoms` is empty and `atom_time`, `atom_mass`
//! and `atom_spread` are 0 (no time is [`Distribution::smeared`]).

use super::super::backward::{
    extreme_states, mesh_on, moments_at_start, solve_on, BackwardOptions, Finite, Mesh, Moments,
    BARRIER,
};
use super::super::upwind::{exp_moments, node_drift};
use super::super::Problem;
use super::{hidden, landing_points, Distribution, Plan, Run, RunAtom};
use crate::error::Result;
use crate::model::noise::chain::{self, Chain};
use crate::model::reset::{NoiseAtReset, Refractory, Reset};
use crate::model::Drag;
use crate::numerics::band::Band;
use crate::numerics::trbdf2::{self, ShiftedLinear, Stats, Tolerances};
use crate::numerics::Failure;

const METHOD: &str = "first-passage distribution (noise model)";

/// One absorbed state's atom on a mesh: its decay q_s + r, its flow time
/// from v_0 and, per node, the times (up, lo) between which the dual
/// cell's average of H(T_f,s(v) - t) falls from 1 to 0.
struct AtomState {
    s: usize,
    kill: f64,
    time: f64,
    ramps: Vec<(f64, f64)>,
    /// The scheme's spread of the arrival from v_0 (standard deviation of
    /// the discrete transport's hypoexponential flow time).
    spread: f64,
}

impl AtomState {
    /// The dual-cell average of H(T_f(v_i) - t), linear between its ends.
    fn ramp(&self, i: usize, t: f64) -> f64 {
        let (up, lo) = self.ramps[i];
        if t <= up {
            1.0
        } else if t >= lo {
            0.0
        } else {
            (lo - t) / (lo - up)
        }
    }
}

/// ∫_x^y dv / (a - g(v)) by the 3-point Gauss-Legendre rule (a short piece
/// of a dual cell, where a - g > 0 and smooth).
fn piece_time<D: Drag>(g: D, a: f64, x: f64, y: f64) -> f64 {
    let (m, h) = (0.5 * (x + y), 0.5 * (y - x));
    let d = h * (0.6f64).sqrt();
    h * (5.0 / (a - g.force(m - d)) + 8.0 / (a - g.force(m)) + 5.0 / (a - g.force(m + d))) / 9.0
}

/// The atom of absorbed state s (level a) on mesh `m` of the canonical
/// problem `cp`, with decay `kill` = q_s + r.
fn atom_state(cp: &Problem, m: &Mesh, s: usize, a: f64, kill: f64) -> AtomState {
    let g = cp.params().drag();
    let v = &m.v;
    let n = v.len();
    // tm[i]: flow time from the midpoint below node i + 1; tn[i]: from node i.
    let (mut tn, mut tm) = (vec![0.0; n], vec![0.0; n]);
    for i in (0..n - 1).rev() {
        let mid = 0.5 * (v[i] + v[i + 1]);
        tm[i] = tn[i + 1] + piece_time(g.clone(), a, mid, v[i + 1]);
        tn[i] = tm[i] + piece_time(g.clone(), a, v[i], mid);
    }
    let ramps = (0..n)
        .map(|i| {
            let up = if i + 1 < n { tm[i] } else { 0.0 };
            let lo = if i > 0 { tm[i - 1] } else { tn[0] };
            (up, lo)
        })
        .collect();
    let spread = (m.start..n - 1)
        .map(|i| ((v[i + 1] - v[i]) / node_drift(g.clone(), a, v[i])).powi(2))
        .sum::<f64>()
        .sqrt();
    AtomState {
        s,
        kill,
        time: g.flow_time(a, cp.v0(), cp.vt()),
        ramps,
        spread,
    }
}

/// The semi-discrete survival equations M C' = A C + U ℓ(C) + F(t) of one
/// mesh (state-interleaved unknowns ns i + s), with the 2N integrals.
struct Survival {
    ns: usize,
    n: usize,
    mesh: Mesh,
    band: Band,
    /// Column j: the coefficient of the reset value ℓ_j(C) in each row.
    border: Vec<Vec<f64>>,
    algebraic: Vec<bool>,
    chain: Chain,
    rate: f64,
    redrawn: bool,
    atoms: Vec<AtomState>,
    reported: Vec<usize>,
    scales: (f64, f64),
    /// An exponential refractory period: (κ, W), the held survivals H_s
    /// after the integrals (module doc).
    hold: Option<(f64, f64)>,
    /// The absolute time at which the current integration started.
    t0: f64,
    cache: Option<Factored>,
}

/// M - cA factored, with B⁻¹(-c U'_j) and the capacitance matrix I + E
/// (U' = U, or U cκ K_c⁻¹ with a hold, K_c then kept).
struct Factored {
    c: f64,
    band: Band,
    z: Vec<Vec<f64>>,
    cap: Vec<Vec<f64>>,
    kc: Vec<Vec<f64>>,
}

/// The rows of one mesh: band (bandwidth N each side), border columns
/// (the coefficient of the reset value ℓ_j in each row) and the algebraic
/// (absorbed) rows.
type Rows = (Band, Vec<Vec<f64>>, Vec<bool>);

/// The monotone upwind rows of Eq. (N37) at T = 0 on mesh `m`; the states
/// `absorbed` at v_t take S_s(v_t) = 0 there (band entry -1).
fn upwind_rows(cp: &Problem, m: &Mesh, chain: &Chain, absorbed: &[bool]) -> Rows {
    let par = cp.params();
    let (g, rate) = (par.drag(), par.rate());
    let ns = chain.states();
    let nodes = m.v.len();
    let n = ns * nodes;
    let redrawn = par.reset().noise() == NoiseAtReset::Redrawn;
    let mut band = Band::new(n, ns, ns);
    let mut border = vec![vec![0.0; n]; ns];
    let mut algebraic = vec![false; n];
    for i in 0..nodes {
        for (s, &absorbed) in absorbed.iter().enumerate() {
            let row = ns * i + s;
            if i + 1 == nodes && absorbed {
                band.set(row, row, -1.0);
                algebraic[row] = true;
                continue;
            }
            let b = node_drift(g.clone(), chain.levels[s], m.v[i]);
            let w = if b > 0.0 && i + 1 < nodes {
                let w = b / (m.v[i + 1] - m.v[i]);
                band.set(row, row + ns, w);
                w
            } else if b < 0.0 && i > 0 {
                let w = -b / (m.v[i] - m.v[i - 1]);
                band.set(row, row - ns, w);
                w
            } else {
                0.0
            };
            for (j, &q) in chain.q[s].iter().enumerate() {
                if j != s && q != 0.0 {
                    band.set(row, ns * i + j, q);
                }
            }
            band.set(row, row, -w - chain.exit[s] - rate);
            for (j, col) in border.iter_mut().enumerate() {
                col[row] = match (redrawn, j == s) {
                    (true, _) => rate * chain.pi[j],
                    (false, true) => rate,
                    (false, false) => 0.0,
                };
            }
        }
    }
    (band, border, algebraic)
}

/// The thermal rows (Eq. (N49)) on mesh `m`: the fitted generator of
/// `mfpt::backward` (Eqs. (N32)-(N34), one code with the mean solver), its
/// band copied into bandwidth N (its stencil couples node i to i ± 1 and
/// the states of node i only).
fn thermal_rows(cp: &Problem, m: &Mesh, chain: &Chain) -> Rows {
    let gen = super::super::backward::thermal_generator(cp, chain, m);
    let ns = chain.states();
    let n = gen.band.dim();
    let mut band = Band::new(n, ns, ns);
    for i in 0..n {
        for j in gen.band.row_range(i) {
            let x = gen.band.get(i, j);
            if x != 0.0 {
                debug_assert!(i.abs_diff(j) <= ns, "thermal stencil wider than N");
                band.set(i, j, x);
            }
        }
    }
    (band, gen.border, gen.absorbed)
}

impl Survival {
    /// Assemble the rows on mesh `m`: the upwind rows of Eq. (N37) at
    /// T = 0, the fitted thermal generator of `mfpt::backward` with T > 0
    /// (Eq. (N49)).
    fn new(cp: &Problem, m: &Mesh, chain: &Chain, scales: (f64, f64)) -> Self {
        let par = cp.params();
        let rate = par.rate();
        let ns = chain.states();
        let n = ns * m.v.len();
        let redrawn = par.reset().noise() == NoiseAtReset::Redrawn;
        let absorbed = absorbed(cp, chain);
        let (band, border, algebraic) = if chain.temperature > 0.0 {
            thermal_rows(cp, m, chain)
        } else {
            upwind_rows(cp, m, chain, &absorbed)
        };
        let atoms = (0..ns)
            .filter(|&s| absorbed[s])
            .map(|s| atom_state(cp, m, s, chain.levels[s], chain.exit[s] + rate))
            .collect();
        let hold = match par.schedule().refractory {
            Some(Refractory::Exp { mean }) if rate > 0.0 => Some((
                1.0 / mean,
                m.weights.as_ref().map_or(1.0, |w| w.iter().sum()),
            )),
            _ => None,
        };
        Survival {
            ns,
            n,
            mesh: m.clone(),
            band,
            border,
            algebraic,
            chain: chain.clone(),
            rate,
            redrawn,
            atoms,
            reported: (0..ns).map(|s| ns * m.start + s).collect(),
            scales,
            hold,
            t0: 0.0,
            cache: None,
        }
    }

    /// The index of the first held survival (after the integrals).
    fn held(&self) -> usize {
        self.n + 2 * self.ns
    }

    /// The values the border columns multiply: the held survivals with a
    /// refractory period, else the reset values of the mesh unknowns.
    fn returns(&self, u: &[f64]) -> Vec<f64> {
        match self.hold {
            Some(_) => u[self.held()..self.held() + self.ns].to_vec(),
            None => (0..self.ns).map(|j| self.reset_value(u, j)).collect(),
        }
    }

    /// (Q y)_s = Σ_s' Q_ss' (y_s' - y_s).
    fn q_times(&self, y: &[f64]) -> Vec<f64> {
        (0..self.ns)
            .map(|s| {
                let q = &self.chain.q[s];
                (0..self.ns)
                    .filter(|&j| j != s)
                    .map(|j| q[j] * y[j])
                    .sum::<f64>()
                    - self.chain.exit[s] * y[s]
            })
            .collect()
    }

    /// K_c = (1 + cκ) I - c Q.
    fn held_matrix(&self, kappa: f64, c: f64) -> Vec<Vec<f64>> {
        (0..self.ns)
            .map(|i| {
                (0..self.ns)
                    .map(|j| match i == j {
                        true => 1.0 + c * (kappa + self.chain.exit[i]),
                        false => -c * self.chain.q[i][j],
                    })
                    .collect()
            })
            .collect()
    }

    /// The atoms' reset values per state at absolute time t: ℓ_s(A).
    fn atom_returns(&self, t: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.ns];
        for a in &self.atoms {
            let d = (-a.kill * t).exp();
            out[a.s] += d * self.mesh.reset_value(|k| a.ramp(k, t));
        }
        out
    }

    /// The initial state: C_s = 1 - A_s(v, 0) (0 in the absorbed states,
    /// 1 in the others; with T > 0 S_s = 1 but at v_t), the integrals 0.
    fn initial(&self) -> Vec<f64> {
        let mut u = vec![0.0; self.dim()];
        if let Some((_, w)) = self.hold {
            let h = self.held();
            u[h..].fill(w);
        }
        let atom: Vec<bool> = (0..self.ns)
            .map(|s| self.atoms.iter().any(|a| a.s == s))
            .collect();
        for (k, x) in u.iter_mut().take(self.n).enumerate() {
            if !atom[k % self.ns] && !self.algebraic[k] {
                *x = 1.0;
            }
        }
        u
    }

    /// The reset value ℓ_j of state j of the nodal vector x.
    fn reset_value(&self, x: &[f64], j: usize) -> f64 {
        self.mesh.reset_value(|k| x[self.ns * k + j])
    }

    /// out = A C + U ℓ(C) on the mesh unknowns (U H with a hold).
    fn apply_mesh(&self, u: &[f64], out: &mut [f64]) {
        let ell = self.returns(u);
        for (i, o) in out.iter_mut().enumerate().take(self.n) {
            let mut x = 0.0;
            for j in self.band.row_range(i) {
                x += self.band.get(i, j) * u[j];
            }
            for (col, l) in self.border.iter().zip(&ell) {
                x += col[i] * l;
            }
            *o = x;
        }
    }

    /// The forcing (Eq. (N39)) of the mesh rows at absolute time t.
    fn forcing_at(&self, t: f64, out: &mut [f64]) {
        let ns = self.ns;
        // Per atom: e^{-k t} and its reset value ℓ(A_s).
        let decay: Vec<f64> = self.atoms.iter().map(|a| (-a.kill * t).exp()).collect();
        let ell: Vec<f64> = self
            .atoms
            .iter()
            .zip(&decay)
            .map(|(a, d)| d * self.mesh.reset_value(|k| a.ramp(k, t)))
            .collect();
        let mut reset = vec![0.0; ns];
        // With a hold the atoms' reset share forces the held rows instead.
        let shared = if self.hold.is_some() {
            0
        } else {
            self.atoms.len()
        };
        for (a, l) in self.atoms.iter().zip(&ell).take(shared) {
            if self.redrawn {
                reset.iter_mut().for_each(|x| *x += self.chain.pi[a.s] * l);
            } else {
                reset[a.s] += l;
            }
        }
        for (row, o) in out.iter_mut().enumerate().take(self.n) {
            if self.algebraic[row] {
                *o = 0.0;
                continue;
            }
            let (i, s) = (row / ns, row % ns);
            let mut x = self.rate * reset[s];
            for (a, d) in self.atoms.iter().zip(&decay) {
                if a.s != s {
                    x += self.chain.q[s][a.s] * d * a.ramp(i, t);
                }
            }
            *o = x;
        }
    }

    /// dC_s/dt at v_0 per state, at absolute time t.
    fn rate_at_start(&self, u: &[f64], t: f64) -> Vec<f64> {
        let mut a = vec![0.0; self.n];
        let mut f = vec![0.0; self.n];
        self.apply_mesh(u, &mut a);
        self.forcing_at(t, &mut f);
        self.reported.iter().map(|&r| a[r] + f[r]).collect()
    }

    /// Per state: S_s(v_0, t) (atom included) and f_s(v_0, t) (the atom's
    /// continuous part smeared over the start node's dual cell).
    fn observe(&self, u: &[f64], t: f64) -> (Vec<f64>, Vec<f64>) {
        let mut s: Vec<f64> = self.reported.iter().map(|&r| u[r]).collect();
        let mut f: Vec<f64> = self.rate_at_start(u, t).iter().map(|d| -d).collect();
        for a in &self.atoms {
            let d = (-a.kill * t).exp();
            s[a.s] += if t < a.time { d } else { 0.0 };
            f[a.s] += a.kill * d * a.ramp(self.mesh.start, t);
        }
        (s, f)
    }

    /// Factor M - cA and the bordering for shift c.
    fn factor(&self, c: f64) -> std::result::Result<Factored, Failure> {
        let n = self.n;
        let mut b = Band::new(n, self.ns, self.ns);
        for i in 0..n {
            for j in self.band.row_range(i) {
                b.set(i, j, -c * self.band.get(i, j));
            }
            if !self.algebraic[i] {
                b.set(i, i, 1.0 + b.get(i, i));
            }
        }
        let bad = || Failure::NonFinite {
            method: METHOD,
            at: c,
        };
        b.factor().map_err(|_| bad())?;
        let (mut z, mut cap, mut kc) = (Vec::new(), Vec::new(), Vec::new());
        if self.rate > 0.0 {
            let border = match self.hold {
                Some((kappa, _)) => {
                    kc = self.held_matrix(kappa, c);
                    self.held_border(&kc, kappa, c).map_err(|_| bad())?
                }
                None => self.border.clone(),
            };
            z = border
                .iter()
                .map(|col| {
                    let mut y: Vec<f64> = col.iter().map(|x| -c * x).collect();
                    b.solve(&mut y);
                    y
                })
                .collect();
            cap = (0..self.ns)
                .map(|i| {
                    (0..self.ns)
                        .map(|j| f64::from(u8::from(i == j)) + self.reset_value(&z[j], i))
                        .collect()
                })
                .collect();
        }
        Ok(Factored {
            c,
            band: b,
            z,
            cap,
            kc,
        })
    }

    /// The border columns with the held rows eliminated: column k is
    /// Σ_j U_j G_jk, G = cκ K_c⁻¹ (column k of G: cκ K_c⁻¹ e_k).
    fn held_border(&self, kc: &[Vec<f64>], kappa: f64, c: f64) -> Result<Vec<Vec<f64>>> {
        let ns = self.ns;
        let mut out = vec![vec![0.0; self.n]; ns];
        for (k, col) in out.iter_mut().enumerate() {
            let mut e = vec![0.0; ns];
            e[k] = c * kappa;
            let g = chain::solve(kc, &e, METHOD)?;
            for (uj, gj) in self.border.iter().zip(&g) {
                for (o, x) in col.iter_mut().zip(uj) {
                    *o += x * gj;
                }
            }
        }
        Ok(out)
    }

    /// The held rows' share of the shifted solve: with b_H moved, the
    /// mesh right side gains c U K_c⁻¹ b_H.
    fn held_rhs(&self, kc: &[Vec<f64>], c: f64, bh: &[f64], out: &mut [f64]) -> Result<()> {
        let y = chain::solve(kc, bh, METHOD)?;
        for (uj, yj) in self.border.iter().zip(&y) {
            for (o, x) in out.iter_mut().zip(uj) {
                *o += c * x * yj;
            }
        }
        Ok(())
    }
}

impl ShiftedLinear for Survival {
    fn dim(&self) -> usize {
        self.n + 2 * self.ns + if self.hold.is_some() { self.ns } else { 0 }
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.apply_mesh(u, out);
        let (n, ns) = (self.n, self.ns);
        for s in 0..ns {
            out[n + s] = u[self.reported[s]];
            out[n + ns + s] = u[n + s];
        }
        if let Some((kappa, _)) = self.hold {
            let h = self.held();
            let qh = self.q_times(&u[h..h + ns]);
            for s in 0..ns {
                let ell = self.reset_value(u, s);
                out[h + s] = qh[s] + kappa * (ell - u[h + s]);
            }
        }
    }

    fn apply_mass(&self, u: &[f64], out: &mut [f64]) {
        out.copy_from_slice(u);
        for (o, &alg) in out.iter_mut().zip(&self.algebraic) {
            if alg {
                *o = 0.0;
            }
        }
    }

    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        if self
            .cache
            .as_ref()
            .map_or(true, |f| f.c.to_bits() != c.to_bits())
        {
            self.cache = Some(self.factor(c)?);
        }
        let fac = self.cache.as_ref().expect("factored above");
        let (n, ns) = (self.n, self.ns);
        let bad = || Failure::NonFinite {
            method: METHOD,
            at: c,
        };
        x[..n].copy_from_slice(&b[..n]);
        if self.hold.is_some() && self.rate > 0.0 {
            let h = self.held();
            self.held_rhs(&fac.kc, c, &b[h..h + ns], &mut x[..n])
                .map_err(|_| bad())?;
        }
        fac.band.solve(&mut x[..n]);
        if self.rate > 0.0 {
            let ell: Vec<f64> = (0..ns).map(|j| self.reset_value(&x[..n], j)).collect();
            let r = chain::solve(&fac.cap, &ell, METHOD).map_err(|_| Failure::NonFinite {
                method: METHOD,
                at: c,
            })?;
            for (zj, rj) in fac.z.iter().zip(&r) {
                x[..n]
                    .iter_mut()
                    .zip(zj)
                    .for_each(|(xi, zi)| *xi -= rj * zi);
            }
        }
        for s in 0..ns {
            x[n + s] = b[n + s] + c * x[self.reported[s]];
            x[n + ns + s] = b[n + ns + s] + c * x[n + s];
        }
        if let Some((kappa, _)) = self.hold {
            // H = K_c⁻¹ (b_H + cκ ℓ(C)).
            let h = self.held();
            let rhs: Vec<f64> = (0..ns)
                .map(|s| b[h + s] + c * kappa * self.reset_value(&x[..n], s))
                .collect();
            let y = chain::solve(&fac.kc, &rhs, METHOD).map_err(|_| bad())?;
            x[h..h + ns].copy_from_slice(&y);
        }
        Failure::check_finite(x, METHOD, c)
    }

    fn atol(&self, i: usize, atol: f64) -> f64 {
        match i.checked_sub(self.n) {
            None => atol,
            Some(k) if k < self.ns => atol * self.scales.0,
            Some(k) if k < 2 * self.ns => atol * self.scales.1,
            Some(_) => atol,
        }
    }

    fn rms_norm_with_max_over(&self) -> Option<&[usize]> {
        Some(&self.reported)
    }

    fn forcing(&self, t: f64, out: &mut [f64]) -> bool {
        if self.atoms.is_empty() {
            // No atom (T > 0): the survival equations are homogeneous.
            return false;
        }
        self.forcing_at(self.t0 + t, out);
        out[self.n..].fill(0.0);
        if let Some((kappa, _)) = self.hold {
            let h = self.held();
            for (o, l) in out[h..].iter_mut().zip(self.atom_returns(self.t0 + t)) {
                *o = kappa * l;
            }
        }
        true
    }
}

/// Integrate `op` from absolute time t to `next` (no observation).
fn advance(op: &mut Survival, u: &mut [f64], t: f64, next: f64, tol: &Tolerances) -> Result<Stats> {
    op.t0 = t;
    trbdf2::integrate(op, u, &[next - t], tol, |_, _, _| Ok(()))
}

/// The survival equations on one mesh (see the module doc).
fn run(cp: &Problem, m: &Mesh, chain: &Chain, plan: &Plan) -> Result<Run> {
    let Plan {
        times,
        tol,
        stop,
        scales,
    } = *plan;
    let mut op = Survival::new(cp, m, chain, scales);
    let view = Survival::new(cp, m, chain, scales);
    let mut u = op.initial();
    let tf = op.atoms.iter().map(|a| a.time).fold(0.0, f64::max);
    let all = landing_points(times, hidden(tf));
    // The first window past the grid: the latest atom, or τ without atoms.
    let horizon = if tf > 0.0 { tf } else { scales.0 };
    let targets: Vec<f64> = all.iter().map(|a| a.0).collect();
    let (mut s, mut f) = (Vec::new(), Vec::new());
    let mut stats = trbdf2::integrate(&mut op, &mut u, &targets, tol, |k, t, x| {
        if all[k].1 {
            let (a, b) = view.observe(x, t);
            s.push(a);
            f.push(b);
        }
        Ok(())
    })?;
    let t = targets.last().copied().unwrap_or(0.0);
    let top = |c: &(Survival, Vec<f64>), t: f64| {
        let s = view.observe(&c.1, t).0;
        s.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
    };
    let mut ctx = (op, u);
    let step = |c: &mut (Survival, Vec<f64>), t, next| advance(&mut c.0, &mut c.1, t, next, tol);
    let (t, st) = stop.finish(&mut ctx, t, horizon, top, step)?;
    stats += st;
    let (op, u) = ctx;
    let (n, ns) = (op.n, op.ns);
    let (mut mean, mut second): (Vec<f64>, Vec<f64>) = (0..ns)
        .map(|s| (u[n + s], 2.0 * (t * u[n + s] - u[n + ns + s])))
        .unzip();
    for a in &op.atoms {
        let (i, j) = exp_moments(a.kill, a.time.min(t));
        mean[a.s] += i;
        second[a.s] += 2.0 * j;
    }
    Ok(Run {
        s,
        f,
        exact_mean: mean.clone(),
        exact_second: second.clone(),
        mean,
        second,
        t_end: t,
        tail: view.observe(&u, t).0,
        stats,
        atoms: op
            .atoms
            .iter()
            .map(|a| RunAtom {
                s: a.s,
                time: a.time,
                kill: a.kill,
                spread: a.spread,
            })
            .collect(),
    })
}

/// The box scheme's moments (`mfpt::backward`) as [`Moments`]: the mixture
/// over the `user` chain's π, `tau_plus` / `tau_minus` its states of
/// highest / lowest level.
fn box_moments(problem: &Problem, cells: usize, user: &Chain) -> Result<Moments> {
    let (hi, lo) = extreme_states(&user.levels);
    let (t1, t2, cells) = match problem.params().schedule().refractory {
        // The box scheme gives the mean only with a hold ((R11)); the
        // second moments 2 T² until the distribution's own replace them.
        Some(_) => {
            let s = solve_on(problem, cells, BARRIER)?;
            let t2 = s.per_state.iter().map(|t| 2.0 * t * t).collect();
            (s.per_state, t2, s.cells)
        }
        None => moments_at_start(problem, cells)?,
    };
    let mix = |x: &[f64]| -> f64 { x.iter().zip(&user.pi).map(|(a, b)| a * b).sum() };
    let (tau, second) = (mix(&t1), mix(&t2));
    let var = |m2: f64, m: f64| m2 - m * m;
    let (variance, variance_plus, variance_minus) =
        (var(second, tau), var(t2[hi], t1[hi]), var(t2[lo], t1[lo]));
    Ok(Moments {
        tau,
        tau_plus: t1[hi],
        tau_minus: t1[lo],
        second,
        second_plus: t2[hi],
        second_minus: t2[lo],
        variance,
        variance_plus,
        variance_minus,
        cv: variance.sqrt() / tau,
        cv_plus: variance_plus.sqrt() / t1[hi],
        cv_minus: variance_minus.sqrt() / t1[lo],
        cells,
    })
}

/// What the backward equations of a noise model refuse (with T > 0: a
/// drag other than linear, tanh, tan, and tan with T > 1, by name).
pub(super) fn admissible(problem: &Problem) -> Result<Chain> {
    let chain = problem.params().chain()?;
    let (cp, _) = problem.canonical();
    super::super::backward::admissible(&cp)?;
    Ok(chain)
}

/// Whether each state's flow crosses v_t (a_s > g(v_t)): absorbed there,
/// and carrying an atom (Eqs. (N31), (N38)). None with T > 0: diffusion
/// reaches v_t continuously (every state is absorbed there, Eq. (N49),
/// and none carries an atom).
fn absorbed(cp: &Problem, chain: &Chain) -> Vec<bool> {
    if chain.temperature > 0.0 {
        return vec![false; chain.states()];
    }
    let g = cp.params().drag();
    chain
        .levels
        .iter()
        .map(|&a| a - g.force(cp.vt()) > 0.0)
        .collect()
}

/// The coarse mesh on `cells` cells, every fixed point inside a node
/// (with T > 0 the mean solver's, truncated as Eq. (N33)), for the
/// canonical problem `cp`.
fn coarse(cp: &Problem, chain: &Chain, cells: usize) -> Result<Mesh> {
    if chain.temperature > 0.0 {
        return super::super::backward::thermal_mesh(cp, cells);
    }
    let g = cp.params().drag();
    let (vl, vu) = cp.params().bounds();
    let stars: Vec<f64> = chain.levels.iter().map(|&a| g.inverse(a)).collect();
    mesh_on(cp, vl, vu, &stars, cells)
}

impl super::Survival for Finite {
    fn moments(&self, p: &Problem, opts: &BackwardOptions, user: &Chain) -> Result<Moments> {
        box_moments(p, opts.cells, user)
    }
    fn coarse(&self, cp: &Problem, cells: usize) -> Result<Mesh> {
        coarse(cp, &self.0, cells)
    }
    fn run(&self, cp: &Problem, m: &Mesh, plan: &Plan) -> Result<Run> {
        run(cp, m, &self.0, plan)
    }
    fn lists_atoms(&self) -> bool {
        true
    }
    /// 1e-3 τ plus the mesh error of E(T) at T = 0 (the box scheme is
    /// second order, its τ nearer the limit than the extrapolated E(T));
    /// with T > 0 twice that error (the fitted scheme is between first and
    /// second order in the mesh, so both the extrapolated E(T) and τ on
    /// `cells` cells are within `mean_error` of the limit).
    fn mean_tolerance(&self, d: &Distribution) -> f64 {
        let k = if self.0.temperature > 0.0 { 2.0 } else { 1.0 };
        1e-3 * d.moments.tau + k * d.mean_error
    }
}
