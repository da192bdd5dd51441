//! The parameterised media: the power law `power:n=N,k=K` and the Carreau
//! law `carreau:n=N,a=A` through every method.
//!
//! (a) At n = 1 (k = 1) both are the linear law: the Fokker-Planck density
//!     and <v²>, the backward MFPT, the r = 0 density and the exact sampler's
//!     seeded output agree with `linear` to 1e-10.
//! (b) r = 0: the Fokker-Planck density against an independent quadrature
//!     (composite Simpson on graded panels, here) of P ∝ (Sigma² - g²)⁻¹
//!     exp(-2 lambda ∫_0^v g / (Sigma² - g²) dv').
//! (c) r > 0: the exact sampler against the Fokker-Planck solver (<v²> and a
//!     histogram), the exact first-passage sampler against the backward
//!     equations.
//! (d) Bad specs: exit 2, one line naming the parameter, nothing written.

use crate::common::stats::bonferroni_z;
use irtp::analytic::r0::R0Density;
use irtp::fp::{stationary, Stationary, StationaryOptions};
use irtp::mfpt::{backward, solve, BackwardOptions, Method, ParticleOptions, Problem};
use irtp::model::{Drag, DragLaw};
use irtp::parallel::NoProgress;
use irtp::sim::{exact, SimSpec, TimeGrid};
use irtp::Params;
use std::process::Command;

fn law(spec: &str) -> DragLaw {
    spec.parse().unwrap()
}

/// The three media of the cross-method checks.
const MEDIA: [&str; 3] = ["power:n=0.5", "power:n=2", "carreau:n=0.5,a=1"];

/// The r = 0 density P(v) ∝ (Sigma² - g²)⁻¹ exp(-2 lambda Φ(v)),
/// Φ(v) = ∫_0^|v| g / (Sigma² - g²), by composite Simpson on graded panels
/// (a different rule from the library's Gauss-Kronrod): the normalised mass
/// of each of `bins` equal bins of (v_l, v_u) and <v²>.
///
/// The logarithmic edge singularity of Φ is subtracted in closed form:
/// g / (Sigma² - g²) ≈ c [1/(v_u - w) - 1/(v_u + w)] near ±v_u with
/// c = 1 / (2 g'(v_u)), whose integral from 0 is -c ln(1 - v²/v_u²); the
/// remainder is bounded. Panels (`PANELS` per bin, on the half line by
/// symmetry) are graded quadratically into v = 0 (where g may behave like
/// |v|^n) and into v_u (where P ~ (v_u - v)^a, a > 0 here); at v_u, P = 0.
fn r0_quadrature(d: DragLaw, sigma: f64, lambda: f64, bins: usize) -> (Vec<f64>, f64) {
    const PANELS: usize = 4000;
    let vu = d.inverse(sigma);
    let c = 0.5 / d.derivative(vu);
    let h = |w: f64| {
        let g = d.force(w);
        g / ((sigma - g) * (sigma + g)) - c / (vu - w) + c / (vu + w)
    };
    let p = |x: f64, rem: f64| {
        if x >= vu {
            return 0.0;
        }
        let g = d.force(x);
        let phi = rem - c * (-(x / vu) * (x / vu)).ln_1p();
        (-2.0 * lambda * phi).exp() / ((sigma - g) * (sigma + g))
    };
    let simpson = |a: f64, b: f64| (b - a) / 6.0 * (h(a) + 4.0 * h(0.5 * (a + b)) + h(b));
    let half = bins / 2;
    let edge = |j: usize| vu * j as f64 / half as f64;
    let (mut mass, mut v2, mut rem) = (vec![0.0; half], 0.0, 0.0);
    for (j, m) in mass.iter_mut().enumerate() {
        let (e0, e1) = (edge(j), edge(j + 1));
        let at = |t: f64| match j {
            0 => e1 * t * t,
            _ if j + 1 == half => vu - (vu - e0) * (1.0 - t) * (1.0 - t),
            _ => e0 + (e1 - e0) * t,
        };
        for i in 0..PANELS {
            let xa = at(i as f64 / PANELS as f64);
            let xb = at((i + 1) as f64 / PANELS as f64);
            let xm = 0.5 * (xa + xb);
            let rem_m = rem + simpson(xa, xm);
            let rem_b = if xb < vu {
                rem_m + simpson(xm, xb)
            } else {
                rem_m
            };
            let (pa, pm, pb) = (p(xa, rem), p(xm, rem_m), p(xb, rem_b));
            *m += (xb - xa) / 6.0 * (pa + 4.0 * pm + pb);
            v2 += (xb - xa) / 6.0 * (xa * xa * pa + 4.0 * xm * xm * pm + xb * xb * pb);
            rem = rem_b;
        }
    }
    let z = 2.0 * mass.iter().sum::<f64>();
    let out: Vec<f64> = mass
        .iter()
        .rev()
        .chain(mass.iter())
        .map(|m| m / z)
        .collect();
    (out, 2.0 * v2 / z)
}

