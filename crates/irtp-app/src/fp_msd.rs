//! `irtp fp msd`: `<x>(t)`, `<x v>(t)`, `<x²>(t)` and the effective exponent
//! d ln<x²>/d ln t without sampling ([`irtp::fp::msd`]).

use super::common::{ModelArgs, OutputArgs};
use super::format::{fmt_digits, fmt_sig};
use super::fp::MeshArg;
use super::{finish, open_out, Context, Outcome, Results, Table};
use clap::Args;
use irtp::error::finite;
use irtp::fp::{self, Mesh, MsdOptions};
use irtp::numerics::time_grid::TimeGrid;
use irtp::Params;
use serde_json::json;
use std::time::Instant;

/// `irtp fp msd`.
#[derive(Args, Debug)]
pub struct MsdArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    #[command(flatten)]
    pub(crate) output: OutputArgs,
    /// First non-zero output time (log grid from t-min to t-max, plus t = 0).
    #[arg(long, default_value_t = 0.01, allow_hyphen_values = true)]
    t_min: f64,
    /// Last output time.
    #[arg(long, default_value_t = 100.0, allow_hyphen_values = true)]
    t_max: f64,
    /// Number of output times, t = 0 included (>= 3).
    #[arg(long, default_value_t = 36, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    samples: usize,
    /// Cells of the coarsest mesh.
    #[arg(long, default_value_t = 200, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    cells: usize,
    /// Nested meshes (cells, 2 cells, ...) combined by Richardson extrapolation.
    #[arg(long, default_value_t = 3, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    levels: usize,
    /// Relative tolerance of the TR-BDF2 local error (global error about rtol^(2/3)).
    #[arg(long, default_value_t = 1e-7, allow_hyphen_values = true)]
    rtol: f64,
    /// Cell placement.
    #[arg(long, value_enum, default_value = "graded")]
    mesh: MeshArg,
}

/// Work per cell and TR-BDF2 step: three shifted solves and one apply of
/// three blocks of 2 unknowns (measured: about 1.5 µs per cell-step).
const OPS_PER_CELL_STEP: f64 = 60.0;

/// Expected TR-BDF2 steps of one mesh (measured on the Fig. 5 curves:
/// ~20 rtol^(-1/3) plus a restart per output interval).
pub fn expected_steps(rtol: f64, samples: usize) -> f64 {
    20.0 * rtol.powf(-1.0 / 3.0) + 10.0 * samples as f64
}

impl MsdArgs {
    /// Flags → model and solver options.
    pub(crate) fn config(&self) -> irtp::Result<(Params, MsdOptions)> {
        let params = self.model.params()?;
        self.output.no_seed("fp msd")?;
        let rtol = finite("rtol", self.rtol)?;
        if !(1e-14..=1e-3).contains(&rtol) {
            return Err(irtp::Error::invalid("rtol", rtol, "1e-14 <= rtol <= 1e-3"));
        }
        if !(1..=fp::MAX_LEVELS).contains(&self.levels) {
            return Err(irtp::Error::invalid(
                "levels",
                self.levels,
                format!("1 <= levels <= {}", fp::MAX_LEVELS),
            ));
        }
        if !(self.cells >= fp::MIN_CELLS && self.cells <= fp::MAX_MSD_CELLS >> (self.levels - 1)) {
            return Err(irtp::Error::invalid(
                "cells",
                self.cells,
                format!(
                    "{} <= cells <= {} / 2^(levels - 1)",
                    fp::MIN_CELLS,
                    fp::MAX_MSD_CELLS
                ),
            ));
        }
        if self.samples > 100_000 {
            return Err(irtp::Error::invalid(
                "samples",
                self.samples,
                "3 <= samples <= 100000",
            ));
        }
        let grid = TimeGrid::log(self.t_min, self.t_max, self.samples)?;
        if !(self.t_max <= 1e6) {
            return Err(irtp::Error::invalid(
                "t_max",
                self.t_max,
                "t_min < t_max <= 1e6",
            ));
        }
        let cells: f64 = (0..self.levels).map(|j| (self.cells << j) as f64).sum();
        let finest = (self.cells << (self.levels - 1)) as f64;
        self.output.budget.check(
            &super::budget::Cost {
                work: cells * OPS_PER_CELL_STEP * expected_steps(rtol, self.samples),
                unit: "cell updates",
                drivers: vec!["cells", "levels", "rtol", "samples"],
                memory: finest * 2.0 * 3.0 * 8.0 * 12.0 + 64.0 * 8.0 * self.samples as f64,
                memory_drivers: vec!["cells", "levels", "samples"],
            }
            .per_drag_evaluation(&params.drag()),
        )?;
        let opts = MsdOptions {
            cells: self.cells,
            mesh: match self.mesh {
                MeshArg::Graded => Mesh::Graded,
                MeshArg::Uniform => Mesh::Uniform,
            },
            levels: self.levels,
            times: grid.times().to_vec(),
            rtol,
        };
        Ok((params, opts))
    }
}

