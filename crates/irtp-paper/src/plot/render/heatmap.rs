//! Rendering of a panel's [`Heat`] layer: the cells between their edges
//! in data coordinates (so a log axis gets geometric cells), and the
//! colour bar right of the plotting area with its ticks and its label
//! placed past the widest tick label (they never run into each other).

use super::{draw_rich, rich_width, text_size, Chart, DynErr, FONT_PX, TICK_FONT_PX};
use crate::plot::heatmap::{viridis, Heat};
use crate::plot::{log_ticks, nice_ticks, tick_labels, Axis, TextBox};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Fill of a cell without a value.
const MISSING: RGBColor = RGBColor(220, 220, 220);
/// Width of the bar itself, its tick marks and the gaps around them.
const BAR_PX: i32 = 16;
const TICK_PX: i32 = 4;
const GAP_PX: i32 = 6;

/// Draw the cells (rows bottom to top, columns left to right).
pub(super) fn draw_cells<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    h: &Heat,
) -> Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    let cells = h.values.iter().enumerate().flat_map(|(j, row)| {
        row.iter().enumerate().filter_map(move |(i, v)| {
            let fill = match v {
                Some(v) if v.is_finite() && (!h.log || *v > 0.0) => {
                    let (r, g, b) = viridis(h.level(*v));
                    RGBColor(r, g, b)
                }
                _ => MISSING,
            };
            let (x0, x1) = (*h.x_edges.get(i)?, *h.x_edges.get(i + 1)?);
            let (y0, y1) = (*h.y_edges.get(j)?, *h.y_edges.get(j + 1)?);
            Some(Rectangle::new([(x0, y0), (x1, y1)], fill.filled()))
        })
    });
    chart.draw_series(cells)?;
    Ok(())
}

/// The colour scale's ends, never empty.
fn bar_range(h: &Heat) -> (f64, f64) {
    match h.value_range() {
        Some((lo, hi)) if hi > lo => (lo, hi),
        Some((v, _)) if h.log => (v / 2.0, v * 2.0),
        Some((v, _)) => (v - 0.5 * (1.0 + v.abs()), v + 0.5 * (1.0 + v.abs())),
        None => (0.0, 1.0),
    }
}

/// The colour bar's ticks: positions as fractions of its height and labels
/// (one format, as an axis'; decades and 2, 5 multiples on a log scale).
fn bar_ticks(h: &Heat) -> Vec<(f64, String)> {
    let (lo, hi) = bar_range(h);
    let axis = if h.log {
        Axis::log("")
    } else {
        Axis::linear("")
    };
    let (a, b) = (axis.tr(lo).unwrap_or(0.0), axis.tr(hi).unwrap_or(1.0));
    let (t, step) = if h.log {
        (log_ticks(a, b).0, 1.0)
    } else {
        let t = nice_ticks(a, b, 5);
        let step = if t.len() > 1 { t[1] - t[0] } else { b - a };
        (t, step)
    };
    let labels = tick_labels(&axis, &t, step);
    t.iter()
        .zip(labels)
        .map(|(&u, l)| ((u - a) / (b - a), l))
        .collect()
}

/// Width of the colour bar's area: gap, bar, ticks, the widest tick label,
/// gap, the label's line height, margin.
pub(super) fn bar_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, h: &Heat) -> i32 {
    let widest = bar_ticks(h)
        .iter()
        .map(|(_, l)| text_size(area, l, TICK_FONT_PX).0)
        .max()
        .unwrap_or(0);
    12 + BAR_PX + TICK_PX + GAP_PX + widest + GAP_PX + FONT_PX as i32 + 8
}

/// Draw the colour bar from (x, top) down to `bottom` (area pixels): the
/// scale, ticks with labels right of it, and the quantity's name reading
/// upwards past the widest label; the boxes of the texts.
pub(super) fn draw_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    h: &Heat,
    (x, top, bottom): (i32, i32, i32),
) -> Result<Vec<TextBox>, DynErr>
where
    DB::ErrorType: 'static,
{
    const STEPS: i32 = 120;
    let height = (bottom - top).max(1);
    for k in 0..STEPS {
        let (y0, y1) = (
            bottom - height * k / STEPS,
            bottom - height * (k + 1) / STEPS,
        );
        let (r, g, b) = viridis((f64::from(k) + 0.5) / f64::from(STEPS));
        area.draw(&Rectangle::new(
            [(x, y1), (x + BAR_PX, y0)],
            RGBColor(r, g, b).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(x, top), (x + BAR_PX, bottom)],
        ShapeStyle::from(&RGBColor(120, 120, 120)).stroke_width(1),
    ))?;
    let mut boxes = Vec::new();
    let mut widest = 0;
    let font = || (super::FAMILY, TICK_FONT_PX).into_font();
    for (f, l) in bar_ticks(h) {
        let y = bottom - (f * f64::from(height)).round() as i32;
        let tick = vec![(x + BAR_PX, y), (x + BAR_PX + TICK_PX, y)];
        area.draw(&PathElement::new(tick, BLACK))?;
        let (w, th) = text_size(area, &l, TICK_FONT_PX);
        let b = TextBox::new(&l, x + BAR_PX + TICK_PX + GAP_PX, y - th / 2, w, th);
        area.draw(&Text::new(l.clone(), (b.x0, b.y0), font()))?;
        widest = widest.max(w);
        boxes.push(b);
    }
    let len = rich_width(area, &h.label, FONT_PX);
    let lx = x + BAR_PX + TICK_PX + GAP_PX + widest + GAP_PX;
    let ly = (top + bottom + len) / 2;
    draw_rich(area, &h.label, (lx, ly), FONT_PX, true)?;
    boxes.push(TextBox::new(
        &h.label,
        lx,
        ly - len,
        FONT_PX as i32 + 4,
        len,
    ));
    Ok(boxes)
}
