//! Time-dependent Fokker-Planck: the paper's explicit upwind scheme
//! (conservation, positivity, exact Newtonian <v²>(t), approach to the direct
//! stationary solve) and adaptive TR-BDF2 on the graded mesh (mass at every
//! output time, <v²>(t) of Fig. 1 against a mesh-refined reference, the
//! long-time limit, Newtonian moments against their closed form).

mod common;

use common::models;
use irtp::fp::{
    stationary, transient, ForwardOperator, Mesh, Scheme, StationaryOptions, Transient,
    TransientOptions,
};
use irtp::numerics::trbdf2::{self, Tolerances};

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
            scheme: Scheme::Paper,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(tr.steps > 40_000);
    assert!(tr.mass_error_max < 1e-12, "{}", tr.mass_error_max);
    // CFL: dt = 0.5 / max(outflow + flip + reset rate); the largest drift on
    // an interior edge is just below 2Σ = 6.
    let dv = 2.0 * 3f64.atan() / 2000.0;
    let dt = tr.dt.unwrap();
    assert!(dt <= 0.5 * dv / 5.98, "{dt}");
    assert!(dt * (6.0 / dv + 2.5) >= 0.5, "{dt}");
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
                scheme: Scheme::Paper,
                ..Default::default()
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
            scheme: Scheme::Paper,
            ..Default::default()
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
    let base = TransientOptions {
        scheme: Scheme::Paper,
        ..Default::default()
    };
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

