//! A sweep's directory: `plan.toml`, `sweep.json` (provenance),
//! `results.csv`, and one directory per point under `workspace/` named by
//! its id, holding `signac_statepoint.json` (its parameters: the layout
//! signac- and row-style workflow tools read), the command's outputs and,
//! written last, `result.json`. Every file is written to a temporary name
//! and renamed into place, so a killed run leaves either the whole file or
//! none of it; a point counts as finished only once its `result.json` is in
//! place.

use super::plan::{statepoint, Plan, Point};
use crate::io::io_err as io;
use irtp::error::{Error, Result};
use serde::{Deserialize, Serialize};
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
}

/// Write `bytes` to `path` atomically (temporary file, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
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
        let store = Store {
            root: root.to_path_buf(),
        };
        fs::create_dir_all(store.workspace()).map_err(|e| io(root, e))?;
        store.check(plan)?;
        write_atomic(&root.join("plan.toml"), plan.text.as_bytes())?;
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

    /// The finished result of a point, if any.
    pub fn result(&self, p: &Point) -> Option<PointResult> {
        read_json(&self.dir(p).join("result.json")).ok()
    }

    /// Whether point `p` still needs work: no result yet, or a failed one
    /// when failures are retried.
    pub fn unfinished(&self, p: &Point, retry: bool) -> bool {
        match self.result(p) {
            None => true,
            Some(r) => retry && r.status != "ok",
        }
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

    /// Record a point's result (last: it marks the point finished).
    pub fn finish(&self, p: &Point, r: &PointResult) -> Result<()> {
        write_json(&self.dir(p).join("result.json"), r)
    }

    /// Files and directories the sweep does not know about, and point
    /// directories whose statepoint is not the plan's.
    fn check(&self, plan: &Plan) -> Result<()> {
        const OWN: [&str; 6] = [
            "plan.toml",
            "sweep.json",
            "results.csv",
            "workspace",
            "slurm",
            "runs",
        ];
        for entry in read_dir(&self.root)? {
            let name = entry.file_name().to_string_lossy().into_owned();
            if !OWN.contains(&name.as_str()) && !name.starts_with('.') {
                return Err(foreign(
                    &self.root.join(&name),
                    "is not a file of an irtp sweep",
                ));
            }
        }
        let points: std::collections::HashMap<String, Point> =
            plan.points().map(|p| (p.id.clone(), p)).collect();
        for entry in read_dir(&self.workspace())? {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue; // a run's staging directory or temporary file
            }
            let path = entry.path();
            let Some(p) = points.get(&name) else {
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
