//! Particle simulation: the paper's Euler scheme (Eqs. (30)-(32)) and the exact
//! event-driven sampler, sharing one set of mergeable observables.
//!
//! A simulation is N independent particles. Particle `i` uses the random
//! stream [`crate::rng::stream`]`(seed, i)`, and particles are reduced with
//! [`crate::parallel`]'s fixed tree (chunks of 256 particles into units of
//! 4096, units in order), so results are bit-identical for any thread
//! count, and a run split into unit-aligned shards ([`simulate_units`],
//! [`combine_units`]) merges into the same bits. Each method implements "simulate one particle and add it to an
//! [`Observables`] accumulator"; everything downstream is shared.

pub mod control;
pub mod euler;
pub mod exact;

pub use crate::numerics::time_grid::TimeGrid;

use crate::error::{finite, Error, Result};
use crate::model::reset::{Clock, Refractory};
use crate::model::Params;
use crate::model::Reset;
use crate::parallel::{self, Progress};
use crate::stats::{merge_all, MeanAcc};
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// Particle simulation method.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "lowercase")]
pub enum Method {
    /// The paper's Euler scheme (Eqs. (30)-(32)) with time step `dt`
    /// ([`Method::euler`]: geometric waiting times for flips and resets, see
    /// [`euler`]).
    Euler {
        /// Time step.
        dt: f64,
        /// How the per-step flips and resets are drawn (the same law either
        /// way; not written when geometric, the default).
        #[serde(default, skip_serializing_if = "euler::EventSampling::is_geometric")]
        events: euler::EventSampling,
    },
    /// The exact event-driven sampler: no time step, no discretisation bias
    /// (see [`exact`]).
    Exact,
}

impl Method {
    /// The Euler scheme with time step `dt` and geometric waiting times
    /// between events (the default sampling).
    pub fn euler(dt: f64) -> Method {
        Method::Euler {
            dt,
            events: euler::EventSampling::Geometric,
        }
    }

    /// Short name written to run.json (`euler`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Method::Euler { .. } => "euler",
            Method::Exact => "exact",
        }
    }
}

/// Simulate `spec.particles` independent particles with `method`.
/// Bit-identical for any rayon thread count.
pub fn simulate(
    params: &Params,
    spec: &SimSpec,
    method: Method,
    progress: &dyn Progress,
) -> Result<Observables> {
    match method {
        Method::Euler { dt, events } => euler::simulate_with(params, spec, dt, events, progress),
        Method::Exact => exact::simulate(params, spec, progress),
    }
}

/// Number of units of a run of `particles` particles: unit `u` holds the
/// particles `u * UNIT .. min((u + 1) * UNIT, particles)` of the run
/// ([`crate::parallel::UNIT`] = 4096), counted from `spec.first_particle`.
pub fn unit_count(particles: u64) -> u64 {
    parallel::unit_count(particles)
}

/// A shard of the run [`simulate`] would do: the totals of units `units`
/// (in order; `spec.particles` is the size of the WHOLE run). Shards cover a
/// contiguous range of units each and may run in separate processes or on
/// separate machines; [`combine_units`] of all unit totals in unit order
/// equals [`simulate`]'s result bit for bit, however the units were split.
/// The totals survive a JSON round trip exactly (serde_json with
/// `float_roundtrip`), so shards can be stored as JSON.
pub fn simulate_units(
    params: &Params,
    spec: &SimSpec,
    method: Method,
    units: Range<u64>,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    let count = unit_count(spec.particles);
    if !(units.start <= units.end && units.end <= count) {
        return Err(Error::invalid(
            "units",
            format!("{units:?}"),
            format!(
                "start <= end <= {count} (units of {} particles)",
                parallel::UNIT
            ),
        ));
    }
    match method {
        Method::Euler { dt, events } => {
            euler::simulate_units(params, spec, dt, events, units, progress)
        }
        Method::Exact => exact::simulate_units(params, spec, units, progress),
    }
}

