//! Noise kinds (`irtp::model::noise`): specs (parse, validation, round
//! trip), generators and stationary laws, mirror symmetry, velocity
//! intervals; the linear-drag closed forms with any noise
//! (`irtp::analytic::linear_noise`) against the two-state closed forms, the
//! Ornstein-Uhlenbeck and run-pause-tumble moments and an exact event-driven
//! simulation; the r = 0 telegraph density (`irtp::analytic::telegraph_r0`)
//! against the symmetric one and the linear closed forms.

use irtp::analytic::linear;
use irtp::analytic::linear_noise::{LinearNoise, NoiseMoments};
use irtp::analytic::r0::R0Density;
use irtp::analytic::telegraph_r0::TelegraphR0Density;
use irtp::model::noise::{chain, NoiseKind, NoiseModel, RunPauseTumble, Telegraph};
use irtp::{Drag, DragLaw, Error, Params};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use rand::Rng;
use rand_distr::StandardNormal;

fn kind(spec: &str) -> NoiseKind {
    spec.parse().unwrap_or_else(|e| panic!("{spec}: {e}"))
}

fn model(spec: &str, t: f64) -> NoiseModel {
    NoiseModel::new(kind(spec), t).unwrap()
}

/// The name of the parameter an error blames, and its message.
fn blamed(e: Error) -> (&'static str, String) {
    let msg = e.to_string();
    match e.parameter() {
        Some(name) => (name, msg),
        None => panic!("not an input error: {e}"),
    }
}

/// Written specs parse back to the same value, bit for bit, and are
/// written again identically; awkward numbers keep every bit.
#[test]
fn specs_round_trip_bit_for_bit() {
    let mut kinds = NoiseKind::examples();
    kinds.extend(
        [
            "telegraph:sigma=3,lambda=0.5",
            "telegraph:plus=0.1,minus=0.30000000000000004,rate_plus=1e-7,rate_minus=3.5e200",
            "telegraph: rate_minus=2, plus=1, rate_plus=1, minus=1",
            "rpt:beta=0.3333333333333333,sigma=2,alpha=7",
            "states:levels=[1,-1,0.5],rates=[[-0.3,0.1,0.2],[1,-1,0],[0.5,0.5,-1]]",
            "states:levels=[2,2,-2,-2],rates=[[-1,1,0,0],[0,-1,1,0],[0,0,-1,1],[1,0,0,-1]]",
            "none",
        ]
        .map(kind),
    );
    for k in kinds {
        let spec = k.spec();
        let back: NoiseKind = spec.parse().unwrap();
        assert_eq!(back, k, "{spec}");
        assert_eq!(back.spec(), spec);
        for (a, b) in back.levels().iter().zip(k.levels()) {
            assert_eq!(a.to_bits(), b.to_bits(), "{spec}");
        }
    }
    // Equal values in the long form are written in the short one.
    let t = kind("telegraph:plus=2,minus=2,rate_plus=0.7,rate_minus=0.7");
    assert_eq!(t.spec(), "telegraph:sigma=2,lambda=0.7");
    assert_eq!(t.symmetric_telegraph(), Some((2.0, 0.7)));
}

/// Every malformed or out-of-range spec is one input error naming
/// `noise` (or `temperature`) and what is allowed.
#[test]
fn invalid_specs_name_the_flag_and_the_range() {
    let cases = [
        ("telegraph:sigma=3", "lambda"),
        ("telegraph:sigma=3,lambda=0", "lambda > 0"),
        ("telegraph:sigma=3,lambda=NaN", "finite number for lambda"),
        ("telegraph:sigma=-1,lambda=1", "sigma > 0"),
        (
            "telegraph:plus=1,minus=-1,rate_plus=1,rate_minus=1",
            "plus + minus > 0",
        ),
        ("telegraph:sigma=1,lambda=1,plus=2", "not both"),
        (
            "telegraph:plus=1,minus=1,rate_plus=1",
            "rate_minus (required",
        ),
        ("telegraph:sigma=1,lambda=1,lambda=2", "repeated"),
        ("telegraph:sigma=1,speed=2", "unknown key"),
        ("rpt:sigma=1,alpha=-1,beta=1", "alpha > 0"),
        ("rpt:sigma=inf,alpha=1,beta=1", "finite number for sigma"),
        ("states:levels=[1],rates=[[0]]", "at least 2 states"),
        (
            "states:levels=[1,-1],rates=[[-1,1],[1,-1.1]]",
            "summing to 0",
        ),
        ("states:levels=[1,-1],rates=[[-1,1],[-1,1]]", "rates >= 0"),
        ("states:levels=[1,-1],rates=[[0,0],[1,-1]]", "irreducible"),
        ("states:levels=[1,-1,0],rates=[[-1,1],[1,-1]]", "3×3"),
        (
            "states:levels=[1,NaN],rates=[[-1,1],[1,-1]]",
            "finite number",
        ),
        ("states:levels=(1;2),rates=[[-1,1],[1,-1]]", "bracketed"),
        ("none:sigma=1", "bare name"),
        ("levy:alpha=1.5", "one of"),
    ];
    for (spec, what) in cases {
        let e = spec.parse::<NoiseKind>().expect_err(spec);
        let (name, msg) = blamed(e);
        assert_eq!(name, "noise", "{spec}");
        assert!(msg.contains(what), "{spec}: {msg}");
    }
    for t in [-1.0, f64::NAN, f64::INFINITY] {
        let e = NoiseModel::new(kind("none"), t).unwrap_err();
        assert_eq!(blamed(e).0, "temperature");
    }
    let (name, msg) = blamed(NoiseModel::new(kind("none"), 0.0).unwrap_err());
    assert!(
        name == "temperature" && msg.contains("temperature > 0"),
        "{msg}"
    );
}