/// Run `irtp fp msd`: `moments.csv`, `summary.json`, `run.json`.
pub fn msd(a: &MsdArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let (params, opts) = a.config()?;
    let out = open_out("fp msd", a.output.out.as_deref(), a.output.force.force)?;
    let start = Instant::now();
    let m = {
        let bar = ctx.reporter.stage("fp msd", 1);
        fp::msd(&params, &opts, bar.as_ref())?
    };
    let wall = start.elapsed().as_secs_f64();
    let k = m.t.len() - 1;
    // d Var(x)/dt = 2 (<xv> - <x><v>) → 2 D_eff; with position resetting
    // the position has a stationary law instead and there is no D_eff.
    let d_slope = m.xv[k] - m.x_mean[k] * m.v_mean[k];
    let position = params.schedule().position.is_some();
    let mut summary = json!({
        "x2_final": m.x2[k],
        "xv_final": m.xv[k],
        "x_mean_final": m.x_mean[k],
        "v2_final": m.v2[k],
        "alpha_final": m.alpha[k],
        "x2_err_final": m.x2_err[k],
        "d_eff_slope": d_slope,
        "t_max": m.t[k],
        "cells_finest": m.cells_finest,
        "levels": opts.levels,
        "steps": m.steps,
        "params": params,
        "wall_time_s": wall,
    });
    if position {
        let obj = summary.as_object_mut().expect("a JSON object");
        obj.remove("d_eff_slope");
    }
    let mut moments = Table {
        name: "moments",
        header: [
            "t", "mass", "v_mean", "v2", "x_mean", "xv", "x2", "alpha", "x2_err",
        ]
        .map(String::from)
        .to_vec(),
        columns: vec![
            m.t.clone(),
            m.mass.clone(),
            m.v_mean.clone(),
            m.v2.clone(),
            m.x_mean.clone(),
            m.xv.clone(),
            m.x2.clone(),
            m.alpha.clone(),
            m.x2_err.clone(),
        ],
    };
    if opts.levels < 2 {
        // One mesh: no error estimate to write.
        moments.header.pop();
        moments.columns.pop();
        summary
            .as_object_mut()
            .expect("a JSON object")
            .remove("x2_err_final");
    }
    let diffusion = if position {
        format!(
            "<x> = {}  (position resetting: no D_eff)",
            fmt_digits(m.x_mean[k], 10)
        )
    } else {
        format!("(<xv> - <x><v>) = {} -> D_eff", fmt_digits(d_slope, 10))
    };
    let text = format!(
        "<x^2>(t = {}) = {}  alpha = {}  {diffusion}  ({} levels up to {} cells, {} TR-BDF2 steps)\n",
        fmt_sig(m.t[k]),
        fmt_digits(m.x2[k], 12),
        fmt_digits(m.alpha[k], 6),
        opts.levels,
        m.cells_finest,
        m.steps
    );
    let results = Results {
        method: format!("fv-upwind-trbdf2-moment-chain-{}", opts.mesh.name()),
        seed: None,
        json: summary,
        parameters: json!({"model": params, "options": opts}),
        tables: vec![moments],
        json_files: Vec::new(),
        text,
        wall_time_s: wall,
    };
    finish("fp msd", results, out, ctx)
}
