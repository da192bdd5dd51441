//! The first-passage-time distribution with a noise model
//! (`mfpt::distribution` over a noise model's `Finite` chain, docs/equations.md Eqs.
//! (N37)-(N39)):
//!
//! (1) over the athermal cases of `NOISE_CASES`: the atoms and the density
//!     integrate to 1 - S(t_last), and E(T) agrees with the N-state
//!     backward equations' tau within the two error estimates;
//! (2) the paper's noise spelt as a generator gives the two-state solver's
//!     S(t) to their discretisation errors (also with the noise re-drawn at
//!     a reset, a random reset target and a downward target);
//! (3) Euler particles (dt and dt/2 extrapolated) against S(t) at three
//!     times, for a run-pause-tumble and an asymmetric case;
//! (4) with thermal noise (Eq. (N49)): E(T) against the thermal backward
//!     tau and the mass identity for Ornstein-Uhlenbeck velocities with
//!     resetting, continuity at T -> 0 against the T = 0 survival, Euler
//!     particles for tan and tanh with telegraph + thermal noise (slow
//!     tier); a drag the thermal backward equations do not run is refused
//!     naming `drag` (tan above T = 1 naming `temperature`).

use crate::common::noises::{self, NoiseCase, NOISE_CASES, PAPER_AS_STATES};
use crate::common::stats::bonferroni_z;
use irtp::mfpt::{
    self, distribution, distribution::ATOM_WINDOW, BackwardOptions, Distribution,
    DistributionOptions, Method, ParticleOptions, Problem,
};
use irtp::parallel::NoProgress;
use irtp::{DragLaw, Params};

/// The passage of noise_conformance.rs: from v_r upward, 60 % of the way
/// to the upper edge (or to v_r + 1).
fn passage(c: &NoiseCase) -> (f64, f64) {
    let (_, hi) = c.params().bounds();
    let v0 = c.reset_velocity;
    (v0, v0 + 0.6 * (hi.min(v0 + 1.0) - v0))
}

/// Options on `cells` cells (the distribution runs cells / 2 and cells).
fn options(cells: usize) -> DistributionOptions {
    DistributionOptions {
        backward: BackwardOptions::with_cells(cells),
        ..DistributionOptions::default()
    }
}

/// `n` + 1 equally spaced times on [0, t_max].
fn grid(t_max: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|i| t_max * i as f64 / n as f64).collect()
}

/// ∫ f dt over the grid by the trapezoid rule.
fn trapezoid(t: &[f64], f: &[f64]) -> f64 {
    t.windows(2)
        .zip(f.windows(2))
        .map(|(t, f)| 0.5 * (t[1] - t[0]) * (f[0] + f[1]))
        .sum()
}

/// The distribution of case `c` on its passage.
fn solve(c: &NoiseCase, times: &[f64], cells: usize) -> (Problem, Distribution) {
    let (v0, vt) = passage(c);
    let prob = Problem::new(c.params(), v0, vt).unwrap_or_else(|e| panic!("{}: {e}", c.name));
    let d = distribution(&prob, times, &options(cells))
        .unwrap_or_else(|e| panic!("{}: distribution: {e}", c.name));
    (prob, d)
}

/// The case's backward tau and its error estimate.
fn backward_tau(prob: &Problem, name: &str) -> (f64, f64) {
    let ode = mfpt::solve(
        prob,
        &Method::Backward(BackwardOptions::default()),
        &NoProgress,
    )
    .unwrap_or_else(|e| panic!("{name}: backward: {e}"));
    let b = ode.backward().expect("backward");
    (b.tau, b.error_estimate)
}

