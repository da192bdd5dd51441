//! The N-state Fokker-Planck solvers (`irtp::fp` with a noise model) over
//! `irtp_testkit::noises::NOISE_CASES`: closed forms for linear drag
//! (Eqs. (N3)-(N6)), the r = 0 telegraph density (Eq. (N8)), the
//! two-state solver for the paper's noise spelt as a generator, T → 0,
//! the Ornstein-Uhlenbeck density, and the time-dependent solvers.

use irtp::analytic::linear_noise::{LinearNoise, NoiseMoments};
use irtp::analytic::telegraph_r0::TelegraphR0Density;
use irtp::fp::{self, Mesh, MsdOptions, Stationary, StationaryOptions, TransientOptions};
use irtp::model::noise::{NoiseKind, NoiseModel};
use irtp::model::reset::{NoiseAtReset, Target};
use irtp::parallel::NoProgress;
use irtp::{DragLaw, Params};
use irtp_testkit::noises::{NoiseCase, NOISE_CASES};

fn opts(cells: usize) -> StationaryOptions {
    StationaryOptions {
        cells,
        mesh: Mesh::Graded,
        extrapolate: true,
    }
}

fn solve(p: &Params, cells: usize) -> Stationary {
    fp::stationary(p, &opts(cells)).unwrap()
}

fn closed_form(c: &NoiseCase) -> NoiseMoments {
    let m = NoiseModel::parse(c.noise, c.temperature).unwrap();
    LinearNoise::new(1.0, m, c.rate, c.reset_velocity)
        .unwrap()
        .moments()
        .unwrap()
}

/// |x - want| within the solver's own error estimate (plus rounding).
fn within(name: &str, what: &str, x: f64, want: f64, est: f64) {
    let err = (x - want).abs();
    println!("{name} {what}: error {err:.2e}, estimate {est:.2e}");
    assert!(
        err <= est + 1e-12 * (1.0 + want.abs()),
        "{name} {what}: {x} vs {want} (error {err:e} > estimate {est:e})"
    );
}

/// Every linear case (thermal ones included): `<v>` (the drift U),
/// `<v²>`, D_eff and the per-state means against Eqs. (N3)-(N6), to the
/// solver's error estimate, which is itself small.
#[test]
fn linear_cases_match_the_closed_forms() {
    for c in NOISE_CASES.iter().filter(|c| c.linear()) {
        let s = solve(&c.params(), 4000);
        let n = s.noise.as_ref().unwrap();
        let e = closed_form(c);
        let est = n.errors.unwrap();
        assert!(est.iter().all(|&x| x < 1e-4), "{}: {est:?}", c.name);
        within(c.name, "<v>", s.v_mean, e.v_mean, est[0]);
        within(c.name, "<v^2>", s.v2, e.v2, est[1]);
        within(c.name, "D_eff", s.d_eff, e.d_eff, est[2]);
        let sme = n.state_mean_errors.as_ref().unwrap();
        for (k, (&m, &want)) in n.state_means.iter().zip(&e.conditional_mean).enumerate() {
            within(c.name, &format!("m_{k}"), m, want, sme[k]);
        }
        assert!(n.tail_mass <= 1e-10);
    }
}

/// Cell masses of a density by 4-point Gauss-Legendre on each cell.
fn cell_masses(edges: &[f64], f: &dyn Fn(f64) -> f64) -> Vec<f64> {
    const X: [f64; 2] = [0.339_981_043_584_856_3, 0.861_136_311_594_052_6];
    const W: [f64; 2] = [0.652_145_154_862_546_1, 0.347_854_845_137_453_9];
    edges
        .windows(2)
        .map(|e| {
            let (m, h) = (0.5 * (e[0] + e[1]), 0.5 * (e[1] - e[0]));
            h * (0..2)
                .map(|k| W[k] * (f(m - h * X[k]) + f(m + h * X[k])))
                .sum::<f64>()
        })
        .collect()
}

