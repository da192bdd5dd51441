//! The cross-method conformance suite: every check below runs over the
//! shared lists of `irtp_testkit::laws` (one line per law and parameter
//! set), so a new law is one line there.
//!
//! (a) Twins (two specs of the same g: Newtonian limits, expressions of
//!     built-in laws): the Fokker-Planck density and <v²>, the backward
//!     MFPT, the r = 0 density and the exact sampler's seeded output agree
//!     to the twin's tolerance.
//! (b) r = 0: the library's density and the Fokker-Planck solver against an
//!     independent reference (composite Simpson of the quadrature formula,
//!     or a closed form).
//! (c) r = 2: the exact sampler against the Fokker-Planck solver (<v²> and
//!     a histogram), the exact first-passage sampler against the backward
//!     equations, each over every law at once (Bonferroni).
//! (d) The Euler scheme's step bound is the steepest secant to the edge,
//!     and its <v²> agrees with the Fokker-Planck solver.

use crate::common::laws::{
    self, law, Cross, CROSS, CROSS_PASSAGE, CROSS_RATE, EULER_BOUNDS, R0_CASES, TWINS, TWIN_VR,
};
use crate::common::stats::bonferroni_z;
use irtp::analytic::r0::R0Density;
use irtp::fp::{stationary, Stationary, StationaryOptions};
use irtp::mfpt::{backward, solve, BackwardOptions, Method, ParticleOptions, Problem};
use irtp::model::{Drag, DragLaw};
use irtp::parallel::NoProgress;
use irtp::sim::{exact, SimSpec, TimeGrid};
use irtp::Params;

/// Probability of each bin [edges[i], edges[i+1]] under the FP cell
/// averages (cells cut by a bin edge share their mass by overlap).
fn fp_bin_mass(fp: &Stationary, edges: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; edges.len() - 1];
    for (i, &p) in fp.p.iter().enumerate() {
        let (a, b) = (fp.edges[i], fp.edges[i + 1]);
        for (j, m) in out.iter_mut().enumerate() {
            let lo = a.max(edges[j]);
            let hi = b.min(edges[j + 1]);
            if hi > lo {
                *m += p * fp.widths[i] * (hi - lo) / (b - a);
            }
        }
    }
    out
}

fn cells(cells: usize) -> StationaryOptions {
    StationaryOptions {
        cells,
        ..StationaryOptions::default()
    }
}

fn params(c: &Cross) -> Params {
    Params::new(law(c.spec), c.sigma, c.lambda, CROSS_RATE, c.vr).unwrap()
}

/// Every registered drag law has a line in the cross-method list, so a new
/// law cannot skip the suite.
#[test]
fn every_registered_law_is_in_the_suite() {
    for d in DragLaw::examples() {
        let spec = d.to_string();
        let k = laws::kind(&spec);
        assert!(
            CROSS.iter().any(|c| laws::kind(c.spec) == k),
            "drag law '{k}' has no line in irtp_testkit::laws::CROSS"
        );
    }
}

/// (a) Fokker-Planck (<v²> and every cell, r = 0 and 2), backward tau, the
/// r = 0 density (<v²> and the pdf on a grid) of a law and its twin.
#[test]
fn twins_agree_in_every_solver() {
    for t in TWINS {
        let close = |a: f64, b: f64| (a - b).abs() <= t.rtol * a.abs().max(1e-3);
        let (a, b) = (law(t.twin), law(t.spec));
        let par = |d: DragLaw, r: f64| Params::new(d, t.sigma, t.lambda, r, TWIN_VR).unwrap();
        for r in [0.0, 2.0] {
            let o = cells(4000);
            let (fa, fb) = (
                stationary(&par(a.clone(), r), &o).unwrap(),
                stationary(&par(b.clone(), r), &o).unwrap(),
            );
            assert!(
                close(fa.v2, fb.v2),
                "{} r={r}: {} vs {}",
                t.spec,
                fa.v2,
                fb.v2
            );
            for (pa, pb) in fa.p.iter().zip(&fb.p) {
                assert!(close(*pa, *pb), "{} r={r}: density {pa} vs {pb}", t.spec);
            }
        }
        let bo = BackwardOptions::default();
        let tau = |d: DragLaw| {
            let prob = Problem::new(par(d, 2.0), -0.249, 0.5).unwrap();
            backward::solve(&prob, &bo).unwrap().tau
        };
        let (ta, tb) = (tau(a.clone()), tau(b.clone()));
        assert!(close(ta, tb), "{}: tau {ta} vs {tb}", t.spec);
        let ra = R0Density::from_params(&par(a.clone(), 0.0)).unwrap();
        let rb = R0Density::by_quadrature(b, t.sigma, t.lambda).unwrap();
        assert!(
            close(ra.v2(), rb.v2()),
            "{}: r0 <v²> {} vs {}",
            t.spec,
            ra.v2(),
            rb.v2()
        );
        let vu = a.inverse(t.sigma);
        for i in 1..40 {
            let v = -vu + 2.0 * vu * i as f64 / 40.0;
            assert!(close(ra.pdf(v), rb.pdf(v)), "{}: r0 pdf at {v}", t.spec);
        }
    }
}