/// Probability of each bin [edges[i], edges[i+1]] under the FP cell
/// averages (cells cut by a bin edge share their mass by overlap).
fn fp_bin_mass(fp: &Stationary, edges: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; edges.len() - 1];
    for (i, &p) in fp.p.iter().enumerate() {
        let (a, b) = (fp.edges[i], fp.edges[i + 1]);
        for (j, m) in out.iter_mut().enumerate() {
            let lo = a.max(edges[j]);
            let hi = b.min(edges[j + 1]);
            if hi > lo {
                *m += p * fp.widths[i] * (hi - lo) / (b - a);
            }
        }
    }
    out
}

fn opts(cells: usize) -> StationaryOptions {
    StationaryOptions {
        cells,
        ..StationaryOptions::default()
    }
}

/// (a) n = 1 (k = 1, a = 1): the Fokker-Planck density (every cell) and
/// <v²>, the backward MFPT tau and the r = 0 density (pdf on a grid and
/// <v²>) equal linear drag's to 1e-10. The laws reach the solvers only
/// through g, g', g⁻¹ and the drift near the edges, which agree with
/// linear to rounding (power: k|v|^1 = |v| exactly; Carreau: hypot^0 = 1).
#[test]
fn newtonian_limit_equals_linear() {
    let lin = |l: DragLaw, r: f64| Params::new(l, 1.3, 0.7, r, 0.2).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-10 * a.abs().max(1e-3);
    for spec in [
        "power:n=1",
        "power:n=1,k=1",
        "carreau:n=1",
        "carreau:n=1,a=3",
    ] {
        let d = law(spec);
        for r in [0.0, 2.0] {
            let (a, b) = (lin(DragLaw::Linear, r), lin(d, r));
            let o = opts(4000);
            let (fa, fb) = (stationary(&a, &o).unwrap(), stationary(&b, &o).unwrap());
            assert!(close(fa.v2, fb.v2), "{spec} r={r}: {} vs {}", fa.v2, fb.v2);
            for (pa, pb) in fa.p.iter().zip(&fb.p) {
                assert!(close(*pa, *pb), "{spec} r={r} density");
            }
        }
        let (pa, pb) = (lin(DragLaw::Linear, 2.0), lin(d, 2.0));
        let bo = BackwardOptions::default();
        let ta = backward::solve(&Problem::new(pa, -0.249, 0.5).unwrap(), &bo).unwrap();
        let tb = backward::solve(&Problem::new(pb, -0.249, 0.5).unwrap(), &bo).unwrap();
        assert!(
            close(ta.tau, tb.tau),
            "{spec}: tau {} vs {}",
            ta.tau,
            tb.tau
        );
        let ra = R0Density::from_params(&lin(DragLaw::Linear, 0.0)).unwrap();
        let rb = R0Density::by_quadrature(d, 1.3, 0.7).unwrap();
        assert!(
            close(ra.v2(), rb.v2()),
            "{spec}: r0 <v²> {} vs {}",
            ra.v2(),
            rb.v2()
        );
        for i in 1..40 {
            let v = -1.3 + 2.6 * i as f64 / 40.0;
            assert!(close(ra.pdf(v), rb.pdf(v)), "{spec}: r0 pdf at {v}");
        }
    }
}

