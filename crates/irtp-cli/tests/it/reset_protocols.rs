//! Resetting protocols beyond the paper's (point target, noise kept) in every
//! method: the noise state re-drawn at a reset (±Sigma with probability ½),
//! and resets to a random velocity (Gaussian truncated to the velocity
//! interval, uniform on [a, b]).
//!
//! - linear drag: the closed forms (`<v>`, `<v²>`, D_eff, `<x²>(t)`) against
//!   the Fokker-Planck solvers (stationary, moment chain) to 1e-8 and
//!   against the exact sampler (4 SE, Bonferroni over the comparisons);
//! - tan drag: the FP stationary density against the sampler's histogram
//!   (z per bin, Bonferroni);
//! - first passage: backward equations (box scheme) and the time-dependent
//!   upwind survival equations against the exact first-passage sampler
//!   (4 SE, Bonferroni);
//! - random targets: closed forms vs FP and vs the exact sampler, the FP
//!   density vs the sampler's histogram (tan), the backward MFPT vs the
//!   exact sampler (the distribution, moments and optimize with random
//!   targets: `random_target_fpt.rs`);
//! - the CLI: flags, provenance spec, one-line errors naming the flag.

use crate::common;
use crate::common::stats::bonferroni_z;
use irtp::analytic::{linear, linear_moments};
use irtp::fp::{msd as fp_moments, stationary, Mesh, MsdOptions, StationaryOptions};
use irtp::mfpt::{self, BackwardOptions, DistributionOptions, Method, ParticleOptions, Problem};
use irtp::model::reset::{NoiseAtReset, Reset, Target};
use irtp::parallel::NoProgress;
use irtp::sim::{simulate, Method as SimMethod, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};

fn redrawn(drag: DragLaw, sigma: f64, lambda: f64, r: f64, vr: f64) -> Params {
    Params::new(drag, sigma, lambda, r, vr)
        .unwrap()
        .with_reset(Target::point(vr), NoiseAtReset::Redrawn)
        .unwrap()
}

/// Relative difference, on the scale 0.1 for quantities near 0 (`<v>`).
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(0.1)
}

#[test]
fn redrawn_rule_is_recorded_and_mirrors() {
    let p = redrawn(DragLaw::Linear, 1.0, 0.5, 2.0, 0.2);
    assert_eq!(p.reset().noise(), NoiseAtReset::Redrawn);
    assert_eq!(p.reset_spec().as_deref(), Some("point:v=0.2,noise=redrawn"));
    let json = serde_json::to_string(&p).unwrap();
    assert!(
        json.contains("\"reset\":\"point:v=0.2,noise=redrawn\""),
        "{json}"
    );
    let back: Params = serde_json::from_str(&json).unwrap();
    assert_eq!(back, p);
    let m = p.mirrored_reset();
    assert_eq!(m.reset_velocity(), -0.2);
    assert_eq!(m.reset().noise(), NoiseAtReset::Redrawn);
    let q = p.with_rate(0.7).unwrap();
    assert_eq!((q.rate(), q.reset().noise()), (0.7, NoiseAtReset::Redrawn));
    // The paper's protocol writes no spec: provenance stays as it was.
    let k = Params::new(DragLaw::Linear, 1.0, 0.5, 2.0, 0.2).unwrap();
    assert!(k.reset_spec().is_none());
    assert!(!serde_json::to_string(&k).unwrap().contains("reset\""));
}

/// Closed forms vs FP (stationary + moment chain), linear drag.
#[test]
#[ignore = "slow tier"]
fn redrawn_linear_closed_forms_match_fokker_planck() {
    for (s, l, r, vr) in [(1.0, 0.5, 2.0, 0.2), (1.5, 0.3, 0.7, 0.0)] {
        let p = redrawn(DragLaw::Linear, s, l, r, vr);
        let fp = stationary(&p, &StationaryOptions::default()).unwrap();
        let (m, v2, d) = (
            linear::v_mean(&p).unwrap(),
            linear::v2(&p).unwrap(),
            linear::d_eff(&p).unwrap(),
        );
        eprintln!(
            "linear s={s} l={l} r={r} vr={vr}: <v> {m} vs {}, <v2> {v2} vs {}, D {d} vs {}",
            fp.v_mean, fp.v2, fp.d_eff
        );
        assert!(rel(fp.v_mean, m) < 1e-8);
        assert!(rel(fp.v2, v2) < 1e-8);
        assert!(rel(fp.d_eff, d) < 1e-8);
        // D_eff differs from the kept rule's: the check discriminates.
        let kept = Params::new(DragLaw::Linear, s, l, r, vr).unwrap();
        assert!(rel(linear::d_eff(&kept).unwrap(), d) > 0.05);

        let times = vec![0.0, 0.5, 2.0, 8.0];
        let exact = linear_moments::moments(&p, &times).unwrap();
        // Graded mesh: v_r is a node on every level.
        let o = MsdOptions {
            cells: 100,
            mesh: Mesh::Graded,
            levels: 3,
            times: times.clone(),
            rtol: 1e-9,
        };
        let chain = fp_moments(&p, &o, &NoProgress).unwrap();
        for (k, t) in times.iter().enumerate().skip(1) {
            eprintln!("  t={t}: <x2> {} vs {}", exact.x2[k], chain.x2[k]);
            assert!(rel(chain.x2[k], exact.x2[k]) < 1e-6, "t = {t}");
            assert!(rel(chain.xv[k], exact.xv[k]) < 1e-6, "t = {t}");
        }
    }
}

