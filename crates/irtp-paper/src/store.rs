//! The output directory of `irtp reproduce`, figure by figure.
//!
//! Each finished figure is committed on its own: its files (`<fig>.csv`,
//! `.png`, `.svg`) and then its provenance `<fig>.json` (a [`Record`]:
//! version, git revision, method, seed, parameters, claims, files), which is
//! moved into place last and so marks the figure complete. After every
//! figure the index (`parameters.json`, `claims.json`, `claims.md`,
//! `REPORT.md`, `run.json`) is rewritten to list exactly the figures present.
//! A rerun with the same options skips a figure whose record matches this
//! build and its parameters, so an interrupted run loses only the figure in
//! progress. A directory holding files irtp did not write, another command's
//! outputs or figures of another seed or size is refused unless `--force`.

use super::{json_short, FigureOutput, Options, Which, IMAGES, NO_IMAGES};
use irtp::error::Result;
use irtp_app::io::{out_in_use, read_provenance, OutputDir, Previous, Provenance};
use irtp_app::lock::OutLock;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The method recorded for every figure.
pub const METHOD: &str = "exact event-driven sampler + Fokker-Planck + backward MFPT equations";

/// The files of the index, rewritten after every figure (`run.json` last).
const INDEX: [&str; 5] = [
    "parameters.json",
    "claims.json",
    "claims.md",
    "REPORT.md",
    "run.json",
];

/// A finished figure's provenance, `<fig>.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Record {
    /// Always "irtp".
    pub software: String,
    /// Crate version of the build that computed it.
    pub version: String,
    /// Git revision of that build, when built from a checkout.
    pub git_revision: Option<String>,
    /// The figure (`fig2`).
    pub figure: String,
    /// Numerical methods.
    pub method: String,
    /// `--quick`.
    pub quick: bool,
    /// Master seed.
    pub seed: u64,
    /// The figure's entry of `parameters.json` (its spec, ...).
    pub parameters: Value,
    /// Plot title.
    pub title: String,
    /// Claims checked with the figure's data.
    pub claims: Vec<Value>,
    /// Wall time in seconds.
    pub wall_time_s: f64,
    /// Seconds since the Unix epoch when it was committed.
    pub finished_unix: u64,
    /// Files of the figure, this record last.
    pub files: Vec<String>,
    /// `sha256:<hex>` of each file of the figure but this record.
    #[serde(default)]
    pub checksums: std::collections::BTreeMap<String, String>,
}

/// Every file name a figure may write, its record last.
fn figure_names(w: Which) -> Vec<String> {
    ["csv", "png", "svg", "json"]
        .iter()
        .map(|ext| format!("{}.{ext}", w.name()))
        .collect()
}

/// The parameter set the current code uses for figure `w`.
fn spec(w: Which, quick: bool) -> Value {
    use super::{fig1, fig2, fig5, fig6, fig7, fpt, media, noise, search, to_json};
    match w {
        Which::Fig1 => to_json(&fig1::Spec::new(quick)),
        Which::Fig2 => to_json(&fig2::Spec::new(fig2::Medium::Tan, quick)),
        Which::Fig3 => to_json(&fig2::Spec::new(fig2::Medium::Tanh, quick)),
        Which::Fig5 => to_json(&fig5::Spec::new(quick)),
        Which::Fig6 => to_json(&fig6::Spec::new(quick)),
        Which::Fig7 => to_json(&fig7::Spec::new(quick)),
        Which::Fpt => to_json(&fpt::Spec::new(quick)),
        Which::Media => to_json(&media::Spec::new(quick)),
        Which::Search => to_json(&search::Spec::new(quick)),
        Which::Noise => to_json(&noise::Spec::new(quick)),
    }
}

impl Record {
    /// Whether this build with `opts` would compute the same figure: same
    /// version, git revision, method, seed, size and parameters.
    fn current(&self, w: Which, opts: &Options) -> bool {
        self.version == irtp_app::VERSION
            && self.git_revision.as_deref() == irtp_app::GIT_REVISION
            && self.method == METHOD
            && self.quick == opts.quick
            && self.seed == opts.seed
            && self.parameters["spec"] == spec(w, opts.quick)
    }
}

/// The complete record of figure `w` in `dir` (its files all present).
fn read_record(dir: &Path, w: Which) -> Option<Record> {
    let v = read_provenance(&dir.join(format!("{}.json", w.name())))?;
    let r: Record = serde_json::from_value(v).ok()?;
    (r.figure == w.name() && r.files.iter().all(|f| dir.join(f).is_file())).then_some(r)
}

/// An `irtp reproduce` output directory.
pub struct Dir {
    path: PathBuf,
    /// Held for the whole run: no other writer while figures are committed.
    lock: Arc<OutLock>,
    opts: Options,
    /// Figures present, in paper order.
    records: Vec<(Which, Record)>,
    /// Whether a finished figure may be skipped (not under `--force`).
    resume: bool,
    /// Previous outputs to remove at the first commit (`--force`).
    replaced: Vec<String>,
    /// Warnings for the user.
    pub warnings: Vec<String>,
}

