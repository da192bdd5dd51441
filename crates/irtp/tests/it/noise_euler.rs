//! The Euler schemes with a noise model (docs/equations.md, "Euler
//! schemes with a noise model", Eqs. (N15)-(N19)): `sim::euler` and
//! `mfpt::euler` over `irtp_testkit::noises::NOISE_CASES`, extrapolated in
//! dt (2 m(dt/2) - m(dt), independent seeds, Var = 4 Var_fine +
//! Var_coarse), against the closed forms of linear drag
//! (`analytic::linear_noise`), the r = 0 density of an asymmetric
//! telegraph noise (`analytic::telegraph_r0`), the Siegert formula of the
//! Ornstein-Uhlenbeck passage time and a finite-difference solve of the
//! backward equation of diffusion with resetting written here. Tolerances:
//! 4 standard errors, Bonferroni-corrected over each test's comparisons.

use irtp::analytic::linear_noise::LinearNoise;
use irtp::analytic::telegraph_r0::TelegraphR0Density;
use irtp::mfpt::euler::extrapolate;
use irtp::mfpt::{EulerFpt, Problem};
use irtp::model::noise::{NoiseKind, NoiseModel};
use irtp::parallel::NoProgress;
use irtp::sim::{self, Method, Observables, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};
use irtp_testkit::noises::{NoiseCase, NOISE_CASES};
use irtp_testkit::stats::bonferroni_z;

fn run(p: &Params, dt: f64, particles: u64, t_max: f64, burn_in: f64, seed: u64) -> Observables {
    let grid = TimeGrid::linear(t_max, 3).unwrap();
    let spec = SimSpec::new(particles, grid, burn_in, 20, seed).unwrap();
    sim::simulate(p, &spec, Method::euler(dt), &NoProgress).unwrap()
}

/// A value and its standard error.
#[derive(Clone, Copy, Debug)]
struct Est(f64, f64);

impl Est {
    /// 2 fine - coarse, independent runs.
    fn extrapolate(coarse: Est, fine: Est) -> Est {
        Est(
            2.0 * fine.0 - coarse.0,
            (4.0 * fine.1 * fine.1 + coarse.1 * coarse.1).sqrt(),
        )
    }
    fn check(self, exact: f64, z: f64, what: &str) {
        let dev = (self.0 - exact).abs() / self.1;
        println!(
            "{what}: {:.6} ± {:.6} vs {exact:.6} ({dev:.2} SE)",
            self.0, self.1
        );
        assert!(
            dev < z,
            "{what}: {} ± {} vs {exact} ({dev:.2} SE > {z:.2})",
            self.0,
            self.1
        );
    }
}

/// (<v>, <v²>, D_eff) of one run: the window time averages and
/// (Var x(t_max) - Var x(t_max/2)) / t_max, whose standard error is bounded
/// for any correlation by the sum of the two variances' (Gaussian x:
/// se(Var) = Var sqrt(2/(n-1))).
fn moments(o: &Observables) -> [Est; 3] {
    let s = o.summary();
    let var = |k: usize| {
        let (m, m2, n) = (o.x[k].mean(), o.x2[k].mean(), o.x[k].n as f64);
        let v = m2 - m * m;
        (v, v * (2.0 / (n - 1.0)).sqrt())
    };
    let (k1, k2) = (1, 2);
    let dt = o.times[k2] - o.times[k1];
    let ((v1, e1), (v2, e2)) = (var(k1), var(k2));
    [
        Est(s.v_mean, s.v_mean_err),
        Est(s.v2, s.v2_err),
        Est((v2 - v1) / (2.0 * dt), (e1 + e2) / (2.0 * dt)),
    ]
}

fn extrapolated(p: &Params, dt: f64, n: u64, t_max: f64, burn_in: f64, seed: u64) -> [Est; 3] {
    let c = moments(&run(p, dt, n, t_max, burn_in, seed));
    let f = moments(&run(p, dt / 2.0, n, t_max, burn_in, seed + 1));
    [0, 1, 2].map(|i| Est::extrapolate(c[i], f[i]))
}

