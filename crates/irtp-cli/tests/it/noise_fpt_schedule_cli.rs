//! `mfpt --method exact` with a finite-state noise under the schedule
//! modifiers (periodic resetting, a renewal clock, fixed and exponential
//! refractory periods): one kernel runs every noise, so the paper's noise
//! spelt as a two-state generator must give the paper's τ under each
//! modifier (within 4 combined standard errors; fixed seeds).

use super::common::*;

/// (Sigma, lambda) = (1.5, 0.7) as the paper's flags and as a generator.
const PAPER: [&str; 4] = ["--sigma", "1.5", "--lambda", "0.7"];
const AS_STATES: [&str; 2] = [
    "--noise",
    "states:levels=[1.5,-1.5],rates=[[-0.7,0.7],[0.7,-0.7]]",
];

#[test]
fn the_papers_noise_as_a_generator_gives_the_papers_tau_under_each_modifier() {
    let modifiers: [&[&str]; 4] = [
        &["--rate", "0", "--reset-period", "1.5"],
        &["--rate", "0", "--reset-clock", "gamma:k=2,theta=0.75"],
        &["--rate", "1", "--refractory", "fixed:t=0.5"],
        &["--rate", "1", "--refractory", "exp:mean=0.5"],
    ];
    let base = [
        "mfpt",
        "--method",
        "exact",
        "--drag",
        "tan",
        "--v0",
        "0",
        "--vt",
        "0.6",
        "--particles",
        "40000",
        "--t-max",
        "10000",
        "--json",
    ];
    for (k, m) in modifiers.iter().enumerate() {
        let seed = (10 + k).to_string();
        let run = |noise: &[&str], seed: &str| {
            let r = json(&irtp(&[&base[..], noise, m, &["--seed", seed]].concat()));
            assert_eq!(r["censored"].as_u64(), Some(0), "{m:?}: {r}");
            (r["tau"].as_f64().unwrap(), r["tau_err"].as_f64().unwrap())
        };
        let (a, ea) = run(&PAPER, &seed);
        let (b, eb) = run(&AS_STATES, &format!("{seed}0"));
        assert!(ea > 0.0 && eb > 0.0 && ea < 0.05 * a, "{m:?}: {a} ± {ea}");
        assert!(
            (a - b).abs() < 4.0 * ea.hypot(eb),
            "{m:?}: paper {a} ± {ea}, as states {b} ± {eb}"
        );
    }
}
