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
    let search = [
        "mfpt",
        "--v0",
        "0",
        "--x0",
        "0",
        "--xt",
        "1",
        "--rate",
        "1",
        "--reset-position",
        "0",
    ];
    let mut out: Vec<Vec<&str>> = vec![
        // simulate (noise_exact_cli.rs, noise_euler_cli.rs), fp
        // (noise_fp_cli.rs), mfpt scan / optimize, `mfpt --method
        // backward` and `mfpt distribution --method backward`
        // (noise_backward_cli.rs), `mfpt --method euler` and `mfpt
        // --method exact` at temperature 0 (noise_fpt_exact_cli.rs) and
        // `mfpt distribution --method exact` (noise_fpt_dist_exact_cli.rs)
        // run noise models; the latter still refuses thermal noise.
        vec![
            "mfpt",
            "distribution",
            "--v0",
            "0",
            "--vt",
            "0.5",
            "--rate",
            "1",
            "--method",
            "exact",
            "--particles",
            "10",
        ],
        vec!["analytic", "--drag", "tan"],
    ];
    for m in ["backward", "exact"] {
        out.push([&search[..], &["--method", m, "--particles", "10"][..]].concat());
        let interval = [
            "mfpt",
            "--v0",
            "0",
            "--x0",
            "0",
            "--interval=-1,1",
            "--rate",
            "1",
            "--method",
            m,
        ];
        out.push([&interval[..], &["--particles", "10"][..]].concat());
    }
    out.push([&search[..], &["--method", "renewal"][..]].concat());
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

/// `mfpt --method exact` runs every finite-state noise at temperature 0
/// but no thermal noise: refused with `--temperature` only.
fn thermal_refused() -> Vec<Vec<&'static str>> {
    let mfpt = ["mfpt", "--v0", "0", "--vt", "0.5", "--rate", "1"];
    vec![[&mfpt[..], &["--method", "exact", "--particles", "10"][..]].concat()]
}

