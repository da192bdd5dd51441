//! SLURM job arrays for a sweep: one array task per shard (one point per
//! task, or several bundled when the plan has more points than
//! `--max-tasks`), split into as many arrays as the cluster's
//! `MaxArraySize` needs (read from `scontrol show config`), chained so that
//! the throttle (`%` of `--array`) holds for the whole sweep, and a merge
//! job after the last (`afterany`: it merges what finished and reports what
//! did not). A resubmission (`--missing`) keeps the first submission's
//! layout (`slurm/layout.json`) and lists only the array tasks that still
//! hold a missing, damaged (or, with `--retry-failed`, failed) point.

use super::plan::Plan;
use super::store::write_atomic;
use irtp::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// SLURM's default `MaxArraySize`, used where `scontrol` cannot be asked.
pub const DEFAULT_MAX_ARRAY: u64 = 1001;

/// How the arrays are laid out and submitted.
#[derive(Clone, Debug)]
pub struct SlurmOptions {
    /// `--partition` of every job.
    pub partition: Option<String>,
    /// `--time` of an array task.
    pub time: Option<String>,
    /// `--cpus-per-task` (the threads of each task).
    pub cpus_per_task: u32,
    /// The cluster's `MaxArraySize`: an array's indices run from 0 to this
    /// minus 1, so an array has at most this many tasks.
    pub max_array: u64,
    /// At most this many array tasks in the whole sweep (points are bundled
    /// beyond it).
    pub max_tasks: u64,
    /// Points per array task (default: 1, or as few as `max_tasks` allows).
    pub points_per_task: Option<u64>,
    /// Array tasks running at once (`%` of `--array`; the arrays of one
    /// sweep run one after the other, so this holds for the sweep).
    pub throttle: u64,
    /// The tasks run failed points again (`sweep run --retry-failed`).
    pub retry_failed: bool,
    /// The `irtp` executable the tasks run.
    pub exe: PathBuf,
}

/// The split of a sweep's work items into array tasks: task g (0-based)
/// runs shard g + 1 of `tasks`. Kept in `slurm/layout.json`, so that a
/// resubmission addresses the same shards.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Layout {
    /// Work items of the plan.
    pub items: u64,
    /// Array tasks (shards).
    pub tasks: u64,
    /// Work items per task, at most.
    pub points_per_task: u64,
    /// Tasks per array, at most (the cluster's MaxArraySize).
    pub max_array: u64,
}

/// One array of the sweep: `sbatch --array=INDICES%throttle` whose task i
/// runs shard `offset + i + 1`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArraySpec {
    /// Global index of the array's task 0.
    pub offset: u64,
    /// SLURM's index expression (`0-1000`, or `3,17-19` on resubmission).
    pub indices: String,
    /// Tasks in it.
    pub count: u64,
}

/// The written (or, for a dry run, rendered) scripts.
#[derive(Clone, Debug, PartialEq)]
pub struct Scripts {
    /// The layout they run.
    pub layout: Layout,
    /// The arrays, in submission order, and their scripts.
    pub arrays: Vec<(ArraySpec, PathBuf)>,
    /// The merge job script.
    pub merge: PathBuf,
    /// A script submitting all of them.
    pub submit: PathBuf,
}

impl SlurmOptions {
    /// Every value that enters the scripts, checked before anything is
    /// written: the counts, the partition (SLURM's names: letters, digits,
    /// `_ . -`, commas between several), the time limit (SLURM's formats),
    /// and the sweep directory `root`, which `#SBATCH --output` lines hold
    /// unquoted. The layout of `items` work items in array tasks.
    pub fn check(&self, items: u64, root: &Path) -> Result<Layout> {
        if let Some(p) = &self.partition {
            let name = |x: &str| {
                !x.is_empty()
                    && x.chars()
                        .all(|c| c.is_ascii_alphanumeric() || "_.-".contains(c))
            };
            if !p.split(',').all(name) {
                return Err(Error::invalid(
                    "partition",
                    p.escape_debug(),
                    "a SLURM partition name (letters, digits, _ . -; a comma between several)",
                ));
            }
        }
        if let Some(t) = &self.time {
            if !slurm_time(t) {
                return Err(Error::invalid(
                    "time",
                    t.escape_debug(),
                    "a SLURM time limit: MINUTES, MINUTES:SECONDS, HOURS:MINUTES:SECONDS, \
                     DAYS-HOURS, DAYS-HOURS:MINUTES, DAYS-HOURS:MINUTES:SECONDS or UNLIMITED",
                ));
            }
        }
        let text = root.to_string_lossy();
        if text
            .chars()
            .any(|c| c.is_whitespace() || c.is_control() || "\"'%\\".contains(c))
        {
            return Err(Error::invalid(
                "out",
                text.escape_debug(),
                "a sweep directory whose path has no spaces, quotes, % or backslashes \
                 (the #SBATCH --output lines hold it as it is)",
            ));
        }
        layout(items, self)
    }
}

