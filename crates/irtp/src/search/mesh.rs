//! The 2-D mesh of the search solvers and the upwind generator on it
//! (docs/equations.md, "Search: the 2-D backward equation and the renewal
//! route", discretisation).
//!
//! Nodes x_i (i < n_x) and v_j (j < n_v), both edges v_l, v_u included:
//! the upwind rows never reach past them (the + drift Sigma - g(v) vanishes
//! at v_u, the - drift at v_l, so the state that would leave has no
//! v-derivative term there). x is piecewise uniform between the
//! breakpoints (start, reset position, target ends), so they are nodes; on
//! a truncated far side a smooth geometric stretch x = x_b ∓ ℓ (e^{βs} - 1)
//! carries the mesh out to distance X. v is piecewise uniform between
//! v_l, v_r, 0, v_0, v_u. Doubling every count nests the meshes (the
//! stretch is uniform in s), so Richardson extrapolation applies.
//!
//! Unknowns are ordered x-column by x-column, (v_j, s) interleaved inside a
//! column (N noise states s, N = 2 for the paper's ±Sigma): the generator
//! is banded with N n_v sub- and super-diagonals. A noise state whose
//! fixed point v*_s = g⁻¹(a_s) lies inside (v_l, v_u) (the pause level
//! a = 0 at v = 0) has its drift a_s - g(v) change sign there: v*_s is a
//! node (a breakpoint of the layout), so each row is upwinded by the sign
//! of its own node's drift and no cell straddles a fixed point.
//!
//! An exponential refractory hold (docs/equations.md, (S13)) adds N held
//! unknowns to each x-column after its (v_j, s) ones: N (n_v + 1) sub- and
//! super-diagonals. The held velocity v_r is a v node.

use crate::error::{Error, Result};
use crate::model::reset::Reset;
use crate::model::Drag;
use crate::numerics::band::Band;
use crate::Params;

/// Which side of the x-domain ends where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Side {
    /// The target: x leaves the domain here (absorbing for v pointing out).
    Target,
    /// Truncation at distance X: zero gradient (the x-term of the rows
    /// whose velocity points out is dropped).
    Truncated,
}

/// What fixes a mesh before its refinement level: the x breakpoints (sorted)
/// with their cell counts, the far stretch, the v breakpoints and counts.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    /// x breakpoints, increasing; the first and last are the near ends.
    pub xb: Vec<f64>,
    /// Cells between consecutive x breakpoints.
    pub xc: Vec<usize>,
    /// Far stretch beyond one end: (below xb[0]?, length X, scale ℓ, cells).
    pub far: Option<Far>,
    /// Ends of the domain: (low, high).
    pub sides: (Side, Side),
    /// v breakpoints, increasing, from v_l to v_u.
    pub vb: Vec<f64>,
    /// Cells between consecutive v breakpoints.
    pub vc: Vec<usize>,
    /// Noise states N: the unknowns per (x, v) node.
    pub states: usize,
    /// An exponential refractory hold at the reset velocity (one held
    /// unknown per noise state in each x-column), or None.
    pub hold: Option<Hold>,
}

/// An exponential refractory hold (docs/equations.md, (S13)): after a
/// reset the velocity is held at `v` for an Exp time of rate `kappa`
/// (1/mean), x moving at `v` and the noise jumping on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hold {
    /// The release rate κ = 1/M.
    pub kappa: f64,
    /// The held velocity v_r (a v node).
    pub v: f64,
}

/// The geometric far stretch of a truncated side.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Far {
    /// True if it extends below the near part (the target is above).
    pub below: bool,
    /// Its length X.
    pub length: f64,
    /// Its scale ℓ (first cell ≈ ℓβ/cells).
    pub scale: f64,
    /// Its cells up to X.
    pub cells: usize,
    /// Cells continued beyond X on the same mapping (0 but for the
    /// truncation check).
    pub extra: usize,
}

