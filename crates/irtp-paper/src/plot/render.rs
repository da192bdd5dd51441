//! Rendering of a [`Figure`] with `plotters` (cargo feature `plot`): PNG
//! through the bitmap backend and SVG, both with the embedded DejaVu Sans
//! font (no system font library needed).
//!
//! plotters does the mapping (linear, or its `log_scale` coordinates), the
//! error bars (`ErrorBar`) and the dashed and dotted strokes, in the plot and
//! in the legend; the layout it lacks (ranges, ticks, legend placement,
//! clipping, cusp splitting) comes from the parent module. Titles, axis
//! labels and legend text are drawn here piece by piece so that `_{...}`
//! subscripts come out lowered and smaller.

use super::{
    choose_place, clip_polyline, fit_range, fit_y, fmt_sig, legend_entries, occupancy,
    rich_segments, split_sharp, tick_labels, ticks, Axis, Color, Dash, Entry, Figure, Panel,
    PanelDrawn, Place, Scale, Style, TextBox, GUIDE,
};
use irtp::error::{Error, Result};
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::Color as _;
use std::ops::Range;
use std::path::Path;
use std::sync::Once;

mod heatmap;
use heatmap::bar_width;

/// The embedded sans-serif font (DejaVu Sans, free license, see assets/fonts).
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType font shipped with the crate.
        plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
            .map_err(|_| ())
            .expect("embedded DejaVu Sans is a valid font");
    });
}

const TITLE_PX: u32 = 34;
/// Height of one row of the figure key under the title.
const KEY_ROW_PX: u32 = 22;
const FONT_PX: f64 = 17.0;
const TICK_FONT_PX: f64 = 15.0;
const LEGEND_FONT_PX: f64 = 15.0;
/// Subscripts: size relative to the text and drop of their top edge.
const SUB_SIZE: f64 = 0.72;
const SUB_DROP: f64 = 0.42;
/// Height reserved above a panel's plotting area for its caption.
const CAPTION_PX: u32 = 28;
/// Label areas: below the plotting area (ticks and x label) and left of it.
const X_LABEL_AREA: u32 = 52;
const Y_LABEL_AREA: u32 = 72;
/// Legend: width of the line/marker sample and height of a row.
const SAMPLE_PX: i32 = 34;
const ROW_PX: i32 = 20;
/// Dash and gap lengths in pixels of dashed and dotted strokes.
const DASHED: (i32, i32) = (9, 6);
const DOTTED: (i32, i32) = (2, 4);

type DynErr = Box<dyn std::error::Error + 'static>;
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<AxisCoord, AxisCoord>>;

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Io {
        path: path.display().to_string(),
        reason: format!("plotting: {e}"),
    }
}

fn rgb(c: Color) -> RGBColor {
    let (r, g, b) = c.rgb();
    RGBColor(r, g, b)
}

/// Pixel size of the whole figure.
fn size(fig: &Figure) -> (u32, u32) {
    let (rows, cols) = fig.grid();
    let w = cols as u32 * fig.panel_px.0;
    (w, rows as u32 * fig.panel_px.1 + header_px(fig, w))
}

/// Height of the title and the key rows under it.
fn header_px(fig: &Figure, width: u32) -> u32 {
    TITLE_PX + KEY_ROW_PX * fig.key_rows(width, LEGEND_FONT_PX, SAMPLE_PX as u32).len() as u32
}

/// Render to a PNG file; where each panel put its ranges and texts.
pub(super) fn png(fig: &Figure, path: &Path) -> Result<Vec<PanelDrawn>> {
    register_font();
    let root = BitMapBackend::new(path, size(fig)).into_drawing_area();
    let drawn = draw_figure(fig, &root).map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(drawn)
}

/// Render to an SVG file; where each panel put its ranges and texts.
pub(super) fn svg(fig: &Figure, path: &Path) -> Result<Vec<PanelDrawn>> {
    register_font();
    let root = SVGBackend::new(path, size(fig)).into_drawing_area();
    let drawn = draw_figure(fig, &root).map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(drawn)
}

