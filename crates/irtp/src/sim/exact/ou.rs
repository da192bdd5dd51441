//! The exact sampler for linear drag g(v) = v with thermal noise T > 0 and
//! any finite-state noise (docs/equations.md, Eqs. (N40)-(N45)).
//!
//! The event clock is that of the exact sampler with a finite-state noise
//! at T = 0 (Eq. (N10)): events at rate q_s + r in state s, one uniform
//! picking a jump of the noise or a reset, drawn from the particle's
//! stream (seed, i) in the same order, so at the same seed a run at T → 0
//! sees the events of the T = 0 sampler. Between
//! events the velocity is an Ornstein-Uhlenbeck process toward the level
//! a_s, and (v(t), x(t) - x(0)) is jointly Gaussian given v(0) (Eqs.
//! (N40)-(N42)); it is sampled at every event, grid time and at the start
//! of the averaging window, the two normals of each sample drawn from a
//! second stream of the particle ([`rng::stream_for`]).
//!
//! The window estimators are the conditional expectations, given the
//! state at the start of each such sub-interval, of the path integrals:
//! E[∫ v dt] and E[∫ v² dt] in closed form (Eq. (N43)), the time in each
//! velocity bin by a randomised (stratified) quadrature over t of the exact
//! P(v(t) ∈ bin), an unbiased estimate of its integral (Eq. (N44); a
//! deterministic Gauss-Legendre rule was biased by up to 5 % of the piece
//! for a cold Gaussian sweeping many bins). By the tower property each has
//! the mean of the path integral it replaces, and the particles stay
//! independent, so the across-particle standard errors hold as they are.

use crate::error::Result;
use crate::model::noise::chain::Chain;
use crate::model::reset::{Reset, ResetRule};
use crate::model::Params;
use crate::parallel::Progress;
use crate::rng::{self, Rng};
use crate::sim::{Observables, Part, SimSpec};
use rand::Rng as _;
use std::ops::Range;

/// The purpose key of the particles' second stream (the Gaussian draws).
const GAUSS_STREAM: u64 = 0x4f55_5f67_6175_7373;

/// Strata per unit time of the randomised quadrature of Eq. (N44), and
/// the most per panel.
const STRATA: usize = 16;

/// Half-width of the Gaussian kept per quadrature node, in standard
/// deviations: the mass beyond is 2 Φ(-8.5) ≈ 2e-17.
const CUT: f64 = 8.5;

/// The standard normal distribution function.
#[inline]
fn normal_cdf(z: f64) -> f64 {
    0.5 * libm::erfc(-z * std::f64::consts::FRAC_1_SQRT_2)
}

/// F(h) = ∫_0^h (1 - e^{-w})² dw = h - E1 - E1²/2 (E1 = 1 - e^{-h}), by
/// its Taylor series Σ_{n≥2} [(-2)^n - 2 (-1)^n] h^{n+1}/(n+1)! below
/// h = 1, where the closed form cancels (F ~ h³/3).
pub(crate) fn var_integral(h: f64) -> f64 {
    if h >= 1.0 {
        let e1 = -(-h).exp_m1();
        return h - e1 - 0.5 * e1 * e1;
    }
    // term = h^{n+1}/(n+1)!, from n = 2.
    let mut term = h * h * h / 6.0;
    let (mut m2, mut m1) = (4.0, 1.0);
    let mut sum = 0.0;
    for n in 2..40 {
        sum += (m2 - 2.0 * m1) * term;
        term *= h / (n as f64 + 2.0);
        m2 *= -2.0;
        m1 = -m1;
    }
    sum
}

