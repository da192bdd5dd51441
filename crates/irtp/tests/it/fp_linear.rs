//! Stationary FP solver against the exact Newtonian (g = v) results of
//! `analytic::linear`, for r >= 0 and v_r != 0, including the singular
//! r = 0 edge (P ∝ (Σ² - v²)^(λ-1), λ < 1).

use crate::common::models;
use irtp::analytic::linear;
use irtp::fp::{stationary, Mesh, StationaryOptions};
use irtp::{DragLaw, Params};

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

#[test]
fn moments_and_d_eff_match_closed_forms_to_1e6() {
    for (s, l, r, vr) in models::LINEAR_CASES {
        let p = models::linear(s, l, r, vr);
        let st = stationary(&p, &StationaryOptions::default()).unwrap();
        let (v1, v2, d) = (
            linear::v_mean(&p).unwrap(),
            linear::v2(&p).unwrap(),
            linear::d_eff(&p).unwrap(),
        );
        let tag = format!("s={s} l={l} r={r} vr={vr}");
        assert!(rel(st.v2, v2) < 1e-6, "{tag}: v2 {} vs {v2}", st.v2);
        assert!(rel(st.d_eff, d) < 1e-6, "{tag}: D {} vs {d}", st.d_eff);
        if vr == 0.0 {
            assert!(st.v_mean.abs() < 1e-12, "{tag}: <v> = {}", st.v_mean);
        } else {
            assert!(
                rel(st.v_mean, v1) < 1e-6,
                "{tag}: <v> {} vs {v1}",
                st.v_mean
            );
        }
    }
}

#[test]
fn density_is_normalised_and_nonnegative() {
    for (s, l, r, vr) in models::LINEAR_CASES {
        let p = models::linear(s, l, r, vr);
        for mesh in [Mesh::Graded, Mesh::Uniform] {
            let st = stationary(
                &p,
                &StationaryOptions {
                    cells: 2000,
                    mesh,
                    extrapolate: false,
                },
            )
            .unwrap();
            assert!((st.mass - 1.0).abs() < 1e-12);
            let m: f64 = st.cell_masses().iter().sum();
            assert!((m - 1.0).abs() < 1e-12, "{m}");
            assert!(st.p_plus.iter().chain(&st.p_minus).all(|&x| x >= 0.0));
            assert_eq!(st.v.len(), 2000);
            assert_eq!(st.edges.len(), 2001);
        }
    }
}

/// Errors of the raw (fine-mesh) values fall like N^-1 and the extrapolated
/// ones like N^-2: measured log-log slopes over N = 2000..32000.
#[test]
fn first_order_raw_second_order_extrapolated_for_d_eff() {
    let p = models::linear(1.0, 0.3, 0.0, 0.0);
    let exact = linear::d_eff(&p).unwrap();
    let ns = [2000usize, 4000, 8000, 16000, 32000];
    let (mut raw, mut ex) = (Vec::new(), Vec::new());
    for &n in &ns {
        let st = stationary(
            &p,
            &StationaryOptions {
                cells: n,
                mesh: Mesh::Graded,
                extrapolate: true,
            },
        )
        .unwrap();
        raw.push(rel(st.fine.d_eff, exact));
        ex.push(rel(st.d_eff, exact));
    }
    let slope = |e: &[f64]| {
        let k = e.len() - 1;
        (e[k] / e[0]).ln() / ((ns[k] as f64) / (ns[0] as f64)).ln()
    };
    let (sr, se) = (slope(&raw), slope(&ex));
    assert!((sr + 1.0).abs() < 0.05, "raw slope {sr}: {raw:?}");
    assert!(se < -1.9, "extrapolated slope {se}: {ex:?}");
    // Monotone decrease, no erratic jumps.
    assert!(raw.windows(2).all(|w| w[1] < 0.6 * w[0]), "{raw:?}");
    assert!(ex.windows(2).all(|w| w[1] < 0.35 * w[0]), "{ex:?}");
}

