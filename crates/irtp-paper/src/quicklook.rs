//! `irtp plot DIR [--out FILE.png|.svg] [--var COLUMN]`: the natural
//! figure of an output directory, so a result can be seen without writing
//! plotting code.
//!
//! The command of the directory (its `run.json`) picks the figure:
//! densities with their standard errors (`simulate`'s P_s(v), `analytic`
//! and `fp stationary`'s P_s(v) with its part per noise state, named as
//! the noise model names its states), moments in time on log axes
//! (`simulate`'s ⟨v²⟩(t), ⟨x²⟩(t) with their errors, thinned to even steps
//! in log t; `fp msd`'s ⟨x²⟩(t) and its exponent α(t)) beside their power
//! laws, the snapshots of `fp transient`, survival curves S(t) (`mfpt`
//! with a particle method, `mfpt distribution`), τ(v₀) of `mfpt` with the
//! backward equations, and τ against the scanned axis with its optimum
//! marked (`mfpt scan`, `mfpt optimize`). The title names the run's
//! parameters in symbols ([`symbols`]); vertical ranges are robust
//! ([`crate::plot::fit_y`]). A sweep directory (one with `plan.toml`)
//! gives one scalar column of `results.csv` (`--var`, default the first
//! `result.*` column) over the plan's crossed axes (module `sweep`): a
//! line for one axis, a heat map for two, small multiples for more.
//!
//! The image goes to `DIR/plot.png` unless `--out` names another file. No
//! checksum of irtp covers that name: `run.json` lists the files a run
//! wrote and a sweep point's `result.json` the files it had when it
//! finished, so a plot beside them damages neither, and a later run into
//! `DIR` leaves `plot.png` alone ([`irtp_app::io::PLOT_FILE`]; an image
//! of another name there is a file irtp did not write, in the way of a
//! run without `--force`). It is written to a temporary name and renamed
//! into place, so a failed
//! drawing leaves nothing. Bad input (not an irtp directory, an unknown
//! `--var`, an `--out` that is not a writable `.png` or `.svg` path) is an
//! [`Error::InvalidParameter`]: one line, exit code 2, nothing written.
//! Drawing needs the cargo feature `plot`; without it the command checks
//! its input and then refuses.

use crate::plot::{Axis, Color, Dash, Figure, Note, Panel, Series, GUIDE};
use clap::Args;
use irtp::error::{Error, Result};
use std::fs;
use std::path::{Path, PathBuf};

mod sweep;
pub mod symbols;

/// Draw the natural figure of an irtp output directory (a run or a sweep) as PNG or SVG.
#[derive(Args, Debug, Clone)]
pub struct PlotArgs {
    /// A directory irtp wrote: a command's `--out`, or a sweep's directory.
    pub dir: PathBuf,
    /// The image to write, ending in .png or .svg [default: DIR/plot.png].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Sweep directories: the results.csv column to colour the heat map by (`result.d_eff` or `d_eff`) [default: the first result.* column].
    #[arg(long)]
    pub var: Option<String>,
}

/// Check the flags, draw the picture of `args.dir` and write it; the path
/// written.
pub fn run(args: &PlotArgs) -> Result<PathBuf> {
    if !args.dir.is_dir() {
        return Err(not_irtp(&args.dir));
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| args.dir.join(irtp_app::io::PLOT_FILE));
    let picture = picture(&args.dir, args.var.as_deref())?;
    let svg = image_kind(&out)?;
    check_place(&out)?;
    write(&picture, &out, svg)?;
    Ok(out)
}

/// The mark every image `irtp plot` draws carries (a PNG `tEXt` chunk, an
/// SVG comment): an existing `--out` file is replaced only when it has it.
const MARK: &str = "irtp plot";

/// Refuse an `--out` that would touch what irtp or the user keeps: a file
/// there that is not an image `irtp plot` drew (a symbolic link
/// included), or a place inside a sweep directory other than its top (where
/// the sweep keeps the user's plain files) and its point directories
/// (whose checksums name only their own files).
fn check_place(out: &Path) -> Result<()> {
    let refuse = |why: &str| Error::invalid("out", out.display(), why);
    if let Ok(m) = fs::symlink_metadata(out) {
        let marked = |b: &[u8]| b.windows(MARK.len()).any(|w| w == MARK.as_bytes());
        if m.file_type().is_symlink() || !fs::read(out).is_ok_and(|b| marked(&b)) {
            return Err(refuse(
                "a new file, or an image irtp plot drew (this file is not one; nothing written)",
            ));
        }
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let parent = parent.canonicalize().map_err(|e| refuse(&e.to_string()))?;
    let point = parent.join("signac_statepoint.json").is_file();
    for up in parent.ancestors().skip(1) {
        let sweep = up.join("plan.toml").is_file() && up.join("workspace").is_dir();
        let in_point = point && parent.parent() == Some(&up.join("workspace"));
        if sweep && !in_point {
            return Err(refuse(&format!(
                "a file outside the parts of the sweep {} (its top directory or a point's are allowed)",
                up.display()
            )));
        }
    }
    Ok(())
}

/// Whether `out` names an SVG (else a PNG) file in an existing directory;
/// refused otherwise.
#[doc(hidden)]
pub fn image_kind(out: &Path) -> Result<bool> {
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let svg = match ext.as_deref() {
        Some("png") => false,
        Some("svg") => true,
        _ => {
            return Err(Error::invalid(
                "out",
                out.display(),
                "a file name ending in .png or .svg",
            ))
        }
    };
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(Error::invalid(
            "out",
            out.display(),
            "a file in an existing directory",
        ));
    }
    if out.is_dir() {
        return Err(Error::invalid(
            "out",
            out.display(),
            "a file name, not a directory",
        ));
    }
    Ok(svg)
}

