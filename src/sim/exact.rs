//! Exact event-driven sampler: no time step, no discretisation bias.
//!
//! The process is piecewise deterministic: noise flips (rate lambda) and
//! velocity resets (rate r, v → v_r, noise state kept) happen at the events
//! of a Poisson process of rate lambda + r; in between, v follows the flow
//! dv/dt = s - g(v), s = ±Sigma (paper Eq. (5)), solved exactly by
//! [`Drag::flow_time`] / [`Drag::flow_velocity`]. Position and the
//! time integrals of v and v² along a flow segment are
//! ∫ v dt = v* Δ - I1 and ∫ v² dt = v*² Δ - 2 v* I1 + I2 with the deficit
//! integrals I_k = ∫ (v* - v)^k dt = ∫ (v* - v)^k / (s - g(v)) dv, whose
//! integrands are smooth up to the fixed point v*. The sampler tabulates their
//! antiderivatives once per run as piecewise Chebyshev series ([`DeficitTable`],
//! built from the trait's quadrature and checked against it to 1e-13), and
//! the velocity solve starts from a tabulated inverse of the flow potential
//! ([`crate::model::drag::InverseGuide`]), so an event costs about one Halley step (three
//! transcendental functions), one exponential waiting time and a few
//! polynomial evaluations. Occupation times come from the flow potential
//! at precomputed bin edges (no transcendental per crossed edge; bins crossed
//! in full are counted in a difference array and weighted by their exact
//! crossing time at the end of the particle).
//!
//! Paper references: flow Eq. (5), reset rule Eq. (3) (here to v_r, noise kept),
//! velocity bounds Eqs. (8)-(10); the Euler scheme it replaces is Eqs. (30)-(32).
//!
//! Estimators are exact functionals of each path: moments at the grid times
//! (flow evaluated inside the segment), time averages of v and v² and the
//! occupation time of every histogram bin over [burn_in, t_max] (bin edges
//! crossed in full contribute the precomputed flow time across the bin).

use crate::error::{Error, Result};
use crate::model::drag::FlowMap;
use crate::model::reset::{Reset, ResetRule};
use crate::model::{Drag, Params};
use crate::numerics::chebyshev::{self, clenshaw, clenshaw2, NC};
use crate::parallel::Progress;
use crate::rng::{self, Rng};
use crate::sim::{Observables, Part, SimSpec};
use rand::Rng as _;
use std::ops::Range;

/// Antiderivatives Ψ_k(v) = ∫_{lo}^{v} (v* - v')^k / (s - g(v')) dv', k = 1, 2,
/// for one noise state s on [lo, hi], as piecewise Chebyshev series on
/// adaptively refined pieces (refined until the last coefficients of the
/// integrand fall below 1e-14 of its size, the rounding-noise level of the sampled values).
#[derive(Clone, Debug)]
pub struct DeficitTable {
    /// Fixed point v* = g⁻¹(s).
    vs: f64,
    /// Piece boundaries (strictly increasing, first = lo, last = hi).
    bounds: Vec<f64>,
    /// Per piece: antiderivative coefficients of k = 1 and k = 2, interleaved
    /// (`[j][k]`) so both series are summed in one Clenshaw pass.
    coef: Vec<[[f64; 2]; NC]>,
    /// Per piece: Ψ_k at the piece's left end.
    offset: Vec<[f64; 2]>,
}