/// Closed forms vs the exact and the Euler samplers: `<x²>(t)` (where the
/// re-drawn noise acts), `<v>`, `<v²>` time averages.
#[test]
fn redrawn_linear_closed_forms_match_samplers() {
    let p = redrawn(DragLaw::Linear, 1.0, 0.5, 2.0, 0.2);
    let grid = TimeGrid::linear(6.0, 4).unwrap();
    let exact = linear_moments::moments(&p, grid.times()).unwrap();
    let kept = linear_moments::moments(
        &Params::new(DragLaw::Linear, 1.0, 0.5, 2.0, 0.2).unwrap(),
        grid.times(),
    )
    .unwrap();
    let spec = SimSpec::new(40_000, grid.clone(), 2.0, 10, 4242).unwrap();
    let methods = [SimMethod::Exact, SimMethod::euler(1e-3)];
    let z = bonferroni_z(2 * (grid.times().len() - 1 + 2));
    for method in methods {
        let obs = simulate(&p, &spec, method, &NoProgress).unwrap();
        // Euler's O(dt) bias, relative: a few dt.
        let bias = if matches!(method, SimMethod::Exact) {
            0.0
        } else {
            5e-3
        };
        for k in 1..obs.times.len() {
            let (mean, se) = (obs.x2[k].mean(), obs.x2[k].sem());
            let dev = (mean - exact.x2[k]).abs() - bias * exact.x2[k];
            eprintln!(
                "{method:?} t={}: <x2> sim {mean} ± {se}, redrawn {}, kept {}",
                obs.times[k], exact.x2[k], kept.x2[k]
            );
            assert!(
                dev < z * se,
                "t = {}: {mean} ± {se} vs {}",
                obs.times[k],
                exact.x2[k]
            );
        }
        let s = obs.summary();
        let (m, v2) = (linear::v_mean(&p).unwrap(), linear::v2(&p).unwrap());
        assert!((s.v_mean - m).abs() - bias * m.abs() < z * s.v_mean_err);
        assert!((s.v2 - v2).abs() - bias * v2 < z * s.v2_err);
    }
    // The kept rule's <x²> is far outside the error bars at the last time.
    let last = grid.times().len() - 1;
    assert!(rel(kept.x2[last], exact.x2[last]) > 0.05);
}

/// tan drag: FP stationary density vs the exact sampler's histogram.
#[test]
fn redrawn_tan_density_matches_sampler_histogram() {
    const BINS: usize = 20;
    let p = redrawn(DragLaw::Tan, 3.0, 0.9, 1.0, 0.3);
    let fine = stationary(
        &p,
        &StationaryOptions {
            cells: BINS * 200,
            mesh: Mesh::Uniform,
            extrapolate: false,
        },
    )
    .unwrap();
    let spec = SimSpec::new(20_000, TimeGrid::linear(10.0, 2).unwrap(), 3.0, BINS, 777).unwrap();
    let obs = simulate(&p, &spec, SimMethod::Exact, &NoProgress).unwrap();
    let m = fine.cell_masses();
    let bw = obs.bin_width();
    let rows = obs.density_rows();
    let compared: Vec<(f64, f64, f64)> = rows
        .iter()
        .enumerate()
        .map(|(b, row)| {
            (
                m[b * 200..(b + 1) * 200].iter().sum(),
                row[1] * bw,
                row[2] * bw,
            )
        })
        .filter(|&(fp, _, _)| fp >= 1e-3)
        .collect();
    let z = bonferroni_z(compared.len());
    for (fp, sim, se) in compared {
        assert!(
            ((sim - fp) / se).abs() < z,
            "bin: FP {fp} vs sim {sim} ± {se}"
        );
    }
}

