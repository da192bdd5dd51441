//! Bounded cost: every command estimates the work and the memory it needs
//! from its validated config, before anything runs, and refuses a run above
//! its budget (`--max-work`, `--max-memory`) with the estimate, the flags it
//! grows with, and the flag that raises the limit (exit 2, nothing written).
//!
//! Work is counted in elementary operations, each some tens of nanoseconds
//! on one core: exact-sampler events (noise flips, resets and recording
//! times), Euler particle steps, mesh cell updates. The default budget, 1e11
//! operations, is of the order of an hour of one core. The estimates are
//! expectations, not bounds (a first-passage run stops at the arrival, whose
//! mean the backward equations give); they decide whether to start, never
//! the result.

use clap::Args;
use irtp::error::{Error, Result};
use irtp::model::Drag;

/// Default `--max-work`: elementary operations (about an hour of one core).
pub const DEFAULT_MAX_WORK: f64 = 1e11;
/// Default `--max-memory`: bytes.
pub const DEFAULT_MAX_MEMORY: f64 = 8e9;

/// Budget flags: `--max-work --max-memory`.
#[derive(Args, Clone, Debug)]
pub struct BudgetArgs {
    /// Refuse a run estimated to need more elementary operations than this
    /// (particle events or steps, mesh cell updates; 1e11 is about an hour of
    /// one core).
    #[arg(long, default_value = "1e11", value_parser = parse_limit)]
    pub max_work: f64,
    /// Refuse a run estimated to need more memory than this many bytes.
    #[arg(long, default_value = "8e9", value_parser = parse_limit)]
    pub max_memory: f64,
}

impl Default for BudgetArgs {
    fn default() -> Self {
        BudgetArgs {
            max_work: DEFAULT_MAX_WORK,
            max_memory: DEFAULT_MAX_MEMORY,
        }
    }
}

fn parse_limit(s: &str) -> std::result::Result<f64, String> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| "not a number: expected a positive limit such as 1e12".to_string())?;
    if !(x > 0.0) || x.is_infinite() {
        return Err("expected a finite limit > 0".into());
    }
    Ok(x)
}

/// A cost estimate: what is counted, how much, and what it grows with.
#[derive(Clone, Debug, PartialEq)]
pub struct Cost {
    /// Elementary operations.
    pub work: f64,
    /// What the operations are, in words ("particle events").
    pub unit: &'static str,
    /// The parameters the work grows with (library names).
    pub drivers: Vec<&'static str>,
    /// Bytes of memory at the peak.
    pub memory: f64,
    /// The parameters the memory grows with.
    pub memory_drivers: Vec<&'static str>,
}

impl Cost {
    /// The sum of two estimates run one after the other (work adds up,
    /// memory is the larger peak).
    pub fn then(mut self, other: Cost) -> Cost {
        self.work += other.work;
        if other.memory > self.memory {
            self.memory = other.memory;
            self.memory_drivers = other.memory_drivers;
        }
        for d in other.drivers {
            if !self.drivers.contains(&d) {
                self.drivers.push(d);
            }
        }
        self
    }
}

impl Cost {
    /// The same estimate for a method that evaluates `drag` in each unit of
    /// its work (a mesh cell, a density point, an Euler step): the work is
    /// [`Drag::evaluation_weight`] times dearer, and `drag` drives it where
    /// that weight exceeds 1 (a long expression law).
    pub fn per_drag_evaluation(mut self, drag: &impl Drag) -> Cost {
        let weight = drag.evaluation_weight();
        if weight > 1.0 {
            self.work *= weight;
            self.drivers.push("drag");
        }
        self
    }
}

impl BudgetArgs {
    /// Refuse `cost` above this budget. NaN estimates (from parameters that
    /// passed validation, so never expected) are refused too.
    pub fn check(&self, cost: &Cost) -> Result<()> {
        if !(cost.work <= self.max_work) {
            return Err(Error::TooCostly {
                unit: cost.unit,
                estimate: cost.work,
                drivers: cost.drivers.clone(),
                limit_name: "max_work",
                limit: self.max_work,
            });
        }
        if !(cost.memory <= self.max_memory) {
            return Err(Error::TooCostly {
                unit: "bytes of memory",
                estimate: cost.memory,
                drivers: cost.memory_drivers.clone(),
                limit_name: "max_memory",
                limit: self.max_memory,
            });
        }
        Ok(())
    }
}

/// Bytes of one mean accumulator (sum, sum of squares, count).
const ACC: f64 = 24.0;

/// A particle simulation of `particles` particles, `per_particle`
/// operations each, recording `samples` times and `bins` histogram bins:
/// at most one block of chunk accumulators ([`irtp::parallel`]) is alive.
pub fn particles(
    particles: u64,
    per_particle: f64,
    unit: &'static str,
    drivers: Vec<&'static str>,
    samples: usize,
    bins: usize,
) -> Cost {
    let n = particles as f64;
    let chunks = (n / irtp::parallel::CHUNK as f64).ceil().clamp(1.0, 1024.0);
    let per_acc = ACC * (4.0 * samples as f64 + 2.0 * bins as f64 + 8.0);
    Cost {
        work: n * per_particle,
        unit,
        drivers,
        memory: (chunks + 2.0) * per_acc + 64.0 * (samples + bins) as f64,
        memory_drivers: vec!["samples", "bins"],
    }
}

/// A mesh computation: `cells` cells updated `sweeps` times, `bytes_per_cell`
/// of storage.
pub fn mesh(cells: usize, sweeps: f64, bytes_per_cell: f64, drivers: Vec<&'static str>) -> Cost {
    let c = cells as f64;
    Cost {
        work: c * sweeps,
        unit: "cell updates",
        drivers,
        memory: c * bytes_per_cell,
        memory_drivers: vec!["cells"],
    }
}