/// Linear drag, every linear case (thermal ones included): the
/// dt-extrapolated stationary <v>, <v²> and D_eff against Eqs. (N3)-(N6).
#[test]
#[ignore = "slow tier: Euler with six noise models at two steps (~10 s)"]
fn linear_cases_extrapolate_to_the_closed_forms() {
    let cases: Vec<&NoiseCase> = NOISE_CASES.iter().filter(|c| c.linear()).collect();
    let z = bonferroni_z(3 * cases.len());
    for (i, c) in cases.iter().enumerate() {
        let p = c.params();
        let m = NoiseModel::parse(c.noise, c.temperature).unwrap();
        let exact = LinearNoise::new(1.0, m, c.rate, c.reset_velocity)
            .unwrap()
            .moments()
            .unwrap();
        let got = extrapolated(&p, 0.02, 8000, 40.0, 8.0, 100 + 2 * i as u64);
        got[0].check(exact.v_mean, z, &format!("{} <v>", c.name));
        got[1].check(exact.v2, z, &format!("{} <v²>", c.name));
        got[2].check(exact.d_eff, z, &format!("{} D_eff", c.name));
    }
}

/// The asymmetric telegraph cases at r = 0: the dt-extrapolated bin
/// densities of the 18 interior bins of 20 (the two edge bins hold the
/// integrable edge singularities of Eq. (N8)) against the bin averages of
/// `TelegraphR0Density` (Simpson, 64 panels per bin), and <v>, <v²>.
#[test]
#[ignore = "slow tier: Euler histograms of three drags at two steps (~10 s)"]
fn asymmetric_telegraph_at_r0_has_the_density_of_eq_n8() {
    let cases: Vec<NoiseCase> = NOISE_CASES
        .iter()
        .filter(|c| c.noise.starts_with("telegraph:plus") && !c.thermal())
        .map(|c| c.at_rate(0.0))
        .collect();
    assert_eq!(cases.len(), 3);
    let z = bonferroni_z(20 * cases.len());
    for (i, c) in cases.iter().enumerate() {
        let p = c.params();
        let NoiseKind::Telegraph(t) = NoiseModel::parse(c.noise, 0.0).unwrap().kind().clone()
        else {
            panic!("telegraph");
        };
        let exact = TelegraphR0Density::new(p.drag(), t).unwrap();
        let seed = 300 + 2 * i as u64;
        let (co, fi) = (
            run(&p, 0.02, 4000, 40.0, 5.0, seed),
            run(&p, 0.01, 4000, 40.0, 5.0, seed + 1),
        );
        let w = co.bin_width();
        for b in 1..19 {
            let (a, e) = (co.v_lo + b as f64 * w, co.v_lo + (b + 1) as f64 * w);
            let n = 64;
            let h = (e - a) / n as f64;
            let simpson: f64 = (0..=n)
                .map(|k| {
                    let wt = if k == 0 || k == n {
                        1.0
                    } else if k % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    wt * exact.pdf(a + k as f64 * h)
                })
                .sum::<f64>()
                * h
                / 3.0;
            let est = |o: &Observables| Est(o.density_time[b].mean(), o.density_time[b].sem());
            Est::extrapolate(est(&co), est(&fi)).check(
                simpson / w,
                z,
                &format!("{} bin {b}", c.name),
            );
        }
        let (mc, mf) = (moments(&co), moments(&fi));
        Est::extrapolate(mc[0], mf[0]).check(
            exact.moment(1).unwrap(),
            z,
            &format!("{} <v>", c.name),
        );
        Est::extrapolate(mc[1], mf[1]).check(
            exact.moment(2).unwrap(),
            z,
            &format!("{} <v²>", c.name),
        );
    }
}