/// Asymmetric telegraph noise at r = 0 (linear, tan, tanh): the per-state
/// densities against Eq. (N8) in L1 (all cells but the two at the
/// singular edges) within the solver's L1 estimate, and `<v>`, `<v²>`.
#[test]
fn asymmetric_telegraph_at_r0_matches_its_density() {
    let cases = NOISE_CASES
        .iter()
        .filter(|c| c.noise.starts_with("telegraph:plus") && !c.thermal());
    let mut seen = 0;
    for c in cases {
        seen += 1;
        let c = c.at_rate(0.0);
        let p = c.params();
        let m = NoiseModel::parse(c.noise, 0.0).unwrap();
        let NoiseKind::Telegraph(t) = m.kind() else {
            panic!("a telegraph noise")
        };
        let exact = TelegraphR0Density::new(p.drag(), *t).unwrap();
        let s = solve(&p, 4000);
        let n = s.noise.as_ref().unwrap();
        assert!(n.levels[0] > 0.0 && n.levels[1] < 0.0);
        let plus = cell_masses(&s.edges, &|v| exact.state_pdf(v).0);
        let minus = cell_masses(&s.edges, &|v| exact.state_pdf(v).1);
        let cells = s.widths.len();
        let l1: f64 = (1..cells - 1)
            .map(|i| {
                let h = s.widths[i];
                (n.densities[0][i] * h - plus[i]).abs() + (n.densities[1][i] * h - minus[i]).abs()
            })
            .sum();
        let est = n.density_l1_error.unwrap();
        println!("{} r=0: L1 {l1:.2e}, estimate {est:.2e}", c.name);
        assert!(l1 <= est && est < 1e-2, "{}: L1 {l1:e} vs {est:e}", c.name);
        let e = n.errors.unwrap();
        within(c.name, "r=0 <v>", s.v_mean, exact.moment(1).unwrap(), e[0]);
        within(c.name, "r=0 <v^2>", s.v2, exact.moment(2).unwrap(), e[1]);
    }
    assert_eq!(seen, 3);
}

/// The paper's noise spelt as a generator runs the N-state path and
/// agrees with the two-state solver to both solvers' discretisation error,
/// with the paper's reset (point, noise kept) and with a uniform target
/// and the noise re-drawn at a reset (the reset's W = π 1ᵀ).
#[test]
fn paper_as_states_matches_the_two_state_solver() {
    let cases = NOISE_CASES
        .iter()
        .filter(|c| c.name.ends_with("paper-as-states"));
    let mut seen = 0;
    for c in cases {
        let drag: DragLaw = c.drag.parse().unwrap();
        let two = Params::new(drag, 1.0, 0.5, c.rate, c.reset_velocity).unwrap();
        for rule in [
            None,
            Some((Target::uniform(-0.3, 0.5), NoiseAtReset::Redrawn)),
        ] {
            seen += 1;
            let (p, q) = match rule {
                None => (c.params(), two.clone()),
                Some((t, w)) => (
                    c.params().with_reset(t, w).unwrap(),
                    two.with_reset(t, w).unwrap(),
                ),
            };
            assert!(p.noise().is_some());
            let s = solve(&p, 4000);
            let t = fp::stationary(&q, &opts(20_000)).unwrap();
            let e = s.noise.as_ref().unwrap().errors.unwrap();
            // The two-state solver's extrapolation error: its change from
            // the fine-mesh value bounds it.
            let e2 = |f: f64, x: f64| (x - f).abs();
            let name = format!(
                "{} ({})",
                c.name,
                if rule.is_some() {
                    "uniform, redrawn"
                } else {
                    "paper reset"
                }
            );
            within(
                &name,
                "<v^2> vs 2-state",
                s.v2,
                t.v2,
                e[1] + e2(t.fine.v2, t.v2),
            );
            within(
                &name,
                "D_eff vs 2-state",
                s.d_eff,
                t.d_eff,
                e[2] + e2(t.fine.d_eff, t.d_eff),
            );
            within(
                &name,
                "<v> vs 2-state",
                s.v_mean,
                t.v_mean,
                e[0] + e2(t.fine.v_mean, t.v_mean),
            );
        }
    }
    assert_eq!(seen, 4);
}

