//! `irtp simulate --method exact` (the default): the same files, columns and
//! JSON keys as the Euler method.

use crate::common::{irtp, json, read_json};
use std::collections::BTreeSet;

fn run(method: Option<&str>, out: &std::path::Path) -> serde_json::Value {
    let mut args = vec![
        "simulate",
        "--particles",
        "200",
        "--t-max",
        "2",
        "--burn-in",
        "0.5",
        "--samples",
        "5",
        "--bins",
        "12",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ];
    if let Some(m) = method {
        args.extend(["--method", m]);
    }
    json(&irtp(&args))
}

fn keys(v: &serde_json::Value) -> BTreeSet<String> {
    v.as_object().unwrap().keys().cloned().collect()
}

#[test]
fn exact_is_default_with_euler_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let (de, dx) = (tmp.path().join("euler"), tmp.path().join("exact"));
    let je = run(Some("euler"), &de);
    let jx = run(None, &dx);
    assert_eq!(jx["method"], "exact");
    assert!(jx["dt"].is_null() && jx["event_sampling"].is_null() && jx["steps"].is_null());
    assert!(jx["events"].as_u64().unwrap() > 0 && je["events"].is_null());
    assert_eq!(keys(&je), keys(&jx));
    assert_eq!(jx["particles"], 200);
    assert!(jx["v2"].as_f64().unwrap() > 0.0);
    for f in ["moments.csv", "density.csv"] {
        let a = std::fs::read_to_string(de.join(f)).unwrap();
        let b = std::fs::read_to_string(dx.join(f)).unwrap();
        assert_eq!(a.lines().next(), b.lines().next(), "{f} header");
        assert_eq!(a.lines().count(), b.lines().count(), "{f} rows");
    }
    let re = read_json(&de.join("run.json"));
    let rx = read_json(&dx.join("run.json"));
    assert_eq!(rx["method"], "exact");
    assert_eq!(keys(&re), keys(&rx));
    assert_eq!(keys(&re["parameters"]), keys(&rx["parameters"]));
}

/// `irtp mfpt --method exact`: particle estimate through the exact sampler,
/// same report keys as euler except the time step.
#[test]
fn mfpt_method_exact() {
    let run = |m: &str| -> serde_json::Value {
        json(&irtp(&[
            "mfpt",
            "--v0",
            "-0.249",
            "--vt",
            "0.5",
            "--lambda",
            "0.9",
            "--rate",
            "2",
            "--particles",
            "400",
            "--json",
            "--method",
            m,
        ]))
    };
    let (x, e) = (run("exact"), run("euler"));
    assert_eq!(x["method"], "exact");
    assert!(x["tau"].as_f64().unwrap() > 0.0 && x["tau_err"].as_f64().unwrap() > 0.0);
    assert!(x.get("dt").is_none());
    let mut ke = keys(&e);
    ke.remove("dt");
    assert_eq!(keys(&x), ke);
}
