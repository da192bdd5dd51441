//! `irtp fp stationary` and `irtp fp transient`: Fokker-Planck solvers.

use super::common::{ModelArgs, OutputArgs};
use super::format::{fmt_digits, fmt_pm, fmt_sig};
use super::{finish, open_out, Context, Outcome, Results, Table};
use clap::{Args, Subcommand, ValueEnum};
use irtp::fp::{self, Mesh, StationaryOptions, TransientOptions};
use irtp::Params;
use serde_json::json;
use std::time::Instant;

/// Solve the Fokker-Planck equations for P±(v) (paper Eqs. (11)-(12)).
#[derive(Args, Debug)]
pub struct FpArgs {
    #[command(subcommand)]
    pub command: FpCommand,
}

/// The solvers of `irtp fp`.
#[derive(Subcommand, Debug)]
pub enum FpCommand {
    /// Stationary density P_s(v), ⟨v⟩, ⟨v²⟩ (Eq. (33)) and the exact D_eff by a direct O(N) solve.
    ///
    /// The stationary Fokker-Planck equations on a finite-volume mesh of
    /// the velocity interval, solved directly and extrapolated over the
    /// meshes with --cells and --cells/2 (Richardson): density.csv, the
    /// moments and the exact effective diffusion coefficient D_eff.
    #[command(after_help = crate::help::FP_STATIONARY)]
    Stationary(StationaryArgs),
    /// <v²>(t) and density snapshots from the paper's initial condition (TR-BDF2 or the paper's scheme).
    ///
    /// The time-dependent Fokker-Planck equations from v = 0 (Sec. 3):
    /// adaptive TR-BDF2 on the graded mesh (default) or the paper's
    /// explicit upwind scheme on a uniform mesh (--scheme paper).
    #[command(after_help = crate::help::FP_TRANSIENT)]
    Transient(TransientArgs),
    /// ⟨x⟩(t), ⟨x v⟩(t), ⟨x²⟩(t) and d ln⟨x²⟩/d ln t without sampling (moment chain).
    ///
    /// The position moments from the moment chain of the forward
    /// equations (TR-BDF2 in time, Richardson over nested meshes), on a log
    /// time grid: the ballistic-to-diffusive crossover of <x²>(t).
    #[command(after_help = crate::help::FP_MSD)]
    Msd(super::fp_msd::MsdArgs),
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MeshArg {
    /// Cells graded towards the (possibly singular) edges; v_r is a node.
    Graded,
    /// Equal cells (the paper's grid).
    Uniform,
}

/// `irtp fp stationary`.
#[derive(Args, Debug)]
pub struct StationaryArgs {
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    output: OutputArgs,
    /// Number of finite-volume cells (even when extrapolating).
    #[arg(long, default_value_t = 20_000, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    cells: usize,
    /// Cell placement.
    #[arg(long, value_enum, default_value = "graded")]
    mesh: MeshArg,
    /// Report the fine-mesh values instead of the Richardson extrapolation
    /// over the meshes with cells and cells/2.
    #[arg(long)]
    no_extrapolate: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SchemeArg {
    /// Graded mesh, adaptive TR-BDF2 (L-stable, step set by --rtol/--atol),
    /// ⟨v⟩, ⟨v²⟩ Richardson-extrapolated over cells, cells/2 and cells/4.
    Trbdf2,
    /// The paper's explicit upwind scheme on a uniform mesh (step set by --cfl).
    Paper,
}

/// `irtp fp transient`.
#[derive(Args, Debug)]
pub struct TransientArgs {
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    output: OutputArgs,
    /// Final time.
    #[arg(long, allow_hyphen_values = true)]
    t_max: f64,
    /// Time stepping and mesh.
    #[arg(long, value_enum, default_value = "trbdf2")]
    scheme: SchemeArg,
    /// Number of cells: graded, even (trbdf2), or uniform (paper: 2000 for
    /// tan, 1000 for tanh).
    #[arg(long, default_value_t = 2000, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    cells: usize,
    /// Number of equally spaced recording times of ⟨v²⟩(t) in [0, t_max].
    #[arg(long, default_value_t = 101, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    samples: usize,
    /// Number of equally spaced density snapshots in (0, t_max].
    #[arg(long, default_value_t = 5, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    snapshots: usize,
    /// Courant number in (0, 1] (--scheme paper only) [default: 0.5].
    #[arg(long, allow_hyphen_values = true)]
    cfl: Option<f64>,
    /// Relative tolerance of the local error per step, in [1e-13, 0.1]
    /// (--scheme trbdf2 only) [default: 1e-6].
    #[arg(long, allow_hyphen_values = true)]
    rtol: Option<f64>,
    /// Absolute tolerance of the local error of the cell masses per step, in
    /// [1e-20, 0.1] (--scheme trbdf2 only) [default: 1e-10].
    #[arg(long, allow_hyphen_values = true)]
    atol: Option<f64>,
}

impl FpArgs {
    /// Whether `--json` was given.
    pub fn json(&self) -> bool {
        match &self.command {
            FpCommand::Stationary(a) => a.output.json,
            FpCommand::Transient(a) => a.output.json,
            FpCommand::Msd(a) => a.output.json,
        }
    }
}

impl FpArgs {
    /// Validate the flags without solving.
    pub(crate) fn validate(&self) -> irtp::Result<()> {
        match &self.command {
            FpCommand::Stationary(a) => a.config().map(drop),
            FpCommand::Transient(a) => a.config().map(drop),
            FpCommand::Msd(a) => a.config().map(drop),
        }
    }
}

/// Run `irtp fp ...`.
pub fn run(args: &FpArgs, ctx: &Context) -> irtp::Result<Outcome> {
    match &args.command {
        FpCommand::Stationary(a) => stationary(a, ctx),
        FpCommand::Transient(a) => transient(a, ctx),
        FpCommand::Msd(a) => super::fp_msd::msd(a, ctx),
    }
}

impl StationaryArgs {
    /// Flags → model and solver options (the solver validates the options).
    fn config(&self) -> irtp::Result<(Params, StationaryOptions)> {
        let params = self.model.params()?;
        self.output.no_seed("fp stationary")?;
        let opts = StationaryOptions {
            cells: self.cells,
            mesh: match self.mesh {
                MeshArg::Graded => Mesh::Graded,
                MeshArg::Uniform => Mesh::Uniform,
            },
            extrapolate: !self.no_extrapolate,
        };
        // Measured: about 2.4 µs (~100 operations) and 128 bytes per cell
        // (2e6 cells: 4.8 s, 255 MB); 256 leaves room.
        // A noise model of N states: about N² times the work and memory
        // (band LU with N sub- and super-diagonals per cell).
        let k = match params.noise() {
            Some(_) => (params.chain()?.states() as f64).powi(2),
            None => 1.0,
        };
        let cost = super::budget::mesh(self.cells, 100.0 * k, 256.0 * k, vec!["cells"]);
        self.output
            .budget
            .check(&cost.per_drag_evaluation(&params.drag()))?;
        Ok((params, opts))
    }
}

impl TransientArgs {
    /// Refuse the flags of the other scheme (`--cfl` with trbdf2,
    /// `--rtol`/`--atol` with paper).
    fn reject_inapplicable(&self) -> irtp::Result<()> {
        let (flags, only) = match self.scheme {
            SchemeArg::Trbdf2 => (vec![("--cfl", self.cfl)], "only with --scheme paper"),
            SchemeArg::Paper => (
                vec![("--rtol", self.rtol), ("--atol", self.atol)],
                "only with --scheme trbdf2 (the paper scheme's step is set by --cfl)",
            ),
        };
        for (flag, value) in flags {
            if let Some(v) = value {
                return Err(irtp::Error::invalid(flag, v, only));
            }
        }
        Ok(())
    }

