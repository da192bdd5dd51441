//! r = 0: the exact sampler's time-averaged stationary density (exact
//! occupation times per bin, one independent estimate per particle) and <v²>
//! against the closed-form density `irtp::analytic::r0::R0Density`, for the
//! paper's parameter sets (Figs. 2-3): tan Sigma = 3, lambda ∈ {0.9, 15};
//! tanh Sigma = 0.6, lambda ∈ {0.5, 1.2}.
//!
//! Significance: every bin probability must agree within 4.5 standard errors
//! (per-bin two-sided p = 6.8e-6, Bonferroni family-wise < 1.4e-4 for 20
//! bins) and <v²> within 4 standard errors. Burn-in of 20 relaxation times
//! makes the initial-condition bias negligible against these errors.

use irtp::analytic::r0::R0Density;
use irtp::model::Drag;
use irtp::parallel::NoProgress;
use irtp::sim::exact;
use irtp::sim::{SimSpec, TimeGrid};
use irtp::{DragLaw, Params};

#[test]
fn r0_density_and_v2_match_closed_form() {
    for (i, &(ref d, sigma, lambda)) in [
        (DragLaw::Tan, 3.0, 0.9),
        (DragLaw::Tan, 3.0, 15.0),
        (DragLaw::Tanh, 0.6, 0.5),
        (DragLaw::Tanh, 0.6, 1.2),
    ]
    .iter()
    .enumerate()
    {
        let p = Params::new(d.clone(), sigma, lambda, 0.0, 0.0).unwrap();
        let exact_density = R0Density::from_params(&p).unwrap();
        // Slowest relaxation: noise (1/(2 lambda)) or drag (1/min g'; g' is
        // extremal at v = 0 or at the edge).
        let gmin = d.derivative(0.0).min(d.derivative(p.v_upper()));
        let relax = (1.0 / (2.0 * lambda)).max(1.0 / gmin);
        let burn = 20.0 * relax;
        let t_max = burn + 60.0 * relax;
        let bins = 20;
        let spec = SimSpec::new(
            1500,
            TimeGrid::from_times(vec![0.0, t_max]).unwrap(),
            burn,
            bins,
            300 + i as u64,
        )
        .unwrap();
        let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
        let w = o.bin_width();
        let edges: Vec<f64> = (0..=bins).map(|k| o.v_lo + w * k as f64).collect();
        let probs = exact_density.bin_probabilities(&edges);
        for (k, acc) in o.density_time.iter().enumerate() {
            let (est, se) = (acc.mean() * w, acc.sem() * w);
            let z = (est - probs[k]) / se;
            assert!(
                z.abs() < 4.5,
                "{d} Sigma={sigma} lambda={lambda} bin {k}: {est} ± {se} vs {}",
                probs[k]
            );
        }
        let z = (o.v2_time_avg.mean() - exact_density.v2()) / o.v2_time_avg.sem();
        let zmax = o
            .density_time
            .iter()
            .enumerate()
            .map(|(k, a)| ((a.mean() * w - probs[k]) / (a.sem() * w)).abs())
            .fold(0.0f64, f64::max);
        eprintln!(
            "{d} Sigma={sigma} lambda={lambda}: <v2> {:.6} ± {:.6} vs {:.6}; max |z| over bins {zmax:.2}",
            o.v2_time_avg.mean(),
            o.v2_time_avg.sem(),
            exact_density.v2()
        );
        assert!(
            z.abs() < 4.0,
            "{d} lambda={lambda}: <v2> {} ± {} vs {}",
            o.v2_time_avg.mean(),
            o.v2_time_avg.sem(),
            exact_density.v2()
        );
    }
}
