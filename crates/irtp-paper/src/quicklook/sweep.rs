//! The figure of a sweep directory: one `results.csv` column over the
//! plan's crossed axes (a `[[zip]]` group is one axis). One axis: the
//! values against it with their error bars (`<column>_err`) on log axes
//! where the plan's values are log-spaced and the values span decades,
//! with the r⁻² law beside D_eff(r) and the smallest τ marked. Two axes: a
//! heat map, cells edged between the plan's values (geometric means on a
//! log-spaced axis), the colour bar labelled with the quantity's symbol.
//! More axes: small multiples, one heat map per value of the further axes
//! (at most [`MAX_PANELS`]), sharing one colour scale.

use super::{choose_var, digits, read_results, symbols};
use crate::plot::heatmap::{edges, log_spaced, Heat};
use crate::plot::{distinct_labels, Axis, Color, Dash, Figure, Note, Panel, Series, GUIDE};
use irtp::error::Result;
use irtp_app::sweep::Plan;
use std::collections::HashMap;
use std::path::Path;

/// The most panels of small multiples (the first ones in plan order).
pub const MAX_PANELS: usize = 12;

/// One crossed axis as drawn: its label, each step's data position and
/// tick label, and whether it is logarithmic.
struct PlanAxis {
    label: String,
    pos: Vec<f64>,
    ticks: Vec<String>,
    log: bool,
    numeric: bool,
    /// Each step as `Σ = 3` (`λ = 0.5, v_{r} = 0` for a `[[zip]]` group).
    at: Vec<String>,
}

/// The most steps of a numeric axis labelled at the steps themselves.
const MAX_STEP_TICKS: usize = 8;

impl PlanAxis {
    /// The axis: log or linear, ticks at the steps (nice ones instead for
    /// more than [`MAX_STEP_TICKS`] numeric steps), range to the cell edges.
    fn axis(&self, cells: bool) -> Axis {
        let a = if self.log {
            Axis::log(self.label.clone())
        } else {
            Axis::linear(self.label.clone())
        };
        let a = match self.numeric && self.pos.len() > MAX_STEP_TICKS {
            true => a,
            false => a.ticks_at(self.pos.iter().copied().zip(self.ticks.clone()).collect()),
        };
        if cells {
            let e = self.edges();
            return a.range(e[0], e[e.len() - 1]);
        }
        a
    }
    fn edges(&self) -> Vec<f64> {
        edges(&self.pos, self.log)
    }
}

/// A point's value and standard error (nan without one), by its steps.
type Values = HashMap<Vec<usize>, (f64, f64)>;

/// The figure of the sweep in `dir` (see the module's documentation).
pub fn figure(dir: &Path, var: Option<&str>) -> Result<Figure> {
    let text = std::fs::read_to_string(dir.join("plan.toml")).map_err(|_| super::not_irtp(dir))?;
    let plan = Plan::parse(&text)?;
    let crossed = plan.crossed();
    let (header, records) = read_results(dir)?;
    let var = choose_var(&header, &records, var)?;
    let col = |name: &str| header.iter().position(|h| h == name);
    let (jv, je) = (col(&var), col(&format!("{var}_err")));
    let mut texts: Vec<Vec<Vec<String>>> = crossed.iter().map(|g| vec![Vec::new(); g.1]).collect();
    let mut values = Values::new();
    for rec in &records {
        let at = |j: Option<usize>| j.and_then(|j| rec.get(j)).unwrap_or("").trim();
        let Some(d) = at(col("point"))
            .parse()
            .ok()
            .and_then(|p| digits(p, &crossed))
        else {
            continue;
        };
        for (k, g) in crossed.iter().enumerate() {
            texts[k][d[k]] = g.0.iter().map(|n| at(col(n)).to_string()).collect();
        }
        let ok = at(col("status")) == "ok";
        let num = |s: &str| s.parse::<f64>().ok().filter(|v| ok && v.is_finite());
        let v = num(at(jv)).unwrap_or(f64::NAN);
        values.insert(d, (v, num(at(je)).unwrap_or(f64::NAN)));
    }
    let axes: Vec<PlanAxis> = crossed
        .iter()
        .zip(texts)
        .map(|(g, t)| plan_axis(&g.0, t))
        .collect();
    let mut fig = Figure::new("plot", title(&plan, &var), 1);
    match axes.len() {
        1 => fig
            .panels
            .push(line_panel(&axes[0], &crossed[0].0, &var, &values)),
        _ => small_multiples(&mut fig, &axes, &crossed, &var, &values),
    }
    Ok(fig)
}

