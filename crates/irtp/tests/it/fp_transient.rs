//! Time-dependent Fokker-Planck: the paper's explicit upwind scheme
//! (conservation, positivity, exact Newtonian <v²>(t), approach to the direct
//! stationary solve) and adaptive TR-BDF2 on the graded mesh (mass at every
//! output time, <v²>(t) of Fig. 1 against a spectral backward-equation
//! reference, the
//! long-time limit, Newtonian moments against their closed form).

use crate::common;
use crate::common::models;
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
#[ignore = "slow tier"]
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
#[ignore = "slow tier"]
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

/// One curve of Fig. 1: <v²>(t) at `samples` + 1 equally spaced times in
/// [0, t_max] from the default TR-BDF2 run on `cells` cells (rtol `rtol`),
/// against the backward-equation spectral reference ([`common::spectral`]:
/// analytic solution, Chebyshev collocation, exact exponential in time).
///
/// The reference is checked converged first (48 against 64 nodes, measured
/// agreement ~1e-11, asserted 1e-9). The forward solution must then be within
/// 1e-6 relative at every t > 0, and its largest reported mesh error
/// estimate must cover its largest actual error (plus the time integration's
/// share, 1e-8; measured 4e-9 at rtol 1e-5 against 1e-8 for tanh r = 0).
/// Pointwise the estimate can fall below the error where the leading
/// 1/N² coefficient changes sign in time (tanh r = 0, t = 8.9: error 9.2e-8,
/// estimate 6.5e-8), so the check is on the maxima over t.
/// t = 0 is left out of the relative check: <v²>(0) = 0, the solver reports
/// the fine mesh's initial cells next to v = 0, O(Δv²) >= 0.
#[allow(clippy::too_many_arguments)]
fn fig1_curve_within_1e6(
    p: &irtp::Params,
    g: &dyn Fn(f64) -> f64,
    v_u: f64,
    t_max: f64,
    samples: usize,
    cells: usize,
    rtol: f64,
) -> f64 {
    let dt = t_max / samples as f64;
    let (s, l, r) = (p.sigma(), p.lambda(), p.rate());
    let reference =
        |nodes| common::spectral::v2_of_t(g, v_u, s, l, r, 0.0, 0.0, nodes, dt, samples);
    let (x, y) = (reference(64), reference(48));
    for k in 1..=samples {
        assert!(
            (y[k] / x[k] - 1.0).abs() < 1e-9,
            "reference at t = {}",
            k as f64 * dt
        );
    }
    let times: Vec<f64> = (0..=samples).map(|k| k as f64 * dt).collect();
    let subject = trbdf2_run(p, cells, &times, rtol, 1e-10);
    let (mut worst, mut estimate) = (0.0f64, 0.0f64);
    for k in 1..=samples {
        let err = (subject.v2[k] / x[k] - 1.0).abs();
        worst = worst.max(err);
        estimate = estimate.max(subject.v2_mesh_error[k] / x[k]);
        assert!(err < 1e-6, "r = {r}, t = {}: {err:e}", times[k]);
    }
    assert!(
        worst <= estimate + 1e-8,
        "r = {r}: {worst:e} > {estimate:e}"
    );
    assert!(
        subject.v2[0] >= 0.0 && subject.v2[0] < 1e-6,
        "{}",
        subject.v2[0]
    );
    worst
}

/// Fig. 1(a) (tan, Sigma = 3, lambda = 0.5) at the figure's times 5 k / 16:
/// r = 0 is the hardest curve (edge exponent (lambda + r)/g'(v_u) - 1 = -0.95:
/// nearly all mass piles up at the edges) and needs 4000 cells (measured
/// max error 5.3e-7; 3.7e-6 at 2000); r = 2 also runs at 4000 (1.5e-8).
/// rtol 1e-5 instead of the default 1e-6 changed no error above 1e-9.
#[test]
#[ignore = "slow tier"]
fn trbdf2_fig1a_v2_within_1e6_of_spectral_reference_r0_r2() {
    for r in [0.0, 2.0] {
        let worst = fig1_curve_within_1e6(
            &models::tan(0.5, r),
            &f64::tan,
            3f64.atan(),
            5.0,
            16,
            4000,
            1e-5,
        );
        eprintln!("tan r = {r}: max relative error {worst:.2e}");
    }
}

/// Fig. 1(a), r = 0.5 and r = 10: within 1e-6 on the default 2000 cells
/// (measured 7.0e-7 and 3.4e-8).
#[test]
#[ignore = "slow tier"]
fn trbdf2_fig1a_v2_within_1e6_of_spectral_reference_r05_r10() {
    for r in [0.5, 10.0] {
        let worst = fig1_curve_within_1e6(
            &models::tan(0.5, r),
            &f64::tan,
            3f64.atan(),
            5.0,
            16,
            2000,
            1e-5,
        );
        eprintln!("tan r = {r}: max relative error {worst:.2e}");
    }
}

/// Fig. 1(b) (tanh, Sigma = 0.6, lambda = 0.5) at the figure's times 13 k / 16,
/// all four rates on the default 2000 cells (measured max errors 9.5e-8,
/// 2.6e-9, 6.1e-9 and 3.8e-8 at r = 0, 0.5, 2, 10).
#[test]
#[ignore = "slow tier"]
fn trbdf2_fig1b_v2_within_1e6_of_spectral_reference() {
    for r in [0.0, 0.5, 2.0, 10.0] {
        let worst = fig1_curve_within_1e6(
            &models::tanh(0.5, r),
            &f64::tanh,
            0.6f64.atanh(),
            13.0,
            16,
            2000,
            1e-5,
        );
        eprintln!("tanh r = {r}: max relative error {worst:.2e}");
    }
}

