//! The exact sampler (`simulate --method exact`) with thermal noise T > 0
//! and linear drag (docs/equations.md, Eqs. (N40)-(N45)): the thermal
//! linear cases of `irtp_testkit::noises::NOISE_CASES` against the closed
//! forms of `analytic::linear_noise` (time averages of v and v², D_eff from
//! the variance growth of x by batch means), pure Ornstein-Uhlenbeck at
//! r = 0 against the Gaussian N(0, T) per bin, continuity at T → 0 against
//! the T = 0 sampler at the same seed (same events), bit-identical runs for
//! any thread count and unit split, and the refusal of other drags at
//! T > 0 naming `temperature`.
//! Tolerances: 4 standard errors, Bonferroni-corrected per test.

use irtp::analytic::linear_noise::LinearNoise;
use irtp::model::noise::NoiseModel;
use irtp::parallel::NoProgress;
use irtp::sim::{self, Method, Observables, SimSpec, TimeGrid};
use irtp::{DragLaw, Error, Params};
use irtp_testkit::noises::{NoiseCase, NOISE_CASES};
use irtp_testkit::stats::bonferroni_z;

use crate::noise_exact::{batch_mean, run, var_x};

/// The standard normal distribution function.
fn normal_cdf(z: f64) -> f64 {
    0.5 * libm::erfc(-z / std::f64::consts::SQRT_2)
}

/// Every thermal linear case: the time averages of v and v² and D_eff
/// (batch means of the growth of Var x between t = 40 and t = 120, the
/// start at v = 0 long forgotten; and the Eq. (36) fit where the sim
/// reports it) against Eqs. (N3), (N4) and (N6).
#[test]
fn thermal_linear_cases_match_the_closed_forms() {
    let cases: Vec<&NoiseCase> = NOISE_CASES
        .iter()
        .filter(|c| c.thermal() && c.linear())
        .collect();
    assert!(cases.len() >= 2, "the list has thermal linear cases");
    let z = bonferroni_z(4 * cases.len());
    let (batches, per) = (16, 150);
    for c in cases {
        let p = c.params();
        let noise = NoiseModel::parse(c.noise, c.temperature).unwrap();
        let m = LinearNoise::new(1.0, noise, c.rate, c.reset_velocity)
            .unwrap()
            .moments()
            .unwrap();
        let grid = TimeGrid::linear(120.0, 4).unwrap();
        let (k1, k2) = (1, 3);
        let (t1, t2) = (grid.times()[k1], grid.times()[k2]);
        let (mut all, mut deff) = (None::<Observables>, Vec::new());
        for b in 0..batches {
            let spec = SimSpec::new(per, grid.clone(), 20.0, 4, 5).unwrap();
            let o = run(&p, &spec.shard(b * per).unwrap());
            deff.push((var_x(&o, k2) - var_x(&o, k1)) / (2.0 * (t2 - t1)));
            match &mut all {
                None => all = Some(o),
                Some(a) => a.merge(&o),
            }
        }
        let all = all.unwrap();
        let (d, d_se) = batch_mean(&deff);
        let mut checks = vec![
            ("<v>", all.v_time_avg.mean(), all.v_time_avg.sem(), m.v_mean),
            ("<v²>", all.v2_time_avg.mean(), all.v2_time_avg.sem(), m.v2),
            ("D_eff", d, d_se, m.d_eff),
        ];
        // The Eq. (36) fit the sim reports (v_r = 0 and a mirror-symmetric
        // noise only).
        let s = all.summary();
        if let (Some(fit), Some(se)) = (s.d_eff_msd, s.d_eff_msd_err) {
            checks.push(("D_eff (Eq. (36) fit)", fit, se, m.d_eff));
        }
        for (what, est, se, exact) in checks {
            eprintln!(
                "{} {what}: {est:.5} ± {se:.5} vs {exact:.5} ({:.2} SE)",
                c.name,
                (est - exact) / se
            );
            assert!((est - exact).abs() <= z * se, "{} {what}", c.name);
        }
    }
}

/// Pure Ornstein-Uhlenbeck (`none`, r = 0): the occupation histogram per
/// bin against the bin masses of N(0, T), max |z| with the Bonferroni
/// bound over the bins holding at least 1e-3 of the mass (the bins are
/// correlated, their z scores each standard normal); the far tails, whose
/// per-particle estimates are too skewed for a z score per bin, by their
/// total mass against the sum of their standard errors.
#[test]
fn ornstein_uhlenbeck_histogram_is_gaussian() {
    let t = 0.5;
    let noise = NoiseModel::parse("none", t).unwrap();
    let p = Params::with_noise(DragLaw::Linear, noise, 0.0, 0.0).unwrap();
    let bins = 40;
    let spec = SimSpec::new(2000, TimeGrid::linear(40.0, 8).unwrap(), 10.0, bins, 29).unwrap();
    let o = run(&p, &spec);
    let w = o.bin_width();
    let cdf = |v: f64| normal_cdf(v / t.sqrt());
    let exact: Vec<f64> = (0..bins)
        .map(|k| {
            let (a, b) = (o.v_lo + w * k as f64, o.v_lo + w * (k + 1) as f64);
            let lo = if k == 0 { 0.0 } else { cdf(a) };
            let hi = if k + 1 == bins { 1.0 } else { cdf(b) };
            (hi - lo) / w
        })
        .collect();
    let resolved = exact.iter().filter(|&&p| p * w >= 1e-3).count();
    let z = bonferroni_z(resolved);
    // The tail bins' mass together: estimate, a bound on its standard
    // error (the sum of theirs), exact.
    let mut tail = (0.0, 0.0, 0.0);
    for (k, &p) in exact.iter().enumerate() {
        let (est, se) = (o.density_time[k].mean(), o.density_time[k].sem());
        if p * w < 1e-3 {
            assert!(est >= 0.0, "tail bin {k}: {est:e}");
            tail.0 += est * w;
            tail.1 += se * w;
            tail.2 += p * w;
            continue;
        }
        let zk = (est - p) / se;
        eprintln!("bin {k}: {est:.6} ± {se:.6} vs {p:.6} ({zk:.2} SE)");
        assert!(zk.abs() <= z, "bin {k}");
    }
    eprintln!("tails: {:e} ± {:e} vs {:e}", tail.0, tail.1, tail.2);
    assert!((tail.0 - tail.2).abs() <= z * tail.1, "tails");
}