/// (a) The exact sampler at n = 1 against linear, same seed: the event
/// times and noise flips are drawn from the same streams whatever the law,
/// and the flows (linear: closed form; power, Carreau: tabulated, exact to
/// ~1e-14) agree to rounding, so every recorded moment and the time
/// averages agree to 1e-10 relative (observed: ~1e-14).
#[test]
fn newtonian_limit_exact_sampler_equals_linear() {
    let spec = SimSpec::new(
        2000,
        TimeGrid::from_times(vec![0.0, 1.0, 5.0, 20.0]).unwrap(),
        5.0,
        20,
        7,
    )
    .unwrap();
    let run = |d: DragLaw| {
        let p = Params::new(d, 1.3, 0.7, 2.0, 0.2).unwrap();
        exact::simulate(&p, &spec, &NoProgress).unwrap()
    };
    let a = run(DragLaw::Linear);
    for s in ["power:n=1", "carreau:n=1"] {
        let b = run(law(s));
        assert_eq!(a.steps, b.steps, "{s}: events");
        let pairs = a.v2.iter().zip(&b.v2).chain(a.x2.iter().zip(&b.x2));
        for (x, y) in pairs.chain([(&a.v2_time_avg, &b.v2_time_avg)]) {
            let (x, y) = (x.mean(), y.mean());
            assert!(
                (x - y).abs() <= 1e-10 * x.abs().max(1e-6),
                "{s}: {x} vs {y}"
            );
        }
    }
}

/// (b) r = 0, where the density is the closed quadrature formula: the FP
/// bin masses (16 bins) and <v²> against composite Simpson. Parameters keep
/// the edge exponent a = lambda/g'(v_u) - 1 > 0 (power n = 0.5: a = 2;
/// n = 2: a = 0.44; Carreau: a = 1.98), so the density is continuous and
/// the quadrature converges. Tolerances from the mesh: the first-order FP bin
/// masses move by |P_N - P_{N/2}| between N = 4000 and 2000 cells, an
/// estimate of the fine mesh's own error, allowed twice over (+1e-9); the
/// extrapolated <v²> within |<v²>_extrapolated - <v²>_fine| (+1e-9).
#[test]
fn r0_density_matches_quadrature() {
    for (spec, lambda) in [
        ("power:n=0.5", 0.5),
        ("power:n=2", 5.0),
        ("carreau:n=0.5,a=1", 0.5),
    ] {
        let (d, sigma) = (law(spec), 3.0);
        let p = Params::new(d, sigma, lambda, 0.0, 0.0).unwrap();
        let (fine, coarse) = (
            stationary(&p, &opts(4000)).unwrap(),
            stationary(&p, &opts(2000)).unwrap(),
        );
        let vu = d.inverse(sigma);
        let edges: Vec<f64> = (0..=16).map(|i| -vu + 2.0 * vu * i as f64 / 16.0).collect();
        let (bins, v2) = r0_quadrature(d, sigma, lambda, 16);
        let (mf, mc) = (fp_bin_mass(&fine, &edges), fp_bin_mass(&coarse, &edges));
        for j in 0..16 {
            let q = bins[j];
            let tol = 2.0 * (mf[j] - mc[j]).abs() + 1e-9;
            assert!(
                (mf[j] - q).abs() <= tol,
                "{spec} bin {j}: FP {} vs quadrature {q} (tol {tol:e})",
                mf[j]
            );
        }
        let tol = (fine.v2 - fine.fine.v2).abs() + 1e-9;
        eprintln!(
            "{spec} r=0: FP <v²> {} quadrature {v2} (tol {tol:e})",
            fine.v2
        );
        assert!((fine.v2 - v2).abs() <= tol, "{spec}: <v²>");
        // The library's own r = 0 density (Gauss-Kronrod) agrees too.
        let lib = R0Density::by_quadrature(d, sigma, lambda).unwrap();
        assert!(
            (lib.v2() - v2).abs() <= 1e-8 * v2,
            "{spec}: {} vs {v2}",
            lib.v2()
        );
    }
}

