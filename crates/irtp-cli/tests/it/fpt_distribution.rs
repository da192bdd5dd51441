//! The first-passage-time distribution: time-dependent backward equations
//! (upwind scheme, atom split off exactly) against the stationary moments of
//! the box scheme and against the exact first-passage sampler, on the
//! parameter sets of Fig. 7; the `irtp mfpt distribution` command's contract.

use crate::common;
use crate::common::{assert_rejected, assert_success, irtp, json};
use irtp::mfpt::backward::moments;
use irtp::mfpt::exact::first_passage_to;
use irtp::mfpt::{distribution, BackwardOptions, Distribution, DistributionOptions, Problem};
use irtp::model::{DragLaw, Params};

/// Fig. 7's sets at v_t = 0.5 (v_0 = -0.249, v_r = 0, lambda = 0.5): tan
/// Sigma = 3 at its r = 2 and without resetting, tanh Sigma = 0.6 at r = 0.2.
fn fig7_sets() -> Vec<Problem> {
    [
        (DragLaw::Tan, 3.0, 2.0),
        (DragLaw::Tan, 3.0, 0.0),
        (DragLaw::Tanh, 0.6, 0.2),
    ]
    .into_iter()
    .map(|(d, s, r)| {
        let p = Params::new(d, s, 0.5, r, 0.0).unwrap();
        Problem::new(p, -0.249, 0.5).unwrap()
    })
    .collect()
}

const CELLS: usize = 4000;

fn solve(pr: &Problem, times: &[f64]) -> Distribution {
    let opts = DistributionOptions {
        backward: BackwardOptions::with_cells(CELLS),
        ..Default::default()
    };
    distribution(pr, times, &opts).unwrap()
}

fn linear(t_max: f64, n: usize) -> Vec<f64> {
    (0..n).map(|i| t_max * i as f64 / (n - 1) as f64).collect()
}

/// Passage times of `n` particles (even i: +Sigma, odd: -Sigma).
fn sample(pr: &Problem, n: u64, seed: u64) -> Vec<(bool, f64)> {
    (0..n)
        .map(|i| {
            let mut rng = irtp::rng::stream(seed, i);
            let plus = i % 2 == 0;
            let p = pr.params();
            let (t, _) =
                first_passage_to(p, pr.v0(), pr.vt(), (i % 2) as usize, 1e6, &mut rng).unwrap();
            (plus, t.expect("arrived by 1e6"))
        })
        .collect()
}

/// E(T) and E(T²) of the distribution (exact in time for the upwind
/// equations, two meshes extrapolated; the error falls as cells⁻²: tanh
/// 3.1e-6, 7.8e-7, 2.0e-7 at 4000, 8000, 16000 cells) against the box
/// scheme's stationary solve at 20 000 cells, an independent
/// discretisation: 1e-6 at 16 000 cells. The running
/// time integral of S agrees to the integrator's global error, about
/// rtol^(2/3) = 2.2e-3 at the default rtol 1e-4.
#[test]
#[ignore = "slow tier"]
fn mean_of_the_density_is_the_stationary_tau() {
    for pr in fig7_sets() {
        let opts = DistributionOptions {
            backward: BackwardOptions::with_cells(16_000),
            ..Default::default()
        };
        let d = distribution(&pr, &linear(5.0, 11), &opts).unwrap();
        let m = moments(&pr, &BackwardOptions::default()).unwrap();
        assert!(d.tail_mass < 1e-10, "{}", d.tail_mass);
        let rel = (d.mean - m.tau).abs() / m.tau;
        assert!(
            rel < 1e-6,
            "{pr:?}: mean {} vs tau {}: {rel:e}",
            d.mean,
            m.tau
        );
        let rel2 = (d.second - m.second).abs() / m.second;
        assert!(
            rel2 < 1e-6,
            "{pr:?}: E(T²) {} vs T2 {}: {rel2:e}",
            d.second,
            m.second
        );
        let rp = (d.mean_plus - m.tau_plus).abs() / m.tau_plus;
        let rm = (d.mean_minus - m.tau_minus).abs() / m.tau_minus;
        assert!(rp < 1e-6 && rm < 1e-6, "{rp:e} {rm:e}");
        let rt = (d.mean_time_integral - d.mean).abs() / d.mean;
        assert!(
            rt < 1e-4f64.powf(2.0 / 3.0),
            "{pr:?}: ∫S dt {} vs {}",
            d.mean_time_integral,
            d.mean
        );
    }
}

#[test]
fn second_moment_agrees_with_the_exact_sampler() {
    // 4 standard errors of the sampled E[T²] (stratified halves).
    for (k, pr) in fig7_sets().into_iter().enumerate() {
        let m = moments(&pr, &BackwardOptions::default()).unwrap();
        let times = sample(&pr, 40_000, 100 + k as u64);
        let half = |plus: bool| {
            let x: Vec<f64> = times
                .iter()
                .filter(|s| s.0 == plus)
                .map(|s| s.1 * s.1)
                .collect();
            let n = x.len() as f64;
            let mean = x.iter().sum::<f64>() / n;
            let var = x.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (mean, var / n)
        };
        let ((mp, vp), (mm, vm)) = (half(true), half(false));
        let (sampled, se) = (0.5 * (mp + mm), 0.5 * (vp + vm).sqrt());
        let z = (sampled - m.second) / se;
        assert!(
            z.abs() < 4.0,
            "{pr:?}: E[T²] {sampled} ± {se} vs {}: z = {z}",
            m.second
        );
        assert!((m.variance - (m.second - m.tau * m.tau)).abs() < 1e-12 * m.second);
        assert!((m.cv - m.variance.sqrt() / m.tau).abs() < 1e-12);
    }
}

