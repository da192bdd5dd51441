//! Help that speaks to users, kept in step with the code: every command's
//! `--help` (found by walking the `Commands:` sections from `irtp --help`)
//! says what it computes, ends with examples that run (each run as
//! printed, at reduced size, as the docs' commands are: [`super::docs`]),
//! `-h` is the short form of `--help`; the version is Cargo's; the
//! defaults `--help` prints by hand are the code's (the run without the
//! flag equals the run with the printed default); the supported
//! combinations in `--help` are the core's support tables; and every
//! refusal the tables can produce is one line under 200 characters naming
//! its flag.

use super::common::BIN;
use super::docs::{adapt, root, run, words};
use irtp::model::noise::support as noise_support;
use irtp::model::noise::NoiseModel;
use irtp::model::reset::support::{runners, supports, Feature, Solver};
use irtp::model::reset::Schedule;
use irtp::{DragLaw, Params};
use std::collections::HashMap;
use std::process::Command;

/// The stdout of `irtp <path> <flag>`, which must exit 0.
fn help(path: &[String], flag: &str) -> String {
    let o = Command::new(BIN).args(path).arg(flag).output().unwrap();
    assert!(o.status.success(), "{path:?} {flag}: {o:?}");
    String::from_utf8(o.stdout).unwrap()
}

/// Every command path of the program, the program itself (`[]`) first:
/// the names in the `Commands:` section of each `--help` but `help`.
fn command_paths() -> Vec<Vec<String>> {
    let mut paths = vec![vec![]];
    let mut i = 0;
    while i < paths.len() {
        let text = help(&paths[i], "--help");
        let section = text.lines().skip_while(|l| *l != "Commands:").skip(1);
        for line in section.take_while(|l| l.starts_with("  ")) {
            let name = line.split_whitespace().next().unwrap();
            if name != "help" {
                let mut p = paths[i].clone();
                p.push(name.to_string());
                paths.push(p);
            }
        }
        i += 1;
    }
    paths
}

/// The example commands of a help text: the lines after `Examples:` that
/// start with `irtp `, as shell words after `irtp` (comments dropped).
fn examples(text: &str) -> Vec<Vec<String>> {
    text.lines()
        .skip_while(|l| l.trim() != "Examples:")
        .filter_map(|l| l.trim().strip_prefix("irtp "))
        .map(words)
        .collect()
}

#[test]
fn every_command_says_what_it_computes_and_ends_with_examples() {
    let paths = command_paths();
    assert!(
        paths.len() >= 19,
        "only {} commands: {paths:?}",
        paths.len()
    );
    for path in &paths {
        let (short, long) = (help(path, "-h"), help(path, "--help"));
        let about = long.lines().next().unwrap();
        assert!(about.len() > 30, "{path:?}: a short opening: {about}");
        assert!(!long.contains("thin binary"), "{path:?}: {about}");
        for text in [&short, &long] {
            let n = examples(text).len();
            assert!((2..=4).contains(&n), "{path:?}: {n} examples:\n{text}");
            let last = text.trim_end().lines().last().unwrap();
            assert!(
                last.trim_start().starts_with("irtp "),
                "{path:?}: ends {last}"
            );
        }
        assert!(short.len() <= long.len(), "{path:?}: -h longer than --help");
        let wide = short.lines().map(|l| l.chars().count()).max().unwrap();
        assert!(wide <= 200, "{path:?}: a -h line of {wide} characters");
    }
}

#[test]
fn top_level_help_says_what_irtp_does() {
    let long = help(&[], "--help");
    for word in ["run-and-tumble", "P_s(v)", "D_eff", "first-passage"] {
        assert!(long.contains(word), "no {word} in:\n{long}");
    }
    assert!(help(&[], "-h").len() < long.len());
}

