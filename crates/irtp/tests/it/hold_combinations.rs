//! An exponential refractory period in the combinations that run it since
//! the hold's equations were carried over (docs/equations.md, (R13)-(R15)):
//! the optimal reset rate over the backward mean (paper's noise and a noise
//! model), the moment chain of `fp msd` and the first-passage distribution
//! with a noise model, each against the exact sampler (4 standard errors,
//! Bonferroni-corrected) and a deterministic cross-check (the slope at
//! r = 0 against a difference quotient of the mean; the paper's noise
//! spelt as a generator against the two-state moment chain; the
//! distribution's mean against the backward mean (R11)).

use crate::common::models;
use irtp::fp::{msd, MsdOptions};
use irtp::mfpt::{
    backward, distribution, optimize_rate, solve, BackwardOptions, DistributionOptions, Method,
    OptimizeOptions, ParticleOptions, Problem,
};
use irtp::model::noise::NoiseModel;
use irtp::model::reset::{NoiseAtReset, Target};
use irtp::parallel::NoProgress;
use irtp::sim::{exact, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};
use irtp_testkit::noises::PAPER_AS_STATES;
use irtp_testkit::stats::bonferroni_z;

const RPT: &str = "rpt:sigma=1,alpha=1,beta=2";

/// `p` with an exponential refractory period of mean `m`.
fn held(p: Params, m: f64) -> Params {
    models::with_schedule(p, None, None, Some(&format!("exp:mean={m}")))
}

fn noise(spec: &str, rate: f64, vr: f64) -> Params {
    let n = NoiseModel::parse(spec, 0.0).unwrap();
    Params::with_noise(DragLaw::Tan, n, rate, vr).unwrap()
}

fn tau(p: &Problem, r: f64, cells: usize) -> f64 {
    let p = p.with_rate(r).unwrap();
    backward::solve(&p, &BackwardOptions::with_cells(cells))
        .unwrap()
        .tau
}

/// `mfpt optimize` with a hold, the paper's noise and run-pause-tumble
/// noise: the slope at r = 0 ((R13)) agrees with the
/// second-order difference quotient of the mean (R6)/(R11) on the same
/// mesh, the optimum is interior, and τ at r* agrees with the exact
/// sampler there.
#[test]
fn optimize_runs_the_hold() {
    let cells = 4000;
    let opts = OptimizeOptions {
        grid_points: 25,
        backward: BackwardOptions::with_cells(cells),
        ..Default::default()
    };
    // Fig. 7's tan medium (Sigma = 3, lambda = 0.5) from v_0 = 0 to 0.5
    // with a hold of mean 0.05; run-pause-tumble noise from v_0 = -0.5 to
    // 0.5, reset to 0.3, a hold of mean 0.2: both with an interior r*.
    let paper = Params::new(DragLaw::Tan, 3.0, 0.5, 0.0, 0.0).unwrap();
    let paper = Problem::new(held(paper, 0.05), 0.0, 0.5).unwrap();
    let rpt = Problem::new(held(noise(RPT, 0.0, 0.3), 0.2), -0.5, 0.5).unwrap();
    let z = bonferroni_z(2);
    for (k, (what, p)) in [("paper", paper), ("rpt", rpt)].into_iter().enumerate() {
        let o = optimize_rate(&p, &opts, &NoProgress).unwrap();
        let h = 1e-4;
        let (t0, t1, t2) = (
            tau(&p, 0.0, cells),
            tau(&p, h, cells),
            tau(&p, 2.0 * h, cells),
        );
        let quotient = (4.0 * t1 - 3.0 * t0 - t2) / (2.0 * h);
        println!(
            "{what}: r* {} tau* {} slope {} quotient {quotient}",
            o.r_opt, o.tau_opt, o.dtau_dr_r0
        );
        assert!(
            (o.dtau_dr_r0 - quotient).abs() <= 1e-4 * o.dtau_dr_r0.abs().max(t0),
            "{what}: {} vs {quotient}",
            o.dtau_dr_r0
        );
        assert!(o.interior && !o.at_upper_bound, "{what}: {o:?}");
        let m = Method::Exact(ParticleOptions {
            particles: 100_000,
            t_max: f64::INFINITY,
            seed: 4100 + k as u64,
        });
        let at = p.with_rate(o.r_opt).unwrap();
        let s = solve(&at, &m, &NoProgress).unwrap().summary().unwrap();
        let zs = (s.tau - o.tau_opt) / s.tau_err;
        println!("{what}: exact {} ± {} (z {zs:.2})", s.tau, s.tau_err);
        assert!(
            zs.abs() < z,
            "{what}: {} ± {} vs {}",
            s.tau,
            s.tau_err,
            o.tau_opt
        );
    }
}