/// (a) The exact sampler, same seed: the event times and flips are drawn
/// from the same streams whatever the law and the flows agree to ~1e-14, so
/// a law and its twin have the same number of events and every recorded
/// moment and time average agrees to the twin's tolerance.
#[test]
fn twins_agree_in_the_exact_sampler() {
    let times = TimeGrid::from_times(vec![0.0, 1.0, 5.0, 20.0]).unwrap();
    let spec = SimSpec::new(2000, times, 5.0, 20, 7).unwrap();
    for t in TWINS {
        let run = |d: DragLaw| {
            let p = Params::new(d, t.sigma, t.lambda, 2.0, TWIN_VR).unwrap();
            exact::simulate(&p, &spec, &NoProgress).unwrap()
        };
        let (a, b) = (run(law(t.twin)), run(law(t.spec)));
        assert_eq!(a.steps, b.steps, "{}: events", t.spec);
        let pairs = a.v2.iter().zip(&b.v2).chain(a.x2.iter().zip(&b.x2));
        for (x, y) in pairs.chain([(&a.v2_time_avg, &b.v2_time_avg)]) {
            let (x, y) = (x.mean(), y.mean());
            assert!(
                (x - y).abs() <= t.rtol * x.abs().max(1e-6),
                "{}: {x} vs {y}",
                t.spec
            );
        }
    }
}

/// (b) r = 0. The library's density against the reference: its shape on a
/// grid to 1e-8 where the reference is pointwise, its <v²> to 1e-8 where
/// the density is bounded (edge exponent a > 0). The Fokker-Planck solver:
/// 16 bin masses against the reference (a > 0) within twice the change
/// from 2000 to 4000 cells (an estimate of the fine mesh's own error) plus
/// 1e-9, and <v²> within its extrapolation's change plus 1e-9; on its
/// default (graded) mesh, its extrapolated <v²> against the library's
/// within its own error estimate |X_extrapolated - X_fine| or 1e-6
/// relative, whichever is smaller (the library's quadrature is good to
/// ~1e-13), and mass 1 to 1e-12.
#[test]
fn r0_density_matches_the_reference() {
    for c in R0_CASES {
        let (d, sigma) = (c.law(), c.sigma);
        let vu = d.inverse(sigma);
        let lib = R0Density::by_quadrature(d.clone(), sigma, c.lambda).unwrap();
        for i in 1..40 {
            let v = -vu + 2.0 * vu * i as f64 / 40.0;
            if let Some(want) = c.reference_shape(v) {
                let got = lib.pdf(v) / lib.pdf(0.0);
                assert!(
                    (got - want).abs() <= 1e-8 * want,
                    "{} v={v}: {got} vs {want}",
                    c.spec
                );
            }
        }
        let p = Params::new(d, sigma, c.lambda, 0.0, 0.0).unwrap();
        let fp = stationary(&p, &StationaryOptions::default()).unwrap();
        let tol = (fp.v2 - fp.fine.v2).abs().min(1e-6 * fp.v2);
        assert!(
            (lib.v2() - fp.v2).abs() <= tol,
            "{}: r0 <v²> {} vs FP {}",
            c.spec,
            lib.v2(),
            fp.v2
        );
        assert!(
            (fp.mass - 1.0).abs() < 1e-12,
            "{}: FP mass {}",
            c.spec,
            fp.mass
        );
        if c.edge_exponent() <= 0.0 {
            continue;
        }
        let (bins, v2) = c.reference_bins(16);
        assert!(
            (lib.v2() - v2).abs() <= 1e-8 * v2,
            "{}: {} vs {v2}",
            c.spec,
            lib.v2()
        );
        let fine = stationary(&p, &cells(4000)).unwrap();
        let coarse = stationary(&p, &cells(2000)).unwrap();
        let edges: Vec<f64> = (0..=16).map(|i| -vu + 2.0 * vu * i as f64 / 16.0).collect();
        let (mf, mc) = (fp_bin_mass(&fine, &edges), fp_bin_mass(&coarse, &edges));
        for j in 0..16 {
            let tol = 2.0 * (mf[j] - mc[j]).abs() + 1e-9;
            let (got, want) = (mf[j], bins[j]);
            assert!(
                (got - want).abs() <= tol,
                "{} bin {j}: FP {got} vs {want} (tol {tol:e})",
                c.spec
            );
        }
        let tol = (fine.v2 - fine.fine.v2).abs() + 1e-9;
        assert!(
            (fine.v2 - v2).abs() <= tol,
            "{}: FP <v²> {} vs {v2}",
            c.spec,
            fine.v2
        );
    }
}

