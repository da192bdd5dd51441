//! Euler particle simulation (paper Eqs. (30)-(32)): exactness against the
//! exactly solvable Euler chain for linear drag, convergence to the continuum
//! formulas, equivalence of the two event samplers, reproducibility.

use crate::common::models;
use irtp::analytic::linear;
use irtp::analytic::r0::R0Density;
use irtp::parallel::NoProgress;
use irtp::sim::euler::{self, EulerPlan, EventSampling, LinearChain};
use irtp::sim::{simulate, Method, Observables, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};

fn spec(
    particles: u64,
    t_max: f64,
    samples: usize,
    burn_in: f64,
    bins: usize,
    seed: u64,
) -> SimSpec {
    SimSpec::new(
        particles,
        TimeGrid::linear(t_max, samples).unwrap(),
        burn_in,
        bins,
        seed,
    )
    .unwrap()
}

fn z(a: f64, b: f64, se: f64) -> f64 {
    (a - b).abs() / se
}

/// Linear drag: the simulation against the EXACT moments of the Euler chain
/// (no discretisation bias at all), at dt = 1e-3, for several (lambda, r, v_r)
/// including r = 0, r = 10 and v_r != 0. Checked: the window-averaged <v²>
/// (the summary's v2) and E v², E x² at every 4th recording time, each within
/// 4 standard errors (fixed seeds).
#[test]
fn linear_drag_matches_exact_euler_chain() {
    let dt = 1e-3;
    let cases = [
        (1.0, 0.0, 0.0),
        (0.5, 2.0, 0.0),
        (2.0, 10.0, 0.0),
        (0.7, 3.0, 0.6),
    ];
    for (i, &(lambda, r, vr)) in cases.iter().enumerate() {
        let p = models::linear(1.0, lambda, r, vr);
        let s = spec(8000, 4.0, 9, 1.5, 10, 100 + i as u64);
        let obs = simulate(&p, &s, Method::euler(dt), &NoProgress).unwrap();
        let plan = EulerPlan::new(&p, &s, dt).unwrap();
        let (v2_window, at) = euler::linear_chain_expectations(&p, &plan).unwrap();
        let sum = obs.summary();
        assert!(
            z(sum.v2, v2_window, sum.v2_err) < 4.0,
            "case {i}: window <v²> {} ± {} vs exact chain {v2_window}",
            sum.v2,
            sum.v2_err
        );
        for k in (1..at.len()).step_by(2) {
            let (v2k, x2k) = (&obs.v2[k], &obs.x2[k]);
            assert!(
                z(v2k.mean(), at[k].v2, v2k.sem()) < 4.0,
                "case {i} t={}: <v²> {} ± {} vs {}",
                obs.times[k],
                v2k.mean(),
                v2k.sem(),
                at[k].v2
            );
            assert!(
                z(x2k.mean(), at[k].x2, x2k.sem()) < 4.0,
                "case {i} t={}: <x²> {} ± {} vs {}",
                obs.times[k],
                x2k.mean(),
                x2k.sem(),
                at[k].x2
            );
            assert!(z(obs.v[k].mean(), at[k].v, obs.v[k].sem()) < 4.0);
        }
    }
}

/// Deterministic: the Euler chain's stationary moments converge to the exact
/// continuum formulas (analytic::linear) at first order in dt.
#[test]
fn euler_chain_converges_to_continuum() {
    for &(lambda, r, vr) in &[
        (1.0, 0.0, 0.0),
        (0.5, 2.0, 0.0),
        (2.0, 10.0, 0.0),
        (0.7, 3.0, 0.6),
    ] {
        let p = models::linear(1.3, lambda, r, vr);
        let exact = linear::v2(&p).unwrap();
        let err = |dt: f64| LinearChain::stationary(&p, dt).unwrap().v2 - exact;
        let (e1, e2, e3) = (err(1e-3), err(1e-4), err(1e-5));
        // First order: the error shrinks ~10x per decade of dt.
        for (a, b) in [(e1, e2), (e2, e3)] {
            let ratio = a / b;
            assert!((9.0..11.0).contains(&ratio), "{lambda} {r}: ratio {ratio}");
        }
        assert!((e2 / exact).abs() < 2e-3, "{e2}");
        let vm = LinearChain::stationary(&p, 1e-7).unwrap();
        assert!((vm.v - linear::v_mean(&p).unwrap()).abs() < 1e-5);
        assert!((vm.v_eta - linear::v_eta(&p).unwrap()).abs() < 1e-5);
        assert!((vm.v2 - exact).abs() < 1e-5 * exact);
    }
}

