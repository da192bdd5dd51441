//! The time-dependent survival equations on a monotone (upwind) scheme, with
//! the first-passage atom split off analytically; used by
//! [`super::distribution`].
//!
//! Canonical frame (target above the start, + state driving towards it).
//! The survival S±(v, t) obeys dS/dt = L S with the generator of
//! [`crate::mfpt`]. Its atom, the probability of no flip and no reset before
//! the deterministic flow reaches v_t, is
//! S_a+(v, t) = e^{-(lambda + r) t} H(T_f(v) - t) with T_f(v) the + flow time
//! from v to v_t, S_a- = 0. The transport part of L annihilates the jump of
//! S_a+ along its characteristic, so the remainder S_c = S - S_a solves
//!
//! dS_c+/dt = L S_c|+ + r S_a+(v_r, t),   dS_c-/dt = L S_c|- + lambda S_a+(v, t),
//!
//! when a reset keeps the noise state; when it re-draws it, the reset of the
//! atom returns r S_a+(v_r, t)/2 to each state's rows instead. For a random
//! target the reset value of S is its average over the target, Σ_j w_j S(v_j)
//! with the mesh's node weights, and so is the atom's: r S_a+(v_r, t) becomes
//! r e^{-(lambda + r) t} Σ_j w_j H(T_f(v_j) - t), the probability that the
//! flow from the landing velocity has not yet reached v_t (H averaged over
//! each node's dual cell, as below; a forcing continuous in time),
//!
//! from S_c+(v, 0) = 0, S_c-(v, 0) = 1, S_c+(v_t, t) = 0: consistent data,
//! bounded forcing, a continuous solution (kinks only). The exact S is
//! S_a + S_c; the atom itself is reported as a point mass, not smeared.
//!
//! Space: first-order upwind differences at the nodes (the + state looks
//! up the mesh, the - state down), an M-matrix: the semi-discrete flow
//! keeps 0 <= S_c and creates no oscillation (the box scheme of
//! [`super::backward`] has no dissipation and rings at grid scale after the
//! jump). At v_l the - drift vanishes and the - row is the regularity
//! relation by itself. The - forcing is averaged over each node's dual cell
//! (T_f taken linear inside it), so it switches off continuously in time.
//! For a point target the + forcing jumps for every row at once at
//! T_f(v_r); the integrator lands on that time
//! ([`UpwindOperator::set_reset_atom`]).
//! First order in h: [`super::distribution`] extrapolates two nested meshes.
//!
//! An exponential refractory period of mean 1/κ (docs/equations.md,
//! (R12)) adds two unknowns H± after the integrals: the survival of a
//! particle held at its reset velocity u (averaged over a random target's
//! nodes below v_t; a landing at or beyond v_t is a passage at the reset),
//! in the noise state ±. The reset terms of the free rows take H where
//! they took S(v_r) (through the same border columns), and
//! dH±/dt = κ (R±(S) - H±) + λ (H∓ - H±), H±(0) = W = Σ w_j (1 for a
//! point target), R± the reset values of S = S_a + S_c: the atom's share
//! enters the H+ row as the forcing κ S_a+(u, t), not the free rows.

use super::backward::Mesh;
use super::Problem;
use crate::model::reset::{NoiseAtReset, Refractory, Reset};
use crate::model::Drag;
use crate::numerics::band::Band;
use crate::numerics::bordered::{responses, LowRank};
use crate::numerics::quad::gk15;
use crate::numerics::trbdf2::ShiftedLinear;
use crate::numerics::Failure;

/// The name of the shifted solve in a failure (`at`: the shift c).
const METHOD: &str = "first-passage distribution: shifted solve (I - cA) x = b";

/// Unknowns: 2 per node (S_c+, S_c- interleaved) and four at v_0: the
/// running integrals I± = ∫ S_c±(v_0) dt and J± = ∫ I± dt.
pub(super) const EXTRA: usize = 4;

/// Values of the two start states (+, -).
pub(super) type Pair = (f64, f64);

