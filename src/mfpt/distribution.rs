//! The first-passage-time distribution from the time-dependent backward
//! equations.
//!
//! The survival probabilities S±(v, t) = P(T > t | v(0) = v, eta(0) = ±Sigma)
//! obey dS/dt = L S with the generator L of [`crate::mfpt`] (the simulated
//! drifts), S+(v_t, t) = 0 and regularity at v_l, S(v, 0) = 1 below v_t.
//! The box scheme of [`super::backward`] on the same mesh turns this into
//! M S' = A S, where A is the stationary operator (band + the two border
//! columns of the reset values) and M the midpoint-averaging mass matrix:
//! h (S_i' + S_{i+1}')/2 on the cell rows, -S-'(v_l) on the regularity row,
//! nothing on the algebraic row S+(v_t) = 0. Integrating M S' = A S from 0 to
//! ∞ gives A ∫S dt = -M S(0), the stationary equation A T1 = -M·1: with
//! M S(0) = M·1 the mean of the discrete distribution is the stationary tau
//! of the same mesh, exactly, and 2∫ t S dt = T2 from A T2 = -2 M T1.
//!
//! Time stepping: one backward-Euler step (M - t_1 A) S(t_1) = M·1 over a
//! tiny t_1 (it starts from M S(0) = M·1, which the algebraic row S+(v_t) = 0
//! cannot hold pointwise, and damps the resulting grid-scale modes), then
//! the adaptive L-stable TR-BDF2 of [`crate::numerics::trbdf2`]. Four extra
//! unknowns at v_0 carry the running integrals I± = ∫_0^t S± ds and
//! J± = ∫_0^t I± ds, so ∫_0^t S ds = I and ∫_0^t s S ds = t I - J.
//! The density f = -dS/dt is -M⁻¹ A S evaluated from the operator at the
//! output state (M inverted by its two bidiagonal recursions: the - state
//! upwards from the regularity row, the + state downwards from S+(v_t) = 0),
//! not by differences in time.
//!
//! The distribution has an atom: a particle started in the state driving
//! it towards the target arrives, with probability e^{-(lambda + r) T_f}, at
//! exactly the deterministic flow time T_f from v_0 to v_t (no flip and no
//! reset before). It is computed exactly ([`Distribution::atom_time`],
//! [`Distribution::atom_mass`]). KNOWN LIMITATION: the box scheme has no
//! numerical dissipation, and the jump of S+ at v_t that carries the atom
//! excites grid-scale modes which travel fast (the scheme's phase speed
//! diverges at the grid scale): at v_0 they appear as ripples BEFORE the
//! atom's flow time, with an amplitude that does not shrink with the mesh
//! (tan, Sigma = 3, lambda = 0.5, r = 2: at t = 0.53 T_f, f+ reaches -5.9
//! times max f at 1000 cells). Pointwise S±, f± for t < 1.3 T_f are
//! therefore unreliable (S can exceed 1, f can be negative), and
//! `irtp mfpt distribution` does not write them
//! ([`Distribution::pointwise_from`]); after the atom
//! they are monotone and converge with the mesh, interval probabilities
//! away from T_f agree with the exact sampler (chi-square,
//! `tests/fpt_distribution.rs`), and the moments are exact identities of
//! the mesh. Removing the atom analytically (S = S_atom + S_c, with S_c
//! continuous; the forcing is [`crate::numerics::trbdf2::ShiftedLinear::forcing`])
//! was tried: it removes the O(1) ripples at the default tolerance, but the
//! kinks U keeps still ring at grid scale once the time steps resolve them
//! (rtol 1e-5, 1000 cells: S - 1 up to 1.7e-4, f down to -0.008 max f), and
//! the split breaks the exact mean identity of the mesh; not adopted.
//!
//! After the output grid the integration continues, in doubling windows,
//! until S±(v_0) < `tail` or [`DistributionOptions::t_stop`]; the survival
//! left there, `tail_mass`, is the unresolved probability (reported).

use super::backward::{self, assemble, mesh, Assembly, BackwardOptions, Band, Mesh, Moments};
use super::Problem;
use crate::error::{Error, Result};
use crate::model::Drag;
use crate::numerics::trbdf2::{self, ShiftedLinear, Tolerances};
use crate::numerics::Failure;
use serde::{Deserialize, Serialize};

