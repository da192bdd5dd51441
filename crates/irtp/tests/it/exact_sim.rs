//! Exact sampler against exact answers. Every statistical check uses fixed
//! seeds and a 4-standard-error tolerance (two-sided false-alarm rate 6e-5
//! per check); the sampler has no time step, so there is no discretisation
//! bias to allow for.

use crate::common::models;
use irtp::analytic::linear;
use irtp::model::Drag;
use irtp::parallel::NoProgress;
use irtp::sim::exact;
use irtp::sim::{SimSpec, TimeGrid};
use irtp::stats::MeanAcc;
use irtp::{DragLaw, Params};

fn z(est: f64, se: f64, exact: f64) -> f64 {
    (est - exact) / se
}

/// Stationary <v²> and <v> (per-particle exact time averages over the
/// window, independent across particles) and the ensemble <v²> at t_max,
/// against the closed forms, for r from 0 to 100 and v_r ≠ 0.
#[test]
fn linear_stationary_moments() {
    for (i, &(lambda, r, vr)) in [
        (0.5, 0.0, 0.0),
        (2.0, 0.0, 0.0),
        (0.5, 2.0, 0.3),
        (1.0, 10.0, -0.5),
        (5.0, 100.0, 0.2),
    ]
    .iter()
    .enumerate()
    {
        let p = models::linear(1.0, lambda, r, vr);
        let relax = 1.0 / (1.0f64 + r).min(2.0 * lambda);
        let burn = 15.0 * relax;
        let t_max = burn + 20.0 * relax.max(0.2);
        let spec = SimSpec::new(
            2000,
            TimeGrid::from_times(vec![0.0, t_max]).unwrap(),
            burn,
            20,
            100 + i as u64,
        )
        .unwrap();
        let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
        let v2 = linear::v2(&p).unwrap();
        let vm = linear::v_mean(&p).unwrap();
        let zs = [
            z(o.v2_time_avg.mean(), o.v2_time_avg.sem(), v2),
            z(o.v_time_avg.mean(), o.v_time_avg.sem(), vm),
            z(o.v2[1].mean(), o.v2[1].sem(), v2),
            z(o.v[1].mean(), o.v[1].sem(), vm),
        ];
        for zz in zs {
            assert!(zz.abs() < 4.0, "lambda={lambda} r={r} vr={vr}: z = {zs:?}");
        }
        // The time-averaged density integrates to 1 exactly (occupation times
        // of every particle sum to the window length).
        let w = o.bin_width();
        let total: f64 = o.density_time.iter().map(|a| a.mean() * w).sum();
        assert!((total - 1.0).abs() < 1e-12, "density mass {total}");
        assert!(o.steps > 0 || lambda + r == 0.0);
    }
}

