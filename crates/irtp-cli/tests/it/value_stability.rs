//! Value stability: seeded outputs of every method, pinned to the bit.
//!
//! Like rand_distr's `tests/value_stability.rs`, this file pins a few numbers
//! of each method at full precision (exact and Euler simulators, exact and
//! Euler first passage, backward MFPT equations, `mfpt optimize`, stationary
//! and transient Fokker-Planck, the r = 0 densities), for every drag law.
//! The numbers are read through the command line's JSON and CSV output, the
//! interface that stays stable while the library is redesigned. A refactor
//! that changes any bit fails here; a deliberate change updates the pins in
//! a commit that says which and why.

use crate::common::irtp;
use std::path::Path;

/// One pinned number: a key of the `--json` object, or a cell
/// (file, data row, column) of a CSV file written by `--out`.
enum Pin {
    Json(&'static str, f64),
    Csv(&'static str, usize, &'static str, f64),
}

struct Case {
    name: &'static str,
    args: &'static [&'static str],
    pins: &'static [Pin],
}

/// The cell (row, column) of a CSV file with a header line.
fn csv_cell(path: &Path, row: usize, column: &str) -> f64 {
    let text = std::fs::read_to_string(path).expect("read csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = header.iter().position(|h| *h == column).expect("column");
    let line = lines.nth(row).expect("row");
    line.split(',')
        .nth(col)
        .expect("cell")
        .parse()
        .expect("number")
}

/// The number stored under `key` of the `results` object of the one-line
/// `--json` object.
fn result_number(json: &str, key: &str) -> Option<f64> {
    let start = json.find("\"results\":")? + "\"results\":".len();
    json_number(&json[start..], key)
}

/// The number stored under top-level `key` of a one-line JSON object, parsed
/// from its text with Rust's correctly rounded parser (serde_json's default
/// float parsing may be off by one ulp, which would defeat a bitwise pin).
/// A small scanner: skips strings, tracks the nesting depth.
fn json_number(json: &str, key: &str) -> Option<f64> {
    let b = json.as_bytes();
    let (mut i, mut depth) = (0usize, 0i32);
    while i < b.len() {
        match b[i] {
            b'{' | b'[' => depth += 1,
            b'}' | b']' => {
                depth -= 1;
                if depth == 0 {
                    return None;
                }
            }
            b'"' => {
                let start = i + 1;
                i += 1;
                while b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                if depth == 1 && &json[start..i] == key && b.get(i + 1) == Some(&b':') {
                    let rest = &json[i + 2..];
                    let end = rest.find([',', '}'])?;
                    return rest[..end].trim().parse().ok();
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

fn check(case: &Case) -> Vec<String> {
    let dir = tempfile::tempdir().expect("tempdir");
    let out_dir = dir.path().join("out");
    let mut args: Vec<&str> = case.args.to_vec();
    args.push("--json");
    let needs_files = case.pins.iter().any(|p| matches!(p, Pin::Csv(..)));
    let out_str = out_dir.to_string_lossy().into_owned();
    if needs_files {
        args.extend(["--out", out_str.as_str()]);
    }
    let out = irtp(&args);
    assert!(
        out.status.success(),
        "{}: {}",
        case.name,
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let json = stdout.lines().last().expect("json line");
    let mut failures = Vec::new();
    for pin in case.pins {
        let (what, got, want) = match pin {
            Pin::Json(key, want) => (key.to_string(), result_number(json, key), *want),
            Pin::Csv(file, row, col, want) => (
                format!("{file}[{row}].{col}"),
                Some(csv_cell(&out_dir.join(file), *row, col)),
                *want,
            ),
        };
        if got.map(f64::to_bits) != Some(want.to_bits()) {
            failures.push(format!("{}: {what} = {got:?}, pinned {want:?}", case.name));
        }
    }
    failures
}

#[test]
fn seeded_outputs_are_pinned() {
    let failures: Vec<String> = CASES.iter().flat_map(check).collect();
    assert!(
        failures.is_empty(),
        "changed values:\n{}",
        failures.join("\n")
    );
}

/// (name, CLI arguments, pins).
const CASES: &[Case] = &[
    Case {
        name: "exact_tan",
        args: &[
            "simulate",
            "--particles",
            "2000",
            "--t-max",
            "5",
            "--burn-in",
            "1",
            "--samples",
            "5",
            "--bins",
            "10",
            "--seed",
            "7",
        ],
        pins: &[
            Pin::Json("v2", 0.650553479907842),
            Pin::Json("v_mean", -0.02198151282135866),
            Pin::Json("v2_final", 0.6598801416510928),
            Pin::Json("x2_final", 4.949447383986663),
            Pin::Json("d_eff_msd", 0.5924517083229294),
            Pin::Json("d_eff_msd_err", 0.015616443721909307),
            Pin::Json("events", 25105.0),
            Pin::Csv("density.csv", 2, "p", 0.3233710851644944),
            Pin::Csv("density.csv", 7, "p_final", 0.312238357166986),
            Pin::Csv("moments.csv", 3, "x2", 3.393294302607143),
        ],
    },
    Case {
        name: "exact_tanh",
        args: &[
            "simulate",
            "--drag",
            "tanh",
            "--sigma",
            "0.6",
            "--lambda",
            "0.85",
            "--rate",
            "1",
            "--particles",
            "2000",
            "--t-max",
            "5",
            "--burn-in",
            "1",
            "--samples",
            "5",
            "--bins",
            "10",
            "--seed",
            "7",
        ],
        pins: &[
            Pin::Json("v2", 0.06694297607598128),
            Pin::Json("v_mean", 0.0025842106570052995),
            Pin::Json("x2_final", 0.5082682634388307),
            Pin::Json("events", 18603.0),
            Pin::Csv("density.csv", 0, "p", 0.05732880981296111),
            Pin::Csv("density.csv", 5, "p", 1.401856382426558),
        ],
    },
    Case {
        name: "exact_linear_vr",
        args: &[
            "simulate",
            "--drag",
            "linear",
            "--sigma",
            "1",
            "--lambda",
            "0.5",
            "--rate",
            "1",
            "--reset-velocity",
            "0.3",
            "--particles",
            "2000",
            "--t-max",
            "5",
            "--burn-in",
            "1",
            "--samples",
            "5",
            "--bins",
            "10",
            "--seed",
            "7",
        ],
        pins: &[
            Pin::Json("v2", 0.24600157616775642),
            Pin::Json("v_mean", 0.14170199389368146),
            Pin::Json("x2_final", 2.418798218221048),
            Pin::Json("events", 14967.0),
            Pin::Csv("density.csv", 4, "p", 0.5293007789339655),
        ],
    },
    Case {
        name: "euler_tan",
        args: &[
            "simulate",
            "--method",
            "euler",
            "--dt",
            "1e-3",
            "--particles",
            "400",
            "--t-max",
            "3",
            "--burn-in",
            "1",
            "--samples",
            "3",
            "--bins",
            "10",
            "--seed",
            "11",
        ],
        pins: &[
            Pin::Json("v2", 0.6590207143640505),
            Pin::Json("v_mean", 0.003409052163411017),
            Pin::Json("x2_final", 2.469511664390643),
            Pin::Json("d_eff_msd", 0.5668635829330357),
            Pin::Csv("density.csv", 1, "p", 0.27770699654504105),
        ],
    },
    Case {
        name: "euler_tanh_bernoulli",
        args: &[
            "simulate",
            "--method",
            "euler",
            "--events",
            "bernoulli",
            "--drag",
            "tanh",
            "--sigma",
            "0.6",
            "--lambda",
            "0.85",
            "--rate",
            "1",
            "--dt",
            "1e-3",
            "--particles",
            "300",
            "--t-max",
            "3",
            "--burn-in",
            "1",
            "--samples",
            "3",
            "--bins",
            "10",
            "--seed",
            "11",
        ],
        pins: &[
            Pin::Json("v2", 0.06418322431041647),
            Pin::Json("v_mean", 0.005269841978512201),
            Pin::Json("x2_final", 0.22341392524249323),
        ],
    },
    Case {
        name: "euler_linear",
        args: &[
            "simulate",
            "--method",
            "euler",
            "--drag",
            "linear",
            "--sigma",
            "1",
            "--lambda",
            "0.5",
            "--rate",
            "1",
            "--reset-velocity",
            "0.3",
            "--dt",
            "1e-3",
            "--particles",
            "300",
            "--t-max",
            "3",
            "--burn-in",
            "1",
            "--samples",
            "3",
            "--bins",
            "10",
            "--seed",
            "11",
        ],
        pins: &[
            Pin::Json("v2", 0.23432620651509328),
            Pin::Json("v_mean", 0.1301280301267743),
            Pin::Json("x2_final", 0.9925758667768806),
        ],
    },
    Case {
        name: "fpt_exact",
        args: &[
            "mfpt",
            "--v0",
            "-0.249",
            "--vt",
            "0.5",
            "--method",
            "exact",
            "--particles",
            "2000",
            "--seed",
            "3",
        ],
        pins: &[
            Pin::Json("tau", 1.7139102494263176),
            Pin::Json("tau_err", 0.0443513269078067),
            Pin::Json("tau_plus", 0.6750023579483269),
            Pin::Json("tau_minus", 2.7528181409043087),
        ],
    },
    Case {
        name: "fpt_exact_down_tanh",
        args: &[
            "mfpt",
            "--drag",
            "tanh",
            "--sigma",
            "0.6",
            "--lambda",
            "0.85",
            "--rate",
            "1",
            "--v0",
            "0.3",
            "--vt",
            "-0.2",
            "--method",
            "exact",
            "--particles",
            "1000",
            "--seed",
            "5",
        ],
        pins: &[
            Pin::Json("tau", 2.7079318955384792),
            Pin::Json("tau_plus", 3.255021058449127),
            Pin::Json("tau_minus", 2.1608427326278314),
        ],
    },
    Case {
        name: "fpt_euler",
        args: &[
            "mfpt",
            "--v0",
            "-0.249",
            "--vt",
            "0.5",
            "--method",
            "euler",
            "--dt",
            "1e-3",
            "--particles",
            "1000",
            "--seed",
            "3",
        ],
        pins: &[
            Pin::Json("tau", 1.8904279999999998),
            Pin::Json("tau_plus", 0.6983680000000003),
            Pin::Json("tau_minus", 3.0824879999999992),
        ],
    },
    Case {
        name: "fpt_euler_linear",
        args: &[
            "mfpt",
            "--drag",
            "linear",
            "--sigma",
            "1",
            "--lambda",
            "0.5",
            "--rate",
            "1",
            "--v0",
            "0.2",
            "--vt",
            "-0.3",
            "--method",
            "euler",
            "--dt",
            "1e-3",
            "--particles",
            "500",
            "--seed",
            "3",
        ],
        pins: &[
            Pin::Json("tau", 2.5360179999999994),
            Pin::Json("tau_plus", 3.5920160000000005),
            Pin::Json("tau_minus", 1.4800199999999986),
        ],
    },
    Case {
        name: "backward_tan",
        args: &["mfpt", "--v0", "-0.249", "--vt", "0.5"],
        pins: &[
            Pin::Json("tau", 1.7442128770260037),
            Pin::Json("tau_plus", 0.6563652826505617),
            Pin::Json("tau_minus", 2.8320604714014457),
            Pin::Json("error_estimate", 1.6281613094785521e-10),
        ],
    },
    Case {
        name: "backward_tanh_down",
        args: &[
            "mfpt", "--drag", "tanh", "--sigma", "0.6", "--lambda", "0.85", "--rate", "1", "--v0",
            "0.3", "--vt", "-0.2", "--cells", "4000",
        ],
        pins: &[
            Pin::Json("tau", 2.706658443297724),
            Pin::Json("tau_plus", 3.2697723934365466),
            Pin::Json("tau_minus", 2.1435444931589007),
        ],
    },
    Case {
        name: "optimize_tan",
        args: &["mfpt", "optimize", "--v0", "-0.249", "--vt", "0.5"],
        pins: &[
            Pin::Json("r_opt", 2.3685113872561674),
            Pin::Json("tau_opt", 1.7422966777209097),
            Pin::Json("tau_r0", 1.8620758026812005),
            Pin::Json("dtau_dr_r0", -0.13382689777121096),
        ],
    },
    Case {
        name: "fp_stationary_tan",
        args: &["fp", "stationary", "--cells", "400"],
        pins: &[
            Pin::Json("v2", 0.6540273402136441),
            Pin::Json("d_eff", 0.6462280238616028),
            Pin::Json("mass", 1.0),
        ],
    },
    Case {
        name: "fp_stationary_tanh_r0",
        args: &[
            "fp",
            "stationary",
            "--drag",
            "tanh",
            "--sigma",
            "0.6",
            "--lambda",
            "0.85",
            "--rate",
            "0",
            "--cells",
            "400",
        ],
        pins: &[
            Pin::Json("v2", 0.14923979010819974),
            Pin::Json("d_eff", 0.25506032717932936),
        ],
    },
    Case {
        name: "fp_stationary_linear_vr",
        args: &[
            "fp",
            "stationary",
            "--drag",
            "linear",
            "--sigma",
            "1",
            "--lambda",
            "0.5",
            "--rate",
            "1",
            "--reset-velocity",
            "0.3",
            "--cells",
            "400",
        ],
        pins: &[
            Pin::Json("v2", 0.2522263888888886),
            Pin::Json("v_mean", 0.1499999999999997),
            Pin::Json("d_eff", 0.28152986111111045),
        ],
    },
    Case {
        name: "fp_transient_tan",
        args: &[
            "fp",
            "transient",
            "--scheme",
            "paper",
            "--t-max",
            "2",
            "--cells",
            "200",
        ],
        pins: &[
            Pin::Json("v2_final", 0.6528622672702848),
            Pin::Json("dt", 0.0010565744925594984),
            Pin::Json("steps", 1900.0),
        ],
    },
    Case {
        name: "fp_transient_tanh",
        args: &[
            "fp",
            "transient",
            "--scheme",
            "paper",
            "--drag",
            "tanh",
            "--sigma",
            "0.6",
            "--lambda",
            "0.85",
            "--rate",
            "1",
            "--t-max",
            "1",
            "--cells",
            "200",
        ],
        pins: &[
            Pin::Json("v2_final", 0.05663763868645592),
            Pin::Json("v_mean_final", 8.964982358442503e-18),
        ],
    },
    Case {
        name: "fp_transient_trbdf2_tan",
        args: &["fp", "transient", "--t-max", "2", "--cells", "200"],
        pins: &[
            Pin::Json("v2_final", 0.6540049436730633),
            Pin::Json("steps", 5148.0),
        ],
    },
    Case {
        name: "analytic_tan",
        args: &[
            "analytic", "--drag", "tan", "--sigma", "3", "--lambda", "0.5",
        ],
        pins: &[
            Pin::Json("v2", 1.2074918336908644),
            Pin::Json("v4", 1.756969917225585),
            Pin::Json("edge_exponent", -0.95),
            Pin::Csv("density.csv", 0, "p", 6191.128990014134),
            Pin::Csv("density.csv", 100, "p", 0.3415060400668804),
            Pin::Csv("density.csv", 100, "cdf", 0.32805494617380526),
        ],
    },
    Case {
        name: "analytic_tanh",
        args: &[
            "analytic", "--drag", "tanh", "--sigma", "0.6", "--lambda", "0.85",
        ],
        pins: &[
            Pin::Json("v2", 0.1492384325647604),
            Pin::Json("v4", 0.040300406711721096),
            Pin::Csv("density.csv", 50, "p", 0.35557137789637044),
        ],
    },
    Case {
        name: "analytic_linear",
        args: &[
            "analytic", "--drag", "linear", "--sigma", "1", "--lambda", "0.7",
        ],
        pins: &[
            Pin::Json("v2", 0.41666666666666663),
            Pin::Csv("density.csv", 30, "p", 1.6324618501725134),
        ],
    },
];