/// Merge unit totals of [`simulate_units`] (same `params`, `spec`,
/// `method`), in the order given, into the empty observables of the run.
/// With every unit of the run in unit order, this is [`simulate`]'s result
/// bit for bit. A unit from a different run geometry (recording times,
/// histogram, fit weights) is refused.
pub fn combine_units(
    params: &Params,
    spec: &SimSpec,
    method: Method,
    units: &[Observables],
) -> Result<Observables> {
    let mut total = empty(params, spec, method)?;
    for (u, o) in units.iter().enumerate() {
        let same = o.times == total.times
            && o.msd_weights == total.msd_weights
            && (o.v_lo, o.v_hi) == (total.v_lo, total.v_hi)
            && o.density_time.len() == total.density_time.len()
            && o.density_final.len() == total.density_final.len()
            && match (&o.position, &total.position) {
                (Some(a), Some(b)) => a.same(b),
                (a, b) => a.is_none() && b.is_none(),
            }
            && [&o.v, &o.v2, &o.x, &o.x2]
                .iter()
                .all(|a| a.len() == total.times.len());
        if !same {
            return Err(Error::invalid(
                "units",
                u,
                "unit totals of this run (same times, histogram and fit weights)",
            ));
        }
        total.merge(o);
    }
    Ok(total)
}

/// The empty observables a run of `method` starts from (the Euler scheme
/// records at whole steps, so its times are the plan's).
fn empty(params: &Params, spec: &SimSpec, method: Method) -> Result<Observables> {
    Ok(match method {
        Method::Euler { dt, .. } => {
            let plan = euler::EulerPlan::new(params, spec, dt)?;
            euler::template(params, spec, &plan)
        }
        Method::Exact => Observables::new(spec, params),
    })
}

/// Which part of a run a sampler reduces: all of it (one total), or the
/// unit totals of some units. Both go through the same reduction loop.
#[derive(Clone, Debug)]
pub(crate) enum Part {
    Whole,
    Units(Range<u64>),
}

impl Part {
    /// [`parallel::reduce_chunks`] (one total) or [`parallel::reduce_units`].
    pub(crate) fn reduce<A, I, C, M>(
        &self,
        n: u64,
        init: I,
        chunk: C,
        merge: M,
        progress: &dyn Progress,
    ) -> Vec<A>
    where
        A: Send,
        I: Fn() -> A + Sync,
        C: Fn(u64, u64, &mut A) + Sync,
        M: Fn(&mut A, A),
    {
        match self {
            Part::Whole => vec![parallel::reduce_chunks(n, init, chunk, merge, progress)],
            Part::Units(u) => parallel::reduce_units(n, u.clone(), init, chunk, merge, progress),
        }
    }
}

/// What to measure and for how many particles (method-independent).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimSpec {
    /// Number of independent particles.
    pub particles: u64,
    /// Recording times for ensemble moments; the run ends at `grid.t_max()`.
    pub grid: TimeGrid,
    /// Start of the time-averaging window [burn_in, t_max] for stationary
    /// estimates (time-averaged <v²> and P_s(v)).
    pub burn_in: f64,
    /// Number of histogram bins on (v_l, v_u).
    pub bins: usize,
    /// Master seed.
    pub seed: u64,
    /// Index of the first particle: a run simulates particles
    /// `first_particle .. first_particle + particles`, each from its own
    /// stream (seed, index), so disjoint shards of one run (e.g. SLURM array
    /// tasks) merge with [`Observables::merge`] into the statistics of the
    /// whole run (sums, counts and sums of squares add; the rounding of the
    /// sums depends on the split). For shards that merge bit for bit, run
    /// the whole spec's units with [`simulate_units`] and [`combine_units`].
    #[serde(default)]
    pub first_particle: u64,
}

impl SimSpec {
    /// Validate.
    pub fn new(
        particles: u64,
        grid: TimeGrid,
        burn_in: f64,
        bins: usize,
        seed: u64,
    ) -> Result<Self> {
        if particles < 2 {
            return Err(Error::invalid(
                "particles",
                particles,
                "particles >= 2 (error bars need two samples)",
            ));
        }
        let burn_in = finite("burn_in", burn_in)?;
        if !(burn_in >= 0.0 && burn_in < grid.t_max()) {
            return Err(Error::invalid(
                "burn_in",
                burn_in,
                format!("0 <= burn_in < t_max = {}", grid.t_max()),
            ));
        }
        if !(1..=10_000_000).contains(&bins) {
            return Err(Error::invalid("bins", bins, "1 <= bins <= 10000000"));
        }
        Ok(SimSpec {
            particles,
            grid,
            burn_in,
            bins,
            seed,
            first_particle: 0,
        })
    }