/// Backward equations and the time-dependent survival equations vs the
/// exact first-passage sampler, noise re-drawn.
#[test]
fn redrawn_first_passage_matches_exact_sampler() {
    let cases = [
        (DragLaw::Tan, 3.0, 0.9, 2.0, 0.0, -0.249, 0.5),
        (DragLaw::Tanh, 0.6, 1.2, 2.0, 0.1, -0.249, 0.3),
        (DragLaw::Tan, 3.0, 0.9, 1.0, 0.2, 0.4, -0.3), // downward (mirror frame)
    ];
    let z = bonferroni_z(3 * cases.len());
    for (i, (d, s, l, r, vr, v0, vt)) in cases.into_iter().enumerate() {
        let p = redrawn(d.clone(), s, l, r, vr);
        let prob = Problem::new(p, v0, vt).unwrap();
        let ode = mfpt::backward::solve(&prob, &Default::default()).unwrap();
        let run = ParticleOptions {
            particles: 16_000,
            t_max: f64::INFINITY,
            seed: 900 + i as u64,
        };
        let sim = mfpt::solve(&prob, &Method::Exact(run), &NoProgress)
            .unwrap()
            .summary()
            .unwrap();
        let dist = mfpt::distribution(
            &prob,
            &[0.5, 1.0],
            &DistributionOptions {
                backward: BackwardOptions::with_cells(4000),
                ..DistributionOptions::default()
            },
        )
        .unwrap();
        eprintln!(
            "{d} r={r} vr={vr} {v0}->{vt}: backward {} (+ {}, - {}), distribution {}, exact {} ± {} (+ {} ± {}, - {} ± {})",
            ode.tau, ode.tau_plus, ode.tau_minus, dist.mean, sim.tau, sim.tau_err,
            sim.tau_plus, sim.tau_plus_err, sim.tau_minus, sim.tau_minus_err
        );
        assert!(((sim.tau_plus - ode.tau_plus) / sim.tau_plus_err).abs() < z);
        assert!(((sim.tau_minus - ode.tau_minus) / sim.tau_minus_err).abs() < z);
        assert!(((sim.tau - dist.mean) / sim.tau_err).abs() < z);
        if i == 0 {
            // The kept rule gives another tau, far outside these error bars.
            let kept = Problem::new(Params::new(d, s, l, r, vr).unwrap(), v0, vt).unwrap();
            let k = mfpt::backward::solve(&kept, &Default::default()).unwrap();
            assert!(
                ((sim.tau - k.tau) / sim.tau_err).abs() > 8.0,
                "kept {}",
                k.tau
            );
        }
    }
}

// ---- CLI -------------------------------------------------------------