#[test]
fn lambda_zero_with_reset_has_infinite_d_eff_and_zero_lambda_without_reset_is_rejected() {
    let p = models::linear(1.0, 0.0, 1.0, 0.0);
    let st = stationary(&p, &StationaryOptions::default()).unwrap();
    assert!(st.d_eff.is_infinite());
    // Each state relaxes to ±Σ at rate 1 and is reset to 0 at rate r:
    // <v²> = Σ² * 2/((1+r)(2+r)) = 1/3 for r = 1.
    assert!(rel(st.v2, 1.0 / 3.0) < 1e-6, "{}", st.v2);
    let p0 = models::linear(1.0, 0.0, 0.0, 0.0);
    assert!(stationary(&p0, &StationaryOptions::default()).is_err());
}

#[test]
fn bad_options_are_rejected() {
    let p = models::tan(1.0, 1.0);
    for (cells, extrapolate) in [(0, false), (15, false), (101, true)] {
        let e = stationary(
            &p,
            &StationaryOptions {
                cells,
                mesh: Mesh::Graded,
                extrapolate,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("invalid cells = "), "{e}");
    }
}

/// Paper Fig. 6: D_eff ~ r^-2 at large r for any drag. Near v_r = 0 every g
/// has g'(0) = 1, so the prefactor is the Newtonian one: D_eff r² → Σ²/(2λ),
/// with O(1/r) corrections.
#[test]
fn d_eff_large_r_law() {
    for (drag, sigma, lambda) in [(DragLaw::Tan, 3.0, 0.5), (DragLaw::Tanh, 0.6, 0.5)] {
        let ratio = |r: f64| {
            let p = Params::new(drag.clone(), sigma, lambda, r, 0.0).unwrap();
            let d = stationary(&p, &StationaryOptions::default()).unwrap().d_eff;
            d * 2.0 * lambda * r * r / (sigma * sigma)
        };
        let (a, b) = (ratio(1000.0), ratio(2000.0));
        assert!((b - 1.0).abs() < 2e-3, "{drag}: {a} {b}");
        let q = (b - 1.0) / (a - 1.0);
        assert!(
            q > 0.4 && q < 0.6,
            "{drag}: O(1/r) approach expected: {a} {b}"
        );
    }
}

/// The paper's noise: the error estimate of D_eff bounds its distance to
/// the closed form (Eq. (R3)) in every linear case, at several meshes, the
/// singular edges (λ < 1, r < 1) and v_r != 0 included, and shrinks with
/// the mesh.
#[test]
fn d_eff_error_estimate_bounds_the_distance_to_the_closed_form() {
    for (s, l, r, vr) in models::LINEAR_CASES {
        let p = models::linear(s, l, r, vr);
        let exact = linear::d_eff(&p).unwrap();
        let mut last = f64::INFINITY;
        for cells in [400, 2000, 20_000] {
            for mesh in [Mesh::Graded, Mesh::Uniform] {
                let o = StationaryOptions {
                    cells,
                    mesh,
                    extrapolate: true,
                };
                let st = stationary(&p, &o).unwrap();
                let est = st.d_eff_err.unwrap();
                let err = (st.d_eff - exact).abs();
                let tag = format!("s={s} l={l} r={r} vr={vr} {cells} {mesh:?}");
                println!("{tag}: error {err:.2e}, estimate {est:.2e}");
                assert!(
                    err <= est,
                    "{tag}: |{} - {exact}| = {err:e} > {est:e}",
                    st.d_eff
                );
                if mesh == Mesh::Graded {
                    assert!(est < last, "{tag}: estimate {est:e} after {last:e}");
                    last = est;
                }
            }
        }
    }
}

#[test]
fn d_eff_error_needs_three_meshes() {
    let p = models::linear(1.0, 0.3, 2.0, 0.0);
    let o = |cells, extrapolate| StationaryOptions {
        cells,
        mesh: Mesh::Graded,
        extrapolate,
    };
    assert!(stationary(&p, &o(2000, false)).unwrap().d_eff_err.is_none());
    assert!(stationary(&p, &o(16, true)).unwrap().d_eff_err.is_none());
    assert!(stationary(&p, &o(32, true)).unwrap().d_eff_err.is_some());
}
