//! A sweep's directory: `plan.toml`, `sweep.json` (provenance),
//! `results.csv`, and one directory per point under `workspace/` named by
//! its id, holding `signac_statepoint.json` (its parameters: the layout
//! signac- and row-style workflow tools read), the command's outputs and,
//! written last, `result.json`. Every file is written to a temporary name
//! and renamed into place, so a killed run leaves either the whole file or
//! none of it; a point counts as finished only once its `result.json` is in
//! place.
//!
//! `result.json` records the SHA-256 of every file of the point and of
//! itself ([`PointResult::seal`]): a point whose files were edited,
//! truncated or deleted since is [`State::Damaged`], which `status` and
//! `merge` report and a rerun moves aside (`.ID.damaged-<time stamp>`) and
//! computes again. Concurrent workers claim each work item with a lock
//! file in `workspace/` ([`Store::claim_path`]), so each item is computed
//! once.

use super::plan::{statepoint, Plan, Point};
use crate::io::{checksum_bytes, checksum_file, io_err as io};
use irtp::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The outcome of one point, as `result.json` holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// `ok` or `failed`.
    pub status: String,
    /// The error of a failed point (one line).
    pub error: Option<String>,
    /// The numerical method.
    pub method: Option<String>,
    /// The point's seed.
    pub seed: Option<u64>,
    /// Wall-clock seconds.
    pub wall_time_s: f64,
    /// The command's JSON summary (what `--json` prints).
    pub summary: serde_json::Value,
    /// `sha256:<hex>` of every file of the point's directory (by name) when
    /// it finished, this record aside.
    #[serde(default)]
    pub files: BTreeMap<String, String>,
    /// `sha256:<hex>` of this record (compact JSON) without this field.
    #[serde(default)]
    pub checksum: Option<String>,
}

/// What a point's directory holds.
#[derive(Clone, Debug)]
pub enum State {
    /// No result yet.
    Missing,
    /// A result whose files are as the point left them.
    Done(PointResult),
    /// A result that does not verify: why.
    Damaged(String),
}

impl PointResult {
    fn digest(&self) -> String {
        let mut bare = self.clone();
        bare.checksum = None;
        checksum_bytes(&serde_json::to_vec(&bare).expect("a result is JSON"))
    }

    /// Record the checksums of the files of `dir` (regular, not hidden,
    /// `result.json` and signac's job document aside) and of this record.
    pub fn seal(&mut self, dir: &Path) -> Result<()> {
        self.files.clear();
        for entry in read_dir(dir)? {
            let name = entry.file_name().to_string_lossy().into_owned();
            let file = entry.file_type().map_err(|e| io(dir, e))?.is_file();
            // signac's job document is the user's to edit (job.doc).
            let own = name == "result.json" || name == super::signac::DOCUMENT;
            if file && !name.starts_with('.') && !own {
                self.files.insert(name, checksum_file(&entry.path())?);
            }
        }
        self.checksum = Some(self.digest());
        Ok(())
    }

    /// Why this record (read from `dir`) or a file it records does not
    /// verify, if one does not.
    fn damage(&self, dir: &Path) -> Option<String> {
        match &self.checksum {
            None => return Some("result.json has no checksum (an older irtp wrote it?)".into()),
            Some(c) if *c != self.digest() => {
                return Some("result.json was changed since the point finished".into())
            }
            Some(_) => {}
        }
        for (name, want) in &self.files {
            let p = dir.join(name);
            if name.contains('/') || name.starts_with('.') {
                return Some(format!(
                    "result.json records a file outside the point: {name}"
                ));
            }
            match fs::symlink_metadata(&p) {
                Err(_) => return Some(format!("{name} is missing")),
                Ok(m) if !m.is_file() => return Some(format!("{name} is not a plain file")),
                Ok(_) => {}
            }
            if checksum_file(&p).ok().as_ref() != Some(want) {
                return Some(format!("{name} was changed since the point finished"));
            }
        }
        None
    }
}

/// Write `bytes` to `path` atomically (temporary file, then rename). The
/// temporary file's name is unique to the process and the call, so threads
/// writing the same file at once (the parts of one point each record its
/// statepoint) never rename each other's file away.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static CALLS: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let call = CALLS.fetch_add(1, Ordering::Relaxed);
    let tmp = path.with_file_name(format!(".{name}.tmp-{}-{call}", std::process::id()));
    fs::write(&tmp, bytes).map_err(|e| io(&tmp, e))?;
    fs::rename(&tmp, path).map_err(|e| io(path, e))
}