fn msd_opts(times: &[f64]) -> MsdOptions {
    MsdOptions {
        cells: 200,
        levels: 2,
        rtol: 1e-8,
        times: times.to_vec(),
        ..MsdOptions::default()
    }
}

/// `fp msd` with run-pause-tumble noise and a hold, a point target (noise
/// kept) and a uniform one (noise re-drawn, one held vector per target
/// cell): `<x²>`(t) and `<v²>`(t) against the exact sampler at t = 1, 4.
#[test]
fn msd_with_a_noise_model_runs_the_hold() {
    let times = [1.0, 4.0];
    let cases = [
        (Target::point(0.0), NoiseAtReset::Kept),
        (Target::uniform(-0.3, 0.4), NoiseAtReset::Redrawn),
    ];
    let z = bonferroni_z(2 * times.len() * cases.len());
    for (i, (target, rule)) in cases.into_iter().enumerate() {
        let p = noise(RPT, 2.0, 0.0).with_reset(target, rule).unwrap();
        let p = held(p, 0.5);
        let fp = msd(&p, &msd_opts(&times), &NoProgress).unwrap();
        let grid = TimeGrid::from_times([vec![0.0], times.to_vec()].concat()).unwrap();
        let spec = SimSpec::new(40_000, grid, 0.0, 20, 4200 + i as u64).unwrap();
        let ex = exact::simulate(&p, &spec, &NoProgress).unwrap();
        for (k, t) in times.iter().enumerate() {
            let (x2, v2) = (&ex.x2[k + 1], &ex.v2[k + 1]);
            let zx = (x2.mean() - fp.x2[k]) / x2.sem();
            let zv = (v2.mean() - fp.v2[k]) / v2.sem();
            println!(
                "{target:?} t={t}: <x²> fp {} exact {} ± {} (z {zx:.2}); <v²> fp {} exact {} ± {} (z {zv:.2})",
                fp.x2[k],
                x2.mean(),
                x2.sem(),
                fp.v2[k],
                v2.mean(),
                v2.sem()
            );
            assert!(
                zx.abs() < z && zv.abs() < z,
                "{target:?} t={t}: z {zx} {zv}"
            );
        }
    }
}

/// The paper's noise spelt as a generator with a hold in `fp msd` ((R14))
/// agrees with the two-state moment chain's (R8) within both chains'
/// extrapolation error estimates.
#[test]
fn msd_paper_as_states_with_a_hold_matches_the_two_state_chain() {
    let times = [1.0, 4.0];
    let chain = held(noise(PAPER_AS_STATES, 1.0, 0.2), 0.7);
    let two = held(Params::new(DragLaw::Tan, 1.0, 0.5, 1.0, 0.2).unwrap(), 0.7);
    let a = msd(&chain, &msd_opts(&times), &NoProgress).unwrap();
    let b = msd(&two, &msd_opts(&times), &NoProgress).unwrap();
    for (k, t) in times.iter().enumerate() {
        let err = a.x2_err[k] + b.x2_err[k];
        println!(
            "t={t}: N-state {} two-state {} (est {err:e})",
            a.x2[k], b.x2[k]
        );
        assert!((a.x2[k] - b.x2[k]).abs() <= err, "t={t}");
        assert!((a.mass[k] - 1.0).abs() < 1e-9);
    }
}