    /// The shard of particles `first .. first + particles` of the same run.
    pub fn shard(mut self, first: u64) -> Result<Self> {
        if first.checked_add(self.particles).is_none() {
            return Err(Error::invalid(
                "first_particle",
                first,
                "first_particle + particles <= 2^64 - 1",
            ));
        }
        self.first_particle = first;
        Ok(self)
    }
}

/// With a periodic reset clock the long-time state is periodic in time
/// (cycle [`crate::model::reset::Periodic::cycle`]), so the window time
/// averages over [burn_in, t_max] are period averages only when the window
/// holds a whole number of cycles (to a relative 1e-9): refused otherwise,
/// naming `burn_in`.
pub(crate) fn check_period_window(params: &Params, spec: &SimSpec) -> Result<()> {
    let schedule = params.schedule();
    let cycle = match (
        schedule.periodic,
        schedule.clock.clone(),
        schedule.refractory,
    ) {
        (Some(periodic), _, r) => periodic.cycle(r),
        // A fixed renewal clock is periodic too: T, plus a fixed
        // refractory period.
        (None, Some(Clock::Fixed(f)), None) => f.t,
        (None, Some(Clock::Fixed(f)), Some(Refractory::Fixed { duration })) => f.t + duration,
        _ => return Ok(()),
    };
    let n = (spec.grid.t_max() - spec.burn_in) / cycle;
    if !(n.round() >= 1.0 && (n - n.round()).abs() <= 1e-9 * n) {
        return Err(Error::invalid(
            "burn_in",
            spec.burn_in,
            format!(
                "t_max - burn_in a whole number of periods {cycle} with --reset-period or a fixed --reset-clock \
                 (the window time averages are period averages; here {n} periods)"
            ),
        ));
    }
    Ok(())
}

/// Least-squares weights w_k with Σ w_k y_k = (slope of y against t over the
/// times in [burn_in, t_max]) / 2; all zero if fewer than two such times, or
/// if v_r ≠ 0: then `<x>` ≠ 0 and `<x²>` carries the drift, so no Eq. (36) fit
/// (with v_r = 0 the process is symmetric under (x, v, η) → -(x, v, η) and `<x>` = 0 exactly).
/// All zero with position resetting too: x is then stationary, `<x²>` does
/// not grow, and there is no diffusion coefficient to fit.
pub(crate) fn msd_fit_weights(times: &[f64], burn_in: f64, params: &Params) -> Vec<f64> {
    let inside = |t: f64| t >= burn_in;
    let n = times.iter().filter(|&&t| inside(t)).count();
    let stationary_x = params.schedule().position.is_some();
    // A noise without the mirror symmetry drifts (<a> ≠ 0 in general).
    let asymmetric = params.noise().is_some_and(|m| !m.is_mirror_symmetric());
    if n < 2 || params.reset().target().moments().0 != 0.0 || stationary_x || asymmetric {
        return vec![0.0; times.len()];
    }
    let mean = times.iter().filter(|&&t| inside(t)).sum::<f64>() / n as f64;
    let sxx: f64 = times
        .iter()
        .filter(|&&t| inside(t))
        .map(|&t| (t - mean) * (t - mean))
        .sum();
    times
        .iter()
        .map(|&t| {
            if inside(t) {
                (t - mean) / (2.0 * sxx)
            } else {
                0.0
            }
        })
        .collect()
}

/// The velocity histogram's range: the velocity interval
/// ([`Params::bounds`]) where it is finite; an unbounded side (thermal
/// noise with a law defined on the whole line) is cut at
/// g⁻¹(a) ∓ 10 sqrt(T / g'(g⁻¹(a))) for a the smallest (largest) level:
/// ten standard deviations of the Gaussian approximation around the
/// outermost fixed point. Velocities beyond it fall in the end bins.
pub fn histogram_range(params: &Params) -> (f64, f64) {
    let (lo, hi) = params.bounds();
    if lo.is_finite() && hi.is_finite() {
        return (lo, hi);
    }
    use crate::model::Drag;
    let Some(m) = params.noise() else {
        return (lo, hi);
    };
    let d = params.drag();
    let levels = m.levels();
    let a_lo = levels.iter().copied().fold(f64::INFINITY, f64::min);
    let a_hi = levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let width = |a: f64| {
        let v = d.inverse(a);
        (v, 10.0 * (m.temperature() / d.derivative(v)).sqrt())
    };
    let (v_lo, w_lo) = width(a_lo);
    let (v_hi, w_hi) = width(a_hi);
    (
        if lo.is_finite() { lo } else { v_lo - w_lo },
        if hi.is_finite() { hi } else { v_hi + w_hi },
    )
}