/// The picture of `dir`: the figure of a sweep (module `sweep`), else the
/// figure of the command its `run.json` names.
pub fn picture(dir: &Path, var: Option<&str>) -> Result<Figure> {
    if dir.join("plan.toml").is_file() {
        return sweep::figure(dir, var);
    }
    let Some(run) = irtp_app::io::read_provenance(&dir.join("run.json")) else {
        return Err(not_irtp(dir));
    };
    if let Some(v) = var {
        return Err(Error::invalid(
            "var",
            v,
            "only with a sweep directory (one with plan.toml)",
        ));
    }
    let command = run["command"].as_str().unwrap_or_default();
    let mut fig = run_figure(dir, command)?;
    let over = run["parameters"]["over"].as_str().unwrap_or_default();
    let scanned = match command {
        "mfpt optimize" => vec!["rate"],
        "mfpt scan" => vec![over],
        _ => Vec::new(),
    };
    let params = symbols::title_parameters(&run["parameters"], &scanned);
    fig.title = match params.is_empty() {
        true => format!("irtp {command}"),
        false => format!("irtp {command}: {params}"),
    };
    Ok(fig)
}

/// The refusal of a directory irtp did not write.
fn not_irtp(dir: &Path) -> Error {
    Error::invalid(
        "dir",
        dir.display(),
        "a directory irtp wrote: a command's --out (with its run.json) or a sweep (with plan.toml)",
    )
}

/// The figure of one run of `command` in `dir`.
fn run_figure(dir: &Path, command: &str) -> Result<Figure> {
    let mut fig = Figure::new("plot", format!("irtp {command}"), 2);
    fig.panels = match command {
        "simulate" => simulate_panels(dir)?,
        "analytic" => vec![analytic_panel(dir)?],
        "fp stationary" => vec![fp_stationary_panel(dir)?],
        "fp transient" => fp_transient_panels(dir)?,
        "fp msd" => fp_msd_panels(dir)?,
        "mfpt" => vec![mfpt_panel(dir)?],
        "mfpt scan" => vec![scan_panel(dir)?],
        "mfpt optimize" => vec![optimize_panel(dir)?],
        "mfpt distribution" => distribution_panels(dir)?,
        "reproduce" => {
            return Err(Error::invalid(
                "dir",
                dir.display(),
                "a run or a sweep (irtp reproduce drew its figures already: figN.png there)",
            ))
        }
        _ => return Err(not_irtp(dir)),
    };
    fig.cols = fig.panels.len().min(2);
    Ok(fig)
}

/// A CSV table of numbers read whole (`nan`, `inf` included; a cell that
/// is not a number reads as nan).
struct Table {
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    /// Read `dir/name`; an unreadable or missing table is bad input (the
    /// directory is not what its run.json says).
    fn read(dir: &Path, name: &str) -> Result<Table> {
        let path = dir.join(name);
        let bad =
            |why: String| Error::invalid("dir", dir.display(), format!("{name} readable ({why})"));
        let mut r = csv::Reader::from_path(&path).map_err(|e| bad(e.to_string()))?;
        let names = r
            .headers()
            .map_err(|e| bad(e.to_string()))?
            .iter()
            .map(String::from)
            .collect();
        let mut rows = Vec::new();
        for rec in r.records() {
            let rec = rec.map_err(|e| bad(e.to_string()))?;
            rows.push(
                rec.iter()
                    .map(|c| c.trim().parse().unwrap_or(f64::NAN))
                    .collect(),
            );
        }
        Ok(Table { names, rows })
    }

    /// Whether the table has column `name`.
    fn has(&self, name: &str) -> bool {
        self.names.iter().any(|n| n == name)
    }

    /// Column `name` (all nan when absent, so a missing optional column
    /// draws nothing).
    fn col(&self, name: &str) -> Vec<f64> {
        match self.names.iter().position(|n| n == name) {
            Some(j) => self
                .rows
                .iter()
                .map(|r| r.get(j).copied().unwrap_or(f64::NAN))
                .collect(),
            None => vec![f64::NAN; self.rows.len()],
        }
    }
}

/// A line from two columns of `t`.
fn line(t: &Table, x: &str, y: &str, label: &str, color: Color, dash: Dash) -> Series {
    Series::line(Some(label.into()), color, dash, y, t.col(x), t.col(y))
}

