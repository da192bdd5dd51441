//! `--drag` specs as a user writes them, for every law with parameters
//! (the cross-method checks of the laws themselves are the core's
//! conformance suite, `crates/irtp/tests/it/conformance.rs`).
//!
//! (a) Bad specs and a Sigma a law never reaches: exit 2, one line naming
//!     `--drag` (or `--sigma`) and the violated rule, nothing written.
//! (b) Coulomb friction with Sigma <= mu (the particle sticks at v = 0) is
//!     refused by every command.
//! (c) The exact sampler refuses a law whose time averages would lose
//!     their precision, naming the methods that cover it.
//! (d) Provenance records the canonical spec, which parses back to the
//!     same law; Params round-trip through serde.

use crate::common::{assert_rejected, assert_success, irtp, json, summary};
use irtp::model::DragLaw;
use irtp::Params;

fn law(spec: &str) -> DragLaw {
    spec.parse().unwrap()
}

/// (spec, --sigma, the flag named, a phrase of the message).
const BAD: [(&str, &str, &str, &str); 41] = [
    ("power:n=0", "3", "--drag", "n > 0"),
    ("power:n=-1", "3", "--drag", "n > 0"),
    ("power:n=NaN", "3", "--drag", "n > 0"),
    ("power:n=inf", "3", "--drag", "n > 0"),
    ("power:n=0.5,k=0", "3", "--drag", "k > 0"),
    ("power:n=0.5,k=-1", "3", "--drag", "k > 0"),
    ("power:n=0.5,k=nan", "3", "--drag", "k > 0"),
    ("carreau:n=0", "3", "--drag", "n > 0"),
    ("carreau:n=0.5,a=0", "3", "--drag", "a > 0"),
    ("carreau:n=0.5,a=-inf", "3", "--drag", "a > 0"),
    ("power:n=0.5,q=1", "3", "--drag", "unknown key 'q'"),
    ("power:k=1", "3", "--drag", "a value for n"),
    ("power", "3", "--drag", "a value for n"),
    ("power:n", "3", "--drag", "key=value"),
    ("power:n=abc", "3", "--drag", "a number for n"),
    ("power:n=1,n=2", "3", "--drag", "'n' repeated"),
    ("carreau:n=1,k=1", "3", "--drag", "unknown key 'k'"),
    ("tan:n=1", "3", "--drag", "no parameters"),
    ("powr:n=1", "3", "--drag", "one of tan"),
    ("coulomb:mu=-0.1", "3", "--drag", "mu >= 0"),
    ("coulomb:mu=NaN", "3", "--drag", "mu >= 0"),
    ("coulomb:mu=inf", "3", "--drag", "mu >= 0"),
    ("coulomb:mu=0.5,gamma=0", "3", "--drag", "gamma > 0"),
    ("coulomb:mu=0.5,gamma=-1", "3", "--drag", "gamma > 0"),
    ("coulomb:mu=0.5,gamma=nan", "3", "--drag", "gamma > 0"),
    ("coulomb", "3", "--drag", "a value for mu"),
    ("coulomb:mu=0.5,k=1", "3", "--drag", "unknown key 'k'"),
    ("expr:v^2", "3", "--drag", "not odd"),
    ("expr:v + v^2", "3", "--drag", "not odd"),
    ("expr:v - v^3", "3", "--drag", "g' < 0 at v = 0.57"),
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

/// (a) Every bad spec, through a command that only reads the law
/// (`analytic`) and one that solves with it (`fp stationary`).
#[test]
fn bad_specs_are_refused_naming_the_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    for (spec, sigma, flag, needle) in BAD {
        for cmd in [&["analytic"][..], &["fp", "stationary"][..]] {
            let args = [cmd, &["--drag", spec, "--sigma", sigma, "--out", out_s]].concat();
            let o = irtp(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
            assert!(
                err.contains(flag) && err.contains(needle),
                "{args:?}: {err}"
            );
            assert!(!out.exists(), "{args:?} wrote {out:?}");
        }
    }
    // The same non-monotone law is valid where Sigma keeps it increasing.
    assert_success(&irtp(&[
        "fp",
        "stationary",
        "--drag",
        "expr:v - v^3",
        "--sigma",
        "0.2",
    ]));
}

/// (b) Sigma <= mu: every command refuses, naming --sigma and mu (the
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

/// (c) The exact sampler refuses a law whose v_u is far above Sigma (power
/// n = 0.1 at Sigma = 3: v_u = 3^10), where its time averages would lose
/// their precision (measured: <v²> 8 % off the FP solver's), naming --drag
/// and the methods that cover it; the FP solver answers.
#[test]
fn exact_sampler_refuses_imprecise_time_averages() {
    let o = irtp(&["simulate", "--drag", "power:n=0.1", "--particles", "100"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--drag") && err.contains("Fokker-Planck"),
        "{err}"
    );
    assert_success(&irtp(&[
        "fp",
        "stationary",
        "--drag",
        "power:n=0.1",
        "--cells",
        "2000",
    ]));
}

/// (d) The spec written to provenance is canonical (every key in the
/// law's order, shortest round-trip numbers, expression whitespace runs
/// collapsed) and parses back to the same law.
#[test]
fn specs_round_trip_through_provenance() {
    let s = summary(&irtp(&[
        "analytic",
        "--drag",
        "power:k=2,n=0.25",
        "--lambda",
        "0.9",
        "--json",
    ]));
    assert_eq!(s["params"]["drag"], "power:n=0.25,k=2");
    let o = irtp(&[
        "fp",
        "stationary",
        "--drag",
        "expr:  v +   0.3*v^3 ",
        "--json",
        "--cells",
        "500",
    ]);
    let s = summary(&o);
    assert!(json(&o).is_object());
    assert_eq!(s["params"]["model"]["drag"], "expr:v + 0.3*v^3");
    assert_eq!(law("expr:v+0.3*v^3").to_string(), "expr:v+0.3*v^3");
    assert_eq!(
        law("coulomb:gamma=2,mu=0.25").to_string(),
        "coulomb:mu=0.25,gamma=2"
    );
    for s in ["power:n=1e-7,k=3.5e200", "carreau:n=123.25,a=1e-3"] {
        assert_eq!(law(s).to_string(), s);
    }
    for d in DragLaw::examples() {
        let spec = d.to_string();
        assert_eq!(law(&spec), d, "{spec}");
        // Sigma inside every law's range (tanh: < 1; Coulomb's example: > mu).
        let sigma = if d == DragLaw::Tanh { 0.6 } else { 2.0 };
        let p = Params::new(d, sigma, 1.0, 1.0, 0.1).unwrap();
        let back: Params = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back, p, "{spec}");
    }
}