/// The Gaussian law of one OU step of length h > 0 at temperature T
/// (Eqs. (N40)-(N42)): standard deviation of v, the regression slope of
/// the displacement on it and the displacement's conditional deviation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OuStep {
    /// e^{-h}.
    pub decay: f64,
    /// 1 - e^{-h}.
    pub e1: f64,
    /// sd of v(h) given v(0): sqrt(T (1 - e^{-2h})).
    pub sd_v: f64,
    /// Cov(v, x) / Var v.
    pub slope: f64,
    /// sd of x(h) - x(0) given v(0) and v(h).
    pub sd_x: f64,
}

impl OuStep {
    /// The step of length h > 0 at temperature t > 0.
    pub(crate) fn new(h: f64, t: f64) -> OuStep {
        let e1 = -(-h).exp_m1();
        let e2 = -(-2.0 * h).exp_m1();
        let var_v = t * e2;
        let cov = t * e1 * e1;
        let cond = t * (2.0 * var_integral(h) - e1 * e1 * e1 * e1 / e2);
        OuStep {
            decay: (-h).exp(),
            e1,
            sd_v: var_v.sqrt(),
            slope: cov / var_v,
            sd_x: cond.max(0.0).sqrt(),
        }
    }
}

/// Everything fixed for a thermal linear-drag run.
pub(super) struct OuSampler {
    chain: Chain,
    /// Per state: q_s + r and its inverse.
    total: Vec<f64>,
    inv_total: Vec<f64>,
    reset: ResetRule,
    temperature: f64,
    /// Histogram edges lo + (hi - lo) k / B, k = 0..=B.
    edges: Vec<f64>,
    times: Vec<f64>,
    burn_in: f64,
    t_max: f64,
    seed: u64,
}

/// One particle in flight.
struct OuLane {
    /// The event stream (seed, i): the N-state chain's draws.
    ev: Rng,
    /// The Gaussian draws.
    gauss: Rng,
    si: usize,
    v: f64,
    x: f64,
    t: f64,
    /// Next grid time index.
    k: usize,
    int_v: f64,
    int_v2: f64,
    msd: f64,
    events: u64,
}

impl OuSampler {
    /// The sampler of `params` (a noise model at T > 0, linear drag:
    /// [`crate::capability::drag_runs`] admits no other, and no schedule
    /// modifier, before any work).
    pub(super) fn new(params: &Params, spec: &SimSpec) -> Result<Self> {
        let chain = params.chain()?;
        let t = chain.temperature;
        // The histogram's range, as Observables::new has it.
        let (lo, hi) = crate::sim::histogram_range(params);
        let b = spec.bins;
        let mut edges: Vec<f64> = (0..=b)
            .map(|k| lo + (hi - lo) * k as f64 / b as f64)
            .collect();
        edges[b] = hi;
        let r = params.reset().rate();
        let total: Vec<f64> = chain.exit.iter().map(|q| q + r).collect();
        Ok(OuSampler {
            inv_total: total.iter().map(|x| 1.0 / x).collect(),
            total,
            reset: *params.reset(),
            temperature: t,
            edges,
            times: spec.grid.times().to_vec(),
            burn_in: spec.burn_in,
            t_max: spec.grid.t_max(),
            seed: spec.seed,
            chain,
        })
    }

    /// Add wt × P(N(m, sd²) ∈ bin) to occ[bin] for every bin (the end bins
    /// take the tails, as [`Observables::bin_of`] clamps); the
    /// distribution function is evaluated only at the edges within
    /// [`CUT`] standard deviations of m.
    #[inline]
    fn add_gauss(&self, m: f64, sd: f64, wt: f64, occ: &mut [f64]) {
        let b = occ.len();
        let (lo, w) = (self.edges[0], (self.edges[b] - self.edges[0]) / b as f64);
        let index = |x: f64| ((x - lo) / w).clamp(0.0, b as f64);
        // Interior edges k in [k0, k1) are evaluated: e_k <= m - CUT sd
        // below k0, e_k >= m + CUT sd from k1 on.
        let mut k0 = (index(m - CUT * sd).floor() as usize + 1).min(b);
        while k0 > 1 && self.edges[k0 - 1] > m - CUT * sd {
            k0 -= 1;
        }
        let mut k1 = (index(m + CUT * sd).ceil() as usize).clamp(k0, b);
        while k1 < b && self.edges[k1] < m + CUT * sd {
            k1 += 1;
        }
        let mut prev = 0.0;
        for k in k0..k1 {
            let c = normal_cdf((self.edges[k] - m) / sd);
            occ[k - 1] += wt * (c - prev);
            prev = c;
        }
        occ[k1 - 1] += wt * (1.0 - prev);
    }

