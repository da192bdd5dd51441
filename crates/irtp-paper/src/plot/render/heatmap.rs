//! Rendering of a [`HeatMap`] with `plotters`: cells on segmented axes
//! (one tick label per column and row, the values as typed in the plan)
//! and a colour bar on the right.

use super::{plot_err, register_font, DynErr, FAMILY, FONT_PX, TICK_FONT_PX};
use crate::plot::heatmap::{viridis, HeatMap};
use irtp::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Pixel size of a heat map image.
const SIZE: (u32, u32) = (820, 620);
/// Width of the colour bar's area (bar, ticks and label).
const BAR_AREA: u32 = 150;
/// Fill of a cell without a value.
const MISSING: RGBColor = RGBColor(220, 220, 220);

/// Render to a PNG file.
pub(in crate::plot) fn heatmap_png(h: &HeatMap, path: &Path) -> Result<()> {
    register_font();
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    draw(h, &root).map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

/// Render to an SVG file.
pub(in crate::plot) fn heatmap_svg(h: &HeatMap, path: &Path) -> Result<()> {
    register_font();
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    draw(h, &root).map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

/// The label of segment `v` of an axis with tick labels `ticks`.
fn segment_label(ticks: &[String], v: &SegmentValue<usize>) -> String {
    match v {
        SegmentValue::CenterOf(i) => ticks.get(*i).cloned().unwrap_or_default(),
        _ => String::new(),
    }
}

fn draw<DB: DrawingBackend>(h: &HeatMap, root: &DrawingArea<DB, Shift>) -> Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (w, _) = root.dim_in_pixel();
    let (main, bar) = root.split_horizontally(w - BAR_AREA);
    let (nx, ny) = (h.x_ticks.len(), h.y_ticks.len());
    let mut chart = ChartBuilder::on(&main)
        .caption(&h.title, (FAMILY, FONT_PX + 2.0))
        .margin(12)
        .x_label_area_size(56)
        .y_label_area_size(84)
        // A discrete range holds its end: `0..n - 1` has n segments.
        .build_cartesian_2d(
            (0..nx.saturating_sub(1)).into_segmented(),
            (0..ny.saturating_sub(1)).into_segmented(),
        )?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(nx.max(1))
        .y_labels(ny.max(1))
        .x_label_formatter(&|v| segment_label(&h.x_ticks, v))
        .y_label_formatter(&|v| segment_label(&h.y_ticks, v))
        .x_desc(h.x_label.as_str())
        .y_desc(h.y_label.as_str())
        .label_style((FAMILY, TICK_FONT_PX))
        .axis_desc_style((FAMILY, FONT_PX))
        .draw()?;
    let cells = h.values.iter().enumerate().flat_map(|(j, row)| {
        row.iter().enumerate().map(move |(i, v)| {
            let fill = match v {
                Some(v) if v.is_finite() => {
                    let (r, g, b) = viridis(h.level(*v));
                    RGBColor(r, g, b)
                }
                _ => MISSING,
            };
            let corners = [
                (SegmentValue::Exact(i), SegmentValue::Exact(j)),
                (SegmentValue::Exact(i + 1), SegmentValue::Exact(j + 1)),
            ];
            Rectangle::new(corners, fill.filled())
        })
    });
    chart.draw_series(cells)?;
    draw_bar(h, &bar)
}

/// The colour bar: the viridis scale from the smallest to the largest
/// value, with ticks and the quantity's name.
fn draw_bar<DB: DrawingBackend>(h: &HeatMap, area: &DrawingArea<DB, Shift>) -> Result<(), DynErr>
where
    DB::ErrorType: 'static,
{
    let (lo, hi) = match h.value_range() {
        Some((lo, hi)) if hi > lo => (lo, hi),
        Some((v, _)) => (v - 0.5 * (1.0 + v.abs()), v + 0.5 * (1.0 + v.abs())),
        None => (0.0, 1.0),
    };
    let mut chart = ChartBuilder::on(area)
        .margin_top(48)
        .margin_bottom(68)
        .margin_left(8)
        .margin_right(16)
        .y_label_area_size(0)
        .right_y_label_area_size(96)
        .build_cartesian_2d(0.0..1.0, lo..hi)?
        .set_secondary_coord(0.0..1.0, lo..hi);
    const STEPS: usize = 100;
    let step = (hi - lo) / STEPS as f64;
    chart.draw_series((0..STEPS).map(|k| {
        let y = lo + k as f64 * step;
        let (r, g, b) = viridis((k as f64 + 0.5) / STEPS as f64);
        Rectangle::new([(0.0, y), (1.0, y + step)], RGBColor(r, g, b).filled())
    }))?;
    chart
        .configure_secondary_axes()
        .y_labels(6)
        .label_style((FAMILY, TICK_FONT_PX))
        .y_desc(h.value_label.as_str())
        .axis_desc_style((FAMILY, FONT_PX))
        .draw()?;
    Ok(())
}
