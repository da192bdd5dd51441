//! Keyword arguments (the Python module's keywords, a sweep plan's
//! parameters) → the equivalent `irtp` command line, parsed by the CLI's own
//! clap definitions ([`Cli`]): the keywords, their defaults, validation and
//! help text have one home, and the same keywords give the same numbers as
//! the same flags. The vocabulary is a type parameter ([`Vocabulary`]): a
//! sweep plan speaks this crate's [`Cli`]; the Python module speaks the full
//! program's (with `reproduce`, from the paper crate). A keyword is a flag without `--`, with `-` written `_`
//! (`--t-max` → `t_max`).

use super::Cli;
use clap::{Arg, ArgAction, Command, Parser};
use std::any::TypeId;
use std::cell::RefCell;
use std::collections::HashMap;

/// A command-line vocabulary keywords are read against: a clap parser and
/// the command paths it runs.
pub trait Vocabulary: Parser {
    /// The commands a keyword call can run (`"fp stationary"`).
    fn commands() -> Vec<&'static str>;
}

impl Vocabulary for Cli {
    fn commands() -> Vec<&'static str> {
        vec![
            "simulate",
            "analytic",
            "fp stationary",
            "fp transient",
            "fp msd",
            "mfpt",
            "mfpt scan",
            "mfpt optimize",
            "mfpt distribution",
        ]
    }
}

/// A keyword argument's value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// A switch (`true`: the flag is given).
    Bool(bool),
    /// An integer.
    Int(i128),
    /// A number (written in its shortest form that parses back exactly).
    Float(f64),
    /// A string or path.
    Str(String),
    /// Several positional values.
    List(Vec<String>),
}

/// Run `f` on this thread's built root command of vocabulary `C`, built
/// once: building the whole program's clap tree (and, in debug builds, its
/// consistency asserts) costs ~1 ms, which a plan of 10⁶ points paid
/// several times per point.
fn with_root<C: Vocabulary + 'static, R>(f: impl FnOnce(&mut Command) -> R) -> R {
    thread_local! {
        static ROOTS: RefCell<HashMap<TypeId, Command>> = RefCell::new(HashMap::new());
    }
    ROOTS.with(|roots| {
        let mut roots = roots.borrow_mut();
        let root = roots.entry(TypeId::of::<C>()).or_insert_with(|| {
            let mut c = C::command();
            c.build();
            c
        });
        f(root)
    })
}

/// Run `f` on the clap command of `irtp <path>` (`"fp stationary"`).
fn with_command<C: Vocabulary + 'static, R>(
    path: &str,
    f: impl FnOnce(&Command) -> R,
) -> Result<R, String> {
    let known = C::commands();
    if !known.contains(&path) {
        return Err(format!(
            "unknown command '{path}' (known: {})",
            known.join(", ")
        ));
    }
    with_root::<C, _>(|root| {
        let mut cur: &Command = root;
        for part in path.split(' ') {
            cur = cur
                .find_subcommand(part)
                .ok_or_else(|| format!("unknown command '{path}'"))?;
        }
        Ok(f(cur))
    })
}

/// The clap command of `irtp <path>` (`"fp stationary"`).
pub fn command<C: Vocabulary + 'static>(path: &str) -> Result<Command, String> {
    with_command::<C, _>(path, Command::clone)
}

/// How an error names a command: its Python function (`fp stationary` →
/// `irtp.fp_stationary`).
pub fn function(path: &str) -> String {
    format!("irtp.{}", path.replace(' ', "_"))
}

/// The arguments a Python function takes: every flag but help, version and
/// `--json` (Python has the result itself).
pub fn keywords(cmd: &Command) -> Vec<&Arg> {
    cmd.get_arguments()
        .filter(|a| !matches!(a.get_id().as_str(), "help" | "version" | "json"))
        .collect()
}

/// The kind of value a keyword takes: bool, int, float, list, path or str.
pub fn kind(a: &Arg) -> &'static str {
    if matches!(a.get_action(), ArgAction::SetTrue) {
        return "bool";
    }
    if a.is_positional() {
        return "list";
    }
    let id = a.get_value_parser().type_id();
    if id == TypeId::of::<f64>() {
        "float"
    } else if id == TypeId::of::<u64>() || id == TypeId::of::<usize>() {
        "int"
    } else if id == TypeId::of::<std::path::PathBuf>() {
        "path"
    } else {
        "str"
    }
}