/// `mfpt distribution` with run-pause-tumble noise and a hold (r = 2,
/// M = 0.5, tan, v_0 = 0, v_t = 0.5), a point target (noise kept) and a
/// uniform one (noise re-drawn, one held survival per state averaged over
/// the target's nodes): E(T) against the
/// backward mean (R11) within both error estimates, and S(t) at the
/// Kaplan-Meier times nearest tau / 2, tau, 2 tau against the exact
/// sampler (Bonferroni over the six).
#[test]
fn distribution_with_a_noise_model_runs_the_hold() {
    let cases = [
        (Target::point(0.0), NoiseAtReset::Kept),
        (Target::uniform(-0.3, 0.4), NoiseAtReset::Redrawn),
    ];
    let zmax = bonferroni_z(3 * cases.len());
    for (i, (target, rule)) in cases.into_iter().enumerate() {
        let p = held(noise(RPT, 2.0, 0.0).with_reset(target, rule).unwrap(), 0.5);
        let prob = Problem::new(p, 0.0, 0.5).unwrap();
        let b = backward::solve(&prob, &BackwardOptions::with_cells(8000)).unwrap();
        let run = ParticleOptions {
            particles: 40_000,
            t_max: 1e4,
            seed: 4300 + i as u64,
        };
        let r = solve(&prob, &Method::Exact(run), &NoProgress).unwrap();
        let c = r.stats().expect("particles").survival();
        let idx: Vec<usize> = [0.5, 1.0, 2.0]
            .iter()
            .map(|x| {
                let near = |i: &usize| (c.t[*i] - x * b.tau).abs();
                (0..c.t.len())
                    .min_by(|a, b| near(a).total_cmp(&near(b)))
                    .unwrap()
            })
            .collect();
        let times: Vec<f64> = idx.iter().map(|&i| c.t[i]).collect();
        let opts = DistributionOptions {
            backward: BackwardOptions::with_cells(4000),
            ..DistributionOptions::default()
        };
        let d = distribution(&prob, &times, &opts).unwrap();
        let tol = d.mean_error + b.error_estimate + d.tail_mass * d.t_end;
        println!("{target:?}: E(T) {} tau {} (tol {tol:e})", d.mean, b.tau);
        assert!(
            (d.mean - b.tau).abs() <= tol,
            "{target:?}: {} vs {}",
            d.mean,
            b.tau
        );
        for (k, &j) in idx.iter().enumerate() {
            let z = (c.survival[j] - d.survival[k]) / c.survival_err[j].hypot(d.mesh_error);
            println!(
                "{target:?} t = {}: particles {:.4} ± {:.4}, S = {:.4}, z = {z:.2}",
                c.t[j], c.survival[j], c.survival_err[j], d.survival[k]
            );
            assert!(z.abs() <= zmax, "{target:?} t = {}: z = {z}", c.t[j]);
        }
    }
}

/// The held x-moments of `fp msd` ((R14)) tend to the stationary
/// Green-Kubo D_eff with the hold ((R10), `fp stationary`): a uniform
/// target, noise re-drawn, (<xv> - <x><v>)(t = 200) against D_eff within
/// the two solvers' error estimates (the chain's: its change when the
/// finest mesh is left out).
#[test]
fn msd_hold_tends_to_the_stationary_d_eff() {
    let p = noise(RPT, 2.0, 0.0)
        .with_reset(Target::uniform(-0.3, 0.4), NoiseAtReset::Redrawn)
        .unwrap();
    let p = held(p, 0.5);
    let slope = |levels: usize| {
        let o = MsdOptions {
            cells: 100,
            levels,
            rtol: 1e-8,
            times: vec![200.0],
            ..MsdOptions::default()
        };
        let m = msd(&p, &o, &NoProgress).unwrap();
        m.xv[0] - m.x_mean[0] * m.v_mean[0]
    };
    let (fine, coarse) = (slope(3), slope(2));
    let o = irtp::fp::StationaryOptions {
        cells: 4000,
        ..irtp::fp::StationaryOptions::default()
    };
    let s = irtp::fp::stationary(&p, &o).unwrap();
    let e = s.noise.as_ref().unwrap().errors.unwrap()[2];
    let tol = (fine - coarse).abs() + e;
    println!(
        "msd {fine} (levels 2: {coarse}), stationary D_eff {} ± {e:e}",
        s.d_eff
    );
    assert!(
        (fine - s.d_eff).abs() <= tol,
        "{fine} vs {} (tol {tol:e})",
        s.d_eff
    );
}
