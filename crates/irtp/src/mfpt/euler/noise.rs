//! Euler first passage with any finite-state noise and thermal noise
//! (docs/equations.md, "Euler schemes with a noise model", Eq. (N19)).
//!
//! The step is that of the simulation ([`crate::sim::euler::noise`]): the
//! velocity step of state s ([`ThermalStep`]: explicit at T = 0,
//! Euler-Maruyama or drift-implicit at T > 0), resets at rate r with the
//! noise state kept or re-drawn, the noise chain moved by P = exp(Q dt)
//! ([`StepChain`]). Step order of [`super`]: the step count, then a reset
//! (passage if the reset velocity is at or beyond v_t) or the velocity
//! step and its arrival check, then the noise jump. Particles start at v_0
//! in a state drawn from π, so tau is the π-averaged MFPT
//! Σ_s π_s tau_s(v_0); the even and odd particles (the `plus` and `minus`
//! halves of [`FptStats`]) are two independent halves of the same law.
//!
//! At T > 0 a passage between two monitored steps is detected by the
//! Brownian-bridge crossing probability: a step v_n → v_{n+1} < v_t
//! crossed v_t with probability exp(-(v_t - v_n)(v_t - v_{n+1}) / (T dt))
//! (the bridge of sqrt(2T) W over dt with the drift frozen), drawn with one
//! uniform where it exceeds e^-40. Without it the discretely monitored
//! passage time carries an O(sqrt(dt)) bias; with it the bias is O(dt) and
//! the dt-extrapolation of [`super::extrapolate`] applies.

use super::{EulerFpt, FptSample, FptStats};
use crate::model::reset::{Reset, ResetRule};
use crate::model::Drag;
use crate::parallel::{self, Progress};
use crate::rng::{self, Rng};
use crate::sim::euler::geometric_gap;
use crate::sim::euler::noise::{temperature, StepChain, ThermalStep};
use rand::Rng as _;
use std::ops::Range;

/// The constants of one run in the canonical (upward) frame.
struct Run<'a, D> {
    f: &'a D,
    chain: StepChain,
    step: ThermalStep,
    /// T dt (0 without thermal noise or with the bridge off: no bridge).
    t_dt: f64,
    /// Thermal noise (one normal per drifting step).
    kick_on: bool,
    v0: f64,
    vt: f64,
    reset: ResetRule,
    ln_reset: f64,
    max_steps: u64,
    seed: u64,
}

/// [`EulerFpt::units`] with a noise model.
pub(super) fn units(
    e: &EulerFpt,
    n: u64,
    units: Range<u64>,
    seed: u64,
    progress: &dyn Progress,
) -> Vec<FptStats> {
    let (p, _) = e.problem.canonical();
    let par = p.params();
    let dt = e.dt;
    // Validated when the EulerFpt was built (the same chain and dt).
    let chain = par
        .chain()
        .and_then(|c| StepChain::new(&c, dt))
        .expect("noise chain validated by EulerFpt::new");
    crate::with_drag!(par.drag(), |d| {
        let run = Run {
            f: d,
            chain: chain.clone(),
            step: ThermalStep::new(par, dt),
            t_dt: if e.bridge { temperature(par) * dt } else { 0.0 },
            kick_on: temperature(par) > 0.0,
            v0: p.v0(),
            vt: p.vt(),
            reset: *par.reset(),
            ln_reset: (-(par.rate() * dt)).ln_1p(),
            max_steps: (e.t_max / dt).floor() as u64,
            seed,
        };
        parallel::reduce_units(
            n,
            units.clone(),
            || FptStats::new(e.t_max),
            |lo, hi, acc| {
                for i in lo..hi {
                    acc.push(i % 2 == 0, run.particle(i));
                }
            },
            |a, b| a.merge(&b),
            progress,
        )
    })
}

impl<D: Drag> Run<'_, D> {
    /// The next jump step of a particle entering state s after step n.
    #[inline]
    fn enter(&self, s: usize, n: u64, rng: &mut Rng) -> u64 {
        n.saturating_add(geometric_gap(rng, self.chain.ln_stay[s]))
    }

    /// Particle i: its stream gives the start state (one uniform), the
    /// first reset gap, the first jump gap; per step the reset's draws or
    /// the normal ξ (T > 0) and the bridge uniform (when drawn), then the
    /// jump's draws.
    fn particle(&self, i: u64) -> FptSample {
        let dt = self.step.dt;
        let mut rng = rng::stream(self.seed, i);
        let mut s = self.chain.draw_stationary(&mut rng);
        let mut next_reset = geometric_gap(&mut rng, self.ln_reset);
        let mut next_jump = self.enter(s, 0, &mut rng);
        let mut v = self.v0;
        let mut step = 0u64;
        let arrived = |step: u64| FptSample {
            time: Some(step as f64 * dt),
            work: step,
        };
        loop {
            // Stopped (polled every few thousand steps): censored, in a
            // chunk the cancelled reduction discards.
            if step >= self.max_steps || crate::parallel::stop_due(step + 1) {
                return FptSample {
                    time: None,
                    work: step,
                };
            }
            step += 1;
            if step == next_reset {
                v = self.reset.draw_velocity(&mut rng);
                let s2 = self.reset.draw_noise_state(s, &self.chain.chain, &mut rng);
                if v >= self.vt {
                    return arrived(step);
                }
                if s2 != s {
                    s = s2;
                    next_jump = self.enter(s, step - 1, &mut rng);
                }
                next_reset = step.saturating_add(geometric_gap(&mut rng, self.ln_reset));
            } else {
                let xi = if self.kick_on {
                    rng.sample::<f64, _>(rand_distr::StandardNormal)
                } else {
                    0.0
                };
                let w = self.step.step(self.f, v, self.chain.levels[s], xi);
                if w >= self.vt || self.bridge_crossed(v, w, &mut rng) {
                    return arrived(step);
                }
                v = w;
            }
            if step == next_jump {
                let u = rng.gen::<f64>() * self.chain.leave[s];
                s = self.chain.dest(s, u);
                next_jump = self.enter(s, step, &mut rng);
            }
        }
    }

    /// Whether the thermal path crossed v_t between v and w (both below):
    /// with probability exp(-(v_t - v)(v_t - w) / (T dt)) (Eq. (N19)).
    #[inline]
    fn bridge_crossed(&self, v: f64, w: f64, rng: &mut Rng) -> bool {
        if !(self.t_dt > 0.0) {
            return false;
        }
        let e = (self.vt - v) * (self.vt - w) / self.t_dt;
        e < 40.0 && rng.gen::<f64>() < (-e).exp()
    }
}