/// Mergeable accumulator of everything a simulation measures.
///
/// Per-particle quantities (time averages, occupation fractions) are pushed
/// once per particle, so their standard errors are the across-particle
/// standard errors of independent samples.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Observables {
    /// Recording times.
    pub times: Vec<f64>,
    /// v(t_k) samples.
    pub v: Vec<MeanAcc>,
    /// v(t_k)² samples.
    pub v2: Vec<MeanAcc>,
    /// x(t_k) samples.
    pub x: Vec<MeanAcc>,
    /// x(t_k)² samples.
    pub x2: Vec<MeanAcc>,
    /// Per-particle time average of v over [burn_in, t_max].
    pub v_time_avg: MeanAcc,
    /// Per-particle time average of v² over [burn_in, t_max].
    pub v2_time_avg: MeanAcc,
    /// Histogram range (v_l, v_u) and bin count.
    pub v_lo: f64,
    /// Upper end of the histogram range.
    pub v_hi: f64,
    /// Per-particle density estimate in each bin: fraction of the window
    /// spent in the bin divided by the bin width.
    pub density_time: Vec<MeanAcc>,
    /// Per-particle indicator of being in each bin at t_max, divided by the bin width.
    pub density_final: Vec<MeanAcc>,
    /// Work done: Euler steps or exact-sampler events, summed over particles.
    pub steps: u64,
    /// Paper Eq. (36) per particle: the least-squares slope of x(t_k)² against
    /// t_k over the grid times in [burn_in, t_max], halved. Its mean is the
    /// MSD-fit D of <x²> = 2 D t + c on those times (the fit is linear in the
    /// data), its across-particle SE the fit's honest standard error. Empty
    /// when the window holds fewer than two grid times.
    #[serde(default)]
    pub msd_fit_d: MeanAcc,
    /// Weights of that fit per grid time (zero outside the window).
    #[serde(default)]
    pub msd_weights: Vec<f64>,
    /// With position resetting: the histogram of x(t_max), P_s(x) (absent
    /// otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<PositionHistogram>,
    /// The point mass of the stationary law, if it has one
    /// ([`crate::model::atoms::atom_velocities`]): the time spent exactly
    /// at its velocity is counted here and in no histogram bin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atom: Option<AtomAcc>,
}

/// Occupation of a point mass of the velocity law at `v`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AtomAcc {
    /// The atom's velocity.
    pub v: f64,
    /// Per-particle fraction of the window [burn_in, t_max] spent exactly
    /// at `v`.
    pub time: MeanAcc,
    /// Per-particle indicator of being exactly at `v` at t_max.
    pub at_final: MeanAcc,
}

/// Histogram of the position at t_max on [lo, hi] (position resetting:
/// the stationary P_s(x); range from
/// [`crate::model::reset::PositionReset::range`]), with the mass outside.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PositionHistogram {
    /// Lower end of the range.
    pub lo: f64,
    /// Upper end of the range.
    pub hi: f64,
    /// Per-particle indicator of x(t_max) in each bin, divided by the bin width.
    pub density: Vec<MeanAcc>,
    /// Per-particle indicator of x(t_max) outside [lo, hi].
    pub outside: MeanAcc,
}

impl PositionHistogram {
    fn new(params: &Params, spec: &SimSpec) -> Option<Self> {
        let reset = params.schedule().position?;
        let (v_lo, v_hi) = histogram_range(params);
        let v_max = v_lo.abs().max(v_hi.abs());
        let (lo, hi) = reset.range(v_max, params.rate(), params.schedule(), spec.grid.t_max());
        Some(PositionHistogram {
            lo,
            hi,
            density: vec![MeanAcc::new(); spec.bins],
            outside: MeanAcc::new(),
        })
    }

    /// Bin width.
    pub fn bin_width(&self) -> f64 {
        (self.hi - self.lo) / self.density.len() as f64
    }

