//! The shared test models (`tests/common/models.rs`) are what they claim:
//! the linear-drag answers equal `irtp::analytic::linear`, and the r = 0
//! sets of Figs. 2 and 3 fall in the regimes their descriptions name.

use crate::common::models;
use irtp::analytic::{linear, r0};
use irtp::DragLaw;

#[test]
fn linear_answers_match_the_library_closed_forms() {
    for (p, known) in models::linear_cases() {
        let rel = |a: f64, b: f64| ((a - b) / b).abs();
        assert!(
            known.v_mean.abs() <= 1e-15 || rel(known.v_mean, linear::v_mean(&p).unwrap()) < 1e-14
        );
        assert!(rel(known.v2, linear::v2(&p).unwrap()) < 1e-14, "{p:?}");
        assert!(
            rel(known.d_eff, linear::d_eff(&p).unwrap()) < 1e-14,
            "{p:?}"
        );
    }
}

#[test]
fn figure_sets_have_the_paper_media_and_regimes() {
    let (f2, f3) = (models::fig2(), models::fig3());
    assert_eq!((f2.len(), f3.len()), (20, 20));
    for (p, what) in f2.iter().chain(&f3) {
        assert_eq!(p.sigma(), models::paper_sigma(p.drag()));
        assert_eq!(p.reset_velocity(), 0.0);
        if p.rate() == 0.0 {
            let label = r0::regime(p.drag(), p.sigma(), p.lambda()).label;
            assert!(
                what.contains(&format!("regime ({label})")),
                "{what}: {label}"
            );
        }
    }
    for set in [models::fig1(), models::fig5(), models::fig6()] {
        assert!(set.iter().any(|(p, _)| p.drag() == DragLaw::Tan));
        assert!(set.iter().any(|(p, _)| p.drag() == DragLaw::Tanh));
    }
    for (prob, _) in models::fig7_cases() {
        assert_eq!((prob.v0(), prob.vt()), (models::FIG7_V0, models::FIG7_VT));
    }
}