/// Cell counts for the pieces between `breaks`, proportional to their
/// lengths, `total` in all (at least one each).
fn split(breaks: &[f64], total: usize) -> Vec<usize> {
    let span = breaks[breaks.len() - 1] - breaks[0];
    breaks
        .windows(2)
        .map(|w| (((w[1] - w[0]) / span * total as f64).round() as usize).max(1))
        .collect()
}

/// Sorted breakpoints with duplicates removed.
fn breakpoints(mut b: Vec<f64>) -> Vec<f64> {
    b.sort_by(f64::total_cmp);
    b.dedup();
    b
}

impl Layout {
    /// The layout of a domain whose near part spans `near` (start, reset
    /// position, target ends) with `cells_x` cells, ends `sides`, a far
    /// stretch of length `extent` (if a side is truncated) on the scale
    /// `scale`; v with `cells_v` cells between the breakpoints `v_points`
    /// (v_l and v_u added), `states` noise states per node.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        p: &Params,
        near: Vec<f64>,
        sides: (Side, Side),
        extent: f64,
        scale: f64,
        cells: (usize, usize),
        v_points: &[f64],
        states: usize,
    ) -> Layout {
        let xb = breakpoints(near);
        let xc = split(&xb, cells.0);
        let h = (xb[xb.len() - 1] - xb[0]) / cells.0 as f64;
        let far = match sides {
            (Side::Truncated, _) | (_, Side::Truncated) => {
                let beta = (1.0 + extent / scale).ln();
                Some(Far {
                    below: sides.0 == Side::Truncated,
                    length: extent,
                    scale,
                    cells: ((scale * beta / h).ceil() as usize).max(2),
                    extra: 0,
                })
            }
            _ => None,
        };
        let (vl, vu) = p.bounds();
        let mut v = vec![vl, vu];
        v.extend_from_slice(v_points);
        let vb = breakpoints(v);
        let vc = split(&vb, cells.1);
        Layout {
            xb,
            xc,
            far,
            sides,
            vb,
            vc,
            states,
            hold: None,
        }
    }

    /// Node counts (n_x, n_v) of the mesh [`Mesh::build`] makes at
    /// refinement `refine`, in f64: a layout too large for memory (or for
    /// usize) is sized here and refused by its cost, never built.
    pub fn nodes(&self, refine: u32) -> (f64, f64) {
        let k = 2f64.powi(refine as i32);
        let sum = |c: &[usize]| c.iter().map(|&n| n as f64).sum::<f64>();
        let far = self.far.map_or(0.0, |f| f.cells as f64 + f.extra as f64);
        ((sum(&self.xc) + far) * k + 1.0, sum(&self.vc) * k + 1.0)
    }

    /// The same layout with the far stretch continued (same mapping, same
    /// cells per unit of its parameter) to at least `factor` times its
    /// length: the mesh at X is part of the wider one, so the difference of
    /// their answers is the truncation's alone (the truncation check).
    pub fn widened(&self, factor: f64) -> Layout {
        let mut l = self.clone();
        if let Some(f) = l.far.as_mut() {
            let beta = (1.0 + f.length / f.scale).ln();
            let s_max = (1.0 + factor * f.length / f.scale).ln() / beta;
            f.extra = ((s_max - 1.0) * f.cells as f64).ceil() as usize;
        }
        l
    }
}

/// Nodes of pieces between `breaks` with `counts` cells each, times `k`.
fn piecewise(breaks: &[f64], counts: &[usize], k: usize) -> Vec<f64> {
    let mut x = vec![breaks[0]];
    for (w, &c) in breaks.windows(2).zip(counts) {
        let n = c * k;
        for m in 1..n {
            x.push(w[0] + (w[1] - w[0]) * m as f64 / n as f64);
        }
        x.push(w[1]);
    }
    x
}