    /// An unbiased estimate of E[time in each bin over (0, h)] for a
    /// particle at v = a_s + u0 in state s, added to `occ` (Eq. (N44)):
    /// the exact bin probabilities of v(t) at stratified random times,
    /// ceil([`STRATA`] len) strata (at most [`STRATA`]) on each of (0, h₁),
    /// h₁ = min(h, 1), and (h₁, h) of length len, each time weighted by its
    /// stratum's length (so the bin times sum to h).
    pub(crate) fn occupy(&self, si: usize, u0: f64, h: f64, occ: &mut [f64], rng: &mut Rng) {
        let (a, t) = (self.chain.levels[si], self.temperature);
        let h1 = h.min(1.0);
        for (start, len) in [(0.0, h1), (h1, h - h1)] {
            if !(len > 0.0) {
                continue;
            }
            let strata = ((STRATA as f64 * len).ceil() as usize).clamp(1, STRATA);
            let k = strata as f64;
            let wt = len / k;
            for j in 0..strata {
                let tt = start + len * (j as f64 + rng.gen::<f64>()) / k;
                // A point mass at v0 where tt = 0 (probability 2^-53).
                let sd = (t * -(-2.0 * tt).exp_m1()).sqrt().max(f64::MIN_POSITIVE);
                self.add_gauss(a + u0 * (-tt).exp(), sd, wt, occ);
            }
        }
    }

    /// Empty scratch (occupation times) for `bins` bins.
    pub(super) fn scratch(&self, bins: usize) -> Vec<f64> {
        vec![0.0; bins]
    }

    /// A particle at t = 0: v = 0, noise state drawn from π (the N-state
    /// loop's first draw).
    fn start(&self, i: u64) -> OuLane {
        let mut ev = rng::stream(self.seed, i);
        let si = self.chain.draw_stationary(ev.gen::<f64>());
        OuLane {
            ev,
            gauss: rng::stream_for(self.seed, GAUSS_STREAM, i),
            si,
            v: 0.0,
            x: 0.0,
            t: 0.0,
            k: 0,
            int_v: 0.0,
            int_v2: 0.0,
            msd: 0.0,
            events: 0,
        }
    }

    /// Move a particle from p.t to p.t + h in its state (no event inside):
    /// the window's conditional expectations if the sub-interval lies in
    /// the window (Eqs. (N43)-(N44)), then (v, x) drawn jointly (Eqs.
    /// (N40)-(N42)).
    fn sub_interval(&self, p: &mut OuLane, h: f64, occ: &mut [f64]) {
        if !(h > 0.0) {
            return;
        }
        let (a, t) = (self.chain.levels[p.si], self.temperature);
        let u0 = p.v - a;
        let step = OuStep::new(h, t);
        if p.t >= self.burn_in {
            let e2 = -(-2.0 * h).exp_m1();
            p.int_v += a * h + u0 * step.e1;
            p.int_v2 += (a * a + t) * h + 2.0 * a * u0 * step.e1 + 0.5 * (u0 * u0 - t) * e2;
            self.occupy(p.si, u0, h, occ, &mut p.gauss);
        }
        let z1: f64 = p.gauss.sample(rand_distr::StandardNormal);
        let z2: f64 = p.gauss.sample(rand_distr::StandardNormal);
        let dv = step.sd_v * z1;
        p.v = a + u0 * step.decay + dv;
        p.x += a * h + u0 * step.e1 + step.slope * dv + step.sd_x * z2;
        p.t += h;
    }

