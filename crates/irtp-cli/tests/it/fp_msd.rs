//! `irtp fp msd`: position moments from the chain of x-weighted densities.
//! Newtonian <x²>(t), <v²>(t) against the exact moment equations; the eight
//! Fig. 5 curves against the exact sampler; the long-time slope against the
//! Green-Kubo D_eff of the same discrete chain; the CLI contract.

use crate::common;
use crate::common::models;
use irtp::analytic::linear_moments;
use irtp::fp::{msd, stationary, Mesh, MsdOptions, StationaryOptions};
use irtp::parallel::NoProgress;
use irtp::sim::{SimSpec, TimeGrid};
use irtp_paper::{compute, fig5};

/// Fig. 5's time grid (t = 0 and 35 log-spaced times in [0.01, 100]).
fn fig5_grid() -> TimeGrid {
    let s = fig5::Spec::new(false);
    TimeGrid::log(s.t_min, s.t_max, s.samples).unwrap()
}

/// Linear drag on the uniform mesh: the discrete moment equations close with
/// rates affine in the cell centres, so the mesh error is a polynomial in
/// 1/N that four Richardson levels (32 ... 256 cells) reduce below 1e-9
/// (measured: 4e-9 at rtol 1e-11, the time error); rtol 4e-12 for margin.
fn linear_against_closed_forms(r: f64) {
    let p = models::linear(1.0, 0.5, r, 0.0);
    let times = fig5_grid().times().to_vec();
    let exact = linear_moments::moments(&p, &times).unwrap();
    let o = MsdOptions {
        cells: 32,
        mesh: Mesh::Uniform,
        levels: 4,
        times: times.clone(),
        rtol: 4e-12,
    };
    let m = msd(&p, &o, &NoProgress).unwrap();
    for (k, &t) in times.iter().enumerate().skip(1) {
        let e2 = m.x2[k] / exact.x2[k] - 1.0;
        let ev = m.v2[k] / exact.v2[k] - 1.0;
        assert!(e2.abs() <= 1e-8, "r = {r}, t = {t}: <x²> rel. error {e2:e}");
        assert!(ev.abs() <= 1e-8, "r = {r}, t = {t}: <v²> rel. error {ev:e}");
        let ea = m.alpha[k] - 2.0 * t * exact.xv[k] / exact.x2[k];
        assert!(ea.abs() <= 1e-7, "r = {r}, t = {t}: alpha error {ea:e}");
    }
}

#[test]
#[ignore = "slow tier"]
fn linear_drag_x2_and_v2_match_closed_forms_without_reset() {
    linear_against_closed_forms(0.0);
}

#[test]
#[ignore = "slow tier"]
fn linear_drag_x2_and_v2_match_closed_forms_with_reset() {
    linear_against_closed_forms(1.0);
}

/// z for 4 standard errors with a Bonferroni correction over the 35 times of
/// one curve: each time is allowed the two-sided tail P(|Z| > 4) / 35 =
/// 6.33e-5 / 35 = 1.81e-6, i.e. |z| <= 4.77.
const Z_BONFERRONI_35: f64 = 4.77;

#[test]
#[ignore = "slow tier"]
fn fig5_curves_match_the_exact_sampler() {
    let spec = fig5::Spec::new(false);
    let grid = fig5_grid();
    let n = grid.times().len() - 1;
    assert_eq!(n, 35);
    for (k, (p, what)) in models::fig5().into_iter().enumerate() {
        // What the figure draws (Spec's mesh and tolerance).
        let o = MsdOptions {
            cells: spec.msd_cells,
            mesh: Mesh::Graded,
            levels: spec.msd_levels,
            times: grid.times().to_vec(),
            rtol: spec.msd_rtol,
        };
        let det = msd(&p, &o, &NoProgress).unwrap();
        let sim_spec = SimSpec::new(10_000, grid.clone(), 50.0, 1, 100 + k as u64).unwrap();
        let sim = compute::moments(&compute::simulate(&p, &sim_spec, &NoProgress).unwrap());
        for (j, s) in sim.iter().enumerate().take(n + 1).skip(1) {
            assert_eq!(s.t, det.t[j]);
            let z = (det.x2[j] - s.x2) / s.x2_err;
            assert!(
                z.abs() <= Z_BONFERRONI_35,
                "{what}: t = {}: chain {} sampler {} ± {} (z = {z:.2})",
                s.t,
                det.x2[j],
                s.x2,
                s.x2_err
            );
        }
    }
}