#[test]
fn cli_records_the_protocol_and_refuses_bad_specs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fp");
    let o = common::irtp(&[
        "fp",
        "stationary",
        "--drag",
        "linear",
        "--sigma",
        "1",
        "--reset-noise",
        "redrawn",
        "--reset-velocity",
        "0.2",
        "--cells",
        "2000",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    common::assert_success(&o);
    let run = common::read_json(&out.join("run.json"));
    let text = run.to_string();
    assert!(
        text.contains("\"reset\":\"point:v=0.2,noise=redrawn\""),
        "{text}"
    );
    // The same protocol through the spec.
    let o2 = common::irtp(&[
        "fp",
        "stationary",
        "--drag",
        "linear",
        "--sigma",
        "1",
        "--reset-to",
        "point:v=0.2,noise=redrawn",
        "--cells",
        "2000",
        "--json",
    ]);
    common::assert_success(&o2);
    let (a, b) = (common::summary(&o), common::summary(&o2));
    assert_eq!(a["results"]["d_eff"], b["results"]["d_eff"]);
    // Default protocol: no reset spec anywhere.
    let o3 = common::irtp(&["fp", "stationary", "--cells", "2000", "--json"]);
    assert!(!String::from_utf8_lossy(&o3.stdout).contains("\"reset\""));

    for (args, flag) in [
        (vec!["--reset-noise", "maybe"], "--reset-noise"),
        (vec!["--reset-to", "point:v=9"], "--reset-to"),
        (vec!["--reset-to", "point:v=nan"], "--reset-to"),
        (vec!["--reset-to", "dirac:v=0"], "--reset-to"),
        (
            vec![
                "--reset-to",
                "point:v=0,noise=kept",
                "--reset-noise",
                "redrawn",
            ],
            "--reset-noise",
        ),
    ] {
        for cmd in [
            vec!["simulate"],
            vec!["fp", "stationary"],
            vec!["mfpt", "--v0", "-0.249", "--vt", "0.5"],
        ] {
            let empty = tempfile::tempdir().unwrap();
            let bad = empty.path().join("out");
            let mut all: Vec<&str> = cmd.clone();
            all.extend(&args);
            all.extend(["--out", bad.to_str().unwrap()]);
            let o = common::irtp(&all);
            common::assert_rejected(&o, flag, &bad);
        }
    }
}

// ---- random targets ----------------------------------------------------

fn with_target(
    drag: DragLaw,
    sigma: f64,
    lambda: f64,
    r: f64,
    t: Target,
    n: NoiseAtReset,
) -> Params {
    Params::new(drag, sigma, lambda, r, 0.0)
        .unwrap()
        .with_reset(t, n)
        .unwrap()
}

fn gauss(mean: f64, std: f64) -> Target {
    Target::gauss(mean, std)
}

/// Truncated Gaussian moments: the untruncated limit, and a strongly
/// truncated case against composite Simpson on 2e5 panels.
#[test]
fn truncated_gaussian_moments_are_exact() {
    let p = with_target(
        DragLaw::Linear,
        1.0,
        0.5,
        1.0,
        gauss(0.2, 0.01),
        NoiseAtReset::Kept,
    );
    let (m1, m2) = p.reset().target().moments();
    assert!(
        (m1 - 0.2).abs() < 1e-15 && (m2 - 0.0401).abs() < 1e-15,
        "{m1} {m2}"
    );
    let p = with_target(
        DragLaw::Linear,
        1.0,
        0.5,
        1.0,
        gauss(0.7, 0.6),
        NoiseAtReset::Kept,
    );
    let (m1, m2) = p.reset().target().moments();
    let n = 200_000;
    let h = 2.0 / n as f64;
    let (mut z, mut s1, mut s2) = (0.0, 0.0, 0.0);
    for k in 0..=n {
        let v = -1.0 + k as f64 * h;
        let w = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let f = w * (-0.5 * ((v - 0.7) / 0.6f64).powi(2)).exp();
        (z, s1, s2) = (z + f, s1 + f * v, s2 + f * v * v);
    }
    eprintln!("truncated: {m1} vs {}, {m2} vs {}", s1 / z, s2 / z);
    assert!(rel(m1, s1 / z) < 1e-12 && rel(m2, s2 / z) < 1e-12);
}

fn random_cases() -> Vec<(Target, NoiseAtReset)> {
    vec![
        (gauss(0.1, 0.3), NoiseAtReset::Kept),
        (gauss(0.1, 0.3), NoiseAtReset::Redrawn),
        (gauss(-0.6, 0.8), NoiseAtReset::Kept),
        (Target::uniform(-0.5, 0.2), NoiseAtReset::Kept),
        (Target::uniform(-0.5, 0.2), NoiseAtReset::Redrawn),
    ]
}

/// Linear drag: closed forms from the target's moments vs the FP solver.
#[test]
fn random_targets_linear_closed_forms_match_fokker_planck() {
    for (t, n) in random_cases() {
        let p = with_target(DragLaw::Linear, 1.0, 0.5, 2.0, t, n);
        let fp = stationary(&p, &StationaryOptions::default()).unwrap();
        let (m, v2, d) = (
            linear::v_mean(&p).unwrap(),
            linear::v2(&p).unwrap(),
            linear::d_eff(&p).unwrap(),
        );
        eprintln!(
            "{}: <v> {m} vs {}, <v2> {v2} vs {}, D {d} vs {}",
            p.reset_spec().unwrap(),
            fp.v_mean,
            fp.v2,
            fp.d_eff
        );
        assert!(rel(fp.v_mean, m) < 1e-8);
        // <v²> by cell-centre quadrature on the default mesh: 1.3e-8 for
        // the uniform target (9e-9 for a point target).
        assert!(rel(fp.v2, v2) < 3e-8);
        assert!(rel(fp.d_eff, d) < 1e-8);
    }
}

/// Linear drag: closed forms vs the exact sampler (<x²>(t), <v>, <v²>).
#[test]
fn random_targets_linear_closed_forms_match_exact_sampler() {
    let grid = TimeGrid::linear(6.0, 4).unwrap();
    let cases = random_cases();
    let z = bonferroni_z(cases.len() * (grid.len() - 1 + 2));
    for (i, (t, n)) in cases.into_iter().enumerate() {
        let p = with_target(DragLaw::Linear, 1.0, 0.5, 2.0, t, n);
        let exact = linear_moments::moments(&p, grid.times()).unwrap();
        let spec = SimSpec::new(20_000, grid.clone(), 2.0, 10, 5150 + i as u64).unwrap();
        let obs = simulate(&p, &spec, SimMethod::Exact, &NoProgress).unwrap();
        for k in 1..obs.times.len() {
            let (mean, se) = (obs.x2[k].mean(), obs.x2[k].sem());
            assert!(
                ((mean - exact.x2[k]) / se).abs() < z,
                "{:?} t = {}: {mean} ± {se} vs {}",
                p.reset_spec(),
                obs.times[k],
                exact.x2[k]
            );
        }
        let s = obs.summary();
        let (m, v2) = (linear::v_mean(&p).unwrap(), linear::v2(&p).unwrap());
        eprintln!(
            "{}: <v> {} ± {} vs {m}, <v2> {} ± {} vs {v2}",
            p.reset_spec().unwrap(),
            s.v_mean,
            s.v_mean_err,
            s.v2,
            s.v2_err
        );
        assert!(((s.v_mean - m) / s.v_mean_err).abs() < z);
        assert!(((s.v2 - v2) / s.v2_err).abs() < z);
    }
}

/// tan drag, Gaussian target: FP density vs the exact sampler's histogram.
#[test]
fn random_target_tan_density_matches_sampler_histogram() {
    const BINS: usize = 20;
    let p = with_target(
        DragLaw::Tan,
        3.0,
        0.9,
        2.0,
        gauss(0.3, 0.25),
        NoiseAtReset::Kept,
    );
    let fine = stationary(
        &p,
        &StationaryOptions {
            cells: BINS * 200,
            mesh: Mesh::Uniform,
            extrapolate: false,
        },
    )
    .unwrap();
    let spec = SimSpec::new(20_000, TimeGrid::linear(10.0, 2).unwrap(), 3.0, BINS, 4711).unwrap();
    let obs = simulate(&p, &spec, SimMethod::Exact, &NoProgress).unwrap();
    let m = fine.cell_masses();
    let bw = obs.bin_width();
    let compared: Vec<(f64, f64, f64)> = obs
        .density_rows()
        .iter()
        .enumerate()
        .map(|(b, row)| {
            (
                m[b * 200..(b + 1) * 200].iter().sum(),
                row[1] * bw,
                row[2] * bw,
            )
        })
        .filter(|&(fp, _, _)| fp >= 1e-3)
        .collect();
    let z = bonferroni_z(compared.len() + 1);
    for (fp, sim, se) in compared {
        assert!(
            ((sim - fp) / se).abs() < z,
            "bin: FP {fp} vs sim {sim} ± {se}"
        );
    }
    let s = obs.summary();
    let fp = stationary(&p, &StationaryOptions::default()).unwrap();
    eprintln!(
        "tan gauss: <v2> FP {} vs sim {} ± {}",
        fp.v2, s.v2, s.v2_err
    );
    assert!(((s.v2 - fp.v2) / s.v2_err).abs() < z);
}

/// Backward equations (the dense rank-one reset term in bordered form)
/// vs the exact first-passage sampler for random targets, a uniform one
/// reaching beyond v_t (a reset there is the passage) included.
#[test]
fn random_target_backward_mfpt_matches_exact_sampler() {
    let cases = [
        (gauss(0.0, 0.2), NoiseAtReset::Kept),
        (gauss(0.0, 0.2), NoiseAtReset::Redrawn),
        (Target::uniform(-0.5, 0.7), NoiseAtReset::Kept),
    ];
    let z = bonferroni_z(3 * cases.len());
    for (i, (t, n)) in cases.into_iter().enumerate() {
        let p = with_target(DragLaw::Tan, 3.0, 0.9, 2.0, t, n);
        let prob = Problem::new(p.clone(), -0.249, 0.5).unwrap();
        let ode = mfpt::backward::solve(&prob, &BackwardOptions::with_cells(4000)).unwrap();
        let run = ParticleOptions {
            particles: 40_000,
            t_max: f64::INFINITY,
            seed: 70 + i as u64,
        };
        let sim = mfpt::solve(&prob, &Method::Exact(run), &NoProgress)
            .unwrap()
            .summary()
            .unwrap();
        eprintln!(
            "{}: backward {} (+ {}, - {}), exact {} ± {}",
            p.reset_spec().unwrap(),
            ode.tau,
            ode.tau_plus,
            ode.tau_minus,
            sim.tau,
            sim.tau_err
        );
        assert!(((sim.tau - ode.tau) / sim.tau_err).abs() < z);
        assert!(((sim.tau_plus - ode.tau_plus) / sim.tau_plus_err).abs() < z);
        assert!(((sim.tau_minus - ode.tau_minus) / sim.tau_minus_err).abs() < z);
    }
}
