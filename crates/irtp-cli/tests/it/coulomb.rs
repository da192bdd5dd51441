//! Coulomb (solid) plus viscous friction, `coulomb:mu=MU,gamma=GAMMA`,
//! g(v) = mu sign(v) + gamma v, through every method.
//!
//! (a) At mu = 0, gamma = 1 it is the linear law: the Fokker-Planck density
//!     and <v²>, the backward MFPT, the r = 0 density and the exact
//!     sampler's seeded output agree with `linear` to 1e-10.
//! (b) r = 0: the density has the closed form
//!     P ∝ (Sigma² - g²)^(lambda/gamma - 1) (the general quadrature formula
//!     integrated on each side of v = 0); the library's r = 0 density and the
//!     Fokker-Planck bin masses are checked against it, and the regime label
//!     reads the cusp at v = 0 (a minimum for lambda < gamma, a maximum for
//!     lambda > gamma).
//! (c) r > 0: the exact sampler against the Fokker-Planck solver (<v²> and a
//!     histogram), the exact first-passage sampler against the backward
//!     equations, with v_r = 0 (v = 0 a node of both meshes) and v_r ≠ 0.
//! (d) Sigma <= mu (the particle sticks at v = 0) is refused by every
//!     command naming --sigma and mu; bad specs name the key; exit 2,
//!     nothing written.

use crate::common::stats::bonferroni_z;
use crate::common::{assert_rejected, irtp};
use irtp::analytic::r0::R0Density;
use irtp::fp::{stationary, Stationary, StationaryOptions};
use irtp::mfpt::{backward, solve, BackwardOptions, Method, ParticleOptions, Problem};
use irtp::model::{Drag, DragLaw};
use irtp::parallel::NoProgress;
use irtp::sim::{exact, SimSpec, TimeGrid};
use irtp::Params;

