//! `irtp sweep {run, merge, status, slurm, collect}`: parameter sweeps (library:
//! [`irtp_app::sweep`]).

use super::progress::Bar;
use clap::{Args, Subcommand};
use irtp_app::sweep::{self, slurm, Plan, RunOptions, Shard, Tally};
use std::path::{Path, PathBuf};

/// Run one command over a grid of parameters (a TOML plan), here or on a SLURM cluster.
#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(subcommand)]
    command: SweepCommand,
}

/// The subcommands of `irtp sweep`.
#[derive(Subcommand, Debug)]
enum SweepCommand {
    /// Run the plan's points (those of --shard), skipping finished ones; results.csv when all are done.
    ///
    /// Every point of the plan's grid is one run of its command, written
    /// under --out with its own seed (derived from the plan's seed and the
    /// point); an interrupted or failed sweep resumes where it stopped.
    /// --shard K/N runs every N-th point, for several machines.
    #[command(after_help = RUN_EXAMPLES)]
    Run(RunArgs),
    /// Merge shard directories into the first one and write results.csv (exit 3 if points are missing).
    #[command(after_help = MERGE_EXAMPLES)]
    Merge(MergeArgs),
    /// Points done, failed and missing, and the command that finishes them.
    #[command(after_help = STATUS_EXAMPLES)]
    Status(StatusArgs),
    /// Write (and with --submit, submit) a SLURM job array and its merge job.
    ///
    /// One array task per point (or per bundle of points, within
    /// --max-tasks), split into several arrays above the cluster's
    /// MaxArraySize, and a merge job that runs after them; --missing
    /// resubmits only the tasks whose points are missing.
    #[command(after_help = SLURM_EXAMPLES)]
    Slurm(SlurmArgs),
    /// The sweep as one dataset file over the plan's axes: netCDF, zarr or CSV (through the Python module).
    #[command(after_help = COLLECT_EXAMPLES)]
    Collect(CollectArgs),
}

/// The opening of `irtp sweep --help`, naming the commands a plan may
/// sweep ([`sweep::plan::SWEEPABLE`]).
pub fn long_about() -> String {
    format!(
        "Parameter sweeps from a TOML plan: one command ({}) over a grid of its flags \
         (docs/sweeps.md, examples/sweeps/), run here (sharded, resumable) or as SLURM job \
         arrays, merged into one results.csv and collected as an xarray dataset.",
        sweep::plan::SWEEPABLE.join(", ")
    )
}

/// The examples of `irtp sweep --help` (run by the tests, as those below).
pub const EXAMPLES: &str = "\
Examples:
  irtp sweep run examples/sweeps/analytic.toml --out runs/sweep   # the r = 0 regimes over (Sigma, lambda)
  irtp sweep status runs/sweep
  irtp plot runs/sweep                             # a heat map of the first result";

/// The examples of `irtp sweep run --help`.
const RUN_EXAMPLES: &str = "\
Examples:
  irtp sweep run examples/sweeps/fp_stationary.toml --out runs/sweep-fp
  irtp sweep run examples/sweeps/analytic.toml --out runs/sweep --shard 1/2   # half the points";

/// The examples of `irtp sweep merge --help`.
const MERGE_EXAMPLES: &str = "\
Examples:
  irtp sweep run examples/sweeps/analytic.toml --out runs/sweep --shard 1/2
  irtp sweep run examples/sweeps/analytic.toml --out runs/sweep-2 --shard 2/2
  irtp sweep merge runs/sweep runs/sweep-2         # runs/sweep/results.csv";

/// The examples of `irtp sweep status --help`.
const STATUS_EXAMPLES: &str = "\
Examples:
  irtp sweep run examples/sweeps/analytic.toml --out runs/sweep
  irtp sweep status runs/sweep                     # exit 3 while points are missing";