/// SLURM's time formats (`sbatch --time`), or UNLIMITED / INFINITE.
fn slurm_time(t: &str) -> bool {
    if ["UNLIMITED", "INFINITE"].contains(&t.to_ascii_uppercase().as_str()) {
        return true;
    }
    let number = |s: &str| !s.is_empty() && s.len() <= 9 && s.bytes().all(|b| b.is_ascii_digit());
    let (days, clock) = match t.split_once('-') {
        Some((d, rest)) => (Some(d), rest),
        None => (None, t),
    };
    let fields: Vec<&str> = clock.split(':').collect();
    let days_ok = match days {
        Some(d) => number(d),
        None => true,
    };
    days_ok && fields.len() <= 3 && fields.iter().all(|f| number(f))
}

/// The split of `items` work items into array tasks (counts checked).
pub fn layout(items: u64, o: &SlurmOptions) -> Result<Layout> {
    for (name, value) in [
        ("cpus_per_task", u64::from(o.cpus_per_task)),
        ("max_array", o.max_array),
        ("max_tasks", o.max_tasks),
        ("throttle", o.throttle),
    ] {
        if value == 0 {
            return Err(Error::invalid(name, 0, format!("{name} >= 1")));
        }
    }
    let fewest = items.div_ceil(o.max_tasks).max(1);
    let per = match o.points_per_task {
        Some(0) => return Err(Error::invalid("points_per_task", 0, "points_per_task >= 1")),
        Some(k) => k,
        None => fewest,
    };
    let tasks = items.div_ceil(per).max(1);
    if tasks > o.max_tasks {
        return Err(Error::invalid(
            "points_per_task",
            per,
            format!("points_per_task >= {fewest} so that {items} work items fit {} array tasks (max_tasks)", o.max_tasks),
        ));
    }
    Ok(Layout {
        items,
        tasks,
        points_per_task: per,
        max_array: o.max_array,
    })
}

/// The arrays that run the global tasks `selected` (all tasks when None):
/// tasks `[j m, (j + 1) m)` form array j (m = MaxArraySize); an array none
/// of whose tasks is selected is left out.
pub fn arrays(l: &Layout, selected: Option<&[u64]>) -> Vec<ArraySpec> {
    let m = l.max_array;
    (0..l.tasks.div_ceil(m))
        .filter_map(|j| {
            let (lo, hi) = (j * m, ((j + 1) * m).min(l.tasks));
            let local: Vec<u64> = match selected {
                None => (0..hi - lo).collect(),
                Some(s) => s
                    .iter()
                    .filter(|&&g| g >= lo && g < hi)
                    .map(|g| g - lo)
                    .collect(),
            };
            (!local.is_empty()).then(|| ArraySpec {
                offset: lo,
                indices: ranges(&local),
                count: local.len() as u64,
            })
        })
        .collect()
}

/// `0-3,7,9-12` for sorted distinct indices (SLURM's `--array` syntax).
fn ranges(xs: &[u64]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < xs.len() {
        let mut j = i;
        while j + 1 < xs.len() && xs[j + 1] == xs[j] + 1 {
            j += 1;
        }
        out.push(if j == i {
            xs[i].to_string()
        } else {
            format!("{}-{}", xs[i], xs[j])
        });
        i = j + 1;
    }
    out.join(",")
}

/// The array tasks (global, 0-based) holding one of the work `items`.
pub fn tasks_of(l: &Layout, items: &[u64]) -> Vec<u64> {
    let mut t: Vec<u64> = items.iter().map(|i| i % l.tasks).collect();
    t.sort_unstable();
    t.dedup();
    t
}