/// dS_c/dt = A S_c + F(t) on a mesh (see the module doc).
pub(super) struct UpwindOperator {
    /// Mesh unknowns (2 per node).
    pub(super) n: usize,
    /// Index of the node v_0.
    pub(super) start: usize,
    /// Index of the node v_r.
    reset: usize,
    /// A random target's node weights ([`Mesh::weights`]).
    weights: Option<Vec<f64>>,
    a: Assembly,
    borders: bool,
    /// lambda and lambda + r.
    lam: f64,
    kill: f64,
    rate: f64,
    /// What a reset does to the noise state (shares of the atom's reset
    /// forcing between the + and - rows).
    noise: NoiseAtReset,
    /// T_f(v_r): the reset forcing r e^{-kill t} is on before it (+∞ for
    /// a random target, whose forcing is continuous in time).
    t_reset: f64,
    /// Whether the + forcing is on (the side of T_f(v_r) being integrated).
    reset_atom: bool,
    /// Per node: T_f at the upper and lower ends of its dual cell.
    ramps: Vec<(f64, f64)>,
    /// Offset of the integrator's clock (it starts at 0 on every call).
    pub(super) t0: f64,
    /// (c, factored I - cA, the correction by (I - cA)⁻¹ of -c times both
    /// border columns).
    cache: Option<(f64, Band, LowRank)>,
    /// Scales of the integrals I and J (tau, tau²), for their error weights.
    pub(super) scales: (f64, f64),
    /// The reported unknowns: S_c± at v_0 and the four integrals.
    reported: [usize; 2 + EXTRA],
    /// An exponential refractory period: (κ, W), the held unknowns H±
    /// at n + EXTRA (see the module doc).
    hold: Option<(f64, f64)>,
}

impl UpwindOperator {
    /// The operator on mesh `m` of the canonical problem `cp`.
    pub(super) fn new(cp: &Problem, m: &Mesh) -> Self {
        let par = cp.params();
        let (g, sigma) = (par.drag(), par.sigma());
        let tf = |v: f64| g.flow_time(sigma, v, cp.vt());
        let nodes = m.v.len();
        let dual: Vec<f64> = (0..=nodes)
            .map(|k| match k {
                0 => m.v[0],
                k if k == nodes => m.v[nodes - 1],
                k => 0.5 * (m.v[k - 1] + m.v[k]),
            })
            .map(tf)
            .collect();
        UpwindOperator {
            n: 2 * nodes,
            start: m.start,
            reset: m.reset,
            weights: m.weights.clone(),
            a: assemble(cp, m),
            borders: par.rate() > 0.0,
            lam: par.lambda(),
            kill: par.lambda() + par.rate(),
            rate: par.rate(),
            noise: par.reset().noise(),
            t_reset: if m.weights.is_some() {
                f64::INFINITY
            } else {
                tf(m.v[m.reset])
            },
            reset_atom: true,
            ramps: (0..nodes).map(|i| (dual[i + 1], dual[i])).collect(),
            t0: 0.0,
            cache: None,
            scales: (1.0, 1.0),
            reported: [
                2 * m.start,
                2 * m.start + 1,
                2 * nodes,
                2 * nodes + 1,
                2 * nodes + 2,
                2 * nodes + 3,
            ],
            hold: match par.schedule().refractory {
                Some(Refractory::Exp { mean }) if par.rate() > 0.0 => Some((
                    1.0 / mean,
                    m.weights.as_ref().map_or(1.0, |w| w.iter().sum()),
                )),
                _ => None,
            },
        }
    }

    /// Index of H+ (H- follows).
    fn held(&self) -> usize {
        self.n + EXTRA
    }

    /// What the border columns multiply: the held values H± with a
    /// refractory period, else the reset values of the mesh unknowns.
    fn reset_inputs(&self, u: &[f64]) -> (f64, f64) {
        match self.hold {
            Some(_) => (u[self.held()], u[self.held() + 1]),
            None => self.reset_values(u),
        }
    }

