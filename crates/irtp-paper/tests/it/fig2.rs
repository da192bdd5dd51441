//! Figure 2 (`irtp_paper::fig2`): bin averages, decimation and the slope jump at v = 0.

use irtp::analytic::cusp::{one_sided_slopes, slope_jump};
use irtp::model::{DragLaw, Params};
use irtp_paper::compute;
use irtp_paper::fig2::{bin_average, decimate};

#[test]
fn bin_average_of_cells() {
    let edges = [0.0, 1.0, 3.0];
    let p = [1.0, 4.0];
    assert!((bin_average(&edges, &p, 0.5, 2.0) - (0.5 + 4.0) / 1.5).abs() < 1e-15);
    let d = decimate(&[-1.0, -0.5, -0.01, 0.02, 0.5, 1.0], 2);
    assert_eq!(d, vec![0, 2, 5]);
}

/// The exact slope jump at v = 0 is what the FP solver produces.
#[test]
fn fp_reproduces_slope_jump() {
    for (d, s, l, r) in [
        (DragLaw::Tan, 3.0, 0.9, 1.0),
        (DragLaw::Tanh, 0.6, 3.0, 5.0),
    ] {
        let p = Params::new(d.clone(), s, l, r, 0.0).unwrap();
        let fp = compute::fp_stationary(&p, 20_000).unwrap();
        let sc = s / (l + r);
        let (a, b) = one_sided_slopes(&fp.v, &fp.p, 1e-3 * sc, 0.02 * sc);
        let e = slope_jump(&p);
        assert!(
            ((b - a) - e).abs() < 2e-3 * e.abs(),
            "{d}: {} vs {e}",
            b - a
        );
    }
}
