//! The Euler scheme with any finite-state noise and thermal noise
//! (docs/equations.md, "Euler schemes with a noise model", Eqs. (N15)-(N19)).
//!
//! One step n → n+1, in the order of the paper's kernel ([`super`]):
//! 1. observe (v_n, x_n) (record, window sums, histogram);
//! 2. x ← x + v·dt with the old velocity;
//! 3. with probability p = r·dt: v ← v_r and the noise state kept or
//!    re-drawn from π ([`Reset::draw_noise_state`]); otherwise the velocity
//!    step of state s, [`ThermalStep::step`]: the explicit step
//!    v + dt (a_s - g(v)) at T = 0 (Eq. (N16)), Euler-Maruyama
//!    v + dt (a_s - g(v)) + sqrt(2 T dt) ξ at T > 0 for linear and tanh
//!    drag, the drift-implicit step for every other law at T > 0 (Eq. (N17));
//! 4. the noise state moves by the one-step transition matrix
//!    P = exp(Q dt) (Eq. (N15)): it leaves s with probability 1 - P_ss, to
//!    s' with probability P_ss'.
//!
//! Step 4 samples the noise chain exactly at the step times (for the
//! paper's two states P_{+-} = ½(1 - e^{-2λ dt}), Eq. (32), so the paper's
//! noise spelt as a generator runs the same Markov chain as the default
//! kernel). Particles start at x = v = 0 in a state drawn from π.
//!
//! These steps run in the scalar scheduled loop of [`super`] (the one the
//! paper's noise runs with a schedule modifier), not the paper's SIMD
//! kernel, so the default path stays bit-identical and as fast; so every
//! modifier of the resetting rule runs with them: step 3's reset is also
//! the periodic or renewal one, a refractory hold keeps v with no drift
//! (and no ξ) while step 4 goes on, and a position reset sets x.

use super::{euler_step, geometric_gap, EulerPlan, Events, Frame, NoiseSteps};
use crate::error::{Error, Result};
use crate::model::noise::chain::Chain;
use crate::model::reset::Reset;
use crate::model::{Drag, Params};
use crate::numerics::root::solve_increasing;
use crate::rng::Rng;
use crate::sim::{Observables, SimSpec};
use rand::Rng as _;

/// The noise chain over one step: P = exp(Q dt) (Eq. (N15)).
#[derive(Clone, Debug)]
pub struct StepChain {
    /// Levels a_s.
    pub levels: Vec<f64>,
    /// 1 - P_ss: the probability of leaving s in one step.
    pub leave: Vec<f64>,
    /// ln P_ss (the geometric gaps of the stay in s; 0 for an absorbing
    /// one-state chain, which never leaves).
    pub ln_stay: Vec<f64>,
    /// Per state, the cumulative P_ss' over s' ≠ s, in state order.
    cum: Vec<Vec<(usize, f64)>>,
    /// The chain (π for the initial and re-drawn states).
    pub chain: Chain,
}

impl StepChain {
    /// P = exp(Q dt) of `chain` by scaling and squaring a Taylor series;
    /// checked: rows sum to 1 within 1e-12, entries ≥ -1e-15 (set to 0).
    pub fn new(chain: &Chain, dt: f64) -> Result<Self> {
        let p = expm(&chain.q, dt);
        let n = chain.states();
        let bad = p.iter().any(|row| {
            (row.iter().sum::<f64>() - 1.0).abs() > 1e-12 || row.iter().any(|&x| !(x >= -1e-15))
        });
        if bad {
            return Err(Error::Numerical {
                method: "Euler noise transition matrix exp(Q dt)",
                reason: format!("not a stochastic matrix: {p:?}"),
            });
        }
        let mut cum = Vec::with_capacity(n);
        let (mut leave, mut ln_stay) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for (s, row) in p.iter().enumerate() {
            let mut acc = 0.0;
            let mut c = Vec::new();
            for (j, &x) in row.iter().enumerate() {
                if j != s && x > 0.0 {
                    acc += x;
                    c.push((j, acc));
                }
            }
            leave.push(acc);
            ln_stay.push(if acc > 0.0 { (-acc).ln_1p() } else { 0.0 });
            cum.push(c);
        }
        Ok(StepChain {
            levels: chain.levels.clone(),
            leave,
            ln_stay,
            cum,
            chain: chain.clone(),
        })
    }