/// Run the examples of every command whose path `pick` selects, each
/// command's examples in order sharing their output directories; `sweep
/// collect` may be refused naming `--python` where the Python module is
/// not installed, and `reproduce all` is left to the reproduce tests.
fn run_examples(pick: impl Fn(&[String]) -> bool) -> usize {
    let mut ran = 0;
    for path in command_paths().iter().filter(|p| pick(p)) {
        let tmp = tempfile::tempdir().unwrap();
        let mut dirs = HashMap::new();
        for args in examples(&help(path, "--help")) {
            let adapted = adapt(&args, tmp.path(), &mut dirs);
            let place = format!("irtp {} --help", path.join(" "));
            let head: Vec<&str> = adapted.iter().take(2).map(String::as_str).collect();
            if head == ["reproduce", "all"] {
                continue;
            }
            if head == ["sweep", "collect"] {
                let o = Command::new(BIN)
                    .args(&adapted)
                    .current_dir(root())
                    .output()
                    .unwrap();
                let err = String::from_utf8_lossy(&o.stderr);
                let no_python = o.status.code() == Some(2) && err.contains("--python");
                assert!(o.status.success() || no_python, "{place}: {err}");
            } else {
                run(&place, &adapted);
            }
            ran += 1;
        }
    }
    ran
}

/// The command paths of the second example test (the rest run in the first).
fn second_half(p: &[String]) -> bool {
    matches!(
        p.first().map(String::as_str),
        Some("fp" | "reproduce" | "sweep")
    )
}

#[test]
#[ignore = "slow tier: runs half the --help examples (~60 s on 2 cores)"]
fn help_examples_run_part_1_of_2() {
    assert!(run_examples(|p| !second_half(p)) >= 15);
}

#[test]
#[ignore = "slow tier: runs half the --help examples (~60 s on 2 cores)"]
fn help_examples_run_part_2_of_2() {
    assert!(run_examples(second_half) >= 15);
}

/// Every example of every `--help` parses and validates as its run would
/// (clap, the applies table, each command's own checks, without computing);
/// an example of `sweep` names a plan that exists. The examples run whole
/// in the slow tier ([`help_examples_run_part_1_of_2`]).
#[test]
fn help_examples_parse_and_validate() {
    use clap::{CommandFactory, FromArgMatches};
    let mut checked = 0;
    for path in command_paths() {
        for args in examples(&help(&path, "--help")) {
            let place = format!("irtp {} --help: irtp {}", path.join(" "), args.join(" "));
            match args[0].as_str() {
                "sweep" => {
                    let plans = args.iter().filter(|a| a.ends_with(".toml"));
                    plans.for_each(|p| assert!(root().join(p).exists(), "{place}"));
                    continue;
                }
                "plot" => continue,
                _ => {}
            }
            let argv = std::iter::once("irtp").chain(args.iter().map(String::as_str));
            let m = irtp_paper::Cli::command().try_get_matches_from(argv);
            let m = m.unwrap_or_else(|e| panic!("{place}: {e}"));
            irtp_app::applies::check(&m).unwrap_or_else(|e| panic!("{place}: {e}"));
            let cli = irtp_paper::Cli::from_arg_matches(&m).unwrap();
            let valid = cli.command.args().validate();
            valid.unwrap_or_else(|e| panic!("{place}: {e}"));
            checked += 1;
        }
    }
    assert!(checked >= 25, "{checked}");
}

#[test]
fn the_version_is_cargos() {
    let o = Command::new(BIN).arg("--version").output().unwrap();
    let text = String::from_utf8(o.stdout).unwrap();
    let version = env!("CARGO_PKG_VERSION");
    assert!(text.starts_with(&format!("irtp {version} ")), "{text}");
    assert_eq!(irtp_app::VERSION, version);
}

/// A cheap search by the renewal route.
const RENEWAL: &str =
    "mfpt --v0 0 --xt 1 --reset-position 0 --rate 1 --method renewal --cells-x 16 --cells-v 8";

