//! `results.csv`: one row per point in plan order, built from the points'
//! `result.json` files only, so the table of a merged sweep is the table of
//! a single run whatever the split (up to the `wall_time_s` column, which
//! times the run).

use super::plan::{text, Plan, Point};
use super::store::{write_atomic, State, Store};
use super::Damaged;
use crate::io::io_err as io;
use irtp::error::{Error, Result};
use rayon::prelude::*;
use std::fs;
use std::path::{Path, PathBuf};

/// Points finished, failed among them, missing and damaged.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Points with a verified result (ok or failed).
    pub done: usize,
    /// Points whose computation failed.
    pub failed: usize,
    /// Points without a result yet.
    pub missing: usize,
    /// Points whose files do not verify.
    pub damaged: usize,
}

impl Counts {
    /// Whether every point is finished, verified and successful.
    pub fn complete(&self) -> bool {
        self.missing == 0 && self.failed == 0 && self.damaged == 0
    }
}

/// The verified state of every point (in parallel: it reads every file).
pub fn states(store: &Store, points: &[Point]) -> Vec<State> {
    points.par_iter().map(|p| store.state(p)).collect()
}

/// Count the `points` by their `states`; also how many of the points
/// `selected` picks (a shard's) failed.
pub fn counts(
    points: &[Point],
    states: &[State],
    selected: impl Fn(&Point) -> bool,
) -> (Counts, usize) {
    let (mut c, mut failed_selected) = (Counts::default(), 0);
    for (p, s) in points.iter().zip(states) {
        match s {
            State::Done(r) => {
                let failed = r.status != "ok";
                c.done += 1;
                c.failed += usize::from(failed);
                failed_selected += usize::from(failed && selected(p));
            }
            State::Missing => c.missing += 1,
            State::Damaged(_) => c.damaged += 1,
        }
    }
    (c, failed_selected)
}

/// The damaged points among `states`.
pub fn damaged(points: &[Point], states: &[State]) -> Vec<Damaged> {
    points
        .iter()
        .zip(states)
        .filter_map(|(p, s)| match s {
            State::Damaged(why) => Some(Damaged {
                index: p.index,
                id: p.id.clone(),
                why: why.clone(),
                moved_to: None,
            }),
            _ => None,
        })
        .collect()
}

/// The summary's scalar entries (numbers, booleans, strings), in order.
fn scalars(summary: &serde_json::Value) -> Vec<(String, String)> {
    let Some(obj) = summary.as_object() else {
        return Vec::new();
    };
    obj.iter()
        .filter_map(|(k, v)| {
            let s = match v {
                serde_json::Value::Number(n) => match n.as_f64() {
                    Some(x) if n.is_f64() => crate::io::format_float(x),
                    _ => n.to_string(),
                },
                serde_json::Value::Bool(b) => b.to_string(),
                serde_json::Value::String(s) => s.clone(),
                _ => return None,
            };
            Some((k.clone(), s))
        })
        .collect()
}

/// Write `results.csv` (atomically): point, id, the parameters, seed,
/// method, status, error, wall_time_s, then every scalar of the summaries
/// (the union, in order of first appearance). Missing points get status
/// `missing`, damaged ones `damaged` with what does not verify as error.
pub fn write_table(
    plan: &Plan,
    store: &Store,
    points: &[Point],
    states: &[State],
) -> Result<(PathBuf, Counts)> {
    let results = states.iter().filter_map(|s| match s {
        State::Done(r) => Some(r),
        _ => None,
    });
    let mut extra: Vec<String> = Vec::new();
    for r in results {
        for (k, _) in scalars(&r.summary) {
            if !extra.contains(&k) {
                extra.push(k);
            }
        }
    }
    let mut header: Vec<String> = vec!["point".into(), "id".into()];
    header.extend(plan.names());
    header.extend(["seed", "method", "status", "error", "wall_time_s"].map(String::from));
    header.extend(extra.iter().map(|k| format!("result.{k}")));
    let mut w = csv::Writer::from_writer(Vec::new());
    let path = store.root.join("results.csv");
    let csv_err = |e: csv::Error| io(&path, e);
    w.write_record(&header).map_err(csv_err)?;
    for (p, state) in points.iter().zip(states) {
        let mut row = vec![p.index.to_string(), p.id.clone()];
        row.extend(p.params.iter().map(|(_, v)| text(v)));
        row.push(p.seed.map(|s| s.to_string()).unwrap_or_default());
        match state {
            State::Done(r) => {
                let s: std::collections::HashMap<String, String> =
                    scalars(&r.summary).into_iter().collect();
                row.extend([
                    r.method.clone().unwrap_or_default(),
                    r.status.clone(),
                    r.error.clone().unwrap_or_default(),
                ]);
                row.push(crate::io::format_float(r.wall_time_s));
                row.extend(extra.iter().map(|k| s.get(k).cloned().unwrap_or_default()));
            }
            other => {
                let (status, why) = match other {
                    State::Damaged(why) => ("damaged", why.as_str()),
                    _ => ("missing", ""),
                };
                row.extend([String::new(), status.into(), why.into(), String::new()]);
                row.extend(extra.iter().map(|_| String::new()));
            }
        }
        w.write_record(&row).map_err(csv_err)?;
    }
    let bytes = w.into_inner().map_err(|e| io(&path, e))?;
    write_atomic(&path, &bytes)?;
    Ok((path, counts(points, states, |_| false).0))
}