/// TR-BDF2 run with the given cells and tolerances.
fn trbdf2_run(p: &irtp::Params, cells: usize, times: &[f64], rtol: f64, atol: f64) -> Transient {
    transient(
        p,
        &TransientOptions {
            scheme: Scheme::TrBdf2,
            cells,
            t_max: times.iter().copied().fold(0.0, f64::max),
            times: times.to_vec(),
            snapshot_times: vec![],
            rtol,
            atol,
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn trbdf2_conserves_mass_at_every_output_time() {
    // Paper medium (tan, Sigma = 3): cells of width 1e-30 at the edges.
    let p = models::tan(0.5, 2.0);
    let tr = transient(
        &p,
        &TransientOptions {
            cells: 400,
            t_max: 5.0,
            times: (0..=50).map(|k| 0.1 * k as f64).collect(),
            snapshot_times: vec![0.0, 0.05, 0.5, 5.0],
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        (tr.scheme, tr.mesh, tr.dt),
        (Scheme::TrBdf2, Mesh::Graded, None)
    );
    assert!(tr.extrapolated && tr.steps > 0);
    assert_eq!(tr.times.len(), 51);
    for m in &tr.mass {
        assert!((m - 1.0).abs() < 1e-12, "{m}");
    }
    // Over both meshes, recording and snapshot times.
    assert!(tr.mass_error_max < 1e-12, "{}", tr.mass_error_max);
    // Symmetry (v, +) <-> (-v, -) of model and initial condition.
    assert!(tr.v_mean.iter().all(|m| m.abs() < 1e-13));
    assert_eq!(tr.snapshots.len(), 4);
}

/// Fig. 1(b) (tanh, Sigma = 0.6, lambda = 0.5) at the quick figure's times
/// 13 k / 16: the default tolerances (rtol 1e-6, atol 1e-10) on 3200 cells
/// give <v²>(t) to 1e-6 relative (at the default 2000 cells the first time,
/// t = 0.8125, is off by 1.3e-6: the mesh error of the early, sharp front).
///
/// Reference: TR-BDF2 at tight tolerances (rtol 1e-7, atol 1e-11: a time
/// error ~1e-8, measured against rtol 1e-10) on the graded meshes of 400,
/// 800 and 1600 cells, each already Richardson-extrapolated over N/2 and N
/// (error O(N^-2), measured ratio 4-5 per doubling), extrapolated once more:
/// X = (4 X_1600 - X_800) / 3. Its own error is estimated by the same
/// construction one mesh coarser (200, 400, 800): measured 1.4e-7, asserted
/// below 3e-7 here, so the 1e-6 check has margin.
/// t = 0 is left out of the relative check: <v²>(0) = 0, the solver reports
/// the fine mesh's initial cells next to v = 0, O(Δv²) >= 0.
#[test]
fn trbdf2_fig1b_v2_matches_mesh_refined_reference() {
    let p = models::tanh(0.5, 0.5);
    let times: Vec<f64> = (0..=16).map(|k| 13.0 * k as f64 / 16.0).collect();
    let tight = |n| trbdf2_run(&p, n, &times, 1e-7, 1e-11).v2;
    let x: Vec<Vec<f64>> = [200, 400, 800, 1600].into_iter().map(tight).collect();
    let r2 = |a: &[f64], b: &[f64]| -> Vec<f64> {
        a.iter().zip(b).map(|(a, b)| (4.0 * b - a) / 3.0).collect()
    };
    let (reference, coarser) = (r2(&x[2], &x[3]), r2(&x[1], &x[2]));
    let subject = transient(
        &p,
        &TransientOptions {
            cells: 3200,
            t_max: 13.0,
            times: times.clone(),
            ..Default::default()
        },
    )
    .unwrap();
    for k in 1..times.len() {
        let rel = |a: f64| (a / reference[k] - 1.0).abs();
        assert!(
            rel(coarser[k]) < 3e-7,
            "reference at t = {}: {}",
            times[k],
            rel(coarser[k])
        );
        assert!(
            rel(subject.v2[k]) < 1e-6,
            "t = {}: {}",
            times[k],
            rel(subject.v2[k])
        );
    }
    assert!(
        subject.v2[0] >= 0.0 && subject.v2[0] < 1e-6,
        "{}",
        subject.v2[0]
    );
}

#[test]
fn trbdf2_long_time_limit_is_the_stationary_solution_on_the_same_mesh() {
    let p = models::tanh(0.85, 1.0);
    let n = 400;
    let tr = transient(
        &p,
        &TransientOptions {
            cells: n,
            t_max: 40.0,
            times: vec![40.0],
            snapshot_times: vec![40.0],
            ..Default::default()
        },
    )
    .unwrap();
    let st = stationary(
        &p,
        &StationaryOptions {
            cells: n,
            mesh: Mesh::Graded,
            extrapolate: true,
        },
    )
    .unwrap();
    // Same meshes (400 and 200 graded cells), same extrapolation; the fixed
    // point of a TR-BDF2 step is the discrete stationary state, so the two
    // agree up to the remaining e^{-t} transient.
    assert_eq!(tr.v, st.v);
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

/// Newtonian moments with reset to v_r, from v(0) = v0 = v_r, η = ±Σ equally
/// likely. With g(v) = v, dv = (η - v) dt, η -> -η at rate λ, v -> v_r at rate
/// r (η kept):
///   d<η>/dt = -2λ <η>               => <η> = 0,
///   d<v>/dt = -<v> + <η> + r (v_r - <v>)
///           => <v> = v_r [r + e^{-(1+r)t}] / (1 + r)   (v0 = v_r),
///   d<vη>/dt = Σ² - <vη> - 2λ <vη> + r (v_r <η> - <vη>) = Σ² - c <vη>,
///           c = 1 + 2λ + r, <vη>(0) = 0 => <vη> = Σ²/c (1 - e^{-ct}),
///   d<v²>/dt = 2<vη> - 2<v²> + r (v_r² - <v²>) = 2<vη> - k <v²> + r v_r², k = 2 + r
///           => <v²> = v0² e^{-kt} + r v_r² (1 - e^{-kt})/k
///                     + 2Σ²/c [(1 - e^{-kt})/k - (e^{-ct} - e^{-kt})/(k - c)].
/// The discrete chain starts with ½ in each cell next to the node v_r (the
/// reset target cells) and is integrated by TR-BDF2 at rtol 1e-7, atol 1e-11
/// (time error ~1e-8, far below the mesh error). Upwind is first order in Δv with a smooth error on the nested
/// meshes, so X = 2 X_N - X_{N/2} is second order: the test asserts the
/// <v²> error ratio of N = 400 to N = 800 (extrapolated) is near 4 (second
/// order, the mesh order) and its error at 800 cells, measured 9.7e-6
/// (relative), within 2x. <v> shows no mesh error (measured 5e-10 and 3e-10
/// relative to v_r at 400 and 800 cells: the O(Δv) drift errors of the two
/// states cancel at M+ = M- = ½), so it is held to the time-integration
/// level, 1e-8.
#[test]
fn trbdf2_newtonian_moments_match_closed_form_at_second_order() {
    let (s, l, r, vr) = (1.0, 1.0, 0.5, 0.3);
    let p = models::linear(s, l, r, vr);
    let (c, k) = (1.0 + 2.0 * l + r, 2.0 + r);
    let mean = |t: f64| vr * (r + (-(1.0 + r) * t).exp()) / (1.0 + r);
    let v2 = |t: f64| {
        let ek = (-k * t).exp();
        vr * vr * ek
            + r * vr * vr * (1.0 - ek) / k
            + 2.0 * s * s / c * ((1.0 - ek) / k - ((-c * t).exp() - ek) / (k - c))
    };
    let times = [0.25, 0.5, 1.0, 2.0, 4.0];
    let tol = Tolerances {
        rtol: 1e-7,
        atol: 1e-11,
        ..Default::default()
    };
    let moments = |cells: usize, refine: usize| {
        let mut op = ForwardOperator::refined(&p, Mesh::Graded, cells, refine).unwrap();
        let mut u = op.point_mass(vr);
        let mut out = Vec::new();
        let probe = op.clone();
        trbdf2::integrate(&mut op, &mut u, &times, &tol, |_, _, u| {
            let m = probe.moments(u);
            assert!((m[0] - 1.0).abs() < 1e-12, "mass {}", m[0]);
            out.push(m);
            Ok(())
        })
        .unwrap();
        out
    };
    let extrapolated = |n: usize| -> Vec<[f64; 3]> {
        let (a, b) = (moments(n / 2, 0), moments(n / 2, 1));
        a.iter()
            .zip(&b)
            .map(|(a, b)| [0, 1, 2].map(|i| 2.0 * b[i] - a[i]))
            .collect()
    };
    let errors = |m: &[[f64; 3]]| {
        let mut e = [0.0f64; 2];
        for (x, &t) in m.iter().zip(&times) {
            e[0] = e[0].max((x[1] - mean(t)).abs() / vr);
            e[1] = e[1].max((x[2] / v2(t) - 1.0).abs());
        }
        e
    };
    let (e1, e2) = (errors(&extrapolated(400)), errors(&extrapolated(800)));
    let ratio = e1[1] / e2[1];
    assert!(
        ratio > 3.0 && ratio < 5.5,
        "second order expected: {e1:?} {e2:?}"
    );
    assert!(e2[1] < 2e-5, "{e2:?}");
    assert!(e1[0] < 1e-8 && e2[0] < 1e-8, "{e1:?} {e2:?}");
}
