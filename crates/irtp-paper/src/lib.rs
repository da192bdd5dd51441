//! Reproduction of the paper's figures 1, 2, 3, 5, 6 and 7, and one beyond
//! the paper (first-passage-time densities, `fpt`) (`irtp reproduce`).
//!
//! Each figure module holds its parameter set (a serialisable `Spec`, with a
//! full and a `quick` size) and works in three steps: `compute` runs the
//! library's solvers (exact event-driven sampler for particles, Fokker-Planck
//! solvers, backward MFPT equations, analytic r = 0 densities) into typed,
//! serialisable rows; `plot` turns the rows into a [`plot::Figure`]; `claims`
//! checks the paper's statements against the same rows ([`Claim`]).
//! [`run_figure`] computes one figure and [`store::Dir`] commits it (CSV,
//! PNG, SVG and its provenance `<fig>.json`, atomically) and rewrites the
//! index (`parameters.json`, `claims.json`, `claims.md`, `REPORT.md`,
//! `run.json`); a rerun skips finished figures. PNG and SVG need the cargo
//! feature `plot` (on by default); without it everything else is written and
//! `REPORT.md` says so.

pub mod compute;
pub mod fig1;
pub mod fig2;
pub mod fig5;
pub mod fig6;
pub mod fig7;
pub mod fpt;
pub mod media;
pub mod noise;
pub mod plot;
pub mod quicklook;
pub mod reproduce;
pub mod search;
pub mod store;

use clap::{Parser, Subcommand};
use irtp::error::{Error, Result};
use irtp::parallel::Progress;
use irtp_app::keywords::Vocabulary;
use irtp_app::{Context, Outcome, Runnable};
use serde::Serialize;
use std::str::FromStr;
use std::sync::atomic::{AtomicU64, Ordering};

/// Every command of the `irtp` program but `sweep`: the commands of
/// [`irtp_app`] and `reproduce`. The binary and the Python module parse
/// into this.
// Parsed once per run: the size of the largest flag set costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
pub enum Command {
    /// The app's commands (analytic, simulate, mfpt, fp).
    #[command(flatten)]
    App(irtp_app::Command),
    /// Regenerate the paper's figures and check its numeric claims (data, plots, claims.json).
    ///
    /// Each figure is computed from scratch with the paper's parameters,
    /// written as CSV data and a PNG plot, and its claims (D_eff ∝ r⁻²,
    /// the optimal resetting rate, ...) are checked against our numbers in
    /// claims.json with a verdict each; `all` runs every figure in paper
    /// order, then those beyond the paper. --quick runs the same code at
    /// small sizes (seconds).
    #[command(after_help = REPRODUCE_EXAMPLES)]
    Reproduce(reproduce::ReproduceArgs),
}

/// The examples that end `irtp reproduce --help` (run by the tests, at
/// `--quick` size).
const REPRODUCE_EXAMPLES: &str = "\
Examples:
  irtp reproduce fig2 --quick --out runs/paper     # P_s(v) with its cusp, in seconds
  irtp reproduce fig7 --out runs/paper             # tau against v_t - v_0 and r
  irtp reproduce all --out runs/paper              # every figure and claim (minutes on 2 cores)";

impl Command {
    /// The command's flags, behind the app's one command interface.
    pub fn args(&self) -> &dyn Runnable {
        match self {
            Command::App(c) => c.args(),
            Command::Reproduce(a) => a,
        }
    }

    /// Whether `--json` was given.
    pub fn json(&self) -> bool {
        self.args().json()
    }

    /// Run the command.
    pub fn run(&self, ctx: &Context) -> Result<Outcome> {
        self.args().run(ctx)
    }
}

/// The `irtp` vocabulary without `sweep` (the Python module's keywords).
#[derive(Parser, Debug)]
#[command(name = "irtp", version, about, long_about = None)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

