//! Renewal reset clocks (`irtp::model::reset::clock`, `--reset-clock`):
//! every law's validation (errors name `reset_clock`), its spec round trip
//! bit for bit, its draws against its CDF (Kolmogorov-Smirnov at the
//! 4-sigma family rate, Bonferroni over the laws) and its mean (within
//! z standard errors); the special cases bit for bit in the samplers
//! (`gamma:k=1,theta=1/R` = `exp:rate=R`, `fixed:t=T` = `--reset-period T`)
//! and in distribution (`exp:rate=R` against `--rate R`); the search
//! sampler against the renewal route under full resetting; the optimiser
//! of the mean waiting time against a dense scan.

use irtp::mfpt::optimize::RateRange;
use irtp::mfpt::ParticleOptions;
use irtp::model::reset::clock::{Clock, GammaClock, TableClock};
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::rng;
use irtp::search::clock_optimize::optimize_clock;
use irtp::search::renewal::{self, RenewalOptions, WaitingTime};
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem};
use irtp::sim::exact::simulate;
use irtp::sim::SimSpec;
use irtp::{DragLaw, Params};
use irtp_testkit::stats::{bonferroni_z, family_rate};

fn clock(s: &str) -> Clock {
    Clock::parse(s).unwrap()
}

/// The KS distance of `draws` (sorted here) to `cdf`.
fn ks(mut draws: Vec<f64>, cdf: impl Fn(f64) -> f64) -> f64 {
    draws.sort_by(f64::total_cmp);
    let n = draws.len() as f64;
    draws
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let f = cdf(x);
            (f - i as f64 / n).abs().max((f - (i + 1) as f64 / n).abs())
        })
        .fold(0.0, f64::max)
}

/// The KS critical distance for n draws, m comparisons (asymptotic
/// Kolmogorov tail 2 e^{-2 n D²} at the family rate over m).
fn ks_critical(n: usize, m: usize) -> f64 {
    ((2.0 * m as f64 / family_rate()).ln() / (2.0 * n as f64)).sqrt()
}

fn draws(c: &Clock, n: usize, seed: u64) -> Vec<f64> {
    let mut r = rng::stream(seed, 0);
    (0..n).map(|_| c.draw(&mut r)).collect()
}

/// A table of the Gamma(2, 0.5) survival on 4001 points to t = 20 (W <
/// 1e-15 there, set to 0).
fn gamma_table() -> Clock {
    let g = GammaClock { k: 2.0, theta: 0.5 };
    let t: Vec<f64> = (0..=4000).map(|i| i as f64 * 0.005).collect();
    let mut w: Vec<f64> = t
        .iter()
        .map(|&x| irtp::model::reset::clock::Law::survival(&g, x))
        .collect();
    w[0] = 1.0;
    *w.last_mut().unwrap() = 0.0;
    Clock::Table(TableClock::new(t, w).unwrap())
}

#[test]
fn bad_specs_name_reset_clock() {
    for bad in [
        "",
        "exp",
        "exp:rate=0",
        "exp:rate=-1",
        "exp:rate=nan",
        "exp:rate=inf",
        "exp:rate=1,rate=2",
        "exp:mean=1",
        "gamma:k=0,theta=1",
        "gamma:k=1",
        "gamma:k=NaN,theta=1",
        "weibull:k=1,scale=-2",
        "pareto:alpha=0,scale=1",
        "fixed:t=0",
        "table:0:1;1:0.5",
        "table:0:0.9;1:0",
        "table:0:1;1:0.2;0.5:0",
        "table:0:1;1:0.2;2:0.5;3:0",
        "table:0:1;x:0",
        "hazard:",
        "hazard:-1",
        "hazard:a-1",
        "hazard:exp(-a)",
        "hazard:v",
        "hazard:1/0",
        "poisson:rate=1",
    ] {
        let e = Clock::parse(bad).unwrap_err().to_string();
        assert!(e.starts_with("invalid reset_clock"), "{bad}: {e}");
    }
    // The reason is said: a cumulative hazard that does not diverge.
    let e = Clock::parse("hazard:exp(-a)").unwrap_err().to_string();
    assert!(e.contains("never come"), "{e}");
}

