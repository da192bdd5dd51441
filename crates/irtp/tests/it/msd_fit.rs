//! The paper's Eq. (36) estimate of D_eff (fit <x²> = 2 D t + c on the grid
//! times of [burn_in, t_max]) carried per particle by both samplers
//! (`Observables::msd_fit_d`, `SimSummary::d_eff_msd`): equal to the fit of
//! the ensemble <x²>, and within 4 standard errors of the exact Newtonian D_eff.

use crate::common::models;
use irtp::analytic::linear;
use irtp::parallel::NoProgress;
use irtp::sim::{self, Method, SimSpec, TimeGrid};
use irtp::DragLaw;

/// OLS slope of y against t, halved, over t >= t0.
fn half_slope(t: &[f64], y: &[f64], t0: f64) -> f64 {
    let pts: Vec<(f64, f64)> = t
        .iter()
        .zip(y)
        .filter(|p| *p.0 >= t0)
        .map(|(&a, &b)| (a, b))
        .collect();
    let n = pts.len() as f64;
    let (mt, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mt) * (p.0 - mt)).sum();
    sxy / sxx / 2.0
}

#[test]
fn per_particle_fit_is_the_fit_of_the_ensemble_msd() {
    let p = models::tan(0.9, 2.0);
    let spec = SimSpec::new(600, TimeGrid::linear(12.0, 25).unwrap(), 4.0, 5, 3).unwrap();
    for method in [Method::Exact, Method::euler(1e-3)] {
        let o = sim::simulate(&p, &spec, method, &NoProgress).unwrap();
        let y: Vec<f64> = o.x2.iter().map(|a| a.mean()).collect();
        let want = half_slope(&o.times, &y, 4.0);
        let got = o.summary().d_eff_msd.unwrap();
        assert!(
            (got - want).abs() <= 1e-10 * want.abs(),
            "{method:?}: {got} vs {want}"
        );
        assert_eq!(o.msd_fit_d.n, 600);
    }
}

#[test]
fn no_fit_without_symmetry_or_window() {
    // v_r != 0: <x> drifts, an Eq. (36) fit of <x²> would include the drift.
    let p = models::medium(DragLaw::Tan, 0.9, 2.0, 0.2);
    let spec = SimSpec::new(50, TimeGrid::linear(6.0, 13).unwrap(), 2.0, 5, 3).unwrap();
    let s = sim::simulate(&p, &spec, Method::Exact, &NoProgress)
        .unwrap()
        .summary();
    assert!(s.d_eff_msd.is_none() && s.d_eff_msd_err.is_none());
    // One grid time in the window: nothing to fit.
    let p = p.with_reset_velocity(0.0).unwrap();
    let spec = SimSpec::new(50, TimeGrid::linear(6.0, 3).unwrap(), 5.0, 5, 3).unwrap();
    let s = sim::simulate(&p, &spec, Method::Exact, &NoProgress)
        .unwrap()
        .summary();
    assert!(s.d_eff_msd.is_none());
}

/// Newtonian drag, where D_eff is known in closed form (`analytic::linear`).
/// Window from 20 to 60 relaxation times, so the non-linear part of <x²>
/// (exponentially small there) is far below the statistical error. The
/// Euler run uses dt = 1e-3: its O(r dt) bias on D (≤ 0.3 % at r = 3) is a
/// tenth of the ≈ 3 % standard error of 5 000 particles.
#[test]
fn matches_exact_newtonian_d_eff() {
    for (i, &(lambda, r)) in [(0.5, 0.0), (1.0, 3.0)].iter().enumerate() {
        let p = models::linear(1.0, lambda, r, 0.0);
        let relax = 1.0 / (1.0f64 + r).min(2.0 * lambda);
        let grid = TimeGrid::linear(60.0 * relax, 31).unwrap();
        let spec = SimSpec::new(5000, grid, 20.0 * relax, 1, 40 + i as u64).unwrap();
        let exact_d = linear::d_eff(&p).unwrap();
        for method in [Method::Exact, Method::euler(1e-3)] {
            let s = sim::simulate(&p, &spec, method, &NoProgress)
                .unwrap()
                .summary();
            let (d, se) = (s.d_eff_msd.unwrap(), s.d_eff_msd_err.unwrap());
            eprintln!("{method:?} lambda={lambda} r={r}: D = {d:.5} ± {se:.5}, exact {exact_d:.5}");
            assert!(
                ((d - exact_d) / se).abs() < 4.0,
                "{method:?} lambda={lambda} r={r}: D = {d} ± {se}, exact {exact_d}"
            );
            assert!(
                se < 0.05 * exact_d,
                "standard error {se} too large to test anything"
            );
        }
    }
}
