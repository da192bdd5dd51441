//! `mfpt distribution --method exact` with a finite-state noise at T = 0
//! (docs/equations.md, Eqs. (N46)-(N48)): the sampled survival S(t) and
//! mean against `mfpt distribution --method backward` (Eqs. (N37)-(N39))
//! and `mfpt --method backward`; thermal noise refused in one line naming
//! the flag, nothing written.

use super::common::*;
use std::path::Path;

const RPT: &str = "rpt:sigma=3,alpha=1,beta=2";

fn base(noise: &str) -> Vec<&str> {
    vec![
        "--drag", "tan", "--noise", noise, "--rate", "1", "--v0", "0", "--vt", "1",
    ]
}

/// The rows of a CSV file (header left out) as numbers.
fn rows(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

/// The row of `table` whose first column is `t` (to 1e-9).
fn at(table: &[Vec<f64>], t: f64) -> &[f64] {
    table
        .iter()
        .find(|r| (r[0] - t).abs() < 1e-9)
        .unwrap_or_else(|| panic!("no row at t = {t}"))
}

/// Run-pause-tumble and a three-level `states:` noise: S(t) of 100000
/// exact particles at five times away from the atom (t_f ≈ 0.43) within
/// 4 SE of the backward S plus its mesh error; the sampled mean within
/// 4 SE (plus the backward error estimate) of `mfpt --method backward`.
#[test]
fn exact_distribution_with_a_noise_model_matches_the_backward_one() {
    let tmp = tempfile::tempdir().unwrap();
    let three = "states:levels=[3,0.5,-2],rates=[[-2,1,1],[1,-2,1],[0.5,0.5,-1]]";
    for (k, noise) in [RPT, three].into_iter().enumerate() {
        let ex = tmp.path().join(format!("exact{k}"));
        let bw = tmp.path().join(format!("backward{k}"));
        let (e, b) = (ex.to_str().unwrap(), bw.to_str().unwrap());
        let exact = ["mfpt", "distribution", "--method", "exact", "--out", e];
        assert_success(&irtp(&[&exact[..], &base(noise)[..]].concat()));
        let backward = [
            "mfpt",
            "distribution",
            "--method",
            "backward",
            "--t-max",
            "10",
            "--points",
            "101",
            "--out",
            b,
        ];
        assert_success(&irtp(&[&backward[..], &base(noise)[..]].concat()));
        let (s, d) = (
            rows(&ex.join("survival.csv")),
            rows(&bw.join("distribution.csv")),
        );
        let mesh = read_json(&bw.join("distribution.json"))["mesh_error"]
            .as_f64()
            .unwrap();
        for t in [1.0, 2.0, 3.0, 5.1, 8.2] {
            let (se, sb) = (at(&s, t), at(&d, t));
            let tol = 4.0 * se[2] + mesh;
            assert!(se[2] > 0.0, "{noise} t = {t}: {se:?}");
            assert!(
                (se[1] - sb[1]).abs() < tol,
                "{noise} t = {t}: {se:?} {sb:?}"
            );
        }
        let r = read_json(&ex.join("distribution.json"));
        let tau = json(&irtp(
            &[
                &["mfpt", "--method", "backward", "--json"][..],
                &base(noise)[..],
            ]
            .concat(),
        ));
        let (t_ex, err) = (r["tau"].as_f64().unwrap(), r["tau_err"].as_f64().unwrap());
        let t_bw = tau["tau"].as_f64().unwrap();
        let tol = 4.0 * err + tau["error_estimate"].as_f64().unwrap();
        assert!(
            (t_ex - t_bw).abs() < tol,
            "{noise}: {t_ex} ± {err} vs {t_bw}"
        );
        assert_eq!(r["censored"].as_u64(), Some(0), "{r}");
        assert!(ex.join("histogram.csv").exists());
    }
}

/// What `mfpt distribution --method exact` refuses with a noise model:
/// thermal noise, naming `--temperature`, in one line under 200
/// characters saying what runs it, exit 2, nothing written; it runs the
/// schedule modifiers (the exact kernel runs every noise under them).
#[test]
fn exact_distribution_with_a_noise_model_refuses_thermal_noise_in_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let cmd = |out: &str, extra: &[&str]| {
        let base = [
            "mfpt",
            "distribution",
            "--method",
            "exact",
            "--drag",
            "tan",
            "--noise",
            RPT,
            "--v0",
            "0",
            "--vt",
            "1",
            "--t-max",
            "100",
            "--particles",
            "2000",
            "--out",
            out,
        ];
        irtp(&[&base[..], extra].concat())
    };
    let dir = tmp.path().join("thermal");
    let out = cmd(
        dir.to_str().unwrap(),
        &["--rate", "1", "--temperature", "0.5"],
    );
    let err = assert_rejected(&out, "--temperature", &dir);
    assert!(
        err.len() < 200 && err.contains("runs in mfpt distribution (backward), simulate, fp"),
        "{err}"
    );
    let dir = tmp.path().join("periodic");
    assert_success(&cmd(
        dir.to_str().unwrap(),
        &["--rate", "0", "--reset-period", "1"],
    ));
    assert!(dir.join("survival.csv").exists());
}
