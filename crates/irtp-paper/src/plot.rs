//! A small declarative plotting layer: the figure model, its CSV, and the
//! layout that `plotters` lacks.
//!
//! A [`Figure`] is a grid of [`Panel`]s; a panel has two [`Axis`] (linear or
//! logarithmic each), [`Series`] (lines with a dash pattern, or points with
//! vertical error bars) and free text [`Note`]s (guide-line labels such as
//! "t²"). Series with the same legend label and colour share one legend entry
//! showing both the marker and the line, so simulation points and solver
//! lines of one parameter set read as one item; a panel's [`Key`] entries
//! follow them and say what each kind of mark is (which points are
//! simulation, which lines which solver). The legend goes into a free
//! corner of the plotting area (one that hides no data), or outside the
//! plotting area when every corner would hide some.
//!
//! Titles, axis labels and legend text may write a subscript as `_{...}`
//! (`D_{eff}`, `τ_{r}`): the renderer lowers it and sets it smaller
//! ([`rich_segments`]). Tick labels of one axis share one format: the same
//! number of decimals, or all in scientific notation (`tick_labels`).
//!
//! The model and [`Figure::data_csv`] need no plotting library. Rendering
//! (`render_png`, `render_svg`, module `render`) uses `plotters` and exists
//! only with the cargo feature `plot` (on by default). What plotters lacks
//! stays here and is tested without it: data-avoiding legend placement
//! (`choose_place` on `occupancy`), clipping of lines to the axes
//! (`clip_polyline`), splitting lines at cusps so thick strokes get no
//! miter spikes (`split_sharp`), tick positions and tick labels.
// Without the `plot` feature the layout helpers have no caller but their tests.
#![cfg_attr(not(feature = "plot"), allow(dead_code))]

use irtp::error::{Error, Result};
use serde::Serialize;

pub mod heatmap;
#[cfg(feature = "plot")]
mod render;

/// Axis scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// Linear axis.
    Linear,
    /// Base-10 logarithmic axis (non-positive values are not drawn).
    Log,
}

/// One axis of a panel.
#[derive(Clone, Debug, Serialize)]
pub struct Axis {
    /// Axis label.
    pub label: String,
    /// Scale.
    pub scale: Scale,
    /// Fixed range in data units; `None` fits the data (with a margin; on
    /// the vertical axis a robust range, see [`robust_range`]).
    pub range: Option<(f64, f64)>,
    /// Ticks at given data positions with given labels (a heat map's cell
    /// centres); `None`: nice ticks chosen from the range.
    pub ticks: Option<Vec<(f64, String)>>,
}

impl Axis {
    /// Linear axis fitted to the data.
    pub fn linear(label: impl Into<String>) -> Self {
        Axis {
            label: label.into(),
            scale: Scale::Linear,
            range: None,
            ticks: None,
        }
    }
    /// Log axis fitted to the data.
    pub fn log(label: impl Into<String>) -> Self {
        Axis {
            label: label.into(),
            scale: Scale::Log,
            range: None,
            ticks: None,
        }
    }
    /// Fix the range.
    pub fn range(mut self, lo: f64, hi: f64) -> Self {
        self.range = Some((lo, hi));
        self
    }
    /// Ticks at data positions `at` labelled `labels`.
    pub fn ticks_at(mut self, ticks: Vec<(f64, String)>) -> Self {
        self.ticks = Some(ticks);
        self
    }
    /// Data value to the axis' linear layout units (log10 on a log axis);
    /// `None` where the value cannot be drawn.
    pub fn tr(&self, v: f64) -> Option<f64> {
        match self.scale {
            Scale::Linear => v.is_finite().then_some(v),
            Scale::Log => (v > 0.0 && v.is_finite()).then(|| v.log10()),
        }
    }
    /// Inverse of [`Axis::tr`].
    pub fn inv(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Linear => u,
            Scale::Log => 10f64.powf(u),
        }
    }
}

/// Line pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Dash {
    /// Solid line.
    Solid,
    /// Dashed line.
    Dashed,
    /// Dotted line.
    Dotted,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Style {
    /// A polyline.
    Line(Dash),
    /// Markers, with vertical error bars when the series has `y_err`.
    Points,
}

/// Series colour: a palette index (same index = same parameter set) or black/grey.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Color {
    /// Entry of the 10-colour palette (indices wrap).
    Palette(usize),
    /// Black (reserved for analytic r = 0 results).
    Black,
    /// Grey (guide lines).
    Gray,
}

/// Tableau-10 palette: distinguishable, readable on white.
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (23, 190, 207),
    (188, 189, 34),
    (127, 127, 127),
];