fn draw_figure<DB: DrawingBackend>(
    fig: &Figure,
    root: &DrawingArea<DB, Shift>,
) -> std::result::Result<Vec<PanelDrawn>, DynErr>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (w, h) = root.dim_in_pixel();
    let (title_area, body) = root.split_vertically(header_px(fig, w).min(h));
    draw_rich(&title_area, &fig.title, (12, 8), FONT_PX + 2.0, false)?;
    for (i, row) in fig
        .key_rows(w, LEGEND_FONT_PX, SAMPLE_PX as u32)
        .iter()
        .enumerate()
    {
        let mut x = 12;
        let cy = (TITLE_PX + KEY_ROW_PX * i as u32) as i32 + ROW_PX / 2 - 2;
        for &k in row {
            let key = &fig.key[k];
            let e = Entry {
                label: key.label.clone(),
                color: key.color,
                dash: key.dash,
                marker: key.marker,
            };
            draw_entry(&title_area, &e, (x, cy))?;
            x += SAMPLE_PX + 8 + rich_width(&title_area, &key.label, LEGEND_FONT_PX) + 28;
        }
    }
    let areas = body.split_evenly(fig.grid());
    let mut drawn = Vec::new();
    for (panel, area) in fig.panels.iter().zip(areas.iter()) {
        let mut d = draw_panel(panel, area)?;
        let (ax, ay) = area.get_base_pixel();
        d.shift(ax, ay);
        drawn.push(d);
    }
    Ok(drawn)
}

/// plotters' linear or logarithmic (`log_scale`) coordinate.
enum Mapping {
    Linear(RangedCoordf64),
    Log(LogCoord<f64>),
}

/// One axis: plotters' mapping with our own tick (bold) and grid (light)
/// positions in data units (plotters' `WithKeyPoints` cannot take a label
/// formatter, and its log key points have no 2-5 subdivisions).
struct AxisCoord {
    mapping: Mapping,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl AxisCoord {
    /// Range and ticks in the axis' layout units (see `Axis::tr`).
    fn new(axis: &Axis, (lo, hi): (f64, f64), bold: &[f64], light: &[f64]) -> Self {
        let mapping = match axis.scale {
            Scale::Linear => Mapping::Linear((lo..hi).into()),
            Scale::Log => Mapping::Log((axis.inv(lo)..axis.inv(hi)).log_scale().into()),
        };
        let data = |u: &[f64]| u.iter().map(|&u| axis.inv(u)).collect();
        AxisCoord {
            mapping,
            bold: data(bold),
            light: data(light),
        }
    }
}

impl Ranged for AxisCoord {
    type ValueType = f64;
    type FormatOption = DefaultFormatting;
    fn range(&self) -> Range<f64> {
        match &self.mapping {
            Mapping::Linear(c) => c.range(),
            Mapping::Log(c) => c.range(),
        }
    }
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        match &self.mapping {
            Mapping::Linear(c) => c.map(value, limit),
            Mapping::Log(c) => c.map(value, limit),
        }
    }
    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }
    fn axis_pixel_range(&self, limit: (i32, i32)) -> Range<i32> {
        match &self.mapping {
            Mapping::Linear(c) => c.axis_pixel_range(limit),
            Mapping::Log(c) => c.axis_pixel_range(limit),
        }
    }
}

/// Where things go in one panel, in layout units (log10 on log axes).
struct Layout {
    xr: (f64, f64),
    yr: (f64, f64),
    /// Whether the vertical range cuts off data ([`crate::plot::fit_y`]).
    clipped: bool,
    entries: Vec<Entry>,
    legend_px: (i32, i32),
    place: Place,
    /// Width of the colour bar's area right of the plotting area (0 without a heat map).
    bar_px: i32,
}