fn write_json(path: &Path, v: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(v).map_err(|e| io(path, e))? + "\n";
    write_atomic(path, text.as_bytes())
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T> {
    let text = fs::read_to_string(path).map_err(|e| io(path, e))?;
    serde_json::from_str(&text).map_err(|e| io(path, format!("not the expected JSON: {e}")))
}

/// A sweep directory.
pub struct Store {
    /// The directory.
    pub root: PathBuf,
}

impl Store {
    /// The sweep directory `root` for `plan`: created if new; if it exists,
    /// every point directory in it must belong to the plan with the same
    /// parameters, and no foreign file may sit in it.
    pub fn open(root: &Path, plan: &Plan) -> Result<Store> {
        crate::io::check_out_path(root)?;
        crate::io::check_not_in_sweep(root, true)?;
        let store = Store {
            root: root.to_path_buf(),
        };
        if root.exists() && !root.is_dir() {
            return Err(Error::invalid(
                "out",
                root.display(),
                "a directory path (it exists and is a file)",
            ));
        }
        // Checked before anything is created: a refused directory is left as it was.
        if root.exists() {
            store.check(plan)?;
        }
        fs::create_dir_all(store.workspace()).map_err(|e| io(root, e))?;
        write_atomic(&root.join("plan.toml"), plan.text.as_bytes())?;
        let config = root.join(super::signac::CONFIG);
        if !config.exists() {
            let dir = config.parent().expect("a file in .signac");
            fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
            write_atomic(&config, super::signac::CONFIG_TEXT.as_bytes())?;
        }
        Ok(store)
    }

    /// `root/workspace`.
    pub fn workspace(&self) -> PathBuf {
        self.root.join("workspace")
    }

    /// A point's directory.
    pub fn dir(&self, p: &Point) -> PathBuf {
        self.workspace().join(&p.id)
    }

    /// What point `p`'s directory holds, verified against its checksums.
    pub fn state(&self, p: &Point) -> State {
        let dir = self.dir(p);
        let path = dir.join("result.json");
        let text = match fs::read_to_string(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return State::Missing,
            Err(e) => return State::Damaged(format!("result.json cannot be read ({e})")),
            Ok(t) => t,
        };
        let r: PointResult = match serde_json::from_str(&text) {
            Err(e) => return State::Damaged(format!("result.json is not a point's result ({e})")),
            Ok(r) => r,
        };
        match r.damage(&dir) {
            Some(why) => State::Damaged(why),
            None => State::Done(r),
        }
    }

    /// The verified result of a point, if any.
    pub fn result(&self, p: &Point) -> Option<PointResult> {
        match self.state(p) {
            State::Done(r) => Some(r),
            _ => None,
        }
    }

    /// Whether point `p` still needs work: no result yet, a damaged one, or
    /// a failed one when failures are retried.
    pub fn unfinished(&self, p: &Point, retry: bool) -> bool {
        match self.state(p) {
            State::Done(r) => retry && r.status != "ok",
            _ => true,
        }
    }

    /// The lock file a worker holds while it computes point `p` (or its
    /// part `part`), or assembles or moves aside a split point.
    pub fn claim_path(&self, p: &Point, part: Option<u64>) -> PathBuf {
        match part {
            None => self.workspace().join(format!(".{}.claim", p.id)),
            Some(k) => self.workspace().join(format!(".{}.part-{k}.claim", p.id)),
        }
    }

    /// Move a damaged point's directory aside (to `.ID.damaged-<time stamp>`
    /// in the workspace, kept for inspection); its new name.
    pub fn move_aside(&self, p: &Point) -> Result<PathBuf> {
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let to = self.workspace().join(format!(".{}.damaged-{now}", p.id));
        fs::rename(self.dir(p), &to).map_err(|e| io(&self.dir(p), e))?;
        Ok(to)
    }

    /// Record a point's statepoint (before it runs).
    pub fn begin(&self, plan: &Plan, p: &Point) -> Result<()> {
        let dir = self.dir(p);
        fs::create_dir_all(&dir).map_err(|e| io(&dir, e))?;
        write_json(
            &dir.join("signac_statepoint.json"),
            &statepoint(&plan.command, &p.params, p.seed),
        )
    }

    /// Record a point's result with the checksums of its files (last: it
    /// marks the point finished).
    pub fn finish(&self, p: &Point, mut r: PointResult) -> Result<PointResult> {
        let doc = serde_json::json!({
            "status": r.status, "error": r.error, "method": r.method,
            "seed": r.seed, "wall_time_s": r.wall_time_s, "summary": r.summary,
        });
        write_json(&self.dir(p).join(super::signac::DOCUMENT), &doc)?;
        r.seal(&self.dir(p))?;
        write_json(&self.dir(p).join("result.json"), &r)?;
        Ok(r)
    }

    /// Files and directories the sweep does not know about (plain files
    /// are the user's in a sweep of this plan), and point directories
    /// whose statepoint is not the plan's.
    fn check(&self, plan: &Plan) -> Result<()> {
        let points: std::collections::HashMap<String, Point> =
            plan.points().map(|p| (p.id.clone(), p)).collect();
        self.rename_legacy(plan, &points)?;
        // A legacy name left after renaming has its new name taken: reported.
        self.foreign_entry(plan, &points, &Default::default())
    }

    /// The refusal of a sweep directory holding what `run` and `merge`
    /// refuse (an entry the sweep does not know about, a point directory
    /// not of the plan), if it holds one; `sweep status` reports the same.
    /// Nothing is changed.
    pub fn foreign(&self, plan: &Plan) -> Result<()> {
        let points: std::collections::HashMap<String, Point> =
            plan.points().map(|p| (p.id.clone(), p)).collect();
        let legacy = self.legacy_ids(plan, &points);
        self.foreign_entry(plan, &points, &legacy)
    }

    fn foreign_entry(
        &self,
        plan: &Plan,
        points: &std::collections::HashMap<String, Point>,
        legacy: &std::collections::HashMap<String, &Point>,
    ) -> Result<()> {
        const OWN: [&str; 6] = [
            "plan.toml",
            "sweep.json",
            "results.csv",
            "workspace",
            "slurm",
            "runs",
        ];
        // A sweep of this very plan may hold the user's own files beside
        // irtp's (a row workflow.toml and its action scripts).
        let this_plan = fs::read_to_string(self.root.join("plan.toml")).ok();
        let ours = this_plan.as_deref() == Some(plan.text.as_str());
        for entry in read_dir(&self.root)? {
            let name = entry.file_name().to_string_lossy().into_owned();
            let file = entry.file_type().is_ok_and(|t| t.is_file());
            if ours && file {
                continue;
            }
            if !OWN.contains(&name.as_str()) && !name.starts_with('.') {
                return Err(foreign(
                    &self.root.join(&name),
                    "is not a file of an irtp sweep",
                ));
            }
        }
        for entry in read_workspace(&self.workspace())? {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue; // a run's staging directory or temporary file
            }
            let path = entry.path();
            let Some(p) = points.get(&name) else {
                if legacy.get(&name).is_some_and(|p| !self.dir(p).exists()) {
                    continue; // an older irtp's name, which the next run renames
                }
                return Err(foreign(
                    &path,
                    "is not a point of this plan (another plan's sweep directory?)",
                ));
            };
            let sp_path = path.join("signac_statepoint.json");
            if sp_path.exists() {
                let sp: serde_json::Value = read_json(&sp_path)?;
                if sp != statepoint(&plan.command, &p.params, p.seed) {
                    return Err(foreign(
                        &sp_path,
                        "holds other parameters than the plan's point",
                    ));
                }
            }
        }
        Ok(())
    }
}