/// The title: the command, the quantity and the plan's fixed parameters.
fn title(plan: &Plan, var: &str) -> String {
    const SHOWN: [&str; 12] = [
        "drag",
        "noise",
        "sigma",
        "lambda",
        "rate",
        "reset_velocity",
        "reset_period",
        "temperature",
        "v0",
        "vt",
        "xt",
        "reset_position",
    ];
    let fixed: Vec<String> = SHOWN
        .iter()
        .filter_map(|k| {
            let (_, v) = plan.fixed.iter().find(|(n, _)| n == k)?;
            symbols::assignment(k, &irtp_app::sweep::plan::json(v))
        })
        .collect();
    let head = format!("{} over a sweep of {}", symbols::result(var), plan.command);
    match fixed.is_empty() {
        true => head,
        false => format!("{head}: {}", fixed.join(", ")),
    }
}

/// A crossed axis from its names and each step's values (one per name)
/// as text: numeric
/// (one name, every value a number, increasing) with rounded tick labels,
/// logarithmic where the values are log-spaced; else the steps 0, 1, ...
/// labelled with the values as written.
fn plan_axis(names: &[String], parts: Vec<Vec<String>>) -> PlanAxis {
    let texts: Vec<String> = parts.iter().map(|p| p.join(", ")).collect();
    let at = parts
        .iter()
        .map(|p| {
            let each = names
                .iter()
                .zip(p)
                .map(|(n, v)| format!("{} = {v}", symbols::param(n)));
            each.collect::<Vec<_>>().join(", ")
        })
        .collect();
    let label = names
        .iter()
        .map(|n| symbols::param(n))
        .collect::<Vec<_>>()
        .join(", ");
    let nums: Option<Vec<f64>> = texts.iter().map(|t| t.parse::<f64>().ok()).collect();
    let increasing =
        |v: &[f64]| v.windows(2).all(|w| w[1] > w[0]) && v.iter().all(|x| x.is_finite());
    match nums {
        Some(v) if names.len() == 1 && increasing(&v) => PlanAxis {
            label,
            log: log_spaced(&v),
            ticks: distinct_labels(&v),
            pos: v,
            numeric: true,
            at,
        },
        _ => PlanAxis {
            label,
            pos: (0..texts.len()).map(|i| i as f64).collect(),
            ticks: texts,
            log: false,
            numeric: false,
            at,
        },
    }
}

/// Whether `vals` (finite ones) are all positive and span more than a
/// factor 30: drawn on a log axis or scale.
fn spans_decades(vals: impl Iterator<Item = f64>) -> bool {
    let v: Vec<f64> = vals.filter(|v| v.is_finite()).collect();
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    lo > 0.0 && hi / lo > 30.0
}

/// One axis: the values with their error bars against the axis, the r⁻²
/// law beside a D_eff(r) on log axes, the smallest τ marked.
fn line_panel(ax: &PlanAxis, names: &[String], var: &str, values: &Values) -> Panel {
    let n = ax.pos.len();
    let at = |i: usize| {
        values
            .get(&vec![i])
            .copied()
            .unwrap_or((f64::NAN, f64::NAN))
    };
    let y: Vec<f64> = (0..n).map(|i| at(i).0).collect();
    let e: Vec<f64> = (0..n).map(|i| at(i).1).collect();
    let symbol = symbols::result(var);
    let ylog = spans_decades(y.iter().copied());
    let yaxis = if ylog {
        Axis::log(symbol.clone())
    } else {
        Axis::linear(symbol.clone())
    };
    let mut p = Panel::new("", "", ax.axis(false), yaxis);
    let label = Some(symbol.clone());
    p.series.push(Series::line(
        label.clone(),
        Color::Palette(0),
        Dash::Solid,
        var,
        ax.pos.clone(),
        y.clone(),
    ));
    let err = e
        .iter()
        .map(|e| if e.is_finite() { *e } else { 0.0 })
        .collect();
    p.series.push(Series::points(
        label,
        Color::Palette(0),
        var,
        ax.pos.clone(),
        y.clone(),
        err,
    ));
    let name = var.strip_prefix("result.").unwrap_or(var);
    if names == ["rate"] && name.starts_with("d_eff") && ax.log && ylog {
        r_minus_two(&mut p, &ax.pos, &y);
    }
    if name.starts_with("tau") {
        mark_minimum(&mut p, &ax.pos, &y, &ax.label);
    }
    p
}