/// Bins of probability about 0.05 from the backward survival on a fine
/// grid (the atom falls inside one), and a last bin to infinity.
fn bins(d: &Distribution) -> Vec<(f64, f64)> {
    let mut edges = vec![(0.0, 1.0)];
    for (&t, &s) in d.t.iter().zip(&d.survival) {
        let last = edges.last().unwrap().1;
        if t > 0.0 && last - s >= 0.05 {
            edges.push((t, s));
        }
    }
    edges
}

#[test]
#[ignore = "slow tier"]
fn sampled_histogram_against_the_backward_density_chi_square() {
    // Level 1e-3 overall, Bonferroni over the three sets: the upper
    // 3.3e-4 quantile of chi-square (Wilson-Hilferty, z = 3.40).
    let sets = fig7_sets();
    let z = 3.40;
    for (k, pr) in sets.iter().enumerate() {
        let tau = moments(pr, &BackwardOptions::with_cells(CELLS))
            .unwrap()
            .tau;
        let d = solve(pr, &linear(10.0 * tau, 801));
        let edges = bins(&d);
        let n = 20_000u64;
        let times = sample(pr, n, 200 + k as u64);
        let mut chi2 = 0.0;
        for j in 0..edges.len() {
            let (lo, s_lo) = edges[j];
            let (hi, s_hi) = edges.get(j + 1).copied().unwrap_or((f64::INFINITY, 0.0));
            let count = times.iter().filter(|s| s.1 > lo && s.1 <= hi).count() as f64;
            let expected = n as f64 * (s_lo - s_hi);
            assert!(expected > 20.0, "bin ({lo}, {hi}]: {expected}");
            chi2 += (count - expected).powi(2) / expected;
        }
        let df = (edges.len() - 1) as f64;
        let q = df * (1.0 - 2.0 / (9.0 * df) + z * (2.0 / (9.0 * df)).sqrt()).powi(3);
        assert!(df >= 10.0, "{df}");
        assert!(chi2 < q, "{pr:?}: chi2 = {chi2} > {q} (df {df})");
    }
}

/// At every time, before the atom's flow time T_f too: 0 <= S <= 1, S
/// non-increasing and f >= 0 (outside the few spreads around T_f where the
/// mesh smears f), within the mesh errors the run reports, and S+ drops by
/// the atom's mass across T_f.
#[test]
#[ignore = "slow tier"]
fn survival_is_a_probability_and_decreases() {
    for pr in fig7_sets() {
        let tau = moments(&pr, &BackwardOptions::with_cells(CELLS))
            .unwrap()
            .tau;
        let d = solve(&pr, &linear(8.0 * tau, 201));
        assert!(d.atom_mass > 0.0 && d.atom_mass < 0.5 && d.atom_mass_minus == 0.0);
        assert!(d.t.iter().filter(|&&t| t > 0.0 && t < d.atom_time).count() >= 2);
        let fmax = d.density.iter().cloned().fold(0.0, f64::max);
        for (s, f) in [
            (&d.survival, &d.density),
            (&d.survival_plus, &d.density_plus),
            (&d.survival_minus, &d.density_minus),
        ] {
            let (es, ef) = (d.mesh_error, d.mesh_error_density);
            for i in 0..d.t.len() {
                let t = d.t[i];
                assert!(s[i] >= -es && s[i] <= 1.0 + es, "t = {t}: S = {}", s[i]);
                assert!(d.smeared(t) || f[i] >= -ef, "t = {t}: f = {} ({ef})", f[i]);
                if i > 0 {
                    assert!(s[i] <= s[i - 1] + es, "t = {t}: {} > {}", s[i], s[i - 1]);
                }
            }
        }
        assert_eq!(d.survival[0], 1.0);
        assert!(d.density[0].abs() < 1e-12, "{}", d.density[0]);
        // Across T_f: S+ loses the atom plus the continuous part's ∫f+ dt.
        let eps = 1e-6 * d.atom_time;
        let d2 = solve(&pr, &[d.atom_time - eps, d.atom_time + eps]);
        let drop = d2.survival_plus[0] - d2.survival_plus[1];
        assert!(
            (drop - d.atom_mass_plus).abs() < 1e-5 * d.atom_mass_plus + 2.0 * eps * fmax,
            "{pr:?}: drop {drop} vs atom {}",
            d.atom_mass_plus
        );
    }
}

