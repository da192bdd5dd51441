//! Rendering (`irtp_paper::plot`, feature `plot`): a demo figure to PNG and SVG.

use irtp_paper::plot::{Axis, Color, Dash, Figure, Note, Panel, Series};

/// Demo figure: all axis combinations, lines, points with error bars, guides.
fn demo() -> Figure {
    let mut f = Figure::new("demo", "Demo figure: λ = 0.5, Σ = 3", 2);
    let t: Vec<f64> = (0..60)
        .map(|i| 10f64.powf(-2.0 + 5.0 * i as f64 / 59.0))
        .collect();
    let mut a = Panel::new("(a)", "log-log", Axis::log("t"), Axis::log("⟨x²⟩"));
    for (k, d) in [1.0, 0.3, 0.05].iter().enumerate() {
        let y: Vec<f64> = t.iter().map(|t| t * t / (1.0 + t / d)).collect();
        let e: Vec<f64> = y.iter().map(|y| 0.1 * y).collect();
        a.series.push(Series::points(
            Some(format!("r = {k}")),
            Color::Palette(k),
            "simulation",
            t.iter().step_by(4).copied().collect(),
            y.iter().step_by(4).copied().collect(),
            e.iter().step_by(4).copied().collect(),
        ));
        a.series.push(Series::line(
            Some(format!("r = {k}")),
            Color::Palette(k),
            Dash::Solid,
            "fp",
            t.clone(),
            y,
        ));
    }
    a.series.push(Series::line(
        None,
        Color::Gray,
        Dash::Dotted,
        "guide",
        vec![0.01, 1.0],
        vec![1e-4, 1.0],
    ));
    a.notes.push(Note {
        text: "t²".into(),
        x: 0.05,
        y: 0.01,
    });
    a.legend_title = Some("reset rate".into());
    f.panels.push(a);
    let v: Vec<f64> = (0..200).map(|i| -1.2 + 2.4 * i as f64 / 199.0).collect();
    let mut b = Panel::new(
        "(b)",
        "linear",
        Axis::linear("v"),
        Axis::linear("P(v)").range(0.0, 2.0),
    );
    b.series.push(Series::line(
        Some("r = 0".into()),
        Color::Black,
        Dash::Solid,
        "analytic",
        v.clone(),
        v.iter().map(|v| 0.3 / (1.25 - v.abs()).sqrt()).collect(),
    ));
    b.series.push(Series::line(
        Some("r = 5".into()),
        Color::Palette(1),
        Dash::Dashed,
        "fp",
        v.clone(),
        v.iter().map(|v| (-3.0 * v.abs()).exp() * 1.4).collect(),
    ));
    f.panels.push(b);
    f
}

#[test]
fn renders_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let f = demo();
    let png = dir.path().join("demo.png");
    let svg = dir.path().join("demo.svg");
    f.render_png(&png).unwrap();
    f.render_svg(&svg).unwrap();
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(s.contains("<svg") && s.contains("r = 0"));
    let csv = f.data_csv().unwrap();
    assert!(csv.starts_with("panel,series,source,style,x,y,y_err\n"));
    if let Ok(d) = std::env::var("IRTP_PLOT_DEMO_DIR") {
        f.render_png(&std::path::Path::new(&d).join("demo.png"))
            .unwrap();
    }
}