    /// K⁻¹ with K = m I + c (κ I - Q) the held rows of M - cA without
    /// their coupling to S (m = 1 with the mass, 0 without), Q the flips:
    /// K = [[a, -b], [-b, a]], a = m + c (κ + λ), b = c λ.
    fn held_inverse(&self, kappa: f64, c: f64, mass: bool) -> [[f64; 2]; 2] {
        let m = f64::from(u8::from(mass));
        let (a, b) = (m + c * (kappa + self.lam), c * self.lam);
        let det = (m + c * kappa) * (m + c * kappa + 2.0 * b);
        [[a / det, b / det], [b / det, a / det]]
    }

    /// The border columns the factored system sees, times -c: with a
    /// refractory period H = K⁻¹ (b_H + c κ R) eliminated, (c+, c-) c κ K⁻¹.
    fn border_columns(&self, c: f64, mass: bool) -> [Vec<f64>; 2] {
        let (cp, cm) = (&self.a.cp, &self.a.cm);
        let col = |x: f64, y: f64| -> Vec<f64> {
            cp.iter()
                .zip(cm)
                .map(|(a, b)| -c * (a * x + b * y))
                .collect()
        };
        let scaled = |col: &[f64]| col.iter().map(|x| -c * x).collect::<Vec<f64>>();
        match self.hold {
            None => [scaled(cp), scaled(cm)],
            Some((kappa, _)) => {
                let k = self.held_inverse(kappa, c, mass);
                let ck = c * kappa;
                [
                    col(ck * k[0][0], ck * k[1][0]),
                    col(ck * k[0][1], ck * k[1][1]),
                ]
            }
        }
    }

    /// Solve (M - cA) x = b on the mesh unknowns and the held ones (the
    /// integrals' rows excluded), `b` and `x` of the full dimension.
    fn solve_mesh(&self, c: f64, mass: bool, band: &Band, low: &LowRank, b: &[f64], x: &mut [f64]) {
        let n = self.n;
        x[..n].copy_from_slice(&b[..n]);
        let Some((kappa, _)) = self.hold else {
            band.solve(&mut x[..n]);
            self.remove_borders(&mut x[..n], low);
            return;
        };
        let (h, k) = (self.held(), self.held_inverse(kappa, c, mass));
        let kb = |y: [f64; 2]| {
            [
                k[0][0] * y[0] + k[0][1] * y[1],
                k[1][0] * y[0] + k[1][1] * y[1],
            ]
        };
        let z = kb([b[h], b[h + 1]]);
        for ((xi, a), b) in x[..n].iter_mut().zip(&self.a.cp).zip(&self.a.cm) {
            *xi += c * (a * z[0] + b * z[1]);
        }
        band.solve(&mut x[..n]);
        self.remove_borders(&mut x[..n], low);
        let (rp, rm) = self.reset_values(x);
        let y = kb([b[h] + c * kappa * rp, b[h + 1] + c * kappa * rm]);
        (x[h], x[h + 1]) = (y[0], y[1]);
    }

    /// T_f(v_r), where the + forcing switches off.
    pub(super) fn reset_atom_time(&self) -> f64 {
        self.t_reset
    }

    /// Integrate the side of T_f(v_r) before it (`on`) or after it.
    pub(super) fn set_reset_atom(&mut self, on: bool) {
        self.reset_atom = on;
    }

    /// The initial state: S_c+ = 0, S_c- = 1, integrals 0.
    pub(super) fn initial(&self) -> Vec<f64> {
        let mut u = vec![0.0; self.dim()];
        for k in (1..self.n).step_by(2) {
            u[k] = 1.0;
        }
        if let Some((_, w)) = self.hold {
            u[self.held()] = w;
            u[self.held() + 1] = w;
        }
        u
    }

    /// dS_c±/dt at v_0 (time `t` on the absolute clock).
    pub(super) fn rate_at_start(&self, u: &[f64], t: f64) -> (f64, f64) {
        let (p, m) = (2 * self.start, 2 * self.start + 1);
        let share = self.reset_atom_share(t);
        let (fp, fm) = self.forcing_rows((-self.kill * t).exp(), t, self.start, share);
        let at = self.reset_inputs(u);
        (self.row(u, p, at) + fp, self.row(u, m, at) + fm)
    }