/// Points with error bars from three columns of `t`.
fn points(t: &Table, x: &str, y: &str, err: &str, label: &str, color: Color) -> Series {
    let e = t
        .col(err)
        .into_iter()
        .map(|e| if e.is_finite() { e } else { 0.0 })
        .collect();
    Series::points(Some(label.into()), color, y, t.col(x), t.col(y), e)
}

/// A panel with its series.
fn panel(label: &str, title: &str, x: Axis, y: Axis, series: Vec<Series>) -> Panel {
    let mut p = Panel::new(label, title, x, y);
    p.series = series;
    p
}

/// `simulate`: the stationary density with its errors, the moments in
/// time on log axes (points thinned to even steps in log t, the t² and t
/// laws beside ⟨x²⟩), and P(x) with `--reset-position`.
fn simulate_panels(dir: &Path) -> Result<Vec<Panel>> {
    let d = Table::read(dir, "density.csv")?;
    let m = Table::read(dir, "moments.csv")?;
    let keep = log_thin(&m.col("t"), LOG_POINTS);
    let thin = |s: Series| thinned(s, &keep);
    let mut moments = panel(
        "(b)",
        "moments",
        Axis::log("t"),
        Axis::log("⟨v²⟩, ⟨x²⟩"),
        vec![
            thin(points(&m, "t", "v2", "v2_err", "⟨v²⟩", Color::Palette(0))),
            thin(points(&m, "t", "x2", "x2_err", "⟨x²⟩", Color::Palette(3))),
        ],
    );
    let _ = power_law_guides(&mut moments, &m.col("t"), &m.col("x2"));
    let mut panels = vec![
        panel(
            "(a)",
            "velocity density",
            Axis::linear("v"),
            Axis::linear("P_{s}(v)"),
            vec![
                points(&d, "v", "p", "p_err", "time average", Color::Palette(0)),
                line(
                    &d,
                    "v",
                    "p_final",
                    "at t_{max}",
                    Color::Palette(1),
                    Dash::Dashed,
                ),
            ]
            .into_iter()
            .chain(exact_r0(dir))
            .collect::<Vec<_>>()
            .with_atoms(dir),
        ),
        moments,
    ];
    if dir.join("position.csv").is_file() {
        let x = Table::read(dir, "position.csv")?;
        let s = points(&x, "x", "p", "p_err", "x(t_{max})", Color::Palette(2));
        panels.push(panel(
            "(c)",
            "position density",
            Axis::linear("x"),
            Axis::linear("P(x)"),
            vec![s],
        ));
    }
    Ok(panels)
}

/// About how many points a moment curve on a log time axis shows.
const LOG_POINTS: usize = 40;

/// Rows of positive times `t` (increasing) about evenly spaced in log t:
/// for each of `n` targets from the first positive time to the last, the
/// first row at or after it (each row once), so a linear time grid does
/// not crowd its points into the last decade.
fn log_thin(t: &[f64], n: usize) -> Vec<usize> {
    let pos: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] > 0.0 && t[i].is_finite())
        .collect();
    let (Some(&a), Some(&b)) = (pos.first(), pos.last()) else {
        return Vec::new();
    };
    if pos.len() <= n || t[b] <= t[a] {
        return pos;
    }
    let (la, lb) = (t[a].ln(), t[b].ln());
    let mut out: Vec<usize> = Vec::new();
    let mut k = 0;
    for j in 0..n {
        let target = (la + (lb - la) * j as f64 / (n - 1) as f64).exp() * (1.0 - 1e-12);
        while k < pos.len() - 1 && t[pos[k]] < target {
            k += 1;
        }
        if out.last() != Some(&pos[k]) {
            out.push(pos[k]);
        }
    }
    out
}

/// The series restricted to rows `keep`.
fn thinned(mut s: Series, keep: &[usize]) -> Series {
    let pick = |v: &[f64]| keep.iter().filter_map(|&i| v.get(i).copied()).collect();
    s.x = pick(&s.x);
    s.y = pick(&s.y);
    s.y_err = s.y_err.as_deref().map(pick);
    s
}

