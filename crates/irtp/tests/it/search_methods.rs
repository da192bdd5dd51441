//! The search problem's particle runs beyond the exact sampler: the Euler
//! scheme at dt and dt/2 extrapolated to dt → 0 against the exact sampler,
//! and particle runs cut into units of particles whose merged totals are
//! bit-identical to the run made whole (velocity target and search, exact
//! and Euler), for any thread count.

use irtp::mfpt::{self, ParticleOptions, Problem};
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem, SearchResult};
use irtp::{DragLaw, Params};

/// Full resetting to (x_r, v_r) = (0, 0) at rate `rate` (noise kept).
fn full(law: DragLaw, sigma: f64, rate: f64) -> Params {
    let schedule = Schedule::parse(None, Some(0.0), None).unwrap();
    Params::new(law, sigma, 1.0, rate, 0.0)
        .unwrap()
        .with_schedule(schedule)
        .unwrap()
}

fn run(particles: u64, seed: u64) -> ParticleOptions {
    ParticleOptions {
        particles,
        t_max: 1e4,
        seed,
    }
}

/// The Euler estimate extrapolated to dt → 0 agrees with the exact sampler
/// within 4 combined standard errors (Bonferroni over the 2 problems:
/// 4 sigma is a two-sided chance below 1.3e-4 each), for linear drag with
/// a level and tan drag with an interval, both under full resetting; the
/// extrapolation is 2 T(dt/2) - T(dt), bit for bit.
#[test]
fn euler_search_extrapolates_to_the_exact_sampler() {
    let cases = [
        (
            full(DragLaw::Linear, 1.0, 0.5),
            0.0,
            PositionTarget::Level(0.8),
        ),
        (
            full(DragLaw::Tan, 1.0, 1.0),
            0.1,
            PositionTarget::Interval(-0.6, 0.5),
        ),
    ];
    for (p, v0, target) in cases {
        let pr = SearchProblem::new(p, 0.0, v0, target).unwrap();
        let euler = SearchMethod::Euler {
            dt: 0.02,
            run: run(40_000, 11),
        };
        let SearchResult::Euler(e) = search::solve(&pr, &euler, &NoProgress).unwrap() else {
            panic!("an Euler result")
        };
        let (c, f) = (e.coarse.summary(), e.fine.summary());
        assert_eq!(e.extrapolated.tau, 2.0 * f.tau - c.tau);
        assert_eq!(e.extrapolated.tau_err, 2.0 * f.tau_err + c.tau_err);
        let exact = search::solve(&pr, &SearchMethod::Exact(run(40_000, 12)), &NoProgress).unwrap();
        let (tau, _, _, err) = exact.tau();
        let (ex, _, _, ex_err) = SearchResult::Euler(e.clone()).tau();
        let z = (ex - tau).abs() / (ex_err * ex_err + err * err).sqrt();
        assert!(
            z < 4.0,
            "{target:?}: Euler extrapolated {ex} ± {ex_err}, exact {tau} ± {err} (z = {z:.2}); \
             dt: {} ± {}, dt/2: {} ± {}",
            c.tau,
            c.tau_err,
            f.tau,
            f.tau_err
        );
        assert!(e.mean_is_finite && c.censored == 0 && f.censored == 0);
    }
}

/// The Euler sampler refuses a step beyond its limits and a refractory
/// period by name.
#[test]
fn euler_search_refuses_by_name() {
    let pr = SearchProblem::new(full(DragLaw::Linear, 1.0, 0.5), 0.0, 0.0, PositionTarget::Level(1.0))
        .unwrap();
    let name = |m: SearchMethod, pr: &SearchProblem| match m.check(pr).unwrap_err() {
        irtp::Error::InvalidParameter { name, .. } => name,
        e => panic!("{e}"),
    };
    let euler = |dt, t_max| SearchMethod::Euler {
        dt,
        run: ParticleOptions {
            particles: 100,
            t_max,
            seed: 1,
        },
    };
    assert_eq!(name(euler(-0.1, 10.0), &pr), "dt");
    assert_eq!(name(euler(3.0, 10.0), &pr), "dt");
    assert_eq!(name(euler(0.01, f64::INFINITY), &pr), "t_max");
    let held = full(DragLaw::Linear, 1.0, 0.5)
        .with_schedule(Schedule::parse(None, Some(0.0), Some("fixed:t=0.1")).unwrap())
        .unwrap();
    let pr = SearchProblem::new(held, 0.0, 0.0, PositionTarget::Level(1.0)).unwrap();
    assert_eq!(name(euler(0.01, 10.0), &pr), "refractory");
}

/// Unit ranges for `parts` parts of `units` units.
fn split(units: u64, parts: u64) -> Vec<std::ops::Range<u64>> {
    (0..parts)
        .map(|k| k * units / parts..(k + 1) * units / parts)
        .collect()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// A particle run cut into 3 parts (unit ranges computed separately, on 1
/// or 2 threads) and assembled gives the run made whole on 1 thread, bit
/// for bit: the search's exact and Euler methods, and the velocity
/// target's.
#[test]
fn particle_runs_in_parts_are_bit_identical_to_the_whole() {
    let n = 3 * irtp::parallel::UNIT + 3;
    let pr = SearchProblem::new(full(DragLaw::Tanh, 0.6, 1.0), 0.0, 0.1, PositionTarget::Level(0.3))
        .unwrap();
    for method in [
        SearchMethod::Exact(run(n, 5)),
        SearchMethod::Euler {
            dt: 0.05,
            run: run(n, 6),
        },
    ] {
        let whole = pool(1).install(|| search::solve(&pr, &method, &NoProgress).unwrap());
        let units = method.unit_count().unwrap();
        assert!(units >= 3);
        for threads in [1, 2] {
            let parts: Vec<_> = split(units, 3)
                .into_iter()
                .flat_map(|r| {
                    pool(threads).install(|| {
                        search::particle_units(&pr, &method, r, &NoProgress).unwrap()
                    })
                })
                .collect();
            let merged = search::assemble(&pr, &method, &parts).unwrap();
            assert_eq!(merged, whole, "{} on {threads} threads", method.name());
        }
        let bad = search::particle_units(&pr, &method, 0..units + 1, &NoProgress);
        assert!(bad.is_err());
        assert!(search::assemble(&pr, &method, &[]).is_err());
    }
    let p = Params::new(DragLaw::Tanh, 0.6, 0.5, 0.2, 0.0).unwrap();
    let vp = Problem::new(p, -0.249, 0.1).unwrap();
    for method in [
        mfpt::Method::Exact(run(n, 7)),
        mfpt::Method::Euler {
            dt: 0.01,
            run: run(n, 8),
        },
    ] {
        let whole = pool(1).install(|| mfpt::solve(&vp, &method, &NoProgress).unwrap());
        let units = method.unit_count().unwrap();
        for threads in [1, 2] {
            let parts: Vec<_> = split(units, 3)
                .into_iter()
                .flat_map(|r| {
                    pool(threads)
                        .install(|| mfpt::particle_units(&vp, &method, r, &NoProgress).unwrap())
                })
                .collect();
            let merged = mfpt::assemble(&vp, &method, &parts).unwrap();
            assert_eq!(merged, whole, "{} on {threads} threads", method.name());
        }
    }
}