    /// The atom's survival averaged over the reset target at absolute time
    /// t: S_a+(v_r, t) e^{(lambda + r) t}, H(T_f(v_r) - t) for a point
    /// target (1 on the side of T_f(v_r) being integrated), Σ_j w_j H_j(t)
    /// for a random one (H_j: the step averaged over node j's dual cell).
    fn reset_atom_share(&self, t: f64) -> f64 {
        match &self.weights {
            None => f64::from(u8::from(self.reset_atom)),
            Some(w) => w
                .iter()
                .enumerate()
                .map(|(j, wj)| wj * self.ramp(j, t))
                .sum(),
        }
    }

    /// H(T_f(v) - t) averaged over node i's dual cell (T_f linear in it).
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

    /// The reset values (x+, x-) of the mesh unknowns s: at the node v_r,
    /// or weighted over a random target's nodes.
    fn reset_values(&self, s: &[f64]) -> (f64, f64) {
        match &self.weights {
            None => (s[2 * self.reset], s[2 * self.reset + 1]),
            Some(w) => w.iter().enumerate().fold((0.0, 0.0), |(a, b), (j, wj)| {
                (a + wj * s[2 * j], b + wj * s[2 * j + 1])
            }),
        }
    }

    /// The forcing of rows (2i, 2i + 1) = (+, -) of node i at absolute time
    /// t, with decay = e^{-(lambda + r) t} and the target's atom `share`
    /// ([`UpwindOperator::reset_atom_share`]).
    fn forcing_rows(&self, decay: f64, t: f64, i: usize, share: f64) -> (f64, f64) {
        // With a hold the atom's reset share forces the H+ row instead.
        let (plus, minus) = if share > 0.0 && self.hold.is_none() {
            self.noise.mix(self.rate * decay * share, 0.0)
        } else {
            (0.0, 0.0)
        };
        let plus = if 2 * i + 2 < self.n { plus } else { 0.0 };
        (plus, self.lam * decay * self.ramp(i, t) + minus)
    }

    /// Row i of A s (band and the two reset columns), with the reset
    /// values `at` = [`UpwindOperator::reset_values`] of s.
    fn row(&self, s: &[f64], i: usize, at: (f64, f64)) -> f64 {
        let (rp, rm) = at;
        let mut x = 0.0;
        for j in self.a.band.row_range(i) {
            x += self.a.band.get(i, j) * s[j];
        }
        x + self.a.cp[i] * rp + self.a.cm[i] * rm
    }

    /// out = A s on the mesh unknowns.
    fn apply_mesh(&self, s: &[f64], out: &mut [f64]) {
        let at = self.reset_inputs(s);
        for (i, o) in out.iter_mut().enumerate().take(self.n) {
            *o = self.row(s, i, at);
        }
    }

    /// The time integrals of S_c± at v_0 over [0, ∞), exact for the
    /// semi-discrete system: integrating M S_c' = A S_c + F gives
    /// A X1 = -M S_c(0) - ∫F dt and A X2 = -M X1 - ∫t F dt with X1 = ∫S_c dt,
    /// X2 = ∫ t S_c dt (F in closed form). Returns ((X1+, X1-), (X2+, X2-)).
    pub(super) fn stationary_integrals(&self) -> std::result::Result<(Pair, Pair), Failure> {
        let dim = self.dim();
        let (f1, f2) = self.forcing_integrals();
        let mut mass = vec![0.0; dim];
        self.apply_mass(&self.initial(), &mut mass);
        // (0·M - 1·A) x = b solves -A x = b (the integrals' rows unused).
        let (band, low) = self.factor(1.0, false)?;
        let solve = |b: Vec<f64>| {
            let mut x = vec![0.0; dim];
            self.solve_mesh(1.0, false, &band, &low, &b, &mut x);
            x
        };
        let x1 = solve((0..dim).map(|i| mass[i] + f1[i]).collect());
        self.apply_mass(&x1, &mut mass);
        let x2 = solve((0..dim).map(|i| mass[i] + f2[i]).collect());
        let (p, q) = (2 * self.start, 2 * self.start + 1);
        Failure::check_finite(&x1, METHOD, f64::INFINITY)?;
        Failure::check_finite(&x2, METHOD, f64::INFINITY)?;
        Ok(((x1[p], x1[q]), (x2[p], x2[q])))
    }

