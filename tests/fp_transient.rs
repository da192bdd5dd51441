//! Explicit upwind time stepping (the paper's way): conservation, positivity,
//! exact Newtonian <v²>(t), and approach to the direct stationary solve.

mod common;

use common::models;
use irtp::fp::{stationary, transient, Mesh, StationaryOptions, TransientOptions};

#[test]
fn mass_conserved_every_step_and_density_nonnegative_at_paper_resolution() {
    // Paper Sec. 3: tan, Sigma = 3, 2000 cells; here t_max = 5 to stay fast.
    let p = models::tan(0.5, 2.0);
    let tr = transient(
        &p,
        &TransientOptions {
            cells: 2000,
            t_max: 5.0,
            times: (0..=50).map(|k| 0.1 * k as f64).collect(),
            snapshot_times: vec![0.0, 0.5, 5.0],
            cfl: 0.5,
        },
    )
    .unwrap();
    assert!(tr.steps > 40_000);
    assert!(tr.mass_error_max < 1e-12, "{}", tr.mass_error_max);
    // CFL: dt = 0.5 / max(outflow + flip + reset rate); the largest drift on
    // an interior edge is just below 2Σ = 6.
    let dv = 2.0 * 3f64.atan() / 2000.0;
    assert!(tr.dt <= 0.5 * dv / 5.98, "{}", tr.dt);
    assert!(tr.dt * (6.0 / dv + 2.5) >= 0.5, "{}", tr.dt);
    assert_eq!(tr.times.len(), 51);
    // Initial mass sits in the two cells next to v = 0 (centres ±Δv/2).
    assert!((tr.v2[0] - 0.25 * dv * dv).abs() < 1e-18);
    for s in &tr.snapshots {
        assert!(s.p_plus.iter().chain(&s.p_minus).all(|&x| x >= 0.0));
    }
    // Symmetry (v, +) <-> (-v, -) of model and initial condition.
    assert!(tr.v_mean.iter().all(|m| m.abs() < 1e-13));
}

/// Linear drag, v_r = 0, symmetric start at v = 0: with c = 1 + 2λ + r, k = 2 + r,
/// <vη>(t) = Σ²/c (1 - e^{-ct}) and <v²>' = 2<vη> - k<v²>, so
/// <v²>(t) = 2Σ²/c [(1 - e^{-kt})/k - (e^{-ct} - e^{-kt})/(k - c)].
#[test]
fn newtonian_v2_of_t_converges_at_first_order() {
    let (s, l, r) = (1.0, 1.0, 0.5);
    let p = models::linear(s, l, r, 0.0);
    let (c, k) = (1.0 + 2.0 * l + r, 2.0 + r);
    let exact = |t: f64| {
        2.0 * s * s / c * ((1.0 - (-k * t).exp()) / k - ((-c * t).exp() - (-k * t).exp()) / (k - c))
    };
    let times = vec![0.5, 1.0, 2.0, 4.0];
    let run = |n: usize| {
        transient(
            &p,
            &TransientOptions {
                cells: n,
                t_max: 4.0,
                times: times.clone(),
                snapshot_times: vec![],
                cfl: 0.9,
            },
        )
        .unwrap()
        .v2
    };
    let (a, b) = (run(400), run(800));
    let err = |v: &[f64]| {
        times
            .iter()
            .zip(v)
            .map(|(&t, &x)| (x - exact(t)).abs() / exact(t))
            .fold(0.0, f64::max)
    };
    let (e1, e2) = (err(&a), err(&b));
    let ratio = e1 / e2;
    assert!(
        ratio > 1.9 && ratio < 2.1,
        "first order expected: {e1} {e2}"
    );
    assert!(e2 < 1e-2, "{e2}");
    // The O(Δv) error is clean, so Richardson removes it.
    let ex: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 2.0 * y - x).collect();
    assert!(err(&ex) < 2e-4, "{}", err(&ex));
}

#[test]
fn long_time_limit_is_the_direct_stationary_solution() {
    let p = models::tanh(0.85, 1.0);
    let n = 500;
    let tr = transient(
        &p,
        &TransientOptions {
            cells: n,
            t_max: 40.0,
            times: vec![40.0],
            snapshot_times: vec![40.0],
            cfl: 0.9,
        },
    )
    .unwrap();
    let st = stationary(
        &p,
        &StationaryOptions {
            cells: n,
            mesh: Mesh::Uniform,
            extrapolate: false,
        },
    )
    .unwrap();
    // The fixed point of the explicit step is exactly the discrete stationary
    // state, so at equal N the two agree up to the remaining e^{-t} transient.
    assert!(
        (tr.v2[0] / st.v2 - 1.0).abs() < 1e-9,
        "{} {}",
        tr.v2[0],
        st.v2
    );
    let snap = &tr.snapshots[0].p;
    let dmax = snap
        .iter()
        .zip(&st.p)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        dmax < 1e-8 * st.p.iter().cloned().fold(0.0, f64::max),
        "{dmax}"
    );
}

#[test]
fn bad_options_are_rejected() {
    let p = models::tan(1.0, 1.0);
    let base = TransientOptions::default();
    let cases: Vec<(TransientOptions, &str)> = vec![
        (
            TransientOptions {
                cells: 3,
                ..base.clone()
            },
            "cells",
        ),
        (
            TransientOptions {
                t_max: 0.0,
                ..base.clone()
            },
            "t_max",
        ),
        (
            TransientOptions {
                t_max: f64::NAN,
                ..base.clone()
            },
            "t_max",
        ),
        (
            TransientOptions {
                cfl: 1.5,
                ..base.clone()
            },
            "cfl",
        ),
        (
            TransientOptions {
                times: vec![11.0],
                ..base.clone()
            },
            "times",
        ),
        (
            TransientOptions {
                snapshot_times: vec![-1.0],
                ..base.clone()
            },
            "snapshot_times",
        ),
    ];
    for (o, name) in cases {
        let e = transient(&p, &o).unwrap_err();
        assert!(
            e.to_string().starts_with(&format!("invalid {name} = ")),
            "{e}"
        );
        assert!(e.is_input_error());
    }
}