/// Geometric waiting times vs the paper's per-step Bernoulli draws: the same
/// process in distribution. Independent seeds; every compared estimate within
/// 4 combined standard errors, and a two-sample chi-square on the final
/// velocity histogram.
#[test]
fn geometric_and_bernoulli_samplers_agree() {
    let p = models::medium(DragLaw::Tan, 0.5, 2.0, 0.2);
    let s1 = spec(4000, 3.0, 4, 1.0, 12, 11);
    let s2 = spec(4000, 3.0, 4, 1.0, 12, 12);
    let a = euler::simulate_with(&p, &s1, 1e-3, EventSampling::Geometric, &NoProgress).unwrap();
    let b = euler::simulate_with(&p, &s2, 1e-3, EventSampling::Bernoulli, &NoProgress).unwrap();
    let cmp = |name: &str, x: &irtp::stats::MeanAcc, y: &irtp::stats::MeanAcc| {
        let se = (x.sem().powi(2) + y.sem().powi(2)).sqrt();
        assert!(
            z(x.mean(), y.mean(), se) < 4.0,
            "{name}: {} vs {} (se {se})",
            x.mean(),
            y.mean()
        );
    };
    cmp("v time avg", &a.v_time_avg, &b.v_time_avg);
    cmp("v2 time avg", &a.v2_time_avg, &b.v2_time_avg);
    for k in 1..a.times.len() {
        cmp("v", &a.v[k], &b.v[k]);
        cmp("v2", &a.v2[k], &b.v2[k]);
        cmp("x2", &a.x2[k], &b.x2[k]);
    }
    // Two-sample chi-square on final-velocity counts (independent particles).
    let w = a.bin_width();
    let (na, nb) = (a.particles() as f64, b.particles() as f64);
    let mut chi2 = 0.0;
    let mut dof = 0;
    for bin in 0..a.density_final.len() {
        let ca = a.density_final[bin].sum * w;
        let cb = b.density_final[bin].sum * w;
        if ca + cb > 0.0 {
            let d = ca * (nb / na).sqrt() - cb * (na / nb).sqrt();
            chi2 += d * d / (ca + cb);
            dof += 1;
        }
    }
    let dof = (dof - 1) as f64;
    // Wilson-Hilferty: chi2 above mean + 4 sd of its normal approximation.
    let lim = dof * (1.0 - 2.0 / (9.0 * dof) + 4.0 * (2.0 / (9.0 * dof)).sqrt()).powi(3);
    assert!(chi2 < lim, "chi2 {chi2} dof {dof} limit {lim}");
}

fn bits(o: &Observables) -> String {
    serde_json::to_string(o).unwrap()
}

/// Bit-identical output for 1 and 2 rayon threads (all fields, both samplers).
#[test]
fn bit_identical_across_thread_counts() {
    let p = models::medium(DragLaw::Tanh, 0.85, 1.0, 0.1);
    let s = spec(700, 1.0, 5, 0.5, 16, 3);
    for sampling in [EventSampling::Geometric, EventSampling::Bernoulli] {
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| euler::simulate_with(&p, &s, 1e-3, sampling, &NoProgress).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a.summary().v2.to_bits(), b.summary().v2.to_bits());
        assert_eq!(a.particles(), 700);
        assert_eq!(a.steps, 700 * 1000);
    }
}