impl Color {
    /// Red, green, blue.
    fn rgb(self) -> (u8, u8, u8) {
        match self {
            Color::Palette(i) => PALETTE[i % PALETTE.len()],
            Color::Black => (0, 0, 0),
            Color::Gray => (110, 110, 110),
        }
    }
}

/// One data series.
#[derive(Clone, Debug, Serialize)]
pub struct Series {
    /// Legend label (`None`: not in the legend).
    pub label: Option<String>,
    /// Colour.
    pub color: Color,
    /// Line or points.
    pub style: Style,
    /// x values.
    pub x: Vec<f64>,
    /// y values.
    pub y: Vec<f64>,
    /// Standard errors of y (points only).
    pub y_err: Option<Vec<f64>>,
    /// Origin of the data, written to the CSV (e.g. "simulation", "fp", "analytic", "guide").
    pub source: String,
}

impl Series {
    /// A line.
    pub fn line(
        label: Option<String>,
        color: Color,
        dash: Dash,
        source: &str,
        x: Vec<f64>,
        y: Vec<f64>,
    ) -> Self {
        Series {
            label,
            color,
            style: Style::Line(dash),
            x,
            y,
            y_err: None,
            source: source.into(),
        }
    }
    /// Points with error bars.
    pub fn points(
        label: Option<String>,
        color: Color,
        source: &str,
        x: Vec<f64>,
        y: Vec<f64>,
        y_err: Vec<f64>,
    ) -> Self {
        Series {
            label,
            color,
            style: Style::Points,
            x,
            y,
            y_err: Some(y_err),
            source: source.into(),
        }
    }
}

/// Free text at a data position (left end of the text at x, centred on y).
#[derive(Clone, Debug, Serialize)]
pub struct Note {
    /// Text.
    pub text: String,
    /// x in data units.
    pub x: f64,
    /// y in data units.
    pub y: f64,
}

/// One subplot.
#[derive(Clone, Debug, Serialize)]
pub struct Panel {
    /// Panel label, e.g. "(a)".
    pub label: String,
    /// Short description after the label, e.g. "tan, Σ = 3, λ = 0.9".
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Data.
    pub series: Vec<Series>,
    /// Text notes (guide labels).
    pub notes: Vec<Note>,
    /// Optional heading of the legend (e.g. "r =").
    pub legend_title: Option<String>,
    /// Legend entries after the series' ones saying what each kind of mark
    /// is (e.g. grey points: "exact sampler, 4000 particles").
    pub key: Vec<Key>,
    /// A heat map filling the plotting area (cells on the axes' data
    /// positions) with its colour bar right of it.
    pub heat: Option<heatmap::Heat>,
}

/// A legend entry of its own, not tied to a series: what a marker or line
/// style means in this panel.
#[derive(Clone, Debug, Serialize)]
pub struct Key {
    /// Text (may hold `_{...}` subscripts).
    pub label: String,
    /// Colour of the sample.
    pub color: Color,
    /// Line sample, if any.
    pub dash: Option<Dash>,
    /// Marker sample.
    pub marker: bool,
}

impl Key {
    /// Grey markers: what the points are.
    pub fn points(label: impl Into<String>) -> Self {
        Key {
            label: label.into(),
            color: Color::Gray,
            dash: None,
            marker: true,
        }
    }
    /// A line sample: what lines of this colour and pattern are.
    pub fn line(label: impl Into<String>, color: Color, dash: Dash) -> Self {
        Key {
            label: label.into(),
            color,
            dash: Some(dash),
            marker: false,
        }
    }
}

impl Panel {
    /// Empty panel.
    pub fn new(label: impl Into<String>, title: impl Into<String>, x: Axis, y: Axis) -> Self {
        Panel {
            label: label.into(),
            title: title.into(),
            x,
            y,
            series: Vec::new(),
            notes: Vec::new(),
            legend_title: None,
            key: Vec::new(),
            heat: None,
        }
    }

    /// The legend as text, one line per row: the heading (if any), then the
    /// entries, subscript markup removed (what a reader sees).
    pub fn legend_lines(&self) -> Vec<String> {
        let entries = legend_entries(self);
        self.legend_title
            .iter()
            .chain(entries.iter().map(|e| &e.label))
            .map(|t| plain_text(t))
            .collect()
    }
}

/// A text drawn, as a box in figure pixels (from the backend's text-size
/// estimate, as the layout placed it).
#[derive(Clone, Debug, PartialEq)]
pub struct TextBox {
    /// The text.
    pub text: String,
    /// Left edge.
    pub x0: i32,
    /// Top edge.
    pub y0: i32,
    /// Right edge.
    pub x1: i32,
    /// Bottom edge.
    pub y1: i32,
}