impl Dir {
    /// Open `path` for figures computed with `opts`, before any work: refused
    /// (unless `force`) when it holds files irtp did not write, another
    /// command's outputs, or figures of another seed or size.
    pub fn open(path: &Path, opts: &Options, force: bool) -> Result<Self> {
        let first = OutputDir::new(path)?; // a bad path, or another writer, fails here
        let lock = first.lock();
        drop(first);
        let run = read_provenance(&path.join("run.json"));
        let records: Vec<(Which, Record)> = Which::ALL
            .into_iter()
            .filter_map(|w| read_record(path, w).map(|r| (w, r)))
            .collect();
        // A figure record (complete or not) or the index makes the
        // directory one of `irtp reproduce`: its file names are irtp's.
        let ours = Which::ALL
            .into_iter()
            .any(|w| read_provenance(&path.join(format!("{}.json", w.name()))).is_some())
            || run.as_ref().is_some_and(is_reproduce);
        let also: Vec<String> = match ours {
            true => Which::ALL
                .into_iter()
                .flat_map(figure_names)
                .chain(INDEX.map(String::from))
                .collect(),
            false => Vec::new(),
        };
        let prev = Previous::read(path, &also)?;
        prev.refuse_changed(path)?;
        let mut dir = Dir {
            path: path.to_path_buf(),
            lock,
            opts: *opts,
            records: Vec::new(),
            resume: !force,
            replaced: Vec::new(),
            warnings: Vec::new(),
        };
        if force {
            dir.replaced = prev.ours.clone();
            if !prev.foreign.is_empty() {
                dir.warnings.push(prev.left_alone(path));
            }
            return Ok(dir);
        }
        dir.refuse_other(&prev, &records)?;
        dir.records = records;
        Ok(dir)
    }

    /// Refuse files irtp did not write, another command's run, figures of
    /// another seed or size.
    fn refuse_other(&self, prev: &Previous, records: &[(Which, Record)]) -> Result<()> {
        let in_use = |what: String| out_in_use(&self.path, what);
        if !prev.foreign.is_empty() {
            return Err(in_use(format!(
                "{}, which irtp did not write",
                prev.foreign_list()
            )));
        }
        if let Some(r) = &prev.run {
            if !is_reproduce(r) {
                return Err(in_use(format!(
                    "the outputs of `irtp {}`",
                    r["command"].as_str().unwrap_or("?")
                )));
            }
            if r["seed"] != self.opts.seed || r["parameters"]["quick"] != self.opts.quick {
                return Err(in_use(format!(
                    "figures of another run ({})",
                    describe(r["seed"].as_u64(), r["parameters"]["quick"].as_bool())
                )));
            }
        }
        if let Some((w, r)) = records
            .iter()
            .find(|(_, r)| r.seed != self.opts.seed || r.quick != self.opts.quick)
        {
            return Err(in_use(format!(
                "{} of another run ({})",
                w.name(),
                describe(Some(r.seed), Some(r.quick))
            )));
        }
        Ok(())
    }

    /// The record of figure `w` when it is finished and current (skip it).
    pub fn finished(&self, w: Which) -> Option<&Record> {
        self.records
            .iter()
            .find(|(x, r)| *x == w && self.resume && r.current(w, &self.opts))
            .map(|(_, r)| r)
    }

    /// The claims of these figures (those present).
    pub fn claims(&self, which: &[Which]) -> Vec<Value> {
        self.records
            .iter()
            .filter(|(w, _)| which.contains(w))
            .flat_map(|(_, r)| r.claims.iter().cloned())
            .collect()
    }

    /// Commit a computed figure (its files, then its record), then rewrite
    /// the index.
    pub fn commit_figure(&mut self, o: &FigureOutput, argv: &[String]) -> Result<()> {
        let name = o.which.name();
        let mut out = OutputDir::with_lock(&self.path, self.lock.clone())?
            .replacing(std::mem::take(&mut self.replaced));
        out.write_bytes(&format!("{name}.csv"), o.figure.data_csv()?)?;
        #[cfg(feature = "plot")]
        {
            let png = out.path(&format!("{name}.png"))?;
            o.figure.render_png(&png)?;
            let svg = out.path(&format!("{name}.svg"))?;
            o.figure.render_svg(&svg)?;
        }
        let mut files = out.files().to_vec();
        files.push(format!("{name}.json"));
        let record = Record {
            software: "irtp".into(),
            version: irtp_app::VERSION.into(),
            git_revision: irtp_app::GIT_REVISION.map(String::from),
            figure: name.into(),
            method: METHOD.into(),
            quick: self.opts.quick,
            seed: self.opts.seed,
            parameters: super::to_json(&o.parameters),
            title: o.figure.title.clone(),
            claims: o.claims.iter().map(super::to_json).collect(),
            wall_time_s: o.wall_time_s,
            finished_unix: unix_now(),
            checksums: out.checksums()?,
            files,
        };
        out.write_json(&format!("{name}.json"), &record)?;
        // The old record goes first: a figure is never marked by a record
        // that does not describe its files.
        let old = self.path.join(format!("{name}.json"));
        if old.exists() {
            std::fs::remove_file(&old).map_err(|e| irtp_app::io::io_err(&old, e))?;
        }
        self.records.retain(|(w, _)| *w != o.which);
        out.commit()?;
        self.records.push((o.which, record));
        self.records.sort_by_key(|(w, _)| *w as u8);
        self.write_index(argv).map(drop)
    }