    /// The state a step that leaves s goes to, u uniform on [0, `leave[s]`).
    #[inline]
    pub fn dest(&self, s: usize, u: f64) -> usize {
        let c = &self.cum[s];
        c.iter().find(|&&(_, x)| u < x).unwrap_or(&c[c.len() - 1]).0
    }

    /// A state drawn from π (one uniform).
    #[inline]
    pub fn draw_stationary(&self, rng: &mut Rng) -> usize {
        self.chain.draw_stationary(rng.gen::<f64>())
    }
}

/// exp(A dt) for a small square matrix: A dt scaled by 2^-k to norm ≤ ¼,
/// Taylor series to 20 terms (error < ¼^21/21! relative), squared k times.
fn expm(a: &[Vec<f64>], dt: f64) -> Vec<Vec<f64>> {
    let n = a.len();
    let norm = a
        .iter()
        .map(|row| row.iter().map(|x| x.abs()).sum::<f64>())
        .fold(0.0f64, f64::max)
        * dt;
    let k = if norm > 0.25 {
        (norm / 0.25).log2().ceil() as i32
    } else {
        0
    };
    let scale = dt / 2f64.powi(k);
    let b: Vec<Vec<f64>> = a
        .iter()
        .map(|r| r.iter().map(|x| x * scale).collect())
        .collect();
    let id: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    // Horner: I + B (I + B/2 (I + B/3 (...))).
    let mut e = id.clone();
    for m in (1..=20).rev() {
        let be = matmul(&b, &e);
        e = (0..n)
            .map(|i| (0..n).map(|j| id[i][j] + be[i][j] / m as f64).collect())
            .collect();
    }
    for _ in 0..k {
        e = matmul(&e, &e);
    }
    e
}

fn matmul(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| (0..n).map(|k| a[i][k] * b[k][j]).sum())
                .collect()
        })
        .collect()
}

/// T of the noise model (0 for the paper's noise).
pub fn temperature(params: &Params) -> f64 {
    params.noise().map_or(0.0, |m| m.temperature())
}

/// Whether the Euler schemes take the drift-implicit step at T > 0
/// (Eq. (N17)): every law but linear and tanh, whose g' ≤ 1 everywhere
/// keeps explicit Euler-Maruyama stable for dt < 1; tan diverges at ±π/2
/// (an explicit step can jump past the bound) and the others grow
/// superlinearly or jump.
pub fn implicit_drift(params: &Params) -> bool {
    temperature(params) > 0.0 && !params.drag().explicit_thermal_step()
}

/// The velocity step of the Euler schemes with a noise model: explicit
/// (T = 0, Eq. (N16)), Euler-Maruyama (Eq. (N17), explicit drift) or
/// drift-implicit (Eq. (N17)).
#[derive(Clone, Copy, Debug)]
pub struct ThermalStep {
    /// Time step.
    pub dt: f64,
    /// sqrt(2 T dt), the standard deviation of the thermal kick.
    pub kick: f64,
    /// Drift-implicit step.
    pub implicit: bool,
    /// The drag's domain (-top, top) (±∞ for an unbounded law).
    pub top: f64,
}

impl ThermalStep {
    /// The step of `params` at time step dt.
    pub fn new(params: &Params, dt: f64) -> Self {
        let d = params.drag();
        ThermalStep {
            dt,
            kick: (2.0 * temperature(params) * dt).sqrt(),
            implicit: implicit_drift(params),
            top: d.inverse(d.force_limit()),
        }
    }

    /// v_{n+1} from v_n in a state of level a with the standard normal ξ
    /// (ignored at T = 0): explicit v + dt (a - g(v)) + sqrt(2 T dt) ξ, or
    /// the root w of w + dt g(w) = v + dt a + sqrt(2 T dt) ξ (unique: the
    /// left side increases from -∞ to ∞ over the domain), by the
    /// safeguarded Newton iteration of [`solve_increasing`]. NaN if that
    /// fails to converge (the engines check their results are finite).
    #[inline]
    pub fn step<D: Drag>(&self, f: &D, v: f64, a: f64, xi: f64) -> f64 {
        if !self.implicit {
            return euler_step(f, v, a, self.dt) + self.kick * xi;
        }
        let dt = self.dt;
        let c = v + dt * a + self.kick * xi;
        let h = |w: f64| (w + dt * f.force(w) - c, 1.0 + dt * f.derivative(w), 0.0);
        let (lo, hi) = if self.top.is_finite() {
            (-self.top, self.top)
        } else {
            // h(c) = dt g(c): the root lies between c and c - dt g(c).
            let e = c - dt * f.force(c);
            (c.min(e), c.max(e))
        };
        solve_increasing(&h, lo, hi, v.clamp(lo, hi), 1e-13, 1e-300).unwrap_or(f64::NAN)
    }
}