/// (c) r = 2: the exact sampler's time-averaged <v²> and its 20-bin
/// histogram against the FP solver, for every law: 21 comparisons each,
/// Bonferroni over all; the FP error estimate added in quadrature to the
/// <v²> standard error; a seed per law, so the comparisons are
/// independent. Bins the particles never visit (far tails of a
/// wide interval) have no standard error: there the FP mass must be
/// negligible too (< 1e-6).
#[test]
fn exact_sampler_matches_fokker_planck() {
    let zmax = bonferroni_z(CROSS.len() * 21);
    let times = TimeGrid::from_times(vec![0.0, 40.0]).unwrap();
    for (i, c) in CROSS.iter().enumerate() {
        let spec = SimSpec::new(4000, times.clone(), 10.0, 20, 2025 + i as u64).unwrap();
        let p = params(c);
        let fp = stationary(&p, &StationaryOptions::default()).unwrap();
        let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
        let (m, se) = (o.v2_time_avg.mean(), o.v2_time_avg.sem());
        let se = se.hypot(fp.v2 - fp.fine.v2);
        eprintln!("{}: exact <v²> {m} ± {se}, FP {}", c.spec, fp.v2);
        assert!(
            ((m - fp.v2) / se).abs() < zmax,
            "{}: {m} ± {se} vs {}",
            c.spec,
            fp.v2
        );
        let w = o.bin_width();
        let edges: Vec<f64> = (0..=20).map(|i| o.v_lo + w * i as f64).collect();
        let mut worst = 0.0f64;
        for (acc, q) in o.density_time.iter().zip(fp_bin_mass(&fp, &edges)) {
            if acc.sem() > 0.0 {
                worst = worst.max(((acc.mean() - q / w) / acc.sem()).abs());
            } else {
                assert!(
                    acc.mean() == 0.0 && q < 1e-6,
                    "{}: unvisited bin with FP mass {q}",
                    c.spec
                );
            }
        }
        eprintln!("{}: histogram max |z| {worst:.2} (bound {zmax:.2})", c.spec);
        assert!(worst < zmax, "{}: histogram max |z| = {worst}", c.spec);
    }
}

/// (c) The exact first-passage sampler's MFPT against the backward
/// equations (v_0 = -0.249 to v_t = 0.5, across v = 0): one comparison per
/// law, Bonferroni over all, the backward error estimate added in
/// quadrature; no passage censored.
#[test]
fn exact_mfpt_matches_backward_equations() {
    let zmax = bonferroni_z(CROSS.len());
    for (i, c) in CROSS.iter().enumerate() {
        let prob = Problem::new(params(c), CROSS_PASSAGE.0, CROSS_PASSAGE.1).unwrap();
        let ode = backward::solve(&prob, &BackwardOptions::default()).unwrap();
        let run = ParticleOptions {
            particles: 10_000,
            t_max: f64::INFINITY,
            seed: 300 + i as u64,
        };
        let st = solve(&prob, &Method::Exact(run), &NoProgress)
            .unwrap()
            .summary()
            .expect("particle estimate");
        assert_eq!(st.censored, 0, "{}", c.spec);
        let err = if ode.error_estimate.is_finite() {
            ode.error_estimate
        } else {
            0.0
        };
        let se = st.tau_err.hypot(err);
        eprintln!(
            "{}: exact tau {} ± {}, backward {}",
            c.spec, st.tau, st.tau_err, ode.tau
        );
        assert!(((st.tau - ode.tau) / se).abs() < zmax, "{}", c.spec);
    }
}