/// Guides beside ⟨x²⟩(t) on log axes: the early power law through the
/// first positive value over its first 1.5 decades (∝ t² from a
/// stationary velocity, ∝ t⁴ from rest: the integer 2 to 4 nearest the
/// data's slope over its first decade), and the diffusive law ∝ t through
/// the last value over the last 1.5 decades (grey dashes, labelled below
/// the line); the early exponent.
fn power_law_guides(p: &mut Panel, t: &[f64], x2: &[f64]) -> Option<i32> {
    let ok: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] > 0.0 && x2[i] > 0.0 && x2[i].is_finite())
        .collect();
    let (&a, &b) = (ok.first()?, ok.last()?);
    if t[b] < 10.0 * t[a] {
        return None;
    }
    let c = *ok.iter().find(|&&i| t[i] >= 10.0 * t[a]).unwrap_or(&b);
    let slope = (x2[c] / x2[a]).ln() / (t[c] / t[a]).ln();
    let early = (slope.round() as i32).clamp(2, 4);
    let sup = ["", "", "²", "³", "⁴"][early as usize];
    let span = (t[b] / t[a]).min(10f64.powf(1.5));
    for (t0, y0, from, to, k, text) in [
        (t[a], x2[a], t[a], t[a] * span, early, format!("∝ t{sup}")),
        (t[b], x2[b], t[b] / span, t[b], 1, "∝ t".to_string()),
    ] {
        let xs: Vec<f64> = (0..=10)
            .map(|i| from * (to / from).powf(i as f64 / 10.0))
            .collect();
        let ys: Vec<f64> = xs.iter().map(|x| y0 * (x / t0).powi(k)).collect();
        let mid = (from * to).sqrt();
        p.series
            .push(Series::line(None, Color::Gray, Dash::Dashed, GUIDE, xs, ys));
        p.notes.push(Note {
            text,
            x: mid,
            y: y0 * (mid / t0).powi(k) / 6.0,
        });
    }
    Some(early)
}

/// `analytic`: the exact r = 0 stationary density.
fn analytic_panel(dir: &Path) -> Result<Panel> {
    let d = Table::read(dir, "density.csv")?;
    let s = line(
        &d,
        "v",
        "p",
        "p(v), exact (r = 0)",
        Color::Black,
        Dash::Solid,
    );
    Ok(panel(
        "",
        "stationary density",
        Axis::linear("v"),
        Axis::linear("p(v)"),
        vec![s],
    ))
}

/// `fp stationary`: the density P_s(v) and its parts per noise state,
/// named as the noise model names its states (η = +Σ, −Σ of the
/// telegraph noise; the levels of `summary.json` otherwise, a level 0 of
/// run-and-tumble-with-pauses noise being the pause).
fn fp_stationary_panel(dir: &Path) -> Result<Panel> {
    let d = Table::read(dir, "density.csv")?;
    let mut series = vec![line(
        &d,
        "v",
        "p",
        "P_{s}(v), all states",
        Color::Black,
        Dash::Solid,
    )];
    let dashes = [Dash::Dashed, Dash::Dotted];
    if d.has("p_plus") {
        for (k, (col, name)) in [("p_plus", "η = +Σ"), ("p_minus", "η = −Σ")]
            .iter()
            .enumerate()
        {
            series.push(line(&d, "v", col, name, Color::Palette(k), dashes[k]));
        }
    } else {
        let (levels, rpt) = state_levels(dir);
        let mut k = 0;
        while d.has(&format!("p_{k}")) {
            let name = state_name(levels.get(k).copied(), rpt, k);
            let col = format!("p_{k}");
            series.push(line(&d, "v", &col, &name, Color::Palette(k), dashes[k % 2]));
            k += 1;
        }
    }
    series.extend(exact_r0(dir));
    let series = series.with_atoms(dir);
    Ok(panel(
        "",
        "stationary velocity density",
        Axis::linear("v"),
        Axis::linear("P_{s}(v)"),
        series,
    ))
}

/// The exact density without resetting (docs/equations.md (34)-(35),
/// `R0Density`) of the run's telegraph noise and drag, as a grey
/// guide beside a density at r > 0: what resetting changed. `None` for
/// another noise, a thermal noise, a drag without it, or a run at r = 0
/// (whose density it is).
fn exact_r0(dir: &Path) -> Option<Series> {
    let run = irtp_app::io::read_provenance(&dir.join("run.json"))?;
    let m = symbols::model(&run["parameters"])?;
    let rate = m["rate"].as_f64().unwrap_or(0.0);
    let thermal = m["temperature"].as_f64().unwrap_or(0.0) != 0.0;
    if !m["noise"].is_null() || thermal || rate == 0.0 {
        return None;
    }
    let drag: irtp::model::drag::DragLaw = m["drag"].as_str()?.parse().ok()?;
    let (sigma, lambda) = (m["sigma"].as_f64()?, m["lambda"].as_f64()?);
    let d = irtp::analytic::r0::R0Density::new(drag, sigma, lambda).ok()?;
    let (lo, hi) = d.bounds();
    let n = 400;
    let v: Vec<f64> = (1..n)
        .map(|i| lo + (hi - lo) * i as f64 / n as f64)
        .collect();
    let p = v.iter().map(|&v| d.pdf(v)).collect();
    let label = Some("exact at r = 0".to_string());
    Some(Series::line(label, Color::Gray, Dash::Dotted, GUIDE, v, p))
}

/// A density panel's series with the point masses of the stationary law
/// drawn as atoms ([`atom_stems`]).
trait WithAtoms {
    fn with_atoms(self, dir: &Path) -> Vec<Series>;
}

impl WithAtoms for Vec<Series> {
    fn with_atoms(mut self, dir: &Path) -> Vec<Series> {
        let probe = Panel::new("", "", Axis::linear("v"), Axis::linear("p"));
        let probe = Panel {
            series: self.clone(),
            ..probe
        };
        let top = crate::plot::robust_range(&probe).map_or(1.0, |r| r.1);
        self.extend(atom_stems(dir, top));
        self
    }
}