/// The search with run-pause-tumble noise runs by `--method exact` and
/// `--method euler` (exit 0, a finite tau with a standard error), the
/// default method (backward) and `--method renewal` (a finite tau with an
/// error estimate, the per-state values listed).
#[test]
fn a_search_with_a_noise_model_runs_by_the_samplers() {
    let base = [
        "mfpt",
        "--xt",
        "1",
        "--v0",
        "0",
        "--reset-position",
        "0",
        "--drag",
        "linear",
        "--noise",
        "rpt:sigma=1,alpha=1,beta=2",
        "--rate",
        "0.5",
    ];
    for m in ["exact", "euler"] {
        let extra = [
            "--method",
            m,
            "--particles",
            "2000",
            "--dt",
            "0.01",
            "--json",
        ];
        let extra = if m == "exact" {
            [&extra[..4], &extra[6..]].concat()
        } else {
            extra.to_vec()
        };
        let r = json(&irtp(&[&base[..], &extra[..]].concat()));
        let (tau, err) = (r["tau"].as_f64().unwrap(), r["tau_err"].as_f64().unwrap());
        assert!(
            tau.is_finite() && tau > 1.0 && err > 0.0 && err < 0.1 * tau,
            "{m}: {r}"
        );
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let r = json(&irtp(&[&base[..], &["--json"]].concat()));
    let (tau, err) = (
        r["tau"].as_f64().unwrap(),
        r["error_estimate"].as_f64().unwrap(),
    );
    assert!(tau > 1.0 && err > 0.0 && err < 0.1 * tau, "backward: {r}");
    let renewal = [
        "--method",
        "renewal",
        "--cells-x",
        "16",
        "--cells-v",
        "8",
        "--time-steps",
        "40",
        "--out",
        dir.to_str().unwrap(),
        "--json",
    ];
    let r = json(&irtp(&[&base[..], &renewal[..]].concat()));
    let (tau, err) = (
        r["tau"].as_f64().unwrap(),
        r["error_estimate"].as_f64().unwrap(),
    );
    assert!(tau > 1.0 && err > 0.0 && err < 0.1 * tau, "renewal: {r}");
    assert_eq!(r["tau_states"].as_array().map(Vec::len), Some(3), "{r}");
}

#[test]
fn every_command_refuses_a_noise_it_does_not_run() {
    let tmp = tempfile::tempdir().unwrap();
    let both = commands().into_iter().map(|c| (c, true));
    let thermal = thermal_refused().into_iter().map(|c| (c, false));
    for (i, (cmd, with_noise)) in both.chain(thermal).enumerate() {
        let dir = tmp.path().join(format!("o{i}")).join("out");
        std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
        let d = dir.to_str().unwrap();
        for (extra, flag) in [
            (vec!["--noise", RPT], "--noise"),
            (vec!["--temperature", "0.5"], "--temperature"),
        ] {
            // Every search method, and `mfpt distribution --method
            // exact`, run a noise model at T = 0.
            let search = cmd.contains(&"--xt") || cmd.contains(&"--interval=-1,1");
            let dist = cmd.contains(&"distribution");
            let runs = search || dist;
            if flag == "--noise" && (!with_noise || runs) {
                continue;
            }
            let args = [&fit(&cmd)[..], &extra[..], &["--out", d][..]].concat();
            let out = irtp(&args);
            let err = assert_rejected(&out, flag, &dir);
            let runners = if search {
                "no search method runs thermal noise"
            } else {
                "simulate, fp"
            };
            assert!(err.contains(runners), "{args:?}: {err}");
        }
    }
}

/// Every table of an output directory, `run.json`'s `parameters` and
/// `summary.json`'s `params` and `results` (less timings and the
/// directory); not the provenance, which records argv.
fn contents(dir: &Path) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read_to_string(&p).unwrap())
        })
        .collect();
    out.sort();
    let run = read_json(&dir.join("run.json"));
    out.push(("parameters".into(), run["parameters"].to_string()));
    let summary = read_json(&dir.join("summary.json"));
    let mut results = summary["results"].clone();
    // What differs between any two runs: timings and the directory.
    if let Some(r) = results.as_object_mut() {
        r.retain(|k, _| !(k.ends_with("_per_s") || k == "wall_time_s" || k == "out"));
    }
    out.push(("results".into(), results.to_string()));
    out.push(("params".into(), summary["params"].to_string()));
    assert!(out.len() > 3, "no tables in {dir:?}");
    out
}

#[test]
fn the_papers_noise_as_a_spec_is_the_same_run_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = [
        "simulate",
        "--method",
        "exact",
        "--particles",
        "200",
        "--t-max",
        "2",
        "--burn-in",
        "1",
        "--drag",
        "tanh",
        "--rate",
        "1",
        "--seed",
        "3",
    ];
    let analytic = ["analytic", "--drag", "tanh", "--points", "50"];
    let paper = ["--sigma", "0.75", "--lambda", "0.625"];
    let specs = [
        vec!["--noise", "telegraph:sigma=0.75,lambda=0.625"],
        vec![
            "--noise",
            "telegraph:plus=0.75,minus=0.75,rate_plus=0.625,rate_minus=0.625",
        ],
        vec!["--sigma", "0.75", "--lambda", "0.625", "--temperature", "0"],
    ];
    for (k, base) in [&sim[..], &analytic[..]].iter().enumerate() {
        let run = |flags: &[&str], name: &str| {
            let dir = tmp.path().join(format!("{k}-{name}"));
            let d = dir.to_str().unwrap();
            assert_success(&irtp(&[base, flags, &["--out", d][..]].concat()));
            contents(&dir)
        };
        let reference = run(&paper, "paper");
        for (i, s) in specs.iter().enumerate() {
            let got = run(s, &format!("spec{i}"));
            assert_eq!(got.len(), reference.len());
            for (a, b) in got.iter().zip(&reference) {
                assert!(a == b, "{base:?} {s:?}: {} differs", a.0);
            }
        }
    }
}