impl Store {
    /// Point directories named by the ids of an older irtp
    /// ([`super::plan::legacy_id`]) renamed to their signac ids (nothing
    /// is copied or removed; a directory whose new name is taken is left
    /// for [`Store::check`] to report).
    fn rename_legacy(
        &self,
        plan: &Plan,
        points: &std::collections::HashMap<String, Point>,
    ) -> Result<()> {
        let names: Vec<String> = read_workspace(&self.workspace())?
            .iter()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('.') && !points.contains_key(n))
            .collect();
        if names.is_empty() {
            return Ok(());
        }
        let legacy = self.legacy_ids(plan, points);
        for name in names {
            if let Some(p) = legacy.get(&name) {
                let (from, to) = (self.workspace().join(&name), self.dir(p));
                if !to.exists() {
                    fs::rename(&from, &to).map_err(|e| io(&from, e))?;
                }
            }
        }
        Ok(())
    }
}

impl Store {
    /// The points by the ids an older irtp gave them.
    fn legacy_ids<'a>(
        &self,
        plan: &Plan,
        points: &'a std::collections::HashMap<String, Point>,
    ) -> std::collections::HashMap<String, &'a Point> {
        points
            .values()
            .map(|p| {
                (
                    super::plan::legacy_id(&statepoint(&plan.command, &p.params, p.seed)),
                    p,
                )
            })
            .collect()
    }
}

/// The entries of a workspace (none when it does not exist yet).
fn read_workspace(dir: &Path) -> Result<Vec<fs::DirEntry>> {
    match dir.is_dir() {
        true => read_dir(dir),
        false => Ok(Vec::new()),
    }
}

fn read_dir(dir: &Path) -> Result<Vec<fs::DirEntry>> {
    let entries = fs::read_dir(dir).map_err(|e| io(dir, e))?;
    entries
        .collect::<std::io::Result<Vec<_>>>()
        .map_err(|e| io(dir, e))
}

fn foreign(path: &Path, why: &str) -> Error {
    Error::InvalidParameter {
        name: "out",
        value: path.display().to_string(),
        allowed: format!(
            "a sweep directory of this plan only: {} {why}; use another --out or remove it",
            path.display()
        ),
    }
}