/// The point masses of the stationary law (`results.atoms` of
/// `summary.json`: `[{"v", "mass", "err"}]`; the density files hold the
/// law without them) drawn as atoms: a stem at v up to `top` (the robust
/// top of the continuous density, so it never sets the range) and a
/// marker on it, its mass and error in the legend. None without atoms.
fn atom_stems(dir: &Path, top: f64) -> Vec<Series> {
    let v = fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok())
        .unwrap_or_default();
    let Some(atoms) = v["results"]["atoms"].as_array() else {
        return Vec::new();
    };
    // `fp transient`: the atoms at t_max (its last snapshot).
    let when = match (&v["results"]["atoms_t"], v["results"]["t_max"].as_f64()) {
        (serde_json::Value::Array(_), Some(t)) => {
            format!(", t = {}", irtp_app::io::format_float(t))
        }
        _ => String::new(),
    };
    let mut out = Vec::new();
    for (k, a) in atoms.iter().enumerate() {
        let (Some(at), Some(mass)) = (a["v"].as_f64(), a["mass"].as_f64()) else {
            continue;
        };
        let mass_text = match a["err"].as_f64() {
            Some(e) => irtp_app::format::fmt_pm(mass, e),
            None => irtp_app::format::fmt_sig(mass),
        };
        let at_text = symbols::number(at).replace('-', "−");
        let label = format!("atom at v = {at_text}{when}: mass {mass_text}");
        let color = Color::Palette(4 + k);
        out.push(Series::line(
            None,
            color,
            Dash::Solid,
            "atom",
            vec![at, at],
            vec![0.0, top],
        ));
        out.push(Series::points(
            Some(label),
            color,
            "atom",
            vec![at],
            vec![top],
            vec![0.0],
        ));
    }
    out
}

/// The noise levels of `summary.json` (`results.levels`; empty when
/// absent) and whether the noise is run-and-tumble with pauses (`rpt:`).
fn state_levels(dir: &Path) -> (Vec<f64>, bool) {
    let v = fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok())
        .unwrap_or_default();
    let levels = v["results"]["levels"]
        .as_array()
        .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
        .unwrap_or_default();
    let spec = v["params"]["model"]["noise"].as_str().unwrap_or_default();
    (levels, spec.starts_with("rpt:"))
}

/// The legend name of noise state `k` at `level`: "η = level", and for
/// run-and-tumble-with-pauses noise "pause (η = 0)", "run (η = ±Σ)".
fn state_name(level: Option<f64>, rpt: bool, k: usize) -> String {
    let Some(l) = level else {
        return format!("state {k}");
    };
    let eta = format!("η = {}", symbols::number(l)).replace("= -", "= −");
    match (rpt, l == 0.0) {
        (true, true) => format!("pause ({eta})"),
        (true, false) => format!("run ({eta})"),
        _ => eta,
    }
}

/// The most snapshots `fp transient`'s figure shows (evenly picked).
const MAX_SNAPSHOTS: usize = 8;

/// `fp transient`: the density snapshots and the moments in time.
fn fp_transient_panels(dir: &Path) -> Result<Vec<Panel>> {
    let s = Table::read(dir, "snapshots.csv")?;
    let (t, v, p) = (s.col("t"), s.col("v"), s.col("p"));
    let mut blocks: Vec<(f64, Vec<f64>, Vec<f64>)> = Vec::new();
    for i in 0..t.len() {
        if blocks.last().map_or(true, |b| b.0 != t[i]) {
            blocks.push((t[i], Vec::new(), Vec::new()));
        }
        let b = blocks.last_mut().expect("a block");
        b.1.push(v[i]);
        b.2.push(p[i]);
    }
    let n = blocks.len();
    let picked: Vec<usize> = match n <= MAX_SNAPSHOTS {
        true => (0..n).collect(),
        false => (0..MAX_SNAPSHOTS)
            .map(|k| k * (n - 1) / (MAX_SNAPSHOTS - 1))
            .collect(),
    };
    let series = picked
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            let (t, v, p) = blocks[i].clone();
            let label = format!("t = {}", irtp_app::io::format_float(t));
            Series::line(Some(label), Color::Palette(k), Dash::Solid, "p", v, p)
        })
        .collect::<Vec<_>>()
        .with_atoms(dir);
    let m = Table::read(dir, "moments.csv")?;
    let mut moments = vec![
        line(&m, "t", "v2", "⟨v²⟩", Color::Palette(0), Dash::Solid),
        line(&m, "t", "v_mean", "⟨v⟩", Color::Palette(1), Dash::Dashed),
    ];
    // With point masses: their total mass in time.
    if m.has("atom_mass") {
        let atoms = line(
            &m,
            "t",
            "atom_mass",
            "atom mass",
            Color::Palette(2),
            Dash::Dotted,
        );
        moments.push(atoms);
    }
    Ok(vec![
        panel(
            "(a)",
            "density snapshots",
            Axis::linear("v"),
            Axis::linear("p(v, t)"),
            series,
        ),
        panel(
            "(b)",
            "moments",
            Axis::linear("t"),
            Axis::linear("⟨v²⟩, ⟨v⟩"),
            moments,
        ),
    ])
}