impl DeficitTable {
    /// Build the table for drag `drag`, noise value `s` on [lo, hi].
    pub fn new<D: Drag>(drag: &D, s: f64, lo: f64, hi: f64) -> Result<Self> {
        let vs = drag.inverse(s);
        let g1 = drag.derivative(vs);
        let f = |v: f64| -> [f64; 2] {
            let u = vs - v;
            let f1 = if u == 0.0 {
                1.0 / g1
            } else {
                u / drag.drift_at_distance(s, u)
            };
            [f1, u * f1]
        };
        let mut pieces: Vec<(f64, f64, [[f64; NC]; 2])> = Vec::new();
        let mut stack = vec![(lo, hi)];
        let min_width = (hi - lo) * 1e-9;
        // Initial uniform split, then refine by coefficient decay.
        stack.clear();
        let init = 8;
        for i in (0..init).rev() {
            let a = lo + (hi - lo) * i as f64 / init as f64;
            let b = if i + 1 == init {
                hi
            } else {
                lo + (hi - lo) * (i + 1) as f64 / init as f64
            };
            stack.push((a, b));
        }
        while let Some((a, b)) = stack.pop() {
            let fit = chebyshev::fit(&f, a, b);
            let abscissa = a.abs().max(b.abs()).max(vs.abs());
            let (ok, c) = (fit.resolved_to_noise(1e-14, abscissa), fit.anti);
            if ok || b - a < min_width {
                if !ok {
                    return Err(Error::Numerical {
                        method: "exact sampler table",
                        reason: format!("deficit integrand not resolved near v = {a} (s = {s})"),
                    });
                }
                pieces.push((a, b, c));
            } else {
                let m = 0.5 * (a + b);
                stack.push((m, b));
                stack.push((a, m));
            }
        }
        let mut bounds = vec![lo];
        let mut coef = Vec::with_capacity(pieces.len());
        let mut offset = Vec::with_capacity(pieces.len());
        let mut acc = [0.0, 0.0];
        for (_, b, c) in pieces {
            bounds.push(b);
            offset.push(acc);
            for k in 0..2 {
                acc[k] += clenshaw(&c[k], 1.0);
            }
            let mut inter = [[0.0; 2]; NC];
            for (j, cj) in inter.iter_mut().enumerate() {
                *cj = [c[0][j], c[1][j]];
            }
            coef.push(inter);
        }
        Ok(DeficitTable {
            vs,
            bounds,
            coef,
            offset,
        })
    }

    /// Fixed point v* of this noise state.
    pub fn fixed_point(&self) -> f64 {
        self.vs
    }

    /// Number of Chebyshev pieces.
    pub fn pieces(&self) -> usize {
        self.coef.len()
    }

    /// (Ψ_1(v), Ψ_2(v)); v is clamped into the table range.
    #[inline]
    pub fn psi(&self, v: f64) -> [f64; 2] {
        let n = self.coef.len();
        let p = self.bounds[1..n].partition_point(|&b| b <= v);
        let (a, b) = (self.bounds[p], self.bounds[p + 1]);
        let x = chebyshev::to_unit(v, a, b);
        let c = &self.coef[p];
        let o = &self.offset[p];
        let r = clenshaw2(c, x);
        [o[0] + r[0], o[1] + r[1]]
    }

    /// Deficit integrals (I1, I2) along the flow from va to vb
    /// (same meaning as [`Drag::flow_deficits`]).
    #[inline]
    pub fn deficits(&self, va: f64, vb: f64) -> (f64, f64) {
        let (a, b) = (self.psi(va), self.psi(vb));
        (b[0] - a[0], b[1] - a[1])
    }
}

/// Smallest relaxation rate g'(v*) at the fixed point v* = v_u the tables
/// resolve: below it (tanh within ~5e-11 of Sigma = 1, where g'(v_u) =
/// 1 - Sigma²) the approach to v_u is so slow that the flow tables lose
/// their precision (measured: <v²> 2.8 standard errors off the FP answer at
/// 1 - Sigma = 1e-12, negative at 1e-14).
const MIN_RELAXATION_RATE: f64 = 1e-10;

fn check_relaxation<D: Drag>(drag: &D, sigma: f64, vu: f64) -> Result<()> {
    let rate = drag.derivative(vu);
    if !(rate >= MIN_RELAXATION_RATE) {
        return Err(Error::invalid(
            "sigma",
            sigma,
            format!(
                "g'(v_u) >= {MIN_RELAXATION_RATE:e} for the exact sampler (here g'(v_u) = \
                 {rate:e}; tanh: Sigma <= 1 - 5e-11); the Fokker-Planck solvers cover it"
            ),
        ));
    }
    Ok(())
}