/// The largest Euler step with a noise model (Eq. (N18)): at T = 0 the
/// explicit step must keep v inside (v_l, v_u) = (g⁻¹(min a), g⁻¹(max a)):
/// dt < 1 / max(slope of [`Drag::euler_slope`] at max |a|, the steepest
/// secants (a_max - g(v))/(v_u - v) and (g(v) - a_min)/(v - v_l), sampled
/// at 4097 points, and the edge derivatives g'(v_l), g'(v_u)). By the mean
/// value theorem every secant is some g'(ξ) on the interval, so for the laws
/// whose [`Drag::euler_slope`] is max g' (all but those with an unbounded
/// g') the first term already bounds them and the paper's noise as a
/// generator gets the default bound [`Params::max_euler_dt`]; at T > 0 the
/// explicit laws (linear, tanh) need dt < 1 / max g' = 1, the
/// drift-implicit step any dt. Errors name `dt`.
pub fn check_noise_dt(params: &Params, dt: f64) -> Result<f64> {
    let dt = crate::error::finite("dt", dt)?;
    let max = max_noise_dt(params)?;
    if !(dt > 0.0 && dt < max) {
        return Err(Error::invalid(
            "dt",
            dt,
            format!(
                "0 < dt < {max} (the Euler step bound of noise {}: an explicit step must not \
                 leave the velocity interval)",
                params.noise().map(|m| m.spec()).unwrap_or_default()
            ),
        ));
    }
    Ok(dt)
}

/// [`check_noise_dt`]'s bound (∞ for the drift-implicit step).
pub fn max_noise_dt(params: &Params) -> Result<f64> {
    if implicit_drift(params) {
        return Ok(f64::INFINITY);
    }
    let chain = params.chain()?;
    let top = chain.levels.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let d = params.drag();
    let slope = if chain.temperature > 0.0 {
        d.max_derivative(top)
    } else {
        let (lo, hi) = params.bounds();
        let a_hi = chain
            .levels
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let a_lo = chain.levels.iter().copied().fold(f64::INFINITY, f64::min);
        let mut m = d
            .euler_slope(top)
            .max(d.derivative(lo))
            .max(d.derivative(hi));
        let n = 4096;
        for i in 0..=n {
            let v = lo + (hi - lo) * i as f64 / n as f64;
            if v < hi {
                m = m.max((a_hi - d.force(v)) / (hi - v));
            }
            if v > lo {
                m = m.max((d.force(v) - a_lo) / (v - lo));
            }
        }
        m
    };
    Ok(1.0 / slope)
}

/// The constants of one N-state run: the noise's steps of the scheduled
/// loop ([`super::scheduled`]) and its frame.
pub(crate) struct NoiseKernel<'a, D> {
    f: &'a D,
    chain: StepChain,
    step: ThermalStep,
    pub(super) frame: Frame<'a>,
    /// Geometric jump gaps (else one Bernoulli draw per step).
    geometric: bool,
}

/// The noise state of one particle and its next jump step.
pub(crate) struct State {
    s: usize,
    next_jump: u64,
}

impl<D: Drag> NoiseKernel<'_, D> {
    /// The kernel of `params` (a noise model) for the plan.
    pub fn new<'a>(
        f: &'a D,
        params: &Params,
        spec: &SimSpec,
        plan: &'a EulerPlan,
        obs: &Observables,
        geometric: bool,
    ) -> Result<NoiseKernel<'a, D>> {
        let frame = Frame {
            plan,
            seed: spec.seed,
            reset: *params.reset(),
            schedule: params.schedule().clone(),
            lo: obs.v_lo,
            scale: spec.bins as f64 / (obs.v_hi - obs.v_lo),
            bins: spec.bins,
        };
        Self::with_frame(f, params, frame, geometric)
    }

    /// The kernel of `params` (a noise model) in the frame `frame`.
    pub(crate) fn with_frame<'a>(
        f: &'a D,
        params: &Params,
        frame: Frame<'a>,
        geometric: bool,
    ) -> Result<NoiseKernel<'a, D>> {
        let dt = frame.plan.dt;
        Ok(NoiseKernel {
            f,
            chain: StepChain::new(&params.chain()?, dt)?,
            step: ThermalStep::new(params, dt),
            frame,
            geometric,
        })
    }

    /// Enter state s at step n: its next jump step (geometric sampling).
    #[inline]
    fn enter(&self, s: usize, n: u64, rng: &mut Rng) -> State {
        let next_jump = if self.geometric {
            n.saturating_add(geometric_gap(rng, self.chain.ln_stay[s]) - 1)
        } else {
            0
        };
        State { s, next_jump }
    }
}