    /// Flags → model and solver options: `--samples` recording times in
    /// [0, t_max], `--snapshots` density times in (0, t_max].
    fn config(&self) -> irtp::Result<(Params, TransientOptions)> {
        let params = self.model.params()?;
        self.output.no_seed("fp transient")?;
        self.reject_inapplicable()?;
        let c = self.cells as f64;
        // TR-BDF2 keeps the state, 8 work vectors and the two columns of the
        // shifted solve on the fine mesh (and half of it on the coarse one).
        let per_cell = match self.scheme {
            SchemeArg::Paper => 128.0,
            SchemeArg::Trbdf2 => 400.0,
        };
        let memory = c * (per_cell + 16.0 * self.snapshots as f64)
            + 64.0 * self.samples as f64
            + 8.0 * self.snapshots as f64;
        let memory_drivers = vec!["cells", "snapshots", "samples"];
        // Memory first: the options allocate the recording times.
        self.output.budget.check(&super::budget::Cost {
            work: 0.0,
            unit: "cell updates",
            drivers: vec![],
            memory,
            memory_drivers: memory_drivers.clone(),
        })?;
        let defaults = TransientOptions::default();
        let base = TransientOptions {
            scheme: match self.scheme {
                SchemeArg::Trbdf2 => fp::Scheme::TrBdf2,
                SchemeArg::Paper => fp::Scheme::Paper,
            },
            cells: self.cells,
            cfl: self.cfl.unwrap_or(defaults.cfl),
            rtol: self.rtol.unwrap_or(defaults.rtol),
            atol: self.atol.unwrap_or(defaults.atol),
            ..defaults
        };
        let opts = TransientOptions::sampled(self.t_max, self.samples, self.snapshots, base)?;
        let plan = irtp::fp::transient_plan(&params, &opts)?;
        let mut drivers = match self.scheme {
            SchemeArg::Paper => vec!["cells", "t_max", "lambda", "rate", "cfl"],
            SchemeArg::Trbdf2 => vec!["cells", "rtol", "samples", "snapshots"],
        };
        drivers.extend(params.schedule().cost_drivers());
        self.output.budget.check(
            &super::budget::Cost {
                work: plan.work,
                unit: "cell updates",
                drivers,
                memory,
                memory_drivers,
            }
            .per_drag_evaluation(&params.drag()),
        )?;
        Ok((params, opts))
    }
}

/// Run `irtp fp stationary`: `density.csv`, `summary.json`, `run.json`.
pub fn stationary(a: &StationaryArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let (params, opts) = a.config()?;
    let out = open_out(
        "fp stationary",
        a.output.out.as_deref(),
        a.output.force.force,
    )?;
    let start = Instant::now();
    let s = fp::stationary(&params, &opts)?;
    // D_eff grows as 1/lambda (∞ at lambda = 0, ballistic): a tiny lambda > 0
    // overflows it.
    if params.lambda() > 0.0 && !s.d_eff.is_finite() {
        return Err(irtp::Error::Overflow {
            method: "fp stationary",
            quantity: "D_eff",
            meaning: "D_eff diverges as lambda -> 0 (ballistic motion)",
        });
    }
    let wall = start.elapsed().as_secs_f64();
    let mut summary = json!({
        "v2": s.v2,
        "v_mean": s.v_mean,
        "d_eff": s.d_eff,
        "d_eff_err": s.d_eff_err,
        "refractory_mass": s.refractory_mass,
        "atoms": atoms_json(&s.atoms),
        "cells": s.cells,
        "mass": s.mass,
        "mesh": s.mesh,
        "extrapolated": s.extrapolated,
        "grading": s.grading,
        "edge_exponent": s.edge_exponent,
        "fine": s.fine,
        "coarse": s.coarse,
        "params": params,
        "wall_time_s": wall,
    });
    // With position resetting the position has a stationary law: <x>, <x²>
    // replace D_eff, which would be meaningless.
    let diffusion = match (s.x_mean, s.x2) {
        (Some(x1), Some(x2)) => {
            let obj = summary.as_object_mut().expect("a JSON object");
            obj.remove("d_eff");
            obj.remove("d_eff_err");
            obj.insert("x_mean".into(), json!(x1));
            obj.insert("x2".into(), json!(x2));
            format!(
                "<x> = {}  <x^2> = {}  (position resetting: no D_eff)",
                fmt_digits(x1, 12),
                fmt_digits(x2, 12)
            )
        }
        _ => format!("D_eff = {}", fmt_estimate(s.d_eff, s.d_eff_err)),
    };
    // The refractory point mass as a last row of zero width.
    let point = (s.refractory_mass > 0.0).then(|| {
        [
            params.reset_velocity(),
            s.refractory_mass,
            s.refractory[0],
            s.refractory[1],
            0.0,
        ]
    });
    let density = match &s.noise {
        None => Table::from_rows(
            "density",
            &["v", "p", "p_plus", "p_minus", "dv"],
            (0..s.cells)
                .map(|i| [s.v[i], s.p[i], s.p_plus[i], s.p_minus[i], s.widths[i]])
                .chain(point),
        ),
        Some(n) => noise_density(&s, n),
    };
    let held = atoms_text(&s.atoms);
    let text = format!(
        "<v^2> = {}  <v> = {}  {diffusion}{held}  ({} cells, {} mesh{})\n",
        fmt_digits(s.v2, 12),
        fmt_digits(s.v_mean, 12),
        s.cells,
        s.mesh.name(),
        if s.extrapolated { ", extrapolated" } else { "" }
    );
    let (text, method) = match &s.noise {
        None => (text, format!("fv-upwind-direct-{}", s.mesh.name())),
        Some(n) => {
            noise_summary(&mut summary, n);
            (
                format!("{text}{}", noise_text(n)),
                format!("fv-nstate-band-direct-{}", s.mesh.name()),
            )
        }
    };
    let results = Results {
        method,
        seed: None,
        json: summary,
        parameters: json!({"model": params, "options": opts}),
        tables: vec![density],
        json_files: Vec::new(),
        text,
        wall_time_s: wall,
    };
    finish("fp stationary", results, out, ctx)
}

/// The `atoms` field of `results`: [{"v", "mass", "err"}] (an error that
/// is not finite as null).
pub(crate) fn atoms_json(atoms: &[irtp::model::VelocityAtom]) -> serde_json::Value {
    let err = |e: f64| e.is_finite().then_some(e);
    atoms
        .iter()
        .map(|a| json!({"v": a.v, "mass": a.mass, "err": err(a.err)}))
        .collect()
}

/// The atoms on the text line: `  atom at v = 0: 0.11111 ± 0.00002`.
pub(crate) fn atoms_text(atoms: &[irtp::model::VelocityAtom]) -> String {
    atoms
        .iter()
        .map(|a| {
            format!(
                "  atom at v = {}: {}",
                fmt_sig(a.v),
                fmt_estimate(a.mass, Some(a.err))
            )
        })
        .collect()
}

/// A mesh-extrapolated value: with its error estimate as `x ± err`
/// (digits the error supports); without one, to 12 digits.
fn fmt_estimate(x: f64, err: Option<f64>) -> String {
    match err {
        Some(e) if e > 0.0 && e.is_finite() && x.is_finite() => fmt_pm(x, e),
        _ => fmt_digits(x, 12),
    }
}

/// The density table of the N-state solver: v, p, one column p_s per
/// noise state (levels in `summary.json`), dv.
fn noise_density(s: &fp::Stationary, n: &fp::NoiseSummary) -> Table {
    let mut header = vec!["v".to_string(), "p".to_string()];
    header.extend((0..n.densities.len()).map(|k| format!("p_{k}")));
    header.push("dv".into());
    let mut columns = vec![s.v.clone(), s.p.clone()];
    columns.extend(n.densities.iter().cloned());
    columns.push(s.widths.clone());
    Table {
        name: "density",
        header,
        columns,
    }
}

/// The N-state solver's additions to `summary.json`: the noise's levels
/// and π, the computational domain and tail mass, the drift U = <v>, the
/// per-state means, the error estimates and observed orders, and the held
/// masses per state of an exponential refractory period.
fn noise_summary(summary: &mut serde_json::Value, n: &fp::NoiseSummary) {
    let obj = summary.as_object_mut().expect("a JSON object");
    obj.remove("edge_exponent");
    obj.insert("drift".into(), obj["v_mean"].clone());
    // Flat keys (`params` already records the noise spec and T).
    let errs = |e: Option<[f64; 3]>| e.map(|e| json!({"v_mean": e[0], "v2": e[1], "d_eff": e[2]}));
    for (k, v) in [
        ("levels", json!(n.levels)),
        ("pi", json!(n.pi)),
        ("domain", json!([n.domain.0, n.domain.1])),
        ("tail_mass", json!(n.tail_mass)),
        ("state_means", json!(n.state_means)),
        ("state_mean_errors", json!(n.state_mean_errors)),
        ("error_estimates", json!(errs(n.errors))),
        ("orders", json!(errs(n.orders))),
        ("density_l1_error", json!(n.density_l1_error)),
        ("meshes", json!(n.meshes)),
    ] {
        obj.insert(k.into(), v);
    }
    if !n.held.is_empty() {
        obj.insert("held".into(), json!(n.held));
    }
}

/// The N-state solver's line of the text output.
fn noise_text(n: &fp::NoiseSummary) -> String {
    let est = match n.errors {
        Some(e) => format!(
            "estimated errors: <v> {:.1e}, <v^2> {:.1e}, D_eff {:.1e}; ",
            e[0], e[1], e[2]
        ),
        None => String::new(),
    };
    format!(
        "{} noise states, T = {}, domain [{}, {}], {est}tail mass {:.1e}\n",
        n.levels.len(),
        fmt_sig(n.temperature),
        fmt_sig(n.domain.0),
        fmt_sig(n.domain.1),
        n.tail_mass
    )
}

/// Run `irtp fp transient`: `moments.csv`, `snapshots.csv`, `atoms.csv`
/// (with point masses), `summary.json`, `run.json`.
pub fn transient(a: &TransientArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let (params, opts) = a.config()?;
    let out = open_out(
        "fp transient",
        a.output.out.as_deref(),
        a.output.force.force,
    )?;
    let t_max = opts.t_max;
    let start = Instant::now();
    let tr = {
        let bar = ctx.reporter.stage("fp transient", 1);
        fp::transient_with_progress(&params, &opts, bar.as_ref())?
    };
    let wall = start.elapsed().as_secs_f64();
    let k = tr.times.len() - 1;
    let mesh_error = tr.v2_mesh_error.iter().copied().reduce(f64::max);
    let mut summary = json!({
        "v2_final": tr.v2[k],
        "v_mean_final": tr.v_mean[k],
        "mass": tr.mass[k],
        "refractory_mass": tr.refractory_mass[k],
        "atoms": atoms_json(&tr.atoms[k]),
        "atoms_t": tr.times.iter().zip(&tr.atoms)
            .map(|(t, a)| json!({"t": t, "atoms": atoms_json(a)}))
            .collect::<Vec<_>>(),
        "mass_error_max": tr.mass_error_max,
        "dt": tr.dt,
        "steps": tr.steps,
        "rejected": tr.rejected,
        "scheme": tr.scheme,
        "mesh": tr.mesh,
        "extrapolated": tr.extrapolated,
        "cells": tr.cells,
        "t_max": t_max,
        "params": params,
        "wall_time_s": wall,
    });
    // TR-BDF2 only (the paper scheme has no mesh error estimate).
    if let Some(e) = mesh_error {
        summary["v2_mesh_error_max"] = json!(e);
    }
    let steps = match tr.dt {
        Some(dt) => format!("dt = {}  ({} time steps", fmt_sig(dt), tr.steps),
        None => format!(
            "TR-BDF2 ({} steps, {} rejected, three meshes; <v^2> mesh error <= {:.1e}",
            tr.steps,
            tr.rejected,
            mesh_error.unwrap_or(0.0)
        ),
    };
    let text = format!(
        "<v^2>(t = {}) = {}  mass error max = {:.1e}  {}, {} cells, {} mesh{})\n",
        fmt_sig(t_max),
        fmt_digits(tr.v2[k], 12),
        tr.mass_error_max,
        steps,
        tr.cells,
        tr.mesh.name(),
        if tr.extrapolated {
            ", extrapolated"
        } else {
            ""
        }
    );
    let text = match atoms_text(&tr.atoms[k]) {
        a if a.is_empty() => text,
        a => format!(
            "{text}point mass at t = {} (not in snapshots.csv): {}\n",
            fmt_sig(t_max),
            a.trim_start()
        ),
    };
    let method = match tr.scheme {
        fp::Scheme::Paper => "fv-upwind-explicit-uniform",
        fp::Scheme::TrBdf2 if params.noise().is_some() => "fv-nstate-trbdf2-graded",
        fp::Scheme::TrBdf2 => "fv-upwind-trbdf2-graded",
    };
    let results = Results {
        method: method.into(),
        seed: None,
        json: summary,
        parameters: json!({"model": params, "options": opts}),
        tables: transient_tables(&tr, &params),
        json_files: Vec::new(),
        text,
        wall_time_s: wall,
    };
    finish("fp transient", results, out, ctx)
}

/// The tables of `fp transient`: `moments`, `snapshots` and, where the law
/// has point masses at some time, `atoms` (one row per recording time and
/// atom: `t, v, mass, err`, as `atoms_t` of the summary).
fn transient_tables(tr: &fp::Transient, params: &Params) -> Vec<Table> {
    let mut moments = Table {
        name: "moments",
        header: ["t", "v_mean", "v2", "mass"].map(String::from).to_vec(),
        columns: vec![
            tr.times.clone(),
            tr.v_mean.clone(),
            tr.v2.clone(),
            tr.mass.clone(),
        ],
    };
    // With a refractory period: the held point mass per recording time.
    if params.schedule().refractory.is_some() {
        moments.header.push("refractory_mass".into());
        moments.columns.push(tr.refractory_mass.clone());
    }
    // With point masses: their total mass and error per recording time.
    if tr.atoms.iter().any(|a| !a.is_empty()) {
        let sum = |f: fn(&irtp::model::VelocityAtom) -> f64| -> Vec<f64> {
            tr.atoms.iter().map(|a| a.iter().map(f).sum()).collect()
        };
        moments
            .header
            .extend(["atom_mass", "atom_err"].map(String::from));
        moments.columns.push(sum(|a| a.mass));
        moments.columns.push(sum(|a| a.err));
    }
    let snapshots = match tr.snapshots.first().map(|s| s.states.len()) {
        Some(ns) if ns > 0 => noise_snapshots(tr, ns),
        _ => Table::from_rows(
            "snapshots",
            &["t", "v", "p", "p_plus", "p_minus"],
            tr.snapshots.iter().flat_map(|s| {
                let v = &tr.v;
                (0..tr.cells).map(move |i| [s.t, v[i], s.p[i], s.p_plus[i], s.p_minus[i]])
            }),
        ),
    };
    let mut tables = vec![moments, snapshots];
    if tr.atoms.iter().any(|a| !a.is_empty()) {
        tables.push(Table::from_rows(
            "atoms",
            &["t", "v", "mass", "err"],
            tr.times
                .iter()
                .zip(&tr.atoms)
                .flat_map(|(&t, at)| at.iter().map(move |a| [t, a.v, a.mass, a.err])),
        ));
    }
    tables
}

/// The snapshots of the N-state solver: t, v, p, one column p_s per state.
fn noise_snapshots(tr: &fp::Transient, ns: usize) -> Table {
    let mut header = vec!["t".to_string(), "v".to_string(), "p".to_string()];
    header.extend((0..ns).map(|k| format!("p_{k}")));
    let mut columns = vec![Vec::new(); 3 + ns];
    for s in &tr.snapshots {
        for (i, &v) in tr.v.iter().enumerate() {
            columns[0].push(s.t);
            columns[1].push(v);
            columns[2].push(s.p[i]);
            for k in 0..ns {
                columns[3 + k].push(s.states[k][i]);
            }
        }
    }
    Table {
        name: "snapshots",
        header,
        columns,
    }
}
