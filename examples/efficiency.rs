//! Side-by-side efficiency of the exact event-driven sampler and the paper's
//! Euler scheme (dt = 1e-3), same parameters, same particle counts, one run:
//! efficiency = 1 / (wall time × variance of the estimate), on the
//! stationary <v²> (per-particle time average) and on the MFPT of v to v_t.
//! Also prints the Euler bias (Euler - exact, with its standard error).
//!
//! cargo run --release --example efficiency -- [particles] [fpt_particles]
//!
//! Stationary <v²>: the library's Euler simulation (`irtp::sim::euler`, same
//! observables). MFPT: a minimal Euler first-passage loop, the paper's scheme
//! (Eqs. 14-16) v += dt(η - g(v)), a noise flip w.p. ½(1 - e^{-2λ dt}) and a
//! reset w.p. r dt per step, drawn as geometric gaps (the fastest form).

use irtp::parallel::{self, NoProgress};
use irtp::rng::{self, Rng};
use irtp::sim::{euler, exact, SimSpec, TimeGrid};
use irtp::stats::MeanAcc;
use irtp::{DragLaw, Params};
use rand::Rng as _;
use std::time::Instant;

/// Steps until the next success of per-step probability p (≥ 1).
fn geometric(rng: &mut Rng, ln_1mp: f64) -> u64 {
    if ln_1mp == 0.0 {
        return u64::MAX;
    }
    let u = 1.0 - rng.gen::<f64>();
    1 + (u.ln() / ln_1mp).floor().min(1e18) as u64
}

struct Euler {
    sigma: f64,
    vr: f64,
    dt: f64,
    ln_flip: f64,
    ln_reset: f64,
}

impl Euler {
    fn new(p: &Params, dt: f64) -> Self {
        let pf = 0.5 * (1.0 - (-2.0 * p.lambda() * dt).exp());
        let pr = p.rate() * dt;
        Euler {
            sigma: p.sigma(),
            vr: p.reset_velocity(),
            dt,
            ln_flip: (-pf).ln_1p(),
            ln_reset: (-pr).ln_1p(),
        }
    }

    /// First step time at which v ≥ vt (None if not by t_max).
    fn fpt(&self, rng: &mut Rng, vt: f64, t_max: f64) -> Option<f64> {
        let mut eta = if rng.gen::<bool>() {
            self.sigma
        } else {
            -self.sigma
        };
        let mut v = 0.0f64;
        let (mut next_flip, mut next_reset) =
            (geometric(rng, self.ln_flip), geometric(rng, self.ln_reset));
        let n = (t_max / self.dt) as u64;
        for step in 1..=n {
            v += self.dt * (eta - v.tan());
            if v >= vt {
                return Some(step as f64 * self.dt);
            }
            if step == next_flip {
                eta = -eta;
                next_flip += geometric(rng, self.ln_flip);
            }
            if step == next_reset {
                v = self.vr;
                next_reset += geometric(rng, self.ln_reset);
            }
        }
        None
    }
}

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
    println!("\nstationary <v^2>, {particles} particles, window [{burn}, {t_max}]:");
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

    // MFPT from v0 = 0 (noise ± equally likely) to v_t = 0.8.
    let vt = 0.8;
    let t_cap = 1e4;
    let collect = |f: &(dyn Fn(u64) -> Option<f64> + Sync)| {
        parallel::reduce(
            fpt_particles,
            || (MeanAcc::new(), 0u64),
            |i, acc| match f(i) {
                Some(t) => acc.0.push(t),
                None => acc.1 += 1,
            },
            |a, b| {
                a.0.merge(&b.0);
                a.1 += b.1;
            },
            &NoProgress,
        )
    };
    let ((fx, cx), w_fx) = timed(|| {
        let fpt = exact::FirstPassage::new(&p);
        collect(&|i| {
            let mut r = rng::stream(21, i);
            let plus = r.gen::<bool>();
            fpt.run(0.0, vt, plus, t_cap, &mut r).0
        })
    });
    let eu = Euler::new(&p, dt);
    let ((fe, ce), w_fe) = timed(|| collect(&|i| eu.fpt(&mut rng::stream(22, i), vt, t_cap)));
    println!("\nMFPT 0 -> {vt}, {fpt_particles} particles:");
    println!(
        "  exact: {:.6} ± {:.6}  wall {:.3} s  (censored {cx})",
        fx.mean(),
        fx.sem(),
        w_fx
    );
    println!(
        "  euler: {:.6} ± {:.6}  wall {:.3} s  (censored {ce})",
        fe.mean(),
        fe.sem(),
        w_fe
    );
    let ratio = (w_fe * fe.sem().powi(2)) / (w_fx * fx.sem().powi(2));
    println!("  efficiency ratio exact/euler (wall × variance): {ratio:.1}");
    let bias = fe.mean() - fx.mean();
    let se = (fx.sem().powi(2) + fe.sem().powi(2)).sqrt();
    println!(
        "  euler bias: {bias:.6} ± {se:.6} ({:.2}%, z = {:.1})",
        100.0 * bias / fx.mean(),
        bias / se
    );
}