fn layout<DB: DrawingBackend>(p: &Panel, area: &DrawingArea<DB, Shift>) -> Layout {
    let (xr, (yr, clipped)) = match &p.heat {
        Some(h) => (
            fit_range(&p.x, h.x_edges.iter().copied()),
            (fit_range(&p.y, h.y_edges.iter().copied()), false),
        ),
        None => {
            // Only where a value can be drawn (an empty bin on a log axis cannot).
            let xs = p.series.iter().flat_map(|s| {
                let drawn = s.y.iter().map(|&y| p.y.tr(y).is_some());
                s.x.iter().zip(drawn).filter(|q| q.1).map(|q| *q.0)
            });
            (fit_range(&p.x, xs), fit_y(p))
        }
    };
    let mut entries = legend_entries(p);
    if clipped {
        entries.push(clip_entry(p, yr));
    }
    let (lw, lh) = legend_size(area, &entries, p.legend_title.as_deref());
    let bar_px = p.heat.as_ref().map_or(0, |h| bar_width(area, h));
    let (aw, ah) = area.dim_in_pixel();
    // Approximate plotting-area size (margins and label areas subtracted).
    let pw = aw as f64 - f64::from(8 + 16 + Y_LABEL_AREA) - bar_px as f64;
    let ph = ah as f64 - f64::from(6 + CAPTION_PX + 6 + X_LABEL_AREA);
    let (fw, fh) = (lw as f64 / pw, lh as f64 / ph);
    let mut yr = yr;
    let mut place = if entries.is_empty() {
        Place::Inside(0.0, 0.0)
    } else {
        match choose_place(&occupancy(p, xr, yr), fw, fh) {
            Place::Outside if p.heat.is_some() => Place::Inside(0.015, 0.015),
            place => place,
        }
    };
    if place == Place::Outside && p.y.range.is_none() && p.heat.is_none() && fh < 0.45 {
        // Headroom above the data for the legend rather than a narrower plot.
        let f = fh + 0.05;
        let high = (yr.0, yr.1 + (yr.1 - yr.0) * f / (1.0 - f));
        if let Place::Inside(x, y) = choose_place(&occupancy(p, xr, high), fw, fh) {
            (yr, place) = (high, Place::Inside(x, y));
        }
    }
    Layout {
        xr,
        yr,
        clipped,
        entries,
        legend_px: (lw, lh),
        place,
        bar_px,
    }
}

/// The legend entry saying that marked values lie beyond the vertical
/// axis, with the most extreme of them.
fn clip_entry(p: &Panel, yr: (f64, f64)) -> Entry {
    let beyond = p
        .series
        .iter()
        .filter(|s| s.source != GUIDE)
        .flat_map(|s| s.y.iter().copied())
        .filter(|&y| p.y.tr(y).is_some_and(|u| u > yr.1 || u < yr.0));
    let far = beyond.fold(f64::NAN, |m, y| {
        if m.is_nan() || y.abs() > m.abs() {
            y
        } else {
            m
        }
    });
    Entry {
        label: format!("▲ beyond the axis (to {})", fmt_sig(far, 3)),
        color: Color::Gray,
        dash: None,
        marker: false,
    }
}