/// `(a cheap command line, a flag whose default its help prints by hand)`:
/// the flags without a clap default (their absence means something), whose
/// `[default: ...]` is typed in the help text.
const TYPED_DEFAULTS: &[(&str, &str)] = &[
    (
        "mfpt --v0 0 --vt 1 --method exact --particles 400",
        "--t-max",
    ),
    ("mfpt --v0 0 --vt 1 --method exact", "--particles"),
    (
        "mfpt --v0 0 --vt 1 --method exact --particles 400",
        "--seed",
    ),
    ("mfpt --v0 0 --vt 1 --method euler --particles 200", "--dt"),
    ("mfpt --v0 0 --vt 1 --cells 400", "--rate"),
    ("mfpt --v0 0 --vt 1 --cells 400", "--reset-noise"),
    ("mfpt --v0 0 --vt 1 --cells 400", "--temperature"),
    (
        "mfpt --v0 0 --xt 1 --reset-position 0 --rate 1 --cells-x 16 --cells-v 8",
        "--x0",
    ),
    (RENEWAL, "--time-steps"),
    (RENEWAL, "--horizon-tail"),
    ("mfpt distribution --v0 0 --vt 1 --cells 400", "--points"),
    ("mfpt distribution --v0 0 --vt 1 --cells 400", "--grid"),
    ("mfpt distribution --v0 0 --vt 1 --cells 400", "--rtol"),
    (
        "mfpt distribution --v0 0 --vt 1 --method exact --cells 400",
        "--particles",
    ),
    (
        "simulate --method euler --particles 200 --t-max 11 --samples 3",
        "--dt",
    ),
    (
        "simulate --method euler --particles 200 --t-max 11 --samples 3",
        "--events",
    ),
    (
        "fp transient --t-max 0.2 --cells 100 --scheme paper",
        "--cfl",
    ),
    ("fp transient --t-max 0.2 --cells 100", "--rtol"),
    ("fp transient --t-max 0.2 --cells 100", "--atol"),
    ("analytic --points 5", "--reset-velocity"),
];

/// The value `--help` of `path` prints as `flag`'s default: the first
/// word after `[default: ` in its entry.
fn printed_default(path: &[&str], flag: &str) -> String {
    let path: Vec<String> = path.iter().map(|s| s.to_string()).collect();
    let text = help(&path, "--help");
    let entry = text
        .split("\n      --")
        .chain(text.split("\n  -r, --"))
        .find(|e| e.starts_with(&flag[2..]) && e[flag.len() - 2..].starts_with([' ', '\n']))
        .unwrap_or_else(|| panic!("{path:?}: no {flag} in its help"));
    let after = entry
        .split("[default")
        .nth(1)
        .unwrap_or_else(|| panic!("{path:?} {flag}: no default printed: {entry}"));
    let value = after.trim_start_matches([':', ' ']);
    let value = value.strip_prefix("with --method euler: ").unwrap_or(value);
    value
        .split([';', ']', ' ', ','])
        .next()
        .unwrap()
        .to_string()
}

/// The JSON of a run, without what differs between runs (wall times) and
/// the command line it records.
fn answer(args: &[&str]) -> serde_json::Value {
    let o = Command::new(BIN).args(args).arg("--json").output().unwrap();
    assert!(o.status.success(), "{args:?}: {o:?}");
    let mut v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    v.as_object_mut().unwrap().remove("provenance");
    if let Some(r) = v.get_mut("results").and_then(|r| r.as_object_mut()) {
        r.retain(|k, _| !k.contains("wall") && !k.ends_with("per_s"));
    }
    v
}

#[test]
fn the_defaults_help_prints_are_the_codes() {
    for (line, flag) in TYPED_DEFAULTS {
        let base: Vec<&str> = line.split(' ').collect();
        let path: Vec<&str> = base
            .iter()
            .take_while(|a| !a.starts_with('-'))
            .copied()
            .collect();
        let value = printed_default(&path, flag);
        let with = [base.clone(), vec![flag, &value]].concat();
        assert_eq!(
            answer(&base),
            answer(&with),
            "{line}: {flag} {value} (the printed default) changes the answer"
        );
    }
}

#[test]
fn the_supported_combinations_in_help_are_the_support_tables() {
    let help = help(&["simulate".into()], "--help");
    for line in irtp_app::common::noise_runs_in().lines() {
        assert!(help.contains(line), "--noise: no `{line}` in {help}");
    }
    for f in [
        Feature::Position,
        Feature::RefractoryExp,
        Feature::RefractoryFixed,
        Feature::Periodic,
        Feature::Renewal,
    ] {
        let line = format!("runs in: {}.", runners(f));
        assert!(help.contains(&line), "{f:?}: no `{line}` in\n{help}");
    }
    // The list of what runs another noise names every method the table
    // lets run one.
    let rpt: NoiseModel =
        NoiseModel::new("rpt:sigma=1,alpha=1,beta=2".parse().unwrap(), 0.0).unwrap();
    let runners = irtp::capability::noise_runners(irtp::capability::NoiseClass::FiniteState);
    for s in Solver::ALL {
        if noise_support::supports(s, &rpt) {
            let (command, _) = s.parts();
            assert!(runners.contains(command), "{command}");
        }
    }
    assert!(!help.contains("Only `analytic` runs"), "{help}");
}