/// Value stability: a fixed seed gives pinned outputs. Changing the stream
/// derivation, the chunking, the step order or the sampler changes these.
#[test]
fn pinned_values() {
    let p = models::tan(0.5, 2.0);
    let s = spec(300, 0.5, 3, 0.25, 8, 42);
    let g = simulate(&p, &s, Method::euler(1e-3), &NoProgress).unwrap();
    let b = euler::simulate_with(&p, &s, 1e-3, EventSampling::Bernoulli, &NoProgress).unwrap();
    let got = [
        g.summary().v2,
        g.summary().x2_final,
        g.v[1].mean(),
        b.summary().v2,
        b.summary().x2_final,
        b.v[1].mean(),
    ];
    let pinned: [u64; 6] = PINNED;
    for (i, (x, want)) in got.iter().zip(pinned).enumerate() {
        assert_eq!(x.to_bits(), want, "value {i}: {x:e} = {:#x}", x.to_bits());
    }
}
const PINNED: [u64; 6] = [
    0x3fde5cc759c67122,
    0x3fabc34ee89963b1,
    0x3f8833342b8f46f2,
    0x3fdcf4dfd752d96c,
    0x3faad990a879bf7f,
    0xbf93f5be25f7139a,
];

/// Grid handling: times are recorded at round(t/dt) and reported as n·dt,
/// times on one step are recorded once; a burn-in at t_max, dt above the
/// stability or reset limit are rejected naming the flag.
#[test]
fn plan_validation_and_rounding() {
    let p = models::tan(0.5, 2.0);
    let s = SimSpec::new(
        10,
        TimeGrid::from_times(vec![0.0, 0.00149, 0.0031, 1.0]).unwrap(),
        0.5,
        4,
        1,
    )
    .unwrap();
    let plan = EulerPlan::new(&p, &s, 1e-3).unwrap();
    assert_eq!(plan.record_steps, vec![0, 1, 3, 1000]);
    assert_eq!(plan.steps, 1000);
    assert_eq!(plan.burn_in_step, 500);
    let obs = simulate(&p, &s, Method::euler(1e-3), &NoProgress).unwrap();
    assert_eq!(obs.times, vec![0.0, 1e-3, 3e-3, 1.0]);
    assert_eq!(obs.v[0].mean(), 0.0);
    assert_eq!(obs.x[1].mean(), 0.0); // x moves only from step 2 on (v_0 = 0)

    let name = |e: irtp::Error| e.parameter().unwrap_or_else(|| panic!("{e}"));
    let close = SimSpec::new(
        10,
        TimeGrid::from_times(vec![0.0, 0.0101, 0.0104, 1.0]).unwrap(),
        0.5,
        4,
        1,
    )
    .unwrap();
    // Times on the same step are recorded once.
    let plan = EulerPlan::new(&p, &close, 1e-3).unwrap();
    assert_eq!(plan.record_steps, vec![0, 10, 1000]);
    let obs = simulate(&p, &close, Method::euler(1e-3), &NoProgress).unwrap();
    assert_eq!(obs.times, vec![0.0, 0.01, 1.0]);
    assert_eq!(obs.moment_rows().len(), 3);
    assert_eq!(obs.v2[2].n, 10);
    let late = spec(10, 1.0, 3, 0.9999, 4, 1);
    assert_eq!(
        name(EulerPlan::new(&p, &late, 1e-3).unwrap_err()),
        "burn_in"
    );
    let ok = spec(10, 1.0, 3, 0.5, 4, 1);
    assert_eq!(name(EulerPlan::new(&p, &ok, 0.1).unwrap_err()), "dt");
    let fast = models::linear(1.0, 0.5, 20.0, 0.0);
    assert_eq!(name(EulerPlan::new(&fast, &ok, 0.06).unwrap_err()), "dt");
    assert!(EulerPlan::new(&fast, &ok, 0.04).is_ok());
}

/// Lanes (particles integrated side by side) change no trajectory and no
/// summation order: every output is bit-identical to the one-lane kernel
/// (several reduction chunks, a short last chunk, a remainder group).
#[test]
fn lanes_do_not_change_results() {
    for (drag, sigma) in [
        (DragLaw::Tan, 3.0),
        (DragLaw::Tanh, 0.6),
        (DragLaw::Linear, 1.0),
    ] {
        let p = Params::new(drag.clone(), sigma, 0.9, 1.5, 0.05).unwrap();
        let s = spec(605, 0.3, 5, 0.1, 9, 8);
        for sampling in [EventSampling::Geometric, EventSampling::Bernoulli] {
            let one = euler::simulate_with_lanes(&p, &s, 1e-3, sampling, 1, &NoProgress).unwrap();
            let four =
                euler::simulate_with_lanes(&p, &s, 1e-3, sampling, euler::LANES, &NoProgress)
                    .unwrap();
            assert_eq!(bits(&one), bits(&four), "{drag} {sampling:?}");
        }
    }
}

