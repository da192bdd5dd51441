//! Which flag applies where: one table ([`RULES`]) of the flags that only
//! some methods, schemes, grids or targets of a command use. A flag the user
//! typed (clap's [`ValueSource::CommandLine`]) where its rule does not hold
//! is refused, never ignored: one line naming the flag and where it applies
//! ([`check`], run by every front end on its parsed command line).

use clap::parser::ValueSource;
use clap::ArgMatches;
use irtp::Error;

/// When a flag applies.
#[derive(Clone, Copy, Debug)]
pub enum When {
    /// The flag `--ID` (clap id `ID`) was given one of these values, or has
    /// it as its default (an absent flag without a default holds none).
    Value(&'static str, &'static [&'static str]),
    /// A search target in position (`--xt` or `--interval`).
    Search,
    /// A target velocity (neither `--xt` nor `--interval`).
    Velocity,
    /// Both conditions.
    Both(&'static When, &'static When),
    /// Never in this command; the refusal (`not with ...`).
    Never(&'static str),
}

/// One flag of one command and when it applies.
#[derive(Clone, Copy, Debug)]
pub struct Rule {
    /// The command path (`"mfpt scan"`).
    pub command: &'static str,
    /// The flag as typed (`"--cells-x"`).
    pub flag: &'static str,
    /// When it applies.
    pub when: When,
}

const PARTICLES: When = When::Value("method", &["euler", "exact"]);
const EULER: When = When::Value("method", &["euler"]);
const EXACT: When = When::Value("method", &["exact"]);
const BACKWARD: When = When::Value("method", &["backward"]);
const MESH_SEARCH: When = When::Both(
    &When::Search,
    &When::Value("method", &["backward", "renewal"]),
);
const DIST_MESH_SEARCH: When = When::Both(&When::Search, &BACKWARD);
const DIST_LOG: When = When::Both(&BACKWARD, &When::Value("grid", &["log"]));
const DETERMINISTIC: When =
    When::Never("not with a deterministic solver (only particle methods take a seed)");

/// Shorthand for a row of [`RULES`].
const fn rule(command: &'static str, flag: &'static str, when: When) -> Rule {
    Rule {
        command,
        flag,
        when,
    }
}

/// Every flag that applies only somewhere (a flag not listed applies
/// wherever its command takes it).
pub const RULES: &[Rule] = &[
    rule("simulate", "--dt", EULER),
    rule("simulate", "--events", EULER),
    rule("simulate", "--t-min", When::Value("grid", &["log"])),
    rule("fp stationary", "--seed", DETERMINISTIC),
    rule("fp transient", "--seed", DETERMINISTIC),
    rule("fp transient", "--cfl", When::Value("scheme", &["paper"])),
    rule("fp transient", "--rtol", When::Value("scheme", &["trbdf2"])),
    rule("fp transient", "--atol", When::Value("scheme", &["trbdf2"])),
    rule("fp msd", "--seed", DETERMINISTIC),
    rule("mfpt", "--particles", PARTICLES),
    rule("mfpt", "--t-max", PARTICLES),
    rule("mfpt", "--seed", PARTICLES),
    rule("mfpt", "--dt", EULER),
    rule("mfpt", "--time-steps", When::Value("method", &["renewal"])),
    rule(
        "mfpt",
        "--horizon-tail",
        When::Value("method", &["renewal"]),
    ),
    rule("mfpt", "--cells", When::Velocity),
    rule("mfpt", "--x0", When::Search),
    rule("mfpt", "--cells-x", MESH_SEARCH),
    rule("mfpt", "--cells-v", MESH_SEARCH),
    rule("mfpt scan", "--particles", PARTICLES),
    rule("mfpt scan", "--t-max", PARTICLES),
    rule("mfpt scan", "--seed", PARTICLES),
    rule("mfpt scan", "--dt", EULER),
    rule(
        "mfpt scan",
        "--vt",
        When::Both(&When::Velocity, &When::Value("over", &["rate"])),
    ),
    rule("mfpt scan", "--cells", When::Velocity),
    rule("mfpt scan", "--x0", When::Search),
    rule("mfpt scan", "--cells-x", When::Search),
    rule("mfpt scan", "--cells-v", When::Search),
    rule(
        "mfpt optimize",
        "--rate",
        When::Never("not with mfpt optimize, which searches r over {0} ∪ [--r-min, --r-max]"),
    ),
    rule("mfpt optimize", "--seed", DETERMINISTIC),
    rule("mfpt optimize", "--cells", When::Velocity),
    rule("mfpt optimize", "--x0", When::Search),
    rule("mfpt optimize", "--cells-x", When::Search),
    rule("mfpt optimize", "--cells-v", When::Search),
    rule("mfpt distribution", "--points", BACKWARD),
    rule("mfpt distribution", "--grid", BACKWARD),
    rule("mfpt distribution", "--rtol", BACKWARD),
    rule("mfpt distribution", "--t-min", DIST_LOG),
    rule("mfpt distribution", "--particles", EXACT),
    rule("mfpt distribution", "--seed", EXACT),
    rule("mfpt distribution", "--x0", When::Search),
    rule("mfpt distribution", "--cells-x", DIST_MESH_SEARCH),
    rule("mfpt distribution", "--cells-v", DIST_MESH_SEARCH),
];

impl When {
    /// Whether the condition holds for the matches of the command.
    pub fn holds(&self, m: &ArgMatches) -> bool {
        match self {
            When::Value(id, values) => raw(m, id).is_some_and(|v| values.contains(&v.as_str())),
            When::Search => typed(m, "xt") || typed(m, "interval"),
            When::Velocity => !(typed(m, "xt") || typed(m, "interval")),
            When::Both(a, b) => a.holds(m) && b.holds(m),
            When::Never(_) => false,
        }
    }

    /// Where the flag applies, in words (`only with --method euler or
    /// exact`).
    pub fn describe(&self) -> String {
        match self {
            When::Never(why) => why.to_string(),
            other => format!("only with {}", other.condition()),
        }
    }

    /// The condition in words (`--method euler or exact`).
    fn condition(&self) -> String {
        match self {
            When::Value(id, values) => {
                format!("--{} {}", id.replace('_', "-"), values.join(" or "))
            }
            When::Search => "a search target (--xt or --interval)".into(),
            When::Velocity => "a target velocity (not with --xt or --interval)".into(),
            When::Both(a, b) => format!("{} and {}", a.condition(), b.condition()),
            When::Never(why) => why.to_string(),
        }
    }
}

/// Whether the flag of clap id `id` was typed on the command line.
fn typed(m: &ArgMatches, id: &str) -> bool {
    m.try_contains_id(id).unwrap_or(false) && m.value_source(id) == Some(ValueSource::CommandLine)
}

/// The value of the flag of clap id `id`, typed or its default, as typed
/// (an alias spelt as its value: `ode` is `backward`).
fn raw(m: &ArgMatches, id: &str) -> Option<String> {
    let mut values = m.try_get_raw(id).ok().flatten()?;
    let v = values.next()?.to_string_lossy().to_lowercase();
    Some(if v == "ode" { "backward".into() } else { v })
}

/// The command path of the matches of the whole program (`"mfpt scan"`)
/// and the matches of its innermost subcommand.
pub fn command_path(root: &ArgMatches) -> (String, &ArgMatches) {
    let mut path = Vec::new();
    let mut cur = root;
    while let Some((name, sub)) = cur.subcommand() {
        path.push(name);
        cur = sub;
    }
    (path.join(" "), cur)
}

/// Refuse a typed flag that does not apply ([`RULES`]); `root`: the
/// matches of the whole program.
pub fn check(root: &ArgMatches) -> irtp::Result<()> {
    let (path, m) = command_path(root);
    for r in RULES.iter().filter(|r| r.command == path) {
        let id = r.flag.trim_start_matches('-').replace('-', "_");
        if typed(m, &id) && !r.when.holds(m) {
            let value = raw(m, &id).unwrap_or_default();
            let value = if value.is_empty() {
                "given".into()
            } else {
                value
            };
            return Err(Error::invalid(r.flag, value, r.when.describe()));
        }
    }
    Ok(())
}