/// `fp msd`: ⟨x²⟩(t) on log axes with the t² and t laws, and its
/// exponent α(t) with the levels 2 and 1.
fn fp_msd_panels(dir: &Path) -> Result<Vec<Panel>> {
    let m = Table::read(dir, "moments.csv")?;
    let x2 = if m.has("x2_err") {
        points(&m, "t", "x2", "x2_err", "⟨x²⟩", Color::Palette(0))
    } else {
        line(&m, "t", "x2", "⟨x²⟩", Color::Palette(0), Dash::Solid)
    };
    let alpha = line(
        &m,
        "t",
        "alpha",
        "α = d ln⟨x²⟩ / d ln t",
        Color::Palette(3),
        Dash::Solid,
    );
    let mut msd = panel(
        "(a)",
        "mean squared displacement",
        Axis::log("t"),
        Axis::log("⟨x²⟩"),
        vec![x2],
    );
    let t = m.col("t");
    let early = power_law_guides(&mut msd, &t, &m.col("x2"));
    let mut exponent = panel(
        "(b)",
        "exponent",
        Axis::log("t"),
        Axis::linear("α"),
        vec![alpha],
    );
    let ends: Vec<f64> = t.iter().copied().filter(|&v| v > 0.0).collect();
    if let (Some(&a), Some(&b)) = (ends.first(), ends.last()) {
        let mut levels = vec![(2.0, "ballistic, α = 2".to_string())];
        if let Some(k) = early.filter(|&k| k != 2) {
            levels.push((f64::from(k), format!("early, α = {k}")));
        }
        levels.push((1.0, "diffusive, α = 1".to_string()));
        for (level, text) in levels {
            exponent.series.push(Series::line(
                None,
                Color::Gray,
                Dash::Dashed,
                GUIDE,
                vec![a, b],
                vec![level, level],
            ));
            exponent.notes.push(Note {
                text,
                x: a * 1.3,
                y: level + 0.1,
            });
        }
    }
    Ok(vec![msd, exponent])
}

/// The survival curve S(t) of `survival.csv`, with its errors.
fn survival_panel(dir: &Path, label: &str) -> Result<Panel> {
    let s = Table::read(dir, "survival.csv")?;
    let p = points(
        &s,
        "t",
        "survival",
        "survival_err",
        "Kaplan-Meier",
        Color::Palette(0),
    );
    Ok(panel(
        label,
        "survival",
        Axis::log("t"),
        Axis::linear("S(t)"),
        vec![p],
    ))
}

/// `mfpt`: τ(v₀) of the backward equations, or the sampled survival curve.
fn mfpt_panel(dir: &Path) -> Result<Panel> {
    if !dir.join("profile.csv").is_file() {
        if !dir.join("survival.csv").is_file() {
            // A search by the backward equation: one number, no table.
            return Err(Error::invalid(
                "dir",
                dir.display(),
                "an output with a table to draw: this mfpt run holds only its numbers \
                 (mfpt.json: a search solved by the backward equation); `--method exact` \
                 gives its survival curve S(t)",
            ));
        }
        return survival_panel(dir, "");
    }
    let t = Table::read(dir, "profile.csv")?;
    let series = vec![
        line(&t, "v0", "tau", "τ", Color::Palette(0), Dash::Solid),
        line(
            &t,
            "v0",
            "tau_plus",
            "τ_{+}",
            Color::Palette(1),
            Dash::Dashed,
        ),
        line(
            &t,
            "v0",
            "tau_minus",
            "τ_{-}",
            Color::Palette(2),
            Dash::Dotted,
        ),
    ];
    Ok(panel(
        "",
        "mean first-passage time",
        Axis::linear("v_{0}"),
        Axis::linear("τ"),
        series,
    ))
}

/// A log axis where every finite value of `vals` is positive and they span
/// more than a decade and a half, else a linear one.
fn auto_axis(label: &str, vals: &[f64]) -> Axis {
    let finite: Vec<f64> = vals.iter().copied().filter(|v| v.is_finite()).collect();
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    match lo > 0.0 && hi / lo > 30.0 {
        true => Axis::log(label),
        false => Axis::linear(label),
    }
}