    /// Write the index of the figures present; returns `run.json`'s content
    /// and every file of the directory written by irtp. It does not stop on
    /// a stop request: it follows a committed figure, which it must list.
    pub fn write_index(&self, argv: &[String]) -> Result<(Value, Vec<PathBuf>)> {
        let mut out = OutputDir::with_lock(&self.path, self.lock.clone())?;
        let mut params = serde_json::Map::new();
        let mut timings = serde_json::Map::new();
        let mut claims = Vec::new();
        let mut files = Vec::new();
        for (w, r) in &self.records {
            params.insert(w.name().into(), r.parameters.clone());
            timings.insert(w.name().into(), r.wall_time_s.into());
            claims.extend(r.claims.iter().cloned());
            files.extend(r.files.iter().cloned());
        }
        let wall: f64 = self.records.iter().map(|(_, r)| r.wall_time_s).sum();
        let params = Value::Object(params);
        out.write_json("parameters.json", &params)?;
        out.write_json("claims.json", &claims)?;
        out.write_bytes("claims.md", claims_markdown(&claims))?;
        out.write_bytes("REPORT.md", self.report(&claims, wall))?;
        let names: Vec<&str> = self.records.iter().map(|(w, _)| w.name()).collect();
        let mut prov = Provenance::new(
            format!("reproduce {}", names.join(" ")),
            METHOD,
            Some(self.opts.seed),
            serde_json::json!({"quick": self.opts.quick, "figures": params, "figure_wall_time_s": timings}),
            wall,
        )
        .with_argv(argv.to_vec());
        files.extend(out.files().iter().cloned());
        files.push("run.json".into());
        // The index vouches for every figure's files too: a rerun removes a
        // figure's old record before it commits the new one.
        for (_, r) in &self.records {
            prov.checksums.extend(r.checksums.clone());
        }
        prov.checksums.extend(out.checksums_unstoppable()?);
        prov.files = files.clone();
        let value = super::to_json(&prov);
        out.write_json("run.json", &value)?;
        out.commit()?;
        Ok((value, files.iter().map(|f| self.path.join(f)).collect()))
    }

    /// `REPORT.md`: figures, parameter sets, claims, timings.
    fn report(&self, claims: &[Value], wall_time_s: f64) -> String {
        let names: Vec<&str> = self.records.iter().map(|(w, _)| w.name()).collect();
        let mut s = format!(
            "# irtp reproduce: {} ({} run, seed {})\n\nTotal wall time {wall_time_s:.1} s.\n\n",
            names.join(", "),
            if self.opts.quick { "quick" } else { "full" },
            self.opts.seed,
        );
        if !IMAGES {
            s.push_str(&format!("{NO_IMAGES}\n\n"));
        }
        for (w, r) in &self.records {
            let name = w.name();
            let image = match IMAGES {
                true => format!("![{name}]({name}.png)\n\n"),
                false => String::new(),
            };
            s.push_str(&format!(
                "## {}\n\n{image}Wall time {:.1} s. Data: `{name}.csv`.\n\n",
                r.title, r.wall_time_s
            ));
            if let Some(spec) = r.parameters["spec"].as_object() {
                s.push_str("| parameter | value |\n|---|---|\n");
                for (k, v) in spec {
                    s.push_str(&format!(
                        "| {k} | {} |\n",
                        json_short(v).replace('|', "\\|")
                    ));
                }
                s.push('\n');
            }
        }
        s.push_str("## Claims\n\n");
        s.push_str(&claims_markdown(claims));
        s
    }
}

/// Whether a `run.json` is one of `irtp reproduce`.
fn is_reproduce(run: &Value) -> bool {
    run["command"]
        .as_str()
        .is_some_and(|c| c.split(' ').next() == Some("reproduce"))
}

/// `--seed 7, --quick` of another run.
fn describe(seed: Option<u64>, quick: Option<bool>) -> String {
    let seed = seed.map_or("?".into(), |s| s.to_string());
    match quick {
        Some(true) => format!("--seed {seed}, --quick"),
        _ => format!("--seed {seed}, full size"),
    }
}

fn unix_now() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0)
}

/// Claims (as serialised [`super::Claim`]s) as a markdown table (paper | ours | verdict).
pub fn claims_markdown(claims: &[Value]) -> String {
    let mut s = String::from(
        "| figure | id | claim (paper) | our number | verdict |\n|---|---|---|---|---|\n",
    );
    let cell = |c: &Value, k: &str| c[k].as_str().unwrap_or("").replace('|', "\\|");
    for c in claims {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            cell(c, "figure"),
            cell(c, "id"),
            cell(c, "paper"),
            cell(c, "ours"),
            cell(c, "verdict")
        ));
    }
    s
}