/// (1a) E(T) against the N-state backward equations' tau, within the two
/// error estimates, over every athermal case.
#[test]
fn noise_distribution_mean_matches_backward_tau() {
    let mut cases = 0;
    for c in noises::athermal() {
        cases += 1;
        let (v0, vt) = passage(c);
        let prob = Problem::new(c.params(), v0, vt).unwrap();
        let (tau, err) = backward_tau(&prob, c.name);
        let (_, d) = solve(c, &[0.5 * tau, tau, 2.0 * tau], 2000);
        assert!(!d.atoms.is_empty(), "{}: no atom", c.name);
        let atoms: f64 = d.atoms.iter().map(|a| a.weight * a.mass).sum();
        assert!((atoms - d.atom_mass).abs() < 1e-15, "{}", c.name);
        eprintln!(
            "{}: tau {tau} ± {err:.1e}, E(T) {} ± {:.1e}, tail {:.1e}, {} steps",
            c.name, d.mean, d.mean_error, d.tail_mass, d.steps
        );
        let tol = 2.0 * (d.mean_error + err) + 1e-4 * tau;
        assert!(
            (d.mean - tau).abs() <= tol,
            "{}: E(T) = {} vs tau = {tau} (tolerance {tol:e})",
            c.name,
            d.mean
        );
        assert!(d.tail_mass < 1e-9, "{}: tail {}", c.name, d.tail_mass);
        assert!(d.second >= d.mean * d.mean, "{}: E(T²) < E(T)²", c.name);
    }
    assert!(cases >= 8);
}

/// Output times to 25 tau for the trapezoid rule: 401 equally spaced, and
/// 101 across each atom's smeared window (f falls there by the atom's
/// continuous share within a few spreads), from a first solve's atoms.
fn mass_grid(c: &NoiseCase, tau: f64) -> Vec<f64> {
    let (_, d) = solve(c, &[tau], 2000);
    let mut times = grid(25.0 * tau, 400);
    for a in &d.atoms {
        let w = 4.0 * ATOM_WINDOW * a.spread;
        times.extend(grid(2.0 * w, 100).iter().map(|x| a.time - w + x));
    }
    times.retain(|&t| t >= 0.0);
    times.sort_by(f64::total_cmp);
    times.dedup();
    times
}

/// Atoms + ∫_0^t_last f dt (trapezoid on [`mass_grid`]) against
/// 1 - S(t_last), and S(t_last) below 1e-4.
fn check_mass(c: &NoiseCase) {
    let (v0, vt) = passage(c);
    let prob = Problem::new(c.params(), v0, vt).unwrap();
    let (tau, _) = backward_tau(&prob, c.name);
    let times = mass_grid(c, tau);
    let (_, d) = solve(c, &times, 4000);
    let last = *d.survival.last().unwrap();
    let mass = d.atom_mass + trapezoid(&times, &d.density);
    eprintln!(
        "{}: atoms {:.4}, mass {mass:.5} + S {last:.1e}",
        c.name, d.atom_mass
    );
    assert!(
        (mass - (1.0 - last)).abs() < 5e-3,
        "{}: atoms + ∫f = {mass}, 1 - S(t_last) = {}",
        c.name,
        1.0 - last
    );
    assert!(last < 1e-4, "{}: S(t_last) = {last}", c.name);
}

/// (1b) The atoms and the density carry the whole mass: a three-state case.
#[test]
fn noise_distribution_atoms_and_density_integrate_to_one() {
    check_mass(NOISE_CASES.iter().find(|c| c.name == "tan-three").unwrap());
}

/// (1b) over every other athermal case (`tan-three` is
/// [`noise_distribution_atoms_and_density_integrate_to_one`]'s, in the fast
/// tier).
#[test]
#[ignore = "slow tier: 9 noise models on dense output grids (~20 s)"]
fn noise_distribution_atoms_and_density_integrate_to_one_every_case() {
    noises::athermal()
        .filter(|c| c.name != "tan-three")
        .for_each(check_mass);
}

/// (2) The paper's noise as a generator against the two-state solver.
#[test]
fn noise_distribution_paper_as_states_matches_two_state_solver() {
    for c in NOISE_CASES
        .iter()
        .filter(|c| c.noise == PAPER_AS_STATES && !c.thermal())
    {
        let (v0, vt) = passage(c);
        let drag: DragLaw = c.drag.parse().unwrap();
        let paper = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
        let two = Problem::new(paper, v0, vt).unwrap();
        let times = grid(4.0, 80);
        let a = distribution(&two, &times, &options(4000)).unwrap();
        let (_, b) = solve(c, &times, 4000);
        // The two meshes' errors and the time integrations' (10 rtol each).
        let tol = a.mesh_error + b.mesh_error + 20.0 * DistributionOptions::default().rtol;
        let mut worst = 0.0f64;
        for (i, t) in times.iter().enumerate() {
            let diff = (a.survival[i] - b.survival[i]).abs();
            worst = worst.max(diff);
            assert!(
                diff <= tol,
                "{}: t = {t}: two-state S = {}, N-state S = {} (tolerance {tol:e})",
                c.name,
                a.survival[i],
                b.survival[i]
            );
        }
        eprintln!("{}: max |ΔS| = {worst:.1e} (tolerance {tol:.1e})", c.name);
        assert!((a.atom_mass - b.atom_mass).abs() < 1e-12 * a.atom_mass.max(1.0));
        assert!((a.atom_time - b.atom_time).abs() < 1e-9 * a.atom_time);
        assert!((a.mean - b.mean).abs() <= a.mean_error + b.mean_error + 1e-3 * a.mean);
    }
}

