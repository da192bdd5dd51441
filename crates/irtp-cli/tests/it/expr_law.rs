//! The expression law `expr:...` through every method.
//!
//! (a) Twins: `expr:tan(v)` equals `tan`, `expr:v` equals `linear` and
//!     `expr:v + v^3/3` equals `cubic` to 1e-9 relative in the Fokker-Planck
//!     <v²> and density, the backward MFPT, the r = 0 density and the exact
//!     sampler's seeded output (the event times and flips are drawn from the
//!     same streams whatever the law; the flows agree to ~1e-14).
//! (b) A law with no built-in twin (`expr:sinh(v)`): the exact sampler's
//!     time-averaged <v²> against the Fokker-Planck solver (4 standard
//!     errors), the Euler step bound against the largest secant.
//! (c) Bad expressions and bounded laws: exit 2, one line naming `--drag`
//!     (or `--sigma`) and the violation, nothing written.
//! (d) The canonical spec in provenance files and serde round trips.

use irtp::analytic::r0::R0Density;
use irtp::fp::{stationary, StationaryOptions};
use irtp::mfpt::{backward, BackwardOptions, Problem};
use irtp::model::{Drag, DragLaw};
use irtp::parallel::NoProgress;
use irtp::sim::{exact, SimSpec, TimeGrid};
use irtp::Params;
use std::process::Command;

fn law(spec: &str) -> DragLaw {
    spec.parse().unwrap()
}

/// (expression, built-in twin, Sigma, lambda).
const TWINS: [(&str, DragLaw, f64, f64); 3] = [
    ("expr:tan(v)", DragLaw::Tan, 3.0, 0.9),
    ("expr:v", DragLaw::Linear, 1.3, 0.7),
    ("expr:v + v^3/3", DragLaw::Cubic, 3.0, 0.9),
];

fn close(a: f64, b: f64, floor: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(floor)
}

/// (a) Fokker-Planck (<v²> and every cell, r = 2 and r = 0), backward
/// tau, the r = 0 density (<v²> and the pdf on a grid).
#[test]
fn twins_agree_in_every_solver() {
    for (spec, twin, sigma, lambda) in TWINS {
        let e = law(spec);
        let par = |d: DragLaw, r: f64| Params::new(d, sigma, lambda, r, 0.0).unwrap();
        for r in [0.0, 2.0] {
            let o = StationaryOptions {
                cells: 4000,
                ..StationaryOptions::default()
            };
            let (fa, fb) = (
                stationary(&par(twin, r), &o).unwrap(),
                stationary(&par(e, r), &o).unwrap(),
            );
            assert!(
                close(fa.v2, fb.v2, 1e-3),
                "{spec} r={r}: {} vs {}",
                fa.v2,
                fb.v2
            );
            for (pa, pb) in fa.p.iter().zip(&fb.p) {
                assert!(close(*pa, *pb, 1e-3), "{spec} r={r}: density {pa} vs {pb}");
            }
        }
        let bo = BackwardOptions::default();
        let tau = |d: DragLaw| {
            let prob = Problem::new(par(d, 2.0), -0.249, 0.5).unwrap();
            backward::solve(&prob, &bo).unwrap().tau
        };
        let (ta, tb) = (tau(twin), tau(e));
        assert!(close(ta, tb, 1e-3), "{spec}: tau {ta} vs {tb}");
        let ra = R0Density::from_params(&par(twin, 0.0)).unwrap();
        let rb = R0Density::from_params(&par(e, 0.0)).unwrap();
        assert!(close(ra.v2(), rb.v2(), 1e-3), "{spec}: r0 <v²>");
        let vu = twin.inverse(sigma);
        for i in 1..40 {
            let v = -vu + 2.0 * vu * i as f64 / 40.0;
            assert!(close(ra.pdf(v), rb.pdf(v), 1e-3), "{spec}: r0 pdf at {v}");
        }
        eprintln!(
            "{spec}: FP, tau {ta} vs {tb}, r0 <v²> {} vs {}",
            ra.v2(),
            rb.v2()
        );
    }
}

/// (a) The exact sampler, same seed: the same number of events and every
/// recorded moment and time average to 1e-9 relative.
#[test]
fn twins_agree_in_the_exact_sampler() {
    let spec = SimSpec::new(
        2000,
        TimeGrid::from_times(vec![0.0, 1.0, 5.0, 20.0]).unwrap(),
        5.0,
        20,
        7,
    )
    .unwrap();
    for (s, twin, sigma, lambda) in TWINS {
        let run = |d: DragLaw| {
            let p = Params::new(d, sigma, lambda, 2.0, 0.2).unwrap();
            exact::simulate(&p, &spec, &NoProgress).unwrap()
        };
        let (a, b) = (run(twin), run(law(s)));
        assert_eq!(a.steps, b.steps, "{s}: events");
        let pairs = a.v2.iter().zip(&b.v2).chain(a.x2.iter().zip(&b.x2));
        for (x, y) in pairs.chain([(&a.v2_time_avg, &b.v2_time_avg)]) {
            let (x, y) = (x.mean(), y.mean());
            assert!(close(x, y, 1e-6), "{s}: {x} vs {y}");
        }
    }
}