/// Pixel positions of ticks along an axis and their labels: the axis'
/// own ticks, or nice ones with labels of one format; labels that would
/// run into their neighbours (estimated text widths, `gap` pixels apart)
/// left out, every second one or more.
fn axis_ticks<DB: DrawingBackend>(
    axis: &Axis,
    range: (f64, f64),
    area: &DrawingArea<DB, Shift>,
    px: impl Fn(f64) -> i32,
    along_x: bool,
) -> (Vec<f64>, Vec<f64>, Vec<(i32, String)>) {
    let (bold, light, labels) = match &axis.ticks {
        Some(t) => {
            let u: Vec<(f64, String)> = t
                .iter()
                .filter_map(|(v, l)| Some((axis.tr(*v)?, l.clone())))
                .filter(|(u, _)| *u >= range.0 - 1e-9 && *u <= range.1 + 1e-9)
                .collect();
            let (pos, labels): (Vec<f64>, Vec<String>) = u.into_iter().unzip();
            (pos, Vec::new(), labels)
        }
        None => {
            let (t, minor, step) = ticks(axis, range.0, range.1);
            let labels = tick_labels(axis, &t, step);
            (t, minor, labels)
        }
    };
    let placed: Vec<(i32, String)> = bold
        .iter()
        .zip(labels)
        .map(|(&u, l)| (px(axis.inv(u)), l))
        .collect();
    let size = |l: &str| text_size(area, l, TICK_FONT_PX);
    let extent = |l: &str| if along_x { size(l).0 } else { size(l).1 };
    let fits = |k: usize| {
        let kept: Vec<&(i32, String)> = placed.iter().step_by(k).collect();
        kept.windows(2).all(|w| {
            let need = (extent(&w[0].1) + extent(&w[1].1)) / 2 + 8;
            (w[1].0 - w[0].0).abs() >= need
        })
    };
    let k = (1..=placed.len().max(1)).find(|&k| fits(k)).unwrap_or(1);
    let shown = placed
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % k == 0)
        .map(|(_, t)| t)
        .collect();
    (bold, light, shown)
}

/// A panel's chart frame: margins (`right` px on the right) and the tick
/// label areas.
fn frame<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    right: i32,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin_top(6 + CAPTION_PX)
        .margin_left(8)
        .margin_bottom(6)
        .margin_right(right)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA);
    b
}

/// Caption, margins, axes, ticks, tick labels and grid of a panel; the
/// boxes of the tick labels drawn.
fn chart<'a, DB: DrawingBackend>(
    p: &Panel,
    area: &'a DrawingArea<DB, Shift>,
    l: &Layout,
) -> std::result::Result<(Chart<'a, DB>, Vec<TextBox>), DynErr>
where
    DB::ErrorType: 'static,
{
    let right_margin = if l.place == Place::Outside && !l.entries.is_empty() {
        l.legend_px.0 + 16
    } else {
        16
    } + l.bar_px;
    let caption = if p.title.is_empty() {
        p.label.clone()
    } else if p.label.is_empty() {
        p.title.clone()
    } else {
        format!("{}  {}", p.label, p.title)
    };
    let cw = rich_width(area, &caption, FONT_PX);
    let aw = area.dim_in_pixel().0 as i32;
    draw_rich(area, &caption, ((aw - cw).max(0) / 2, 6), FONT_PX, false)?;
    let plain = |axis: &Axis, r: (f64, f64)| AxisCoord::new(axis, r, &[], &[]);
    // The same frame twice: once to learn the pixel scale of the axes (the
    // tick labels' placement needs it), once with the ticks chosen.
    let probe =
        frame(area, right_margin).build_cartesian_2d(plain(&p.x, l.xr), plain(&p.y, l.yr))?;
    let (ax, ay) = area.get_base_pixel();
    let y0 = probe.plotting_area().get_y_range().start;
    let x0 = probe.plotting_area().get_x_range().start;
    let xpx = |v: f64| probe.backend_coord(&(v, y0)).0 - ax;
    let ypx = |v: f64| probe.backend_coord(&(x0, v)).1 - ay;
    let (xt, xminor, xlab) = axis_ticks(&p.x, l.xr, area, xpx, true);
    let (yt, yminor, ylab) = axis_ticks(&p.y, l.yr, area, ypx, false);
    let mut chart = frame(area, right_margin).build_cartesian_2d(
        AxisCoord::new(&p.x, l.xr, &xt, &xminor),
        AxisCoord::new(&p.y, l.yr, &yt, &yminor),
    )?;
    let mut mesh = chart.configure_mesh();
    mesh.label_style((FAMILY, TICK_FONT_PX))
        .x_label_formatter(&|_| String::new())
        .y_label_formatter(&|_| String::new())
        .bold_line_style(RGBColor(225, 225, 225))
        .light_line_style(RGBColor(243, 243, 243));
    if p.heat.is_some() {
        mesh.disable_mesh();
    }
    mesh.draw()?;
    let mut boxes = tick_texts(area, &chart, &xlab, &ylab)?;
    boxes.extend(axis_labels(p, area, &chart)?);
    Ok((chart, boxes))
}

/// Draw the tick labels (x centred under the axis, y right-aligned left
/// of it); their boxes in area pixels.
fn tick_texts<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &Chart<'_, DB>,
    xlab: &[(i32, String)],
    ylab: &[(i32, String)],
) -> std::result::Result<Vec<TextBox>, DynErr>
where
    DB::ErrorType: 'static,
{
    let (l, _, _, b) = plot_box(area, chart);
    let font = || (FAMILY, TICK_FONT_PX).into_font();
    let mut out = Vec::new();
    for (x, s) in xlab {
        let (w, h) = text_size(area, s, TICK_FONT_PX);
        let bx = TextBox::new(s, x - w / 2, b + 8, w, h);
        area.draw(&Text::new(s.clone(), (bx.x0, bx.y0), font()))?;
        out.push(bx);
    }
    for (y, s) in ylab {
        let (w, h) = text_size(area, s, TICK_FONT_PX);
        let bx = TextBox::new(s, l - 8 - w, y - h / 2, w, h);
        area.draw(&Text::new(s.clone(), (bx.x0, bx.y0), font()))?;
        out.push(bx);
    }
    Ok(out)
}