impl TextBox {
    /// The box of `text` at (x, y) (top left), `w` × `h` pixels.
    pub fn new(text: &str, x: i32, y: i32, w: i32, h: i32) -> Self {
        TextBox {
            text: text.to_string(),
            x0: x,
            y0: y,
            x1: x + w,
            y1: y + h,
        }
    }
    /// Whether the two boxes share pixels (touching edges do not count).
    pub fn overlaps(&self, o: &TextBox) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
}

/// What rendering made of one panel: its ranges in data units, how many
/// values lie beyond the vertical range (marked), and the boxes of its
/// tick labels, axis labels and colour-bar texts in figure pixels.
#[derive(Clone, Debug)]
pub struct PanelDrawn {
    /// Horizontal range drawn.
    pub x_range: (f64, f64),
    /// Vertical range drawn.
    pub y_range: (f64, f64),
    /// Values beyond the vertical range (each run marked by a triangle).
    pub clipped: usize,
    /// Texts drawn: tick labels, axis labels, colour bar ticks and label.
    pub labels: Vec<TextBox>,
    /// The plotting area: left, top, right, bottom (figure pixels).
    pub plot_box: (i32, i32, i32, i32),
}

impl PanelDrawn {
    /// Move every box by (dx, dy) (area pixels to figure pixels).
    pub fn shift(&mut self, dx: i32, dy: i32) {
        for b in &mut self.labels {
            b.x0 += dx;
            b.x1 += dx;
            b.y0 += dy;
            b.y1 += dy;
        }
        let (l, t, r, b) = self.plot_box;
        self.plot_box = (l + dx, t + dy, r + dx, b + dy);
    }
    /// Pairs of texts that overlap.
    pub fn overlaps(&self) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for (i, a) in self.labels.iter().enumerate() {
            for b in &self.labels[i + 1..] {
                if a.overlaps(b) {
                    out.push((a.text.clone(), b.text.clone()));
                }
            }
        }
        out
    }
}

/// A figure: panels on a grid with `cols` columns, each `panel_px` pixels.
#[derive(Clone, Debug, Serialize)]
pub struct Figure {
    /// File stem, e.g. "fig2".
    pub name: String,
    /// Title over all panels.
    pub title: String,
    /// Number of panel columns.
    pub cols: usize,
    /// Panel size in pixels (width, height).
    pub panel_px: (u32, u32),
    /// Panels in reading order.
    pub panels: Vec<Panel>,
    /// What each kind of mark means in every panel (e.g. grey points:
    /// "exact sampler, 4000 particles"), a row of samples under the title.
    pub key: Vec<Key>,
}

impl Figure {
    /// New empty figure.
    pub fn new(name: impl Into<String>, title: impl Into<String>, cols: usize) -> Self {
        Figure {
            name: name.into(),
            title: title.into(),
            cols: cols.max(1),
            panel_px: (640, 480),
            panels: Vec::new(),
            key: Vec::new(),
        }
    }

    /// Every legend as text: the figure's key first, then each panel's
    /// [`Panel::legend_lines`] (subscript markup removed).
    pub fn legend_lines(&self) -> Vec<String> {
        self.key
            .iter()
            .map(|k| plain_text(&k.label))
            .chain(self.panels.iter().flat_map(|p| p.legend_lines()))
            .collect()
    }

    /// The figure key in rows that fit `width` pixels (indices into `key`),
    /// text widths estimated from the character count.
    fn key_rows(&self, width: u32, font_px: f64, sample_px: u32) -> Vec<Vec<usize>> {
        let mut rows: Vec<Vec<usize>> = Vec::new();
        let mut used = width;
        for (i, k) in self.key.iter().enumerate() {
            let w = key_item_width(&k.label, font_px, sample_px);
            if used + w > width.saturating_sub(24) || rows.is_empty() {
                rows.push(Vec::new());
                used = 12;
            }
            rows.last_mut().expect("a row").push(i);
            used += w;
        }
        rows
    }

    /// Panel rows and columns of the grid.
    fn grid(&self) -> (usize, usize) {
        let rows = self.panels.len().div_ceil(self.cols).max(1);
        let cols = self.cols.min(self.panels.len().max(1));
        (rows, cols)
    }

    /// Render to a PNG file.
    #[cfg(feature = "plot")]
    pub fn render_png(&self, path: &std::path::Path) -> Result<()> {
        render::png(self, path).map(|_| ())
    }

    /// Render to an SVG file.
    #[cfg(feature = "plot")]
    pub fn render_svg(&self, path: &std::path::Path) -> Result<()> {
        render::svg(self, path).map(|_| ())
    }