/// Levels outside the drag's force range (tanh: |a| < 1) and within a
/// Coulomb law's static friction are refused naming `noise`; the velocity
/// interval is (g⁻¹(min a), g⁻¹(max a)), or the drag's domain with T > 0.
#[test]
fn levels_against_the_drag_and_the_velocity_interval() {
    let m = model("telegraph:plus=0.5,minus=1.2,rate_plus=1,rate_minus=1", 0.0);
    let (name, msg) = blamed(m.check_drag(&DragLaw::Tanh).unwrap_err());
    assert!(name == "noise" && msg.contains("force range"), "{msg}");
    m.check_drag(&DragLaw::Tan).unwrap();
    let coulomb: DragLaw = "coulomb:mu=0.5".parse().unwrap();
    let rpt = model("rpt:sigma=2,alpha=1,beta=1", 0.0);
    let (name, msg) = blamed(rpt.check_drag(&coulomb).unwrap_err());
    assert!(name == "noise" && msg.contains("static friction"), "{msg}");
    let (lo, hi) = m.velocity_interval(&DragLaw::Tan);
    assert_eq!((lo, hi), (-(1.2f64.atan()), 0.5f64.atan()));
    let hot = model("telegraph:plus=0.5,minus=1.2,rate_plus=1,rate_minus=1", 0.1);
    let half_pi = std::f64::consts::FRAC_PI_2;
    assert_eq!(hot.velocity_interval(&DragLaw::Tan), (-half_pi, half_pi));
    let lin = hot.velocity_interval(&DragLaw::Linear);
    assert!(lin.0 == f64::NEG_INFINITY && lin.1 == f64::INFINITY);
}

/// Generators have rows summing to 0; the stationary law solves Qᵀ π = 0
/// with Σ π = 1, and the closed forms of telegraph and run-pause-tumble
/// equal the generic solve.
#[test]
fn generators_and_stationary_laws() {
    let mut kinds = NoiseKind::examples();
    kinds.push(kind(
        "telegraph:plus=2,minus=0.5,rate_plus=0.3,rate_minus=4",
    ));
    for k in kinds {
        let q = k.generator();
        let pi = k.stationary().unwrap();
        assert_eq!(q.len(), k.levels().len());
        assert!((pi.iter().sum::<f64>() - 1.0).abs() < 1e-15, "{k}");
        for (i, row) in q.iter().enumerate() {
            assert!(row.iter().sum::<f64>().abs() < 1e-15, "{k} row {i}");
            let flux: f64 = (0..q.len()).map(|j| q[j][i] * pi[j]).sum();
            assert!(flux.abs() < 1e-14, "{k}: (Qᵀπ)_{i} = {flux}");
        }
        let generic = chain::stationary(&q).unwrap();
        for (a, b) in pi.iter().zip(&generic) {
            assert!((a - b).abs() < 1e-15, "{k}: {pi:?} vs {generic:?}");
        }
    }
    let pi = kind("telegraph:plus=2,minus=0.5,rate_plus=0.3,rate_minus=4")
        .stationary()
        .unwrap();
    assert_eq!(pi, vec![4.0 / 4.3, 0.3 / 4.3]);
}

/// Mirror symmetry: the symmetric telegraph, run-pause-tumble and a
/// four-state chain written in scrambled order are symmetric; an
/// asymmetric telegraph and a chain whose rates break the mirror are not.
#[test]
fn mirror_symmetry() {
    assert!(model("telegraph:sigma=1,lambda=2", 0.0).is_mirror_symmetric());
    assert!(!model("telegraph:plus=1,minus=1,rate_plus=1,rate_minus=2", 0.0).is_mirror_symmetric());
    assert!(model("rpt:sigma=1,alpha=2,beta=3", 0.0).is_mirror_symmetric());
    assert!(model("none", 1.0).is_mirror_symmetric());
    // A run of two phases in each direction (Erlang-2 run times), states
    // ordered (+a, -a, +b, -b): +a → +b → -a → -b → +a.
    let cycle = "states:levels=[1,-1,1,-1],rates=[[-2,0,2,0],[0,-2,0,2],[0,3,-3,0],[3,0,0,-3]]";
    let k = kind(cycle);
    assert_eq!(k.mirror(), Some(vec![1, 0, 3, 2]));
    let broken =
        "states:levels=[1,-1,1,-1],rates=[[-2,0,2,0],[0,-2,0,2],[0,3,-3,0],[3.5,0,0,-3.5]]";
    assert_eq!(kind(broken).mirror(), None);
}