/// D_eff from the growth of Var x between two late times,
/// D = [Var x(T2) - Var x(T1)] / (2 (T2 - T1)): once the velocity process has
/// relaxed (T1 ≫ 1/(1+r), 1/(2 lambda)), Var x(T) = 2 D T + c + O(e^{-T/τ})
/// with the same constant c at both times, so the difference is unbiased up
/// to exponentially small terms. Its standard error comes from 16
/// independent batches (different seeds), which accounts for the strong
/// correlation of x(T1) and x(T2) within a particle.
#[test]
fn linear_effective_diffusion() {
    for (i, &(lambda, r, vr)) in [(0.5, 0.0, 0.0), (1.0, 3.0, 0.4), (5.0, 100.0, 0.0)]
        .iter()
        .enumerate()
    {
        let p = models::linear(1.0, lambda, r, vr);
        let relax = 1.0 / (1.0f64 + r).min(2.0 * lambda);
        let t1 = 20.0 * relax;
        let t2 = t1 + 40.0 * relax;
        let batches = 16;
        let mut slopes = Vec::new();
        for b in 0..batches {
            let spec = SimSpec::new(
                500,
                TimeGrid::from_times(vec![t1, t2]).unwrap(),
                0.0,
                1,
                1000 * (i as u64 + 1) + b,
            )
            .unwrap();
            let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
            let var = |k: usize| o.x2[k].mean() - o.x[k].mean().powi(2);
            slopes.push((var(1) - var(0)) / (2.0 * (t2 - t1)));
        }
        let n = batches as f64;
        let mean = slopes.iter().sum::<f64>() / n;
        let sd = (slopes.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let se = sd / n.sqrt();
        let d = linear::d_eff(&p).unwrap();
        assert!(
            ((mean - d) / se).abs() < 4.0,
            "lambda={lambda} r={r}: D = {mean} ± {se}, exact {d}"
        );
    }
}

/// Bit-identical results for rayon pools of 1 and 2 threads.
#[test]
fn identical_across_thread_counts() {
    let p = models::medium(DragLaw::Tan, 0.9, 2.0, 0.1);
    let spec = SimSpec::new(700, TimeGrid::linear(5.0, 11).unwrap(), 1.0, 30, 7).unwrap();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| exact::simulate(&p, &spec, &NoProgress).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(
        serde_json::to_string(&a).unwrap(),
        serde_json::to_string(&b).unwrap()
    );
}

/// The exact occupation-time density (time average over the window) and the
/// ensemble histogram at t_max are independent estimators of the same
/// stationary density: per-bin agreement within 4.5 combined standard errors
/// (Bonferroni over 16 bins: family-wise false alarm < 1.1e-4), for a
/// nonlinear drag with resetting, where no closed form exists.
#[test]
fn occupation_density_matches_final_histogram() {
    for (i, &(ref d, sigma, lambda, r, vr)) in [
        (DragLaw::Tan, 3.0, 0.9, 2.0, 0.3),
        (DragLaw::Tanh, 0.6, 1.2, 0.5, -0.2),
    ]
    .iter()
    .enumerate()
    {
        let p = Params::new(d.clone(), sigma, lambda, r, vr).unwrap();
        let spec = SimSpec::new(
            6000,
            TimeGrid::from_times(vec![0.0, 30.0]).unwrap(),
            15.0,
            16,
            500 + i as u64,
        )
        .unwrap();
        let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
        for k in 0..16 {
            let (a, b) = (&o.density_time[k], &o.density_final[k]);
            let se = (a.sem().powi(2) + b.sem().powi(2)).sqrt();
            let z = (a.mean() - b.mean()) / se;
            assert!(
                z.abs() < 4.5,
                "{d} bin {k}: {} vs {} (z = {z})",
                a.mean(),
                b.mean()
            );
        }
    }
}

/// Nonlinear drag with resetting, no closed form: the exact sampler's
/// stationary <v²> agrees within 4 standard errors with the library's Euler
/// scheme Richardson-extrapolated (and so does <x²>(t)) to dt → 0 from dt = 2e-3 and 1e-3
/// (2 E(dt/2) - E(dt) cancels the O(dt) bias, about 1% at r = 10).
#[test]
fn matches_richardson_extrapolated_euler() {
    use irtp::sim::euler;
    let p = models::tan(0.5, 10.0);
    let spec = |seed| {
        SimSpec::new(
            3000,
            TimeGrid::from_times(vec![0.0, 13.0]).unwrap(),
            3.0,
            10,
            seed,
        )
        .unwrap()
    };
    let ox = exact::simulate(&p, &spec(40), &NoProgress).unwrap();
    let o1 = euler::simulate(&p, &spec(41), 2e-3, &NoProgress).unwrap();
    let o2 = euler::simulate(&p, &spec(42), 1e-3, &NoProgress).unwrap();
    // 2 E(dt/2) - E(dt) against the exact estimate, within 4 combined SE.
    let check = |name: &str, ex: &MeanAcc, e1: &MeanAcc, e2: &MeanAcc| {
        let rich = 2.0 * e2.mean() - e1.mean();
        let se = (4.0 * e2.sem().powi(2) + e1.sem().powi(2) + ex.sem().powi(2)).sqrt();
        let msg = format!(
            "{name}: exact {} ± {}; Euler dt=2e-3 {} ± {}, dt=1e-3 {} ± {}; extrapolated {rich} ± {se}",
            ex.mean(),
            ex.sem(),
            e1.mean(),
            e1.sem(),
            e2.mean(),
            e2.sem()
        );
        eprintln!("{msg}");
        assert!(((rich - ex.mean()) / se).abs() < 4.0, "{msg}");
    };
    // Positions too: <x²>(t = 13) (exact displacement integrals vs Euler's
    // left-point rule, also O(dt)).
    check("<x²>(13)", &ox.x2[1], &o1.x2[1], &o2.x2[1]);
    check("<v²>", &ox.v2_time_avg, &o1.v2_time_avg, &o2.v2_time_avg);
}

/// Extreme but valid parameters: no events at all (lambda = r = 0, the
/// deterministic flow parks at v*), no flips, very fast resetting, huge
/// Sigma, Sigma near the tanh limit: every estimate finite, the occupation
/// density integrates to 1, and the deterministic case is exact.
#[test]
fn extreme_parameters_stay_finite() {
    for &(ref d, sigma, lambda, r, vr) in &[
        (DragLaw::Tan, 3.0, 0.0, 0.0, 0.0),
        (DragLaw::Tan, 3.0, 0.0, 5.0, 0.5),
        (DragLaw::Tanh, 0.6, 2.0, 1e4, -0.1),
        (DragLaw::Tan, 1000.0, 1.0, 1.0, 0.0),
        (DragLaw::Tanh, 0.999_999, 0.3, 0.1, 0.0),
        (DragLaw::Linear, 1.0, 50.0, 0.0, 0.0),
    ] {
        let p = Params::new(d.clone(), sigma, lambda, r, vr).unwrap();
        let t_max = if r > 100.0 { 0.5 } else { 40.0 };
        let spec =
            SimSpec::new(64, TimeGrid::linear(t_max, 9).unwrap(), 0.5 * t_max, 25, 3).unwrap();
        let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
        let s = o.summary();
        for x in [s.v2, s.v_mean, s.v2_final, s.x2_final] {
            assert!(x.is_finite(), "{d} {sigma} {lambda} {r}: {s:?}");
        }
        let w = o.bin_width();
        let mass: f64 = o.density_time.iter().map(|a| a.mean() * w).sum();
        assert!((mass - 1.0).abs() < 1e-9, "{d} {sigma}: mass {mass}");
        if lambda + r == 0.0 {
            assert_eq!(o.steps, 0);
            // Each particle follows the flow of its initial noise state.
            let t = t_max;
            let vu = p.v_upper();
            let v_end = d.flow_velocity(sigma, 0.0, t);
            assert!((o.v2[8].mean() - v_end * v_end).abs() < 1e-12);
            assert!(v_end <= vu);
        }
    }
}

/// `Method::Exact` dispatches to the exact sampler and serialises as
/// {"method": "exact"}.
#[test]
fn method_dispatch() {
    use irtp::sim::{simulate, Method};
    let p = models::tanh(0.85, 1.0);
    let spec = SimSpec::new(50, TimeGrid::linear(3.0, 4).unwrap(), 1.0, 8, 2).unwrap();
    let a = simulate(&p, &spec, Method::Exact, &NoProgress).unwrap();
    let b = exact::simulate(&p, &spec, &NoProgress).unwrap();
    assert_eq!(a, b);
    assert_eq!(Method::Exact.name(), "exact");
    assert_eq!(
        serde_json::to_string(&Method::Exact).unwrap(),
        r#"{"method":"exact"}"#
    );
}

/// The flow tables are shared between runs of one (law, Sigma, bins)
/// (`irtp::memo`): a run on shared tables, one on tables rebuilt after
/// eviction and the first run give the same numbers bit for bit.
#[test]
fn shared_tables_give_the_numbers_of_a_fresh_build() {
    let spec = SimSpec::new(
        64,
        TimeGrid::from_times(vec![0.0, 5.0]).unwrap(),
        1.0,
        20,
        9,
    )
    .unwrap();
    let run = |law: &str, sigma: f64| {
        let p = Params::new(law.parse::<DragLaw>().unwrap(), sigma, 0.5, 2.0, 0.0).unwrap();
        exact::simulate(&p, &spec, &NoProgress).unwrap()
    };
    let law = "expr:v + 0.2*v^3";
    let first = run(law, 2.0);
    let shared = run(law, 2.0);
    // More distinct set-ups than the store keeps evict the first.
    for k in 0..=irtp::memo::CAPACITY {
        run("tanh", 0.3 + 0.01 * k as f64);
    }
    let rebuilt = run(law, 2.0);
    assert_eq!(format!("{first:?}"), format!("{shared:?}"));
    assert_eq!(format!("{first:?}"), format!("{rebuilt:?}"));
}