    /// Render to a PNG file and say where each panel put its ranges and
    /// texts (what the gallery test checks).
    #[cfg(feature = "plot")]
    pub fn render_png_drawn(&self, path: &std::path::Path) -> Result<Vec<PanelDrawn>> {
        render::png(self, path)
    }

    /// All plotted data in long format:
    /// `panel,series,source,style,x,y,y_err` (y_err empty for lines).
    pub fn data_csv(&self) -> Result<String> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let e = |e: csv::Error| Error::Io {
            path: format!("{}.csv", self.name),
            reason: e.to_string(),
        };
        w.write_record(["panel", "series", "source", "style", "x", "y", "y_err"])
            .map_err(e)?;
        for p in &self.panels {
            let panel = p.label.trim_matches(|c| c == '(' || c == ')');
            for s in &p.series {
                let style = match s.style {
                    Style::Points => "points",
                    Style::Line(Dash::Solid) => "line",
                    Style::Line(Dash::Dashed) => "dashed",
                    Style::Line(Dash::Dotted) => "dotted",
                };
                for i in 0..s.x.len() {
                    let err = s
                        .y_err
                        .as_ref()
                        .map(|v| irtp_app::io::format_float(v[i]))
                        .unwrap_or_default();
                    w.write_record([
                        panel,
                        s.label.as_deref().unwrap_or(""),
                        &s.source,
                        style,
                        &irtp_app::io::format_float(s.x[i]),
                        &irtp_app::io::format_float(s.y[i]),
                        &err,
                    ])
                    .map_err(e)?;
                }
            }
        }
        let bytes = w.into_inner().map_err(|x| Error::Io {
            path: format!("{}.csv", self.name),
            reason: x.to_string(),
        })?;
        Ok(String::from_utf8(bytes).expect("csv of utf-8 strings"))
    }
}

/// Estimated width of one figure-key item: sample, text, gap.
fn key_item_width(label: &str, font_px: f64, sample_px: u32) -> u32 {
    let chars = plain_text(label).chars().count() as f64;
    sample_px + 8 + (0.6 * font_px * chars) as u32 + 28
}