/// Pointwise S±, f± are reliable from this multiple of the atom's flow
/// time on (see the module doc): `irtp mfpt distribution` withholds the
/// rows before [`Distribution::pointwise_from`].
pub const POINTWISE_AFTER_ATOM: f64 = 1.3;

/// Options of [`distribution`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistributionOptions {
    /// Mesh (cells, drift convention) of the backward equations.
    pub backward: BackwardOptions,
    /// Relative tolerance of the time integration.
    pub rtol: f64,
    /// Absolute tolerance of S (probabilities).
    pub atol: f64,
    /// Integrate on after the output grid until S±(v_0) < tail ...
    pub tail: f64,
    /// ... or until this time (in units of tau when `None`: 1e3 tau).
    pub t_stop: Option<f64>,
}

impl Default for DistributionOptions {
    fn default() -> Self {
        DistributionOptions {
            backward: BackwardOptions::default(),
            rtol: 1e-4,
            atol: 1e-7,
            tail: 1e-10,
            t_stop: None,
        }
    }
}

impl DistributionOptions {
    /// Mesh valid; 1e-12 <= rtol <= 1e-2; 0 < atol, tail < 1.
    pub fn validate(&self) -> Result<()> {
        self.backward.validate()?;
        if !(self.rtol >= 1e-12 && self.rtol <= 1e-2) {
            return Err(Error::invalid("rtol", self.rtol, "1e-12 <= rtol <= 1e-2"));
        }
        if !(self.atol > 0.0 && self.atol < 1.0) {
            return Err(Error::invalid("atol", self.atol, "0 < atol < 1"));
        }
        if !(self.tail > 0.0 && self.tail < 1.0) {
            return Err(Error::invalid("tail", self.tail, "0 < tail < 1"));
        }
        Ok(())
    }
}

/// S±(v_0, t) and f±(v_0, t) on an output grid, with the moments.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Distribution {
    /// Output times.
    pub t: Vec<f64>,
    /// S = (S+ + S-)/2: survival of a uniformly random initial state.
    pub survival: Vec<f64>,
    /// S+ (start in +Sigma).
    pub survival_plus: Vec<f64>,
    /// S- (start in -Sigma).
    pub survival_minus: Vec<f64>,
    /// f = -dS/dt.
    pub density: Vec<f64>,
    /// f+ = -dS+/dt.
    pub density_plus: Vec<f64>,
    /// f- = -dS-/dt.
    pub density_minus: Vec<f64>,
    /// The stationary moments of the same mesh (L T1 = -1, L T2 = -2 T1).
    pub moments: Moments,
    /// ∫_0^t_end S dt: the mean from the time integration.
    pub mean: f64,
    /// Starting in +Sigma.
    pub mean_plus: f64,
    /// Starting in -Sigma.
    pub mean_minus: f64,
    /// 2 ∫_0^t_end t S dt: E(T²) from the time integration.
    pub second: f64,
    /// Where the time integration stopped.
    pub t_end: f64,
    /// S(v_0, t_end): probability not resolved by the time integration
    /// (the mean misses about tail_mass times the decay time).
    pub tail_mass: f64,
    /// The deterministic flow time T_f from v_0 to v_t, where the atom sits.
    pub atom_time: f64,
    /// Its mass in the mixture: half the mass of the driving start state.
    pub atom_mass: f64,
    /// Its mass starting in +Sigma (e^{-(lambda + r) T_f} for an upward
    /// target, 0 for a downward one).
    pub atom_mass_plus: f64,
    /// Its mass starting in -Sigma (0 for an upward target).
    pub atom_mass_minus: f64,
    /// Time steps taken (accepted).
    pub steps: usize,
    /// Steps rejected by the error control.
    pub rejected: usize,
}

impl Distribution {
    /// The first time where pointwise S, f are reliable:
    /// [`POINTWISE_AFTER_ATOM`] × `atom_time` (the moments hold regardless).
    pub fn pointwise_from(&self) -> f64 {
        POINTWISE_AFTER_ATOM * self.atom_time
    }
}