/// Provenance: a noise model serialises as its spec and temperature and
/// reads back equal; invalid values are refused on the way in.
#[test]
fn serde_round_trip() {
    let m = model("rpt:sigma=2,alpha=0.1,beta=3", 0.25);
    let s = serde_json::to_string(&m).unwrap();
    assert_eq!(
        s,
        r#"{"noise":"rpt:sigma=2,alpha=0.1,beta=3","temperature":0.25}"#
    );
    assert_eq!(serde_json::from_str::<NoiseModel>(&s).unwrap(), m);
    let bad = r#"{"noise":"rpt:sigma=2,alpha=0.1,beta=3","temperature":-1}"#;
    assert!(serde_json::from_str::<NoiseModel>(bad).is_err());
    let default_t: NoiseModel =
        serde_json::from_str(r#"{"noise":"telegraph:sigma=1,lambda=1"}"#).unwrap();
    assert_eq!(default_t.temperature(), 0.0);
}

fn moments(gamma: f64, m: NoiseModel, r: f64, vr: f64) -> NoiseMoments {
    LinearNoise::new(gamma, m, r, vr)
        .unwrap()
        .moments()
        .unwrap()
}

/// Symmetric telegraph, γ = 1: `<v>`, `<v²>`, D_eff equal the two-state
/// closed forms of `analytic::linear` to 1e-12, with and without
/// resetting.
#[test]
fn linear_noise_reduces_to_the_two_state_closed_forms() {
    for (s, l, r, vr) in [
        (1.0, 0.5, 0.0, 0.0),
        (2.0, 0.7, 0.0, 0.0),
        (3.0, 0.5, 2.0, 0.0),
        (1.3, 2.5, 0.4, 0.6),
        (0.7, 0.05, 5.0, -0.3),
    ] {
        let p = Params::new(DragLaw::Linear, s, l, r, vr).unwrap();
        let got = moments(1.0, NoiseModel::telegraph(s, l).unwrap(), r, vr);
        let want = [
            linear::v_mean(&p).unwrap(),
            linear::v2(&p).unwrap(),
            linear::d_eff(&p).unwrap(),
        ];
        for (name, a, b) in [
            ("<v>", got.v_mean, want[0]),
            ("<v2>", got.v2, want[1]),
            ("D_eff", got.d_eff, want[2]),
        ] {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                "{s} {l} {r} {vr} {name}: {a} vs {b}"
            );
        }
        assert_eq!(got.drift, got.v_mean);
        let v_eta = s * (got.conditional_mean[0] - got.conditional_mean[1]);
        assert!((v_eta - linear::v_eta(&p).unwrap()).abs() < 1e-12);
    }
}

/// Thermal noise alone (`none`, T): the Ornstein-Uhlenbeck velocity,
/// `<v²>` = T/γ and D_eff = T/γ² at r = 0; with resetting `<v>` =
/// r v_r/(γ + r), `<v²>` = (2T + r v_r²)/(2γ + r).
#[test]
fn thermal_noise_alone_is_ornstein_uhlenbeck() {
    for (g, t) in [(1.0, 1.0), (0.3, 2.5), (4.0, 0.01)] {
        let m = moments(g, model("none", t), 0.0, 0.0);
        assert!(m.v_mean == 0.0);
        assert!((m.v2 - t / g).abs() < 1e-15 * t / g);
        assert!((m.d_eff - t / (g * g)).abs() < 1e-14 * t / (g * g));
        let (r, vr) = (1.5, 0.8);
        let m = moments(g, model("none", t), r, vr);
        assert!((m.v_mean - r * vr / (g + r)).abs() < 1e-15);
        assert!((m.v2 - (2.0 * t + r * vr * vr) / (2.0 * g + r)).abs() < 1e-14);
    }
    // Thermal noise adds 2T/(2γ + r) to <v²> and α Var-share to D_eff, and
    // leaves <v> alone.
    let cold = moments(2.0, model("telegraph:sigma=1,lambda=1", 0.0), 0.5, 0.2);
    let hot = moments(2.0, model("telegraph:sigma=1,lambda=1", 0.3), 0.5, 0.2);
    assert_eq!(hot.v_mean, cold.v_mean);
    assert!((hot.v2 - cold.v2 - 0.6 / 4.5).abs() < 1e-15);
    assert!((hot.d_eff - cold.d_eff - 0.6 / 4.5 / 2.5).abs() < 1e-15);
}