/// `mfpt scan`: τ against the scanned quantity (the first column), with
/// the sampled τ and its errors when a particle method ran too.
fn scan_panel(dir: &Path) -> Result<Panel> {
    let t = Table::read(dir, "mfpt_scan.csv")?;
    let axis = t.names.first().cloned().unwrap_or_default();
    let mut series = vec![
        line(
            &t,
            &axis,
            "tau",
            "τ (backward equations)",
            Color::Palette(0),
            Dash::Solid,
        ),
        line(
            &t,
            &axis,
            "tau_plus",
            "τ_{+}",
            Color::Palette(1),
            Dash::Dashed,
        ),
        line(
            &t,
            &axis,
            "tau_minus",
            "τ_{-}",
            Color::Palette(2),
            Dash::Dotted,
        ),
    ];
    if t.has("tau_sim") {
        series.push(points(
            &t,
            &axis,
            "tau_sim",
            "tau_sim_err",
            "τ (sampled)",
            Color::Palette(3),
        ));
    }
    let (xs, taus) = (t.col(&axis), t.col("tau"));
    let best = (0..taus.len())
        .filter(|&i| taus[i].is_finite())
        .min_by(|&a, &b| taus[a].total_cmp(&taus[b]));
    let symbol = symbols::param(&axis);
    if let Some(i) = best {
        let label = format!(
            "smallest τ = {} at {symbol} = {}",
            symbols::number(taus[i]),
            symbols::number(xs[i])
        );
        series.push(Series::points(
            Some(label),
            Color::Palette(3),
            "optimum",
            vec![xs[i]],
            vec![taus[i]],
            vec![0.0],
        ));
    }
    let x = auto_axis(&symbol, &xs);
    let y = auto_axis("τ", &taus);
    Ok(panel("", "mean first-passage time", x, y, series))
}

/// `mfpt optimize`: the searched grid τ(r) and the optimum found.
fn optimize_panel(dir: &Path) -> Result<Panel> {
    let t = Table::read(dir, "rate_grid.csv")?;
    let mut series = vec![line(
        &t,
        "rate",
        "tau",
        "τ(r), grid",
        Color::Palette(0),
        Dash::Solid,
    )];
    let opt = fs::read_to_string(dir.join("optimum.json"))
        .ok()
        .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok());
    if let Some(o) = opt {
        if let (Some(r), Some(tau)) = (o["r_opt"].as_f64(), o["tau_opt"].as_f64()) {
            let label = format!(
                "optimum: τ = {} at r = {}",
                symbols::number(tau),
                symbols::number(r)
            );
            let s = Series::points(
                Some(label),
                Color::Palette(3),
                "optimum",
                vec![r],
                vec![tau],
                vec![0.0],
            );
            series.push(s);
        }
    }
    let x = auto_axis("r", &t.col("rate"));
    Ok(panel(
        "",
        "mean first-passage time against the reset rate",
        x,
        Axis::linear("τ"),
        series,
    ))
}

/// `mfpt distribution`: S(t) and the density f(t) of the first-passage
/// time (backward equations, or the sampled histogram and survival).
fn distribution_panels(dir: &Path) -> Result<Vec<Panel>> {
    if !dir.join("distribution.csv").is_file() {
        let h = Table::read(dir, "histogram.csv")?;
        let mid = h
            .col("t_lo")
            .iter()
            .zip(h.col("t_hi"))
            .map(|(a, b)| (a * b).sqrt())
            .collect();
        let e = h
            .col("density_err")
            .into_iter()
            .map(|e| if e.is_finite() { e } else { 0.0 })
            .collect();
        let f = Series::points(
            Some("sampled".into()),
            Color::Palette(0),
            "density",
            mid,
            h.col("density"),
            e,
        );
        let density = panel(
            "(b)",
            "first-passage-time density",
            Axis::log("t"),
            Axis::log("f(t)"),
            vec![f],
        );
        return Ok(vec![survival_panel(dir, "(a)")?, density]);
    }
    let d = Table::read(dir, "distribution.csv")?;
    let three = |what: &str| {
        vec![
            line(&d, "t", what, "mixture", Color::Palette(0), Dash::Solid),
            line(
                &d,
                "t",
                &format!("{what}_plus"),
                "start +Σ",
                Color::Palette(1),
                Dash::Dashed,
            ),
            line(
                &d,
                "t",
                &format!("{what}_minus"),
                "start −Σ",
                Color::Palette(2),
                Dash::Dotted,
            ),
        ]
    };
    Ok(vec![
        panel(
            "(a)",
            "survival",
            Axis::log("t"),
            Axis::linear("S(t)"),
            three("survival"),
        ),
        panel(
            "(b)",
            "first-passage-time density",
            Axis::log("t"),
            Axis::log("f(t)"),
            three("density"),
        ),
    ])
}

/// Write `picture` to `out` (a temporary name beside it, then renamed): a
/// location that cannot be written is bad input and leaves nothing.
#[cfg(feature = "plot")]
fn write(picture: &Figure, out: &Path, svg: bool) -> Result<()> {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = if svg { "svg" } else { "png" };
    let tmp = out.with_file_name(format!(".{name}.tmp-{}.{ext}", std::process::id()));
    let refused = |why: String| {
        let _ = fs::remove_file(&tmp);
        Error::invalid(
            "out",
            out.display(),
            format!("a writable image path ({why})"),
        )
    };
    let drawn = match svg {
        false => picture.render_png(&tmp),
        true => picture.render_svg(&tmp),
    };
    drawn.map_err(|e| refused(e.to_string()))?;
    mark(&tmp, svg).map_err(|e| refused(e.to_string()))?;
    fs::rename(&tmp, out).map_err(|e| refused(e.to_string()))
}

