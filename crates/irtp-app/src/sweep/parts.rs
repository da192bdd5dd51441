//! Points whose particles are cut into parts (`particle_parts = M`, command
//! `simulate`, or `mfpt` by particles): part k of a point is its own work
//! item, which any shard can run; it stores the unit totals of its
//! particles as `part-<k>.json` in the point's directory. Once all M parts
//! exist, the point is assembled from them ([`crate::simulate::Parts`],
//! `mfpt::parts::MfptParts`; `Split` is the one registry of the
//! commands that split): the same outputs, bit for bit, as the point run
//! whole.

use super::plan::{Plan, Point};
use super::store::{write_atomic, PointResult, Store};
use crate::io::io_err;
use crate::mfpt::parts::MfptParts;
use crate::mfpt::MfptArgs;
use crate::simulate::Parts;
use crate::{keywords, Command, Context, Outcome, Quiet};
use irtp::error::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::PathBuf;

/// One stored part: its unit totals as the command's JSON (`simulate`:
/// observables; `mfpt`: first-passage statistics).
#[derive(Serialize, Deserialize)]
struct Part {
    part: u64,
    parts: u64,
    wall_time_s: f64,
    units: Vec<Value>,
}

/// The commands whose points split into parts: one arm per command.
enum Split<'a> {
    Simulate(Parts<'a>),
    Mfpt(MfptParts<'a>),
}

/// The refusal of a command that does not split.
fn unsplittable(parts: u64) -> Error {
    Error::invalid(
        "particle_parts",
        parts,
        "only with command = \"simulate\" or \"mfpt\" (one problem by particles)",
    )
}

/// Decode stored unit totals.
fn decode<T: for<'de> Deserialize<'de>>(units: &[Value]) -> Result<Vec<T>> {
    units
        .iter()
        .map(|u| {
            serde_json::from_value(u.clone())
                .map_err(|e| Error::invalid("part", "…", format!("stored unit totals: {e}")))
        })
        .collect()
}

/// Encode unit totals for storage.
fn encode<T: Serialize>(units: &[T]) -> Result<Vec<Value>> {
    units
        .iter()
        .map(|u| {
            serde_json::to_value(u)
                .map_err(|e| Error::invalid("part", "…", format!("unit totals: {e}")))
        })
        .collect()
}

impl<'a> Split<'a> {
    /// `parts` parts of the run `command` describes.
    fn new(command: &'a Command, parts: u64) -> Result<Split<'a>> {
        match command {
            Command::Simulate(a) => Parts::new(a, parts).map(Split::Simulate),
            Command::Mfpt(MfptArgs {
                command: None,
                direct,
            }) => MfptParts::new(direct, parts).map(Split::Mfpt),
            _ => Err(unsplittable(parts)),
        }
    }

    /// The unit totals of part `k`, encoded.
    fn compute(&self, k: u64, ctx: &Context) -> Result<Vec<Value>> {
        match self {
            Split::Simulate(s) => encode(&s.compute(k, ctx)?),
            Split::Mfpt(s) => encode(&s.compute(k, ctx)?),
        }
    }

    /// The outcome of the whole run from every part's unit totals.
    fn assemble(&self, units: &[Value], wall: f64, ctx: &Context) -> Result<Outcome> {
        match self {
            Split::Simulate(s) => s.assemble(&decode(units)?, wall, ctx),
            Split::Mfpt(s) => s.assemble(&decode(units)?, wall, ctx),
        }
    }
}

/// A unit of work: a whole point, or part `k` of a split point.
#[derive(Clone, Copy, Debug)]
pub struct Item<'p> {
    /// The point.
    pub point: &'p Point,
    /// The part, for a split point.
    pub part: Option<u64>,
}

/// The work items of a plan, in plan order (a split point's parts in turn).
pub fn items<'p>(plan: &Plan, points: &'p [Point]) -> Vec<Item<'p>> {
    let parts = plan.particle_parts;
    points
        .iter()
        .flat_map(|p| {
            let split = (parts > 1).then_some(parts);
            let ks: Vec<Option<u64>> = match split {
                Some(m) => (0..m).map(Some).collect(),
                None => vec![None],
            };
            ks.into_iter().map(move |part| Item { point: p, part })
        })
        .collect()
}