/// The Euler particles' Kaplan-Meier survival (t, S, SE) at step dt.
fn particle_curve(prob: &Problem, dt: f64, seed: u64) -> Vec<(f64, f64, f64)> {
    let run = ParticleOptions {
        particles: 8000,
        t_max: 1e4,
        seed,
    };
    let r = mfpt::solve(prob, &Method::Euler { dt, run }, &NoProgress).unwrap();
    let c = r.stats().expect("particles").survival();
    (0..c.t.len())
        .map(|i| (c.t[i], c.survival[i], c.survival_err[i]))
        .collect()
}

/// Euler particles (dt and dt/2 extrapolated, 2 S(dt/2) - S(dt)) against
/// S(t) at the grid times of the Kaplan-Meier curve nearest tau / 2, tau
/// and 2 tau, |z| within `zmax`; `seed` and `seed + 1` for the two steps.
fn survival_matches_euler(c: &NoiseCase, seed: u64, zmax: f64) {
    const DT: f64 = 0.01;
    let (v0, vt) = passage(c);
    let prob = Problem::new(c.params(), v0, vt).unwrap();
    let (a, b) = (
        particle_curve(&prob, DT, seed),
        particle_curve(&prob, DT / 2.0, seed + 1),
    );
    let (tau, _) = backward_tau(&prob, c.name);
    let times: Vec<f64> = [0.5, 1.0, 2.0]
        .iter()
        .map(|x| {
            let near = |p: &&(f64, f64, f64)| (p.0 - x * tau).abs();
            a.iter()
                .min_by(|p, q| near(p).total_cmp(&near(q)))
                .unwrap()
                .0
        })
        .collect();
    let (_, d) = solve(c, &times, 4000);
    for (i, &t) in times.iter().enumerate() {
        let at = |curve: &[(f64, f64, f64)]| *curve.iter().find(|p| p.0 == t).unwrap();
        let (pa, pb) = (at(&a), at(&b));
        let (s, se) = (2.0 * pb.1 - pa.1, (4.0 * pb.2 * pb.2 + pa.2 * pa.2).sqrt());
        let z = (s - d.survival[i]) / se.hypot(d.mesh_error);
        eprintln!(
            "{}: t = {t}: particles {s:.4} ± {se:.4}, S = {:.4}, z = {z:.2} (bound {zmax:.2})",
            c.name, d.survival[i]
        );
        assert!(z.abs() <= zmax, "{}: t = {t}: z = {z}", c.name);
    }
}

/// (3) [`survival_matches_euler`] at temperature 0.
#[test]
fn noise_distribution_survival_matches_euler_particles() {
    let names = ["linear-rpt", "tan-asym"];
    let zmax = bonferroni_z(3 * names.len());
    for (k, name) in names.iter().enumerate() {
        survival_matches_euler(case(name), 9100 + 2 * k as u64, zmax);
    }
}

