//! `mfpt --method euler` runs every schedule modifier with a noise model
//! (the first passage's scheduled loop over the Euler sampler's noise
//! steps): run-pause-tumble with tan drag under a periodic clock, a gamma
//! renewal clock, an exponential and a fixed refractory period and a
//! position reset, at the default particles, dt and t_max (admitted by the
//! default work budget), and thermal noise with a periodic clock. Each
//! exits 0 with a finite tau, no particle censored. The cost estimate
//! (printed by a refusal under `--max-work 1`) is within a factor 3 of the
//! work done: every particle arrives, after tau/dt steps on average, so
//! the run's steps are particles · tau / dt.

use crate::common::{irtp, json};

const RPT: &str = "rpt:sigma=3,alpha=1,beta=2";

/// The estimated work in `irtp: error: too costly: estimated X <unit> ...`.
fn estimate(args: &[&str]) -> f64 {
    let out = irtp(&[args, &["--max-work", "1"]].concat());
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{err}");
    let x = err
        .split("estimated ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap_or_else(|| panic!("no estimate: {err}"));
    x.parse().unwrap_or_else(|_| panic!("{x}: {err}"))
}

#[test]
fn euler_first_passage_runs_every_modifier_with_a_noise_model_at_defaults() {
    let modifiers: [&[&str]; 5] = [
        &["--reset-period", "1"],
        &["--reset-clock", "gamma:k=2,theta=0.5"],
        &["--refractory", "exp:mean=0.5"],
        &["--refractory", "fixed:t=0.5"],
        &["--reset-position", "0"],
    ];
    let base = [
        "mfpt", "--method", "euler", "--drag", "tan", "--noise", RPT, "--v0", "0", "--vt", "1",
    ];
    for flags in modifiers {
        let args = [&base[..], flags].concat();
        let r = json(&irtp(&[&args[..], &["--json"]].concat()));
        let tau = r["tau"].as_f64().unwrap_or(f64::NAN);
        assert!(tau.is_finite() && tau > 0.0, "{flags:?}: {r}");
        assert_eq!(r["censored"], 0, "{flags:?}: {r}");
        let (n, dt) = (r["particles"].as_f64().unwrap(), r["dt"].as_f64().unwrap());
        let done = n * tau / dt;
        let est = estimate(&args);
        assert!(
            est / done < 3.0 && done / est < 3.0,
            "{flags:?}: estimated {est:e} steps, done {done:e}"
        );
    }
}

#[test]
fn euler_first_passage_runs_a_clock_with_thermal_noise() {
    let r = json(&irtp(&[
        "mfpt",
        "--method",
        "euler",
        "--drag",
        "tan",
        "--noise",
        "telegraph:sigma=1,lambda=0.5",
        "--temperature",
        "0.3",
        "--reset-period",
        "1",
        "--v0",
        "0",
        "--vt",
        "1",
        "--particles",
        "1000",
        "--json",
    ]));
    let tau = r["tau"].as_f64().unwrap_or(f64::NAN);
    assert!(tau.is_finite() && tau > 0.0, "{r}");
}