/// Run-pause-tumble at r = 0 against its three-state moments (derived by
/// hand from (N3), (N6) with m₀ = 0, m± = ±m by the mirror symmetry):
/// m = S π₊/(α + γ), π₊ = β/(2(α + β)), `<v²>` = 2 S m/γ,
/// D_eff = `<v²>` (1/γ + 1/α).
#[test]
fn run_pause_tumble_three_state_moments() {
    for (s, a, b, g) in [
        (1.0, 1.0, 1.0, 1.0),
        (3.0, 0.2, 5.0, 0.7),
        (0.5, 4.0, 0.1, 2.0),
    ] {
        let noise =
            NoiseModel::new(NoiseKind::Rpt(RunPauseTumble::new(s, a, b).unwrap()), 0.0).unwrap();
        let got = moments(g, noise, 0.0, 0.0);
        let m = s * b / (2.0 * (a + b)) / (a + g);
        let v2 = 2.0 * s * m / g;
        let d = v2 * (1.0 / g + 1.0 / a);
        assert!(got.v_mean.abs() < 1e-15);
        assert!((got.conditional_mean[0] - m).abs() < 1e-15 * m.max(1.0));
        assert!((got.v2 - v2).abs() < 1e-14 * v2);
        assert!((got.d_eff - d).abs() < 1e-13 * d, "{} vs {d}", got.d_eff);
    }
}

/// The exact transition of dv = (a - γv) dt + sqrt(2T) dW, dx = v dt over
/// a time h: the mean relaxes exponentially, and the thermal parts of
/// (v, x) are jointly Gaussian with Var v = (T/γ)(1 - e²),
/// Var x = (2T/γ²)[h - 2(1 - e)/γ + (1 - e²)/(2γ)], Cov = (T/γ²)(1 - e)²,
/// e = e^{-γh}.
fn advance(
    state: (f64, f64),
    a: f64,
    gamma: f64,
    temp: f64,
    h: f64,
    rng: &mut impl Rng,
) -> (f64, f64) {
    let (v, x) = state;
    let (vs, e) = (a / gamma, (-gamma * h).exp());
    let (mut v1, mut x1) = (vs + (v - vs) * e, x + vs * h + (v - vs) * (1.0 - e) / gamma);
    if temp > 0.0 {
        let g2 = gamma * gamma;
        let var_v = temp / gamma * (1.0 - e * e);
        let var_x = 2.0 * temp / g2 * (h - 2.0 * (1.0 - e) / gamma + (1.0 - e * e) / (2.0 * gamma));
        let cov = temp / g2 * (1.0 - e) * (1.0 - e);
        let (z1, z2): (f64, f64) = (rng.sample(StandardNormal), rng.sample(StandardNormal));
        let sv = var_v.sqrt();
        v1 += sv * z1;
        if sv > 0.0 {
            x1 += cov / sv * z1 + (var_x - cov * cov / var_v).max(0.0).sqrt() * z2;
        }
    }
    (v1, x1)
}

/// The process of a test case: drag γ v, noise kind, temperature, reset
/// rate and velocity.
struct Case {
    gamma: f64,
    kind: NoiseKind,
    temp: f64,
    rate: f64,
    vr: f64,
}

/// An exact event-driven simulation of dv = (a_η - γv) dt + sqrt(2T) dW,
/// dx = v dt with the noise's jumps and resets to v_r at rate r, exact
/// between events ([`advance`]). Returns per particle (v at the end, the
/// centred increments ((Δ₂ - 2UT)² - (Δ₁ - UT)²)/(2T)) whose mean is D_eff
/// up to e^{-γ·burn}: Δ_k the displacement over k windows T after a
/// burn-in, U the drift, so the O(1/T) boundary terms of Var x cancel.
fn simulate(c: &Case, drift: f64, particles: u64) -> Vec<(f64, f64)> {
    let (a, q, pi) = (
        c.kind.levels(),
        c.kind.generator(),
        c.kind.stationary().unwrap(),
    );
    let (burn, window) = (30.0, 20.0);
    let times = [burn, burn + window, burn + 2.0 * window];
    (0..particles)
        .map(|i| {
            let mut rng = irtp::rng::stream(20_261_206, i);
            let mut u: f64 = rng.gen();
            let mut s = pi
                .iter()
                .position(|p| {
                    u -= p;
                    u < 0.0
                })
                .unwrap_or(pi.len() - 1);
            let (mut t, mut state) = (0.0f64, (0.0f64, 0.0f64));
            let mut xs = [0.0; 3];
            for (slot, &stop) in times.iter().enumerate() {
                loop {
                    let total = -q[s][s] + c.rate;
                    let tau = -(1.0 - rng.gen::<f64>()).ln() / total;
                    if t + tau >= stop {
                        state = advance(state, a[s], c.gamma, c.temp, stop - t, &mut rng);
                        t = stop;
                        break;
                    }
                    state = advance(state, a[s], c.gamma, c.temp, tau, &mut rng);
                    t += tau;
                    let mut pick = rng.gen::<f64>() * total;
                    if pick < c.rate {
                        state.0 = c.vr;
                        continue;
                    }
                    pick -= c.rate;
                    s = (0..q.len())
                        .filter(|&j| j != s)
                        .find(|&j| {
                            pick -= q[s][j];
                            pick < 0.0
                        })
                        .unwrap_or(s);
                }
                xs[slot] = state.1;
            }
            let (d1, d2) = (
                xs[1] - xs[0] - drift * window,
                xs[2] - xs[0] - 2.0 * drift * window,
            );
            (state.0, (d2 * d2 - d1 * d1) / (2.0 * window))
        })
        .collect()
}

