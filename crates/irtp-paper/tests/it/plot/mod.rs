//! The figure layer (`irtp_paper::plot`): clipping, ticks and their labels,
//! legends and vertical ranges.

use irtp_paper::plot::{
    choose_place, clip_polyline, count_range, fit_y, fmt_count, legend_entries, log_ticks,
    nice_ticks, plain_text, rich_segments, split_sharp, tick_labels, Axis, Color, Dash, Key, Panel,
    Place, Series,
};

mod heatmap;
// As in the library: drawing needs the feature.
#[cfg(feature = "plot")]
mod render;

#[test]
fn clipping_keeps_inside_and_cuts_crossings() {
    let pts = [(0.0, 0.0), (2.0, 2.0), (4.0, 0.0)];
    let out = clip_polyline(&pts, (0.0, 4.0), (0.0, 1.0));
    assert_eq!(out.len(), 2);
    assert_eq!(out[0], vec![(0.0, 0.0), (1.0, 1.0)]);
    assert_eq!(out[1], vec![(3.0, 1.0), (4.0, 0.0)]);
    let all = clip_polyline(&pts, (-1.0, 5.0), (-1.0, 3.0));
    assert_eq!(all, vec![pts.to_vec()]);
}

#[test]
fn sharp_turns_split() {
    let pts = vec![(0.0, 0.0), (1.0, 10.0), (1.01, 0.0), (2.0, 0.0)];
    let px: Vec<(f64, f64)> = pts.iter().map(|p| (p.0 * 100.0, -p.1 * 10.0)).collect();
    let out = split_sharp(pts.clone(), &px);
    assert_eq!(out.len(), 2);
    assert_eq!(out[0], pts[..2].to_vec());
    assert_eq!(out[1], pts[1..].to_vec());
}

#[test]
fn ticks_are_nice() {
    assert_eq!(
        nice_ticks(0.0, 1.0, 5),
        vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
    );
    let (maj, _) = log_ticks(-2.1, 1.2);
    assert_eq!(maj, vec![-2.0, -1.0, 0.0, 1.0]);
}

#[test]
fn tick_labels_of_one_axis_share_one_format() {
    let lin = Axis::linear("x");
    let t = [0.0, 0.25, 0.5, 0.75, 1.0, 1.25];
    assert_eq!(
        tick_labels(&lin, &t, 0.25),
        ["0.00", "0.25", "0.50", "0.75", "1.00", "1.25"]
    );
    let t = nice_ticks(-1.2, 1.2, 6);
    assert_eq!(
        tick_labels(&lin, &t, 0.5),
        ["-1.0", "-0.5", "0.0", "0.5", "1.0"]
    );
    assert_eq!(tick_labels(&lin, &[0.0, 5.0, 10.0], 5.0), ["0", "5", "10"]);
    assert_eq!(
        tick_labels(&lin, &[0.0, 1e5, 2e5], 1e5),
        ["0", "1.0×10⁵", "2.0×10⁵"]
    );
    let log = Axis::log("y");
    assert_eq!(
        tick_labels(&log, &[-2.0, -1.0, 0.0, 1.0, 4.0], 1.0),
        ["10⁻²", "10⁻¹", "10⁰", "10¹", "10⁴"]
    );
    let (maj, _) = log_ticks(-0.8, 0.5);
    assert_eq!(tick_labels(&log, &maj, 1.0), ["0.2", "0.5", "1.0", "2.0"]);
    assert_eq!(
        tick_labels(&log, &[-4.0, 2f64.log10() - 4.0], 1.0),
        ["1×10⁻⁴", "2×10⁻⁴"]
    );
}

#[test]
fn subscript_markup() {
    assert_eq!(
        rich_segments("D_{eff}(r), τ_{r}"),
        [
            ("D".to_string(), false),
            ("eff".to_string(), true),
            ("(r), τ".to_string(), false),
            ("r".to_string(), true)
        ]
    );
    assert_eq!(plain_text("P_{s}(v)"), "Ps(v)");
    assert_eq!(fmt_count(1_000_000), "1\u{2009}000\u{2009}000");
    assert_eq!(fmt_count(200), "200");
    assert_eq!(count_range([2000, 1000, 1500]), "1\u{2009}000–2\u{2009}000");
    assert_eq!(count_range([4000, 4000]), "4\u{2009}000");
    assert_eq!(plain_text("a_b {c}"), "a_b {c}");
}

#[test]
fn key_entries_follow_series_entries() {
    let mut p = Panel::new("(a)", "", Axis::linear("x"), Axis::linear("y"));
    p.legend_title = Some("r =".into());
    p.series.push(Series::line(
        Some("1".into()),
        Color::Palette(0),
        Dash::Solid,
        "fp",
        vec![0.0, 1.0],
        vec![0.0, 1.0],
    ));
    p.key.push(Key::points("exact sampler"));
    p.key
        .push(Key::line("D_{eff}, FP", Color::Gray, Dash::Solid));
    assert_eq!(p.legend_lines(), ["r =", "1", "exact sampler", "Deff, FP"]);
}

#[test]
fn legend_merges_points_and_line_of_same_parameter() {
    let mut p = Panel::new("(a)", "", Axis::linear("x"), Axis::linear("y"));
    p.series.push(Series::points(
        Some("r = 1".into()),
        Color::Palette(0),
        "simulation",
        vec![0.0],
        vec![0.0],
        vec![0.1],
    ));
    p.series.push(Series::line(
        Some("r = 1".into()),
        Color::Palette(0),
        Dash::Solid,
        "fp",
        vec![0.0, 1.0],
        vec![0.0, 1.0],
    ));
    let e = legend_entries(&p);
    assert_eq!(e.len(), 1);
    assert!(e[0].marker && e[0].dash == Some(Dash::Solid));
}

#[test]
fn outlying_groups_do_not_set_the_range() {
    // τ(r) on a sparse grid running away to 10⁷⁹: the minimum stays visible.
    let mut p = Panel::new("", "", Axis::log("r"), Axis::linear("τ"));
    let r = vec![1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0, 1000.0];
    let tau = vec![1.86, 1.86, 1.85, 1.77, 2.24, 1.98e6, 6.66e79];
    p.series.push(Series::line(
        None,
        Color::Palette(0),
        Dash::Solid,
        "tau",
        r,
        tau,
    ));
    let ((lo, hi), clipped) = fit_y(&p);
    assert!(clipped && lo < 1.77 && hi > 2.24 && hi < 3.0, "{lo} {hi}");
    // A flat line with one step is no outlier.
    let mut q = Panel::new("", "", Axis::linear("t"), Axis::linear("S"));
    let t: Vec<f64> = (0..10).map(f64::from).collect();
    let s = vec![1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.5];
    q.series.push(Series::line(
        None,
        Color::Palette(0),
        Dash::Solid,
        "s",
        t,
        s,
    ));
    let ((_, hi), clipped) = fit_y(&q);
    assert!(!clipped && hi > 1.5, "{hi}");
}

#[test]
fn legend_avoids_data() {
    // Data filling the upper right: the legend must go elsewhere.
    let pts: Vec<(f64, f64)> = (0..100)
        .map(|i| (0.6 + 0.004 * i as f64, 0.05 + 0.003 * i as f64))
        .collect();
    match choose_place(&pts, 0.3, 0.3) {
        Place::Inside(x, y) => assert!(!(x > 0.5 && y < 0.2), "{x} {y}"),
        Place::Outside => panic!("free corners exist"),
    }
}