impl Vocabulary for Cli {
    fn commands() -> Vec<&'static str> {
        let mut c = irtp_app::Cli::commands();
        c.push("reproduce");
        c
    }
}

/// Which figure to reproduce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Which {
    /// <v²>(t), both media.
    Fig1,
    /// P_s(v), tan, Sigma = 3.
    Fig2,
    /// P_s(v), tanh, Sigma = 0.6.
    Fig3,
    /// <x²>(t), both media.
    Fig5,
    /// D_eff(r), both media.
    Fig6,
    /// MFPT against v_t - v_0 and r.
    Fig7,
    /// Beyond the paper: first-passage-time densities.
    Fpt,
    /// Beyond the paper: the questions of Figs. 2 and 7 in every medium.
    Media,
    /// Beyond the paper: the search (first passage in position) in every medium.
    Search,
    /// Beyond the paper: the questions of Figs. 2, 6 and 7 under other noises.
    Noise,
}

impl Which {
    /// Every reproduced figure, in paper order.
    pub const ALL: [Which; 10] = [
        Which::Fig1,
        Which::Fig2,
        Which::Fig3,
        Which::Fig5,
        Which::Fig6,
        Which::Fig7,
        Which::Fpt,
        Which::Media,
        Which::Search,
        Which::Noise,
    ];
    /// File stem ("fig1", ...).
    pub fn name(self) -> &'static str {
        match self {
            Which::Fig1 => "fig1",
            Which::Fig2 => "fig2",
            Which::Fig3 => "fig3",
            Which::Fig5 => "fig5",
            Which::Fig6 => "fig6",
            Which::Fig7 => "fig7",
            Which::Fpt => "fpt",
            Which::Media => "media",
            Which::Search => "search",
            Which::Noise => "noise",
        }
    }
}

impl FromStr for Which {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Which::ALL
            .into_iter()
            .find(|w| w.name() == s)
            .ok_or_else(|| {
                Error::invalid(
                    "figure",
                    s,
                    "one of fig1, fig2, fig3, fig5, fig6, fig7, fpt, media, search, noise, all",
                )
            })
    }
}

/// Run options shared by all figures.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Options {
    /// Small sizes (CI): same code path, fewer particles, cells and points.
    pub quick: bool,
    /// Master seed; every curve derives its own seed from it.
    pub seed: u64,
}

/// Verdict of a claim check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Our numbers support the paper's statement.
    Agrees,
    /// Supported only with a qualification (stated in `ours`).
    Partly,
    /// Our numbers contradict the paper's statement.
    Differs,
}

/// One numeric claim, computed by code.
#[derive(Clone, Debug, Serialize)]
pub struct Claim {
    /// Stable identifier, e.g. "deff_r_minus_2_tan".
    pub id: String,
    /// Figure it belongs to.
    pub figure: &'static str,
    /// What the paper says.
    pub paper: String,
    /// What we find (numbers).
    pub ours: String,
    /// Verdict.
    pub verdict: Verdict,
    /// Machine-readable numbers behind `ours`.
    pub values: serde_json::Value,
}

/// Serialise a figure's rows (plain data: cannot fail) for `claims.json`
/// and `parameters.json`.
pub fn to_json<T: Serialize + ?Sized>(rows: &T) -> serde_json::Value {
    serde_json::to_value(rows).expect("figure rows are plain data")
}

/// A number as JSON writes it (`7.0`, `0.9`, `null` for NaN): how claim
/// texts print parameter values such as λ.
pub fn json_num(x: f64) -> String {
    serde_json::Value::from(x).to_string()
}

/// A figure's entry in `parameters.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Parameters {
    /// The figure's parameter set (its `Spec`), as JSON.
    pub spec: serde_json::Value,
    /// Per-curve stationary summaries (Fig. 1 only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stationary: Option<serde_json::Value>,
}

impl Parameters {
    /// Just the spec.
    pub fn of<T: Serialize>(spec: &T) -> Self {
        Parameters {
            spec: to_json(spec),
            stationary: None,
        }
    }
}