fn mean_se(xs: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = xs.clone().count() as f64;
    let m = xs.clone().sum::<f64>() / n;
    let var = xs.map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// The closed forms against the exact simulation: an asymmetric telegraph
/// with resetting, a three-state chain with repeated levels at r = 0, and
/// run-pause-tumble with thermal noise and resetting; `<v>`, `<v²>` and
/// D_eff each within 4 standard errors (nine comparisons). U is the test's
/// own (`<a>` + r v_r)/(γ + r), the mean of L v = 0. Measured (20000
/// particles): |z| ≤ 1.71.
#[test]
fn linear_noise_against_exact_simulation() {
    let cases = [
        (
            "telegraph:plus=1.5,minus=0.5,rate_plus=0.8,rate_minus=0.4",
            1.3,
            0.0,
            0.7,
            0.3,
        ),
        (
            "states:levels=[1,1,-2],rates=[[-2,2,0],[0,-2,2],[1,0,-1]]",
            0.8,
            0.0,
            0.0,
            0.0,
        ),
        ("rpt:sigma=1.2,alpha=0.6,beta=1.5", 1.7, 0.4, 0.5, -0.2),
    ];
    for (spec, gamma, temp, rate, vr) in cases {
        let c = Case {
            gamma,
            kind: kind(spec),
            temp,
            rate,
            vr,
        };
        let pi = c.kind.stationary().unwrap();
        let mean_a: f64 = pi.iter().zip(c.kind.levels()).map(|(p, a)| p * a).sum();
        let u = (mean_a + rate * vr) / (gamma + rate);
        let noise = NoiseModel::new(c.kind.clone(), temp).unwrap();
        let got = moments(gamma, noise, rate, vr);
        assert!((got.drift - u).abs() < 1e-14);
        let sim = simulate(&c, u, 20_000);
        for (name, exact, (m, se)) in [
            ("<v>", got.v_mean, mean_se(sim.iter().map(|p| p.0))),
            ("<v2>", got.v2, mean_se(sim.iter().map(|p| p.0 * p.0))),
            ("D_eff", got.d_eff, mean_se(sim.iter().map(|p| p.1))),
        ] {
            let z = (m - exact) / se;
            eprintln!(
                "{spec} T={temp} {name}: exact {exact:.6}, simulated {m:.6} ± {se:.6} (z = {z:.2})"
            );
            assert!(z.abs() < 4.0, "{spec} {name}: {m} ± {se} vs {exact}");
        }
    }
}

/// The r = 0 telegraph density with a symmetric noise equals the
/// symmetric density (Eqs. (34)-(35) for tan, tanh, linear; quadrature for
/// cubic) at points up to 1e-12 from the edges, in its state split and in
/// `<v²>`, to 1e-12 relative (measured: 4e-15 at worst).
#[test]
fn telegraph_r0_reduces_to_the_symmetric_density() {
    for (drag, s, l) in [
        (DragLaw::Tan, 3.0, 0.9),
        (DragLaw::Tan, 3.0, 7.0),
        (DragLaw::Tanh, 0.6, 0.85),
        (DragLaw::Linear, 1.3, 0.3),
        (DragLaw::Cubic, 2.0, 1.5),
    ] {
        let sym = R0Density::new(drag.clone(), s, l).unwrap();
        let tel =
            TelegraphR0Density::new(drag.clone(), Telegraph::symmetric(s, l).unwrap()).unwrap();
        let vu = sym.bounds().1;
        assert_eq!(tel.bounds(), sym.bounds());
        for w in [1e-12, 1e-6, 0.01, 0.3, 0.9] {
            for v in [vu - w * vu, -vu + w * vu] {
                let (a, b) = (tel.pdf(v), sym.pdf(v));
                assert!(
                    (a - b).abs() <= 1e-12 * b,
                    "{drag} {s} {l} v={v}: {a} vs {b}"
                );
                let (sa, sb) = (tel.state_pdf(v), sym.state_pdf(v));
                assert!((sa.0 - sb.0).abs() <= 1e-12 * b && (sa.1 - sb.1).abs() <= 1e-12 * b);
            }
        }
        let v2 = tel.moment(2).unwrap();

        assert!(
            (v2 - sym.v2()).abs() < 1e-12 * sym.v2(),
            "{drag} {v2} vs {}",
            sym.v2()
        );
        assert!(tel.moment(1).unwrap().abs() < 1e-12);
    }
}

/// Asymmetric telegraph, linear drag g = γ v at r = 0 (γ = 1: the shipped
/// linear law): the density's `<v>` and `<v²>` equal the closed forms
/// (N3)-(N4), an independent route (moments of the generator, not the
/// density); the edge exponents are k/g' - 1.
#[test]
fn telegraph_r0_matches_the_linear_closed_forms() {
    for (p, m, kp, km) in [
        (1.5, 0.5, 0.8, 0.4),
        (2.0, 1.0, 0.3, 3.0),
        (1.0, -0.4, 2.0, 0.5),
    ] {
        let t = Telegraph::new(p, m, kp, km).unwrap();
        let d = TelegraphR0Density::new(DragLaw::Linear, t).unwrap();
        let noise = NoiseModel::new(NoiseKind::Telegraph(t), 0.0).unwrap();
        let want = moments(1.0, noise, 0.0, 0.0);
        let (v1, v2) = (d.moment(1).unwrap(), d.moment(2).unwrap());
        assert!(
            (v1 - want.v_mean).abs() < 1e-11,
            "{p} {m}: {v1} vs {}",
            want.v_mean
        );
        assert!(
            (v2 - want.v2).abs() < 1e-11 * want.v2,
            "{p} {m}: {v2} vs {}",
            want.v2
        );
        assert_eq!(d.edge_exponents(), (km - 1.0, kp - 1.0));
        assert_eq!(d.bounds(), (-m, p));
    }
    // tan drag, asymmetric: <g(v)> = <a> is checked inside new(); the
    // density is positive and its state split sums to it.
    let t = Telegraph::new(3.0, 1.0, 0.5, 1.5).unwrap();
    let d = TelegraphR0Density::new(DragLaw::Tan, t).unwrap();
    let (pp, pm) = d.state_pdf(0.3);
    assert!((pp + pm - d.pdf(0.3)).abs() < 1e-15 * d.pdf(0.3));
    assert!(DragLaw::Tan.inverse(3.0) == d.bounds().1);
}

/// The asymmetric r = 0 density solves the stationary forward equations
/// it was derived from, d/dv(f₊p₊) = -k₊p₊ + k₋p₋ and
/// d/dv(f₋p₋) = k₊p₊ - k₋p₋ (central differences, step 1e-5: error
/// ~1e-9 of the terms), for a Riccati law, generic laws, power laws,
/// Coulomb friction (its jump at v = 0 is the split point) and an
/// expression, on both halves of the interval.
#[test]
fn telegraph_r0_solves_the_forward_equations() {
    let laws = [
        "tan",
        "cubic",
        "power:n=0.5",
        "power:n=2,k=0.5",
        "coulomb:mu=0.3",
        "expr:v + 0.3*v^3",
    ];
    for (law, (p, m, kp, km)) in laws.iter().zip([
        (3.0, 1.0, 0.5, 1.5),
        (2.0, 0.5, 1.2, 0.3),
        (1.0, 2.0, 0.7, 2.5),
        (1.5, 0.4, 3.0, 0.8),
        (2.0, 1.0, 0.6, 1.1),
        (1.0, 1.5, 2.0, 0.9),
    ]) {
        let drag: DragLaw = law.parse().unwrap();
        let d =
            TelegraphR0Density::new(drag.clone(), Telegraph::new(p, m, kp, km).unwrap()).unwrap();
        let (vl, vu) = d.bounds();
        let fluxes = |v: f64| {
            let (pp, pm) = d.state_pdf(v);
            ((p - drag.force(v)) * pp, (-m - drag.force(v)) * pm)
        };
        for x in [0.1, 0.3, 0.45, 0.6, 0.8, 0.95] {
            let v = vl + x * (vu - vl);
            if v.abs() < 1e-4 {
                continue;
            }
            let h = 1e-5;
            let (hi, lo) = (fluxes(v + h), fluxes(v - h));
            let (dp, dm) = ((hi.0 - lo.0) / (2.0 * h), (hi.1 - lo.1) / (2.0 * h));
            let (pp, pm) = d.state_pdf(v);
            let rhs = -kp * pp + km * pm;
            let scale = kp * pp + km * pm;
            assert!(
                (dp - rhs).abs() < 1e-7 * scale,
                "{law} v={v}: {dp} vs {rhs}"
            );
            assert!(
                (dm + rhs).abs() < 1e-7 * scale,
                "{law} v={v}: {dm} vs {}",
                -rhs
            );
            let (f0, f1) = fluxes(v);
            assert!((f0 + f1).abs() < 1e-13 * f0.abs(), "{law} zero flux at {v}");
        }
    }
}

/// `cases` cases from a fixed seed: the same inputs on every run.
fn fixed(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(0x0015_e0ce),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// A positive finite double of any magnitude (every bit pattern of the
/// exponent range 1e-300..1e300).
fn positive() -> impl Strategy<Value = f64> {
    (-300.0f64..300.0, 1.0f64..10.0).prop_map(|(e, m)| m * 10f64.powf(e))
}

proptest! {
    #![proptest_config(fixed(500))]

    /// Any valid telegraph or chain spec round-trips bit for bit.
    #[test]
    fn random_specs_round_trip(p in positive(), m in positive(), kp in positive(), km in positive(),
                               rates in proptest::collection::vec(0.0f64..10.0, 6)) {
        let t = NoiseKind::Telegraph(Telegraph::new(p, m, kp, km).unwrap());
        prop_assert_eq!(t.spec().parse::<NoiseKind>().unwrap(), t);
        let levels = vec![p, -m, kp];
        let q: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                let mut row: Vec<f64> = (0..3).map(|j| if i == j { 0.0 } else { rates[2 * i + j.min(1)] + 0.1 }).collect();
                row[i] = -row.iter().sum::<f64>();
                row
            })
            .collect();
        let s = NoiseKind::States(irtp::model::noise::States::new(levels, q).unwrap());
        prop_assert_eq!(s.spec().parse::<NoiseKind>().unwrap(), s);
    }

    /// The stationary law of a random irreducible chain (2 to 6 states,
    /// rates spanning four decades) is a probability law with Qᵀ π = 0 to
    /// 1e-12 of the largest rate; the chain doubled into mirror pairs
    /// (levels ±a_k, rate 1 within a pair, half the chain's rate to each
    /// state of another pair) has the pair swap as its mirror map, and
    /// none once one rate is changed.
    #[test]
    fn random_chains_have_a_stationary_law(n in 2usize..7, logs in proptest::collection::vec(-2.0f64..2.0, 36)) {
        let mut q: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| if i == j { 0.0 } else { 10f64.powf(logs[i * 6 + j]) }).collect()).collect();
        for (i, row) in q.iter_mut().enumerate() {
            row[i] = -row.iter().sum::<f64>();
        }
        let pi = chain::stationary(&q).unwrap();
        let top = q.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        prop_assert!((pi.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        for i in 0..n {
            let flux: f64 = (0..n).map(|j| q[j][i] * pi[j]).sum();
            prop_assert!(flux.abs() <= 1e-12 * top && pi[i] >= 0.0);
        }
        let levels: Vec<f64> = (0..2 * n).map(|k| if k % 2 == 0 { 1.0 + k as f64 } else { -(k as f64) }).collect();
        let mut big: Vec<Vec<f64>> = (0..2 * n)
            .map(|a| {
                (0..2 * n)
                    .map(|b| match (a / 2 == b / 2, a == b) {
                        (true, true) => 0.0,
                        (true, false) => 1.0,
                        _ => 0.5 * q[a / 2][b / 2],
                    })
                    .collect()
            })
            .collect();
        for (a, row) in big.iter_mut().enumerate() {
            row[a] = -row.iter().sum::<f64>();
        }
        chain::validate(&levels, &big, "s", "u").unwrap();
        let swap: Vec<usize> = (0..2 * n).map(|k| k ^ 1).collect();
        prop_assert_eq!(chain::mirror(&levels, &big), Some(swap));
        big[0][2] *= 1.5;
        big[0][0] -= 0.5 * big[0][2] / 1.5;
        prop_assert_eq!(chain::mirror(&levels, &big), None);
    }
}