/// T → 0: the thermal sampler at T = 1e-10 sees the events of the T = 0
/// sampler at the same seed (the same draws from the event stream) and
/// departs from its path by O(sqrt T): <v²> and <v> within 20 sqrt(T)
/// v_max of the T = 0 run.
#[test]
fn tiny_temperature_tends_to_the_athermal_sampler() {
    let t = 1e-10;
    for c in NOISE_CASES.iter().filter(|c| c.linear() && !c.thermal()) {
        let cold = c.params();
        let noise = NoiseModel::parse(c.noise, t).unwrap();
        let warm = Params::with_noise(DragLaw::Linear, noise, c.rate, c.reset_velocity).unwrap();
        let spec = SimSpec::new(200, TimeGrid::linear(20.0, 4).unwrap(), 5.0, 8, 41).unwrap();
        let (a, b) = (run(&cold, &spec), run(&warm, &spec));
        assert_eq!(a.steps, b.steps, "{}: the same events", c.name);
        let (lo, hi) = cold.bounds();
        let v_max = lo.abs().max(hi.abs());
        let tol_v = 20.0 * t.sqrt() * v_max;
        // x departs like a Brownian motion, sd sqrt(2 T t), so x² by twice
        // that times |x|.
        let tol_x = 20.0 * (2.0 * t * spec.grid.t_max()).sqrt() * a.x2[3].mean().sqrt();
        for (what, x, y, tol) in [
            ("<v²>", &a.v2_time_avg, &b.v2_time_avg, tol_v),
            ("<v>", &a.v_time_avg, &b.v_time_avg, tol_v),
            ("<x²>", &a.x2[3], &b.x2[3], tol_x),
        ] {
            let d = (x.mean() - y.mean()).abs();
            eprintln!(
                "{} {what}: {} vs {} (diff {d:e}, tolerance {tol:e})",
                c.name,
                x.mean(),
                y.mean()
            );
            assert!(d <= tol, "{} {what}: {d:e} > {tol:e}", c.name);
        }
    }
}

/// One run, bit for bit, on 1 and 2 threads, and from its unit totals
/// (two units) combined in order.
#[test]
fn thermal_runs_are_bit_identical_for_threads_and_units() {
    let case = NOISE_CASES
        .iter()
        .find(|c| c.name == "linear-telegraph-thermal")
        .unwrap();
    let p = case.params();
    let spec = SimSpec::new(4100, TimeGrid::linear(2.0, 3).unwrap(), 0.5, 6, 13).unwrap();
    let mut runs = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        runs.push(pool.install(|| run(&p, &spec)));
    }
    assert!(runs[0] == runs[1], "1 vs 2 threads");
    let count = sim::unit_count(spec.particles);
    assert_eq!(count, 2);
    let units: Vec<Observables> = (0..count)
        .flat_map(|u| sim::simulate_units(&p, &spec, Method::Exact, u..u + 1, &NoProgress).unwrap())
        .collect();
    let combined = sim::combine_units(&p, &spec, Method::Exact, &units).unwrap();
    assert!(combined == runs[0], "units combined");
}

/// Every thermal case runs or is refused: linear drag runs (occupation
/// summing to 1), any other drag is refused by the capability module
/// naming `temperature` and `simulate (euler)` among the methods that run it.
#[test]
fn other_drags_at_positive_temperature_are_refused_by_name() {
    let spec = SimSpec::new(20, TimeGrid::linear(2.0, 2).unwrap(), 0.5, 10, 3).unwrap();
    for c in NOISE_CASES.iter().filter(|c| c.thermal()) {
        let p = c.params();
        match sim::simulate(&p, &spec, Method::Exact, &NoProgress) {
            Ok(o) => {
                assert!(c.linear(), "{} runs", c.name);
                let total: f64 =
                    o.density_time.iter().map(|d| d.mean()).sum::<f64>() * o.bin_width();
                assert!((total - 1.0).abs() < 1e-9, "{}: occupation {total}", c.name);
            }
            Err(e) => {
                let msg = e.to_string();
                let Error::Unsupported { flag, runners, .. } = e else {
                    panic!("{}: {msg}", c.name)
                };
                assert!(!c.linear(), "{}: {msg}", c.name);
                assert_eq!(flag, "temperature", "{}: {msg}", c.name);
                assert!(runners.contains("simulate (euler)"), "{msg}");
            }
        }
    }
    let power: DragLaw = "power:n=0.5".parse().unwrap();
    let noise = NoiseModel::parse("rpt:sigma=1,alpha=1,beta=1", 0.3).unwrap();
    let p = Params::with_noise(power, noise, 0.5, 0.0).unwrap();
    let e = sim::simulate(&p, &spec, Method::Exact, &NoProgress).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Unsupported {
                flag: "temperature",
                ..
            }
        ),
        "{e}"
    );
}