/// S(t) converges with the mesh: the extrapolated S at 1000 and 4000 cells
/// agree to the reported mesh_error of the coarser run, before and after
/// the atom.
#[test]
#[ignore = "slow tier"]
fn survival_converges_with_the_mesh() {
    let pr = &fig7_sets()[0];
    let times = linear(3.0, 31);
    let run = |cells: usize| {
        let opts = DistributionOptions {
            backward: BackwardOptions::with_cells(cells),
            rtol: 1e-6,
            atol: 1e-9,
            ..Default::default()
        };
        distribution(pr, &times, &opts).unwrap()
    };
    let (a, b) = (run(1000), run(4000));
    let diff = a
        .survival
        .iter()
        .zip(&b.survival)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(diff <= a.mesh_error, "{diff} vs {}", a.mesh_error);
    assert!(
        b.mesh_error < a.mesh_error,
        "{} {}",
        b.mesh_error,
        a.mesh_error
    );
}

#[test]
fn downward_target_mirrors_the_upward_one() {
    let p = Params::new(DragLaw::Tanh, 0.6, 0.5, 0.2, 0.0).unwrap();
    let up = Problem::new(p.clone(), -0.249, 0.5).unwrap();
    let down = Problem::new(p, 0.249, -0.5).unwrap();
    let times = linear(4.0, 9);
    let (a, b) = (solve(&up, &times), solve(&down, &times));
    assert_eq!(a.survival_plus, b.survival_minus);
    assert_eq!(a.density_minus, b.density_plus);
    assert_eq!(a.atom_mass_plus, b.atom_mass_minus);
}

const PAPER: [&str; 12] = [
    "mfpt",
    "distribution",
    "--drag",
    "tan",
    "--sigma",
    "3",
    "--lambda",
    "0.5",
    "--rate",
    "2",
    "--v0",
    "-0.249",
];

#[test]
fn cli_backward_and_exact_write_their_tables() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("b");
    let mut a = PAPER.to_vec();
    let d = dir.to_str().unwrap();
    a.extend([
        "--vt", "0.5", "--cells", "400", "--points", "21", "--json", "--out", d,
    ]);
    let v = json(&irtp(&a));
    let (tau, t2) = (
        v["tau"].as_f64().unwrap(),
        v["second_moment"].as_f64().unwrap(),
    );
    assert!((v["distribution_mean"].as_f64().unwrap() - tau).abs() < 1e-4 * tau);
    assert!((v["mean_time_integral"].as_f64().unwrap() - tau).abs() < 1e-3 * tau);
    assert!((v["variance"].as_f64().unwrap() - (t2 - tau * tau)).abs() < 1e-9 * t2);
    let csv = std::fs::read_to_string(dir.join("distribution.csv")).unwrap();
    assert!(csv.starts_with("t,survival,density,"), "{csv}");
    // Every output time is written, t = 0 and the times before the atom too.
    assert_eq!(csv.lines().count(), 1 + 21);
    assert!(v["mesh_error"].as_f64().unwrap() < 1e-2);
    let dir = tmp.path().join("e");
    let mut a = PAPER.to_vec();
    let d = dir.to_str().unwrap();
    a.extend([
        "--vt",
        "0.5",
        "--method",
        "exact",
        "--particles",
        "2000",
        "--out",
        d,
    ]);
    assert_success(&irtp(&a));
    let h = std::fs::read_to_string(dir.join("histogram.csv")).unwrap();
    assert!(h.starts_with("t_lo,t_hi,density,density_err,count"), "{h}");
    assert!(dir.join("survival.csv").exists());
}

#[test]
fn cli_writes_times_before_the_atom() {
    // t_max 0.01 is far below the flow time (~0.26 here): S+ is the atom's
    // e^{-(lambda + r) t} plus what flips or resets can still bring in.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let mut a = PAPER.to_vec();
    a.extend([
        "--vt", "0.5", "--cells", "400", "--t-max", "0.01", "--points", "3",
    ]);
    a.extend(["--out", dir.to_str().unwrap()]);
    assert_success(&irtp(&a));
    let csv = std::fs::read_to_string(dir.join("distribution.csv")).unwrap();
    let last = common::last_csv_row(&dir.join("distribution.csv"));
    assert_eq!(last[0], 0.01);
    // S = 1 up to the mesh error (S_c's kink, smeared ahead of the atom).
    assert!(last[1] > 0.99 && last[1] <= 1.0 + 1e-4, "{csv}");
}

#[test]
fn cli_bad_input_exits_2_and_writes_nothing() {
    let cases: [(&[&str], &str); 7] = [
        (&["--method", "exact", "--points", "11"], "--points"),
        (&["--particles", "100"], "--particles"),
        (&["--seed", "3"], "--seed"),
        (&["--t-max", "-1"], "--t-max"),
        (&["--rtol", "1"], "--rtol"),
        (&["--grid", "log", "--points", "2"], "--points"),
        (&["--t-min", "0.1"], "--t-min"),
    ];
    for (extra, flag) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let mut a = PAPER.to_vec();
        a.extend(["--vt", "0.5", "--out", dir.to_str().unwrap()]);
        a.extend(extra);
        assert_rejected(&irtp(&a), flag, &dir);
    }
}