/// Everything fixed for a run: parameters, tables, histogram geometry.
struct Sampler<F> {
    /// Flows for s = +Sigma (index 0) and s = -Sigma (index 1), accelerated.
    flows: [F; 2],
    lambda: f64,
    total_rate: f64,
    /// The resetting rule (rate, target, noise state at a reset).
    reset: ResetRule,
    /// Its point target, when it has one: Ψ and Φ there are precomputed.
    point: Option<f64>,
    /// Tables for s = +Sigma (index 0) and s = -Sigma (index 1).
    tables: [DeficitTable; 2],
    /// Flow time across bin k in full, per noise state (0 where never crossed).
    tau: [Vec<f64>; 2],
    /// Flow potential (see [`FlowMap::potential`]) at every edge, per noise state.
    phi_edges: [Vec<f64>; 2],
    /// Ψ(v_r) of each table at the point target (segment start after a reset).
    psi_vr: [[f64; 2]; 2],
    /// Flow potential at v_r, per noise state.
    phi_vr: [f64; 2],
    times: Vec<f64>,
    burn_in: f64,
    t_max: f64,
    seed: u64,
}

/// Per-chunk scratch: occupation times and full-crossing counts
/// (difference arrays, so a segment crossing many bins costs O(1)).
struct Scratch {
    occ: Vec<f64>,
    cross: [Vec<i64>; 2],
}

impl<F: FlowMap> Sampler<F> {
    fn new<D: Drag<Flow = F>>(drag: &D, params: &Params, spec: &SimSpec) -> Result<Self> {
        let sigma = params.sigma();
        let (lo, hi) = params.bounds();
        check_relaxation(drag, sigma, hi)?;
        let tables = [
            DeficitTable::new(drag, sigma, lo, hi)?,
            DeficitTable::new(drag, -sigma, lo, hi)?,
        ];
        let b = spec.bins;
        let mut edges: Vec<f64> = (0..=b)
            .map(|k| lo + (hi - lo) * k as f64 / b as f64)
            .collect();
        edges[b] = hi;
        // Crossing time of a bin: +∞ (bin not crossed) counts 0; NaN means
        // the flow-time quadrature failed.
        let fin = |t: f64, at: f64| match t {
            t if t.is_nan() => Err(Error::NonFinite {
                method: "exact sampler bin crossing time",
                at,
            }),
            t if t.is_finite() => Ok(t),
            _ => Ok(0.0),
        };
        let tau = [
            (0..b)
                .map(|k| fin(drag.flow_time(sigma, edges[k], edges[k + 1]), edges[k]))
                .collect::<Result<_>>()?,
            (0..b)
                .map(|k| fin(drag.flow_time(-sigma, edges[k + 1], edges[k]), edges[k]))
                .collect::<Result<_>>()?,
        ];
        let flows = [
            drag.flow(sigma).accelerated(),
            drag.flow(-sigma).accelerated(),
        ];
        let phi_edges = [
            edges.iter().map(|&e| flows[0].potential(e)).collect(),
            edges.iter().map(|&e| flows[1].potential(e)).collect(),
        ];
        let reset = *params.reset();
        let point = reset.point();
        let vr = point.unwrap_or(0.0);
        let psi_vr = [tables[0].psi(vr), tables[1].psi(vr)];
        let phi_vr = [flows[0].potential(vr), flows[1].potential(vr)];
        Ok(Sampler {
            flows,
            phi_edges,
            psi_vr,
            phi_vr,
            lambda: params.lambda(),
            total_rate: params.lambda() + reset.rate(),
            reset,
            point,
            tables,
            tau,
            times: spec.grid.times().to_vec(),
            burn_in: spec.burn_in,
            t_max: spec.grid.t_max(),
            seed: spec.seed,
        })
    }