/// Everything one figure produced.
#[derive(Clone, Debug)]
pub struct FigureOutput {
    /// Which figure.
    pub which: Which,
    /// The plot (its data is also written as `<name>.csv`).
    pub figure: plot::Figure,
    /// The parameter set used (written into parameters.json).
    pub parameters: Parameters,
    /// Claims checked with this figure's data.
    pub claims: Vec<Claim>,
    /// Wall time in seconds.
    pub wall_time_s: f64,
}

/// Maps the (done, total) of one stage onto a slice of a figure-wide bar
/// with `SCALE` units in all.
pub struct Stage<'a> {
    inner: &'a dyn Progress,
    offset: f64,
    weight: f64,
}

/// Units of a figure-wide progress bar.
pub const SCALE: u64 = 1000;

/// `f(i, j, stage)` over a rows × cols grid of curves (medium × rate), all
/// curves at the same time (each is deterministic on its own, so the result
/// does not depend on the order; a curve whose work is too small to fill
/// the cores, or is serial like a moment chain, leaves them to the others),
/// each one equally weighted share of the figure's progress bar, collected
/// as `[row][col]`; the first error stops the work.
pub fn grid_of_curves<T: Send>(
    rows: usize,
    cols: usize,
    progress: &dyn Progress,
    f: impl Fn(usize, usize, &dyn Progress) -> Result<T> + Sync,
) -> Result<Vec<Vec<T>>> {
    rows_of_curves(&vec![cols; rows], progress, f)
}

/// [`grid_of_curves`] with rows of different lengths `cols[i]`.
pub fn rows_of_curves<T: Send>(
    cols: &[usize],
    progress: &dyn Progress,
    f: impl Fn(usize, usize, &dyn Progress) -> Result<T> + Sync,
) -> Result<Vec<Vec<T>>> {
    use rayon::prelude::*;
    let cells: Vec<(usize, usize)> = cols
        .iter()
        .enumerate()
        .flat_map(|(i, &n)| (0..n).map(move |j| (i, j)))
        .collect();
    let shares = Shares {
        inner: progress,
        done: cells.iter().map(|_| AtomicU64::new(0)).collect(),
    };
    let flat: Vec<T> = cells
        .par_iter()
        .enumerate()
        .map(|(k, &(i, j))| f(i, j, &Share { all: &shares, k }))
        .collect::<Result<_>>()?;
    let mut it = flat.into_iter();
    Ok(cols
        .iter()
        .map(|&n| it.by_ref().take(n).collect())
        .collect())
}

/// Stages that run at the same time: each keeps its own fraction done (in
/// units of [`SCALE`]), and the figure-wide bar shows their mean.
struct Shares<'a> {
    inner: &'a dyn Progress,
    done: Vec<AtomicU64>,
}

/// Stage `k` of [`Shares`].
struct Share<'a> {
    all: &'a Shares<'a>,
    k: usize,
}

impl Progress for Share<'_> {
    fn update(&self, done: u64, total: u64) {
        let units = if total == 0 {
            SCALE
        } else {
            (SCALE as f64 * done as f64 / total as f64).round() as u64
        };
        self.all.done[self.k].fetch_max(units.min(SCALE), Ordering::Relaxed);
        let sum: u64 = self
            .all
            .done
            .iter()
            .map(|d| d.load(Ordering::Relaxed))
            .sum();
        self.all
            .inner
            .update(sum / self.all.done.len().max(1) as u64, SCALE);
    }
    fn cancelled(&self) -> bool {
        self.all.inner.cancelled()
    }
}

impl<'a> Stage<'a> {
    /// Stage `k` of `n` equally weighted stages.
    pub fn new(inner: &'a dyn Progress, k: usize, n: usize) -> Self {
        let n = n.max(1) as f64;
        Stage {
            inner,
            offset: k as f64 / n,
            weight: 1.0 / n,
        }
    }
}