    /// ∫_0^∞ F dt and ∫_0^∞ t F dt, row by row.
    fn forcing_integrals(&self) -> (Vec<f64>, Vec<f64>) {
        let k = self.kill;
        let (mut f1, mut f2) = (vec![0.0; self.dim()], vec![0.0; self.dim()]);
        // Per node: ∫ e^{-k t} H_i(t) t^m dt, m = 0, 1 (H_i: the atom's step
        // averaged over the dual cell, [`UpwindOperator::ramp`]).
        let atom: Vec<(f64, f64)> = self
            .ramps
            .iter()
            .map(|&(up, lo)| {
                let (a0, a1) = exp_moments(k, up);
                let ramp = |m: usize| {
                    if lo > up {
                        let f = |t: f64| (-k * t).exp() * (lo - t) / (lo - up) * t.powi(m as i32);
                        gk15(&f, up, lo).kronrod
                    } else {
                        0.0
                    }
                };
                (a0 + ramp(0), a1 + ramp(1))
            })
            .collect();
        let (r0, r1) = match &self.weights {
            None => exp_moments(k, self.t_reset),
            Some(w) => w
                .iter()
                .zip(&atom)
                .fold((0.0, 0.0), |(x, y), (wj, h)| (x + wj * h.0, y + wj * h.1)),
        };
        let (mut p0, mut m0) = self.noise.mix(self.rate * r0, 0.0);
        let (mut p1, mut m1) = self.noise.mix(self.rate * r1, 0.0);
        if let Some((kappa, _)) = self.hold {
            // The atom's reset share forces the H+ row ([`ShiftedLinear::forcing`]).
            (f1[self.held()], f2[self.held()]) = (kappa * r0, kappa * r1);
            (p0, m0, p1, m1) = (0.0, 0.0, 0.0, 0.0);
        }
        for (i, h) in atom.iter().enumerate() {
            if 2 * i + 2 < self.n {
                f1[2 * i] = p0;
                f2[2 * i] = p1;
            }
            f1[2 * i + 1] = self.lam * h.0 + m0;
            f2[2 * i + 1] = self.lam * h.1 + m1;
        }
        (f1, f2)
    }

    /// x -= R+ y1 + R- y2 with R± the reset values of the solution
    /// ([`UpwindOperator::reset_values`]) solved from the 2×2 system
    /// (bordering: the reset columns outside the band, [`LowRank`]).
    fn remove_borders(&self, x: &mut [f64], low: &LowRank) {
        if self.borders {
            let (p, m) = self.reset_values(x);
            low.correct(x, [p, m]);
        }
    }

    /// M - cA factored (M = I except the algebraic row of S_c+(v_t); no M
    /// when `mass` is false), and its inverse applied to -c times each
    /// border column.
    fn factor(&self, c: f64, mass: bool) -> std::result::Result<(Band, LowRank), Failure> {
        let n = self.n;
        let mut b = Band::new(n, 2, 2);
        for i in 0..n {
            for j in self.a.band.row_range(i) {
                b.set(i, j, -c * self.a.band.get(i, j));
            }
            if mass && i != n - 2 {
                b.set(i, i, 1.0 + b.get(i, i));
            }
        }
        b.factor().map_err(|_| Failure::NonFinite {
            method: METHOD,
            at: c,
        })?;
        let z = responses(|y| b.solve(y), self.border_columns(c, mass));
        let low = LowRank::standard(z, |y| {
            let (p, m) = self.reset_values(y);
            [p, m]
        });
        Ok((b, low))
    }
}

/// The drift of level `a` at node v: a - g(v), except at a jump of g at
/// v = 0, where a state moving up sees g(0+) and one moving down g(0-)
/// (and one held by static friction none).
pub(super) fn node_drift<D: Drag>(g: D, a: f64, v: f64) -> f64 {
    let jump = g.static_friction();
    if jump > 0.0 && v == 0.0 {
        if a - jump > 0.0 {
            a - jump
        } else if a + jump < 0.0 {
            a + jump
        } else {
            0.0
        }
    } else {
        a - g.force(v)
    }
}

