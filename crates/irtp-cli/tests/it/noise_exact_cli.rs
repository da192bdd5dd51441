//! `irtp simulate --method exact` with a noise model (docs/equations.md,
//! Eqs. (N10)-(N12)): a run-pause-tumble noise runs and records its noise
//! in the provenance; thermal noise with linear drag runs (Eqs.
//! (N40)-(N45)) and its stationary <v²> is the closed form's; a noise or
//! temperature it does not run, and a level a drag cannot reach, are
//! refused naming the flag (exit 2, nothing written).

use super::common::*;

const SIM: [&str; 12] = [
    "simulate",
    "--method",
    "exact",
    "--particles",
    "200",
    "--t-max",
    "3",
    "--burn-in",
    "1",
    "--seed",
    "4",
    "--bins=20",
];

#[test]
fn simulate_exact_runs_a_run_pause_tumble_noise() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rpt");
    let noise = "rpt:sigma=1,alpha=1,beta=1";
    let args = [
        &SIM[..],
        &["--drag", "tan", "--noise", noise, "--rate", "0.5", "--out"][..],
        &[dir.to_str().unwrap()][..],
    ]
    .concat();
    assert_success(&irtp(&args));
    let run = read_json(&dir.join("run.json"));
    let p = &run["parameters"]["model"];
    assert_eq!(p["noise"].as_str(), Some(noise), "{p}");
    assert!(p.get("sigma").is_none(), "{p}");
    let s = read_json(&dir.join("summary.json"));
    let v2 = s["results"]["v2"].as_f64().unwrap_or(f64::NAN);
    // Inside the velocity interval (-atan 1, atan 1).
    let edge = 1f64.atan();
    assert!(v2 > 0.0 && v2 < edge * edge, "{s}");
    // The same run again is the same bit for bit.
    let again = tmp.path().join("again");
    let args2 = [
        &SIM[..],
        &["--drag", "tan", "--noise", noise, "--rate", "0.5", "--out"][..],
        &[again.to_str().unwrap()][..],
    ]
    .concat();
    assert_success(&irtp(&args2));
    for f in ["moments.csv", "density.csv"] {
        let (a, b) = (dir.join(f), again.join(f));
        if a.exists() {
            assert_eq!(
                std::fs::read_to_string(a).unwrap(),
                std::fs::read_to_string(b).unwrap(),
                "{f}"
            );
        }
    }
}

#[test]
fn simulate_exact_refuses_what_it_does_not_run() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        // A level beyond tanh's range.
        (
            vec![
                "--drag",
                "tanh",
                "--noise",
                "telegraph:plus=2,minus=0.5,rate_plus=1,rate_minus=1",
            ],
            "--noise",
        ),
        // Thermal noise with tan drag (the exact sampler runs T > 0 with
        // linear drag only).
        (
            vec!["--drag", "tan", "--temperature", "0.5"],
            "--temperature",
        ),
        (
            vec![
                "--drag",
                "tan",
                "--noise",
                "rpt:sigma=1,alpha=1,beta=1",
                "--temperature",
                "0.5",
            ],
            "--temperature",
        ),
        // The pause level 0 at the kink of the power law (g'(0) = ∞).
        (
            vec![
                "--drag",
                "power:n=0.5",
                "--noise",
                "rpt:sigma=1,alpha=1,beta=1",
            ],
            "--noise",
        ),
    ];
    for (i, (extra, flag)) in cases.iter().enumerate() {
        let dir = tmp.path().join(format!("c{i}")).join("out");
        std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
        let args = [&SIM[..], &extra[..], &["--out", dir.to_str().unwrap()][..]].concat();
        let err = assert_rejected(&irtp(&args), flag, &dir);
        eprintln!("{err}");
    }
}

/// Pure Ornstein-Uhlenbeck with resetting to 0 at rate r = 1 (the
/// default method, exact): the stationary <v²> of summary.json within 4
/// standard errors of Eq. (N4), `<v²>` = 2T/(2 + r) (`m` = 0: one level
/// at 0), computed by the library's closed form.
#[test]
fn simulate_exact_runs_thermal_noise_with_linear_drag() {
    use irtp::analytic::linear_noise::LinearNoise;
    use irtp::model::noise::NoiseModel;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ou");
    let args = [
        "simulate",
        "--drag",
        "linear",
        "--noise",
        "none",
        "--temperature",
        "0.5",
        "--rate",
        "1",
        "--particles",
        "2000",
        "--bins",
        "20",
        "--seed",
        "8",
        "--out",
        dir.to_str().unwrap(),
    ];
    assert_success(&irtp(&args));
    let s = read_json(&dir.join("summary.json"));
    let r = &s["results"];
    let (v2, se) = (r["v2"].as_f64().unwrap(), r["v2_err"].as_f64().unwrap());
    let noise = NoiseModel::parse("none", 0.5).unwrap();
    let exact = LinearNoise::new(1.0, noise, 1.0, 0.0)
        .unwrap()
        .moments()
        .unwrap()
        .v2;
    assert!((exact - 2.0 * 0.5 / 3.0).abs() < 1e-12, "{exact}");
    eprintln!(
        "<v²> = {v2} ± {se} vs {exact} ({:.2} SE)",
        (v2 - exact) / se
    );
    assert!(se > 0.0 && (v2 - exact).abs() <= 4.0 * se, "{s}");
}