/// The examples of `irtp sweep slurm --help`.
const SLURM_EXAMPLES: &str = "\
Examples:
  irtp sweep slurm examples/sweeps/mfpt.toml --out runs/sweep-mfpt --time 00:30:00 --dry-run
  irtp sweep slurm examples/sweeps/mfpt.toml --out runs/sweep-mfpt --time 00:30:00 --max-array 1001 --submit";

/// The examples of `irtp sweep collect --help` (the Python module with its
/// xarray extra: pip install './python[xarray]').
const COLLECT_EXAMPLES: &str = "\
Examples:
  irtp sweep run examples/sweeps/analytic.toml --out runs/sweep
  irtp sweep collect runs/sweep --out runs/sweep.nc              # netCDF, for xarray
  irtp sweep collect runs/sweep --format csv --out runs/sweep-csv";

/// `irtp sweep collect`: the Python module's `python -m irtp collect`, whose
/// libraries (xarray with h5netcdf, zarr) write these formats; the binary
/// itself writes only CSV and JSON.
#[derive(Args, Debug)]
struct CollectArgs {
    /// Sweep directory.
    dir: PathBuf,
    /// netcdf (a .nc file), zarr (a store directory) or csv (a directory).
    #[arg(long, default_value = "netcdf", value_parser = ["netcdf", "zarr", "csv"])]
    format: String,
    /// The file (netcdf) or directory (zarr, csv) to write.
    #[arg(long)]
    out: PathBuf,
    /// The Python interpreter that has the irtp module with its xarray extra.
    #[arg(long, default_value = "python3")]
    python: PathBuf,
}

#[derive(Args, Debug)]
struct RunArgs {
    /// The plan (TOML; see docs/sweeps.md).
    plan: PathBuf,
    /// Sweep directory.
    #[arg(long)]
    out: PathBuf,
    /// Run only shard K of N (points whose index is K-1 modulo N).
    #[arg(long, default_value = "1/1", value_parser = parse_shard)]
    shard: Shard,
    /// Run failed points again.
    #[arg(long)]
    retry_failed: bool,
}

#[derive(Args, Debug)]
struct MergeArgs {
    /// The sweep directory to merge into, then shard directories to take points from.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
}

#[derive(Args, Debug)]
struct StatusArgs {
    /// Sweep directory.
    dir: PathBuf,
}

#[derive(Args, Debug)]
struct SlurmArgs {
    /// The plan (TOML).
    plan: PathBuf,
    /// Sweep directory (on a file system the compute nodes share).
    #[arg(long)]
    out: PathBuf,
    /// SLURM partition.
    #[arg(long)]
    partition: Option<String>,
    /// Time limit of one array task (SLURM format, e.g. 01:00:00).
    #[arg(long)]
    time: Option<String>,
    /// CPUs (threads) per array task.
    #[arg(long, default_value_t = 1)]
    cpus_per_task: u32,
    /// The cluster's MaxArraySize: an array has at most this many tasks, and
    /// a larger sweep is split into several arrays [default: from `scontrol
    /// show config`, else SLURM's default 1001].
    #[arg(long)]
    max_array: Option<u64>,
    /// At most this many array tasks in the whole sweep; beyond it points are
    /// bundled into tasks.
    #[arg(long, default_value_t = 10_000)]
    max_tasks: u64,
    /// Points per array task [default: 1, or the fewest that fit --max-tasks].
    #[arg(long)]
    points_per_task: Option<u64>,
    /// Array tasks running at once (the % of --array; the arrays of a sweep
    /// run one after the other, so this holds for the whole sweep).
    #[arg(long, default_value_t = 100)]
    throttle: u64,
    /// Only the array tasks that still hold a missing or damaged point, in
    /// the layout of the first submission into --out (`sweep status` prints
    /// this command).
    #[arg(long)]
    missing: bool,
    /// The tasks run failed points again too (with --missing: and the tasks
    /// holding a failed point are submitted).
    #[arg(long)]
    retry_failed: bool,
    /// Print the scripts instead of writing them; nothing is written or
    /// submitted.
    #[arg(long, conflicts_with = "submit")]
    dry_run: bool,
    /// Submit both jobs (sbatch) and print their ids.
    #[arg(long)]
    submit: bool,
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse()
}