    /// Add the occupation times of a flow segment va → vb of duration dt:
    /// partial first and last bins from flow potentials (time to an edge =
    /// (Φ(va) - Φ(edge)) / g'(v*), edge potentials precomputed), bins crossed
    /// in full via the difference array of crossings.
    #[allow(clippy::too_many_arguments)]
    #[allow(clippy::too_many_arguments)]
    fn occupy(
        &self,
        obs: &Observables,
        sc: &mut Scratch,
        si: usize,
        va: f64,
        pa: Option<f64>,
        vb: f64,
        dt: f64,
    ) {
        let (ka, kb) = (obs.bin_of(va), obs.bin_of(vb));
        if ka == kb {
            sc.occ[ka] += dt;
            return;
        }
        let flow = &self.flows[si];
        let pa = pa.unwrap_or_else(|| flow.potential(va));
        let k = flow.rate();
        let phi = &self.phi_edges[si];
        // Time to reach edge e (clamped into [0, dt] against rounding).
        let to = |e: usize| ((pa - phi[e]) / k).clamp(0.0, dt);
        if kb > ka {
            sc.occ[ka] += to(ka + 1);
            if kb > ka + 1 {
                sc.cross[si][ka + 1] += 1;
                sc.cross[si][kb] -= 1;
            }
            sc.occ[kb] += dt - to(kb);
        } else {
            sc.occ[ka] += to(ka);
            if ka > kb + 1 {
                sc.cross[si][kb + 1] += 1;
                sc.cross[si][ka] -= 1;
            }
            sc.occ[kb] += dt - to(kb + 1);
        }
    }

    fn particle(&self, i: u64, obs: &mut Observables, sc: &mut Scratch) {
        let mut rng = rng::stream(self.seed, i);
        let mut plus = rng.gen::<bool>();
        let (mut t, mut v, mut x) = (0.0f64, 0.0f64, 0.0f64);
        let mut k = 0usize;
        let (mut int_v, mut int_v2) = (0.0f64, 0.0f64);
        let mut events = 0u64;
        let mut msd = 0.0f64;
        // Ψ(v) of the current table at the segment start, when known (after a
        // reset it is the precomputed Ψ(v_r)).
        let mut psi_start: Option<[f64; 2]> = None;
        loop {
            let gap = exp_gap(&mut rng, self.total_rate);
            let t_end = (t + gap).min(self.t_max);
            let si = usize::from(!plus);
            let flow = &self.flows[si];
            let table = &self.tables[si];
            let vs = table.fixed_point();
            // Moments at grid times inside (t, t_end].
            while k < self.times.len() && self.times[k] <= t_end {
                let dt = self.times[k] - t;
                let vk = flow.velocity(v, dt);
                let xk = x + vs * dt - table.deficits(v, vk).0;
                obs.record(k, vk, xk);
                msd += obs.msd_term(k, xk);
                k += 1;
            }
            let dt = t_end - t;
            let vb = flow.velocity(v, dt);
            let psi_a = psi_start.unwrap_or_else(|| table.psi(v));
            let psi_b = table.psi(vb);
            // Stationary window [burn_in, t_max].
            if t_end > self.burn_in {
                let (va, psi_w, phi_w, dw) = if t < self.burn_in {
                    let va = flow.velocity(v, self.burn_in - t);
                    (va, table.psi(va), None, t_end - self.burn_in)
                } else {
                    // After a reset the start potential is the precomputed one.
                    let phi = psi_start.map(|_| self.phi_vr[si]);
                    (v, psi_a, phi, dt)
                };
                let (j1, j2) = (psi_b[0] - psi_w[0], psi_b[1] - psi_w[1]);
                int_v += vs * dw - j1;
                int_v2 += vs * vs * dw - 2.0 * vs * j1 + j2;
                self.occupy(obs, sc, si, va, phi_w, vb, dw);
            }
            x += vs * dt - (psi_b[0] - psi_a[0]);
            v = vb;
            t = t_end;
            if t >= self.t_max {
                break;
            }
            events += 1;
            if rng.gen::<f64>() * self.total_rate < self.lambda {
                plus = !plus;
                psi_start = None;
            } else {
                v = self.reset.draw_velocity(&mut rng);
                plus = self.reset.draw_noise(plus, &mut rng);
                psi_start = self.point.map(|_| self.psi_vr[usize::from(!plus)]);
            }
        }
        // Full bin crossings: occupation += (number of crossings) × tau.
        for si in 0..2 {
            let mut n = 0i64;
            for (kb, c) in sc.cross[si].iter_mut().enumerate() {
                n += *c;
                *c = 0;
                if n != 0 {
                    sc.occ[kb] += n as f64 * self.tau[si][kb];
                }
            }
        }
        let window = self.t_max - self.burn_in;
        obs.finish_particle(int_v / window, int_v2 / window, &mut sc.occ, window, v, msd);
        obs.steps += events;
    }
}