/// (2) with the noise re-drawn at a reset, a random reset target, and a
/// downward target: the paper's noise as a generator against the
/// two-state solver.
#[test]
fn noise_distribution_paper_as_states_matches_with_redrawn_noise_random_target_downward() {
    use irtp::model::reset::{NoiseAtReset, Target};
    let c = NOISE_CASES
        .iter()
        .find(|c| c.noise == PAPER_AS_STATES && c.drag == "tan")
        .unwrap();
    let drag: DragLaw = c.drag.parse().unwrap();
    let two = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
    let times = grid(4.0, 40);
    for (target, rule, (v0, vt)) in [
        (Target::point(0.2), NoiseAtReset::Redrawn, (0.1, 0.5)),
        (Target::uniform(-0.3, 0.4), NoiseAtReset::Kept, (0.1, 0.5)),
        (
            Target::uniform(-0.3, 0.4),
            NoiseAtReset::Redrawn,
            (0.1, 0.5),
        ),
        (Target::point(0.2), NoiseAtReset::Kept, (0.1, -0.4)),
    ] {
        let n = Problem::new(c.params().with_reset(target, rule).unwrap(), v0, vt).unwrap();
        let q = Problem::new(two.with_reset(target, rule).unwrap(), v0, vt).unwrap();
        let a = distribution(&q, &times, &options(2000)).unwrap();
        let b = distribution(&n, &times, &options(2000)).unwrap();
        let tol = a.mesh_error + b.mesh_error + 20.0 * DistributionOptions::default().rtol;
        let worst = (0..times.len())
            .map(|i| (a.survival[i] - b.survival[i]).abs())
            .fold(0.0, f64::max);
        eprintln!("{target:?} {rule:?} {v0} -> {vt}: max |ΔS| = {worst:.1e} (tolerance {tol:.1e})");
        assert!(
            worst <= tol,
            "{target:?} {rule:?} {v0} -> {vt}: {worst} > {tol}"
        );
        assert!(
            (a.atom_mass - b.atom_mass).abs() < 1e-12,
            "{target:?} {rule:?}"
        );
        assert!((a.mean - b.mean).abs() <= a.mean_error + b.mean_error + 1e-3 * a.mean);
    }
}

/// A telegraph + thermal tanh case (the list's tanh cases have no
/// telegraph noise with a temperature).
const TANH_TELEGRAPH_THERMAL: NoiseCase = NoiseCase {
    name: "tanh-telegraph-thermal",
    drag: "tanh",
    noise: "telegraph:sigma=0.5,lambda=1",
    temperature: 0.1,
    rate: 1.0,
    reset_velocity: 0.0,
};

/// The named case of `NOISE_CASES`.
fn case(name: &str) -> &'static NoiseCase {
    NOISE_CASES.iter().find(|c| c.name == name).unwrap()
}

/// (4) Ornstein-Uhlenbeck velocities with resetting (`--noise none`,
/// linear drag, T = 0.5) and the telegraph + thermal linear case: no atom,
/// E(T) against the thermal backward equations' tau within the two error
/// estimates, and the mass identity ∫_0^t_last f dt = 1 - S(t_last)
/// (trapezoid on 801 times to 25 tau and 401 to 2 tau, where f rises
/// steeply from 0).
#[test]
fn noise_distribution_thermal_mean_and_mass() {
    for name in ["linear-thermal", "linear-telegraph-thermal"] {
        let c = case(name);
        let (v0, vt) = passage(c);
        let prob = Problem::new(c.params(), v0, vt).unwrap();
        let (tau, err) = backward_tau(&prob, c.name);
        let mut times = grid(25.0 * tau, 800);
        times.extend(grid(2.0 * tau, 400));
        times.sort_by(f64::total_cmp);
        times.dedup();
        let (_, d) = solve(c, &times, 2000);
        assert!(
            d.atoms.is_empty() && d.atom_mass == 0.0,
            "{}: atoms",
            c.name
        );
        assert!(!d.smeared(d.atom_time), "{}: smeared", c.name);
        let tol = 2.0 * (d.mean_error + err) + 1e-4 * tau;
        let last = *d.survival.last().unwrap();
        let mass = trapezoid(&times, &d.density);
        eprintln!(
            "{}: tau {tau} ± {err:.1e}, E(T) {} ± {:.1e} (rel. diff {:.1e}), mass {mass:.6} + \
             S {last:.1e}, mesh error {:.1e}, {} steps",
            c.name,
            d.mean,
            d.mean_error,
            (d.mean - tau).abs() / tau,
            d.mesh_error,
            d.steps
        );
        assert!(
            (d.mean - tau).abs() <= tol,
            "{}: E(T) = {} vs tau = {tau} (tolerance {tol:e})",
            c.name,
            d.mean
        );
        assert!((d.survival[0] - 1.0).abs() < 1e-12, "{}", c.name);
        assert!(
            (mass - (1.0 - last)).abs() < 2e-3,
            "{}: ∫f = {mass}, 1 - S(t_last) = {}",
            c.name,
            1.0 - last
        );
        assert!(last < 1e-4 && d.tail_mass < 1e-9, "{}: S {last}", c.name);
        assert!(d.second >= d.mean * d.mean, "{}: E(T²) < E(T)²", c.name);
    }
}