/// Data range of an axis in transformed units, with a margin.
fn fit_range(axis: &Axis, vals: impl Iterator<Item = f64>) -> (f64, f64) {
    if let Some((lo, hi)) = axis.range {
        let (a, b) = (axis.tr(lo), axis.tr(hi));
        if let (Some(a), Some(b)) = (a, b) {
            if b > a {
                return (a, b);
            }
        }
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter_map(|v| axis.tr(v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 * (1.0 + lo.abs()) {
        let d = if axis.scale == Scale::Log {
            0.5
        } else {
            0.5 * (1.0 + lo.abs())
        };
        return (lo - d, hi + d);
    }
    let m = 0.04 * (hi - lo);
    (lo - m, hi + m)
}

/// Source name of guide lines (power laws, reference levels): they never
/// set an axis range.
pub const GUIDE: &str = "guide";

/// The vertical range of a panel in layout units, and whether it clips
/// data. Fitted to the data (error bars included, guides not) with a
/// margin, unless a few extreme values would squeeze the rest into a line
/// (an integrable singularity at the edge of the velocity range, an atom
/// drawn as a tall cell): an end further than twice the spread of the
/// central 98 % ([`robust_range`]) from it is cut there.
pub fn fit_y(p: &Panel) -> ((f64, f64), bool) {
    let data = || p.series.iter().filter(|s| s.source != GUIDE);
    let vals: Vec<f64> = data()
        .flat_map(|s| {
            let e = s.y_err.clone();
            s.y.iter().enumerate().flat_map(move |(i, &y)| {
                let d = e
                    .as_ref()
                    .map_or(0.0, |e| if e[i].is_finite() { e[i] } else { 0.0 });
                [y - d, y, y + d]
            })
        })
        .collect();
    let full = fit_range(&p.y, vals.iter().copied());
    if p.y.range.is_some() {
        return (full, false);
    }
    let Some((qlo, qhi)) = robust_range(p) else {
        return (full, false);
    };
    let u: Vec<f64> = vals.iter().filter_map(|&v| p.y.tr(v)).collect();
    let lo = u.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = u.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = (qhi - qlo).max(1e-9 * (1.0 + qhi.abs()));
    let cut_lo = qlo - lo > 2.0 * span;
    let cut_hi = hi - qhi > 2.0 * span;
    if !(cut_lo || cut_hi) {
        return (full, false);
    }
    let a = if cut_lo { qlo - 0.15 * span } else { lo };
    let b = if cut_hi { qhi + 0.15 * span } else { hi };
    let m = 0.04 * (b - a);
    ((a - m, b + m), true)
}

/// The 1 % and 99 % quantiles (layout units) of a panel's drawn values,
/// guides left out, each series weighing one: a line's values weighted by
/// the share of its horizontal extent each covers (what the eye sees), a
/// series of points' equally; outlying groups at the ends left out first
/// (`main_cluster`). `None` without values.
pub fn robust_range(p: &Panel) -> Option<(f64, f64)> {
    let mut wv: Vec<(f64, f64)> = Vec::new();
    for s in p.series.iter().filter(|s| s.source != GUIDE) {
        let pts: Vec<(f64, f64)> =
            s.x.iter()
                .zip(&s.y)
                .filter_map(|(&x, &y)| Some((p.x.tr(x)?, p.y.tr(y)?)))
                .collect();
        let n = pts.len();
        if n == 0 {
            continue;
        }
        let w: Vec<f64> = match s.style {
            Style::Line(_) if n > 2 => (0..n)
                .map(|i| 0.5 * (pts[(i + 1).min(n - 1)].0 - pts[i.saturating_sub(1)].0).abs())
                .collect(),
            _ => vec![1.0; n],
        };
        let total: f64 = w.iter().sum();
        let total = if total > 0.0 { total } else { n as f64 };
        wv.extend(pts.iter().zip(&w).map(|(q, w)| (q.1, w / total)));
    }
    if wv.is_empty() {
        return None;
    }
    wv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (a, b) = main_cluster(&wv);
    let wv = &wv[a..=b];
    let all: f64 = wv.iter().map(|q| q.1).sum();
    let quantile = |f: f64| {
        let mut acc = 0.0;
        for &(v, w) in wv {
            acc += w;
            if acc >= f * all {
                return v;
            }
        }
        wv.last().expect("values").0
    };
    Some((quantile(0.01), quantile(0.99)))
}

/// The sorted weighted values `wv` without outlying groups at either end:
/// a group of at most 30 % of the weight cut off by a gap more than ten
/// times the (non-zero) extent of the rest (a τ(r) that runs away to 10⁷⁹
/// on a sparse grid, an atom drawn as a tall cell), repeatedly; the first
/// and last index kept.
fn main_cluster(wv: &[(f64, f64)]) -> (usize, usize) {
    let all: f64 = wv.iter().map(|q| q.1).sum();
    let (mut a, mut b) = (0, wv.len() - 1);
    loop {
        let (a0, b0) = (a, b);
        let mut above = 0.0;
        for j in (a..b).rev() {
            above += wv[j + 1].1;
            if above > 0.3 * all {
                break;
            }
            let rest = wv[j].0 - wv[a].0;
            if rest > 0.0 && wv[j + 1].0 - wv[j].0 > 10.0 * rest {
                b = j;
                break;
            }
        }
        let mut below = 0.0;
        for j in a + 1..=b {
            below += wv[j - 1].1;
            if below > 0.3 * all {
                break;
            }
            let rest = wv[b].0 - wv[j].0;
            if rest > 0.0 && wv[j].0 - wv[j - 1].0 > 10.0 * rest {
                a = j;
                break;
            }
        }
        if (a, b) == (a0, b0) {
            return (a, b);
        }
    }
}

/// Labels of `vals` rounded to the fewest significant digits (at least
/// one) that keep them distinct and within 5 % of the values:
/// 0.31622776601683794 reads 0.32 beside 0.1 and 1.
pub fn distinct_labels(vals: &[f64]) -> Vec<String> {
    for d in 1..=8 {
        let labels: Vec<String> = vals.iter().map(|&v| fmt_sig(v, d)).collect();
        let close = vals.iter().zip(&labels).all(|(&v, l)| {
            match l.replace('\u{2212}', "-").parse::<f64>() {
                Ok(x) => (x - v).abs() <= 0.05 * v.abs(),
                Err(_) => true,
            }
        });
        let mut sorted = labels.clone();
        sorted.sort();
        sorted.dedup();
        if close && sorted.len() == labels.len() {
            return labels;
        }
    }
    vals.iter().map(|&v| fmt_sig(v, 9)).collect()
}

/// `v` to `d` significant digits, trailing zeros dropped; plain decimals
/// for 10⁻³ ≤ |v| < 10⁵, else `m×10ᵏ`.
pub fn fmt_sig(v: f64, d: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { v.to_string() };
    }
    let e = v.abs().log10().floor() as i32;
    let r: f64 = format!("{:.*e}", d.saturating_sub(1), v)
        .parse()
        .unwrap_or(v);
    if !(1e-3..1e5).contains(&r.abs()) {
        let e = r.abs().log10().floor() as i32;
        let m = trim_zeros(&format!("{:.*}", d.saturating_sub(1), r / 10f64.powi(e)));
        return match m.as_str() {
            "1" => format!("10{}", superscript(&e.to_string())),
            "-1" => format!("-10{}", superscript(&e.to_string())),
            _ => format!("{m}×10{}", superscript(&e.to_string())),
        };
    }
    let dec = (d as i32 - 1 - e).max(0) as usize;
    trim_zeros(&format!("{r:.dec$}"))
}

/// "2.50" → "2.5", "3.00" → "3".
fn trim_zeros(s: &str) -> String {
    if !s.contains('.') {
        return s.to_string();
    }
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// "Nice" linear tick positions covering [lo, hi] (about `n` of them).
#[doc(hidden)]
pub fn nice_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = hi - lo;
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= n as f64 + 0.5)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Decades (and 2, 5 subdivisions for short ranges) in log10 units.
#[doc(hidden)]
pub fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let (a, b) = (lo.ceil() as i64, hi.floor() as i64);
    let mut major: Vec<f64> = (a..=b).map(|k| k as f64).collect();
    let mut minor = Vec::new();
    for k in (lo.floor() as i64)..=(hi.ceil() as i64) {
        for m in 2..10 {
            let v = k as f64 + (m as f64).log10();
            if v >= lo && v <= hi {
                minor.push(v);
            }
        }
    }
    if major.len() < 2 {
        // Less than two decades shown: label 2 and 5 multiples too.
        major.extend(
            minor
                .iter()
                .copied()
                .filter(|v| {
                    let f = 10f64.powf(v - v.floor());
                    (f - 2.0).abs() < 1e-9 || (f - 5.0).abs() < 1e-9
                })
                .collect::<Vec<_>>(),
        );
        major.sort_by(|a, b| a.total_cmp(b));
    }
    (major, minor)
}

/// Decimals that write `x` exactly enough for a tick (0.25 needs two, 0.2 one).
fn decimals(x: f64) -> usize {
    let x = x.abs();
    (0..12)
        .find(|&d| {
            let f = 10f64.powi(d);
            ((x * f).round() - x * f).abs() < 1e-6 * (x * f).max(1e-300)
        })
        .unwrap_or(12) as usize
}

fn superscript(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            c => c,
        })
        .collect()
}