/// r = 0: the Euler simulation against the exact stationary densities, for
/// tanh Sigma = 0.6 lambda = 0.85 (paper Fig. 3b, two maxima) and tan Sigma = 3
/// lambda = 15 (Fig. 2c, cusp-like zero at the edges). 8000 particles,
/// t_max = 15, window [5, 15], 20 bins, dt = 1e-3. Reference: the exact
/// [`R0Density`] (paper Eqs. (34)-(35); its bin masses agree with an
/// independent midpoint-rule integration of the closed forms to 1.2e-6
/// relative, <v²> to 2e-7).
/// - Ensemble snapshot at t_max (independent particles, multinomial counts;
///   bins with expected count < 5 pooled): chi-square below its 1 - 1e-4
///   quantile (Wilson-Hilferty, z = 3.719).
/// - Time-averaged density: every bin within the Bonferroni-corrected
///   two-sided threshold for overall alpha = 1e-4 over 20 bins,
///   |z| < Φ⁻¹(1 - 1e-4/40) = 4.565.
/// - Time-averaged <v²> within 4 SE.
///
/// Euler bias: runs of 40000 particles at dt = 1e-3 and 5e-4 (same seeds)
/// differ by <= 0.3% in any bin and 0.015% in <v²>, while the per-bin SE here
/// is >= 1.5% and the <v²> SE 0.4%: the O(dt) bias is < 0.2 SE. Relaxation:
/// the 40000-particle runs with the same window agree with the exact density
/// within 2.9 SE, so the start at v = 0 is forgotten by t = 5.
#[test]
fn r0_density_matches_exact() {
    const Z_MAX: f64 = 4.565;
    let bins = 20;
    for (drag, sigma, lambda, seed) in [
        (DragLaw::Tanh, 0.6, 0.85, 21u64),
        (DragLaw::Tan, 3.0, 15.0, 22u64),
    ] {
        let p = Params::new(drag.clone(), sigma, lambda, 0.0, 0.0).unwrap();
        let s = spec(8000, 15.0, 2, 5.0, bins, seed);
        let obs = simulate(&p, &s, Method::euler(1e-3), &NoProgress).unwrap();
        let w = obs.bin_width();
        let exact = R0Density::from_params(&p).unwrap();
        let mut edges: Vec<f64> = (0..=bins).map(|k| obs.v_lo + w * k as f64).collect();
        edges[bins] = obs.v_hi;
        let (prob, v2) = (exact.bin_probabilities(&edges), exact.v2());
        let n = obs.particles() as f64;

        // Chi-square on the final snapshot, pooling bins with expected < 5.
        let (mut chi2, mut groups) = (0.0, 0usize);
        let (mut o_acc, mut e_acc) = (0.0, 0.0);
        for b in 0..bins {
            o_acc += obs.density_final[b].sum * w; // count of particles in bin b
            e_acc += prob[b] * n;
            if e_acc >= 5.0 && prob[b + 1..].iter().sum::<f64>() * n >= 5.0 || b == bins - 1 {
                chi2 += (o_acc - e_acc) * (o_acc - e_acc) / e_acc;
                groups += 1;
                o_acc = 0.0;
                e_acc = 0.0;
            }
        }
        let dof = (groups - 1) as f64;
        let c = 2.0 / (9.0 * dof);
        let limit = dof * (1.0 - c + 3.719 * c.sqrt()).powi(3);
        assert!(
            chi2 < limit,
            "{drag}: chi2 {chi2:.1} dof {dof} limit {limit:.1}"
        );

        // Time-averaged density, per-bin z-scores.
        for (b, (acc, pb)) in obs.density_time.iter().zip(&prob).enumerate() {
            let zb = z(acc.mean(), pb / w, acc.sem());
            assert!(
                zb < Z_MAX,
                "{drag} bin {b}: {} ± {} vs {} (z = {zb:.2})",
                acc.mean(),
                acc.sem(),
                pb / w
            );
        }
        let sum = obs.summary();
        assert!(
            z(sum.v2, v2, sum.v2_err) < 4.0,
            "{drag}: <v²> {} ± {} vs {v2}",
            sum.v2,
            sum.v2_err
        );
    }
}