/// A random reset target with linear drag: Eqs. (N3)-(N6) with the
/// target's moments (`LinearNoise::with_target`), noise kept.
#[test]
fn a_random_target_matches_the_closed_forms() {
    for c in NOISE_CASES
        .iter()
        .filter(|c| c.name == "linear-rpt" || c.name == "linear-thermal")
    {
        let target = Target::uniform(-0.4, 0.6);
        let p = c.params().with_reset(target, NoiseAtReset::Kept).unwrap();
        let s = solve(&p, 4000);
        let m = NoiseModel::parse(c.noise, c.temperature).unwrap();
        let e = LinearNoise::with_target(1.0, m, c.rate, target.moments())
            .unwrap()
            .moments()
            .unwrap();
        let est = s.noise.as_ref().unwrap().errors.unwrap();
        let name = format!("{} uniform target", c.name);
        within(&name, "<v>", s.v_mean, e.v_mean, est[0]);
        within(&name, "<v^2>", s.v2, e.v2, est[1]);
        within(&name, "D_eff", s.d_eff, e.d_eff, est[2]);
    }
}

/// T → 0: T = 1e-6 and T = 0 agree to their estimates plus O(T); pure
/// Ornstein-Uhlenbeck (no jump noise, linear drag, r = 0): the Gaussian
/// of variance T.
#[test]
fn vanishing_temperature_and_ornstein_uhlenbeck() {
    for c in NOISE_CASES
        .iter()
        .filter(|c| !c.thermal() && c.name.ends_with("asym"))
    {
        let warm = NoiseCase {
            temperature: 1e-6,
            ..*c
        };
        let (a, b) = (solve(&c.params(), 4000), solve(&warm.params(), 4000));
        let (ea, eb) = (
            a.noise.as_ref().unwrap().errors.unwrap(),
            b.noise.as_ref().unwrap().errors.unwrap(),
        );
        let t = 1e-5;
        within(c.name, "T=1e-6 <v^2>", b.v2, a.v2, ea[1] + eb[1] + t);
        within(c.name, "T=1e-6 D_eff", b.d_eff, a.d_eff, ea[2] + eb[2] + t);
    }
    let t = 0.5;
    let ou = Params::with_noise(
        DragLaw::Linear,
        NoiseModel::parse("none", t).unwrap(),
        0.0,
        0.0,
    )
    .unwrap();
    let s = solve(&ou, 4000);
    let e = s.noise.as_ref().unwrap().errors.unwrap();
    within("OU", "<v^2>", s.v2, t, e[1]);
    let gauss = |v: f64| (-v * v / (2.0 * t)).exp() / (2.0 * std::f64::consts::PI * t).sqrt();
    let exact = cell_masses(&s.edges, &gauss);
    let l1: f64 = (0..s.widths.len())
        .map(|i| (s.p[i] * s.widths[i] - exact[i]).abs())
        .sum();
    let est = s.noise.as_ref().unwrap().density_l1_error.unwrap();
    println!("OU density: L1 {l1:.2e}, estimate {est:.2e}");
    assert!(l1 <= est, "OU L1 {l1:e} vs {est:e}");
}

/// `<v>`(t) of linear drag from v = 0 with the noise started from π:
/// d`<v>`/dt = `<a>` - (1 + r)`<v>` + r v_r, so `<v>`(t) = V (1 - e^{-kt}),
/// V = (`<a>` + r v_r)/k, k = 1 + r; and `<x>`(t) = V (t - (1 - e^{-kt})/k).
fn linear_means(c: &NoiseCase, t: f64) -> (f64, f64) {
    let mean_a = NoiseModel::parse(c.noise, c.temperature)
        .unwrap()
        .mean_level()
        .unwrap();
    let k = 1.0 + c.rate;
    let v_inf = (mean_a + c.rate * c.reset_velocity) / k;
    let e = (-k * t).exp();
    (v_inf * (1.0 - e), v_inf * (t - (1.0 - e) / k))
}

fn transient_opts(cells: usize, times: &[f64], rtol: f64) -> TransientOptions {
    TransientOptions {
        cells,
        t_max: *times.last().unwrap(),
        times: times.to_vec(),
        snapshot_times: vec![times[0]],
        rtol,
        atol: 1e-4 * rtol,
        ..TransientOptions::default()
    }
}