#[test]
fn specs_round_trip_bit_for_bit() {
    let third = 1.0 / 3.0;
    for c in [
        format!("exp:rate={}", 0.1 + 0.2),
        format!("gamma:k={third},theta=1e-7"),
        "weibull:k=0.7,scale=3".into(),
        "pareto:alpha=0.5,scale=0.25".into(),
        format!("fixed:t={}", 2.0f64.sqrt()),
        "table:0:1;0.1:0.75;0.3:0.2;1:0".into(),
        "hazard:2*a + sin(a)^2".into(),
    ] {
        let k = clock(&c);
        let again = clock(&k.spec());
        assert_eq!(again, k, "{c}");
        assert_eq!(again.spec(), k.spec());
        assert_eq!(
            again.mean().to_bits(),
            k.mean().to_bits(),
            "{c}: {}",
            k.spec()
        );
    }
}

/// 1e5 draws of each law against its CDF (KS) and its mean (z SE); the
/// constant hazard against the exponential, the table against the Gamma
/// it tabulates.
#[test]
fn draws_follow_the_law() {
    let n = 100_000;
    let laws = [
        ("exp:rate=1.5", None),
        ("gamma:k=0.5,theta=2", None),
        ("gamma:k=3,theta=0.4", None),
        ("weibull:k=0.7,scale=1.2", None),
        ("weibull:k=2.5,scale=0.8", None),
        ("pareto:alpha=3.5,scale=0.6", None),
        ("hazard:2*a", Some("weibull:k=2,scale=1")),
        ("hazard:1.5", Some("exp:rate=1.5")),
        ("hazard:0.5/sqrt(a)", Some("weibull:k=0.5,scale=1")),
    ];
    let m = laws.len() + 1;
    let (crit, z) = (ks_critical(n, m), bonferroni_z(m));
    let check = |name: &str, c: Clock, reference: Clock, seed: u64| {
        let d = draws(&c, n, seed);
        let mean = d.iter().sum::<f64>() / n as f64;
        let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let se = (var / n as f64).sqrt();
        let dist = ks(d, |t| reference.cdf(t));
        assert!(dist < crit, "{name}: KS {dist} >= {crit}");
        let m_ref = reference.mean();
        assert!(
            (mean - m_ref).abs() < z * se,
            "{name}: mean {mean} vs {m_ref} (se {se})"
        );
        assert!(
            (c.mean() - m_ref).abs() < 1e-9 * m_ref,
            "{name}: law mean {} vs {m_ref}",
            c.mean()
        );
    };
    for (i, (spec, reference)) in laws.iter().enumerate() {
        let c = clock(spec);
        check(spec, c, clock(reference.unwrap_or(spec)), 100 + i as u64);
    }
    let g = clock("gamma:k=2,theta=0.5");
    check("table of gamma", gamma_table(), g.clone(), 99);
    // The table's W is the Gamma's between its points to the linear
    // interpolation bound h² max|W''| / 8 = 0.005² · 4 / 8 = 1.25e-5.
    let t = gamma_table();
    let worst = (0..1000)
        .map(|i| 0.0137 * i as f64)
        .map(|x| (t.survival(x) - g.survival(x)).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1.25e-5, "table vs gamma W: {worst}");
}

/// with_mean keeps the shape and sets the mean; an infinite mean refuses.
#[test]
fn with_mean_rescales_time() {
    for s in [
        "exp:rate=2",
        "gamma:k=0.5,theta=2",
        "weibull:k=2,scale=1",
        "pareto:alpha=3,scale=1",
        "fixed:t=1",
        "table:0:1;1:0.5;2:0",
        "hazard:2*a",
    ] {
        let c = clock(s);
        let r = c.with_mean(0.37).unwrap();
        assert!((r.mean() - 0.37).abs() < 1e-9, "{s}: {}", r.mean());
        assert_eq!(r.kind(), c.kind());
        // Shape kept: W_r(t) = W(t m / m_r).
        let f = c.mean() / 0.37;
        for t in [0.1, 0.3, 0.9] {
            assert!(
                (r.survival(t) - c.survival(t * f)).abs() < 1e-9,
                "{s} at {t}"
            );
        }
    }
    let e = clock("pareto:alpha=1,scale=1").with_mean(1.0).unwrap_err();
    assert!(e.to_string().starts_with("invalid reset_clock"), "{e}");
}

fn full_reset(drag: DragLaw, sigma: f64, lambda: f64, rate: f64, sched: Schedule) -> Params {
    Params::new(drag, sigma, lambda, rate, 0.0)
        .unwrap()
        .with_schedule(sched)
        .unwrap()
}

fn sched(period: Option<f64>, position: Option<f64>, clock: Option<&str>) -> Schedule {
    Schedule::parse(period, position, None)
        .unwrap()
        .with_clock(clock)
        .unwrap()
}