#[test]
fn analytic_linear_drag_gives_the_librarys_noise_moments() {
    let cases = [
        (
            "telegraph:plus=1,minus=0.5,rate_plus=1,rate_minus=2",
            0.0,
            0.5,
            0.1,
        ),
        ("rpt:sigma=1.5,alpha=0.5,beta=2", 0.25, 2.0, -0.2),
        (
            "states:levels=[1,0,-2],rates=[[-1,0.5,0.5],[1,-2,1],[0.25,0.75,-1]]",
            0.0,
            0.0,
            0.0,
        ),
        ("none", 0.5, 1.0, 0.3),
        ("telegraph:sigma=1,lambda=0.5", 0.5, 0.0, 0.0),
    ];
    for (spec, t, r, vr) in cases {
        let (ts, rs, vs) = (t.to_string(), r.to_string(), vr.to_string());
        let out = irtp(&[
            "analytic",
            "--drag",
            "linear",
            "--noise",
            spec,
            "--temperature",
            &ts,
            "--rate",
            &rs,
            "--reset-velocity",
            &vs,
            "--json",
        ]);
        let j = json(&out);
        let lib = LinearNoise::new(1.0, NoiseModel::parse(spec, t).unwrap(), r, vr)
            .unwrap()
            .moments()
            .unwrap();
        for (key, want) in [
            ("v_mean", lib.v_mean),
            ("v2", lib.v2),
            ("drift", lib.drift),
            ("d_eff", lib.d_eff),
        ] {
            assert_eq!(j[key].as_f64(), Some(want), "{spec} {key}: {j}");
        }
        assert_eq!(j["pi"].as_array().unwrap().len(), lib.pi.len(), "{spec}");
        // Only the asymmetric telegraph noise at T = 0 and r = 0 has the density.
        assert!(j.get("density").is_none(), "{spec}: {j}");
    }
}