/// The name of the shifted solve in a failure (`at`: the shift c).
const METHOD: &str = "first-passage distribution: shifted solve (M - cA) x = b";

/// Unknowns: 2 per node (S+, S- interleaved) and four at v_0 (I+, I-, J+, J-).
const EXTRA: usize = 4;

/// M S' = A S on the mesh (see the module doc), with the integrals at v_0.
struct TimeOperator {
    /// Cell widths.
    h: Vec<f64>,
    /// Mesh unknowns (2 per node).
    n: usize,
    /// Index of v_0 and v_r (nodes).
    start: usize,
    reset: usize,
    /// A (unfactored band and border columns).
    a: Assembly,
    /// Whether the border columns are present (r > 0).
    borders: bool,
    /// (c, factored M - cA, (M - cA)⁻¹ of both border columns).
    cache: Option<(f64, Band, Vec<f64>, Vec<f64>)>,
    /// Scales of the integrals I and J (tau, tau²), for their error weights.
    scales: (f64, f64),
}

impl TimeOperator {
    fn new(cp: &Problem, m: &Mesh, opts: &BackwardOptions) -> Self {
        TimeOperator {
            h: m.v.windows(2).map(|w| w[1] - w[0]).collect(),
            n: 2 * m.v.len(),
            start: m.start,
            reset: m.reset,
            a: assemble(cp, m, cp.params().rate(), opts.drift),
            borders: cp.params().rate() > 0.0,
            cache: None,
            scales: (1.0, 1.0),
        }
    }

    /// M - cA factored, and its inverse applied to -c times each border column.
    fn factor(&self, c: f64) -> std::result::Result<(Band, Vec<f64>, Vec<f64>), Failure> {
        let n = self.n;
        let mut b = Band::new(n, 2, 2);
        for i in 0..n {
            for j in self.a.band.row_range(i) {
                b.set(i, j, -c * self.a.band.get(i, j));
            }
        }
        let mut add = |i: usize, j: usize, x: f64| {
            let y = b.get(i, j);
            b.set(i, j, y + x);
        };
        add(0, 1, -1.0);
        for (i, &h) in self.h.iter().enumerate() {
            add(2 * i + 1, 2 * i, 0.5 * h);
            add(2 * i + 1, 2 * i + 2, 0.5 * h);
            add(2 * i + 2, 2 * i + 1, 0.5 * h);
            add(2 * i + 2, 2 * i + 3, 0.5 * h);
        }
        b.factor().map_err(|_| Failure::NonFinite {
            method: METHOD,
            at: c,
        })?;
        let border = |col: &[f64]| {
            let mut y: Vec<f64> = col.iter().map(|x| -c * x).collect();
            b.solve(&mut y);
            y
        };
        let (y1, y2) = (border(&self.a.cp), border(&self.a.cm));
        Ok((b, y1, y2))
    }

    /// f = -dS/dt at the nodes of v_0: M f = -A S solved by the recursions
    /// of M (see the module doc); returns (f+, f-) at v_0.
    fn density_at_start(&self, s: &[f64]) -> (f64, f64) {
        let mut a_s = vec![0.0; self.n];
        self.apply_mesh(s, &mut a_s);
        let mut fm = a_s[0];
        for i in 0..self.start {
            fm = -2.0 * a_s[2 * i + 2] / self.h[i] - fm;
        }
        let mut fp = 0.0;
        for i in (self.start..self.h.len()).rev() {
            fp = -2.0 * a_s[2 * i + 1] / self.h[i] - fp;
        }
        (fp, fm)
    }

    /// out = A s on the mesh unknowns.
    fn apply_mesh(&self, s: &[f64], out: &mut [f64]) {
        let (kp, km) = (2 * self.reset, 2 * self.reset + 1);
        let (rp, rm) = (s[kp], s[km]);
        for (i, o) in out.iter_mut().enumerate().take(self.n) {
            let mut x = 0.0;
            for j in self.a.band.row_range(i) {
                x += self.a.band.get(i, j) * s[j];
            }
            *o = x + self.a.cp[i] * rp + self.a.cm[i] * rm;
        }
    }
}

