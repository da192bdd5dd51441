//! `mfpt --method exact` with a noise model at temperature 0 (the exact
//! first-passage sampler's N-state loop, docs/equations.md Eqs.
//! (N46)-(N48)): the run writes its outputs with provenance and the noise
//! in its parameters, τ agrees with `--method backward` within 4 standard
//! errors, the run is the same bits for 1 and 2 threads, and thermal
//! noise is refused naming `--temperature`.

use super::common::*;

const RPT: &str = "rpt:sigma=3,alpha=1,beta=2";

fn base(method: &str) -> Vec<&str> {
    vec![
        "mfpt", "--method", method, "--drag", "tan", "--noise", RPT, "--v0", "0", "--vt", "0.5",
        "--rate", "1",
    ]
}

#[test]
fn exact_passage_with_a_noise_model_matches_backward() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("exact");
    let d = dir.to_str().unwrap();
    let exact = [
        &base("exact")[..],
        &["--particles", "20000", "--seed", "5", "--json", "--out", d],
    ]
    .concat();
    let s = summary(&irtp(&exact));
    let r = &s["results"];
    let (tau, se) = (r["tau"].as_f64().unwrap(), r["tau_err"].as_f64().unwrap());
    assert_eq!(r["censored"].as_u64(), Some(0), "{s}");
    assert_eq!(s["provenance"]["seed"].as_u64(), Some(5), "{s}");
    let run = read_json(&dir.join("run.json"));
    let params = run["parameters"].to_string();
    assert!(params.contains(RPT), "{params}");
    assert!(run["argv"].to_string().contains(RPT), "{run}");
    assert_eq!(run["seed"].as_u64(), Some(5), "{run}");
    assert!(run["git_revision"].is_string(), "{run}");
    assert!(dir.join("survival.csv").exists());
    let back = json(&irtp(&[&base("backward")[..], &["--json"]].concat()));
    let reference = back["tau"].as_f64().unwrap();
    let z = (tau - reference) / se;
    eprintln!("exact {tau} ± {se}, backward {reference}: z = {z:.2}");
    assert!(
        z.abs() < 4.0,
        "z = {z}: exact {tau} ± {se}, backward {reference}"
    );
    // The same bits for any thread count.
    let small = [&base("exact")[..], &["--particles", "3000", "--json"]].concat();
    let results = |threads: &str| {
        let out = irtp_env(&small, &[("RAYON_NUM_THREADS", threads)]);
        json(&out).to_string()
    };
    assert_eq!(results("1"), results("2"));
}

#[test]
fn thermal_noise_is_refused_naming_temperature() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("o").join("out");
    std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
    let args = [
        &base("exact")[..],
        &["--temperature", "0.5", "--out", dir.to_str().unwrap()],
    ]
    .concat();
    let err = assert_rejected(&irtp(&args), "--temperature", &dir);
    assert!(
        err.contains("thermal noise not run by mfpt --method exact"),
        "{err}"
    );
}