impl Progress for Stage<'_> {
    fn update(&self, done: u64, total: u64) {
        let f = if total == 0 {
            1.0
        } else {
            done as f64 / total as f64
        };
        let units = ((self.offset + self.weight * f) * SCALE as f64).round() as u64;
        self.inner.update(units.min(SCALE), SCALE);
    }
    fn cancelled(&self) -> bool {
        self.inner.cancelled()
    }
}

/// A seed for curve `index` of figure `fig`, derived from the master seed.
pub fn curve_seed(seed: u64, fig: Which, index: u64) -> u64 {
    use rand::RngCore;
    irtp::rng::stream_for(seed, 0xF16_0000 + fig as u64, index).next_u64()
}

/// Compute one figure. `progress` receives (done, SCALE).
pub fn run_figure(which: Which, opts: &Options, progress: &dyn Progress) -> Result<FigureOutput> {
    let t0 = std::time::Instant::now();
    let mut out = match which {
        Which::Fig1 => fig1::run(opts, progress)?,
        Which::Fig2 => fig2::run(fig2::Medium::Tan, opts, progress)?,
        Which::Fig3 => fig2::run(fig2::Medium::Tanh, opts, progress)?,
        Which::Fig5 => fig5::run(opts, progress)?,
        Which::Fig6 => fig6::run(opts, progress)?,
        Which::Fig7 => fig7::run(opts, progress)?,
        Which::Fpt => fpt::run(opts, progress)?,
        Which::Media => media::run(opts, progress)?,
        Which::Search => search::run(opts, progress)?,
        Which::Noise => noise::run(opts, progress)?,
    };
    out.wall_time_s = t0.elapsed().as_secs_f64();
    progress.update(SCALE, SCALE);
    Ok(out)
}

fn json_short(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Array(a) if a.len() > 12 => format!(
            "{} values from {} to {}",
            a.len(),
            json_short(&a[0]),
            json_short(&a[a.len() - 1])
        ),
        serde_json::Value::Array(a) => {
            format!(
                "[{}]",
                a.iter().map(json_short).collect::<Vec<_>>().join(", ")
            )
        }
        serde_json::Value::Number(n) if n.is_u64() || n.is_i64() => n.to_string(),
        serde_json::Value::Number(n) => n.as_f64().map_or(n.to_string(), fmt_num),
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Object(o) => format!(
            "{{{}}}",
            o.iter()
                .map(|(k, v)| format!("{k}: {}", json_short(v)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        other => other.to_string(),
    }
}

/// Whether this build renders PNG and SVG images (cargo feature `plot`).
pub const IMAGES: bool = cfg!(feature = "plot");

/// What `REPORT.md` and `irtp reproduce` say when images are not rendered.
pub const NO_IMAGES: &str =
    "No PNG/SVG images: they need the cargo feature `plot` (on by default), \
     which this build lacks. The figures' data are in the CSV files.";

/// Complementary error function (W. J. Cody's rational approximations are
/// overkill here: Numerical Recipes' erfcc, relative error < 1.2e-7, is
/// plenty for tail probabilities of z-scores).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Limit for the maximum of `n` independent z-scores: 4 (the project's
/// 4-sigma rule), raised to the two-sided Bonferroni bound at family-wise
/// level 1 % (P(|Z| > z) = 0.01 / n) once that exceeds 4 (n ≳ 160). Every
/// "max |z|" verdict uses it.
pub fn z_crit(n: usize) -> f64 {
    bonferroni_z(n).max(4.0)
}

/// Two-sided z with P(|Z| > z) = 0.01 / n.
pub fn bonferroni_z(n: usize) -> f64 {
    let p = 0.01 / n.max(1) as f64;
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if erfc(mid / std::f64::consts::SQRT_2) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Format a number for a legend / table: up to 3 significant digits, no trailing zeros.
pub fn fmt_num(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e4).contains(&a) {
        let d = (2 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.d$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.2e}")
    }
}
