//! Point masses of the stationary velocity law in `fp stationary`
//! (`irtp::model::atoms`): reported as atoms beside a density without
//! them, against their closed forms.

use crate::common::models;
use irtp::fp::{stationary, Mesh, StationaryOptions};
use irtp::model::noise::NoiseModel;
use irtp::{DragLaw, Params};

fn opts(cells: usize) -> StationaryOptions {
    StationaryOptions {
        cells,
        mesh: Mesh::Graded,
        extrapolate: true,
    }
}

fn rpt(drag: &str, rate: f64, vr: f64) -> Params {
    let drag: DragLaw = drag.parse().unwrap();
    let noise = NoiseModel::parse("rpt:sigma=3,alpha=1,beta=2", 0.0).unwrap();
    Params::with_noise(drag, noise, rate, vr).unwrap()
}

/// Σ p Δv over the cells.
fn density_mass(s: &irtp::fp::Stationary) -> f64 {
    s.p.iter().zip(&s.widths).map(|(p, w)| p * w).sum()
}

/// Run-pause-tumble noise reset to v_r = 0, the pause's fixed point: an
/// atom of mass π₀ r/(r + β) (π₀ = α/(α + β)) at 0 within its error
/// estimate, on several meshes and drags; the density carries the rest.
#[test]
fn run_pause_tumble_reset_to_the_pause_has_its_atom() {
    for (drag, rate) in [("tan", 1.0), ("tan", 3.0), ("linear", 1.0), ("cubic", 0.5)] {
        let p = rpt(drag, rate, 0.0);
        let want = (1.0 / 3.0) * rate / (rate + 2.0);
        for cells in [2000, 20_000] {
            let s = stationary(&p, &opts(cells)).unwrap();
            let tag = format!("{drag} r={rate} cells={cells}");
            assert_eq!(s.atoms.len(), 1, "{tag}: {:?}", s.atoms);
            let a = s.atoms[0];
            println!("{tag}: atom {} ± {:.1e} (want {want})", a.mass, a.err);
            assert_eq!(a.v, 0.0, "{tag}");
            assert!(a.err > 0.0 && a.err < 1e-3, "{tag}: error {}", a.err);
            assert!(
                (a.mass - want).abs() <= a.err,
                "{tag}: {} vs {want} ± {}",
                a.mass,
                a.err
            );
            let total = density_mass(&s) + a.mass;
            assert!((total - 1.0).abs() <= a.err + 1e-12, "{tag}: total {total}");
            assert!(s.p.iter().all(|&x| x >= 0.0), "{tag}");
        }
    }
}

/// No atom where nothing holds the velocity: a reset away from the
/// pause's fixed point, or thermal noise.
#[test]
fn no_atom_without_a_held_velocity() {
    let s = stationary(&rpt("tan", 1.0, 0.3), &opts(2000)).unwrap();
    assert!(s.atoms.is_empty(), "{:?}", s.atoms);
    let drag: DragLaw = "linear".parse().unwrap();
    let noise = NoiseModel::parse("rpt:sigma=3,alpha=1,beta=2", 0.1).unwrap();
    let p = Params::with_noise(drag, noise, 1.0, 0.0).unwrap();
    assert!(stationary(&p, &opts(2000)).unwrap().atoms.is_empty());
    let p = models::linear(1.0, 0.3, 2.0, 0.0);
    assert!(stationary(&p, &opts(2000)).unwrap().atoms.is_empty());
}

/// The paper's noise with an exponential refractory period of mean M: the
/// held mass at v_r is r M/(1 + r M) (κ q = r (1 - q), κ = 1/M).
#[test]
fn refractory_hold_is_an_atom_at_the_reset_velocity() {
    for (r, m, vr) in [(2.0, 0.5, 0.0), (1.0, 2.0, 0.3)] {
        let p = models::with_schedule(
            models::linear(1.0, 0.3, r, vr),
            None,
            None,
            Some(&format!("exp:mean={m}")),
        );
        let s = stationary(&p, &opts(4000)).unwrap();
        let want = r * m / (1.0 + r * m);
        assert_eq!(s.atoms.len(), 1);
        let a = s.atoms[0];
        assert_eq!(a.v, vr);
        assert!(
            (a.mass - want).abs() <= a.err + 1e-12,
            "{} vs {want}",
            a.mass
        );
        let total = density_mass(&s) + a.mass;
        assert!((total - 1.0).abs() < 1e-12, "total {total}");
    }
}