/// The upwind operator on a mesh of the paper's noise, before any
/// right-hand side: the band part (unknowns interleaved tau+_0, tau-_0,
/// tau+_1, ...) and the two border columns multiplying the reset values
/// x±(v_r).
struct Assembly {
    /// The band part (unfactored).
    band: Band,
    /// Border column of x+(v_r).
    cp: Vec<f64>,
    /// Border column of x-(v_r).
    cm: Vec<f64>,
}

/// Upwind rows at the nodes: + rows look up the mesh, - rows down; the
/// last + row is the algebraic S_c+(v_t) = 0 (written -S = 0, so that
/// I - cA keeps a positive diagonal).
fn assemble(cp: &Problem, m: &Mesh) -> Assembly {
    let par = cp.params();
    let (g, sigma, lam, rate) = (par.drag(), par.sigma(), par.lambda(), par.rate());
    let noise = par.reset().noise();
    let nodes = m.v.len();
    let n = 2 * nodes;
    let mut a = Band::new(n, 2, 2);
    let (mut bp, mut bm) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..nodes {
        let (p, q) = (2 * i, 2 * i + 1);
        // Where g jumps at a node v = 0 (Coulomb friction), each state's
        // drift is its limit on the side it moves to: g(0+) for +, g(0-) for -.
        if i + 1 < nodes {
            let w = node_drift(g.clone(), sigma, m.v[i]) / (m.v[i + 1] - m.v[i]);
            a.set(p, p + 2, w);
            a.set(p, p, -w - lam - rate);
            a.set(p, q, lam);
            (bp[p], bm[p]) = noise.mix(rate, 0.0);
        } else {
            a.set(p, p, -1.0);
        }
        // The - drift -(Sigma + g) vanishes at v_l = -v_u (i = 0).
        let w = if i > 0 {
            (-node_drift(g.clone(), -sigma, m.v[i])).max(0.0) / (m.v[i] - m.v[i - 1])
        } else {
            0.0
        };
        if i > 0 {
            a.set(q, q - 2, w);
        }
        a.set(q, q, -w - lam - rate);
        a.set(q, p, lam);
        (bp[q], bm[q]) = noise.mix(0.0, rate);
    }
    Assembly {
        band: a,
        cp: bp,
        cm: bm,
    }
}

impl ShiftedLinear for UpwindOperator {
    fn dim(&self) -> usize {
        self.n + EXTRA + if self.hold.is_some() { 2 } else { 0 }
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.apply_mesh(u, out);
        let n = self.n;
        out[n] = u[2 * self.start];
        out[n + 1] = u[2 * self.start + 1];
        out[n + 2] = u[n];
        out[n + 3] = u[n + 1];
        if let Some((kappa, _)) = self.hold {
            let (h, (rp, rm)) = (self.held(), self.reset_values(u));
            let (hp, hm) = (u[h], u[h + 1]);
            out[h] = kappa * (rp - hp) + self.lam * (hm - hp);
            out[h + 1] = kappa * (rm - hm) + self.lam * (hp - hm);
        }
    }

    fn apply_mass(&self, u: &[f64], out: &mut [f64]) {
        out.copy_from_slice(u);
        out[self.n - 2] = 0.0;
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
            .map_or(true, |k| k.0.to_bits() != c.to_bits())
        {
            let (f, low) = self.factor(c, true)?;
            self.cache = Some((c, f, low));
        }
        let (_, f, low) = self.cache.as_ref().expect("factored above");
        let n = self.n;
        self.solve_mesh(c, true, f, low, b, x);
        // I - c S_c(v_0) = b_I, J - c I = b_J.
        x[n] = b[n] + c * x[2 * self.start];
        x[n + 1] = b[n + 1] + c * x[2 * self.start + 1];
        x[n + 2] = b[n + 2] + c * x[n];
        x[n + 3] = b[n + 3] + c * x[n + 1];
        Failure::check_finite(x, METHOD, c)
    }

    fn atol(&self, i: usize, atol: f64) -> f64 {
        // The integrals grow to tau and E[T²]/2: errors on their own scale.
        match i.checked_sub(self.n) {
            None => atol,
            Some(k) if k < 2 => atol * self.scales.0,
            Some(k) if k < EXTRA => atol * self.scales.1,
            Some(_) => atol,
        }
    }