/// The steps of the module docs. The stream: the start state (one
/// uniform), the reset sampler's initial draws, the first jump gap; per
/// step the reset draws, the normal ξ (T > 0, drifting steps only), the
/// jump draws (every step, during a refractory hold too).
impl<D: Drag> NoiseSteps for NoiseKernel<'_, D> {
    type State = State;
    fn start<E: Events>(&self, rng: &mut Rng, plan: &EulerPlan) -> (State, E) {
        let s0 = self.chain.draw_stationary(rng);
        let ev = E::new(rng, plan);
        (self.enter(s0, 0, rng), ev)
    }
    fn drift(&self, v: f64, st: &State, rng: &mut Rng) -> f64 {
        let xi = if self.step.kick > 0.0 {
            rng.sample::<f64, _>(rand_distr::StandardNormal)
        } else {
            0.0
        };
        self.step.step(self.f, v, self.chain.levels[st.s], xi)
    }
    fn reset(&self, st: &mut State, n: u64, rng: &mut Rng) {
        let s = self
            .frame
            .reset
            .draw_noise_state(st.s, &self.chain.chain, rng);
        if s != st.s {
            *st = self.enter(s, n, rng);
        }
    }
    /// Step 4: does the state leave s in step n, and where to.
    fn jump<E: Events>(&self, st: &mut State, _ev: &mut E, n: u64, rng: &mut Rng) {
        let s = st.s;
        if self.geometric {
            if n == st.next_jump {
                let u = rng.gen::<f64>() * self.chain.leave[s];
                *st = self.enter(self.chain.dest(s, u), n + 1, rng);
            }
        } else {
            let u = rng.gen::<f64>();
            if u < self.chain.leave[s] {
                st.s = self.chain.dest(s, u);
            }
        }
    }
    fn rests(&self, v: f64, st: &State, obs: &Observables) -> bool {
        let level = self.chain.levels[st.s];
        obs.is_atom(v) && self.step.kick == 0.0 && self.step.step(self.f, v, level, 0.0) == v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::noise::NoiseModel;
    use crate::model::DragLaw;

    #[test]
    fn step_matrix_of_two_states_is_eq_32() {
        let m =
            NoiseModel::parse("states:levels=[1,-1],rates=[[-0.5,0.5],[0.5,-0.5]]", 0.0).unwrap();
        let dt = 0.01;
        let c = StepChain::new(&Chain::new(&m).unwrap(), dt).unwrap();
        let q = 0.5 * (-(-2.0 * 0.5 * dt).exp_m1());
        assert!((c.leave[0] - q).abs() < 1e-16, "{} {q}", c.leave[0]);
        assert_eq!(c.dest(0, 0.0), 1);
        // A large step: scaling and squaring.
        let c = StepChain::new(&Chain::new(&m).unwrap(), 30.0).unwrap();
        assert!((c.leave[1] - 0.5 * (-(-30.0f64).exp_m1())).abs() < 1e-13);
    }

    #[test]
    fn implicit_step_solves_its_equation_inside_the_domain() {
        let m = NoiseModel::parse("telegraph:sigma=1,lambda=0.5", 0.3).unwrap();
        let p = Params::with_noise(DragLaw::Tan, m, 0.0, 0.0).unwrap();
        let st = ThermalStep::new(&p, 0.05);
        assert!(st.implicit);
        for (v, xi) in [(1.5, 40.0), (-1.5, -40.0), (0.2, 0.3), (1.57, 1.0)] {
            let w = st.step(&crate::model::drag::Tan, v, 1.0, xi);
            assert!(w.abs() < std::f64::consts::FRAC_PI_2, "{w}");
            let c = v + 0.05 * 1.0 + st.kick * xi;
            assert!(
                (w + 0.05 * w.tan() - c).abs() < 1e-10 * c.abs().max(1.0),
                "{v} {xi}"
            );
        }
    }
}