/// `fp transient` for every linear case: mass 1 at all times, `<v>`(t)
/// against [`linear_means`] at short times, snapshots per state and ≥ 0.
#[test]
fn transient_conserves_mass_and_follows_the_mean() {
    for c in NOISE_CASES.iter().filter(|c| c.linear()) {
        let times = [0.25, 0.5, 1.0, 2.0];
        let tr = fp::transient(&c.params(), &transient_opts(400, &times, 1e-6)).unwrap();
        assert!(
            tr.mass_error_max < 1e-10,
            "{}: {}",
            c.name,
            tr.mass_error_max
        );
        for (k, &t) in times.iter().enumerate() {
            let want = linear_means(c, t).0;
            let err = (tr.v_mean[k] - want).abs();
            println!("{} transient <v>({t}): error {err:.2e}", c.name);
            assert!(
                err < 1e-5,
                "{} <v>({t}) = {} vs {want}",
                c.name,
                tr.v_mean[k]
            );
        }
        let snap = &tr.snapshots[0];
        assert_eq!(snap.states.len(), closed_form(c).pi.len());
        assert!(snap.p.iter().all(|&x| x >= 0.0));
    }
}

/// `fp transient` relaxes to the stationary solution: `<v²>`(40) against
/// the closed form (N4) for a jump noise and a thermal one.
#[test]
#[ignore = "slow tier: long transients on T = 0 graded meshes (~10 s)"]
fn transient_relaxes_to_the_stationary_state() {
    for c in NOISE_CASES
        .iter()
        .filter(|c| c.name == "linear-three" || c.name == "linear-telegraph-thermal")
    {
        let tr = fp::transient(&c.params(), &transient_opts(400, &[1.0, 40.0], 1e-7)).unwrap();
        let e = closed_form(c);
        let err = (tr.v2[1] - e.v2).abs();
        println!(
            "{} transient <v^2>(40): error {err:.2e} (mesh estimate {:.2e})",
            c.name, tr.v2_mesh_error[1]
        );
        assert!(err < 1e-5 && err <= tr.v2_mesh_error[1], "{}", c.name);
    }
}

/// `fp msd`: `<x>`(t) against [`linear_means`] and Var x growing with
/// slope 2 D_eff (Eq. (N6)) at long times, on the linear cases `cases`.
fn msd_check(cases: &[&str]) {
    for c in NOISE_CASES.iter().filter(|c| cases.contains(&c.name)) {
        let e = closed_form(c);
        let o = MsdOptions {
            cells: 100,
            mesh: Mesh::Graded,
            levels: 3,
            times: vec![1.0, 30.0, 40.0],
            rtol: 1e-9,
        };
        let m = fp::msd(&c.params(), &o, &NoProgress).unwrap();
        for (i, &t) in o.times.iter().enumerate() {
            let want = linear_means(c, t).1;
            let err = (m.x_mean[i] - want).abs();
            println!("{} msd <x>({t}): error {err:.2e}", c.name);
            assert!(err < 1e-4 * (1.0 + want.abs()), "{}: <x>({t})", c.name);
        }
        let var = |i: usize| m.x2[i] - m.x_mean[i].powi(2);
        let slope = (var(2) - var(1)) / 10.0;
        let err = (slope / (2.0 * e.d_eff) - 1.0).abs();
        println!("{} msd Var x slope / 2 D_eff - 1 = {err:.2e}", c.name);
        assert!(
            err < 1e-3,
            "{}: slope {slope} vs 2 D_eff {}",
            c.name,
            2.0 * e.d_eff
        );
    }
}

#[test]
fn msd_gives_the_drift_and_the_diffusion_coefficient() {
    msd_check(&["linear-thermal", "linear-telegraph-thermal"]);
}

#[test]
#[ignore = "slow tier: moment chains on T = 0 graded meshes (~20 s)"]
fn msd_gives_the_drift_and_the_diffusion_coefficient_for_jump_noises() {
    msd_check(&["linear-asym", "linear-rpt", "linear-three"]);
}
