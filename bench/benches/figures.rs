//! Rendering cost of the plotting layer: a Fig. 2-sized figure (4 panels,
//! 5 FP lines of 1200 points and 5 point series of 80 points with error
//! bars per panel) to PNG and SVG, and its CSV. Target: well under a second
//! per figure, so plotting is negligible next to the computations of
//! `irtp reproduce`.

use criterion::{criterion_group, criterion_main, Criterion};
use irtp_paper::plot::{Axis, Color, Dash, Figure, Panel, Series};

fn synthetic() -> Figure {
    let mut f = Figure::new("bench", "synthetic P_s(v)", 2);
    for k in 0..4 {
        let mut p = Panel::new(
            format!("({})", ["a", "b", "c", "d"][k]),
            format!("λ = {k}"),
            Axis::linear("v"),
            Axis::linear("P_s(v)").range(0.0, 6.0),
        );
        for c in 0..5 {
            let a = 1.0 + c as f64;
            let v: Vec<f64> = (0..1200).map(|i| -1.2 + 2.4 * i as f64 / 1199.0).collect();
            let y: Vec<f64> = v.iter().map(|v| a * (-a * v.abs()).exp()).collect();
            p.series.push(Series::line(
                Some(format!("r = {c}")),
                Color::Palette(c),
                Dash::Solid,
                "fp",
                v.clone(),
                y.clone(),
            ));
            let idx: Vec<usize> = (0..80).map(|i| i * 15).collect();
            p.series.push(Series::points(
                Some(format!("r = {c}")),
                Color::Palette(c),
                "simulation",
                idx.iter().map(|&i| v[i]).collect(),
                idx.iter().map(|&i| y[i]).collect(),
                idx.iter().map(|&i| 0.02 * y[i]).collect(),
            ));
        }
        f.panels.push(p);
    }
    f
}

fn render(c: &mut Criterion) {
    let f = synthetic();
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("f.png");
    let svg = dir.path().join("f.svg");
    let mut g = c.benchmark_group("figures");
    g.sample_size(10);
    g.bench_function("render_png_fig2_size", |b| {
        b.iter(|| f.render_png(&png).unwrap())
    });
    g.bench_function("render_svg_fig2_size", |b| {
        b.iter(|| f.render_svg(&svg).unwrap())
    });
    g.bench_function("data_csv_fig2_size", |b| b.iter(|| f.data_csv().unwrap()));
    g.finish();
}

criterion_group!(benches, render);
criterion_main!(benches);
