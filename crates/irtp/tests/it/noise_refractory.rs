//! An exponential refractory period with a noise model in the N-state
//! Fokker-Planck and backward solvers (docs/equations.md, (R10), (R11)):
//! the paper's noise spelt as a generator against the two-state solver,
//! the held mass against its closed form r M/(1 + r M), the continuous
//! density against the plain one scaled by 1/(1 + r M), τ with a re-drawn
//! noise state against (1 + r M) τ_plain, and run-pause-tumble noise
//! against the exact sampler (4 standard errors, Bonferroni-corrected).

use crate::common::models;
use irtp::fp::{stationary, Mesh, StationaryOptions};
use irtp::mfpt::{self, BackwardOptions, FptSummary, Method, ParticleOptions, Problem};
use irtp::model::noise::NoiseModel;
use irtp::model::reset::{NoiseAtReset, Reset, Target};
use irtp::parallel::NoProgress;
use irtp::sim::{simulate, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};
use irtp_testkit::noises::PAPER_AS_STATES;
use irtp_testkit::stats::bonferroni_z;

const RPT: &str = "rpt:sigma=3,alpha=1,beta=2";

fn opts(cells: usize) -> StationaryOptions {
    StationaryOptions {
        cells,
        mesh: Mesh::Graded,
        extrapolate: true,
    }
}

/// `p` with an exponential refractory period of mean `m`.
fn held(p: Params, m: f64) -> Params {
    models::with_schedule(p, None, None, Some(&format!("exp:mean={m}")))
}

fn noise(spec: &str, rate: f64, vr: f64) -> Params {
    let n = NoiseModel::parse(spec, 0.0).unwrap();
    Params::with_noise(DragLaw::Tan, n, rate, vr).unwrap()
}

/// The paper's noise (Sigma = 1, lambda = 0.5) spelt as a generator with
/// a refractory period agrees with the two-state solver's (R1) to both
/// solvers' discretisation error, with the paper's reset and with a
/// uniform target and the noise re-drawn; both hold exactly r M/(1 + r M).
#[test]
fn paper_as_states_with_a_hold_matches_the_two_state_solver() {
    let (r, m) = (1.0, 0.7);
    let want = r * m / (1.0 + r * m);
    for rule in [
        None,
        Some((Target::uniform(-0.3, 0.5), NoiseAtReset::Redrawn)),
    ] {
        let chain = noise(PAPER_AS_STATES, r, 0.2);
        let two = Params::new(DragLaw::Tan, 1.0, 0.5, r, 0.2).unwrap();
        let (p, q) = match rule {
            None => (chain, two),
            Some((t, w)) => (
                chain.with_reset(t, w).unwrap(),
                two.with_reset(t, w).unwrap(),
            ),
        };
        let s = stationary(&held(p, m), &opts(4000)).unwrap();
        let t = stationary(&held(q, m), &opts(20_000)).unwrap();
        let e = s.noise.as_ref().unwrap().errors.unwrap();
        let e2 = |f: f64, x: f64| (x - f).abs();
        for (what, x, y, est) in [
            (
                "<v>",
                s.v_mean,
                t.v_mean,
                e[0] + e2(t.fine.v_mean, t.v_mean),
            ),
            ("<v^2>", s.v2, t.v2, e[1] + e2(t.fine.v2, t.v2)),
            ("D_eff", s.d_eff, t.d_eff, e[2] + e2(t.fine.d_eff, t.d_eff)),
        ] {
            println!("{rule:?} {what}: N-state {x} two-state {y} (est {est:e})");
            assert!((x - y).abs() <= est + 1e-12, "{rule:?} {what}: {x} vs {y}");
        }
        // Exact but for rounding (the two-state solver sums its masses).
        for r in [s.refractory_mass, t.refractory_mass] {
            assert!((r - want).abs() < 1e-12, "{r} vs {want}");
        }
    }
}

/// Run-pause-tumble noise, noise kept or re-drawn, point or uniform
/// target: the held mass is r M/(1 + r M) (the noise does not see the
/// phase: M + q = π, Qᵀπ = 0), and the continuous density is the plain
/// one times 1/(1 + r M) on the same mesh (the re-entry κ q is the plain
/// reset influx r π scaled). A point target at the pause's fixed point
/// reports one atom: the hold plus the pause's scaled atom.
#[test]
fn the_hold_scales_the_plain_density() {
    for (target, rule) in [
        (Target::point(0.0), NoiseAtReset::Kept),
        (Target::point(0.3), NoiseAtReset::Redrawn),
        (Target::uniform(-0.4, 0.6), NoiseAtReset::Kept),
    ] {
        let (r, m) = (2.0, 0.5);
        let plain = noise(RPT, r, 0.0).with_reset(target, rule).unwrap();
        let a = stationary(&plain, &opts(2000)).unwrap();
        let b = stationary(&held(plain.clone(), m), &opts(2000)).unwrap();
        let scale = 1.0 / (1.0 + r * m);
        assert!((b.refractory_mass - r * m * scale).abs() < 1e-14);
        let held = &b.noise.as_ref().unwrap().held;
        let pi = &b.noise.as_ref().unwrap().pi;
        for (q, p) in held.iter().zip(pi) {
            assert!((q - r * m * scale * p).abs() < 1e-15, "{q} vs {p}");
        }
        let top = a.p.iter().fold(0.0f64, |x, &y| x.max(y));
        for (x, y) in a.p.iter().zip(&b.p) {
            assert!(
                (y - scale * x).abs() <= 1e-12 * top,
                "{target:?}: {y} vs {x}"
            );
        }
        if let Some(vr) = plain.reset().point() {
            let plain_atom = a.atoms.first().map_or(0.0, |a| a.mass);
            assert_eq!(b.atoms.len(), 1, "{target:?}");
            assert_eq!(b.atoms[0].v, vr);
            let want = plain_atom * scale + b.refractory_mass;
            assert!((b.atoms[0].mass - want).abs() <= 1e-12, "{target:?}");
        }
    }
}

