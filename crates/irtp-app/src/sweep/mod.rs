//! Parameter sweeps: one command over a grid of parameters ([`plan`]),
//! every point in its own directory ([`store`]), run in parallel on this
//! machine or split into shards (`--shard K/N`, one per SLURM array task,
//! [`slurm`]), merged into one table that does not depend on the split.
//!
//! Each point runs through [`crate`] exactly as `irtp <command>` with
//! the point's flags would (its `run.json` records that command line), with
//! a seed derived from the plan seed and the point's parameters. A point
//! that fails records its error and the sweep goes on; a killed sweep,
//! run again, redoes only the points without a `result.json`.
//!
//! Layering: `sweep` sits above [`crate`], below the binary.

pub mod parts;
pub mod plan;
pub mod signac;
pub mod slurm;
pub mod store;
mod table;

pub use plan::{Plan, Point};
pub use store::{PointResult, State, Store};
pub use table::{write_table, Counts};

use crate::lock::{Acquired, FileLock};
use crate::{keywords, Context, Quiet};
use irtp::error::{Error, Result};
use rayon::prelude::*;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Which points a run takes: those whose plan index is `k - 1` modulo `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 1-based.
    pub k: u64,
    /// Number of shards.
    pub n: u64,
}

impl Shard {
    /// The whole plan.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// Whether point `index` belongs to this shard.
    pub fn has(&self, index: usize) -> bool {
        index as u64 % self.n == self.k - 1
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Shard, String> {
        let parsed = s
            .split_once('/')
            .and_then(|(k, n)| Some((k.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((k, n)) if k >= 1 && k <= n => Ok(Shard { k, n }),
            _ => Err(format!("'{s}' is not K/N with 1 <= K <= N")),
        }
    }
}

/// Progress of a sweep: points finished (failed among them) of those this
/// run takes.
pub trait Tally: Sync {
    /// `done` of `total` points finished, `failed` of them failed.
    fn update(&self, done: u64, failed: u64, total: u64);
}

impl Tally for () {
    fn update(&self, _: u64, _: u64, _: u64) {}
}

/// A point whose files do not verify.
#[derive(Clone, Debug, PartialEq)]
pub struct Damaged {
    /// The point's index in the plan.
    pub index: usize,
    /// Its id.
    pub id: String,
    /// What does not verify.
    pub why: String,
    /// Where a rerun moved its directory.
    pub moved_to: Option<PathBuf>,
}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
pub struct RunReport {
    /// Points of the plan.
    pub points: usize,
    /// Work items of the plan (points, or their parts with `particle_parts`).
    pub items: usize,
    /// Work items of this shard.
    pub shard_items: usize,
    /// Items this run computed.
    pub ran: usize,
    /// Of those, failed.
    pub failed: usize,
    /// Items of this shard already finished before the run.
    pub skipped: usize,
    /// Items this run listed that another worker finished meanwhile.
    pub by_others: usize,
    /// Points of this shard whose recorded result is a failure after the
    /// run (this run's, a failed part included, and earlier ones not
    /// retried).
    pub failed_points: usize,
    /// Damaged points this run moved aside (and computed again).
    pub moved_aside: Vec<Damaged>,
    /// The table, when every point of the plan is finished.
    pub table: Option<PathBuf>,
}

/// Options of a run.
#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    /// This run's share of the work items.
    pub shard: Shard,
    /// Run failed points again (else a failure is a finished point).
    pub retry_failed: bool,
}

/// Whether an item still needs work.
fn pending(plan: &Plan, store: &Store, it: &parts::Item, retry: bool) -> bool {
    let open = store.unfinished(it.point, retry);
    match it.part {
        None => open,
        Some(k) => open && !(parts::path(store, it.point, k).exists() && plan.particle_parts > 1),
    }
}

/// Counters of a run, shared by its threads.
#[derive(Default)]
struct Progress {
    handled: AtomicU64,
    ran: AtomicU64,
    failed: AtomicU64,
}

impl Progress {
    fn step(&self, ran: bool, ok: bool, total: u64, tally: &dyn Tally) {
        self.ran.fetch_add(u64::from(ran), Ordering::Relaxed);
        self.failed.fetch_add(u64::from(!ok), Ordering::Relaxed);
        let d = self.handled.fetch_add(1, Ordering::Relaxed) + 1;
        tally.update(d, self.failed.load(Ordering::Relaxed), total);
    }
}

/// Compute item `it` (whose claim the caller holds) if it is still pending:
/// another worker may have finished it since this run listed it.
fn work(plan: &Plan, store: &Store, it: &parts::Item, opts: RunOptions) -> Result<Option<bool>> {
    if !pending(plan, store, it, opts.retry_failed) {
        return Ok(None);
    }
    Ok(Some(match it.part {
        None => run_point(plan, store, it.point)?.status == "ok",
        Some(k) => parts::run_part(plan, store, it.point, k)?,
    }))
}

/// Run the work items of `plan` this shard takes and has not finished, in
/// parallel, into `root`; assemble split points whose parts are all there;
/// write `results.csv` when the whole plan is done.
///
/// Each item is claimed first ([`Store::claim_path`]): an item another
/// worker holds is left to it and, once this run has done the rest, waited
/// for and computed only if that worker did not finish it. So any number
/// of workers (shards or not) share one directory, each item computed once.
pub fn run(plan: &Plan, root: &Path, opts: RunOptions, tally: &dyn Tally) -> Result<RunReport> {
    let store = Store::open(root, plan)?;
    write_provenance(&store, plan, opts.shard)?;
    let points: Vec<Point> = plan.points().collect();
    let all = parts::items(plan, &points);
    let mine: Vec<parts::Item> = all
        .iter()
        .enumerate()
        .filter(|(i, _)| opts.shard.has(*i))
        .map(|(_, it)| *it)
        .collect();
    let moved = quarantine(&store, &mine)?;
    let todo: Vec<&parts::Item> = mine
        .iter()
        .filter(|it| pending(plan, &store, it, opts.retry_failed))
        .collect();
    let progress = Progress::default();
    let total = todo.len() as u64;
    tally.update(0, 0, total);
    let held = std::sync::Mutex::new(Vec::new());
    todo.par_iter().try_for_each(|it| -> Result<()> {
        let claim = store.claim_path(it.point, it.part);
        match FileLock::try_acquire(&claim)? {
            Acquired::Mine(_lock) => {
                let done = work(plan, &store, it, opts)?;
                progress.step(done.is_some(), done != Some(false), total, tally);
            }
            Acquired::Held(_) => held.lock().expect("no panic holds it").push(*it),
        }
        Ok(())
    })?;
    let held = held.into_inner().expect("no panic holds it");
    held.par_iter().try_for_each(|it| -> Result<()> {
        let _lock = FileLock::acquire_waiting(&store.claim_path(it.point, it.part))?;
        let done = work(plan, &store, it, opts)?;
        progress.step(done.is_some(), done != Some(false), total, tally);
        Ok(())
    })?;
    assemble_ready(plan, &store, &points, opts.retry_failed)?;
    let in_shard: std::collections::HashSet<usize> = mine.iter().map(|it| it.point.index).collect();
    let states = table::states(&store, &points);
    let (counts, failed_points) = table::counts(&points, &states, |p| in_shard.contains(&p.index));
    let table = if counts.missing == 0 && counts.damaged == 0 {
        Some(write_table(plan, &store, &points, &states)?.0)
    } else {
        None
    };
    let ran = progress.ran.into_inner() as usize;
    Ok(RunReport {
        points: plan.len(),
        items: all.len(),
        shard_items: mine.len(),
        ran,
        failed: progress.failed.into_inner() as usize,
        skipped: mine.len() - todo.len(),
        by_others: todo.len() - ran,
        failed_points,
        moved_aside: moved,
        table,
    })
}

/// Move aside the damaged points among `items` (each under its point's
/// claim, checked again once held): (index, id, why, new name).
fn quarantine(store: &Store, items: &[parts::Item]) -> Result<Vec<Damaged>> {
    let mut seen = std::collections::HashSet::new();
    let mut moved = Vec::new();
    for it in items.iter().filter(|it| seen.insert(it.point.index)) {
        if !matches!(store.state(it.point), State::Damaged(_)) {
            continue;
        }
        let _lock = FileLock::acquire_waiting(&store.claim_path(it.point, None))?;
        if let State::Damaged(why) = store.state(it.point) {
            let to = store.move_aside(it.point)?;
            moved.push(Damaged {
                index: it.point.index,
                id: it.point.id.clone(),
                why,
                moved_to: Some(to),
            });
        }
    }
    Ok(moved)
}

/// Assemble every split point whose parts are all stored and which has no
/// result yet (or a failed one, with `retry`), under the point's claim.
fn assemble_ready(plan: &Plan, store: &Store, points: &[Point], retry: bool) -> Result<()> {
    if plan.particle_parts <= 1 {
        return Ok(());
    }
    points.par_iter().try_for_each(|p| -> Result<()> {
        if store.unfinished(p, retry) && parts::complete(plan, store, p) {
            let _lock = FileLock::acquire_waiting(&store.claim_path(p, None))?;
            if store.unfinished(p, retry) && parts::complete(plan, store, p) {
                parts::assemble(plan, store, p)?;
            }
        }
        Ok(())
    })
}

/// Run one point through [`crate::run`] into its directory and record its
/// result; a failure of the computation is a failed point, an i/o failure
/// of the sweep directory stops the sweep.
fn run_point(plan: &Plan, store: &Store, p: &Point) -> Result<PointResult> {
    store.begin(plan, p)?;
    let t0 = std::time::Instant::now();
    let argv = plan
        .argv(p, Some(&store.dir(p)))
        .map_err(|e| bad_point(p, e))?;
    let cli = keywords::parse::<crate::Cli>(&plan.command, &argv).map_err(|e| bad_point(p, e))?;
    let ctx = Context {
        reporter: &Quiet,
        argv,
    };
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        crate::run(&cli.command, &ctx)
    }))
    .unwrap_or_else(|_| {
        Err(Error::Numerical {
            method: "irtp",
            reason: "internal error (a panic); please report it".into(),
        })
    });
    store.finish(p, point_result(p, outcome, t0.elapsed().as_secs_f64()))
}

/// A point's record from its command's outcome.
fn point_result(p: &Point, outcome: Result<crate::Outcome>, wall_time_s: f64) -> PointResult {
    match outcome {
        Ok(o) => PointResult {
            status: "ok".into(),
            error: None,
            method: Some(o.results.method.clone()),
            seed: p.seed,
            wall_time_s,
            summary: stable_summary(o.results.json),
            files: Default::default(),
            checksum: None,
        },
        Err(e) => failed(p, e.message_with(|n| n.to_string()), wall_time_s),
    }
}

fn failed(p: &Point, error: String, wall_time_s: f64) -> PointResult {
    PointResult {
        status: "failed".into(),
        error: Some(error),
        method: None,
        seed: p.seed,
        wall_time_s,
        summary: serde_json::Value::Null,
        files: Default::default(),
        checksum: None,
    }
}

fn bad_point(p: &Point, e: String) -> Error {
    Error::InvalidParameter {
        name: "plan",
        value: format!("point {} ({})", p.index, plan::describe(&p.params)),
        allowed: e,
    }
}

/// The summary without what changes from run to run (timings, the output path).
fn stable_summary(mut v: serde_json::Value) -> serde_json::Value {
    if let Some(o) = v.as_object_mut() {
        for k in ["wall_time_s", "particle_steps_per_s", "events_per_s", "out"] {
            o.shift_remove(k);
        }
    }
    v
}

/// `sweep.json` (written once: the plan, the software, its revision) and
/// one record per run under `runs/` (host, shard, command line, time).
fn write_provenance(store: &Store, plan: &Plan, shard: Shard) -> Result<()> {
    let sweep = store.root.join("sweep.json");
    if !sweep.exists() {
        let v = json!({
            "software": "irtp",
            "version": crate::VERSION,
            "git_revision": crate::GIT_REVISION,
            "command": plan.command,
            "plan_seed": plan.seed,
            "points": plan.len(),
            "point_seed": "first 8 bytes (little-endian) of SHA-256 of \"irtp sweep seed <plan seed> <parameters as sorted JSON>\"",
            "plan": plan.text,
        });
        store::write_atomic(
            &sweep,
            (serde_json::to_string_pretty(&v).expect("JSON") + "\n").as_bytes(),
        )?;
    }
    let host = gethostname::gethostname().to_string_lossy().into_owned();
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let run = json!({
        "host": host,
        "pid": std::process::id(),
        "shard": format!("{}/{}", shard.k, shard.n),
        "argv": std::env::args().collect::<Vec<_>>(),
        "threads": rayon::current_num_threads(),
        "started_unix": now,
        "version": crate::VERSION,
        "git_revision": crate::GIT_REVISION,
    });
    let dir = store.root.join("runs");
    std::fs::create_dir_all(&dir).map_err(|e| crate::io::io_err(&dir, e))?;
    let name = format!(
        "{host}-{}-{now}-shard{}of{}.json",
        std::process::id(),
        shard.k,
        shard.n
    );
    store::write_atomic(
        &dir.join(name),
        (serde_json::to_string_pretty(&run).expect("JSON") + "\n").as_bytes(),
    )
}

/// The work items of `plan` still to compute in `root`, as plan-order item
/// indices (the numbering of [`Shard`]): missing and damaged points, and
/// failed ones with `retry_failed`. A SLURM resubmission runs only the
/// array tasks that hold one ([`slurm`]).
pub fn pending_items(plan: &Plan, root: &Path, retry_failed: bool) -> Result<Vec<u64>> {
    let store = Store {
        root: root.to_path_buf(),
    };
    let points: Vec<Point> = plan.points().collect();
    Ok(parts::items(plan, &points)
        .iter()
        .enumerate()
        .filter(|(_, it)| pending(plan, &store, it, retry_failed))
        .map(|(i, _)| i as u64)
        .collect())
}

/// Read the plan a sweep directory holds; a directory without one (or no
/// directory) is bad input naming `DIR`.
pub fn plan_of(root: &Path) -> Result<Plan> {
    let path = root.join("plan.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory => Error::invalid(
            "dir",
            root.display(),
            "a sweep directory: one holding plan.toml, sweep.json and workspace/ \
             (irtp sweep run PLAN --out DIR writes them)",
        ),
        _ => crate::io::io_err(&path, e),
    })?;
    Plan::parse(&text)
}

/// Merge shard directories into `target` (which may be one of them): copy
/// their finished points that `target` lacks, check that points present in
/// both agree, and write `results.csv`. Every directory must hold the same
/// plan. Returns the counts and every damaged point seen (in the sources,
/// and in `target` where no source had a verified copy).
pub fn merge(target: &Path, sources: &[PathBuf]) -> Result<(Counts, Vec<Damaged>)> {
    let first = sources.first().map(PathBuf::as_path).unwrap_or(target);
    let plan = if target.join("plan.toml").exists() {
        plan_of(target)?
    } else {
        plan_of(first)?
    };
    let store = Store::open(target, &plan)?;
    let mut seen = Vec::new();
    for src in sources {
        if same_dir(src, target) {
            continue;
        }
        let other = plan_of(src)?;
        if other.text != plan.text {
            return Err(Error::invalid(
                "sweep_dir",
                src.display(),
                format!("a sweep directory of the same plan as {}", target.display()),
            ));
        }
        let src_store = Store::open(src, &plan)?;
        for p in plan.points() {
            seen.extend(table::take_point(&src_store, &store, &p)?);
        }
    }
    let points: Vec<Point> = plan.points().collect();
    assemble_ready(&plan, &store, &points, false)?;
    let states = table::states(&store, &points);
    seen.extend(table::damaged(&points, &states));
    Ok((write_table(&plan, &store, &points, &states)?.1, seen))
}

fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// A sweep directory's state.
#[derive(Clone, Debug)]
pub struct Status {
    /// The directory.
    pub dir: PathBuf,
    /// Points of the plan.
    pub points: usize,
    /// Finished points (verified).
    pub done: usize,
    /// Failed points: (index, id, error).
    pub failed: Vec<(usize, String, String)>,
    /// Missing points: (index, id, parameters).
    pub missing: Vec<(usize, String, String)>,
    /// Points whose files do not verify.
    pub damaged: Vec<Damaged>,
    /// Work items a live worker holds now: (lock file, holder).
    pub running: Vec<(String, String)>,
    /// Damaged point directories a rerun moved aside (kept for inspection).
    pub moved_aside: Vec<String>,
    /// Leftovers of killed runs (staging directories, temporary files).
    pub leftovers: Vec<String>,
    /// What `run` and `merge` refuse in the directory (an entry the sweep
    /// does not know about, a point of another plan): their refusal.
    pub foreign: Option<String>,
    /// The sweep was submitted to SLURM (`slurm/layout.json`): the command
    /// that finishes it resubmits the tasks of the missing points.
    pub slurm: bool,
}

impl Status {
    /// Whether every point is finished, verified and successful, and the
    /// directory holds nothing that `run` and `merge` refuse.
    pub fn complete(&self) -> bool {
        self.missing.is_empty()
            && self.failed.is_empty()
            && self.damaged.is_empty()
            && self.foreign.is_none()
    }
}

/// The state of the sweep directory `root` holding `plan`, every finished
/// point verified against its checksums (as `merge` and `run` do).
pub fn status(plan: &Plan, root: &Path) -> Result<Status> {
    let store = Store {
        root: root.to_path_buf(),
    };
    let points: Vec<Point> = plan.points().collect();
    let states = table::states(&store, &points);
    let mut s = Status {
        dir: root.to_path_buf(),
        points: plan.len(),
        done: 0,
        failed: Vec::new(),
        missing: Vec::new(),
        damaged: table::damaged(&points, &states),
        running: Vec::new(),
        moved_aside: Vec::new(),
        leftovers: Vec::new(),
        foreign: foreign_in(&store, plan),
        slurm: root.join("slurm").join("layout.json").is_file(),
    };
    for (p, state) in points.iter().zip(states) {
        match state {
            State::Done(r) => {
                s.done += 1;
                if r.status != "ok" {
                    s.failed
                        .push((p.index, p.id.clone(), r.error.unwrap_or_default()));
                }
            }
            State::Missing => s
                .missing
                .push((p.index, p.id.clone(), plan::describe(&p.params))),
            State::Damaged(_) => {}
        }
    }
    if let Ok(entries) = std::fs::read_dir(store.workspace()) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if !name.starts_with('.') {
                continue;
            }
            let lock = name.ends_with(".claim") || name.ends_with(".lock");
            match lock.then(|| FileLock::holder_of(&e.path())).flatten() {
                Some(who) => s.running.push((name, who)),
                None if name.contains(".damaged-") => s.moved_aside.push(name),
                None => s.leftovers.push(name),
            }
        }
    }
    s.running.sort();
    s.moved_aside.sort();
    s.leftovers.sort();
    Ok(s)
}

/// The refusal `run` and `merge` give the directory of `store`, if any (a
/// missing workspace is no refusal: a run creates it).
fn foreign_in(store: &Store, plan: &Plan) -> Option<String> {
    if !store.workspace().is_dir() {
        return None;
    }
    store
        .foreign(plan)
        .err()
        .map(|e| e.message_with(|n| format!("--{n}")))
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let d = self.dir.display();
        writeln!(
            f,
            "{d}: {} points: {} finished ({} failed), {} missing, {} damaged",
            self.points,
            self.done,
            self.failed.len(),
            self.missing.len(),
            self.damaged.len()
        )?;
        for (i, id, e) in &self.failed {
            writeln!(f, "failed  point {i} ({id}): {e}")?;
        }
        for p in &self.damaged {
            writeln!(f, "damaged point {} ({}): {}", p.index, p.id, p.why)?;
        }
        for (i, id, params) in self.missing.iter().take(20) {
            writeln!(f, "missing point {i} ({id}): {params}")?;
        }
        if self.missing.len() > 20 {
            writeln!(f, "missing ... and {} more", self.missing.len() - 20)?;
        }
        for (lock, who) in &self.running {
            writeln!(f, "running {lock}: {who}")?;
        }
        if !self.moved_aside.is_empty() {
            writeln!(
                f,
                "{} damaged point directories moved aside in {d}/workspace (kept for inspection): {}",
                self.moved_aside.len(),
                self.moved_aside.join(", ")
            )?;
        }
        if !self.leftovers.is_empty() {
            writeln!(f, "{} leftovers of interrupted runs in {d}/workspace (ignored; safe to delete when no run is active)", self.leftovers.len())?;
        }
        if let Some(why) = &self.foreign {
            writeln!(
                f,
                "not complete: sweep run and sweep merge refuse {d}: {why}"
            )?;
            if self.missing.is_empty() && self.damaged.is_empty() && self.failed.is_empty() {
                return Ok(());
            }
        }
        let (what, retry) = match (
            self.missing.is_empty() && self.damaged.is_empty(),
            self.failed.is_empty(),
        ) {
            (true, true) => return writeln!(f, "complete: {d}/results.csv"),
            (false, _) => (
                "to finish (damaged points are moved aside and computed again)",
                "",
            ),
            (true, false) => ("to retry the failed points", " --retry-failed"),
        };
        writeln!(f, "{what}: irtp sweep run {d}/plan.toml --out {d}{retry}")?;
        if self.slurm {
            writeln!(
                f,
                "or on the cluster, only the array tasks that hold them: irtp sweep slurm {d}/plan.toml --out {d} --missing{retry} --submit"
            )?;
        }
        Ok(())
    }
}