    /// Add one particle's x(t_max).
    fn push(&mut self, x: f64) {
        let w = self.bin_width();
        let inside = x >= self.lo && x < self.hi;
        let bin = ((x - self.lo) / w).floor();
        for (b, d) in self.density.iter_mut().enumerate() {
            d.push(if inside && bin == b as f64 {
                1.0 / w
            } else {
                0.0
            });
        }
        self.outside.push(if inside { 0.0 } else { 1.0 });
    }

    fn merge(&mut self, o: &PositionHistogram) {
        merge_all(&mut self.density, &o.density);
        self.outside.merge(&o.outside);
    }

    /// Same geometry.
    fn same(&self, o: &PositionHistogram) -> bool {
        (self.lo, self.hi, self.density.len()) == (o.lo, o.hi, o.density.len())
    }

    /// Rows (x, p, p_err): bin centre, density and its standard error.
    pub fn rows(&self) -> Vec<[f64; 3]> {
        let w = self.bin_width();
        self.density
            .iter()
            .enumerate()
            .map(|(b, d)| [self.lo + (b as f64 + 0.5) * w, d.mean(), d.sem()])
            .collect()
    }

    /// Header for [`PositionHistogram::rows`].
    pub const HEADER: [&'static str; 3] = ["x", "p", "p_err"];
}

impl Observables {
    /// Empty accumulator for a spec and a model (histogram on (v_l, v_u)).
    pub fn new(spec: &SimSpec, params: &Params) -> Self {
        let (v_lo, v_hi) = histogram_range(params);
        let k = spec.grid.len();
        Observables {
            times: spec.grid.times().to_vec(),
            v: vec![MeanAcc::new(); k],
            v2: vec![MeanAcc::new(); k],
            x: vec![MeanAcc::new(); k],
            x2: vec![MeanAcc::new(); k],
            v_time_avg: MeanAcc::new(),
            v2_time_avg: MeanAcc::new(),
            v_lo,
            v_hi,
            density_time: vec![MeanAcc::new(); spec.bins],
            density_final: vec![MeanAcc::new(); spec.bins],
            steps: 0,
            msd_fit_d: MeanAcc::new(),
            msd_weights: msd_fit_weights(spec.grid.times(), spec.burn_in, params),
            position: PositionHistogram::new(params, spec),
            atom: crate::model::atoms::atom_velocities(params)
                .first()
                .map(|&v| AtomAcc {
                    v,
                    time: MeanAcc::new(),
                    at_final: MeanAcc::new(),
                }),
        }
    }

    /// Whether `v` is exactly the velocity of the law's atom.
    #[inline]
    pub fn is_atom(&self, v: f64) -> bool {
        self.atom.as_ref().is_some_and(|a| a.v == v)
    }

    /// Add one particle's position at t_max to the histogram of P_s(x)
    /// (position resetting; nothing otherwise).
    #[inline]
    pub fn record_final_position(&mut self, x: f64) {
        if let Some(h) = &mut self.position {
            h.push(x);
        }
    }

    /// Contribution of x(t_k) to the particle's Eq. (36) slope (see
    /// [`Observables::msd_fit_d`]); samplers sum it over k per particle.
    #[inline]
    pub fn msd_term(&self, k: usize, x: f64) -> f64 {
        self.msd_weights[k] * x * x
    }

    /// Bin width.
    pub fn bin_width(&self) -> f64 {
        (self.v_hi - self.v_lo) / self.density_time.len() as f64
    }

    /// Bin index of a velocity (clamped into range).
    #[inline]
    pub fn bin_of(&self, v: f64) -> usize {
        let b = self.density_time.len();
        let i = ((v - self.v_lo) / (self.v_hi - self.v_lo) * b as f64) as isize;
        i.clamp(0, b as isize - 1) as usize
    }

    /// Record the state of one particle at grid time index `k`.
    #[inline]
    pub fn record(&mut self, k: usize, v: f64, x: f64) {
        self.v[k].push(v);
        self.v2[k].push(v * v);
        self.x[k].push(x);
        self.x2[k].push(x * x);
    }