/// The cluster's `MaxArraySize` from `scontrol show config`, or None where
/// scontrol is missing, fails, or does not answer within 5 s (it waits for
/// an unreachable controller much longer).
pub fn cluster_max_array() -> Option<u64> {
    use std::process::{Command, Stdio};
    let mut child = Command::new("scontrol")
        .args(["show", "config"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
    while child.try_wait().ok()?.is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let out = child.wait_with_output().ok()?;
    if !out.status.success() {
        return None;
    }
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|line| {
            let (key, value) = line.split_once('=')?;
            (key.trim() == "MaxArraySize").then(|| value.trim().parse().ok())?
        })
}

fn quote(p: &Path) -> String {
    format!("'{}'", p.display().to_string().replace('\'', r"'\''"))
}

/// The scripts' names and texts for the arrays `specs` of layout `l`, in
/// the sweep directory `root` (absolute): `slurm/run-J.sbatch` per array,
/// `slurm/merge.sbatch`, `slurm/submit.sh`.
pub fn render(
    plan: &Plan,
    root: &Path,
    o: &SlurmOptions,
    l: &Layout,
    specs: &[ArraySpec],
) -> Vec<(PathBuf, String)> {
    let dir = root.join("slurm");
    let mut head = String::from("#!/bin/bash\n");
    if let Some(p) = &o.partition {
        head += &format!("#SBATCH --partition={p}\n");
    }
    let (exe, rootq) = (quote(&o.exe), quote(root));
    let retry = if o.retry_failed {
        " --retry-failed"
    } else {
        ""
    };
    let mut files = Vec::new();
    for (j, a) in specs.iter().enumerate() {
        let mut run = head.clone();
        run += &format!(
            "#SBATCH --job-name=irtp-sweep\n#SBATCH --array={}%{}\n",
            a.indices, o.throttle
        );
        run += &format!("#SBATCH --cpus-per-task={}\n", o.cpus_per_task);
        if let Some(t) = &o.time {
            run += &format!("#SBATCH --time={t}\n");
        }
        run += &format!("#SBATCH --output={}/task-%A_%a.out\n", dir.display());
        run += &format!(
            "# {} work items ({} points), at most {} per task, in {} tasks: this array's task i runs shard {} + i + 1.\nset -euo pipefail\n\
             export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-{}}}\"\n\
             exec {exe} sweep run {rootq}/plan.toml --out {rootq} --shard \"$((SLURM_ARRAY_TASK_ID + {} + 1))/{}\"{retry}\n",
            l.items, plan.len(), l.points_per_task, l.tasks, a.offset, o.cpus_per_task, a.offset, l.tasks
        );
        files.push((dir.join(format!("run-{}.sbatch", j + 1)), run));
    }
    let mut merge = head;
    merge += &format!("#SBATCH --job-name=irtp-merge\n#SBATCH --cpus-per-task=1\n#SBATCH --output={}/merge-%j.out\n", dir.display());
    merge += &format!("set -euo pipefail\n{exe} sweep merge {rootq}\n");
    let mut submit = String::from(
        "#!/bin/bash\n# Submit the arrays one after the other (each after the last, afterany: the\n\
         # throttle holds for the whole sweep), then the merge job after all of them.\n\
         set -euo pipefail\nafter=\"\"\nids=\"\"\n",
    );
    for (run, _) in &files {
        submit += &format!(
            "id=$(sbatch --parsable ${{after:+--dependency=afterany:$after}} {})\nafter=${{id%%;*}}\nids=\"$ids${{ids:+:}}$after\"\n",
            quote(run)
        );
    }
    submit += &format!(
        "merge=$(sbatch --parsable --dependency=afterany:$ids {})\necho \"array jobs ${{ids//:/, }}; merge job $merge\"\n",
        quote(&dir.join("merge.sbatch"))
    );
    files.push((dir.join("merge.sbatch"), merge));
    files.push((dir.join("submit.sh"), submit));
    files
}

/// Write the scripts of [`render`] and `slurm/layout.json`.
pub fn write_scripts(
    files: &[(PathBuf, String)],
    l: &Layout,
    specs: &[ArraySpec],
    root: &Path,
) -> Result<Scripts> {
    let dir = root.join("slurm");
    std::fs::create_dir_all(&dir).map_err(|e| crate::io::io_err(&dir, e))?;
    for (path, text) in files {
        write_atomic(path, text.as_bytes())?;
    }
    let json = serde_json::to_string_pretty(l).expect("a layout serialises");
    write_atomic(&dir.join("layout.json"), json.as_bytes())?;
    let n = specs.len();
    Ok(Scripts {
        layout: *l,
        arrays: specs
            .iter()
            .cloned()
            .zip(files[..n].iter().map(|f| f.0.clone()))
            .collect(),
        merge: files[n].0.clone(),
        submit: files[n + 1].0.clone(),
    })
}

/// The layout of an earlier submission into `root` (`slurm/layout.json`).
pub fn read_layout(root: &Path) -> Result<Layout> {
    let path = root.join("slurm").join("layout.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        crate::io::io_err(
            &path,
            format!("{e} (no earlier `irtp sweep slurm` into this directory)"),
        )
    })?;
    serde_json::from_str(&text).map_err(|e| crate::io::io_err(&path, e))
}

/// Submit the arrays, each after the one before (afterany), then the merge
/// job after all of them; their job ids.
pub fn submit(s: &Scripts) -> Result<(Vec<String>, String)> {
    let mut ids: Vec<String> = Vec::new();
    for (_, run) in &s.arrays {
        let mut args = Vec::new();
        if let Some(last) = ids.last() {
            args.push(format!("--dependency=afterany:{last}"));
        }
        args.push(run.display().to_string());
        let id = sbatch(&args)?;
        ids.push(id.split(';').next().unwrap_or(&id).to_string());
    }
    let merge = sbatch(&[
        format!("--dependency=afterany:{}", ids.join(":")),
        s.merge.display().to_string(),
    ])?;
    Ok((ids, merge))
}

fn sbatch(args: &[String]) -> Result<String> {
    let out = std::process::Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .map_err(|e| Error::Io {
            path: "sbatch".into(),
            reason: format!("cannot run sbatch: {e} (is SLURM installed here?)"),
        })?;
    if !out.status.success() {
        return Err(Error::Io {
            path: "sbatch".into(),
            reason: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}