/// A bar of points: done of total, failed, time left.
struct PointsBar(Bar);

impl Tally for PointsBar {
    fn update(&self, done: u64, failed: u64, total: u64) {
        self.0.message(&format!("{failed} failed"));
        irtp::parallel::Progress::update(&self.0, done, total);
    }
}

fn read_plan(path: &Path) -> anyhow::Result<Plan> {
    let text = std::fs::read_to_string(path).map_err(|e| irtp::Error::Io {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    Ok(Plan::parse(&text)?)
}

/// Run `irtp sweep ...`; the process exit code (0, or 3 when points are
/// missing or failed).
pub fn run(args: SweepArgs) -> anyhow::Result<u8> {
    match args.command {
        SweepCommand::Run(a) => run_points(a),
        SweepCommand::Merge(a) => merge(a),
        SweepCommand::Status(a) => status(a),
        SweepCommand::Slurm(a) => slurm_scripts(a),
        SweepCommand::Collect(a) => collect(a),
    }
}

fn run_points(a: RunArgs) -> anyhow::Result<u8> {
    let plan = read_plan(&a.plan)?;
    let bar = PointsBar(Bar::new("points", 0));
    let opts = RunOptions {
        shard: a.shard,
        retry_failed: a.retry_failed,
    };
    let r = sweep::run(&plan, &a.out, opts, &bar)?;
    drop(bar);
    for d in &r.moved_aside {
        let to = d.moved_to.as_ref().map(|p| p.display().to_string());
        println!(
            "damaged point {} ({}): {}; moved aside to {} and computed again",
            d.index,
            d.id,
            d.why,
            to.unwrap_or_default()
        );
    }
    println!(
        "{}: {} points, {} work items; shard {}/{} has {}: ran {} ({} failed), {} already finished, {} finished by another worker",
        a.out.display(),
        r.points,
        r.items,
        a.shard.k,
        a.shard.n,
        r.shard_items,
        r.ran,
        r.failed,
        r.skipped,
        r.by_others
    );
    match r.table {
        Some(t) => println!("all points finished: {}", t.display()),
        None => println!(
            "points of other shards are missing: `irtp sweep status {}`",
            a.out.display()
        ),
    }
    // A failed point of this shard is not success (exit 3, as for missing
    // points in `status` and `merge`): pipelines must not take the table as done.
    if r.failed_points > 0 {
        println!(
            "{} points of this shard failed: `irtp sweep status {}` lists them; --retry-failed runs them again",
            r.failed_points,
            a.out.display()
        );
        return Ok(3);
    }
    Ok(0)
}

fn merge(a: MergeArgs) -> anyhow::Result<u8> {
    let (target, sources) = a.dirs.split_first().expect("clap requires one dir");
    let (c, damaged) = sweep::merge(target, sources)?;
    for d in &damaged {
        let moved = match &d.moved_to {
            Some(p) => format!("; the damaged copy moved aside to {}", p.display()),
            None => String::new(),
        };
        println!("damaged point {} ({}): {}{moved}", d.index, d.id, d.why);
    }
    println!(
        "{}: {} points finished ({} failed), {} missing, {} damaged; wrote results.csv",
        target.display(),
        c.done,
        c.failed,
        c.missing,
        c.damaged
    );
    Ok(if c.complete() { 0 } else { 3 })
}

fn status(a: StatusArgs) -> anyhow::Result<u8> {
    let plan = sweep::plan_of(&a.dir)?;
    let report = sweep::status(&plan, &a.dir)?;
    print!("{report}");
    Ok(if report.complete() { 0 } else { 3 })
}

fn slurm_scripts(a: SlurmArgs) -> anyhow::Result<u8> {
    let plan = read_plan(&a.plan)?;
    let (max_array, source) = match a.max_array {
        Some(m) => (m, "--max-array"),
        None => match slurm::cluster_max_array() {
            Some(m) => (m, "scontrol show config"),
            None => (
                slurm::DEFAULT_MAX_ARRAY,
                "SLURM's default; scontrol did not say",
            ),
        },
    };
    let o = slurm::SlurmOptions {
        partition: a.partition,
        time: a.time,
        cpus_per_task: a.cpus_per_task,
        max_array,
        max_tasks: a.max_tasks,
        points_per_task: a.points_per_task,
        throttle: a.throttle,
        retry_failed: a.retry_failed,
        exe: std::env::current_exe()?,
    };
    // Every value is checked before --out is created.
    let out = std::path::absolute(&a.out)?;
    let mut layout = o.check(plan.len() as u64 * plan.particle_parts, &out)?;
    let selected = if a.missing {
        layout = slurm::read_layout(&out)?;
        let pending = sweep::pending_items(&plan, &out, a.retry_failed)?;
        Some(slurm::tasks_of(&layout, &pending))
    } else {
        None
    };
    let specs = slurm::arrays(&layout, selected.as_deref());
    if specs.is_empty() {
        println!("{}: no missing points: nothing to submit", out.display());
        return Ok(0);
    }
    let files = slurm::render(&plan, &out, &o, &layout, &specs);
    let tasks: u64 = specs.iter().map(|s| s.count).sum();
    let summary = format!(
        "{} work items ({} points), {} of {} array tasks of at most {} items in {} arrays (MaxArraySize {max_array}: {source})",
        layout.items,
        plan.len(),
        tasks,
        layout.tasks,
        layout.points_per_task,
        specs.len()
    );
    if a.dry_run {
        println!("# dry run: {summary}; nothing written");
        for (path, text) in &files {
            println!("# ---- {} ----\n{text}", path.display());
        }
        return Ok(0);
    }
    // The directory is checked (a sweep of this plan, or new: nothing
    // inside another sweep), created, and holds the plan before any task starts.
    sweep::Store::open(&a.out, &plan)?;
    let root = a.out.canonicalize()?;
    let files = slurm::render(&plan, &root, &o, &layout, &specs);
    let s = slurm::write_scripts(&files, &layout, &specs, &root)?;
    println!("{summary}: {}", s.submit.display());
    if a.submit {
        let (arrays, merge) = slurm::submit(&s)?;
        println!(
            "submitted: array jobs {}; merge job {merge} (afterany:{})",
            arrays.join(", "),
            arrays.join(":")
        );
    } else {
        println!("submit with: bash {}", s.submit.display());
    }
    Ok(0)
}

/// Run `python -m irtp collect` (exit code passed on: 0, 3 for unfinished
/// points, 2 for bad input); refused naming `--python` where that Python
/// lacks the module or its xarray extra.
fn collect(a: CollectArgs) -> anyhow::Result<u8> {
    sweep::plan_of(&a.dir)?;
    let python = a.python.display().to_string();
    let missing = |why: String| {
        irtp::Error::InvalidParameter {
        name: "--python",
        value: python.clone(),
        allowed: format!(
            "a Python with the irtp module and its xarray extra (pip install './python[xarray]'): {why}"
        ),
    }
    };
    let probe = std::process::Command::new(&a.python)
        .args(["-c", "import irtp._sweep, xarray"])
        .output()
        .map_err(|e| missing(format!("cannot run it ({e})")))?;
    if !probe.status.success() {
        let err = String::from_utf8_lossy(&probe.stderr);
        let last = err.trim().lines().last().unwrap_or("").to_string();
        return Err(missing(last).into());
    }
    let status = std::process::Command::new(&a.python)
        .args(["-m", "irtp", "collect"])
        .arg(&a.dir)
        .args(["--format", &a.format, "--out"])
        .arg(&a.out)
        .status()
        .map_err(|e| missing(format!("cannot run it ({e})")))?;
    Ok(status.code().map_or(1, |c| c.clamp(0, 255) as u8))
}