/// The plotting area's left, top, right and bottom edges in area pixels.
fn plot_box<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &Chart<'_, DB>,
) -> (i32, i32, i32, i32) {
    let plot = chart.plotting_area();
    let (xrange, yrange) = (plot.get_x_range(), plot.get_y_range());
    let (ax, ay) = area.get_base_pixel();
    let tl = chart.backend_coord(&(xrange.start, yrange.end));
    let br = chart.backend_coord(&(xrange.end, yrange.start));
    (tl.0 - ax, tl.1 - ay, br.0 - ax, br.1 - ay)
}

/// The axis labels, centred below and left of the plotting area (the y
/// label reading upwards); their boxes in area pixels.
fn axis_labels<DB: DrawingBackend>(
    p: &Panel,
    area: &DrawingArea<DB, Shift>,
    chart: &Chart<'_, DB>,
) -> std::result::Result<Vec<TextBox>, DynErr>
where
    DB::ErrorType: 'static,
{
    let (l, t, r, b) = plot_box(area, chart);
    let h = FONT_PX as i32 + 4;
    let w = rich_width(area, &p.x.label, FONT_PX);
    let y = b + X_LABEL_AREA as i32 - FONT_PX as i32 - 4;
    draw_rich(area, &p.x.label, ((l + r - w) / 2, y), FONT_PX, false)?;
    let xb = TextBox::new(&p.x.label, (l + r - w) / 2, y, w, h);
    let len = rich_width(area, &p.y.label, FONT_PX);
    let x = l - Y_LABEL_AREA as i32 + 2;
    draw_rich(area, &p.y.label, (x, (t + b + len) / 2), FONT_PX, true)?;
    let yb = TextBox::new(&p.y.label, x, (t + b - len) / 2, h, len);
    Ok(vec![xb, yb])
}

/// Width and height in pixels of plain `t` at `px` font size (the
/// backend's estimate).
fn text_size<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, t: &str, px: f64) -> (i32, i32) {
    let font = (FAMILY, px).into_font();
    area.estimate_text_size(t, &TextStyle::from(font))
        .map(|(w, h)| (w as i32, h as i32))
        .unwrap_or(((0.6 * px) as i32 * t.chars().count() as i32, px as i32))
}