/// The paper's noise written as a model (either telegraph spelling, T = 0)
/// is the default `Params` bit for bit: no noise carried, the same JSON.
#[test]
fn params_with_the_papers_noise_are_the_default() {
    let plain = Params::new(DragLaw::Tanh, 0.75, 0.625, 1.5, 0.1).unwrap();
    for spec in [
        "telegraph:sigma=0.75,lambda=0.625",
        "telegraph:plus=0.75,minus=0.75,rate_plus=0.625,rate_minus=0.625",
    ] {
        let p = Params::with_noise(DragLaw::Tanh, model(spec, 0.0), 1.5, 0.1).unwrap();
        assert_eq!(p, plain, "{spec}");
        assert!(p.noise().is_none());
        assert_eq!(
            serde_json::to_string(&p).unwrap(),
            serde_json::to_string(&plain).unwrap()
        );
    }
    let json = serde_json::to_string(&plain).unwrap();
    assert!(
        !json.contains("noise") && !json.contains("temperature"),
        "{json}"
    );
}

/// Another noise is carried, serialised and read back, kept by the
/// `with_*` builders, and refused by every solver whose line of the
/// support table is off, naming `noise` (or `temperature` for the paper's
/// noise at T > 0); the search problem refuses thermal noise only.
#[test]
fn params_carry_another_noise_and_every_solver_refuses_it() {
    use irtp::model::reset::Solver;
    use irtp::search::{PositionTarget, SearchProblem};
    let rpt = model("rpt:sigma=1,alpha=1,beta=2", 0.0);
    let warm = model("telegraph:sigma=1,lambda=0.5", 0.25);
    for (m, flag) in [(rpt, "noise"), (warm, "temperature")] {
        let p = Params::with_noise(DragLaw::Linear, m.clone(), 0.5, 0.2).unwrap();
        assert_eq!(p.noise(), Some(&m));
        let json = serde_json::to_string(&p).unwrap();
        assert!(
            json.contains(&format!("\"noise\":\"{}\"", m.spec())),
            "{json}"
        );
        let back: Params = serde_json::from_str(&json).unwrap();
        assert_eq!(back, p);
        assert_eq!(p.with_rate(2.0).unwrap().noise(), Some(&m));
        assert_eq!(p.with_reset_velocity(-0.1).unwrap().noise(), Some(&m));
        assert_eq!(blamed(p.with_lambda(1.0).unwrap_err()).0, "lambda");
        // The engines that run a noise model say so in the support table.
        let refused = Solver::ALL
            .into_iter()
            .filter(|&s| !irtp::model::noise::support::supports(s, &m));
        for solver in refused {
            let (name, msg) = blamed(p.require(solver).unwrap_err());
            assert_eq!(name, flag, "{solver}: {msg}");
            assert!(
                msg.contains(solver.command()) && msg.contains("simulate, fp"),
                "{msg}"
            );
        }
        // The backward equations run every noise model (mfpt::backward).
        assert!(irtp::mfpt::Problem::new(p.clone(), 0.0, 0.5).is_ok());
        // A search admits a noise model at T = 0 (its methods decide at
        // `search::noise_gate`) and refuses thermal noise with the problem.
        let search = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Interval(-1.0, 1.0));
        match flag {
            "noise" => assert!(search.is_ok()),
            _ => assert_eq!(blamed(search.unwrap_err()).0, flag),
        }
    }
    // A level outside the drag's force range, and v_r outside the interval.
    let e = Params::with_noise(
        DragLaw::Tanh,
        model("rpt:sigma=1,alpha=1,beta=1", 0.0),
        0.0,
        0.0,
    );
    assert_eq!(blamed(e.unwrap_err()).0, "noise");
    let e = Params::with_noise(
        DragLaw::Linear,
        model("rpt:sigma=1,alpha=1,beta=1", 0.0),
        1.0,
        1.0,
    );
    assert_eq!(blamed(e.unwrap_err()).0, "reset_velocity");
}

