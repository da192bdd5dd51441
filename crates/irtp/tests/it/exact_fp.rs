//! Exact sampler vs the Fokker-Planck stationary solver (`irtp::fp`) on the
//! paper's parameter sets (Figs. 1-3, 6): stationary <v²> within 4 standard
//! errors (the FP value is Richardson-extrapolated, its discretisation error
//! is orders of magnitude below the sampling error), and D_eff for a
//! nonlinear drag with resetting.
//!
//! Relaxation: particles start with a stationary (symmetric) noise state, so
//! only the velocity must forget v(0) = 0, at rate >= min g' + r; a burn-in
//! of 15/(min g' + r) leaves an initial-condition bias below e^{-15}.

use crate::common::models;
use irtp::fp::{stationary, StationaryOptions};
use irtp::model::Drag;
use irtp::parallel::NoProgress;
use irtp::sim::exact;
use irtp::sim::{SimSpec, TimeGrid};
use irtp::{DragLaw, Params};

fn relax(p: &Params) -> f64 {
    let d = p.drag();
    let gmin = d.derivative(0.0).min(d.derivative(p.v_upper()));
    1.0 / (gmin + p.rate())
}

#[test]
fn stationary_v2_matches_fokker_planck() {
    for (i, &(ref d, sigma, lambda, r)) in [
        (DragLaw::Tan, 3.0, 0.9, 0.0),
        (DragLaw::Tan, 3.0, 7.0, 2.0),
        (DragLaw::Tan, 3.0, 15.0, 10.0),
        (DragLaw::Tan, 3.0, 25.0, 100.0),
        (DragLaw::Tanh, 0.6, 0.5, 0.2),
        (DragLaw::Tanh, 0.6, 0.85, 1.0),
        (DragLaw::Tanh, 0.6, 1.2, 10.0),
        (DragLaw::Tanh, 0.6, 3.0, 100.0),
    ]
    .iter()
    .enumerate()
    {
        let p = Params::new(d.clone(), sigma, lambda, r, 0.0).unwrap();
        let fp = stationary(&p, &StationaryOptions::default()).unwrap();
        let tr = relax(&p);
        let spec = SimSpec::new(
            1500,
            TimeGrid::from_times(vec![0.0, 55.0 * tr]).unwrap(),
            15.0 * tr,
            10,
            700 + i as u64,
        )
        .unwrap();
        let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
        let (m, se) = (o.v2_time_avg.mean(), o.v2_time_avg.sem());
        eprintln!(
            "{d} Sigma={sigma} lambda={lambda} r={r}: exact <v2> {m:.6} ± {se:.6}, FP {:.6}",
            fp.v2
        );
        assert!(
            ((m - fp.v2) / se).abs() < 4.0,
            "{d} Sigma={sigma} lambda={lambda} r={r}: exact {m} ± {se}, FP {}",
            fp.v2
        );
    }
}

/// D_eff of tan drag with resetting from Var x growth between two late
/// times (batch standard error, as in `exact_sim.rs`) vs the FP value.
#[test]
fn d_eff_matches_fokker_planck() {
    let p = models::tan(0.9, 2.0);
    let fp = stationary(&p, &StationaryOptions::default()).unwrap();
    // Position variance is stationary in its increments once both the
    // velocity (1/(1+r)) and the noise (1/(2 lambda)) have relaxed.
    let tr = relax(&p).max(1.0 / (2.0 * p.lambda()));
    let (t1, t2) = (20.0 * tr, 60.0 * tr);
    let batches = 16;
    let slopes: Vec<f64> = (0..batches)
        .map(|b| {
            let spec = SimSpec::new(
                500,
                TimeGrid::from_times(vec![t1, t2]).unwrap(),
                0.0,
                1,
                900 + b,
            )
            .unwrap();
            let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
            let var = |k: usize| o.x2[k].mean() - o.x[k].mean().powi(2);
            (var(1) - var(0)) / (2.0 * (t2 - t1))
        })
        .collect();
    let n = batches as f64;
    let mean = slopes.iter().sum::<f64>() / n;
    let se = (slopes.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / n.sqrt();
    eprintln!("D_eff exact {mean:.6} ± {se:.6}, FP {:.6}", fp.d_eff);
    assert!(
        ((mean - fp.d_eff) / se).abs() < 4.0,
        "D_eff exact {mean} ± {se}, FP {}",
        fp.d_eff
    );
}
