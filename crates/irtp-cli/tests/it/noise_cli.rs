//! `--noise` and `--temperature` (docs/equations.md, "Noise kinds"): the
//! paper's noise written as a spec is the same run bit for bit; a noise
//! that a method does not run is refused by name everywhere; `analytic`
//! runs the closed forms of the library.

use super::common::*;
use irtp::analytic::linear_noise::LinearNoise;
use irtp::analytic::telegraph_r0::TelegraphR0Density;
use irtp::model::noise::{NoiseModel, Telegraph};
use irtp::DragLaw;
use std::path::Path;

const RPT: &str = "rpt:sigma=1,alpha=1,beta=1";

/// Every command path (and method) with small budgets; each runs (exit 0)
/// without the noise flags (checked by hand when this list was written:
/// `irtp <command>` for each).
fn commands() -> Vec<Vec<&'static str>> {
    let mfpt = ["mfpt", "--v0", "0", "--vt", "0.5", "--rate", "1"];
    let search = ["mfpt", "--v0", "0", "--x0", "0", "--xt", "1", "--rate", "1", "--reset-position", "0"];
    let mut out: Vec<Vec<&str>> = vec![
        vec!["simulate", "--method", "exact", "--particles", "10", "--t-max", "1", "--burn-in", "0.5"],
        vec!["simulate", "--method", "euler", "--particles", "10", "--t-max", "1", "--burn-in", "0.5"],
        vec!["fp", "stationary", "--cells", "50"],
        vec!["fp", "transient", "--cells", "128", "--t-max", "1"],
        vec!["fp", "msd", "--cells", "50", "--t-max", "0.1"],
        vec!["mfpt", "scan", "--v0", "0", "--vt", "0.5", "--over", "rate", "--from", "0.5", "--to", "1", "--points", "2"],
        vec!["mfpt", "optimize", "--v0", "0", "--vt", "0.5"],
        vec!["mfpt", "distribution", "--v0", "0", "--vt", "0.5", "--rate", "1", "--method", "backward"],
        vec!["mfpt", "distribution", "--v0", "0", "--vt", "0.5", "--rate", "1", "--method", "exact", "--particles", "10"],
        vec!["analytic", "--drag", "tan"],
    ];
    for m in ["backward", "exact", "euler"] {
        out.push([&mfpt[..], &["--method", m, "--particles", "10"][..]].concat());
    }
    for m in ["backward", "exact"] {
        out.push([&search[..], &["--method", m, "--particles", "10"][..]].concat());
        let interval = ["mfpt", "--v0", "0", "--x0", "0", "--interval=-1,1", "--rate", "1", "--method", m];
        out.push([&interval[..], &["--particles", "10"][..]].concat());
    }
    out
}

/// `--particles` only where the method samples (the deterministic ones
/// refuse it): drop it from backward runs.
fn fit(cmd: &[&'static str]) -> Vec<&'static str> {
    let backward = cmd.contains(&"backward");
    let mut out = Vec::new();
    let mut skip = false;
    for a in cmd {
        if skip {
            skip = false;
            continue;
        }
        if backward && *a == "--particles" {
            skip = true;
            continue;
        }
        out.push(*a);
    }
    out
}

#[test]
fn every_command_refuses_a_noise_it_does_not_run() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, cmd) in commands().iter().enumerate() {
        let dir = tmp.path().join(format!("o{i}")).join("out");
        std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
        let d = dir.to_str().unwrap();
        for (extra, flag) in [
            (vec!["--noise", RPT], "--noise"),
            (vec!["--temperature", "0.5"], "--temperature"),
        ] {
            let args = [&fit(cmd)[..], &extra[..], &["--out", d][..]].concat();
            let out = irtp(&args);
            let err = assert_rejected(&out, flag, &dir);
            assert!(err.contains("run by: analytic"), "{args:?}: {err}");
        }
    }
}