/// d Var(x)/dt = 2 (<xv> - <x><v>) → 2 D_eff, with D_eff the Green-Kubo
/// value of the same discrete chain (same mesh, no extrapolation on either
/// side, so the mesh error is shared): agreement to 1e-6 at t = 100.
#[test]
#[ignore = "slow tier"]
fn long_time_slope_is_the_green_kubo_d_eff() {
    for (p, what) in models::fig5() {
        let o = MsdOptions {
            cells: 200,
            mesh: Mesh::Graded,
            levels: 1,
            times: vec![100.0],
            rtol: 1e-9,
        };
        let m = msd(&p, &o, &NoProgress).unwrap();
        let slope = m.xv[0] - m.x_mean[0] * m.v_mean[0];
        let so = StationaryOptions {
            cells: 200,
            mesh: Mesh::Graded,
            extrapolate: false,
        };
        let d = stationary(&p, &so).unwrap().d_eff;
        assert!(
            (slope / d - 1.0).abs() <= 1e-6,
            "{what}: slope {slope} D_eff {d}"
        );
    }
}

#[test]
fn cli_writes_moments_and_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("msd");
    let o = out.to_str().unwrap();
    let base = [
        "fp", "msd", "--drag", "tanh", "--sigma", "0.6", "--rate", "1",
    ];
    let small = [
        "--cells",
        "32",
        "--levels",
        "2",
        "--samples",
        "6",
        "--t-min",
        "0.5",
        "--t-max",
        "2",
    ];
    let args: Vec<&str> = base
        .iter()
        .chain(&small)
        .copied()
        .chain(["--json", "--out", o])
        .collect();
    let res = common::json(&common::irtp(&args));
    for k in [
        "x2_final",
        "xv_final",
        "alpha_final",
        "d_eff_slope",
        "steps",
        "cells_finest",
    ] {
        assert!(res.get(k).is_some(), "no {k}: {res}");
    }
    assert_eq!(res["cells_finest"], 64);
    let csv = std::fs::read_to_string(out.join("moments.csv")).unwrap();
    let header = csv.lines().find(|l| l.starts_with("t,")).unwrap();
    assert_eq!(header, "t,mass,v_mean,v2,x_mean,xv,x2,alpha,x2_err");
    assert_eq!(csv.lines().filter(|l| !l.starts_with('#')).count(), 7);
    for (flag, value) in [
        ("--levels", "0"),
        ("--levels", "6"),
        ("--rtol", "0"),
        ("--rtol", "nan"),
        ("--t-min", "0"),
        ("--t-max", "inf"),
        ("--samples", "2"),
        ("--cells", "8"),
        ("--seed", "1"),
        ("--lambda", "-1"),
    ] {
        let fresh = tempfile::tempdir().unwrap();
        let bad = fresh.path().join("bad");
        let args: Vec<&str> = base
            .iter()
            .copied()
            .chain([flag, value, "--out", bad.to_str().unwrap()])
            .collect();
        common::assert_rejected(&common::irtp(&args), flag, &bad);
    }
    // A mesh too coarse for t = 0.01 (cells wider than Sigma t): the
    // invariants refuse the answer, exit 4, nothing written.
    let bad = dir.path().join("coarse");
    let args: Vec<&str> = base
        .iter()
        .copied()
        .chain([
            "--cells",
            "32",
            "--levels",
            "2",
            "--out",
            bad.to_str().unwrap(),
        ])
        .collect();
    let r = common::irtp(&args);
    assert_eq!(
        r.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert!(!bad.exists());
    // Over budget: refused before any work, nothing written.
    let bad = dir.path().join("costly");
    let args: Vec<&str> = base
        .iter()
        .copied()
        .chain([
            "--cells",
            "100000",
            "--max-work",
            "1e6",
            "--out",
            bad.to_str().unwrap(),
        ])
        .collect();
    let r = common::irtp(&args);
    assert_eq!(r.status.code(), Some(2));
    assert!(!bad.exists());
}
