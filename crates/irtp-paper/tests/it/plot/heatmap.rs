//! Heat maps (`irtp_paper::plot::heatmap`): colours, ranges and cell edges.

use irtp_paper::plot::heatmap::{edges, log_spaced, viridis, Heat};

#[test]
fn viridis_ends_and_clamps() {
    assert_eq!(viridis(0.0), (68, 1, 84));
    assert_eq!(viridis(1.0), (253, 231, 37));
    assert_eq!(viridis(-3.0), viridis(0.0));
    assert_eq!(viridis(7.0), viridis(1.0));
    assert_eq!(viridis(0.5), (33, 145, 140));
}

#[test]
fn range_skips_missing_and_non_finite_cells() {
    let mut h = Heat {
        x_edges: vec![0.0, 1.0, 2.0],
        y_edges: vec![0.0, 1.0, 2.0],
        label: "v".into(),
        values: vec![vec![Some(2.0), None], vec![Some(f64::NAN), Some(4.0)]],
        range: None,
        log: false,
    };
    assert_eq!(h.value_range(), Some((2.0, 4.0)));
    assert_eq!(h.level(3.0), 0.5);
    h.log = true;
    h.values[0][1] = Some(8.0);
    assert!((h.level(4.0) - 0.5).abs() < 1e-12);
}

#[test]
fn edges_are_geometric_on_log_axes() {
    let e = edges(&[0.1, 1.0, 10.0], true);
    let want = [
        10f64.powf(-1.5),
        10f64.powf(-0.5),
        10f64.powf(0.5),
        10f64.powf(1.5),
    ];
    for (a, b) in e.iter().zip(want) {
        assert!((a / b - 1.0).abs() < 1e-12, "{e:?}");
    }
    assert_eq!(edges(&[1.0, 2.0, 3.0], false), [0.5, 1.5, 2.5, 3.5]);
    assert!(log_spaced(&[0.1, 0.316, 1.0, 3.16, 10.0]));
    assert!(!log_spaced(&[1.0, 2.0, 3.0]));
    assert!(!log_spaced(&[0.0, 1.0, 2.0]));
    assert!(log_spaced(&[0.5, 1.0, 5.0, 50.0]));
}