/// The far stretch's nodes beyond `edge` (excluded), ordered away from it.
fn stretch(edge: f64, f: &Far, k: usize) -> Vec<f64> {
    let n = f.cells * k;
    let beta = (1.0 + f.length / f.scale).ln();
    let dir = if f.below { -1.0 } else { 1.0 };
    (1..=n + f.extra * k)
        .map(|m| {
            let d = if m == n {
                f.length
            } else {
                f.scale * (beta * m as f64 / n as f64).exp_m1()
            };
            edge + dir * d
        })
        .collect()
}

/// A mesh: nodes, ends, and the generator's layout.
#[derive(Clone, Debug)]
pub(crate) struct Mesh {
    /// x nodes, increasing.
    pub x: Vec<f64>,
    /// v nodes, increasing, v_l and v_u included.
    pub v: Vec<f64>,
    /// Ends of the domain: (low, high).
    pub sides: (Side, Side),
    /// Noise states N per node.
    pub states: usize,
    /// The hold and the index of its velocity's node, or None: then each
    /// x-column has one more slot after its v nodes, the held unknowns.
    pub hold: Option<(Hold, usize)>,
}

impl Mesh {
    /// The mesh of `layout` with every count multiplied by 2^`refine`.
    pub fn build(layout: &Layout, refine: u32) -> Mesh {
        let k = 1usize << refine;
        let mut x = piecewise(&layout.xb, &layout.xc, k);
        if let Some(f) = &layout.far {
            if f.below {
                let mut s = stretch(layout.xb[0], f, k);
                s.reverse();
                s.extend(x);
                x = s;
            } else {
                x.extend(stretch(layout.xb[layout.xb.len() - 1], f, k));
            }
        }
        let v = piecewise(&layout.vb, &layout.vc, k);
        // The held velocity is a breakpoint of the layout, hence a node.
        let hold = layout.hold.map(|h| {
            let j = v.iter().position(|&z| z == h.v);
            (h, j.expect("the held velocity is a v breakpoint"))
        });
        Mesh {
            x,
            v,
            sides: layout.sides,
            states: layout.states,
            hold,
        }
    }

    /// Slots per x-column: the v nodes, and one more with a hold.
    #[inline]
    fn slots(&self) -> usize {
        self.v.len() + usize::from(self.hold.is_some())
    }

    /// Number of unknowns, N n_x n_v (N n_x (n_v + 1) with a hold).
    pub fn unknowns(&self) -> usize {
        self.states * self.x.len() * self.slots()
    }

    /// Sub- (and super-) diagonals of the generator: N n_v (N (n_v + 1)
    /// with a hold).
    pub fn band(&self) -> usize {
        self.states * self.slots()
    }

    /// Index of node (x_i, v_j) in state s (the paper's noise: 0 is
    /// +Sigma, 1 is -Sigma).
    #[inline]
    pub fn idx(&self, i: usize, j: usize, s: usize) -> usize {
        (i * self.slots() + j) * self.states + s
    }

    /// Index of the held unknown at x_i in state s (after the column's v
    /// nodes); meaningful only with a hold.
    #[inline]
    pub fn held(&self, i: usize, s: usize) -> usize {
        (i * self.slots() + self.v.len()) * self.states + s
    }

    /// Whether node (i, j) lies on the target with a velocity pointing out:
    /// T = 0 there.
    pub fn absorbing(&self, i: usize, j: usize) -> bool {
        let last = self.x.len() - 1;
        (i == 0 && self.sides.0 == Side::Target && self.v[j] < 0.0)
            || (i == last && self.sides.1 == Side::Target && self.v[j] > 0.0)
    }

    /// Index of the node at exactly (x, v), or a typed error: the mesh
    /// places its breakpoints as nodes.
    pub fn node(&self, x: f64, v: f64) -> Result<(usize, usize)> {
        let find = |nodes: &[f64], y: f64| nodes.iter().position(|&z| z == y);
        match (find(&self.x, x), find(&self.v, v)) {
            (Some(i), Some(j)) => Ok((i, j)),
            _ => Err(Error::Numerical {
                method: "the search mesh (--cells-x, --cells-v)",
                reason: format!("no mesh node at (x, v) = ({x}, {v})"),
            }),
        }
    }
}