/// `m.d×10ᵏ` with `dec` mantissa decimals ("0" for zero).
fn fmt_sci(v: f64, dec: usize) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let mut e = v.abs().log10().floor() as i32;
    let mut m = v / 10f64.powi(e);
    if (m.abs() * 10f64.powi(dec as i32)).round() >= 10f64.powi(dec as i32 + 1) {
        e += 1;
        m /= 10.0;
    }
    format!("{m:.dec$}×10{}", superscript(&e.to_string()))
}

/// Labels of the ticks of one axis (positions in layout units, log10 on a
/// log axis), all in one format: decades of a log axis as 10ᵏ; otherwise
/// plain numbers with one number of decimals, or all in scientific notation
/// when some tick is below 10⁻³ or at least 10⁵ in magnitude.
#[doc(hidden)]
pub fn tick_labels(axis: &Axis, ticks: &[f64], step: f64) -> Vec<String> {
    if axis.scale == Scale::Log && ticks.iter().all(|u| (u - u.round()).abs() < 1e-9) {
        return ticks
            .iter()
            .map(|u| format!("10{}", superscript(&(u.round() as i32).to_string())))
            .collect();
    }
    let vals: Vec<f64> = match axis.scale {
        // Snap to the step so that 0.6000000000000001 reads 0.6 and -0 reads 0.
        Scale::Linear => ticks
            .iter()
            .map(|&v| (v / step).round() * step)
            .map(|v| if v == 0.0 { 0.0 } else { v })
            .collect(),
        Scale::Log => ticks.iter().map(|&u| axis.inv(u)).collect(),
    };
    let sci = vals
        .iter()
        .any(|&v| v != 0.0 && !(1e-3..1e5).contains(&v.abs()));
    if sci {
        let dec = match axis.scale {
            Scale::Linear => 1,
            Scale::Log => 0,
        };
        return vals.iter().map(|&v| fmt_sci(v, dec)).collect();
    }
    let dec = match axis.scale {
        Scale::Linear => decimals(step),
        Scale::Log => vals.iter().map(|&v| decimals(v)).max().unwrap_or(0),
    };
    vals.iter().map(|v| format!("{v:.dec$}")).collect()
}