fn law(spec: &str) -> DragLaw {
    spec.parse().unwrap()
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

/// (a) mu = 0, gamma = 1 is the linear law: FP density (every cell) and
/// <v²> at r = 0 and 2, backward tau, r = 0 density (pdf and <v²>) to
/// 1e-10. The law reaches the solvers through g, g', g⁻¹, the drift near
/// the edges and its closed-form flow, which agree with linear to rounding.
#[test]
fn zero_friction_equals_linear() {
    let d = law("coulomb:mu=0");
    let lin = |l: DragLaw, r: f64| Params::new(l, 1.3, 0.7, r, 0.2).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-10 * a.abs().max(1e-3);
    for r in [0.0, 2.0] {
        let (a, b) = (lin(DragLaw::Linear, r), lin(d, r));
        let o = opts(4000);
        let (fa, fb) = (stationary(&a, &o).unwrap(), stationary(&b, &o).unwrap());
        assert!(close(fa.v2, fb.v2), "r={r}: {} vs {}", fa.v2, fb.v2);
        for (pa, pb) in fa.p.iter().zip(&fb.p) {
            assert!(close(*pa, *pb), "r={r} density");
        }
    }
    let (pa, pb) = (lin(DragLaw::Linear, 2.0), lin(d, 2.0));
    let bo = BackwardOptions::default();
    let ta = backward::solve(&Problem::new(pa, -0.249, 0.5).unwrap(), &bo).unwrap();
    let tb = backward::solve(&Problem::new(pb, -0.249, 0.5).unwrap(), &bo).unwrap();
    assert!(close(ta.tau, tb.tau), "tau {} vs {}", ta.tau, tb.tau);
    let ra = R0Density::from_params(&lin(DragLaw::Linear, 0.0)).unwrap();
    let rb = R0Density::by_quadrature(d, 1.3, 0.7).unwrap();
    assert!(
        close(ra.v2(), rb.v2()),
        "r0 <v²> {} vs {}",
        ra.v2(),
        rb.v2()
    );
    for i in 1..40 {
        let v = -1.3 + 2.6 * i as f64 / 40.0;
        assert!(close(ra.pdf(v), rb.pdf(v)), "r0 pdf at {v}");
    }
}

/// (a) The exact sampler at mu = 0 against linear, same seed: the same
/// events, and every recorded moment and time average to 1e-10 relative.
#[test]
fn zero_friction_exact_sampler_equals_linear() {
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
    let (a, b) = (run(DragLaw::Linear), run(law("coulomb:mu=0,gamma=1")));
    assert_eq!(a.steps, b.steps, "events");
    let pairs = a.v2.iter().zip(&b.v2).chain(a.x2.iter().zip(&b.x2));
    for (x, y) in pairs.chain([(&a.v2_time_avg, &b.v2_time_avg)]) {
        let (x, y) = (x.mean(), y.mean());
        assert!((x - y).abs() <= 1e-10 * x.abs().max(1e-6), "{x} vs {y}");
    }
}

/// The closed-form r = 0 density, unnormalised: (Sigma² - g²)^(lambda/gamma - 1)
/// with g = mu + gamma |v| (the quadrature formula integrated on each side
/// of v = 0: ∫ g/(Sigma² - g²) dv = -ln(Sigma² - g²)/(2 gamma)).
fn r0_closed(mu: f64, gamma: f64, sigma: f64, lambda: f64, v: f64) -> f64 {
    let g = mu + gamma * v.abs();
    ((sigma - g) * (sigma + g)).powf(lambda / gamma - 1.0)
}

/// Bin masses of the closed form on `bins` equal bins of (v_l, v_u) and
/// <v²>, by composite Simpson in t = (v/v_u)^... on each half (quadratic
/// grading into v_u, where P ~ (v_u - v)^a with a > 0 here).
fn r0_bins(mu: f64, gamma: f64, sigma: f64, lambda: f64, bins: usize) -> (Vec<f64>, f64) {
    const PANELS: usize = 4000;
    let vu = (sigma - mu) / gamma;
    let half = bins / 2;
    let p = |v: f64| r0_closed(mu, gamma, sigma, lambda, v);
    let (mut mass, mut v2) = (vec![0.0; half], 0.0);
    for (j, m) in mass.iter_mut().enumerate() {
        let (e0, e1) = (
            vu * j as f64 / half as f64,
            vu * (j + 1) as f64 / half as f64,
        );
        for i in 0..PANELS {
            let at = |t: f64| e1 - (e1 - e0) * (1.0 - t) * (1.0 - t);
            let (xa, xb) = (
                at(i as f64 / PANELS as f64),
                at((i + 1) as f64 / PANELS as f64),
            );
            let xm = 0.5 * (xa + xb);
            let (pa, pm, pb) = (p(xa), p(xm), p(xb));
            *m += (xb - xa) / 6.0 * (pa + 4.0 * pm + pb);
            v2 += (xb - xa) / 6.0 * (xa * xa * pa + 4.0 * xm * xm * pm + xb * xb * pb);
        }
    }
    let z = 2.0 * mass.iter().sum::<f64>();
    let out = mass
        .iter()
        .rev()
        .chain(mass.iter())
        .map(|m| m / z)
        .collect();
    (out, 2.0 * v2 / z)
}

/// (b) r = 0: the library's r = 0 density (pdf on a grid on both sides of
/// the cusp, <v²>) against the closed form to 1e-8, for an edge exponent
/// a = lambda/gamma - 1 of either sign; the FP bin masses (16 bins, a > 0)
/// and <v²> within their own mesh error estimate (twice the change from
/// 2000 to 4000 cells, + 1e-9; <v²>: the extrapolation's change + 1e-9).
#[test]
fn r0_density_matches_closed_form() {
    for (mu, gamma, sigma, lambda) in [(0.5, 1.0, 2.0, 2.5), (1.0, 2.0, 3.0, 1.0)] {
        let d = law(&format!("coulomb:mu={mu},gamma={gamma}"));
        let vu = d.inverse(sigma);
        let lib = R0Density::by_quadrature(d, sigma, lambda).unwrap();
        let p0 = r0_closed(mu, gamma, sigma, lambda, 0.0);
        for i in 1..40 {
            let v = -vu + 2.0 * vu * i as f64 / 40.0;
            let want = r0_closed(mu, gamma, sigma, lambda, v) / p0;
            let got = lib.pdf(v) / lib.pdf(0.0);
            assert!(
                (got - want).abs() <= 1e-8 * want,
                "mu={mu} v={v}: {got} vs {want}"
            );
        }
        if lambda / gamma - 1.0 <= 0.0 {
            continue;
        }
        let (bins, v2) = r0_bins(mu, gamma, sigma, lambda, 16);
        assert!((lib.v2() - v2).abs() <= 1e-8 * v2, "{} vs {v2}", lib.v2());
        let p = Params::new(d, sigma, lambda, 0.0, 0.0).unwrap();
        let (fine, coarse) = (
            stationary(&p, &opts(4000)).unwrap(),
            stationary(&p, &opts(2000)).unwrap(),
        );
        let edges: Vec<f64> = (0..=16).map(|i| -vu + 2.0 * vu * i as f64 / 16.0).collect();
        let (mf, mc) = (fp_bin_mass(&fine, &edges), fp_bin_mass(&coarse, &edges));
        for j in 0..16 {
            let tol = 2.0 * (mf[j] - mc[j]).abs() + 1e-9;
            assert!(
                (mf[j] - bins[j]).abs() <= tol,
                "bin {j}: {} vs {}",
                mf[j],
                bins[j]
            );
        }
        let tol = (fine.v2 - fine.fine.v2).abs() + 1e-9;
        eprintln!(
            "coulomb r=0: FP <v²> {} closed form {v2} (tol {tol:e})",
            fine.v2
        );
        assert!((fine.v2 - v2).abs() <= tol, "<v²>");
    }
}

/// (b) The regime of the r = 0 density reads the cusp at v = 0 from the
/// sign of gamma - lambda: a minimum below, a maximum above, flat (the
/// uniform density) at lambda = gamma.
#[test]
fn r0_regime_reads_the_cusp() {
    let d = law("coulomb:mu=0.5,gamma=1");
    for (lambda, centre) in [(0.5, "minimum"), (2.0, "maximum"), (1.0, "flat")] {
        let lib = R0Density::by_quadrature(d, 2.0, lambda).unwrap();
        let label = lib.regime().label.clone();
        assert!(label.contains(centre), "lambda={lambda}: {label}");
    }
    let lib = R0Density::by_quadrature(d, 2.0, 1.0).unwrap();
    for v in [-1.2, -0.3, 0.4, 1.1] {
        assert!((lib.pdf(v) / lib.pdf(0.0) - 1.0).abs() < 1e-10);
    }
}

/// The cases of the r > 0 cross-method checks: (spec, Sigma, lambda, v_r).
const CASES: [(&str, f64, f64, f64); 2] = [
    ("coulomb:mu=0.5,gamma=1", 2.0, 0.5, 0.0),
    ("coulomb:mu=1,gamma=2", 3.0, 1.0, 0.3),
];

/// (c) r = 2: the exact sampler's time-averaged <v²> and its 20-bin
/// histogram against the FP solver: 2 cases × 21 comparisons, Bonferroni;
/// the FP error estimate added in quadrature.
#[test]
fn exact_sampler_matches_fokker_planck() {
    let zmax = bonferroni_z(CASES.len() * 21);
    let spec = SimSpec::new(
        4000,
        TimeGrid::from_times(vec![0.0, 40.0]).unwrap(),
        10.0,
        20,
        2026,
    )
    .unwrap();
    for (s, sigma, lambda, vr) in CASES {
        let p = Params::new(law(s), sigma, lambda, 2.0, vr).unwrap();
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
        let mut worst = 0.0f64;
        for (acc, q) in o.density_time.iter().zip(&mass) {
            assert!(acc.sem() > 0.0, "{s}: unvisited bin");
            worst = worst.max(((acc.mean() - q / w) / acc.sem()).abs());
        }
        eprintln!("{s} r=2: histogram max |z| {worst:.2} (bound {zmax:.2})");
        assert!(worst < zmax, "{s}: histogram max |z| = {worst}");
    }
}

/// (c) The exact first-passage sampler's MFPT against the backward
/// equations, across v = 0 (v_0 < 0 < v_t): 2 comparisons, Bonferroni, the
/// backward error estimate added in quadrature.
#[test]
fn exact_mfpt_matches_backward_equations() {
    let zmax = bonferroni_z(CASES.len());
    for (i, (s, sigma, lambda, vr)) in CASES.into_iter().enumerate() {
        let p = Params::new(law(s), sigma, lambda, 2.0, vr).unwrap();
        let prob = Problem::new(p, -0.249, 0.5).unwrap();
        let ode = backward::solve(&prob, &BackwardOptions::default()).unwrap();
        let run = ParticleOptions {
            particles: 10_000,
            t_max: f64::INFINITY,
            seed: 400 + i as u64,
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

/// (d) Sigma <= mu: every command refuses, naming --sigma and mu (the
/// particle sticks at v = 0), exit 2, nothing written.
#[test]
fn sticking_is_refused_by_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    let drag = ["--drag", "coulomb:mu=0.5,gamma=1"];
    let scan = "mfpt scan --v0 0 --vt 0.01 --over rate --from 0.1 --to 1 --points 3";
    let scan: Vec<&str> = scan.split(' ').collect();
    let commands: [&[&str]; 10] = [
        &["simulate", "--particles", "100"],
        &["simulate", "--method", "euler", "--particles", "100"],
        &["analytic", "--rate", "0"],
        &["fp", "stationary"],
        &["fp", "transient", "--t-max", "1"],
        &["fp", "msd"],
        &["mfpt", "--v0", "0", "--vt", "0.01"],
        &scan,
        &["mfpt", "distribution", "--v0", "0", "--vt", "0.01"],
        &["mfpt", "optimize", "--v0", "0", "--vt", "0.01"],
    ];
    for sigma in ["0.5", "0.3"] {
        for cmd in commands {
            let args = [cmd, &drag[..], &["--sigma", sigma, "--out", out_s]].concat();
            let err = assert_rejected(&irtp(&args), "--sigma", &out);
            assert!(
                err.contains("mu = 0.5") && err.contains("sticks"),
                "{args:?}: {err}"
            );
        }
    }
}

/// (d) Bad specs: exit 2, one line naming --drag and the key, nothing
/// written.
#[test]
fn bad_specs_are_refused_naming_the_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    for (spec, needle) in [
        ("coulomb:mu=-0.1", "mu >= 0"),
        ("coulomb:mu=NaN", "mu >= 0"),
        ("coulomb:mu=inf", "mu >= 0"),
        ("coulomb:mu=0.5,gamma=0", "gamma > 0"),
        ("coulomb:mu=0.5,gamma=-1", "gamma > 0"),
        ("coulomb:mu=0.5,gamma=nan", "gamma > 0"),
        ("coulomb", "a value for mu"),
        ("coulomb:mu=0.5,k=1", "unknown key 'k'"),
    ] {
        for cmd in [&["analytic"][..], &["fp", "stationary"][..]] {
            let args = [cmd, &["--drag", spec, "--out", out_s]].concat();
            let o = irtp(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
            assert!(
                err.contains("--drag") && err.contains(needle),
                "{args:?}: {err}"
            );
            assert!(!out.exists(), "{args:?} wrote {out:?}");
        }
    }
    assert_eq!(
        law("coulomb:gamma=2,mu=0.25").to_string(),
        "coulomb:mu=0.25,gamma=2"
    );
}

/// The Euler scheme's step limit is the steepest secant to the edge,
/// gamma + 2 mu/v_u (just left of the jump): a step just below it keeps
/// every velocity of a fine grid inside (v_l, v_u), one 1 % above throws
/// some out and is refused naming --dt. With dt = 2e-3 its <v²> at r = 2
/// agrees with the FP solver within 4 standard errors (the drift jump
/// costs an O(dt) bias, measured -0.0009 ± 0.0005 at dt = 4e-3).
#[test]
fn euler_step_limit_and_fokker_planck() {
    let p = Params::new(law("coulomb:mu=0.5,gamma=1"), 2.0, 0.5, 2.0, 0.0).unwrap();
    let (d, vu) = (p.drag(), p.v_upper());
    let max = p.max_euler_dt();
    assert!((max - 1.0 / (1.0 + 2.0 * 0.5 / 1.5)).abs() < 1e-12, "{max}");
    let escapes = |dt: f64| {
        (1..200_000)
            .map(|i| -vu + 2.0 * vu * i as f64 / 200_000.0)
            .filter(|v| v + dt * (2.0 - d.force(*v)) >= vu)
            .count()
    };
    assert_eq!(escapes(max * (1.0 - 1e-9)), 0);
    assert!(escapes(1.01 * max) > 0, "the bound is not sharp");
    let e = p.check_dt(1.01 * max).unwrap_err().to_string();
    assert!(e.contains("dt"), "{e}");
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
    eprintln!("coulomb r=2: Euler <v²> {m} ± {se}, FP {}", fp.v2);
    assert!(((m - fp.v2) / se).abs() < 4.0, "{m} ± {se} vs {}", fp.v2);
}

/// (c) In time, from v(0) = v_r = 0: the Fokker-Planck moment chain's
/// <x²>(t) and <v²>(t) (`fp msd`, x-weighted densities on the forward
/// operator) against the exact sampler at t = 1, 4, 10: 6 comparisons,
/// Bonferroni. A coarse chain (200 and 400 cells, rtol 1e-8; its error,
/// ~3e-5 relative, is far below the standard errors of ~0.5 %) keeps the
/// test short.
#[test]
fn position_moments_match_exact_sampler() {
    let p = Params::new(law("coulomb:mu=0.5,gamma=1"), 2.0, 0.5, 2.0, 0.0).unwrap();
    let times = vec![1.0, 4.0, 10.0];
    let o = irtp::fp::MsdOptions {
        cells: 200,
        levels: 2,
        rtol: 1e-8,
        times: times.clone(),
        ..irtp::fp::MsdOptions::default()
    };
    let fp = irtp::fp::msd(&p, &o, &NoProgress).unwrap();
    let grid = [vec![0.0], times.clone()].concat();
    let spec = SimSpec::new(40_000, TimeGrid::from_times(grid).unwrap(), 0.0, 20, 17).unwrap();
    let ex = exact::simulate(&p, &spec, &NoProgress).unwrap();
    let zmax = bonferroni_z(2 * times.len());
    for (k, t) in times.iter().enumerate() {
        let (x2, v2) = (&ex.x2[k + 1], &ex.v2[k + 1]);
        let zx = (x2.mean() - fp.x2[k]) / x2.sem();
        let zv = (v2.mean() - fp.v2[k]) / v2.sem();
        eprintln!(
            "t={t}: <x²> exact {} ± {} FP {} (z {zx:.2}); <v²> exact {} ± {} FP {} (z {zv:.2})",
            x2.mean(),
            x2.sem(),
            fp.x2[k],
            v2.mean(),
            v2.sem(),
            fp.v2[k]
        );
        assert!(zx.abs() < zmax && zv.abs() < zmax, "t={t}: z {zx} {zv}");
    }
}