/// (d) The Euler step bound: a step just below it keeps every velocity of
/// a fine grid of (v_l, v_u) inside (the Euler map v + dt (Sigma - g(v))
/// stays below v_u), `over` times it throws some out and is refused naming
/// --dt; the closed form where known.
#[test]
fn euler_step_bound_is_the_steepest_secant() {
    for b in EULER_BOUNDS {
        let p = Params::new(law(b.spec), b.sigma, 0.5, 2.0, 0.0).unwrap();
        let (d, vu, max) = (p.drag(), p.v_upper(), p.max_euler_dt());
        assert!(max.is_finite() && max > 0.0, "{}: {max}", b.spec);
        if let Some(exact) = b.exact {
            assert!((max - exact).abs() < 1e-12, "{}: {max} vs {exact}", b.spec);
        }
        let escapes = |dt: f64| {
            (1..200_000)
                .map(|i| -vu + 2.0 * vu * i as f64 / 200_000.0)
                .filter(|v| v + dt * (b.sigma - d.force(*v)) >= vu)
                .count()
        };
        assert_eq!(escapes(max * (1.0 - 1e-9)), 0, "{}", b.spec);
        assert!(
            escapes(b.over * max) > 0,
            "{}: the bound is not sharp",
            b.spec
        );
        assert!(p.check_dt(0.5 * max).is_ok(), "{}", b.spec);
        let e = p.check_dt(b.over * max).unwrap_err().to_string();
        assert!(e.contains("dt"), "{}: {e}", b.spec);
    }
}

/// (d) The Euler scheme (dt = 2e-3) against the FP <v²> at r = 2 where the
/// drift is steep or jumps: Bonferroni over the listed laws (the O(dt)
/// bias, ~1e-3 relative, is below the standard error of ~1 %; measured
/// -0.0009 ± 0.0005 for Coulomb at dt = 4e-3).
#[test]
fn euler_matches_fokker_planck_for_steep_drift() {
    let cases: Vec<_> = EULER_BOUNDS.iter().filter(|b| b.against_fp).collect();
    let zmax = bonferroni_z(cases.len());
    let times = TimeGrid::from_times(vec![0.0, 30.0]).unwrap();
    let spec = SimSpec::new(2000, times, 10.0, 20, 11).unwrap();
    for b in cases {
        let p = Params::new(law(b.spec), b.sigma, 0.5, 2.0, 0.0).unwrap();
        let fp = stationary(&p, &StationaryOptions::default()).unwrap();
        let o = irtp::sim::euler::simulate(&p, &spec, 2e-3, &NoProgress).unwrap();
        let (m, se) = (o.v2_time_avg.mean(), o.v2_time_avg.sem());
        eprintln!("{} r=2: Euler <v²> {m} ± {se}, FP {}", b.spec, fp.v2);
        assert!(
            ((m - fp.v2) / se).abs() < zmax,
            "{}: {m} ± {se} vs {}",
            b.spec,
            fp.v2
        );
    }
}

/// (c) In time, from v(0) = v_r: the Fokker-Planck moment chain's
/// <x²>(t) and <v²>(t) (`fp msd`, x-weighted densities on the forward
/// operator) against the exact sampler at t = 1, 4, 10, for every law: 6
/// comparisons each, Bonferroni over all. A coarse chain (200 and 400
/// cells, rtol 1e-8; its error, ~3e-5 relative, is far below the standard
/// errors of ~0.5 %) keeps the test short.
#[test]
fn position_moments_match_exact_sampler() {
    let cases = &CROSS;
    let times = vec![1.0, 4.0, 10.0];
    let zmax = bonferroni_z(2 * times.len() * cases.len());
    for (i, c) in cases.iter().enumerate() {
        let p = params(c);
        let o = irtp::fp::MsdOptions {
            cells: 200,
            levels: 2,
            rtol: 1e-8,
            times: times.clone(),
            ..irtp::fp::MsdOptions::default()
        };
        let fp = irtp::fp::msd(&p, &o, &NoProgress).unwrap();
        let grid = TimeGrid::from_times([vec![0.0], times.clone()].concat()).unwrap();
        let ex = exact::simulate(
            &p,
            &SimSpec::new(40_000, grid, 0.0, 20, 17 + i as u64).unwrap(),
            &NoProgress,
        )
        .unwrap();
        for (k, t) in times.iter().enumerate() {
            let (x2, v2) = (&ex.x2[k + 1], &ex.v2[k + 1]);
            let zx = (x2.mean() - fp.x2[k]) / x2.sem();
            let zv = (v2.mean() - fp.v2[k]) / v2.sem();
            eprintln!("{} t={t}: <x²> z {zx:.2}, <v²> z {zv:.2}", c.spec);
            assert!(
                zx.abs() < zmax && zv.abs() < zmax,
                "{} t={t}: z {zx} {zv}",
                c.spec
            );
        }
    }
}