    /// Add one particle's stationary-window results: time averages of v and v²,
    /// `occupation[b]` = time spent in bin b during the window (cleared here),
    /// `window` = window length, `v_final` = velocity at t_max.
    /// `msd_d` = the particle's sum of [`Observables::msd_term`].
    pub fn finish_particle(
        &mut self,
        v_avg: f64,
        v2_avg: f64,
        occupation: &mut [f64],
        window: f64,
        v_final: f64,
        msd_d: f64,
    ) {
        self.v_time_avg.push(v_avg);
        self.v2_time_avg.push(v2_avg);
        if self.msd_weights.iter().any(|&w| w != 0.0) {
            self.msd_fit_d.push(msd_d);
        }
        let w = self.bin_width();
        // A particle at the atom at t_max is in no bin.
        let final_bin = (!self.is_atom(v_final)).then(|| self.bin_of(v_final));
        for (b, occ) in occupation.iter_mut().enumerate() {
            self.density_time[b].push(*occ / (window * w));
            self.density_final[b].push(if Some(b) == final_bin { 1.0 / w } else { 0.0 });
            *occ = 0.0;
        }
    }

    /// Add one particle's time `at` (within the window of length `window`)
    /// spent exactly at the atom, and whether it ends there; nothing
    /// without an atom.
    pub fn finish_atom(&mut self, at: f64, window: f64, v_final: f64) {
        if let Some(a) = &mut self.atom {
            a.time.push(at / window);
            a.at_final.push(if a.v == v_final { 1.0 } else { 0.0 });
        }
    }

    /// The atom as (velocity, time-averaged mass, its standard error), if
    /// the law has one.
    pub fn atom_mass(&self) -> Option<crate::model::VelocityAtom> {
        self.atom.as_ref().map(|a| crate::model::VelocityAtom {
            v: a.v,
            mass: a.time.mean(),
            err: a.time.sem(),
        })
    }

    /// The atom at t_max as (velocity, fraction of particles there, its
    /// standard error), if the law has one.
    pub fn atom_final(&self) -> Option<crate::model::VelocityAtom> {
        self.atom.as_ref().map(|a| crate::model::VelocityAtom {
            v: a.v,
            mass: a.at_final.mean(),
            err: a.at_final.sem(),
        })
    }

    /// Merge another accumulator (same spec) into this one.
    pub fn merge(&mut self, o: &Observables) {
        merge_all(&mut self.v, &o.v);
        merge_all(&mut self.v2, &o.v2);
        merge_all(&mut self.x, &o.x);
        merge_all(&mut self.x2, &o.x2);
        self.v_time_avg.merge(&o.v_time_avg);
        self.v2_time_avg.merge(&o.v2_time_avg);
        merge_all(&mut self.density_time, &o.density_time);
        merge_all(&mut self.density_final, &o.density_final);
        self.steps += o.steps;
        self.msd_fit_d.merge(&o.msd_fit_d);
        if let (Some(a), Some(b)) = (&mut self.position, &o.position) {
            a.merge(b);
        }
        if let (Some(a), Some(b)) = (&mut self.atom, &o.atom) {
            a.time.merge(&b.time);
            a.at_final.merge(&b.at_final);
        }
    }

    /// Number of particles accumulated.
    pub fn particles(&self) -> u64 {
        self.v2_time_avg.n
    }

    /// Bin centres.
    pub fn bin_centres(&self) -> Vec<f64> {
        let w = self.bin_width();
        (0..self.density_time.len())
            .map(|b| self.v_lo + (b as f64 + 0.5) * w)
            .collect()
    }

    /// Rows (t, v_mean, v_mean_err, v2, v2_err, x_mean, x_mean_err, x2, x2_err).
    pub fn moment_rows(&self) -> Vec<[f64; 9]> {
        (0..self.times.len())
            .map(|k| {
                [
                    self.times[k],
                    self.v[k].mean(),
                    self.v[k].sem(),
                    self.v2[k].mean(),
                    self.v2[k].sem(),
                    self.x[k].mean(),
                    self.x[k].sem(),
                    self.x2[k].mean(),
                    self.x2[k].sem(),
                ]
            })
            .collect()
    }

    /// Header for [`Observables::moment_rows`].
    pub const MOMENT_HEADER: [&'static str; 9] = [
        "t",
        "v_mean",
        "v_mean_err",
        "v2",
        "v2_err",
        "x_mean",
        "x_mean_err",
        "x2",
        "x2_err",
    ];