/// (c) r = 2: the exact sampler's time-averaged <v²> and its 20-bin
/// histogram against the FP solver. 3 laws × 21 comparisons, Bonferroni:
/// |z| < 4.89; the FP error estimate is added in quadrature.
#[test]
fn exact_sampler_matches_fokker_planck() {
    let zmax = bonferroni_z(MEDIA.len() * 21);
    let spec = SimSpec::new(
        4000,
        TimeGrid::from_times(vec![0.0, 40.0]).unwrap(),
        10.0,
        20,
        2025,
    )
    .unwrap();
    for s in MEDIA {
        let p = Params::new(law(s), 3.0, 0.5, 2.0, 0.0).unwrap();
        let fp = stationary(&p, &StationaryOptions::default()).unwrap();
        let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
        let (m, se) = (o.v2_time_avg.mean(), o.v2_time_avg.sem());
        let se = se.hypot(fp.v2 - fp.fine.v2);
        eprintln!("{s} r=2: exact <v²> {m} ± {se}, FP {}", fp.v2);
        assert!(
            ((m - fp.v2) / se).abs() < zmax,
            "{s}: {m} ± {se} vs {}",
            fp.v2
        );
        let w = o.bin_width();
        let edges: Vec<f64> = (0..=20).map(|i| o.v_lo + w * i as f64).collect();
        let mass = fp_bin_mass(&fp, &edges);
        // Bins the particles never visit (the far tails of the wide
        // power-law interval, v_u = 9) have no standard error: there the FP
        // mass must be negligible too (< 1e-6).
        let mut worst = 0.0f64;
        for (acc, q) in o.density_time.iter().zip(&mass) {
            if acc.sem() > 0.0 {
                worst = worst.max(((acc.mean() - q / w) / acc.sem()).abs());
            } else {
                assert!(
                    acc.mean() == 0.0 && *q < 1e-6,
                    "{s}: unvisited bin with FP mass {q}"
                );
            }
        }
        eprintln!("{s} r=2: histogram max |z| {worst:.2} (bound {zmax:.2})");
        assert!(worst < zmax, "{s}: histogram max |z| = {worst}");
    }
}

/// (c) The exact first-passage sampler's MFPT against the backward
/// equations (v_0 = -0.249, v_t = 0.5, r = 2): 3 comparisons, Bonferroni
/// |z| < 4.25, the backward error estimate added in quadrature.
#[test]
fn exact_mfpt_matches_backward_equations() {
    let zmax = bonferroni_z(MEDIA.len());
    for (i, s) in MEDIA.into_iter().enumerate() {
        let p = Params::new(law(s), 3.0, 0.5, 2.0, 0.0).unwrap();
        let prob = Problem::new(p, -0.249, 0.5).unwrap();
        let ode = backward::solve(&prob, &BackwardOptions::default()).unwrap();
        let run = ParticleOptions {
            particles: 10_000,
            t_max: f64::INFINITY,
            seed: 300 + i as u64,
        };
        let st = solve(&prob, &Method::Exact(run), &NoProgress)
            .unwrap()
            .summary()
            .expect("particle estimate");
        assert_eq!(st.censored, 0);
        let err = if ode.error_estimate.is_finite() {
            ode.error_estimate
        } else {
            0.0
        };
        let se = st.tau_err.hypot(err);
        eprintln!(
            "{s}: exact tau {} ± {}, backward {}",
            st.tau, st.tau_err, ode.tau
        );
        assert!(((st.tau - ode.tau) / se).abs() < zmax, "{s}");
    }
}

/// The Euler scheme accepts the power law with n < 1 (bounded drift, g'
/// unbounded at 0) up to its secant bound: a step just below the bound keeps
/// every velocity of a fine grid of (v_l, v_u) inside (the Euler map
/// v + dt (Sigma - g(v)) stays below v_u), one 1 % above it throws some out
/// and is refused naming --dt.
#[test]
fn euler_step_limit_for_unbounded_slope() {
    for spec in ["power:n=0.5", "power:n=0.2,k=3"] {
        let p = Params::new(law(spec), 3.0, 0.5, 2.0, 0.0).unwrap();
        let (d, vu) = (p.drag(), p.v_upper());
        let max = p.max_euler_dt();
        assert!(max.is_finite() && max > 0.0, "{max}");
        assert!(d.max_derivative(3.0).is_infinite());
        let escapes = |dt: f64| {
            (1..200_000)
                .map(|i| -vu + 2.0 * vu * i as f64 / 200_000.0)
                .filter(|v| v + dt * (3.0 - d.force(*v)) >= vu)
                .count()
        };
        assert_eq!(escapes(max * (1.0 - 1e-9)), 0, "{spec}");
        assert!(escapes(1.01 * max) > 0, "{spec}: the bound is not sharp");
        assert!(p.check_dt(0.5 * max).is_ok());
        let e = p.check_dt(1.01 * max).unwrap_err().to_string();
        assert!(e.contains("dt"), "{e}");
    }
}