/// Width in pixels of `text` (with `_{...}` subscripts) at `px` font size.
fn rich_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str, px: f64) -> i32 {
    rich_segments(text)
        .iter()
        .map(|(t, sub)| text_width(area, t, if *sub { SUB_SIZE * px } else { px }))
        .sum()
}

fn text_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, t: &str, px: f64) -> i32 {
    let font = (FAMILY, px).into_font();
    area.estimate_text_size(t, &TextStyle::from(font))
        .map(|(w, _)| w as i32)
        .unwrap_or((0.6 * px) as i32 * t.chars().count() as i32)
}

/// Draw `text` with its `_{...}` subscripts lowered and smaller, from
/// (x, y) (area pixels): the top left of the text, or with `upwards` the
/// bottom left of text reading upwards.
fn draw_rich<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    (x, y): (i32, i32),
    px: f64,
    upwards: bool,
) -> std::result::Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    let mut along = 0;
    for (t, sub) in rich_segments(text) {
        let (size, drop) = if sub {
            (SUB_SIZE * px, (SUB_DROP * px) as i32)
        } else {
            (px, 0)
        };
        let w = text_width(area, &t, size);
        let font = (FAMILY, size).into_font();
        if upwards {
            let font = font.transform(FontTransform::Rotate270);
            area.draw(&Text::new(t, (x + drop, y - along), font))?;
        } else {
            area.draw(&Text::new(t, (x + along, y + drop), font))?;
        }
        along += w;
    }
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    p: &Panel,
    area: &DrawingArea<DB, Shift>,
) -> std::result::Result<PanelDrawn, DynErr>
where
    DB::ErrorType: 'static,
{
    let l = layout(p, area);
    let (mut chart, mut labels) = chart(p, area, &l)?;
    if let Some(h) = &p.heat {
        heatmap::draw_cells(&mut chart, h)?;
        let (_, pt, pr, pb) = plot_box(area, &chart);
        labels.extend(heatmap::draw_bar(area, h, (pr + 12, pt, pb))?);
    }
    // Lines first, points on top.
    draw_lines(&mut chart, p, &l)?;
    draw_points(&mut chart, p, &l)?;
    let clipped = draw_clip_marks(area, &chart, p, &l)?;
    draw_notes(&mut chart, p, &l)?;
    let drawn = PanelDrawn {
        x_range: (p.x.inv(l.xr.0), p.x.inv(l.xr.1)),
        y_range: (p.y.inv(l.yr.0), p.y.inv(l.yr.1)),
        clipped,
        labels,
        plot_box: plot_box(area, &chart),
    };
    if l.entries.is_empty() {
        return Ok(drawn);
    }
    let (ox, oy, br0, br1) = plot_box(area, &chart);
    let (w, h) = (br0 - ox, br1 - oy);
    let (ax, ay) = area.get_base_pixel();
    let corner = match l.place {
        Place::Inside(fx, fy) => (ox + (fx * w as f64) as i32, oy + (fy * h as f64) as i32),
        Place::Outside => (br0 + 10, oy),
    };
    draw_legend(
        area,
        &l.entries,
        p.legend_title.as_deref(),
        (corner.0 + ax, corner.1 + ay),
        l.legend_px,
    )?;
    Ok(drawn)
}