    /// Rows (v, p, p_err, p_final, p_final_err): time-averaged stationary
    /// density over the window and the ensemble density at t_max.
    pub fn density_rows(&self) -> Vec<[f64; 5]> {
        self.bin_centres()
            .into_iter()
            .enumerate()
            .map(|(b, v)| {
                let (t, f) = (&self.density_time[b], &self.density_final[b]);
                [v, t.mean(), t.sem(), f.mean(), f.sem()]
            })
            .collect()
    }

    /// Header for [`Observables::density_rows`].
    pub const DENSITY_HEADER: [&'static str; 5] = ["v", "p", "p_err", "p_final", "p_final_err"];

    /// Summary numbers (the `--json` contract of `irtp simulate`).
    pub fn summary(&self) -> SimSummary {
        let last = self.times.len() - 1;
        SimSummary {
            v2: self.v2_time_avg.mean(),
            v2_err: self.v2_time_avg.sem(),
            v_mean: self.v_time_avg.mean(),
            v_mean_err: self.v_time_avg.sem(),
            v2_final: self.v2[last].mean(),
            v2_final_err: self.v2[last].sem(),
            x2_final: self.x2[last].mean(),
            x2_final_err: self.x2[last].sem(),
            x_final: self.x[last].mean(),
            x_final_err: self.x[last].sem(),
            x_range: self.position.as_ref().map(|h| [h.lo, h.hi]),
            x_outside: self.position.as_ref().map(|h| h.outside.mean()),
            x_outside_err: self.position.as_ref().map(|h| h.outside.sem()),
            t_max: self.times[last],
            particles: self.particles(),
            steps: self.steps,
            d_eff_msd: (self.msd_fit_d.n >= 2).then(|| self.msd_fit_d.mean()),
            d_eff_msd_err: (self.msd_fit_d.n >= 2).then(|| self.msd_fit_d.sem()),
            atoms: self.atom_mass().into_iter().collect(),
            atoms_final: self.atom_final().into_iter().collect(),
        }
    }
}

/// Headline numbers of a simulation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimSummary {
    /// Time-averaged stationary <v²> over [burn_in, t_max].
    pub v2: f64,
    /// Its standard error (across particles).
    pub v2_err: f64,
    /// Time-averaged stationary `<v>`.
    pub v_mean: f64,
    /// Its standard error.
    pub v_mean_err: f64,
    /// Ensemble <v²> at t_max.
    pub v2_final: f64,
    /// Its standard error.
    pub v2_final_err: f64,
    /// Ensemble <x²> at t_max.
    pub x2_final: f64,
    /// Its standard error.
    pub x2_final_err: f64,
    /// Ensemble `<x>` at t_max.
    pub x_final: f64,
    /// Its standard error.
    pub x_final_err: f64,
    /// With position resetting: the range of the histogram of P_s(x)
    /// (`position.csv`), else None.
    pub x_range: Option<[f64; 2]>,
    /// With position resetting: the fraction of particles with x(t_max)
    /// outside that range, else None.
    pub x_outside: Option<f64>,
    /// Its standard error.
    pub x_outside_err: Option<f64>,
    /// Final time.
    pub t_max: f64,
    /// Number of particles.
    pub particles: u64,
    /// Euler steps or exact events, summed over particles.
    pub steps: u64,
    /// D_eff by the paper's Eq. (36) fit, <x²> = 2 D t + c, over the grid
    /// times in [burn_in, t_max] (None with fewer than two such times). Only
    /// meaningful when burn_in is many correlation times; the exact value is
    /// `irtp fp stationary`'s `d_eff`.
    pub d_eff_msd: Option<f64>,
    /// Its standard error (across particles).
    pub d_eff_msd_err: Option<f64>,
    /// The point mass of the stationary law, if it has one: its velocity,
    /// the time-averaged fraction of particles exactly there over
    /// [burn_in, t_max] and its standard error; the density histogram
    /// holds the rest.
    #[serde(default)]
    pub atoms: Vec<crate::model::VelocityAtom>,
    /// The same point mass at t_max: the fraction of particles exactly at
    /// its velocity at t_max and its standard error (the time-dependent
    /// atom of `fp transient` at t_max; `density_final` holds the rest).
    #[serde(default)]
    pub atoms_final: Vec<crate::model::VelocityAtom>,
}