/// The Euler scheme (dt = 2e-3) on the power law with n = 0.5 against the FP
/// <v²> at r = 2: one comparison, 4 standard errors (the O(dt) bias, ~1e-3
/// relative, is below the SE of ~1 %).
#[test]
fn euler_matches_fokker_planck_for_unbounded_slope() {
    let p = Params::new(law("power:n=0.5"), 3.0, 0.5, 2.0, 0.0).unwrap();
    let fp = stationary(&p, &StationaryOptions::default()).unwrap();
    let spec = SimSpec::new(
        2000,
        TimeGrid::from_times(vec![0.0, 30.0]).unwrap(),
        10.0,
        20,
        11,
    )
    .unwrap();
    let o = irtp::sim::euler::simulate(&p, &spec, 2e-3, &NoProgress).unwrap();
    let (m, se) = (o.v2_time_avg.mean(), o.v2_time_avg.sem());
    eprintln!("power:n=0.5 r=2: Euler <v²> {m} ± {se}, FP {}", fp.v2);
    assert!(((m - fp.v2) / se).abs() < 4.0, "{m} ± {se} vs {}", fp.v2);
}

fn irtp(args: &[&str]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// (d) Every bad spec: exit 2, one line naming the parameter (or the
/// offending key), nothing written.
#[test]
fn bad_specs_are_refused_naming_the_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    let cases = [
        ("power:n=0", "n > 0"),
        ("power:n=-1", "n > 0"),
        ("power:n=NaN", "n > 0"),
        ("power:n=inf", "n > 0"),
        ("power:n=0.5,k=0", "k > 0"),
        ("power:n=0.5,k=-1", "k > 0"),
        ("power:n=0.5,k=nan", "k > 0"),
        ("carreau:n=0", "n > 0"),
        ("carreau:n=0.5,a=0", "a > 0"),
        ("carreau:n=0.5,a=-inf", "a > 0"),
        ("power:n=0.5,q=1", "unknown key 'q'"),
        ("power:k=1", "a value for n"),
        ("power", "a value for n"),
        ("power:n", "key=value"),
        ("power:n=abc", "a number for n"),
        ("power:n=1,n=2", "'n' repeated"),
        ("carreau:n=1,k=1", "unknown key 'k'"),
        ("tan:n=1", "no parameters"),
        ("powr:n=1", "one of tan"),
    ];
    for (spec, needle) in cases {
        for cmd in [&["analytic"][..], &["fp", "stationary"][..]] {
            let args = [cmd, &["--drag", spec, "--out", out_s]].concat();
            let (code, err) = irtp(&args);
            assert_eq!(code, Some(2), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
            assert!(
                err.contains("--drag") && err.contains(needle),
                "{args:?}: {err}"
            );
            assert!(!out.exists(), "{args:?} wrote {out:?}");
        }
    }
}

/// The spec written to provenance is canonical (every key, shortest
/// round-trip numbers) and parses back to the same law.
#[test]
fn specs_round_trip_through_provenance() {
    let o = Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args([
            "analytic",
            "--drag",
            "power:k=2,n=0.25",
            "--lambda",
            "0.9",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["params"]["drag"], "power:n=0.25,k=2");
    for s in ["power:n=1e-7,k=3.5e200", "carreau:n=123.25,a=1e-3"] {
        assert_eq!(law(s).to_string(), s);
    }
    for s in ["power:n=0.25,k=2", "carreau:n=0.5,a=1", "tan"] {
        let d = law(s);
        assert_eq!(d.to_string(), s);
        assert_eq!(law(&d.to_string()), d);
        let p = Params::new(d, 0.5, 1.0, 0.0, 0.0).unwrap();
        let back: Params = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back, p);
    }
}

/// The exact sampler refuses a law whose v_u is far above Sigma (power
/// n = 0.1 at Sigma = 3: v_u = 3^10), where its time averages would lose
/// their precision (measured: <v²> 8 % off the FP solver's), naming --drag
/// and the methods that cover it; the FP solver answers.
#[test]
fn exact_sampler_refuses_imprecise_time_averages() {
    let (code, err) = irtp(&["simulate", "--drag", "power:n=0.1", "--particles", "100"]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--drag") && err.contains("Fokker-Planck"),
        "{err}"
    );
    let (code, err) = irtp(&[
        "fp",
        "stationary",
        "--drag",
        "power:n=0.1",
        "--cells",
        "2000",
    ]);
    assert_eq!(code, Some(0), "{err}");
}