/// Run-pause-tumble noise with tan drag, r = 2, M = 0.5: `<v²>`, the atom
/// at v = 0 (hold plus pause) and D_eff against the exact sampler.
#[test]
fn the_hold_matches_the_exact_sampler() {
    let p = held(noise(RPT, 2.0, 0.0), 0.5);
    let fp = stationary(&p, &StationaryOptions::default()).unwrap();
    let spec = SimSpec::new(40_000, TimeGrid::linear(60.0, 7).unwrap(), 10.0, 20, 2026).unwrap();
    let s = simulate(&p, &spec, irtp::sim::Method::Exact, &NoProgress)
        .unwrap()
        .summary();
    let z = bonferroni_z(3);
    let atom = s.atoms[0];
    let d = (s.d_eff_msd.unwrap(), s.d_eff_msd_err.unwrap());
    for (what, x, se, want) in [
        ("<v^2>", s.v2, s.v2_err, fp.v2),
        ("atom", atom.mass, atom.err, fp.atoms[0].mass),
        ("D_eff", d.0, d.1, fp.d_eff),
    ] {
        println!("{what}: sampler {x} ± {se}, FP {want}");
        assert!(((x - want) / se).abs() < z, "{what}: {x} ± {se} vs {want}");
    }
}

fn backward(p: &Problem) -> f64 {
    let m = Method::Backward(BackwardOptions::with_cells(20_000));
    mfpt::solve(p, &m, &NoProgress)
        .unwrap()
        .backward()
        .unwrap()
        .tau
}

fn exact(p: &Problem, seed: u64) -> FptSummary {
    let m = Method::Exact(ParticleOptions {
        particles: 100_000,
        t_max: f64::INFINITY,
        seed,
    });
    mfpt::solve(p, &m, &NoProgress).unwrap().summary().unwrap()
}

/// The paper's noise spelt as a generator with a refractory period: the
/// N-state backward τ agrees with the two-state (R6) to 1e-9, point and
/// uniform targets, noise kept and re-drawn.
#[test]
fn backward_paper_as_states_with_a_hold_matches_the_two_state_solver() {
    for (target, rule) in [
        (Target::point(0.0), NoiseAtReset::Kept),
        (Target::point(0.0), NoiseAtReset::Redrawn),
        (Target::uniform(-0.3, 0.4), NoiseAtReset::Kept),
    ] {
        let chain = noise(PAPER_AS_STATES, 1.0, 0.0).with_reset(target, rule);
        let two = Params::new(DragLaw::Tan, 1.0, 0.5, 1.0, 0.0).unwrap();
        let two = two.with_reset(target, rule).unwrap();
        let n = backward(&Problem::new(held(chain.unwrap(), 0.5), 0.1, 0.5).unwrap());
        let t = backward(&Problem::new(held(two, 0.5), 0.1, 0.5).unwrap());
        let rel = (n - t).abs() / t;
        println!("{target:?} {rule:?}: N-state {n} two-state {t} rel {rel:e}");
        assert!(rel < 1e-9, "{target:?} {rule:?}: {n} vs {t}");
    }
}

/// With the noise re-drawn at a reset the hold only adds its duration to
/// each reset: τ = (1 + r M) τ_plain (the discrete system's right side
/// scales so, to rounding).
#[test]
fn backward_redrawn_hold_scales_tau() {
    let (r, m) = (2.0, 0.5);
    let plain = noise(RPT, r, 0.0)
        .with_reset(Target::point(0.0), NoiseAtReset::Redrawn)
        .unwrap();
    let a = backward(&Problem::new(plain.clone(), 0.0, 0.5).unwrap());
    let b = backward(&Problem::new(held(plain, m), 0.0, 0.5).unwrap());
    let want = (1.0 + r * m) * a;
    assert!((b - want).abs() <= 1e-12 * want, "{b} vs {want}");
}

/// Run-pause-tumble noise with a hold, point and uniform targets: τ
/// against the exact sampler.
#[test]
fn backward_hold_matches_the_exact_sampler() {
    let z = bonferroni_z(2);
    for (k, target) in [Target::point(0.0), Target::uniform(-0.3, 0.4)]
        .into_iter()
        .enumerate()
    {
        let p = noise(RPT, 2.0, 0.0)
            .with_reset(target, NoiseAtReset::Kept)
            .unwrap();
        let prob = Problem::new(held(p, 0.5), 0.0, 0.5).unwrap();
        let (t, s) = (backward(&prob), exact(&prob, 310 + k as u64));
        println!("{target:?}: backward {t}, exact {} ± {}", s.tau, s.tau_err);
        assert!(((s.tau - t) / s.tau_err).abs() < z, "{target:?}");
    }
}