/// `analytic::noise::solve`: linear drag gives [`LinearNoise`]'s moments,
/// an asymmetric telegraph noise at r = 0 the density of Eq. (N8); both
/// for linear drag with that noise, and then they agree; nothing else.
#[test]
fn closed_forms_from_params() {
    use irtp::analytic::noise::solve;
    let asym = model("telegraph:plus=1,minus=0.5,rate_plus=1,rate_minus=2", 0.0);
    let p = Params::with_noise(DragLaw::Linear, asym.clone(), 0.0, 0.0).unwrap();
    let c = solve(&p).unwrap();
    let (m, d) = (c.moments.unwrap(), c.density.unwrap());
    assert_eq!(m, moments(1.0, asym.clone(), 0.0, 0.0));
    assert!((d.moment(1).unwrap() - m.v_mean).abs() < 1e-10);
    assert!((d.moment(2).unwrap() - m.v2).abs() < 1e-10);
    let tan = Params::with_noise(
        DragLaw::Tan,
        model("telegraph:plus=3,minus=2,rate_plus=1,rate_minus=2", 0.0),
        0.0,
        0.0,
    )
    .unwrap();
    let c = solve(&tan).unwrap();
    assert!(c.moments.is_none() && c.density.is_some());
    let rpt = Params::with_noise(
        DragLaw::Tan,
        model("rpt:sigma=1,alpha=1,beta=1", 0.0),
        0.0,
        0.0,
    )
    .unwrap();
    assert_eq!(blamed(solve(&rpt).unwrap_err()).0, "noise");
    let reset = Params::with_noise(DragLaw::Tan, asym, 1.0, 0.0).unwrap();
    assert_eq!(blamed(solve(&reset).unwrap_err()).0, "noise");
    // The paper's noise takes the route of its `states:` spelling.
    let paper = Params::new(DragLaw::Linear, 1.0, 0.5, 0.7, 0.2).unwrap();
    let spelt = model("states:levels=[1,-1],rates=[[-0.5,0.5],[0.5,-0.5]]", 0.0);
    let spelt = Params::with_noise(DragLaw::Linear, spelt, 0.7, 0.2).unwrap();
    let a = solve(&paper).unwrap().moments.unwrap();
    let b = solve(&spelt).unwrap().moments.unwrap();
    for (x, y) in [
        (a.v_mean, b.v_mean),
        (a.v2, b.v2),
        (a.drift, b.drift),
        (a.d_eff, b.d_eff),
    ] {
        assert!((x - y).abs() <= 1e-12 * y.abs().max(1.0), "{x} vs {y}");
    }
}