/// The r⁻² law of D_eff at large r through the last value, over the
/// last decade of r (grey dashes, labelled).
fn r_minus_two(p: &mut Panel, r: &[f64], d: &[f64]) {
    let Some(k) = (0..r.len()).rev().find(|&k| d[k].is_finite() && d[k] > 0.0) else {
        return;
    };
    let (r1, d1) = (r[k], d[k]);
    let r0 = (r1 / 10.0).max(r[0]);
    let xs: Vec<f64> = (0..=10)
        .map(|i| r0 * (r1 / r0).powf(i as f64 / 10.0))
        .collect();
    let ys = xs.iter().map(|x| d1 * (r1 / x).powi(2)).collect();
    p.series
        .push(Series::line(None, Color::Gray, Dash::Dashed, GUIDE, xs, ys));
    p.notes.push(Note {
        text: "∝ r⁻²".into(),
        x: (r0 * r1).sqrt(),
        y: d1 * (r1 / (r0 * r1).sqrt()).powi(2) * 1.6,
    });
}

/// Mark the smallest value (an optimum of a mean first-passage time).
fn mark_minimum(p: &mut Panel, x: &[f64], y: &[f64], xlabel: &str) {
    let best = (0..y.len())
        .filter(|&i| y[i].is_finite())
        .min_by(|&a, &b| y[a].total_cmp(&y[b]));
    if let Some(i) = best {
        let label = format!(
            "smallest: {} at {xlabel} = {}",
            symbols::number(y[i]),
            symbols::number(x[i])
        );
        p.series.push(Series::points(
            Some(label),
            Color::Palette(3),
            "minimum",
            vec![x[i]],
            vec![y[i]],
            vec![0.0],
        ));
    }
}

/// Heat maps of the first two axes, one per combination of the further
/// ones (at most [`MAX_PANELS`]), on one colour scale.
fn small_multiples(
    fig: &mut Figure,
    axes: &[PlanAxis],
    crossed: &[(Vec<String>, usize)],
    var: &str,
    values: &Values,
) {
    let rest: usize = crossed[2..].iter().map(|g| g.1).product();
    let shown = rest.min(MAX_PANELS);
    let log = spans_decades(values.values().map(|v| v.0));
    let finite = values
        .values()
        .map(|v| v.0)
        .filter(|v| v.is_finite() && (!log || *v > 0.0));
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let range = (lo <= hi).then_some((lo, hi));
    let (ys, xs) = (&axes[0], &axes[1]);
    for m in 0..shown {
        let mut tail = Vec::new();
        let mut k = m;
        for g in crossed[2..].iter().rev() {
            tail.push(k % g.1);
            k /= g.1;
        }
        tail.reverse();
        let cell = |j: usize, i: usize| {
            let mut d = vec![j, i];
            d.extend(&tail);
            values.get(&d).map(|v| v.0).filter(|v| v.is_finite())
        };
        let heat = Heat {
            x_edges: xs.edges(),
            y_edges: ys.edges(),
            values: (0..ys.pos.len())
                .map(|j| (0..xs.pos.len()).map(|i| cell(j, i)).collect())
                .collect(),
            label: symbols::result(var),
            range,
            log,
        };
        let at: Vec<String> = axes[2..]
            .iter()
            .zip(&tail)
            .map(|(a, &t)| a.at[t].clone())
            .collect();
        let mut p = Panel::new("", at.join(", "), xs.axis(true), ys.axis(true));
        p.heat = Some(heat);
        fig.panels.push(p);
    }
    fig.cols = shown.clamp(1, 3);
    if shown < rest {
        fig.title = format!("{} (the first {shown} of {rest} panels)", fig.title);
    }
}