    /// Move a particle to `t_end` in its state, split at the grid times
    /// (recorded there) and at the start of the window.
    fn advance(&self, p: &mut OuLane, obs: &mut Observables, occ: &mut [f64], t_end: f64) {
        let n = self.times.len();
        loop {
            while p.k < n && self.times[p.k] <= p.t {
                obs.record(p.k, p.v, p.x);
                p.msd += obs.msd_term(p.k, p.x);
                p.k += 1;
            }
            if p.t >= t_end {
                return;
            }
            let mut next = t_end;
            if p.k < n {
                next = next.min(self.times[p.k]);
            }
            if p.t < self.burn_in {
                next = next.min(self.burn_in);
            }
            let h = next - p.t;
            self.sub_interval(p, h, occ);
            // Land on the split point exactly (no drift of p.t by rounding).
            p.t = next;
        }
    }

    /// One segment up to the next event (or t_max), then the event: a jump
    /// of the noise or a reset (Eq. (N10), the N-state chain's draws).
    /// Returns false at t_max.
    fn step(&self, p: &mut OuLane, obs: &mut Observables, occ: &mut [f64]) -> bool {
        let s = p.si;
        let gap = if self.total[s] > 0.0 {
            p.ev.sample::<f64, _>(rand_distr::Exp1) * self.inv_total[s]
        } else {
            f64::INFINITY
        };
        let t_end = (p.t + gap).min(self.t_max);
        self.advance(p, obs, occ, t_end);
        if t_end >= self.t_max {
            return false;
        }
        p.events += 1;
        let u = p.ev.gen::<f64>() * self.total[s];
        if u < self.chain.exit[s] {
            p.si = self.chain.jump(s, u);
        } else {
            p.v = self.reset.draw_velocity(&mut p.ev);
            p.si = self.reset.draw_noise_state(s, &self.chain, &mut p.ev);
        }
        true
    }

    /// Particles `ids` one after the other.
    pub(super) fn particles(&self, ids: Range<u64>, obs: &mut Observables, occ: &mut [f64]) {
        let window = self.t_max - self.burn_in;
        for i in ids {
            let mut p = self.start(i);
            while self.step(&mut p, obs, occ) {}
            obs.finish_particle(p.int_v / window, p.int_v2 / window, occ, window, p.v, p.msd);
            obs.record_final_position(p.x);
            obs.steps += p.events;
        }
    }
}