/// Put [`MARK`] into the image at `path`: a `tEXt` chunk `Software` after
/// a PNG's header chunk, a comment after an SVG's opening tag.
#[cfg(feature = "plot")]
fn mark(path: &Path, svg: bool) -> std::io::Result<()> {
    let mut bytes = fs::read(path)?;
    if svg {
        let open = String::from_utf8_lossy(&bytes).find("<svg").unwrap_or(0);
        let end = bytes[open..].iter().position(|&b| b == b'>');
        let at = end.map_or(0, |e| open + e + 1);
        bytes.splice(at..at, format!("\n<!-- {MARK} -->").into_bytes());
        return fs::write(path, bytes);
    }
    // After the PNG signature (8 bytes) and IHDR (length, type, 13 bytes, CRC).
    let at = 8 + 25;
    if bytes.len() < at || &bytes[12..16] != b"IHDR" {
        return Err(std::io::Error::other("not a PNG image"));
    }
    let body: Vec<u8> = format!("tEXtSoftware\0{MARK}").into_bytes();
    let mut chunk = ((body.len() - 4) as u32).to_be_bytes().to_vec();
    chunk.extend(&body);
    chunk.extend(crc32(&body).to_be_bytes());
    bytes.splice(at..at, chunk);
    fs::write(path, bytes)
}

/// The CRC-32 of PNG chunks (ISO 3309, reflected polynomial 0xEDB88320).
#[doc(hidden)]
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 == 1 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// Without the `plot` feature there is nothing to draw with: refused after
/// the input was checked, nothing written.
#[cfg(not(feature = "plot"))]
fn write(_: &Figure, out: &Path, _: bool) -> Result<()> {
    Err(Error::invalid(
        "out",
        out.display(),
        "only in a build with the cargo feature `plot` (irtp-cli's default; this irtp was built without it)",
    ))
}

/// The header and rows of a sweep's `results.csv`; refused when it is
/// missing (the sweep has not finished) or unreadable.
fn read_results(dir: &Path) -> Result<(Vec<String>, Vec<csv::StringRecord>)> {
    let unfinished = || {
        Error::invalid(
            "dir",
            dir.display(),
            "a finished sweep (results.csv is written once every point is done: irtp sweep status DIR)",
        )
    };
    let mut r = csv::Reader::from_path(dir.join("results.csv")).map_err(|_| unfinished())?;
    let header = r
        .headers()
        .map_err(|_| unfinished())?
        .iter()
        .map(String::from)
        .collect();
    let records = r
        .records()
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| unfinished())?;
    Ok((header, records))
}

/// The position of plan point `p` on each crossed axis (the first axis
/// varies slowest); `None` past the plan's end.
#[doc(hidden)]
pub fn digits(p: usize, crossed: &[(Vec<String>, usize)]) -> Option<Vec<usize>> {
    let mut rest = p;
    let mut out = vec![0; crossed.len()];
    for (k, &(_, n)) in crossed.iter().enumerate().rev() {
        out[k] = rest % n.max(1);
        rest /= n.max(1);
    }
    (rest == 0).then_some(out)
}

/// Whether column `j` of `records` holds numbers: every cell empty (a
/// failed point) or a number, and one finite.
fn numeric(records: &[csv::StringRecord], j: usize) -> bool {
    let cells = || records.iter().filter_map(|r| r.get(j)).map(str::trim);
    cells().all(|c| c.is_empty() || c.parse::<f64>().is_ok())
        && cells().any(|c| c.parse::<f64>().is_ok_and(f64::is_finite))
}

/// The numeric `results.csv` column `var` names (`result.` may be left
/// out), or the first numeric `result.*` column; an unknown or
/// non-numeric one is refused listing the numeric `result.*` columns.
#[doc(hidden)]
pub fn choose_var(
    header: &[String],
    records: &[csv::StringRecord],
    var: Option<&str>,
) -> Result<String> {
    let usable = |j: usize| numeric(records, j);
    let results: Vec<&String> = (0..header.len())
        .filter(|&j| header[j].starts_with("result.") && usable(j))
        .map(|j| &header[j])
        .collect();
    let Some(v) = var else {
        return results.first().map(|s| s.to_string()).ok_or_else(|| {
            Error::invalid(
                "var",
                "(default)",
                "a numeric result.* column of results.csv; it has none",
            )
        });
    };
    let full = format!("result.{v}");
    let found = header.iter().position(|h| *h == v || *h == full);
    if let Some(j) = found.filter(|&j| usable(j)) {
        return Ok(header[j].clone());
    }
    let list: Vec<&str> = results.iter().take(8).map(|s| s.as_str()).collect();
    let more = if results.len() > 8 { ", ..." } else { "" };
    let what = match found {
        Some(_) => "a numeric column of results.csv (this one is not)",
        None => "a numeric column of results.csv",
    };
    Err(Error::invalid(
        "var",
        v,
        format!("{what}: {}{more}", list.join(", ")),
    ))
}