    fn rms_norm_with_max_over(&self) -> Option<&[usize]> {
        // A node's forcing switches off within its cell's flow time: under
        // the max norm every such kink would set the step (steps ~ cells).
        Some(&self.reported)
    }

    fn forcing(&self, t: f64, out: &mut [f64]) -> bool {
        let t = self.t0 + t;
        let decay = (-self.kill * t).exp();
        let share = self.reset_atom_share(t);
        for i in 0..self.n / 2 {
            (out[2 * i], out[2 * i + 1]) = self.forcing_rows(decay, t, i, share);
        }
        out[self.n..].fill(0.0);
        if let Some((kappa, _)) = self.hold {
            // κ S_a+(u, t): the atom's share of the held particle's release.
            out[self.held()] = kappa * decay * share;
        }
        true
    }
}

/// (∫_0^T e^{-k t} dt, ∫_0^T t e^{-k t} dt), without cancellation for small
/// k T (series) and exact for T = ∞.
pub(super) fn exp_moments(k: f64, t: f64) -> (f64, f64) {
    let x = k * t;
    let first = -(-x).exp_m1() / k;
    // 1 - e^{-x}(1 + x) = x²/2 - x³/3 + x⁴/8 - x⁵/30 + ...
    let second = if x < 1e-2 {
        x * x * (0.5 - x * (1.0 / 3.0 - x * (0.125 - x / 30.0)))
    } else if x.is_finite() {
        1.0 - (-x).exp() * (1.0 + x)
    } else {
        1.0
    };
    (first, second / (k * k))
}

/// The upwind scheme's own image of the atom's step H(T_f(v_0) - t): the
/// pure transport dQ_i/dt = w_i (Q_{i+1} - Q_i), w_i = (Sigma - g(v_i))/h_i,
/// from Q = 1 below v_t and Q(v_t) = 0, read at v_0 (a hypoexponential
/// survival: mean the discrete flow time, spread ~ sqrt(h T_f)). The kink
/// of S_c+ at the atom's flow time is smeared by the scheme exactly as this
/// step is, so the continuous density is assembled as
/// f+ = (lambda + r) e^{-(lambda + r) t} Q(v_0, t) - dS_c+/dt: with the
/// exact step H instead, the two would not cancel and f would dip below 0
/// just after T_f.
pub(super) struct AtomProbe {
    /// Transport rates from v_0 up to the last node below v_t.
    w: Vec<f64>,
}

impl AtomProbe {
    /// The probe on mesh `m` of the canonical problem `cp`.
    pub(super) fn new(cp: &Problem, m: &Mesh) -> Self {
        let par = cp.params();
        let (g, sigma) = (par.drag(), par.sigma());
        let w = (m.start..m.v.len() - 1)
            .map(|i| node_drift(g.clone(), sigma, m.v[i]) / (m.v[i + 1] - m.v[i]))
            .collect();
        AtomProbe { w }
    }

    /// The spread of the scheme's arrival time from v_0: the standard
    /// deviation sqrt(Σ w_i⁻²) of the hypoexponential, the width in time
    /// over which the kink of S_c at T_f is smeared.
    pub(super) fn spread(&self) -> f64 {
        self.w.iter().map(|w| w.powi(-2)).sum::<f64>().sqrt()
    }

    /// Q = 1 at every node below v_t.
    pub(super) fn initial(&self) -> Vec<f64> {
        vec![1.0; self.w.len()]
    }
}

impl ShiftedLinear for AtomProbe {
    fn dim(&self) -> usize {
        self.w.len()
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        let m = self.w.len();
        for j in 0..m {
            let next = if j + 1 < m { u[j + 1] } else { 0.0 };
            out[j] = self.w[j] * (next - u[j]);
        }
    }

    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        // Upper bidiagonal: back substitution from the node below v_t.
        let mut next = 0.0;
        for j in (0..self.w.len()).rev() {
            let cw = c * self.w[j];
            next = (b[j] + cw * next) / (1.0 + cw);
            x[j] = next;
        }
        Ok(())
    }
}
