//! SLURM job arrays for a sweep: one array task per shard (bundling several
//! points per task, so a large plan fits the cluster's `MaxArraySize`),
//! throttled with `%`, and a merge job that runs after the array
//! (`afterany`: it merges what finished and reports what did not).

use super::plan::Plan;
use super::store::write_atomic;
use irtp::error::{Error, Result};
use std::path::{Path, PathBuf};

/// How the array is laid out and submitted.
#[derive(Clone, Debug)]
pub struct SlurmOptions {
    /// `--partition` of both jobs.
    pub partition: Option<String>,
    /// `--time` of an array task.
    pub time: Option<String>,
    /// `--cpus-per-task` (the threads of each task).
    pub cpus_per_task: u32,
    /// The cluster's `MaxArraySize` (array indices stay below it).
    pub max_array: u64,
    /// Points per array task (default: as few as `max_array` allows).
    pub points_per_task: Option<u64>,
    /// Array tasks running at once (`%` of `--array`).
    pub throttle: u64,
    /// The `irtp` executable the tasks run.
    pub exe: PathBuf,
}

/// The written scripts.
#[derive(Clone, Debug, PartialEq)]
pub struct Scripts {
    /// Array tasks.
    pub tasks: u64,
    /// Points per task (at most).
    pub points_per_task: u64,
    /// The array job script.
    pub run: PathBuf,
    /// The merge job script.
    pub merge: PathBuf,
    /// A script submitting both.
    pub submit: PathBuf,
}

impl SlurmOptions {
    /// Every value that enters the scripts, checked before anything is
    /// written: the counts, the partition (SLURM's names: letters, digits,
    /// `_ . -`, commas between several), the time limit (SLURM's formats),
    /// and the sweep directory `root`, which `#SBATCH --output` lines hold
    /// unquoted. The array's layout for `items` work items.
    pub fn check(&self, items: u64, root: &Path) -> Result<(u64, u64)> {
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

/// The array's size: (tasks, points per task).
pub fn layout(points: u64, o: &SlurmOptions) -> Result<(u64, u64)> {
    for (name, value) in [
        ("cpus_per_task", u64::from(o.cpus_per_task)),
        ("max_array", o.max_array),
        ("throttle", o.throttle),
    ] {
        if value == 0 {
            return Err(Error::invalid(name, 0, format!("{name} >= 1")));
        }
    }
    let per = match o.points_per_task {
        Some(0) => return Err(Error::invalid("points_per_task", 0, "points_per_task >= 1")),
        Some(k) => k,
        None => points.div_ceil(o.max_array).max(1),
    };
    let tasks = points.div_ceil(per);
    if tasks > o.max_array {
        return Err(Error::invalid(
            "points_per_task",
            per,
            format!(
                "points_per_task >= {} so that {points} points fit {} array tasks (max_array)",
                points.div_ceil(o.max_array),
                o.max_array
            ),
        ));
    }
    Ok((tasks, per))
}

fn quote(p: &Path) -> String {
    format!("'{}'", p.display().to_string().replace('\'', r"'\''"))
}

/// Write `slurm/run.sbatch`, `slurm/merge.sbatch` and `slurm/submit.sh`
/// into the sweep directory `root` (absolute), whose `plan.toml` is `plan`.
pub fn write_scripts(plan: &Plan, root: &Path, o: &SlurmOptions) -> Result<Scripts> {
    let items = plan.len() as u64 * plan.particle_parts;
    let (tasks, per) = o.check(items, root)?;
    let dir = root.join("slurm");
    std::fs::create_dir_all(&dir).map_err(|e| crate::io::io_err(&dir, e))?;
    let mut head = String::from("#!/bin/bash\n");
    if let Some(p) = &o.partition {
        head += &format!("#SBATCH --partition={p}\n");
    }
    let (exe, rootq) = (quote(&o.exe), quote(root));
    let mut run = head.clone();
    run += &format!(
        "#SBATCH --job-name=irtp-sweep\n#SBATCH --array=0-{}%{}\n",
        tasks - 1,
        o.throttle
    );
    run += &format!("#SBATCH --cpus-per-task={}\n", o.cpus_per_task);
    if let Some(t) = &o.time {
        run += &format!("#SBATCH --time={t}\n");
    }
    run += &format!("#SBATCH --output={}/task-%A_%a.out\n", dir.display());
    run += &format!(
        "# {items} work items ({} points), at most {per} per task: task i runs shard i+1 of {tasks}.\nset -euo pipefail\n\
         export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-{}}}\"\n\
         exec {exe} sweep run {rootq}/plan.toml --out {rootq} --shard \"$((SLURM_ARRAY_TASK_ID + 1))/{tasks}\"\n",
        plan.len(),
        o.cpus_per_task
    );
    let mut merge = head;
    merge += &format!("#SBATCH --job-name=irtp-merge\n#SBATCH --cpus-per-task=1\n#SBATCH --output={}/merge-%j.out\n", dir.display());
    merge += &format!("set -euo pipefail\n{exe} sweep merge {rootq}\n");
    let submit = format!(
        "#!/bin/bash\n# Submit the array, then the merge job after it (afterany).\nset -euo pipefail\n\
         array=$(sbatch --parsable {run})\narray=${{array%%;*}}\n\
         merge=$(sbatch --parsable --dependency=afterany:$array {merge})\n\
         echo \"array job $array, merge job $merge\"\n",
        run = quote(&dir.join("run.sbatch")),
        merge = quote(&dir.join("merge.sbatch")),
    );
    let s = Scripts {
        tasks,
        points_per_task: per,
        run: dir.join("run.sbatch"),
        merge: dir.join("merge.sbatch"),
        submit: dir.join("submit.sh"),
    };
    write_atomic(&s.run, run.as_bytes())?;
    write_atomic(&s.merge, merge.as_bytes())?;
    write_atomic(&s.submit, submit.as_bytes())?;
    Ok(s)
}

/// Submit the array and the merge job (`sbatch --parsable`); their job ids.
pub fn submit(s: &Scripts) -> Result<(String, String)> {
    let array = sbatch(&[s.run.display().to_string()])?;
    let array = array.split(';').next().unwrap_or(&array).to_string();
    let merge = sbatch(&[
        format!("--dependency=afterany:{array}"),
        s.merge.display().to_string(),
    ])?;
    Ok((array, merge))
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
