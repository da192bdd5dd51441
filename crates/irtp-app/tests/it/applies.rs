//! Which flag applies where (`irtp_app::applies`): every rule refuses its
//! flag exactly where it does not hold.

use clap::CommandFactory;
use irtp_app::applies::{check, command_path, Rule, When, RULES};

/// A command line of `command` with a velocity or a search target.
fn base(command: &str, search: bool) -> Vec<String> {
    let mut argv: Vec<&str> = vec!["irtp"];
    argv.extend(command.split(' '));
    if command == "fp transient" {
        argv.extend(["--t-max", "1"]);
    }
    if command.starts_with("mfpt") {
        argv.extend(["--v0", "0"]);
        match (command, search) {
            ("mfpt scan", true) => argv.extend(["--xt", "1", "--over", "x0"]),
            ("mfpt scan", false) => argv.extend(["--over", "vt"]),
            (_, true) => argv.extend(["--xt", "1"]),
            (_, false) => argv.extend(["--vt", "1"]),
        }
        if command == "mfpt scan" {
            argv.extend(["--from", "0.5", "--to", "1"]);
        }
    }
    argv.into_iter().map(String::from).collect()
}

/// The clap ids a condition reads its values from.
fn ids(w: &When, out: &mut Vec<&'static str>) {
    match w {
        When::Value(id, _) => out.push(id),
        When::Both(a, b) => {
            ids(a, out);
            ids(b, out);
        }
        _ => {}
    }
}

/// Every command line of the rule's command with its flag typed: both
/// targets, and every value of each flag its condition reads.
fn variants(r: &Rule) -> Vec<Vec<String>> {
    let root = irtp_app::Cli::command();
    let mut cmd = &root;
    for part in r.command.split(' ') {
        cmd = cmd
            .find_subcommand(part)
            .expect("the rule's command exists");
    }
    let arg = |id: &str| cmd.get_arguments().find(|a| a.get_id() == id).cloned();
    let flag = arg(&r.flag[2..].replace('-', "_")).expect("the rule's flag exists");
    let value = flag
        .get_possible_values()
        .first()
        .map_or("1".to_string(), |v| v.get_name().to_string());
    let mut lines = vec![];
    for search in [false, true] {
        lines.push(base(r.command, search));
    }
    let mut conds = vec![];
    ids(&r.when, &mut conds);
    if conds.contains(&"over") {
        for l in &mut lines {
            let i = l.iter().position(|a| a == "--over").expect("a scan's base");
            l.drain(i..i + 2);
        }
    }
    for id in conds {
        let values = arg(id)
            .expect("the condition's flag exists")
            .get_possible_values();
        lines = lines
            .iter()
            .flat_map(|l| {
                values.iter().map(move |v| {
                    let mut l = l.clone();
                    l.extend([format!("--{}", id.replace('_', "-")), v.get_name().into()]);
                    l
                })
            })
            .collect();
    }
    for l in &mut lines {
        l.extend([r.flag.to_string(), value.clone()]);
    }
    lines
}

#[test]
fn every_rule_refuses_where_it_does_not_apply_and_only_there() {
    for r in RULES {
        let (mut refused, mut accepted) = (0, 0);
        for argv in variants(r) {
            let Ok(m) = irtp_app::Cli::command().try_get_matches_from(&argv) else {
                continue; // a combination clap itself refuses
            };
            match check(&m) {
                Err(e) if !e.to_string().starts_with(&format!("invalid {} ", r.flag)) => {
                    continue; // a flag of the condition refused by its own rule
                }
                Err(e) => {
                    let msg = e.to_string();
                    assert!(msg.contains(" with "), "{argv:?}: {msg}");
                    assert!(!r.when.holds(command_path(&m).1), "{argv:?}");
                    refused += 1;
                }
                Ok(()) => {
                    assert!(r.when.holds(command_path(&m).1), "{argv:?}");
                    accepted += 1;
                }
            }
        }
        assert!(refused > 0, "{} {} is never refused", r.command, r.flag);
        let never = matches!(r.when, When::Never(_));
        assert!(
            never || accepted > 0,
            "{} {} is never accepted",
            r.command,
            r.flag
        );
    }
}

#[test]
fn a_default_is_not_typed_and_an_alias_is_its_value() {
    let m = irtp_app::Cli::command()
        .try_get_matches_from(["irtp", "mfpt", "--v0", "0", "--vt", "1", "--method", "ode"])
        .unwrap();
    assert!(check(&m).is_ok());
    // `mfpt`'s default method: the rules' condition `BACKWARD`.
    let backward = When::Value("method", &["backward"]);
    assert!(backward.holds(command_path(&m).1));
    let m = irtp_app::Cli::command()
        .try_get_matches_from(["irtp", "mfpt", "--v0", "0", "--vt", "1", "--cells-x", "8"])
        .unwrap();
    let msg = check(&m).unwrap_err().to_string();
    assert!(msg.starts_with("invalid --cells-x = 8: allowed only with a search target"));
}