#[test]
fn analytic_asymmetric_telegraph_density_at_r0() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let spec = "telegraph:plus=3,minus=2,rate_plus=1,rate_minus=2";
    let out = irtp(&[
        "analytic",
        "--drag",
        "tan",
        "--noise",
        spec,
        "--points",
        "400",
        "--json",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let j = json(&out);
    let d = &j["density"];
    let lib =
        TelegraphR0Density::new(DragLaw::Tan, Telegraph::new(3.0, 2.0, 1.0, 2.0).unwrap()).unwrap();
    // The mass in + is pi_+ = k_-/(k_+ + k_-) (Eq. (N2)); <g(v)> = <a>.
    let plus = d["mass_plus"].as_f64().unwrap();
    assert!((plus - 2.0 / 3.0).abs() < 1e-10, "{plus}");
    assert_eq!(d["v2"].as_f64(), Some(lib.moment(2).unwrap()));
    assert_eq!(d["v4"].as_f64(), Some(lib.moment(4).unwrap()));
    let mean_g = lib.expect(&|v: f64| v.tan()).unwrap();
    assert!(
        (mean_g - (3.0 * 2.0 / 3.0 - 2.0 / 3.0)).abs() < 1e-9,
        "{mean_g}"
    );
    assert_eq!(
        (d["v_lower"].as_f64(), d["v_upper"].as_f64()),
        (Some((-2f64).atan()), Some(3f64.atan()))
    );
    // No linear-drag moments for tan drag.
    assert!(j.get("d_eff").is_none(), "{j}");
    // density.csv: p = p_plus + p_minus, and its trapezoid mass near 1 away
    // from the integrable edge singularities.
    let text = std::fs::read_to_string(dir.join("density.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 400);
    for r in &rows {
        assert!(
            (r[1] - r[2] - r[3]).abs() <= 1e-12 * r[1].abs().max(1.0),
            "{r:?}"
        );
        assert_eq!(r[1], lib.pdf(r[0]));
    }
}

#[test]
fn bad_noise_input_is_refused_naming_the_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "--drag",
                "tanh",
                "--noise",
                "telegraph:plus=2,minus=0.5,rate_plus=1,rate_minus=1",
            ],
            "--noise",
        ),
        (
            vec!["--drag", "tanh", "--noise", "rpt:sigma=1,alpha=1,beta=1"],
            "--noise",
        ),
        (
            vec![
                "--drag",
                "linear",
                "--noise",
                "telegraph:plus=1,minus=1,rate_plus=0,rate_minus=1",
            ],
            "--noise",
        ),
        (
            vec![
                "--drag",
                "linear",
                "--noise",
                "telegraph:plus=1,minus=1,rate_plus=-1,rate_minus=1",
            ],
            "--noise",
        ),
        (
            vec![
                "--drag",
                "linear",
                "--noise",
                "states:levels=[1,-1],rates=[[-1,1],[1,-2]]",
            ],
            "--noise",
        ),
        (
            vec![
                "--drag",
                "linear",
                "--noise",
                "rpt:sigma=nan,alpha=1,beta=1",
            ],
            "--noise",
        ),
        (vec!["--drag", "linear", "--noise", "bogus"], "--noise"),
        (vec!["--drag", "linear", "--noise", "none"], "--temperature"),
        (
            vec!["--drag", "linear", "--temperature", "-1"],
            "--temperature",
        ),
        (
            vec!["--drag", "linear", "--temperature", "nan"],
            "--temperature",
        ),
        (
            vec![
                "--drag",
                "linear",
                "--noise",
                "rpt:sigma=1,alpha=1,beta=1",
                "--temperature",
                "inf",
            ],
            "--temperature",
        ),
        (
            vec![
                "--drag",
                "linear",
                "--noise",
                "rpt:sigma=1,alpha=1,beta=1",
                "--rate",
                "1",
                "--reset-velocity",
                "2",
            ],
            "--reset-velocity",
        ),
        (
            vec!["--drag", "tan", "--reset-velocity", "0.1"],
            "--reset-velocity",
        ),
    ];
    for (i, (flags, flag)) in cases.iter().enumerate() {
        for cmd in [&["analytic"][..], &["simulate", "--particles", "10"][..]] {
            if cmd[0] == "simulate" && flags.contains(&"--reset-velocity") {
                continue;
            }
            let dir = tmp.path().join(format!("{}-{i}", cmd[0])).join("out");
            std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
            let args = [cmd, &flags[..], &["--out", dir.to_str().unwrap()][..]].concat();
            assert_rejected(&irtp(&args), flag, &dir);
        }
    }
    // --noise replaces --sigma/--lambda: both at once is a usage error.
    let out = irtp(&[
        "analytic",
        "--sigma",
        "1",
        "--noise",
        "none",
        "--temperature",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(2));
}

/// `noise` and `temperature` are sweep plan keys: each point runs its noise
/// and the table gets the moments.
#[test]
fn a_sweep_plan_sweeps_the_noise() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = tmp.path().join("plan.toml");
    std::fs::write(
        &plan,
        r#"
command = "analytic"
[fixed]
drag = "linear"
rate = 0.5
[axes]
noise = ["telegraph:plus=1,minus=0.5,rate_plus=1,rate_minus=2", "rpt:sigma=1,alpha=1,beta=1"]
temperature = [0.0, 0.25]
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = irtp(&[
        "sweep",
        "run",
        plan.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_success(&o);
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(rows.len(), 4);
    for row in &rows {
        let (spec, t) = (&row[col("noise")], row[col("temperature")].parse().unwrap());
        let lib = LinearNoise::new(1.0, NoiseModel::parse(spec, t).unwrap(), 0.5, 0.0)
            .unwrap()
            .moments()
            .unwrap();
        let d_eff: f64 = row[col("result.d_eff")].parse().unwrap();
        assert_eq!(d_eff, lib.d_eff, "{spec} T = {t}");
    }
}