/// (b) `expr:sinh(v)`, Sigma = 3, lambda = 0.5, r = 2: the exact sampler's
/// time-averaged <v²> against the FP solver, one comparison at 4 standard
/// errors (the FP error estimate added in quadrature).
#[test]
fn exact_sampler_matches_fokker_planck_without_a_twin() {
    let p = Params::new(law("expr:sinh(v)"), 3.0, 0.5, 2.0, 0.0).unwrap();
    let fp = stationary(&p, &StationaryOptions::default()).unwrap();
    let spec = SimSpec::new(
        4000,
        TimeGrid::from_times(vec![0.0, 40.0]).unwrap(),
        10.0,
        20,
        2026,
    )
    .unwrap();
    let o = exact::simulate(&p, &spec, &NoProgress).unwrap();
    let (m, se) = (o.v2_time_avg.mean(), o.v2_time_avg.sem());
    let se = se.hypot(fp.v2 - fp.fine.v2);
    eprintln!("expr:sinh(v) r=2: exact <v²> {m} ± {se}, FP {}", fp.v2);
    assert!(((m - fp.v2) / se).abs() < 4.0, "{m} ± {se} vs {}", fp.v2);
}

/// (b) The Euler step bound is the steepest secant to the edge: a step
/// just below it keeps every velocity of a fine grid inside (v_l, v_u), one
/// 2 % above it does not (the bound carries a 1 % margin).
#[test]
fn euler_step_bound_is_the_steepest_secant() {
    for (spec, sigma) in [("expr:sinh(v)", 3.0), ("expr:v - v^3/3", 0.6)] {
        let p = Params::new(law(spec), sigma, 0.5, 2.0, 0.0).unwrap();
        let (d, vu, max) = (p.drag(), p.v_upper(), p.max_euler_dt());
        let escapes = |dt: f64| {
            (1..200_000)
                .map(|i| -vu + 2.0 * vu * i as f64 / 200_000.0)
                .filter(|v| v + dt * (sigma - d.force(*v)) >= vu)
                .count()
        };
        assert_eq!(escapes(max * (1.0 - 1e-9)), 0, "{spec}");
        assert!(escapes(1.02 * max) > 0, "{spec}: the bound is not sharp");
    }
}

fn irtp(args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// (c) Every bad expression and a Sigma a bounded law never reaches.
#[test]
fn bad_expressions_are_refused_naming_the_violation() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    let cases = [
        ("expr:v^2", "3", "--drag", "not odd"),
        ("expr:v + v^2", "3", "--drag", "not odd"),
        ("expr:v - v^3", "3", "--drag", "g' <= 0 at v = 0.57"),
        ("expr:v +", "3", "--drag", "parse error"),
        ("expr:(v", "3", "--drag", "parse error"),
        ("expr:foo(v)", "3", "--drag", "unknown name 'foo'"),
        ("expr:v + w", "3", "--drag", "unknown name 'w'"),
        ("expr:abs(v)", "3", "--drag", "unknown name 'abs'"),
        ("expr:2", "3", "--drag", "depend on v"),
        ("expr:", "3", "--drag", "empty"),
        ("expr", "3", "--drag", "an expression in v"),
        ("expr:ln(v)", "3", "--drag", "not odd"),
        ("expr:tanh(v)", "3", "--sigma", "supremum"),
        ("expr:atan(v)", "2", "--sigma", "1.57"),
    ];
    for (spec, sigma, flag, needle) in cases {
        for cmd in [&["analytic"][..], &["fp", "stationary"][..]] {
            let args = [cmd, &["--drag", spec, "--sigma", sigma, "--out", out_s]].concat();
            let (code, _, err) = irtp(&args);
            assert_eq!(code, Some(2), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
            assert!(
                err.contains(flag) && err.contains(needle),
                "{args:?}: {err}"
            );
            assert!(!out.exists(), "{args:?} wrote {out:?}");
        }
    }
    // The same non-monotone law is valid where Sigma keeps it increasing.
    let (code, _, err) = irtp(&[
        "fp",
        "stationary",
        "--drag",
        "expr:v - v^3",
        "--sigma",
        "0.2",
    ]);
    assert_eq!(code, Some(0), "{err}");
}

/// (d) The provenance records the canonical spec (whitespace runs
/// collapsed), which parses back to the same law; Params round-trip
/// through serde.
#[test]
fn canonical_spec_in_provenance() {
    let (code, stdout, err) = irtp(&[
        "fp",
        "stationary",
        "--drag",
        "expr:  v +   0.3*v^3 ",
        "--json",
        "--cells",
        "500",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(json["params"]["model"]["drag"], "expr:v + 0.3*v^3");
    let d = law("expr:v + 0.3*v^3");
    assert_eq!(d.to_string(), "expr:v + 0.3*v^3");
    assert_eq!(law(&d.to_string()), d);
    assert_eq!(law("expr:v+0.3*v^3").to_string(), "expr:v+0.3*v^3");
    let p = Params::new(d, 2.0, 1.0, 1.0, 0.1).unwrap();
    let back: Params = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
    assert_eq!(back, p);
}