impl ShiftedLinear for TimeOperator {
    fn dim(&self) -> usize {
        self.n + EXTRA
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.apply_mesh(u, out);
        let n = self.n;
        out[n] = u[2 * self.start];
        out[n + 1] = u[2 * self.start + 1];
        out[n + 2] = u[n];
        out[n + 3] = u[n + 1];
    }

    fn apply_mass(&self, u: &[f64], out: &mut [f64]) {
        let n = self.n;
        out[0] = -u[1];
        for (i, &h) in self.h.iter().enumerate() {
            out[2 * i + 1] = 0.5 * h * (u[2 * i] + u[2 * i + 2]);
            out[2 * i + 2] = 0.5 * h * (u[2 * i + 1] + u[2 * i + 3]);
        }
        out[n - 1] = 0.0;
        out[n..].copy_from_slice(&u[n..]);
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
            let (f, y1, y2) = self.factor(c)?;
            self.cache = Some((c, f, y1, y2));
        }
        let (_, f, y1, y2) = self.cache.as_ref().expect("factored above");
        let n = self.n;
        x[..n].copy_from_slice(&b[..n]);
        f.solve(&mut x[..n]);
        if self.borders {
            // x = y0 - R+ y1 - R- y2 with R± = x±(v_r): a 2×2 system.
            let (kp, km) = (2 * self.reset, 2 * self.reset + 1);
            let (a11, a12, a21, a22) = (1.0 + y1[kp], y2[kp], y1[km], 1.0 + y2[km]);
            let det = a11 * a22 - a12 * a21;
            let (rp, rm) = (
                (x[kp] * a22 - a12 * x[km]) / det,
                (a11 * x[km] - a21 * x[kp]) / det,
            );
            for k in 0..n {
                x[k] -= rp * y1[k] + rm * y2[k];
            }
        }
        // I - c S(v_0) = b_I, J - c I = b_J.
        x[n] = b[n] + c * x[2 * self.start];
        x[n + 1] = b[n + 1] + c * x[2 * self.start + 1];
        x[n + 2] = b[n + 2] + c * x[n];
        x[n + 3] = b[n + 3] + c * x[n + 1];
        if x.iter().any(|v| !v.is_finite()) {
            return Err(Failure::NonFinite {
                method: METHOD,
                at: c,
            });
        }
        Ok(())
    }

    fn atol(&self, i: usize, atol: f64) -> f64 {
        // The integrals grow to tau and E[T²]/2: errors on their own scale.
        match i.checked_sub(self.n) {
            None => atol,
            Some(k) if k < 2 => atol * self.scales.0,
            Some(_) => atol * self.scales.1,
        }
    }
}

/// Validate output times: finite, >= 0, increasing.
fn check_times(times: &[f64]) -> Result<()> {
    if times.is_empty() {
        return Err(Error::invalid("points", 0, "at least one output time"));
    }
    let ok =
        times.iter().all(|t| t.is_finite() && *t >= 0.0) && times.windows(2).all(|w| w[0] < w[1]);
    if !ok {
        return Err(Error::invalid(
            "t",
            format!("{:?}..", times[0]),
            "finite output times >= 0, increasing",
        ));
    }
    Ok(())
}

/// S±(v_0), f±(v_0) at the output times (canonical frame: + state first).
#[derive(Default)]
struct Record {
    t: Vec<f64>,
    s: Vec<(f64, f64)>,
    f: Vec<(f64, f64)>,
}

impl Record {
    fn push(&mut self, t: f64, s: (f64, f64), f: (f64, f64)) {
        self.t.push(t);
        self.s.push(s);
        self.f.push(f);
    }
}

/// The state at t_1 after one backward-Euler step from M S(0) = M·1.
fn start_state(op: &mut TimeOperator, t1: f64) -> Result<Vec<f64>> {
    let dim = op.dim();
    let mut one = vec![1.0; dim];
    one[op.n..].fill(0.0);
    let mut b = vec![0.0; dim];
    op.apply_mass(&one, &mut b);
    let mut u = vec![0.0; dim];
    op.solve_shifted(t1, &b, &mut u)?;
    Ok(u)
}

