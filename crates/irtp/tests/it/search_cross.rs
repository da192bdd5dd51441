//! The search problem across methods, over the shared law list
//! (`irtp_testkit::laws::CROSS`): under full resetting (x and v reset to
//! (0, v_r), noise kept) the exact sampler's mean first-passage time to a
//! level agrees with the 2-D backward solver's Richardson-extrapolated
//! answer within z standard errors plus the solver's own error estimate
//! (z Bonferroni-corrected over every comparison of the test). The level
//! sits at half the distance a particle at top speed covers between resets
//! (L = v_u / (2 r)), so a search is neither instant nor rare at any rate.
//! The renewal route is checked against the direct solve in
//! `search_backward.rs`.

use irtp::mfpt::ParticleOptions;
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::search::backward::BackwardOptions;
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem};
use irtp::Params;
use irtp_testkit::laws::{law, Cross, CROSS};
use irtp_testkit::stats::bonferroni_z;

/// The search of `c` at reset rate `rate`.
fn problem(c: &Cross, rate: f64) -> SearchProblem {
    let p = Params::new(law(c.spec), c.sigma, c.lambda, rate, c.vr)
        .unwrap()
        .with_schedule(Schedule::parse(None, Some(0.0), None).unwrap())
        .unwrap();
    let l = p.v_upper() / (2.0 * rate);
    SearchProblem::new(p, 0.0, c.vr, PositionTarget::Level(l)).unwrap()
}

/// (tau, error) by `method`.
fn tau(p: &SearchProblem, method: SearchMethod) -> (f64, f64) {
    let r = search::solve(p, &method, &NoProgress).unwrap();
    let (tau, _, _, err) = r.tau();
    assert!(
        tau.is_finite() && err.is_finite(),
        "{}: {r:?}",
        method.name()
    );
    (tau, err)
}

/// Every case at every rate: sampler against backward; returns the worst
/// |difference| / tolerance.
fn sampler_vs_backward(cases: &[Cross], rates: &[f64], particles: u64, cells: (usize, usize)) {
    let z = bonferroni_z(cases.len() * rates.len());
    let mut worst = 0.0f64;
    for (i, c) in cases.iter().enumerate() {
        for &rate in rates {
            let p = problem(c, rate);
            let (exact, se) = tau(
                &p,
                SearchMethod::Exact(ParticleOptions {
                    particles,
                    t_max: f64::INFINITY,
                    seed: 40 + i as u64,
                }),
            );
            let (back, est) = tau(
                &p,
                SearchMethod::Backward(BackwardOptions::with_cells(cells.0, cells.1)),
            );
            let tol = z * se + est;
            let ratio = (exact - back).abs() / tol;
            println!(
                "{} r = {rate}: exact {exact:.5} ± {se:.5}, backward {back:.5} (est. {est:.2e}): |d|/tol = {ratio:.2}",
                c.spec
            );
            assert!(
                ratio < 1.0,
                "{} r = {rate}: exact {exact} ± {se} vs backward {back} ± {est} (z = {z:.2})",
                c.spec
            );
            worst = worst.max(ratio);
        }
    }
    println!("worst |d|/tol = {worst:.2} (z = {z:.2})");
}

/// The paper's media (tan, tanh) and the Newtonian reference at r = 1.
#[test]
fn sampler_agrees_with_the_backward_equation() {
    sampler_vs_backward(&CROSS[..3], &[1.0], 20_000, (32, 16));
}

/// Every registered law at a slow and a fast reset rate.
#[test]
#[ignore = "slow tier"]
fn sampler_agrees_with_the_backward_equation_for_every_law() {
    sampler_vs_backward(&CROSS, &[0.3, 3.0], 40_000, (48, 24));
}