/// (4) T -> 0: the telegraph noise with linear drag at T = 1e-4 against
/// the same noise at T = 0 (the paper's two-state path) at times away
/// from the atom's (T_f ± 0.3: diffusion spreads the atom over
/// sqrt(2 T T_f) / (speed) ~ 0.02, the meshes over their spreads): within
/// both mesh errors, the time integrations' (10 rtol each) and O(T).
#[test]
fn noise_distribution_thermal_is_continuous_at_zero_temperature() {
    use irtp::model::noise::NoiseModel;
    let drag: DragLaw = "linear".parse().unwrap();
    let at = |t: f64| {
        let noise = NoiseModel::parse(noises::PAPER_TELEGRAPH, t).unwrap();
        let p = Params::with_noise(drag.clone(), noise, 0.5, 0.0).unwrap();
        Problem::new(p, 0.0, 0.5).unwrap()
    };
    let cold = distribution(&at(0.0), &[0.1], &options(4000)).unwrap();
    let tf = cold.atom_time;
    let times: Vec<f64> = [0.3, tf - 0.3, tf + 0.3, 2.0, 4.0]
        .into_iter()
        .filter(|&t| t > 0.0)
        .collect();
    let a = distribution(&at(0.0), &times, &options(4000)).unwrap();
    let b = distribution(&at(1e-4), &times, &options(4000)).unwrap();
    assert!(b.atoms.is_empty() && a.atom_mass > 0.0);
    let tol = a.mesh_error + b.mesh_error + 20.0 * DistributionOptions::default().rtol + 1e-3;
    for (i, t) in times.iter().enumerate() {
        let diff = (a.survival[i] - b.survival[i]).abs();
        eprintln!(
            "t = {t:.3}: S(T=0) = {:.5}, S(T=1e-4) = {:.5}, |ΔS| = {diff:.1e} (tolerance \
             {tol:.1e})",
            a.survival[i], b.survival[i]
        );
        assert!(diff <= tol, "t = {t}: {diff} > {tol}");
    }
    let rel = (a.mean - b.mean).abs() / a.mean;
    assert!(rel < 1e-2, "E(T): {} vs {}", a.mean, b.mean);
}

/// (4) What the thermal backward equations do not run is refused by name,
/// before any solve: a cubic drag (`drag`), tan above T = 1
/// (`temperature`).
#[test]
fn noise_distribution_thermal_refuses_by_name() {
    use irtp::model::noise::NoiseModel;
    for (drag, t, flag) in [("cubic", 0.5, "drag"), ("tan", 1.5, "temperature")] {
        let noise = NoiseModel::parse("none", t).unwrap();
        let p = Params::with_noise(drag.parse().unwrap(), noise, 0.5, 0.0).unwrap();
        let prob = Problem::new(p, 0.0, 0.5).unwrap();
        for e in [
            distribution(&prob, &[1.0], &options(200)).unwrap_err(),
            mfpt::distribution::check_problem(&prob).unwrap_err(),
        ] {
            match e.parameter() {
                Some(name) => assert_eq!(name, flag, "{drag}"),
                None => panic!("{drag}: {e}"),
            }
        }
    }
}

/// (4) [`survival_matches_euler`] (the Brownian-bridge crossing check of
/// the Euler particles) for tan and tanh with telegraph + thermal noise;
/// 4-sigma family rate over the six comparisons.
#[test]
#[ignore = "slow tier: 4 x 8000 Euler particles with thermal noise (~5 s)"]
fn noise_distribution_thermal_survival_matches_euler_particles() {
    let cases = [*case("tan-telegraph-thermal"), TANH_TELEGRAPH_THERMAL];
    let zmax = bonferroni_z(3 * cases.len());
    for (k, c) in cases.iter().enumerate() {
        survival_matches_euler(c, 9200 + 2 * k as u64, zmax);
    }
}