/// A library refusal as the binary prints it (parameter names as flags).
fn printed(e: &irtp::Error) -> String {
    let flag = |n: &str| match n.starts_with('-') {
        true => n.to_string(),
        false => format!("--{}", n.replace('_', "-")),
    };
    format!("irtp: error: {}", e.message_with(flag))
}

/// Every refusal the applies table ([`irtp_app::applies::RULES`]) and the
/// support tables (noise: every kind at T = 0 and T > 0 for every method
/// and the search; reset features: every feature for every method) can
/// produce, with a value as long as a message echoes.
fn table_refusals() -> Vec<String> {
    let value = "v".repeat(48);
    let mut out: Vec<String> = irtp_app::applies::RULES
        .iter()
        .map(|r| printed(&irtp::Error::invalid(r.flag, &value, r.when.describe())))
        .collect();
    let kinds = [
        "telegraph:sigma=3,lambda=0.5",
        "telegraph:plus=2,minus=-1,rate_plus=1,rate_minus=2",
        "rpt:sigma=1,alpha=1,beta=2",
        "states:levels=[1,0,-1],rates=[[-1,1,0],[1,-2,1],[0,1,-1]]",
        "none",
    ];
    for kind in kinds {
        for t in [0.0, 0.5] {
            let Ok(m) = NoiseModel::new(kind.parse().unwrap(), t) else {
                continue; // no noise at all (`none` at T = 0)
            };
            for s in Solver::ALL {
                out.extend(noise_support::check(s, &m).err().map(|e| printed(&e)));
            }
            let search = noise_support::refuse("a search (--xt, --interval)", &m);
            out.extend(search.err().map(|e| printed(&e)));
        }
    }
    let schedules = [
        Schedule::parse(None, Some(0.0), None),
        Schedule::parse(None, None, Some("exp:mean=1")),
        Schedule::parse(None, None, Some("fixed:t=1")),
        Schedule::parse(Some(1.0), None, None),
        Schedule::parse(None, None, None).and_then(|s| s.with_clock(Some("gamma:k=2,theta=1"))),
    ];
    let tan: DragLaw = "tan".parse().unwrap();
    for schedule in schedules {
        let p = Params::new(tan.clone(), 3.0, 0.5, 0.0, 0.0)
            .and_then(|p| p.with_schedule(schedule.unwrap()))
            .unwrap();
        for s in Solver::ALL {
            out.extend(p.require(s).err().map(|e| printed(&e)));
        }
    }
    out
}

#[test]
fn every_refusal_of_the_tables_is_one_short_line_naming_its_flag() {
    let all = table_refusals();
    let features = Solver::ALL.len() * 5;
    let refused = Solver::ALL
        .iter()
        .flat_map(|s| {
            [
                Feature::Position,
                Feature::RefractoryExp,
                Feature::RefractoryFixed,
                Feature::Periodic,
                Feature::Renewal,
            ]
            .map(|f| supports(*s, f))
        })
        .filter(|ok| !ok)
        .count();
    assert!(refused > 0 && refused < features);
    assert!(
        all.len() >= irtp_app::applies::RULES.len() + refused,
        "{}",
        all.len()
    );
    for msg in &all {
        assert!(!msg.contains('\n'), "{msg}");
        assert!(
            msg.chars().count() < 200,
            "{} chars: {msg}",
            msg.chars().count()
        );
        assert!(msg.contains(" --"), "no flag: {msg}");
    }
    let longest = all.iter().map(|m| m.chars().count()).max().unwrap();
    eprintln!(
        "{} refusals from the tables, the longest {longest} characters",
        all.len()
    );
}