/// T → 0 is continuous: T = 1e-6 against T = 0 on the same noise. Linear
/// and tanh drag keep the explicit step at T > 0: the same dt, moments
/// within the combined SE; tan switches to the drift-implicit step (another
/// O(dt) bias): both dt-extrapolated.
#[test]
#[ignore = "slow tier: Euler at T = 0 and T = 1e-6 (~8 s)"]
fn temperature_to_zero_is_continuous() {
    let names = ["linear-three", "tanh-asym", "tan-rpt"];
    let z = bonferroni_z(2 * names.len());
    for (i, name) in names.iter().enumerate() {
        let c = NOISE_CASES.iter().find(|c| c.name == *name).unwrap();
        let cold = c.params();
        let warm = NoiseCase {
            temperature: 1e-6,
            ..*c
        }
        .params();
        let seed = 500 + 4 * i as u64;
        let (a, b) = if c.drag == "tan" {
            (
                extrapolated(&cold, 0.02, 4000, 24.0, 6.0, seed),
                extrapolated(&warm, 0.02, 4000, 24.0, 6.0, seed + 2),
            )
        } else {
            let m = |p: &Params, s| moments(&run(p, 0.01, 4000, 24.0, 6.0, s));
            (m(&cold, seed), m(&warm, seed + 2))
        };
        for k in 0..2 {
            let diff = Est(a[k].0 - b[k].0, a[k].1.hypot(b[k].1));
            diff.check(0.0, z, &format!("{name} T=0 - T=1e-6, moment {}", k + 1));
        }
    }
}

/// The paper's noise spelt as a two-state generator runs the N-state
/// kernel; at the same dt it is the same discrete process in law as the
/// default kernel (P = exp(Q dt) is Eq. (32)): <v>, <v²> and D_eff (from
/// the variance growth of x) agree within the combined SE (different
/// streams).
#[test]
#[ignore = "slow tier: the default and the N-state kernels (~5 s)"]
fn paper_as_states_matches_the_default_kernel() {
    let cases: Vec<&NoiseCase> = NOISE_CASES
        .iter()
        .filter(|c| c.name.ends_with("paper-as-states"))
        .collect();
    assert_eq!(cases.len(), 2);
    let z = bonferroni_z(3 * cases.len());
    for c in cases {
        let states = c.params();
        let drag: DragLaw = c.drag.parse().unwrap();
        let default = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
        assert!(default.noise().is_none());
        let (a, b) = (
            moments(&run(&states, 0.01, 6000, 30.0, 6.0, 41)),
            moments(&run(&default, 0.01, 6000, 30.0, 6.0, 42)),
        );
        for k in 0..3 {
            let diff = Est(a[k].0 - b[k].0, a[k].1.hypot(b[k].1));
            diff.check(0.0, z, &format!("{} states - default, moment {k}", c.name));
        }
    }
}

/// Bit-identical for 1 and 2 threads and for any split into shards, with
/// a thermal noise on tan drag (the drift-implicit step) and a three-state
/// noise; the first-passage sampler likewise across thread counts.
#[test]
fn noise_runs_are_identical_across_threads_and_shards() {
    let pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    };
    for name in ["tan-telegraph-thermal", "linear-three"] {
        let p = NOISE_CASES
            .iter()
            .find(|c| c.name == name)
            .unwrap()
            .params();
        let grid = TimeGrid::linear(1.0, 5).unwrap();
        let spec = SimSpec::new(5000, grid, 0.5, 10, 9).unwrap();
        let m = Method::euler(0.01);
        let go = |t| pool(t).install(|| sim::simulate(&p, &spec, m, &NoProgress).unwrap());
        let (a, b) = (go(1), go(2));
        let json = |o: &Observables| serde_json::to_string(o).unwrap();
        assert_eq!(json(&a), json(&b), "{name}");
        let mut units = sim::simulate_units(&p, &spec, m, 0..1, &NoProgress).unwrap();
        units.extend(sim::simulate_units(&p, &spec, m, 1..2, &NoProgress).unwrap());
        let c = sim::combine_units(&p, &spec, m, &units).unwrap();
        assert_eq!(json(&a), json(&c), "{name} shards");
        assert!(a.summary().v2.is_finite());
    }
    let c = NOISE_CASES
        .iter()
        .find(|c| c.name == "tan-telegraph-thermal")
        .unwrap();
    let pr = Problem::new(c.params(), 0.0, 0.5).unwrap();
    let e = EulerFpt::new(pr, 0.01, 100.0).unwrap();
    let (a, b) = (
        pool(1).install(|| e.stats(600, 3, &NoProgress)),
        pool(2).install(|| e.stats(600, 3, &NoProgress)),
    );
    assert_eq!(a, b);
    assert_eq!(a.censored(), 0);
}

