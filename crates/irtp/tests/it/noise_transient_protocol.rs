//! `fp transient` with a noise model under periodic resetting (the chain's
//! [`TransientSpace`] reset: all mass to the target at every kT): the
//! linear closed form and the paper's noise spelt as a generator against
//! the two-state solver, before and after resets.

use irtp::fp::{self, Transient, TransientOptions};
use irtp::model::noise::NoiseModel;
use irtp::model::reset::{Periodic, Refractory, Schedule};
use irtp::{DragLaw, Params};
use irtp_testkit::noises::{PAPER_AS_STATES, RPT};

/// Reset to v_r every T = 1 (Poisson rate 0).
fn periodic(p: Params) -> Params {
    p.with_schedule(Schedule {
        periodic: Some(Periodic::new(1.0).unwrap()),
        ..Default::default()
    })
    .unwrap()
}

/// The paper's noise (Sigma = 1, lambda = 1/2) as a two-state generator.
fn as_chain(drag: &str, vr: f64) -> Params {
    let noise = NoiseModel::parse(PAPER_AS_STATES, 0.0).unwrap();
    periodic(Params::with_noise(drag.parse().unwrap(), noise, 0.0, vr).unwrap())
}

fn run(p: &Params, cells: usize, times: &[f64]) -> Transient {
    let o = TransientOptions {
        cells,
        t_max: *times.last().unwrap(),
        times: times.to_vec(),
        snapshot_times: vec![],
        rtol: 1e-6,
        atol: 1e-10,
        ..TransientOptions::default()
    };
    fp::transient(p, &o).unwrap()
}

/// <v²>(t) of linear drag (Sigma = 1, lambda = 1/2) from v = 0 with the
/// noise drawn from π, reset to v_r = 0.2 every T = 1 (noise kept): before
/// the reset (1 - e^{-2t}(1 + 2t))/2; after it, with s = t - 1 and the
/// noise still stationary and symmetric, v_r² e^{-2s} + (1 - e^{-2s}(1 +
/// 2s))/2 (at t = 1 the state just after the reset: v_r²). The chain's reported mesh error bounds the actual error (plus
/// the time integration's share, 1e-8 as for the two-state solver).
#[test]
fn chain_periodic_resetting_matches_the_linear_closed_form() {
    let p = as_chain("linear", 0.2);
    let free = |s: f64| (1.0 - (-2.0 * s).exp() * (1.0 + 2.0 * s)) / 2.0;
    let exact = |t: f64| {
        if t < 1.0 {
            free(t)
        } else {
            0.04 * (-2.0 * (t - 1.0)).exp() + free(t - 1.0)
        }
    };
    let times = [0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75];
    let tr = run(&p, 400, &times);
    assert!(
        tr.mass_error_max < 1e-10,
        "mass error {}",
        tr.mass_error_max
    );
    for (k, &t) in times.iter().enumerate() {
        let err = (tr.v2[k] - exact(t)).abs();
        println!(
            "t = {t}: <v^2> {:.10} exact {:.10} error {err:.2e} estimate {:.2e}",
            tr.v2[k],
            exact(t),
            tr.v2_mesh_error[k]
        );
        assert!(
            err <= tr.v2_mesh_error[k] + 1e-8,
            "t = {t}: error {err:e} > estimate {:e}",
            tr.v2_mesh_error[k]
        );
    }
}

/// The paper's noise spelt as a two-state generator with tan drag and
/// periodic resetting agrees with the two-state solver within the sum of
/// both mesh error estimates (plus 1e-8 for the time integration), before
/// and after two resets.
#[test]
fn chain_periodic_resetting_matches_the_two_state_solver() {
    let times = [0.5, 1.0, 1.5, 2.25, 2.75];
    let chain = run(&as_chain("tan", 0.2), 400, &times);
    let drag: DragLaw = "tan".parse().unwrap();
    let two = run(
        &periodic(Params::new(drag, 1.0, 0.5, 0.0, 0.2).unwrap()),
        400,
        &times,
    );
    for (k, &t) in times.iter().enumerate() {
        let (a, b) = (chain.v2[k], two.v2[k]);
        let est = chain.v2_mesh_error[k] + two.v2_mesh_error[k];
        println!("t = {t}: chain {a:.10} two-state {b:.10} estimate {est:.2e}");
        assert!(
            (a - b).abs() <= est + 1e-8,
            "t = {t}: chain {a} vs two-state {b}, estimate {est:e}"
        );
    }
}

/// Reset at rate 1 into an exponential refractory period of mean 1/2.
fn with_hold(p: Params) -> Params {
    p.with_schedule(Schedule {
        refractory: Some(Refractory::Exp { mean: 0.5 }),
        ..Default::default()
    })
    .unwrap()
}

/// The total held mass from a start with nothing held obeys dq/dt =
/// r (1 − q) − κ q whatever the noise (each noise state's phases sum to
/// the chain's law): q(t) = r/(r + κ) (1 − e^{−(r + κ) t}); the chain's
/// `refractory_mass` follows it within the time integration's tolerance
/// (rtol = 1e-6).
#[test]
fn chain_refractory_mass_follows_the_hold_fraction() {
    let noise = NoiseModel::parse(RPT, 0.0).unwrap();
    let p = with_hold(Params::with_noise("tan".parse().unwrap(), noise, 1.0, 0.2).unwrap());
    let times = [0.25, 0.5, 1.0, 2.0];
    let tr = run(&p, 200, &times);
    let (r, kappa) = (1.0, 2.0);
    assert!(
        tr.mass_error_max < 1e-10,
        "mass error {}",
        tr.mass_error_max
    );
    for (k, &t) in times.iter().enumerate() {
        let want = r / (r + kappa) * (1.0 - (-(r + kappa) * t).exp());
        let err = (tr.refractory_mass[k] - want).abs();
        println!(
            "t = {t}: held {:.10} want {want:.10} error {err:.2e}",
            tr.refractory_mass[k]
        );
        assert!(
            err <= 1e-5,
            "t = {t}: held {} vs {want}",
            tr.refractory_mass[k]
        );
    }
}

/// The paper's noise spelt as a generator with an exponential refractory
/// period agrees with the two-state solver's held pairs within the sum of
/// both mesh error estimates (plus 1e-8 for the time integration).
#[test]
fn chain_refractory_matches_the_two_state_solver() {
    let times = [0.5, 1.0, 2.0];
    let noise = NoiseModel::parse(PAPER_AS_STATES, 0.0).unwrap();
    let drag: DragLaw = "tan".parse().unwrap();
    let chain = run(
        &with_hold(Params::with_noise(drag.clone(), noise, 1.0, 0.2).unwrap()),
        400,
        &times,
    );
    let two = run(
        &with_hold(Params::new(drag, 1.0, 0.5, 1.0, 0.2).unwrap()),
        400,
        &times,
    );
    for (k, &t) in times.iter().enumerate() {
        let (a, b) = (chain.v2[k], two.v2[k]);
        let est = chain.v2_mesh_error[k] + two.v2_mesh_error[k];
        println!("t = {t}: chain {a:.10} two-state {b:.10} estimate {est:.2e}");
        assert!(
            (a - b).abs() <= est + 1e-8,
            "t = {t}: chain {a} vs two-state {b}, estimate {est:e}"
        );
        let (ha, hb) = (chain.refractory_mass[k], two.refractory_mass[k]);
        assert!(
            (ha - hb).abs() <= 1e-5,
            "t = {t}: held {ha} vs two-state {hb}"
        );
    }
}