/// A velocity-only reset inside the generator: rate r, the target's node
/// weights and the noise rule's weights `mix[s][s']` (state s before, s'
/// after).
#[derive(Clone, Debug)]
pub(crate) struct LocalReset {
    /// Rate r.
    pub rate: f64,
    /// (j, w_j): the reset target on the v nodes ([`Mesh::target_weights`]).
    pub target: Vec<(usize, f64)>,
    /// mix[s][s']: probability of state s' after a reset from state s.
    pub mix: Vec<Vec<f64>>,
}

/// The noise as the search mesh runs it (Eq. (N1) at T = 0): levels a_s,
/// generator Q (rows summing to 0), stationary law π. The paper's noise is
/// (+Sigma, -Sigma) with Q_01 = Q_10 = lambda and π = (1/2, 1/2).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Noise {
    /// Levels a_s.
    pub levels: Vec<f64>,
    /// Generator Q: Q[s][s'] the rate of s → s' (s' ≠ s).
    pub q: Vec<Vec<f64>>,
    /// Stationary law π.
    pub pi: Vec<f64>,
    /// The mean jump rate Σ_s π_s q_s (the paper's: lambda), which sets
    /// the scale of the far stretch with the reset rate.
    pub rate: f64,
}

impl Noise {
    /// The noise of `p`: the paper's from Sigma and lambda, another model
    /// from its chain ([`Params::chain`]); a temperature is refused
    /// (naming it: the mesh has no diffusion in v).
    pub fn of(p: &Params, method: &str) -> Result<Noise> {
        let Some(m) = p.noise() else {
            let (s, l) = (p.sigma(), p.lambda());
            return Ok(Noise {
                levels: vec![s, -s],
                q: vec![vec![-l, l], vec![l, -l]],
                pi: vec![0.5, 0.5],
                rate: l,
            });
        };
        if m.temperature() > 0.0 {
            return Err(Error::invalid(
                "temperature",
                m.temperature(),
                format!("temperature 0 with --noise for {method} (no thermal noise on its mesh)"),
            ));
        }
        let c = p.chain()?;
        let rate = c.pi.iter().zip(&c.exit).map(|(p, q)| p * q).sum();
        Ok(Noise {
            levels: c.levels,
            q: c.q,
            pi: c.pi,
            rate,
        })
    }

    /// Number of states N.
    pub fn states(&self) -> usize {
        self.levels.len()
    }
}

impl Mesh {
    /// The reset target as weights on the v nodes: (j_r, 1) for a point
    /// target (v_r is a node), for a random one w_j = ∫ q φ_j, φ_j the hat
    /// function of node j (exact for T linear between nodes; normalised
    /// over (v_l, v_u)), zero weights dropped.
    pub fn target_weights(&self, p: &Params) -> Result<Vec<(usize, f64)>> {
        let reset = p.reset();
        if let Some(v) = reset.point() {
            let j = self.v.iter().position(|&z| z == v);
            return j.map(|j| vec![(j, 1.0)]).ok_or_else(|| Error::Numerical {
                method: "the search mesh (--cells-x, --cells-v)",
                reason: format!("no mesh node at v_r = {v}"),
            });
        }
        let target = reset.target();
        let (vl, vu) = p.bounds();
        let total = target.mass(vl, vu);
        let mut w = vec![0.0; self.v.len()];
        for (i, c) in self.v.windows(2).enumerate() {
            let mass = target.mass(c[0], c[1]);
            let upper = (target.moment_from(c[0], c[1]) / (c[1] - c[0])).clamp(0.0, mass);
            w[i] += (mass - upper) / total;
            w[i + 1] += upper / total;
        }
        Ok(w.into_iter()
            .enumerate()
            .filter(|(_, x)| *x > 0.0)
            .collect())
    }
}