/// Exp(rate) waiting time (∞ for rate 0), by the ziggurat sampler of
/// `rand_distr::Exp1` (exact in distribution, cheaper than -ln U).
#[inline]
pub fn exp_gap(rng: &mut Rng, rate: f64) -> f64 {
    if rate > 0.0 {
        let e: f64 = rng.sample(rand_distr::Exp1);
        e / rate
    } else {
        f64::INFINITY
    }
}

/// Simulate `spec.particles` particles exactly (no time step). Same
/// observables as the Euler method; `steps` counts events (flips + resets).
/// Bit-identical for any thread count.
pub fn simulate(params: &Params, spec: &SimSpec, progress: &dyn Progress) -> Result<Observables> {
    Ok(simulate_part(params, spec, Part::Whole, progress)?.remove(0))
}

/// The unit totals of units `units` of [`simulate`]'s run (see
/// [`crate::sim::simulate_units`]).
pub fn simulate_units(
    params: &Params,
    spec: &SimSpec,
    units: Range<u64>,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    simulate_part(params, spec, Part::Units(units), progress)
}

fn simulate_part(
    params: &Params,
    spec: &SimSpec,
    part: Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    crate::with_drag!(params.drag(), |d| simulate_drag(
        d, params, spec, part, progress
    ))
}

/// [`simulate_part`] for one law's type (monomorphised). The accumulator
/// carries the per-chunk [`Scratch`]; only its observables are the result.
fn simulate_drag<D: Drag>(
    drag: &D,
    params: &Params,
    spec: &SimSpec,
    part: Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    let sampler = Sampler::new(drag, params, spec)?;
    let template = Observables::new(spec, params);
    let b = spec.bins;
    let first = spec.first_particle;
    let totals = part.reduce(
        spec.particles,
        || {
            (
                template.clone(),
                Scratch {
                    occ: vec![0.0; b],
                    cross: [vec![0; b], vec![0; b]],
                },
            )
        },
        |lo, hi, (obs, sc)| {
            for i in lo..hi {
                sampler.particle(first + i, obs, sc);
            }
        },
        |a, b| a.0.merge(&b.0),
        progress,
    );
    Ok(totals.into_iter().map(|(obs, _)| obs).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    #[test]
    fn table_matches_quadrature() {
        // Extreme parameters (g'(v*) ~ 1e6 or 1e-6) lose a few digits: the
        // integrand spans many orders of magnitude.
        for (d, sg, tol) in [
            (DragLaw::Tan, 3.0, 1e-13),
            (DragLaw::Tan, 30.0, 1e-13),
            (DragLaw::Tanh, 0.6, 1e-13),
            (DragLaw::Tanh, 0.99, 1e-13),
            (DragLaw::Linear, 2.0, 1e-13),
            (DragLaw::Tan, 1000.0, 1e-11),
            (DragLaw::Tanh, 0.999999, 1e-11),
        ] {
            let p = Params::new(d, sg, 1.0, 0.0, 0.0).unwrap();
            let (lo, hi) = p.bounds();
            for s in [sg, -sg] {
                let tab = DeficitTable::new(&d, s, lo, hi).unwrap();
                for i in 0..=40 {
                    for j in [0, 7, 40] {
                        let va = lo + (hi - lo) * i as f64 / 40.0;
                        let vb = lo + (hi - lo) * j as f64 / 40.0;
                        let (a1, a2) = tab.deficits(va, vb);
                        let (b1, b2) = d.flow_deficits(s, va, vb);
                        let scale = 1.0 + b1.abs() + b2.abs();
                        assert!(
                            (a1 - b1).abs() < tol * scale && (a2 - b2).abs() < tol * scale,
                            "{d} s={s} {va}->{vb}: {a1} {b1} / {a2} {b2} ({} pieces)",
                            tab.pieces()
                        );
                    }
                }
            }
        }
    }
}