#[test]
#[ignore = "slow tier"]
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
    let st = |cells| {
        stationary(
            &p,
            &StationaryOptions {
                cells,
                mesh: Mesh::Graded,
                extrapolate: true,
            },
        )
        .unwrap()
    };
    let (fine, coarse) = (st(n), st(n / 2));
    let st_raw = |cells| {
        stationary(
            &p,
            &StationaryOptions {
                cells,
                mesh: Mesh::Graded,
                extrapolate: false,
            },
        )
        .unwrap()
        .v2
    };
    // Same nested meshes (400, 200 and 100 graded cells): the stationary
    // solver extrapolates once over (N, N/2), so extrapolating its N and N/2
    // answers once more is the transient's (8 X_N - 6 X_{N/2} + X_{N/4}) / 3.
    // The fixed point of a TR-BDF2 step is the discrete stationary state, so
    // the two agree up to the remaining e^{-t} transient.
    assert_eq!(tr.v, fine.v);
    let v2 = (4.0 * fine.v2 - coarse.v2) / 3.0;
    assert!((tr.v2[0] / v2 - 1.0).abs() < 1e-9, "{} {}", tr.v2[0], v2);
    // The reported estimate is the change made by the second extrapolation
    // plus the bound on the first extrapolation's error (Eq. (N27)), whose
    // three meshes are the stationary solver's N, N/2 and N/4: at least
    // the change, and the bound of the stationary N-mesh answer on top.
    let (quarter, half, full) = (st_raw(n / 4), st_raw(n / 2), st_raw(n));
    let bound = irtp::fp::extrapolation_error(quarter, half, full);
    assert!(
        (tr.v2_mesh_error[0] - ((v2 - fine.v2).abs() + bound)).abs() < 1e-9 * v2,
        "{} {} {bound}",
        tr.v2_mesh_error[0],
        (v2 - fine.v2).abs()
    );
    let snap = &tr.snapshots[0].p;
    let dmax = snap
        .iter()
        .zip(&fine.p)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        dmax < 1e-8 * fine.p.iter().cloned().fold(0.0, f64::max),
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
#[ignore = "slow tier"]
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

/// <v²>(t) of linear drag (g = v, Sigma = 1, lambda = 1/2) from v = 0 with
/// the noise ±1 equally likely, reset to v_r = 0.2 every T = 1 (noise kept):
/// before the reset <v²>(t) = (1 - e^{-2t}(1 + 2t))/2 (the noise's
/// correlation e^{-2 lambda |s - s'|} = e^{-|s - s'|}); after it, with
/// s = t - 1 and the noise still stationary and symmetric,
/// v_r² e^{-2s} + (1 - e^{-2s}(1 + 2s))/2. At every time and mesh the
/// reported mesh error must bound the actual error (plus the time
/// integration's share, 1e-8 as in `fig1_curve_within_1e6`), including the coarse meshes where the
/// initial delta's front crosses few cells (200 cells, t = 0.5: the twice
/// extrapolated value is 7.0e-5 off).
#[test]
fn mesh_error_bounds_the_linear_closed_form_at_every_time() {
    use irtp::model::reset::{Periodic, Schedule};
    let p = models::linear(1.0, 0.5, 0.0, 0.2)
        .with_schedule(Schedule {
            periodic: Some(Periodic::new(1.0).unwrap()),
            ..Default::default()
        })
        .unwrap();
    let free = |s: f64| (1.0 - (-2.0 * s).exp() * (1.0 + 2.0 * s)) / 2.0;
    let exact = |t: f64| {
        if t < 1.0 {
            free(t)
        } else {
            0.04 * (-2.0 * (t - 1.0)).exp() + free(t - 1.0)
        }
    };
    let times = [0.25, 0.5, 0.75, 1.25, 1.5, 1.75];
    for cells in [200, 400, 800] {
        let tr = trbdf2_run(&p, cells, &times, 1e-6, 1e-10);
        for (k, &t) in times.iter().enumerate() {
            let err = (tr.v2[k] - exact(t)).abs();
            assert!(
                err <= tr.v2_mesh_error[k] + 1e-8,
                "cells = {cells}, t = {t}: error {err:e} > estimate {:e}",
                tr.v2_mesh_error[k]
            );
        }
    }
}

/// Periodic resetting to v_r = 0 (tan, r = 0, T = 1): just after every kT
/// the state is the reset's delta placed in the cell of v = 0, as at t = 0.
/// The twice-extrapolated <v²> cancels its Δv² to rounding (it was
/// -5.6e-11 and refused by the range check, exit 4); it is now 0 within
/// its error estimate, and between the resets the moments stay in range.
#[test]
fn a_periodic_reset_to_zero_reports_zero_within_its_estimate() {
    use irtp::model::reset::{Periodic, Schedule};
    let p = models::tan(0.5, 0.0)
        .with_reset_velocity(0.0)
        .unwrap()
        .with_schedule(Schedule {
            periodic: Some(Periodic::new(1.0).unwrap()),
            ..Default::default()
        })
        .unwrap();
    let times = [0.0, 0.5, 1.0, 1.5, 2.0];
    let tr = trbdf2_run(&p, 400, &times, 1e-6, 1e-10);
    for k in [2, 4] {
        let (x, e) = (tr.v2[k], tr.v2_mesh_error[k]);
        assert!(
            x >= 0.0 && x <= e && e < 1e-3,
            "t = {}: {x:e} ± {e:e}",
            times[k]
        );
    }
    assert!(tr.v2.iter().all(|&x| x >= 0.0), "{:?}", tr.v2);
    let far = (tr.v2[1] - tr.v2[3]).abs();
    assert!(far < 10.0 * (tr.v2_mesh_error[1] + tr.v2_mesh_error[3]));
}
