//! The exact sampler (`simulate --method exact`) with a finite-state noise
//! at T = 0, checked once over `irtp_testkit::noises::NOISE_CASES` (the
//! athermal cases): linear drag against the closed forms of
//! `analytic::linear_noise` (time averages of v and v², the drift and
//! D_eff from the position moments by batch means), the asymmetric
//! telegraph cases at r = 0 against `analytic::telegraph_r0` (velocity
//! histogram, per bin), the paper's noise spelt as a generator against the
//! default path, the spelt-out symmetric telegraph bit for bit, and
//! bit-identical runs for any thread count and shard split.
//! Tolerances: 4 standard errors, Bonferroni-corrected per test.

use irtp::analytic::linear_noise::LinearNoise;
use irtp::analytic::telegraph_r0::TelegraphR0Density;
use irtp::model::noise::{NoiseKind, NoiseModel};
use irtp::parallel::NoProgress;
use irtp::sim::{self, Method, Observables, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};
use irtp_testkit::noises::{athermal, NoiseCase, NOISE_CASES};
use irtp_testkit::stats::bonferroni_z;

/// An exact-sampler run (shared with `noise_exact_ou`).
pub(crate) fn run(p: &Params, spec: &SimSpec) -> Observables {
    sim::simulate(p, spec, Method::Exact, &NoProgress).unwrap()
}

/// Mean and standard error of batch values.
pub(crate) fn batch_mean(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Sample variance of x at grid index k of one batch.
pub(crate) fn var_x(o: &Observables, k: usize) -> f64 {
    let n = o.x[k].n as f64;
    (o.x2[k].mean() - o.x[k].mean().powi(2)) * n / (n - 1.0)
}

#[test]
fn spelt_out_symmetric_telegraph_is_the_default_bit_for_bit() {
    let spec = SimSpec::new(400, TimeGrid::linear(4.0, 5).unwrap(), 1.0, 10, 3).unwrap();
    let noise =
        NoiseModel::parse("telegraph:plus=2,minus=2,rate_plus=0.7,rate_minus=0.7", 0.0).unwrap();
    let spelt = Params::with_noise(DragLaw::Tan, noise, 0.5, 0.1).unwrap();
    assert!(spelt.noise().is_none(), "normalised to the default");
    let default = Params::new(DragLaw::Tan, 2.0, 0.7, 0.5, 0.1).unwrap();
    assert!(run(&spelt, &spec) == run(&default, &spec));
}

#[test]
fn noise_runs_are_bit_identical_for_threads_and_shards() {
    let case = NOISE_CASES.iter().find(|c| c.name == "tan-rpt").unwrap();
    let p = case.params();
    let spec = SimSpec::new(300, TimeGrid::linear(3.0, 4).unwrap(), 0.5, 8, 11).unwrap();
    let mut runs = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        runs.push(pool.install(|| run(&p, &spec)));
    }
    assert!(runs[0] == runs[1], "1 vs 2 threads");
    let mut merged = run(
        &p,
        &SimSpec {
            particles: 120,
            ..spec.clone()
        },
    );
    let rest = SimSpec {
        particles: 180,
        ..spec.clone()
    }
    .shard(120)
    .unwrap();
    merged.merge(&run(&p, &rest));
    assert_eq!(merged.steps, runs[0].steps);
    for k in 0..spec.grid.len() {
        let (a, b) = (merged.x2[k].sum, runs[0].x2[k].sum);
        assert!((a - b).abs() <= 1e-12 * a.abs().max(b.abs()), "shards {k}");
    }
}