/// The first-passage-time distribution of `problem` at the output `times`
/// (see the module doc). Errors: invalid options or times;
/// [`Error::Overflow`] where the moments exceed the f64 range; a numerical
/// failure of the time integration.
pub fn distribution(
    problem: &Problem,
    times: &[f64],
    opts: &DistributionOptions,
) -> Result<Distribution> {
    opts.validate()?;
    check_times(times)?;
    let moments = backward::moments(problem, &opts.backward)?;
    let (cp, swapped) = problem.canonical();
    let m = mesh(&cp, opts.backward.cells)?;
    let mut op = TimeOperator::new(&cp, &m, &opts.backward);
    op.scales = (moments.tau, moments.second);
    // A second copy of A evaluates f while the integrator holds `op`.
    let view = TimeOperator::new(&cp, &m, &opts.backward);
    let start = 2 * m.start;
    // t_1 <= every positive output time; earlier output times are t = 0.
    let first = times.iter().copied().find(|&t| t > 0.0);
    let t1 = first.map_or(1e-9 * moments.tau, |t| t.min(1e-9 * moments.tau));
    let mut u = start_state(&mut op, t1)?;
    let mut rec = Record::default();
    for _ in times.iter().take_while(|&&t| t < t1) {
        rec.push(0.0, (1.0, 1.0), (0.0, 0.0));
    }
    let rest: Vec<f64> = times.iter().filter(|&&t| t >= t1).map(|t| t - t1).collect();
    let tol = Tolerances {
        rtol: opts.rtol,
        atol: opts.atol,
        ..Tolerances::default()
    };
    let (mut steps, mut rejected) = (0, 0);
    let mut observe = |_: usize, t: f64, x: &[f64]| -> Result<()> {
        rec.push(t + t1, (x[start], x[start + 1]), view.density_at_start(x));
        Ok(())
    };
    if !rest.is_empty() {
        let st = trbdf2::integrate(&mut op, &mut u, &rest, &tol, &mut observe)?;
        (steps, rejected) = (st.steps, st.rejected);
    }
    // On past the grid, in doubling windows, until the tail is small.
    let mut t = t1 + rest.last().copied().unwrap_or(0.0);
    let t_stop = opts.t_stop.unwrap_or(1e3 * moments.tau).max(t);
    while u[start].max(u[start + 1]) >= opts.tail && t < t_stop {
        let window = t.min(t_stop - t);
        let st = trbdf2::integrate(&mut op, &mut u, &[window], &tol, |_, _, _| Ok(()))?;
        (steps, rejected) = (steps + st.steps, rejected + st.rejected);
        t += window;
    }
    let n = op.n;
    let sw = |p: (f64, f64)| if swapped { (p.1, p.0) } else { p };
    let (i, j) = (sw((u[n], u[n + 1])), sw((u[n + 2], u[n + 3])));
    let second = |i: f64, j: f64| 2.0 * (t * i - j);
    let (sp, sm): (Vec<f64>, Vec<f64>) = rec.s.iter().map(|&p| sw(p)).unzip();
    let (fp, fm): (Vec<f64>, Vec<f64>) = rec.f.iter().map(|&p| sw(p)).unzip();
    let par = cp.params();
    let atom_time = par.drag().flow_time(par.sigma(), cp.v0(), cp.vt());
    let atom = sw(((-(par.lambda() + par.rate()) * atom_time).exp(), 0.0));
    let mean = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect();
    Ok(Distribution {
        survival: mean(&sp, &sm),
        density: mean(&fp, &fm),
        t: rec.t,
        survival_plus: sp,
        survival_minus: sm,
        density_plus: fp,
        density_minus: fm,
        moments,
        mean: 0.5 * (i.0 + i.1),
        mean_plus: i.0,
        mean_minus: i.1,
        second: 0.5 * (second(i.0, j.0) + second(i.1, j.1)),
        t_end: t,
        tail_mass: 0.5 * (u[start] + u[start + 1]),
        atom_time,
        atom_mass: 0.5 * (atom.0 + atom.1),
        atom_mass_plus: atom.0,
        atom_mass_minus: atom.1,
        steps,
        rejected,
    })
}
