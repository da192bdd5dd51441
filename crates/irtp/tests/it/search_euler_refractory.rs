//! The search's Euler scheme with refractory periods (exponential and
//! fixed, the paper's noise and run-pause-tumble noise) and a renewal
//! reset clock (alone and with a hold): extrapolated to dt → 0 against the
//! exact sampler, whose hold is exact (v held at the reset velocity, x
//! moving linearly, resets off, the noise jumping on).

use irtp::mfpt::ParticleOptions;
use irtp::model::noise::NoiseModel;
use irtp::model::reset::clock::Clock;
use irtp::model::reset::{NoiseAtReset, Schedule, Target};
use irtp::parallel::NoProgress;
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem, SearchResult};
use irtp::{DragLaw, Params};
use irtp_testkit::stats::bonferroni_z;

fn run(seed: u64) -> ParticleOptions {
    ParticleOptions {
        particles: 20_000,
        t_max: 1e4,
        seed,
    }
}

/// Full resetting to x_r = 0 with the velocity reset to 0.2 (x moves
/// during a hold) at rate 0.5 (0 with a clock), the refractory law
/// `hold` ("" for none) and the renewal clock `clock` ("" for none), from
/// (0, 0) to the interval (-0.7, 0.5).
fn problem(params: Params, hold: &str, clock: &str) -> SearchProblem {
    let hold = (!hold.is_empty()).then_some(hold);
    let mut schedule = Schedule::parse(None, Some(0.0), hold).unwrap();
    let mut params = params;
    if !clock.is_empty() {
        schedule.clock = Some(Clock::parse(clock).unwrap());
        params = params.with_rate(0.0).unwrap();
    }
    let params = params
        .with_schedule(schedule)
        .unwrap()
        .with_reset(Target::point(0.2), NoiseAtReset::Kept)
        .unwrap();
    SearchProblem::new(params, 0.0, 0.0, PositionTarget::Interval(-0.7, 0.5)).unwrap()
}

/// The exact sampler's tau against the Euler scheme's 2 T(dt/2) - T(dt)
/// (standard error sqrt(4 se_f² + se_c²), a bound: both steps run the
/// same streams), within z times the combined standard error, z
/// Bonferroni over the 5 cases.
#[test]
fn euler_with_a_refractory_period_matches_the_exact_sampler() {
    let paper = Params::new(DragLaw::Linear, 1.0, 0.5, 0.5, 0.0).unwrap();
    let rpt = NoiseModel::parse("rpt:sigma=1,alpha=1,beta=2", 0.0).unwrap();
    let rpt = Params::with_noise(DragLaw::Linear, rpt, 0.5, 0.0).unwrap();
    let cases = [
        (paper.clone(), "exp:mean=0.5", ""),
        (paper.clone(), "fixed:t=0.5", ""),
        (rpt, "exp:mean=0.5", ""),
        (paper.clone(), "", "gamma:k=2,theta=0.5"),
        (paper, "fixed:t=0.3", "gamma:k=2,theta=0.5"),
    ];
    let z = bonferroni_z(cases.len());
    for (k, (params, hold, clock)) in cases.into_iter().enumerate() {
        let pr = problem(params.clone(), hold, clock);
        let seed = 500 + 2 * k as u64;
        let (tau, se) = match search::solve(&pr, &SearchMethod::Exact(run(seed)), &NoProgress) {
            Ok(SearchResult::Particles(r)) => {
                let s = r.stats.summary();
                (s.tau, s.tau_err)
            }
            other => panic!("the exact sampler gave {other:?}"),
        };
        let m = SearchMethod::Euler {
            dt: 0.01,
            run: run(seed + 1),
        };
        let (ext, se_ext) = match search::solve(&pr, &m, &NoProgress) {
            Ok(SearchResult::Euler(e)) => {
                let (c, f) = (e.coarse.summary(), e.fine.summary());
                (
                    2.0 * f.tau - c.tau,
                    (4.0 * f.tau_err.powi(2) + c.tau_err.powi(2)).sqrt(),
                )
            }
            other => panic!("the Euler scheme gave {other:?}"),
        };
        let zk = (tau - ext).abs() / se.hypot(se_ext);
        eprintln!(
            "{hold} (noise {:?}): exact {tau} ± {se}, euler {ext} ± {se_ext}, z {zk}",
            params.noise().is_some()
        );
        assert!(
            zk < z,
            "{hold} {clock}: exact {tau} ± {se} vs euler {ext} ± {se_ext}"
        );
    }
}