/// With a noise model the step bound is that of its levels (Eq. (N18)),
/// refused by name; a schedule modifier runs (the scheduled loop).
#[test]
fn noise_step_bound_and_refusals_name_the_flag() {
    let blamed = |e: irtp::Error| e.parameter().unwrap_or_else(|| panic!("{e}"));
    let c = NOISE_CASES.iter().find(|c| c.name == "tan-asym").unwrap();
    let p = c.params();
    let max = irtp::sim::euler::noise::max_noise_dt(&p).unwrap();
    // tan: 1 / max g' on the interval = 1/(1 + 1.5²).
    assert!((max - 1.0 / 3.25).abs() < 1e-3, "{max}");
    let grid = TimeGrid::linear(10.0, 3).unwrap();
    let spec = SimSpec::new(10, grid, 1.0, 10, 1).unwrap();
    let e = sim::simulate(&p, &spec, Method::euler(1.01 * max), &NoProgress).unwrap_err();
    assert_eq!(blamed(e), "dt");
    assert!(sim::simulate(&p, &spec, Method::euler(0.99 * max), &NoProgress).is_ok());
    // The paper's noise as states has the default bound.
    let s = NOISE_CASES
        .iter()
        .find(|c| c.name == "tan-paper-as-states")
        .unwrap();
    let d = Params::new(DragLaw::Tan, 1.0, 0.5, 1.0, 0.2).unwrap();
    let ms = irtp::sim::euler::noise::max_noise_dt(&s.params()).unwrap();
    assert!(
        (ms - d.max_euler_dt()).abs() <= 1e-12 * ms,
        "{ms} {}",
        d.max_euler_dt()
    );
    // The drift-implicit step has no bound.
    let warm = NOISE_CASES
        .iter()
        .find(|c| c.name == "tan-telegraph-thermal")
        .unwrap();
    assert_eq!(
        irtp::sim::euler::noise::max_noise_dt(&warm.params()).unwrap(),
        f64::INFINITY
    );
    let sched = p
        .with_schedule(irtp::model::reset::Schedule {
            refractory: Some(irtp::model::reset::Refractory::Fixed { duration: 0.5 }),
            ..Default::default()
        })
        .unwrap();
    assert!(sim::simulate(&sched, &spec, Method::euler(0.01), &NoProgress).is_ok());
}

/// The Siegert mean first-passage time of the Ornstein-Uhlenbeck process
/// dv = -v dt + sqrt(2T) dW from v0 up to vt:
/// (1/T) ∫_{v0}^{vt} dy e^{y²/(2T)} ∫_{-∞}^{y} e^{-z²/(2T)} dz, by the
/// trapezoid rule on a grid of step h from -14 sqrt(T), Richardson-
/// extrapolated over h and h/2 (error below 1e-9 relative).
fn siegert(t: f64, v0: f64, vt: f64) -> f64 {
    let at = |m: usize| {
        // Nodes z_k = v0 + (k - k0) h, v0 and vt on the grid.
        let h = (vt - v0) / m as f64;
        let k0 = (14.0 * t.sqrt() / h).ceil() as usize;
        let f = |z: f64| (-z * z / (2.0 * t)).exp();
        let z = |k: usize| v0 + (k as f64 - k0 as f64) * h;
        let mut inner = 0.0f64;
        for k in 1..=k0 {
            inner += 0.5 * h * (f(z(k - 1)) + f(z(k)));
        }
        let mut prev = inner / f(v0);
        let mut outer = 0.0f64;
        for k in k0 + 1..=k0 + m {
            inner += 0.5 * h * (f(z(k - 1)) + f(z(k)));
            let g = inner / f(z(k));
            outer += 0.5 * h * (prev + g);
            prev = g;
        }
        outer / t
    };
    let (a, b) = (at(4000), at(8000));
    (4.0 * b - a) / 3.0
}