/// The upwind generator A (a Markov generator: off-diagonal entries ≥ 0,
/// rows summing to 0) in compressed rows; absorbing rows are empty.
#[derive(Clone, Debug)]
pub(crate) struct Generator {
    start: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
    /// Per unknown: whether T = 0 is imposed there.
    pub absorbing: Vec<bool>,
    /// Per unknown: whether it is held (a refractory hold's unknown: no
    /// resets act on it).
    pub held: Vec<bool>,
    kl: usize,
}

impl Generator {
    /// Assemble the reset-free generator of docs/equations.md (search
    /// section) on `mesh`: upwind x- and v-transport, the noise's jumps
    /// (rates Q_ss'; the paper's flips at rate lambda), and a velocity-only
    /// reset if `local` is given (into the held unknowns with a hold).
    /// With a hold, each column's held rows follow its v nodes ((S13)).
    pub fn assemble(
        mesh: &Mesh,
        p: &Params,
        noise: &Noise,
        local: Option<&LocalReset>,
    ) -> Generator {
        let n = mesh.unknowns();
        let mut g = Generator {
            start: Vec::with_capacity(n + 1),
            col: Vec::with_capacity(6 * n),
            val: Vec::with_capacity(6 * n),
            absorbing: vec![false; n],
            held: vec![false; n],
            kl: mesh.band(),
        };
        g.start.push(0);
        let mut row: Vec<(usize, f64)> = Vec::with_capacity(8);
        for i in 0..mesh.x.len() {
            for j in 0..mesh.v.len() {
                for s in 0..mesh.states {
                    row.clear();
                    if mesh.absorbing(i, j) {
                        g.absorbing[mesh.idx(i, j, s)] = true;
                    } else {
                        upwind_row(mesh, p, noise, local, (i, j, s), &mut row);
                    }
                    g.push_row(&row);
                }
            }
            let Some((hold, jr)) = mesh.hold else {
                continue;
            };
            for s in 0..mesh.states {
                row.clear();
                let k = mesh.held(i, s);
                g.held[k] = true;
                if mesh.absorbing(i, jr) {
                    g.absorbing[k] = true;
                } else {
                    held_row(mesh, noise, (hold, jr), (i, s), &mut row);
                }
                g.push_row(&row);
            }
        }
        g
    }

    fn push_row(&mut self, row: &[(usize, f64)]) {
        for &(c, v) in row {
            self.col.push(c);
            self.val.push(v);
        }
        self.start.push(self.col.len());
    }

    /// Number of unknowns.
    pub fn dim(&self) -> usize {
        self.absorbing.len()
    }

    /// The band matrix `alpha I - beta A` (identity rows where absorbing),
    /// with `held_alpha` in place of `alpha` on the held rows (a full
    /// reset's loss rate is in `alpha`, and no reset acts during a hold).
    /// A stop request (SIGTERM) leaves it unfilled: the factorisation that
    /// follows polls the request at its first row and discards the run, so
    /// filling a large band (page faults under load) does not delay the stop.
    pub fn shifted_held(&self, alpha: f64, held_alpha: f64, beta: f64) -> Band {
        let n = self.dim();
        let mut b = Band::new(n, self.kl, self.kl);
        for k in 0..n {
            if k % crate::numerics::band::STOP_POLL_ROWS == 0 && crate::stop::stop_requested() {
                return b;
            }
            if self.absorbing[k] {
                b.set(k, k, 1.0);
                continue;
            }
            b.set(k, k, if self.held[k] { held_alpha } else { alpha });
            for e in self.start[k]..self.start[k + 1] {
                let c = self.col[e];
                b.set(k, c, b.get(k, c) - beta * self.val[e]);
            }
        }
        b
    }