/// Mark values beyond the vertical range: a triangle at the edge they
/// pass, one per run of consecutive such values of a series (at the
/// extreme one); the number of values beyond.
fn draw_clip_marks<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &Chart<'_, DB>,
    p: &Panel,
    l: &Layout,
) -> std::result::Result<usize, DynErr>
where
    DB::ErrorType: 'static,
{
    if !l.clipped {
        return Ok(0);
    }
    let ax = area.get_base_pixel().0;
    let (_, top, _, bottom) = plot_box(area, chart);
    let mut count = 0;
    for s in p.series.iter().filter(|s| s.source != GUIDE) {
        let style = ShapeStyle::from(&rgb(s.color)).filled();
        let side = |y: f64| match p.y.tr(y) {
            Some(u) if u > l.yr.1 => 1,
            Some(u) if u < l.yr.0 => -1,
            _ => 0,
        };
        let mut i = 0;
        while i < s.y.len() {
            let d = side(s.y[i]);
            if d == 0 || !p.x.tr(s.x[i]).is_some_and(|u| u >= l.xr.0 && u <= l.xr.1) {
                i += 1;
                continue;
            }
            let mut j = i;
            let mut far = i;
            while j < s.y.len() && side(s.y[j]) == d {
                if (s.y[j] - s.y[far]) * d as f64 > 0.0 {
                    far = j;
                }
                j += 1;
            }
            count += j - i;
            let x = chart.backend_coord(&(s.x[far], p.y.inv(l.yr.0))).0 - ax;
            let (tip, base) = if d > 0 {
                (top, top + 9)
            } else {
                (bottom, bottom - 9)
            };
            area.draw(&Polygon::new(
                vec![(x, tip), (x - 5, base), (x + 5, base)],
                style,
            ))?;
            i = j;
        }
    }
    Ok(count)
}

/// Lines, clipped to the axes and split at cusps, solid or with plotters' dashes.
fn draw_lines<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    p: &Panel,
    l: &Layout,
) -> std::result::Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    for s in &p.series {
        let Style::Line(dash) = s.style else {
            continue;
        };
        let pts: Vec<(f64, f64)> =
            s.x.iter()
                .zip(&s.y)
                .filter_map(|(&x, &y)| Some((p.x.tr(x)?, p.y.tr(y)?)))
                .collect();
        let width = if s.source == "guide" && dash == Dash::Dashed {
            1
        } else {
            2
        };
        let style = ShapeStyle::from(&rgb(s.color)).stroke_width(width);
        for piece in clip_polyline(&pts, l.xr, l.yr) {
            let data: Vec<(f64, f64)> = piece
                .iter()
                .map(|&(u, v)| (p.x.inv(u), p.y.inv(v)))
                .collect();
            let px: Vec<(f64, f64)> = data
                .iter()
                .map(|c| {
                    let b = chart.backend_coord(c);
                    (b.0 as f64, b.1 as f64)
                })
                .collect();
            for part in split_sharp(data, &px) {
                match dash {
                    Dash::Solid => {
                        chart.draw_series(std::iter::once(PathElement::new(part, style)))?
                    }
                    Dash::Dashed => {
                        chart.draw_series(DashedLineSeries::new(part, DASHED.0, DASHED.1, style))?
                    }
                    Dash::Dotted => {
                        chart.draw_series(DashedLineSeries::new(part, DOTTED.0, DOTTED.1, style))?
                    }
                };
            }
        }
    }
    Ok(())
}

/// Points inside the axes with plotters' vertical error bars (clipped to the axes).
fn draw_points<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    p: &Panel,
    l: &Layout,
) -> std::result::Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    let (xr, yr) = (l.xr, l.yr);
    // Caps 1.2 % of the plotting area wide.
    let cap_px = 2 * (0.006 * chart.plotting_area().dim_in_pixel().0 as f64).round() as u32;
    for s in p.series.iter().filter(|s| s.style == Style::Points) {
        let col = rgb(s.color);
        let bar_style = ShapeStyle::from(&col).stroke_width(1);
        let mut pts = Vec::new();
        let mut bars = Vec::new();
        for i in 0..s.x.len() {
            let (Some(x), Some(y)) = (p.x.tr(s.x[i]), p.y.tr(s.y[i])) else {
                continue;
            };
            if x < xr.0 || x > xr.1 || y < yr.0 || y > yr.1 {
                continue;
            }
            pts.push((s.x[i], s.y[i]));
            let e = s.y_err.as_ref().map_or(0.0, |e| e[i]);
            if e.is_finite() && e > 0.0 {
                let lo = p.y.tr(s.y[i] - e).unwrap_or(yr.0).max(yr.0);
                let hi = p.y.tr(s.y[i] + e).unwrap_or(yr.1).min(yr.1);
                bars.push(ErrorBar::new_vertical(
                    s.x[i],
                    p.y.inv(lo),
                    s.y[i],
                    p.y.inv(hi),
                    bar_style,
                    cap_px,
                ));
            }
        }
        chart.draw_series(bars)?;
        chart.draw_series(
            pts.into_iter()
                .map(|c| Circle::new(c, 3, ShapeStyle::from(&col).filled())),
        )?;
    }
    Ok(())
}