/// A count with thin spaces between groups of three digits: "1 000 000".
pub fn fmt_count(n: u64) -> String {
    let d = n.to_string();
    let mut out = String::new();
    for (i, c) in d.chars().enumerate() {
        if i > 0 && (d.len() - i) % 3 == 0 {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    out
}

/// "N" when all counts are N, "N–M" for a range, "" for none.
pub fn count_range(counts: impl IntoIterator<Item = u64>) -> String {
    let (lo, hi) = counts
        .into_iter()
        .fold((u64::MAX, 0), |(a, b), n| (a.min(n), b.max(n)));
    match (lo, hi) {
        (u64::MAX, _) => String::new(),
        (a, b) if a == b => fmt_count(a),
        (a, b) => format!("{}–{}", fmt_count(a), fmt_count(b)),
    }
}

/// Text and subscript markup `_{...}` as (text, is_subscript) pieces.
pub fn rich_segments(s: &str) -> Vec<(String, bool)> {
    let mut out: Vec<(String, bool)> = Vec::new();
    let mut rest = s;
    while let Some(i) = rest.find("_{") {
        let Some(j) = rest[i + 2..].find('}') else {
            break;
        };
        if i > 0 {
            out.push((rest[..i].to_string(), false));
        }
        out.push((rest[i + 2..i + 2 + j].to_string(), true));
        rest = &rest[i + 3 + j..];
    }
    if !rest.is_empty() {
        out.push((rest.to_string(), false));
    }
    out
}

/// `s` without subscript markup: "D_{eff}" → "Deff".
pub fn plain_text(s: &str) -> String {
    rich_segments(s).into_iter().map(|(t, _)| t).collect()
}

/// Ticks for an axis in transformed units and the label step (linear only).
fn ticks(axis: &Axis, lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>, f64) {
    match axis.scale {
        Scale::Linear => {
            let t = nice_ticks(lo, hi, 6);
            let step = if t.len() > 1 { t[1] - t[0] } else { hi - lo };
            (t, Vec::new(), step)
        }
        Scale::Log => {
            let (a, b) = log_ticks(lo, hi);
            (a, b, 1.0)
        }
    }
}

/// Cut a polyline (transformed units) into pieces inside the box
/// `[x0,x1]×[y0,y1]` (Liang-Barsky clipping of each segment).
#[doc(hidden)]
pub fn clip_polyline(pts: &[(f64, f64)], bx: (f64, f64), by: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    for w in pts.windows(2) {
        let (p, q) = (w[0], w[1]);
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut ok = true;
        for (pi, qi) in [
            (-dx, p.0 - bx.0),
            (dx, bx.1 - p.0),
            (-dy, p.1 - by.0),
            (dy, by.1 - p.1),
        ] {
            if pi == 0.0 {
                if qi < 0.0 {
                    ok = false;
                    break;
                }
            } else {
                let r = qi / pi;
                if pi < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if !ok || t0 > t1 {
            if cur.len() > 1 {
                out.push(std::mem::take(&mut cur));
            }
            cur.clear();
            continue;
        }
        let a = (p.0 + t0 * dx, p.1 + t0 * dy);
        let b = (p.0 + t1 * dx, p.1 + t1 * dy);
        if cur.is_empty() {
            cur.push(a);
        } else if t0 > 0.0 {
            if cur.len() > 1 {
                out.push(std::mem::take(&mut cur));
            }
            cur = vec![a];
        }
        cur.push(b);
        if t1 < 1.0 {
            if cur.len() > 1 {
                out.push(std::mem::take(&mut cur));
            }
            cur.clear();
        }
    }
    if cur.len() > 1 {
        out.push(cur);
    }
    out
}

/// Split a polyline where it turns by more than 120° in pixel space (a cusp),
/// so thick lines get no miter spike there; pieces share the turning point.
#[doc(hidden)]
pub fn split_sharp(pts: Vec<(f64, f64)>, px: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut start = 0;
    // Direction of the last segment of non-zero pixel length.
    let mut prev: Option<(f64, f64)> = None;
    for i in 1..pts.len() {
        let d = (px[i].0 - px[i - 1].0, px[i].1 - px[i - 1].1);
        let len = (d.0 * d.0 + d.1 * d.1).sqrt();
        if len < 1e-9 {
            continue;
        }
        let d = (d.0 / len, d.1 / len);
        if let Some(p) = prev {
            if p.0 * d.0 + p.1 * d.1 < -0.5 && i - 1 > start {
                out.push(pts[start..i].to_vec());
                start = i - 1;
            }
        }
        prev = Some(d);
    }
    out.push(pts[start..].to_vec());
    out.retain(|p| p.len() > 1);
    out
}

/// One legend entry: label, colour, line pattern and/or marker.
#[doc(hidden)]
pub struct Entry {
    /// The text.
    pub label: String,
    /// The colour of its line or marker.
    pub color: Color,
    /// Its line pattern; `None`: no line.
    pub dash: Option<Dash>,
    /// Whether it shows a marker.
    pub marker: bool,
}

/// The legend of `p`: one entry per label and colour of its series (a
/// marker and the first line pattern among them), then its key.
#[doc(hidden)]
pub fn legend_entries(p: &Panel) -> Vec<Entry> {
    let mut out: Vec<Entry> = Vec::new();
    for s in &p.series {
        let Some(label) = &s.label else { continue };
        let idx = out
            .iter()
            .position(|e| &e.label == label && e.color == s.color);
        let e = match idx {
            Some(i) => &mut out[i],
            None => {
                out.push(Entry {
                    label: label.clone(),
                    color: s.color,
                    dash: None,
                    marker: false,
                });
                out.last_mut().expect("just pushed")
            }
        };
        match s.style {
            Style::Points => e.marker = true,
            Style::Line(d) => {
                if e.dash.is_none() {
                    e.dash = Some(d)
                }
            }
        }
    }
    out.extend(p.key.iter().map(|k| Entry {
        label: k.label.clone(),
        color: k.color,
        dash: k.dash,
        marker: k.marker,
    }));
    out
}

/// Where the legend goes: a corner of the plotting area, or outside on the right.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Place {
    /// Inside, its top-left corner at these fractions of the plotting area.
    Inside(f64, f64),
    /// Outside, on the right.
    Outside,
}

/// Choose the legend place: the candidate box (fractions of the plotting
/// area) covering the fewest data points; outside if all cover some.
#[doc(hidden)]
pub fn choose_place(pts: &[(f64, f64)], fw: f64, fh: f64) -> Place {
    if fw > 0.6 || fh > 0.9 {
        return Place::Outside;
    }
    let m = 0.015;
    let cands = [
        (1.0 - fw - m, m),            // upper right
        (m, m),                       // upper left
        (1.0 - fw - m, 1.0 - fh - m), // lower right
        (m, 1.0 - fh - m),            // lower left
        (0.5 - fw / 2.0, m),          // upper centre
        (0.5 - fw / 2.0, 1.0 - fh - m),
        (1.0 - fw - m, 0.5 - fh / 2.0),
        (m, 0.5 - fh / 2.0),
        // Corners set in from the frame, clear of lines along its edges
        // (a density that diverges at the ends of the velocity range).
        (1.0 - fw - 4.0 * m, 4.0 * m),
        (4.0 * m, 4.0 * m),
    ];
    let pad = 0.01;
    let mut best = (usize::MAX, Place::Outside);
    for (x, y) in cands {
        let n = pts
            .iter()
            .filter(|(px, py)| {
                *px >= x - pad && *px <= x + fw + pad && *py >= y - pad && *py <= y + fh + pad
            })
            .count();
        if n < best.0 {
            best = (n, Place::Inside(x, y));
        }
    }
    if best.0 == 0 {
        best.1
    } else {
        Place::Outside
    }
}

/// Data points of a panel as fractions of the plotting area (0,0 = top left),
/// lines densely sampled so crossing segments count.
fn occupancy(p: &Panel, xr: (f64, f64), yr: (f64, f64)) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let fx = |x: f64| (x - xr.0) / (xr.1 - xr.0);
    let fy = |y: f64| 1.0 - (y - yr.0) / (yr.1 - yr.0);
    for s in &p.series {
        let pts: Vec<(f64, f64)> =
            s.x.iter()
                .zip(&s.y)
                .filter_map(|(&x, &y)| Some((p.x.tr(x)?, p.y.tr(y)?)))
                .collect();
        match s.style {
            Style::Points => {
                for &(x, y) in &pts {
                    out.push((fx(x), fy(y)));
                }
                // Error bar ends count as data too.
                if let Some(e) = &s.y_err {
                    for ((&xv, &yv), &ev) in s.x.iter().zip(&s.y).zip(e) {
                        for yy in [yv - ev, yv + ev] {
                            if let (Some(x), Some(y)) = (p.x.tr(xv), p.y.tr(yy)) {
                                out.push((fx(x), fy(y)));
                            }
                        }
                    }
                }
            }
            Style::Line(_) => {
                for piece in clip_polyline(&pts, xr, yr) {
                    for w in piece.windows(2) {
                        for k in 0..=20 {
                            let t = k as f64 / 20.0;
                            let x = w[0].0 + t * (w[1].0 - w[0].0);
                            let y = w[0].1 + t * (w[1].1 - w[0].1);
                            out.push((fx(x), fy(y)));
                        }
                    }
                }
            }
        }
    }
    out.retain(|(x, y)| (0.0..=1.0).contains(x) && (0.0..=1.0).contains(y));
    out
}
