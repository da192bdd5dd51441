//! `irtp mfpt` in parts (a sweep's `particle_parts`): a particle method's
//! run (velocity target or search; `--method exact` or `euler`) cut into
//! contiguous ranges of particle units (`irtp::mfpt::particle_units`,
//! `irtp::search::particle_units`: each particle's stream comes from
//! (seed, index)), each computable anywhere; [`MfptParts::assemble`] of all
//! parts' unit totals writes the outputs of the run made whole, bit for bit.

use super::super::{open_out, Context, Outcome};
use super::{search, DirectArgs, DirectConfig};
use irtp::mfpt::FptStats;
use irtp::Error;
use std::time::Instant;

/// The validated run of either target.
enum Run {
    Velocity(DirectConfig),
    Search(search::SearchConfig),
}

/// A run of `irtp mfpt` by particles in `parts` parts.
pub struct MfptParts<'a> {
    args: &'a DirectArgs,
    run: Run,
    /// Units of the whole run.
    units: u64,
    /// Number of parts.
    pub parts: u64,
}

impl<'a> MfptParts<'a> {
    /// `parts` parts of the run `a` (a particle method with a finite
    /// `--t-max`: the parts' statistics are stored as JSON; at least one
    /// unit each).
    pub fn new(a: &'a DirectArgs, parts: u64) -> irtp::Result<MfptParts<'a>> {
        let (run, units, t_max) = if a.is_search() {
            let c = search::config(a)?;
            let units = c.method.unit_count();
            let t_max = c.method.particles().map(|r| r.t_max);
            (Run::Search(c), units, t_max)
        } else {
            let c = a.config()?;
            let units = c.method.unit_count();
            let t_max = c.method.particles().map(|r| r.t_max);
            (Run::Velocity(c), units, t_max)
        };
        let (Some(units), Some(t_max)) = (units, t_max) else {
            return Err(Error::invalid(
                "particle_parts",
                parts,
                "1 with a deterministic method (only particles, --method exact or euler, \
                 are cut into parts)",
            ));
        };
        if !t_max.is_finite() {
            return Err(Error::invalid(
                "t_max",
                t_max,
                "a finite t_max with particle_parts (the parts' statistics are stored as JSON)",
            ));
        }
        if !(parts >= 1 && parts <= units) {
            return Err(Error::invalid(
                "particle_parts",
                parts,
                format!(
                    "1 ..= {units} (parts of whole {}-particle units{})",
                    irtp::parallel::UNIT,
                    if a.sim.method == super::Method::Euler {
                        ", of the runs at dt and dt/2"
                    } else {
                        ""
                    }
                ),
            ));
        }
        Ok(MfptParts {
            args: a,
            run,
            units,
            parts,
        })
    }

    /// The unit totals of part `k` (0-based).
    pub fn compute(&self, k: u64, ctx: &Context) -> irtp::Result<Vec<FptStats>> {
        let range = k * self.units / self.parts..(k + 1) * self.units / self.parts;
        let bar = ctx.reporter.stage("mfpt part", 1);
        let r = match &self.run {
            Run::Velocity(c) => {
                irtp::mfpt::particle_units(&c.problem, &c.method, range, bar.as_ref())
            }
            Run::Search(c) => {
                irtp::search::particle_units(&c.problem, &c.method, range, bar.as_ref())
            }
        }?;
        ctx.check()?;
        Ok(r)
    }

    /// The outcome of the whole run from every part's unit totals (in part
    /// order) and the parts' summed wall time: written to `--out` as the
    /// run made whole would.
    pub fn assemble(&self, units: &[FptStats], wall: f64, ctx: &Context) -> irtp::Result<Outcome> {
        let o = &self.args.output;
        let out = open_out("mfpt", o.out.as_deref(), o.force.force)?;
        let t0 = Instant::now();
        match &self.run {
            Run::Velocity(c) => {
                let result = irtp::mfpt::assemble(&c.problem, &c.method, units)?;
                super::write_direct(self.args, c, result, (t0, wall), out, ctx)
            }
            Run::Search(c) => {
                let result = irtp::search::assemble(&c.problem, &c.method, units)?;
                search::write(c, result, wall + t0.elapsed().as_secs_f64(), out, ctx)
            }
        }
    }
}