    /// y = A x.
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        for (k, yk) in y.iter_mut().enumerate() {
            *yk = (self.start[k]..self.start[k + 1])
                .map(|e| self.val[e] * x[self.col[e]])
                .sum();
        }
    }
}

/// The entries of row (i, j, s) of the generator: transport in x at speed
/// v_j and in v at the drift a_s - g(v_j), each upwind (towards where the
/// motion goes: by the sign at the node, so on either side of a fixed
/// point v*_s towards it), the jumps s → s' at rate Q_ss', and the
/// velocity-only reset. The entries come in this order, the diagonal last
/// (the paper's noise: one flip at rate lambda).
fn upwind_row(
    mesh: &Mesh,
    p: &Params,
    noise: &Noise,
    local: Option<&LocalReset>,
    (i, j, s): (usize, usize, usize),
    row: &mut Vec<(usize, f64)>,
) {
    let k = mesh.idx(i, j, s);
    let mut diag = 0.0;
    let mut add = |row: &mut Vec<(usize, f64)>, c: usize, rate: f64| {
        row.push((c, rate));
        diag -= rate;
    };
    let v = mesh.v[j];
    if v > 0.0 && i + 1 < mesh.x.len() {
        add(row, mesh.idx(i + 1, j, s), v / (mesh.x[i + 1] - mesh.x[i]));
    } else if v < 0.0 && i > 0 {
        add(row, mesh.idx(i - 1, j, s), -v / (mesh.x[i] - mesh.x[i - 1]));
    }
    let b = p.drag().drift(noise.levels[s], v);
    if b > 0.0 && j + 1 < mesh.v.len() {
        add(row, mesh.idx(i, j + 1, s), b / (mesh.v[j + 1] - mesh.v[j]));
    } else if b < 0.0 && j > 0 {
        add(row, mesh.idx(i, j - 1, s), -b / (mesh.v[j] - mesh.v[j - 1]));
    }
    for (t, &q) in noise.q[s].iter().enumerate() {
        if t != s && q > 0.0 {
            add(row, mesh.idx(i, j, t), q);
        }
    }
    if let Some(r) = local {
        for t in 0..mesh.states {
            if mesh.hold.is_some() {
                // The reset starts a hold in state t ((S13)).
                if r.mix[s][t] > 0.0 {
                    add(row, mesh.held(i, t), r.rate * r.mix[s][t]);
                }
                continue;
            }
            for &(jr, w) in r.target.iter().filter(|_| r.mix[s][t] > 0.0) {
                add(row, mesh.idx(i, jr, t), r.rate * r.mix[s][t] * w);
            }
        }
    }
    row.push((k, diag));
}

/// The entries of the held row (i, s) ((S13)): transport in x at the held
/// velocity v_r, upwind (none for v_r = 0: the row is algebraic in x), the
/// noise's jumps s → s' between held unknowns at rate Q_ss', and the
/// release at rate κ to the node (x_i, v_r) in state s; the diagonal last.
fn held_row(
    mesh: &Mesh,
    noise: &Noise,
    (hold, jr): (Hold, usize),
    (i, s): (usize, usize),
    row: &mut Vec<(usize, f64)>,
) {
    let mut diag = 0.0;
    let mut add = |row: &mut Vec<(usize, f64)>, c: usize, rate: f64| {
        row.push((c, rate));
        diag -= rate;
    };
    let v = hold.v;
    if v > 0.0 && i + 1 < mesh.x.len() {
        add(row, mesh.held(i + 1, s), v / (mesh.x[i + 1] - mesh.x[i]));
    } else if v < 0.0 && i > 0 {
        add(row, mesh.held(i - 1, s), -v / (mesh.x[i] - mesh.x[i - 1]));
    }
    for (t, &q) in noise.q[s].iter().enumerate() {
        if t != s && q > 0.0 {
            add(row, mesh.held(i, t), q);
        }
    }
    add(row, mesh.idx(i, jr, s), hold.kappa);
    row.push((mesh.held(i, s), diag));
}