/// Bring point `p` from `src` into `dst`: copied when only `src` has its
/// verified result (a damaged copy in `dst` moved aside first); when both
/// do, the results must agree (up to timing). Returns the damage seen.
pub fn take_point(src: &Store, dst: &Store, p: &Point) -> Result<Option<Damaged>> {
    let report = |why: String, moved_to| Damaged {
        index: p.index,
        id: p.id.clone(),
        why,
        moved_to,
    };
    let theirs = match src.state(p) {
        State::Missing => return take_parts(src, dst, p).map(|_| None),
        State::Damaged(why) => {
            let why = format!("{why} (in {}; not taken)", src.root.display());
            return Ok(Some(report(why, None)));
        }
        State::Done(r) => r,
    };
    let ours = match dst.state(p) {
        State::Missing => return copy_dir(&src.dir(p), &dst.dir(p)).map(|_| None),
        State::Damaged(why) => {
            let to = dst.move_aside(p)?;
            copy_dir(&src.dir(p), &dst.dir(p))?;
            let why = format!("{why} (replaced by the copy in {})", src.root.display());
            return Ok(Some(report(why, Some(to))));
        }
        State::Done(ours) => ours,
    };
    let same = ours.status == theirs.status
        && ours.summary == theirs.summary
        && ours.error == theirs.error;
    if !same {
        return Err(Error::invalid(
            "sweep_dir",
            src.root.display(),
            format!(
                "the same results as {} for point {} ({})",
                dst.root.display(),
                p.index,
                p.id
            ),
        ));
    }
    Ok(None)
}

/// Copy the stored parts of an unfinished split point that `dst` lacks.
fn take_parts(src: &Store, dst: &Store, p: &Point) -> Result<()> {
    let Ok(entries) = fs::read_dir(src.dir(p)) else {
        return Ok(());
    };
    for entry in entries {
        let entry = entry.map_err(|e| io(&src.dir(p), e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let wanted = (name.starts_with("part-") && name.ends_with(".json"))
            || name == "signac_statepoint.json";
        let to = dst.dir(p).join(&name);
        if wanted && !to.exists() {
            fs::create_dir_all(dst.dir(p)).map_err(|e| io(&dst.dir(p), e))?;
            let bytes = fs::read(entry.path()).map_err(|e| io(&entry.path(), e))?;
            write_atomic(&to, &bytes)?;
        }
    }
    Ok(())
}

/// Copy a point directory: files first, `result.json` last (so the copy is
/// finished only when complete).
fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    fs::create_dir_all(to).map_err(|e| io(to, e))?;
    let mut names: Vec<String> = Vec::new();
    for entry in fs::read_dir(from).map_err(|e| io(from, e))? {
        let entry = entry.map_err(|e| io(from, e))?;
        if entry.file_type().map_err(|e| io(from, e))?.is_file() {
            names.push(entry.file_name().to_string_lossy().into_owned());
        }
    }
    names.sort_by_key(|n| n == "result.json");
    for n in names {
        let bytes = fs::read(from.join(&n)).map_err(|e| io(&from.join(&n), e))?;
        write_atomic(&to.join(&n), &bytes)?;
    }
    Ok(())
}