/// `irtp <path> --flag value ...` for the given keywords (in their order);
/// an unknown keyword or a value of the wrong kind is an error naming it.
pub fn build<C: Vocabulary + 'static>(
    path: &str,
    options: Vec<(String, Value)>,
) -> Result<Vec<String>, String> {
    with_command::<C, _>(path, |cmd| {
        let args = keywords(cmd);
        let mut argv: Vec<String> = std::iter::once("irtp")
            .chain(path.split(' '))
            .map(String::from)
            .collect();
        for (name, value) in options {
            let Some(arg) = args.iter().find(|a| a.get_id().as_str() == name) else {
                let known: Vec<&str> = args.iter().map(|a| a.get_id().as_str()).collect();
                return Err(format!(
                    "unknown keyword '{name}' for {} (known: {})",
                    function(path),
                    known.join(", ")
                ));
            };
            push(&mut argv, arg, &name, value)?;
        }
        Ok(argv)
    })?
}

/// Append one keyword's flag and value.
fn push(argv: &mut Vec<String>, arg: &Arg, name: &str, value: Value) -> Result<(), String> {
    let flag = || format!("--{}", arg.get_long().unwrap_or(name));
    match (kind(arg), value) {
        ("bool", Value::Bool(true)) => argv.push(flag()),
        ("bool", Value::Bool(false)) => {}
        ("bool", _) => return Err(format!("invalid {name}: allowed True or False")),
        ("list", Value::List(items)) => argv.extend(items),
        ("list", Value::Str(s)) => argv.push(s),
        (_, Value::Bool(b)) => {
            return Err(format!("invalid {name} = {b}: allowed a {}", kind(arg)));
        }
        (_, v) => {
            argv.push(flag());
            argv.push(match v {
                Value::Int(i) => i.to_string(),
                // Shortest representation that parses back to the same f64.
                Value::Float(x) => format!("{x:?}"),
                Value::Str(s) => s,
                Value::List(items) => items.join(","),
                Value::Bool(_) => unreachable!("handled above"),
            });
        }
    }
    Ok(())
}

/// Parse a command line built by [`build`]; a clap error becomes one line
/// naming keywords instead of flags.
pub fn parse<C: Vocabulary + 'static>(path: &str, argv: &[String]) -> Result<C, String> {
    let parsed = with_root::<C, _>(|root| {
        let mut m = root.try_get_matches_from_mut(argv)?;
        // A flag that does not apply is refused as the binary refuses it.
        if let Err(e) = crate::applies::check(&m) {
            return Ok(Err(e));
        }
        C::from_arg_matches_mut(&mut m)
            .map(Ok)
            .map_err(|e| e.format(root))
    });
    let parsed = match parsed {
        Ok(Err(e)) => {
            let msg = e.message_with(|n| format!("--{}", n.replace('_', "-")));
            return Err(flags_to_keywords::<C>(path, &msg));
        }
        Ok(Ok(c)) => Ok(c),
        Err(e) => Err(e),
    };
    parsed.map_err(|e| {
        // The message up to clap's usage line, on one line.
        let rendered = e.render().to_string();
        let lines: Vec<&str> = rendered
            .lines()
            .map(str::trim)
            .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("tip:"))
            .filter(|l| !l.is_empty())
            .collect();
        let text = lines.join(" ");
        flags_to_keywords::<C>(path, text.strip_prefix("error: ").unwrap_or(&text))
    })
}

/// Replace `--flag <VALUE>` and `--flag` by the keyword names.
pub fn flags_to_keywords<C: Vocabulary + 'static>(path: &str, text: &str) -> String {
    let Ok(cmd) = command::<C>(path) else {
        return text.to_string();
    };
    let mut pairs: Vec<(String, String)> = Vec::new();
    for a in keywords(&cmd) {
        let id = a.get_id().as_str().to_string();
        if let Some(long) = a.get_long() {
            for v in a.get_value_names().unwrap_or_default() {
                pairs.push((format!("--{long} <{v}>"), id.clone()));
            }
            pairs.push((format!("--{long}"), id.clone()));
        }
    }
    pairs.sort_by_key(|(f, _)| std::cmp::Reverse(f.len()));
    let mut out = text.to_string();
    for (f, id) in pairs {
        out = out.replace(&f, &id);
    }
    out
}