/// The thermal linear-drag run of [`super::simulate_part`]: the same
/// reduction over particles as the other loops.
pub(super) fn simulate(
    params: &Params,
    spec: &SimSpec,
    part: Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    params.require(crate::model::reset::Solver::Exact)?;
    super::super::check_period_window(params, spec)?;
    let sampler = OuSampler::new(params, spec)?;
    Ok(super::reduce_particles(
        (params, spec),
        part,
        progress,
        || sampler.scratch(spec.bins),
        |ids, obs, occ| sampler.particles(ids, obs, occ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::noise::NoiseModel;
    use crate::model::DragLaw;
    use crate::sim::TimeGrid;

    /// F(h) by its series and closed form agree across h = 1, and match a
    /// fine midpoint quadrature.
    #[test]
    fn var_integral_is_continuous_and_right() {
        // F'(1) = (1 - 1/e)² ≈ 0.40: the two sides 1e-12 apart differ by
        // 4e-13 plus rounding.
        let (a, b) = (var_integral(1.0 - 1e-12), var_integral(1.0));
        assert!((b - a - 0.3996e-12).abs() < 1e-14, "{a} {b}");
        for h in [1e-4, 0.1, 0.7, 1.0, 2.5] {
            let n = 200_000;
            let dw = h / n as f64;
            let q: f64 = (0..n)
                .map(|i| {
                    let w = (i as f64 + 0.5) * dw;
                    (-(-w).exp_m1()).powi(2) * dw
                })
                .sum();
            let f = var_integral(h);
            assert!((f - q).abs() < 1e-9 * f.max(1e-12), "{h}: {f} {q}");
        }
    }

    fn sampler(t: f64, bins: usize) -> OuSampler {
        let noise = NoiseModel::parse("rpt:sigma=1.2,alpha=1,beta=1", t).unwrap();
        let p = Params::with_noise(DragLaw::Linear, noise, 0.5, 0.0).unwrap();
        let spec = SimSpec::new(10, TimeGrid::linear(10.0, 2).unwrap(), 1.0, bins, 1).unwrap();
        OuSampler::new(&p, &spec).unwrap()
    }

    /// The reference of Eq. (N44): the midpoint rule in t on n points.
    fn occupy_midpoint(s: &OuSampler, si: usize, u0: f64, h: f64, n: usize) -> Vec<f64> {
        let mut occ = vec![0.0; s.edges.len() - 1];
        let (a, t) = (s.chain.levels[si], s.temperature);
        for i in 0..n {
            let tt = h * (i as f64 + 0.5) / n as f64;
            let sd = (t * -(-2.0 * tt).exp_m1()).sqrt();
            s.add_gauss(a + u0 * (-tt).exp(), sd, h / n as f64, &mut occ);
        }
        occ
    }

    /// The randomised quadrature of Eq. (N44) is unbiased: per bin, the
    /// mean of 2000 estimates against a converged midpoint rule (checked
    /// against half its points) within 5 standard errors of that mean, from
    /// wide Gaussians to a cold one (T = 1e-3, the mean sweeping tens of
    /// bins), start points on and between edges, short to long pieces; the
    /// bin times of each estimate sum to h.
    #[test]
    fn randomised_occupation_is_unbiased() {
        let mut rng = rng::stream(3, 0);
        let draws = 2000;
        for (t, bins) in [(0.5, 20), (0.2, 40), (1e-3, 50)] {
            let s = sampler(t, bins);
            let w = s.edges[1] - s.edges[0];
            for (si, v0) in [
                (0, 0.0),
                (1, s.edges[bins / 2]),
                (2, s.edges[bins / 3] + 0.01 * w),
                (0, -1.1),
            ] {
                let a = s.chain.levels[si];
                for h in [1e-3, 0.4, 3.0, 40.0] {
                    let fine = occupy_midpoint(&s, si, v0 - a, h, 40_000);
                    let half = occupy_midpoint(&s, si, v0 - a, h, 20_000);
                    let (mut sum, mut sum2) = (vec![0.0; bins], vec![0.0; bins]);
                    for _ in 0..draws {
                        let mut c = vec![0.0; bins];
                        s.occupy(si, v0 - a, h, &mut c, &mut rng);
                        let total: f64 = c.iter().sum();
                        assert!((total - h).abs() < 1e-12 * h.max(1.0), "{total} {h}");
                        for b in 0..bins {
                            sum[b] += c[b];
                            sum2[b] += c[b] * c[b];
                        }
                    }
                    for b in 0..bins {
                        let n = draws as f64;
                        let mean = sum[b] / n;
                        let se = ((sum2[b] / n - mean * mean).max(0.0) / (n - 1.0)).sqrt();
                        let conv = (fine[b] - half[b]).abs();
                        assert!(conv < 1e-5 * h, "reference {t} {v0} {h} bin {b}: {conv:e}");
                        let d = (mean - fine[b]).abs();
                        assert!(
                            d <= 5.0 * se + 2.0 * conv + 1e-12 * h,
                            "T {t} v0 {v0} h {h} bin {b}: {mean} vs {} (se {se:e})",
                            fine[b]
                        );
                    }
                }
            }
        }
    }
}
