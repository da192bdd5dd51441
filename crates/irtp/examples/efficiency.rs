//! Side-by-side efficiency of the exact event-driven sampler and the paper's
//! Euler scheme (dt = 1e-3), same parameters, same particle counts, one run:
//! efficiency = 1 / (wall time × variance of the estimate), on the
//! stationary <v²> (per-particle time average) and on the MFPT of v to v_t.
//! Also prints the Euler bias (Euler - exact, with its standard error).
//!
//! cargo run --release --example efficiency -- [particles] [fpt_particles]
//!
//! Both sides use the library: `irtp::sim::euler` vs `irtp::sim::exact`
//! (same observables) for <v²>, and `irtp::mfpt::solve` with
//! `Method::Euler` vs `Method::Exact` (same driver) for the MFPT, whose
//! backward-equation value (`Method::Backward`) is printed as reference.

use irtp::mfpt::{self, BackwardOptions, Method, ParticleOptions, Problem};
use irtp::parallel::NoProgress;
use irtp::sim::{euler, exact, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};
use std::time::Instant;

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t0 = Instant::now();
    let r = f();
    (r, t0.elapsed().as_secs_f64())
}

fn main() {
    let args: Vec<u64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("integer argument"))
        .collect();
    let particles = args.first().copied().unwrap_or(2000);
    let fpt_particles = args.get(1).copied().unwrap_or(20000);
    let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap();
    let dt = 1e-3;
    let (burn, t_max) = (10.0, 110.0);
    println!(
        "tan Sigma=3 lambda=0.5 r=2 v_r=0; Euler dt={dt}; {} rayon threads",
        rayon::current_num_threads()
    );

    // Stationary <v²>: per-particle time average over [10, 110].
    let spec = SimSpec::new(
        particles,
        TimeGrid::from_times(vec![0.0, t_max]).unwrap(),
        burn,
        100,
        11,
    )
    .unwrap();
    let (ex, w_ex) = timed(|| exact::simulate(&p, &spec, &NoProgress).unwrap());
    let (eo, w_eu) = timed(|| euler::simulate(&p, &spec, dt, &NoProgress).unwrap());
    let ev = eo.v2_time_avg;
    let (a, b) = (&ex.v2_time_avg, &ev);
    let fp = irtp::fp::stationary(&p, &irtp::fp::StationaryOptions::default()).unwrap();
    println!(
        "\nstationary <v^2>, {particles} particles, window [{burn}, {t_max}] (Fokker-Planck: {:.6}):",
        fp.v2
    );
    println!(
        "  exact: {:.6} ± {:.6}  wall {:.3} s  ({} events)",
        a.mean(),
        a.sem(),
        w_ex,
        ex.steps
    );
    println!(
        "  euler: {:.6} ± {:.6}  wall {:.3} s  ({} steps)",
        b.mean(),
        b.sem(),
        w_eu,
        eo.steps
    );
    let ratio = (w_eu * b.sem().powi(2)) / (w_ex * a.sem().powi(2));
    println!("  efficiency ratio exact/euler (wall × variance): {ratio:.1}");
    let bias = b.mean() - a.mean();
    let se = (a.sem().powi(2) + b.sem().powi(2)).sqrt();
    println!(
        "  euler bias: {bias:.6} ± {se:.6} ({:.2}% of <v^2>, z = {:.1})",
        100.0 * bias / a.mean(),
        bias / se
    );
    for (name, acc) in [("exact", a), ("euler", b)] {
        let d = acc.mean() - fp.v2;
        println!(
            "  {name} - FP: {d:.6} ± {:.6} (z = {:.1})",
            acc.sem(),
            d / acc.sem()
        );
    }

    // MFPT from v0 = 0 to v_t = 0.8 (start states stratified ±, both methods
    // through the same driver), with the backward-equation value.
    let vt = 0.8;
    let t_cap = 1e4;
    let problem = Problem::new(p, 0.0, vt).unwrap();
    let solve = |m: Method| mfpt::solve(&problem, &m, &NoProgress).unwrap();
    let ode = solve(Method::Backward(BackwardOptions::default()));
    let run = |seed| ParticleOptions {
        particles: fpt_particles,
        t_max: t_cap,
        seed,
    };
    let (fx, w_fx) = timed(|| solve(Method::Exact(run(21))).summary().unwrap());
    let (fe, w_fe) = timed(|| solve(Method::Euler { dt, run: run(22) }).summary().unwrap());
    let ode = ode.backward().unwrap();
    println!(
        "\nMFPT 0 -> {vt}, {fpt_particles} particles (backward equations: {:.6}):",
        ode.tau
    );
    println!(
        "  exact: {:.6} ± {:.6}  wall {:.3} s  (censored {}, {:.1} events/particle)",
        fx.tau, fx.tau_err, w_fx, fx.censored, fx.work_per_particle
    );
    println!(
        "  euler: {:.6} ± {:.6}  wall {:.3} s  (censored {}, {:.0} steps/particle)",
        fe.tau, fe.tau_err, w_fe, fe.censored, fe.work_per_particle
    );
    let ratio = (w_fe * fe.tau_err.powi(2)) / (w_fx * fx.tau_err.powi(2));
    println!("  efficiency ratio exact/euler (wall × variance): {ratio:.1}");
    for (name, est, se) in [("exact", fx.tau, fx.tau_err), ("euler", fe.tau, fe.tau_err)] {
        println!(
            "  {name} - backward: {:.6} ± {se:.6} (z = {:.1})",
            est - ode.tau,
            (est - ode.tau) / se
        );
    }
}