/// Backward equation of the reset OU process, T τ'' - v τ' + r (τ(v_r) - τ)
/// = -1 on (-L, vt), τ(vt) = 0, τ'(-L) = 0, by central differences (τ =
/// u + c w with c = τ(v_r) eliminated), Richardson-extrapolated over two
/// meshes.
fn reset_ou_backward(t: f64, r: f64, vr: f64, v0: f64, vt: f64) -> f64 {
    let at = |m: usize| {
        // Nodes v_i = vt - (n - i) h with v0 and v_r on nodes (they are
        // whole multiples of h below vt); node n is vt, where τ = 0.
        let h = (vt - v0) / m as f64;
        let n = m + ((12.0 * t.sqrt() + 1.0) / h).ceil() as usize;
        let lo = vt - n as f64 * h;
        let solve = |rhs: f64| {
            let (mut a, mut b, mut c, mut d) =
                (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![rhs; n]);
            for i in 0..n {
                let v = lo + i as f64 * h;
                a[i] = t / (h * h) + v / (2.0 * h);
                b[i] = -2.0 * t / (h * h) - r;
                c[i] = t / (h * h) - v / (2.0 * h);
            }
            // Ghost node: τ_{-1} = τ_1 (zero slope at -L).
            c[0] += a[0];
            for i in 1..n {
                let w = a[i] / b[i - 1];
                b[i] -= w * c[i - 1];
                d[i] -= w * d[i - 1];
            }
            let mut x = vec![0.0; n + 1];
            x[n - 1] = d[n - 1] / b[n - 1];
            for i in (0..n - 1).rev() {
                x[i] = (d[i] - c[i] * x[i + 1]) / b[i];
            }
            x
        };
        // T u'' - v u' - r u = -1 and T w'' - v w' - r w = -r; τ = u + c w.
        let (u, w) = (solve(-1.0), solve(-r));
        let node = |v: f64| ((v - lo) / h).round() as usize;
        let c = u[node(vr)] / (1.0 - w[node(vr)]);
        u[node(v0)] + c * w[node(v0)]
    };
    let (a, b) = (at(400), at(800));
    (4.0 * b - a) / 3.0
}

/// mfpt euler for the Ornstein-Uhlenbeck process (noise none, linear drag)
/// at r = 0 against Siegert and at r = 1 against the finite-difference
/// backward solve, dt-extrapolated; without the bridge the coarse-step
/// bias is several times larger (the O(sqrt(dt)) bias the bridge removes).
#[test]
#[ignore = "slow tier: Euler first passages at three steps (~10 s)"]
fn ou_first_passage_matches_siegert_and_the_backward_solve() {
    let (t, v0, vt) = (0.5, 0.0, 0.8);
    let exact0 = siegert(t, v0, vt);
    let cases = [
        (0.0, 0.0, exact0),
        (1.0, -0.2, reset_ou_backward(t, 1.0, -0.2, v0, vt)),
    ];
    // The reference solvers agree with each other at r = 0.
    let fd0 = reset_ou_backward(t, 0.0, 0.0, v0, vt);
    assert!((fd0 - exact0).abs() < 1e-6 * exact0, "{fd0} {exact0}");
    let z = bonferroni_z(cases.len());
    for (k, (r, vr, exact)) in cases.into_iter().enumerate() {
        let m = NoiseModel::parse("none", t).unwrap();
        let p = Params::with_noise(DragLaw::Linear, m, r, vr).unwrap();
        let pr = Problem::new(p, v0, vt).unwrap();
        let n = 20_000;
        let seed = 700 + 10 * k as u64;
        let dt = 0.02;
        let st = |dt: f64, s: u64| {
            EulerFpt::new(pr.clone(), dt, 1e4)
                .unwrap()
                .stats(n, s, &NoProgress)
                .summary()
        };
        let (coarse, fine) = (st(dt, seed), st(dt / 2.0, seed + 1));
        let ex = extrapolate(&coarse, &fine);
        let est = Est(
            ex.tau,
            (4.0 * fine.tau_err.powi(2) + coarse.tau_err.powi(2)).sqrt(),
        );
        est.check(exact, z, &format!("OU r={r} tau, bridge"));
        let plain = EulerFpt::new(pr, dt, 1e4)
            .unwrap()
            .without_bridge()
            .stats(n, seed + 2, &NoProgress)
            .summary();
        let (b_bridge, b_plain) = (coarse.tau - exact, plain.tau - exact);
        println!(
            "r={r}: dt={dt} bias with bridge {b_bridge:.4}, without {b_plain:.4}, exact {exact:.4}"
        );
        assert!(
            b_plain > 3.0 * b_bridge.abs() + 4.0 * plain.tau_err,
            "{b_plain} {b_bridge}"
        );
    }
}