/// `part-<k>.json` of a point.
pub fn path(store: &Store, p: &Point, k: u64) -> PathBuf {
    store.dir(p).join(format!("part-{k}.json"))
}

/// The point's command line, parsed.
fn point_cli(plan: &Plan, store: &Store, p: &Point) -> Result<crate::Cli> {
    let argv = plan
        .argv(p, Some(&store.dir(p)))
        .map_err(|e| Error::invalid("plan", p.index, e))?;
    keywords::parse::<crate::Cli>(&plan.command, &argv)
        .map_err(|e| Error::invalid("plan", p.index, e))
}

/// Check that every point can be cut into the plan's parts.
pub fn check(plan: &Plan, p: &Point, cli: &crate::Cli) -> Result<()> {
    if plan.particle_parts <= 1 {
        return Ok(());
    }
    Split::new(&cli.command, plan.particle_parts)
        .map(drop)
        .map_err(|e| {
            Error::invalid(
                "plan",
                format!("point {}", p.index),
                e.message_with(|n| n.to_string()),
            )
        })
}

/// Compute part `k` of point `p` and store it; a failure of the computation
/// records the point as failed.
pub fn run_part(plan: &Plan, store: &Store, p: &Point, k: u64) -> Result<bool> {
    store.begin(plan, p)?;
    let t0 = std::time::Instant::now();
    let cli = point_cli(plan, store, p)?;
    let ctx = Context::new(&Quiet);
    let units =
        Split::new(&cli.command, plan.particle_parts).and_then(|parts| parts.compute(k, &ctx));
    let wall_time_s = t0.elapsed().as_secs_f64();
    match units {
        Ok(units) => {
            let part = Part {
                part: k,
                parts: plan.particle_parts,
                wall_time_s,
                units,
            };
            let text = serde_json::to_string(&part).map_err(|e| io_err(&path(store, p, k), e))?;
            write_atomic(&path(store, p, k), text.as_bytes())?;
            Ok(true)
        }
        Err(e) => {
            let msg = format!(
                "part {k} of {}: {}",
                plan.particle_parts,
                e.message_with(|n| n.to_string())
            );
            store.finish(p, super::failed(p, msg, wall_time_s))?;
            Ok(false)
        }
    }
}

/// Whether every part of `p` is stored.
pub fn complete(plan: &Plan, store: &Store, p: &Point) -> bool {
    (0..plan.particle_parts).all(|k| path(store, p, k).exists())
}

/// Assemble point `p` from its stored parts into its outputs and result.
pub fn assemble(plan: &Plan, store: &Store, p: &Point) -> Result<PointResult> {
    let mut units = Vec::new();
    let mut wall = 0.0;
    for k in 0..plan.particle_parts {
        let file = path(store, p, k);
        let text = std::fs::read_to_string(&file).map_err(|e| io_err(&file, e))?;
        let part: Part = serde_json::from_str(&text)
            .map_err(|e| io_err(&file, format!("not a stored part: {e}")))?;
        if part.part != k || part.parts != plan.particle_parts {
            return Err(Error::Io {
                path: file.display().to_string(),
                reason: format!(
                    "holds part {} of {}, expected {k} of {}",
                    part.part, part.parts, plan.particle_parts
                ),
            });
        }
        wall += part.wall_time_s;
        units.extend(part.units);
    }
    let cli = point_cli(plan, store, p)?;
    let argv = plan
        .argv(p, Some(&store.dir(p)))
        .map_err(|e| Error::invalid("plan", p.index, e))?;
    let ctx = Context {
        reporter: &Quiet,
        argv,
    };
    let outcome = Split::new(&cli.command, plan.particle_parts)
        .and_then(|parts| parts.assemble(&units, wall, &ctx));
    store.finish(p, super::point_result(p, outcome, wall))
}