/// Guide labels inside the axes.
fn draw_notes<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    p: &Panel,
    l: &Layout,
) -> std::result::Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    let (xr, yr) = (l.xr, l.yr);
    for n in &p.notes {
        if let (Some(x), Some(y)) = (p.x.tr(n.x), p.y.tr(n.y)) {
            if x >= xr.0 && x <= xr.1 && y >= yr.0 && y <= yr.1 {
                chart.draw_series(std::iter::once(Text::new(
                    n.text.clone(),
                    (n.x, n.y),
                    (FAMILY, FONT_PX).into_font().color(&rgb(Color::Gray)),
                )))?;
            }
        }
    }
    Ok(())
}

/// Pixel size of the legend box.
fn legend_size<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    title: Option<&str>,
) -> (i32, i32) {
    let mut w = 0i32;
    for t in entries.iter().map(|e| e.label.as_str()).chain(title) {
        w = w.max(rich_width(area, t, LEGEND_FONT_PX));
    }
    let rows = entries.len() as i32 + i32::from(title.is_some());
    (SAMPLE_PX + 14 + w + 8, rows * ROW_PX + 10)
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    title: Option<&str>,
    (x, y): (i32, i32),
    (w, h): (i32, i32),
) -> std::result::Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    // The area's own pixel origin: drawing uses coordinates relative to it.
    let (ax, ay) = area.get_base_pixel();
    let (x, y) = (x - ax, y - ay);
    area.draw(&Rectangle::new(
        [(x, y), (x + w, y + h)],
        ShapeStyle::from(&WHITE.mix(0.85)).filled(),
    ))?;
    area.draw(&Rectangle::new(
        [(x, y), (x + w, y + h)],
        ShapeStyle::from(&RGBColor(190, 190, 190)).stroke_width(1),
    ))?;
    let mut row = y + 5;
    if let Some(t) = title {
        draw_rich(area, t, (x + 8, row + 2), LEGEND_FONT_PX, false)?;
        row += ROW_PX;
    }
    for e in entries {
        draw_entry(area, e, (x + 8, row + ROW_PX / 2))?;
        row += ROW_PX;
    }
    Ok(())
}

/// One legend entry: line and/or marker sample from x0, then its text;
/// `cy` is the vertical centre.
fn draw_entry<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    e: &Entry,
    (x0, cy): (i32, i32),
) -> std::result::Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    let col = rgb(e.color);
    let x1 = x0 + SAMPLE_PX;
    let sample = vec![(x0, cy), (x1, cy)];
    let style = ShapeStyle::from(&col).stroke_width(2);
    match e.dash {
        Some(Dash::Solid) => area.draw(&PathElement::new(sample, style))?,
        Some(Dash::Dashed) => {
            area.draw(&DashedPathElement::new(sample, DASHED.0, DASHED.1, style))?
        }
        Some(Dash::Dotted) => {
            area.draw(&DashedPathElement::new(sample, DOTTED.0, DOTTED.1, style))?
        }
        None => {}
    }
    if e.marker {
        area.draw(&Circle::new(
            ((x0 + x1) / 2, cy),
            4,
            ShapeStyle::from(&col).filled(),
        ))?;
    }
    let ty = cy - (LEGEND_FONT_PX as i32) / 2 - 1;
    draw_rich(area, &e.label, (x1 + 8, ty), LEGEND_FONT_PX, false)?;
    Ok(())
}