/// `gamma:k=1,theta=1/R` and `exp:rate=R` draw the same bits, and so run
/// the same bits in simulate exact, mfpt exact and the search sampler;
/// `fixed:t=T` runs `--reset-period T`'s bits in simulate exact and the
/// search sampler.
#[test]
fn special_cases_bit_for_bit() {
    let rate = 1.7;
    let gamma = format!("gamma:k=1,theta={}", 1.0 / rate);
    let exp = format!("exp:rate={rate}");
    assert_eq!(draws(&clock(&gamma), 1000, 5), draws(&clock(&exp), 1000, 5));
    let grid = irtp::numerics::time_grid::TimeGrid::log(0.1, 7.6, 6).unwrap();
    let spec = SimSpec::new(400, grid, 0.6, 20, 7).unwrap();
    let pairs = [
        (
            sched(None, None, Some(&gamma)),
            sched(None, None, Some(&exp)),
        ),
        (
            sched(None, Some(0.0), Some("fixed:t=0.7")),
            sched(Some(0.7), Some(0.0), None),
        ),
    ];
    for (a, b) in pairs {
        let (pa, pb) = (
            full_reset(DragLaw::Tanh, 0.6, 1.0, 0.0, a.clone()),
            full_reset(DragLaw::Tanh, 0.6, 1.0, 0.0, b.clone()),
        );
        let (sa, sb) = (
            simulate(&pa, &spec, &NoProgress).unwrap(),
            simulate(&pb, &spec, &NoProgress).unwrap(),
        );
        assert_eq!(sa, sb, "simulate exact: {a:?} vs {b:?}");
        let (qa, qb) = (
            SearchProblem::new(pa, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap(),
            SearchProblem::new(pb, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap(),
        );
        for i in 0..200u64 {
            let s = (i % 2) as usize;
            let ra = search::exact::search_once(&qa, s, 1e4, &mut rng::stream(9, i)).unwrap();
            let rb = search::exact::search_once(&qb, s, 1e4, &mut rng::stream(9, i)).unwrap();
            assert_eq!(ra, rb, "search sampler, particle {i}");
        }
    }
    let (pa, pb) = (
        full_reset(
            DragLaw::Tanh,
            0.6,
            1.0,
            0.0,
            sched(None, None, Some(&gamma)),
        ),
        full_reset(DragLaw::Tanh, 0.6, 1.0, 0.0, sched(None, None, Some(&exp))),
    );
    let vt = 0.5 * pa.v_upper();
    for i in 0..200u64 {
        let f = |p: &Params| {
            irtp::mfpt::exact::first_passage_to(
                p,
                0.0,
                vt,
                (i % 2) as usize,
                1e4,
                &mut rng::stream(4, i),
            )
            .unwrap()
        };
        assert_eq!(f(&pa), f(&pb), "mfpt exact, particle {i}");
    }
}

/// The search time under full resetting by the sampler, (tau, SE).
fn sampled(p: Params, particles: u64, seed: u64) -> (f64, f64) {
    let problem = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    let m = SearchMethod::Exact(ParticleOptions {
        particles,
        t_max: f64::INFINITY,
        seed,
    });
    let r = search::solve(&problem, &m, &NoProgress).unwrap();
    let (tau, _, _, err) = r.tau();
    (tau, err)
}

/// `exp:rate=R` against `--rate R` (different streams): the same mean
/// search time within z SE combined.
#[test]
fn exp_clock_matches_the_poisson_rate() {
    let a = full_reset(
        DragLaw::Linear,
        1.0,
        0.5,
        0.0,
        sched(None, Some(0.0), Some("exp:rate=0.8")),
    );
    let b = full_reset(DragLaw::Linear, 1.0, 0.5, 0.8, sched(None, Some(0.0), None));
    let (ta, ea) = sampled(a, 40_000, 21);
    let (tb, eb) = sampled(b, 40_000, 21);
    let z = bonferroni_z(1);
    assert!(
        (ta - tb).abs() < z * ea.hypot(eb),
        "exp clock {ta} ± {ea} vs rate {tb} ± {eb}"
    );
}

/// Sampler against renewal route, each case (drag, clock): within z SE
/// plus the route's error estimate (Bonferroni over `cases`). Where the
/// route's mesh ladder is not asymptotic within its budget it refuses,
/// naming the mesh flags (a verdict, not an answer); every other refusal
/// fails, and so does a law without one resolved case.
fn sampler_vs_renewal(
    cases: &[(DragLaw, f64, &str)],
    particles: u64,
    total: usize,
    (steps, tail): (usize, f64),
) {
    let z = bonferroni_z(total);
    let opts = RenewalOptions {
        cells_x: 24,
        cells_v: 12,
        steps,
        tail,
        ..Default::default()
    };
    let mut resolved = std::collections::BTreeSet::new();
    for (i, &(ref drag, sigma, spec)) in cases.iter().enumerate() {
        let p = full_reset(
            drag.clone(),
            sigma,
            0.5,
            0.0,
            sched(None, Some(0.0), Some(spec)),
        );
        let problem = SearchProblem::new(p.clone(), 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
        let t0 = std::time::Instant::now();
        let route = match renewal::solve(&problem, &WaitingTime::of(&p).unwrap(), &opts) {
            Ok(route) => route,
            Err(e @ irtp::Error::Numerical { .. })
                if e.to_string().contains("meshes not asymptotic")
                    && e.to_string().contains("--cells-x") =>
            {
                eprintln!("{drag:?} {spec}: refused: {e}");
                continue;
            }
            Err(e) => panic!("{drag:?} {spec}: {e}"),
        };
        resolved.insert(spec.split(':').next().unwrap());
        let t1 = std::time::Instant::now();
        let (tau, se) = sampled(p, particles, 300 + i as u64);
        let diff = (tau - route.tau).abs();
        eprintln!(
            "{drag:?} {spec}: sampler {tau} ± {se} ({:?}), renewal {} ± {} ({:?})",
            t1.elapsed(),
            route.tau,
            route.error_estimate,
            t1 - t0
        );
        assert!(
            diff < z * se + route.error_estimate,
            "{drag:?} {spec}: sampler {tau} ± {se}, renewal {} ± {}",
            route.tau,
            route.error_estimate
        );
    }
    for &(_, _, spec) in cases {
        let law = spec.split(':').next().unwrap();
        assert!(resolved.contains(law), "no case of {law} resolved");
    }
}

/// Every law; the fixed clock on linear drag is left to
/// [`search_sampler_matches_the_renewal_route`], which checks that case
/// on the route's finer time mesh (80 steps to 1e-6, a smaller estimate).
const SLOW_CASES: [(DragLaw, f64, &str); 7] = [
    (DragLaw::Linear, 1.0, "gamma:k=0.5,theta=1.6"),
    (DragLaw::Tanh, 0.9, "gamma:k=3,theta=0.6"),
    (DragLaw::Linear, 1.0, "weibull:k=1.5,scale=1"),
    (DragLaw::Linear, 1.0, "pareto:alpha=2.5,scale=0.3"),
    (DragLaw::Tanh, 0.9, "fixed:t=3"),
    (DragLaw::Linear, 1.0, "table:0:1;0.5:0.8;1:0.5;2:0.1;4:0"),
    (DragLaw::Tanh, 0.9, "hazard:0.5+a"),
];

/// The fast subset: gamma (k = 3) and a fixed clock on linear drag (T = 3:
/// a period of 1.5 could not reach the level, the + flow from v = 0 covers
/// 1.5 - (1 - e^{-1.5}) = 0.72 < 1).
#[test]
fn search_sampler_matches_the_renewal_route() {
    sampler_vs_renewal(
        &[
            (DragLaw::Linear, 1.0, "gamma:k=3,theta=0.4"),
            (DragLaw::Linear, 1.0, "fixed:t=3"),
        ],
        20_000,
        2,
        (80, 1e-6),
    );
}

/// Every law, on a coarser time mesh of the route (40 steps to a horizon
/// where the clock's survival is 1e-4, instead of 80 to 1e-6). The route
/// is the whole cost (100 000 particles take about 1 s a case; the route
/// took 25 CPU-s for gamma k = 0.5, 8 s now, and more than 73 s for the
/// Pareto law's long horizon), and its mesh error (2-30% of tau) sets the
/// tolerance, not the sampler's SE (0.3%): the time error and the tail
/// bound, both in the route's estimate, add 0.06 to it for gamma k = 0.5
/// (18.09 ± 1.06 against 18.11 ± 1.00), whose tolerance z SE + estimate
/// grows from 6.8% to 7.2% of tau; a fixed clock has no tail and keeps
/// its 2%. A law whose sampler and renewal kernel disagree by more than
/// that is still caught.
#[test]
#[ignore = "slow tier: every law, linear and tanh drag"]
fn search_sampler_matches_the_renewal_route_every_law() {
    sampler_vs_renewal(&SLOW_CASES, 100_000, SLOW_CASES.len(), (40, 1e-4));
}

/// An infinite-mean law: a level is never reached in finite mean time (a
/// failed period lasts the waiting time), and the renewal route reports it
/// as the exact sampler's verdict (tau = +inf); an interval's mean is finite
/// (every period ends at the exit or a reset) but the route's horizon cannot
/// bound the neglected tail, so it is refused by name.
#[test]
fn renewal_route_on_an_infinite_mean_law() {
    let p = full_reset(
        DragLaw::Linear,
        1.0,
        0.5,
        0.0,
        sched(None, Some(0.0), Some("pareto:alpha=0.8,scale=0.5")),
    );
    let waiting = WaitingTime::of(&p).unwrap();
    let problem = SearchProblem::new(p.clone(), 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    let s = renewal::solve(&problem, &waiting, &Default::default()).unwrap();
    assert!(s.infinite_mean && s.tau == f64::INFINITY, "{s:?}");
    assert!(!problem.mean_is_finite());
    let interval = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Interval(-1.0, 1.0)).unwrap();
    assert!(interval.mean_is_finite());
    let e = renewal::solve(&interval, &waiting, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("invalid reset_clock"), "{e}");
}

/// Full resetting, fixed clock, linear drag: tau(T) has an interior
/// minimum; the optimiser's T* (the shared minimiser over the reset
/// frequency 1/T) agrees with a dense scan of the renewal route (within
/// the scan's spacing and the optimum's range); a range that stops below
/// the optimal frequency reports the minimum at its upper bound; a
/// problem without a clock is refused naming `reset_clock`.
#[test]
fn optimum_mean_matches_a_dense_scan() {
    let p = full_reset(
        DragLaw::Linear,
        1.0,
        0.5,
        0.0,
        sched(None, Some(0.0), Some("fixed:t=1")),
    );
    let problem = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    let opts = RenewalOptions {
        cells_x: 16,
        cells_v: 8,
        refine: false,
        steps: 40,
        ..Default::default()
    };
    let c = clock("fixed:t=1");
    let range = RateRange {
        r_min: 0.05,
        r_max: 2.0,
        grid_points: 13,
        rtol: 1e-4,
    };
    let best = optimize_clock(&problem, &range, &opts, &NoProgress).unwrap();
    assert!(best.optimum.interior && !best.optimum.at_upper_bound);
    let scan: Vec<(f64, f64)> = (0..=40)
        .map(|i| 0.5 * (40f64).powf(i as f64 / 40.0))
        .map(|m| {
            let w = WaitingTime::Renewal {
                clock: c.with_mean(m).unwrap(),
            };
            (m, renewal::solve(&problem, &w, &opts).unwrap().tau)
        })
        .collect();
    let (m_scan, tau_scan) =
        scan.iter()
            .copied()
            .fold((0.0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    let spacing = (40f64).powf(1.0 / 40.0);
    let (lo, hi) = best.mean_range;
    assert!(
        lo <= m_scan * spacing && m_scan / spacing <= hi && lo <= best.mean && best.mean <= hi,
        "optimum {} in [{lo}, {hi}] vs scan {m_scan}",
        best.mean
    );
    assert!(
        (best.mean - m_scan).abs() <= m_scan * (spacing - 1.0),
        "optimum {} vs scan {m_scan} (spacing {spacing})",
        best.mean
    );
    assert!(
        best.optimum.tau_opt <= tau_scan + 1e-9 * tau_scan,
        "{} vs {tau_scan}",
        best.optimum.tau_opt
    );
    assert_eq!(
        best.clock.unwrap().with_mean(1.0).unwrap(),
        c.with_mean(1.0).unwrap()
    );
    let low = RateRange {
        r_max: 0.5 / best.mean,
        r_min: 0.05 / best.mean,
        ..range
    };
    let edge = optimize_clock(&problem, &low, &opts, &NoProgress).unwrap();
    assert!(edge.optimum.at_upper_bound, "{:?}", edge.optimum);
    let plain = SearchProblem::new(
        full_reset(DragLaw::Linear, 1.0, 0.5, 1.0, sched(None, Some(0.0), None)),
        0.0,
        0.0,
        PositionTarget::Level(1.0),
    )
    .unwrap();
    let e = optimize_clock(&plain, &range, &opts, &NoProgress)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("invalid reset_clock"), "{e}");
}