/// Linear drag: the time averages of v and v², the drift and D_eff
/// (batch means of the increments of the mean and variance of x between
/// t1 = 60 and t2 = 160, the transient of the start at v = 0 long gone)
/// against Eqs. (N3)-(N6).
#[test]
#[ignore = "slow tier: statistical check of the N-state exact sampler against linear closed forms"]
fn linear_noise_cases_match_the_closed_forms() {
    let cases: Vec<&NoiseCase> = athermal().filter(|c| c.linear()).collect();
    let z = bonferroni_z(4 * cases.len());
    let (batches, per) = (16, 250);
    for c in cases {
        let p = c.params();
        let noise = NoiseModel::parse(c.noise, 0.0).unwrap();
        let m = LinearNoise::new(1.0, noise, c.rate, c.reset_velocity)
            .unwrap()
            .moments()
            .unwrap();
        let grid = TimeGrid::linear(160.0, 8).unwrap();
        let (k1, k2) = (2, 7);
        let (t1, t2) = (grid.times()[k1], grid.times()[k2]);
        let (mut all, mut drift, mut deff) = (None::<Observables>, Vec::new(), Vec::new());
        for b in 0..batches {
            let spec = SimSpec::new(per, grid.clone(), 20.0, 10, 5).unwrap();
            let o = run(&p, &spec.shard(b * per).unwrap());
            drift.push((o.x[k2].mean() - o.x[k1].mean()) / (t2 - t1));
            deff.push((var_x(&o, k2) - var_x(&o, k1)) / (2.0 * (t2 - t1)));
            match &mut all {
                None => all = Some(o),
                Some(a) => a.merge(&o),
            }
        }
        let all = all.unwrap();
        let checks = [
            ("<v>", all.v_time_avg.mean(), all.v_time_avg.sem(), m.v_mean),
            ("<v²>", all.v2_time_avg.mean(), all.v2_time_avg.sem(), m.v2),
            ("drift", batch_mean(&drift).0, batch_mean(&drift).1, m.drift),
            ("D_eff", batch_mean(&deff).0, batch_mean(&deff).1, m.d_eff),
        ];
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

/// ∫ p over [a, b] by 16-point Gauss-Legendre on 8 panels in s. Near an
/// edge singularity p ~ w^e at distance w from the edge (lower: `lower` =
/// Some(e) at a, upper: `upper` = Some(e) at b): the first D = 1e-12 in
/// closed form, p(D) D / (e + 1) (the mass within rounding distance of the
/// edge is not negligible for e near -1: ~ D^(e+1)), the rest with
/// w = D + (h - D) s^16, whose integrand is smooth for these cases' e > -0.76.
fn bin_mass(d: &TelegraphR0Density, a: f64, b: f64, lower: Option<f64>, upper: Option<f64>) -> f64 {
    const X: [f64; 8] = [
        0.095_012_509_837_637_44,
        0.281_603_550_779_258_9,
        0.458_016_777_657_227_4,
        0.617_876_244_402_643_8,
        0.755_404_408_355_003,
        0.865_631_202_387_831_8,
        0.944_575_023_073_232_6,
        0.989_400_934_991_649_9,
    ];
    const W: [f64; 8] = [
        0.189_450_610_455_068_5,
        0.182_603_415_044_923_6,
        0.169_156_519_395_002_5,
        0.149_595_988_816_576_7,
        0.124_628_971_255_533_9,
        0.095_158_511_682_492_8,
        0.062_253_523_938_647_9,
        0.027_152_459_411_754_1,
    ];
    const D: f64 = 1e-12;
    let edge = lower.or(upper);
    let (m, skip) = if edge.is_some() {
        (16.0, D)
    } else {
        (1.0, 0.0)
    };
    let at = |w: f64| if upper.is_some() { b - w } else { a + w };
    let h = b - a - skip;
    let f = |s: f64| d.pdf(at(skip + h * s.powf(m))) * m * h * s.powf(m - 1.0);
    let panels = 8;
    let mut total = edge.map_or(0.0, |e| d.pdf(at(D)) * D / (e + 1.0));
    for i in 0..panels {
        let (lo, hi) = (i as f64 / panels as f64, (i + 1) as f64 / panels as f64);
        let (c, r) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        for (x, w) in X.iter().zip(W) {
            total += w * r * (f(c - r * x) + f(c + r * x));
        }
    }
    total
}

/// The asymmetric telegraph cases at r = 0: the occupation histogram per
/// bin against the bin masses of the exact density (Eq. (N8)).
#[test]
#[ignore = "slow tier: statistical check of the N-state exact sampler against the r = 0 density"]
fn asymmetric_telegraph_histogram_at_r0_matches_the_density() {
    let bins = 12;
    let cases: Vec<NoiseCase> = athermal()
        .filter(|c| c.noise.starts_with("telegraph:plus"))
        .map(|c| c.at_rate(0.0))
        .collect();
    let z = bonferroni_z(bins * cases.len());
    for c in &cases {
        let p = c.params();
        let model = NoiseModel::parse(c.noise, 0.0).unwrap();
        let NoiseKind::Telegraph(t) = model.kind() else {
            panic!("{}", c.name)
        };
        let d = TelegraphR0Density::new(p.drag(), *t).unwrap();
        let spec = SimSpec::new(3000, TimeGrid::linear(60.0, 2).unwrap(), 20.0, bins, 17).unwrap();
        let o = run(&p, &spec);
        let (lo, hi) = (o.v_lo, o.v_hi);
        let w = (hi - lo) / bins as f64;
        let mut mass = 0.0;
        for k in 0..bins {
            let (a, b) = (lo + w * k as f64, lo + w * (k + 1) as f64);
            let (el, eu) = d.edge_exponents();
            let exact = bin_mass(
                &d,
                a,
                b,
                (k == 0).then_some(el),
                (k + 1 == bins).then_some(eu),
            ) / w;
            mass += exact * w;
            let (est, se) = (o.density_time[k].mean(), o.density_time[k].sem());
            eprintln!(
                "{} bin {k}: {est:.4} ± {se:.4} vs {exact:.4} ({:.2} SE)",
                c.name,
                (est - exact) / se
            );
            assert!((est - exact).abs() <= z * se, "{} bin {k}", c.name);
        }
        // The reference's quadrature error, far below the bins' SE (> 1e-3).
        assert!(
            (mass - 1.0).abs() < 1e-5,
            "{}: exact bin masses sum to {mass}",
            c.name
        );
    }
}

/// The paper's noise spelt as a two-state generator runs the N-state path
/// (its own random draws) and agrees with the default path within 4 SE:
/// the time averages of v², the occupation histogram and <x²>(t_max).
#[test]
#[ignore = "slow tier: statistical check of the N-state path against the default path"]
fn paper_noise_as_states_agrees_with_the_default_path() {
    let cases: Vec<&NoiseCase> = athermal()
        .filter(|c| c.name.ends_with("paper-as-states"))
        .collect();
    let bins = 8;
    let z = bonferroni_z((bins + 2) * cases.len());
    for c in cases {
        let states = c.params();
        let drag: DragLaw = c.drag.parse().unwrap();
        let default = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
        let spec = SimSpec::new(4000, TimeGrid::linear(30.0, 3).unwrap(), 10.0, bins, 23).unwrap();
        let (a, b) = (run(&states, &spec), run(&default, &spec));
        assert_eq!((a.v_lo, a.v_hi), (b.v_lo, b.v_hi), "{}", c.name);
        let mut pairs = vec![
            ("<v²>", &a.v2_time_avg, &b.v2_time_avg),
            ("<x²>", &a.x2[2], &b.x2[2]),
        ];
        for k in 0..bins {
            pairs.push(("bin", &a.density_time[k], &b.density_time[k]));
        }
        for (what, x, y) in pairs {
            let se = x.sem().hypot(y.sem());
            let d = x.mean() - y.mean();
            eprintln!(
                "{} {what}: {} vs {} ({:.2} SE)",
                c.name,
                x.mean(),
                y.mean(),
                d / se
            );
            assert!(d.abs() <= z * se, "{} {what}", c.name);
        }
    }
}

/// Every athermal case runs (a short run, fast tier): finite moments,
/// velocities inside the noise's interval, occupation summing to 1.
#[test]
fn every_athermal_case_runs() {
    for c in athermal() {
        let p = c.params();
        let spec = SimSpec::new(40, TimeGrid::linear(5.0, 3).unwrap(), 1.0, 10, 2).unwrap();
        let o = run(&p, &spec);
        let (lo, hi) = p.bounds();
        let v2 = o.v2_time_avg.mean();
        assert!(
            v2 >= 0.0 && v2 <= lo.abs().max(hi.abs()).powi(2),
            "{}: {v2}",
            c.name
        );
        let total: f64 = o.density_time.iter().map(|d| d.mean()).sum::<f64>() * o.bin_width();
        assert!((total - 1.0).abs() < 1e-9, "{}: occupation {total}", c.name);
        assert!(o.steps > 0, "{}", c.name);
    }
}

/// T > 0 with a drag other than linear (`temperature`, see
/// noise_exact_ou.rs) and a level at a kink of the drag are refused by name.
#[test]
fn refusals_name_their_flag() {
    let spec = SimSpec::new(10, TimeGrid::linear(1.0, 2).unwrap(), 0.0, 4, 1).unwrap();
    let thermal = NOISE_CASES
        .iter()
        .find(|c| c.thermal() && !c.linear())
        .unwrap()
        .params();
    let err = sim::simulate(&thermal, &spec, Method::Exact, &NoProgress).unwrap_err();
    assert!(err.to_string().contains("temperature"), "{err}");
    let power: DragLaw = "power:n=0.5".parse().unwrap();
    let noise = NoiseModel::parse("rpt:sigma=1,alpha=1,beta=1", 0.0).unwrap();
    let p = Params::with_noise(power, noise, 0.5, 0.0).unwrap();
    let err = sim::simulate(&p, &spec, Method::Exact, &NoProgress).unwrap_err();
    assert!(err.to_string().contains("noise"), "{err}");
}
