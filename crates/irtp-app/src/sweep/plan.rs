//! A sweep plan: one command, fixed parameters and grid axes, read from TOML
//! and checked whole (every key, every grid point) before any work.
//!
//! ```toml
//! command = "fp stationary"     # simulate, analytic, fp stationary, fp transient, mfpt, mfpt optimize
//! seed = 1                      # plan seed: each point's seed derives from it and the point
//! particle_parts = 4            # simulate, mfpt by particles: each point's particles in 4 work items
//!
//! [fixed]                       # keywords = the command's flags (`--t-max` → t_max)
//! drag = "tan"
//! cells = 2000
//!
//! [axes]                        # crossed with each other (first axis slowest)
//! sigma = [1.0, 2.0, 3.0]
//! rate = { from = 0.1, to = 10.0, points = 5, spacing = "log" }   # or "linear"
//!
//! [[zip]]                       # axes that advance together, crossed with the rest
//! lambda = [0.5, 1.0]
//! reset_velocity = [0.0, 0.1]
//! ```

use crate::keywords::{self, Value};
use irtp::error::{Error, Result};
use irtp::numerics::grid::{linspace, logspace};
use serde::Deserialize;
use sha2::{Digest, Sha256};

/// The commands a sweep runs.
pub const SWEEPABLE: [&str; 6] = [
    "simulate",
    "analytic",
    "fp stationary",
    "fp transient",
    "mfpt",
    "mfpt optimize",
];

/// Keywords a plan may not set: the sweep owns them.
const RESERVED: [(&str, &str); 3] = [
    (
        "seed",
        "set the plan's top-level `seed`; each point's seed derives from it",
    ),
    ("out", "the sweep writes each point into its own directory"),
    (
        "force",
        "the sweep owns each point's directory (a rerun resumes; --retry-failed recomputes failed points)",
    ),
];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPlan {
    command: String,
    #[serde(default = "default_seed")]
    seed: u64,
    particle_parts: Option<u64>,
    #[serde(default)]
    fixed: toml::Table,
    #[serde(default)]
    axes: toml::Table,
    #[serde(default)]
    zip: Vec<toml::Table>,
}

fn default_seed() -> u64 {
    1
}

/// A range axis: `{ from, to, points, spacing }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Range {
    from: f64,
    to: f64,
    points: usize,
    #[serde(default)]
    spacing: Spacing,
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum Spacing {
    #[default]
    Linear,
    Log,
}

/// Axes that advance together (one crossed axis is a group of one).
#[derive(Clone, Debug)]
struct Group {
    names: Vec<String>,
    /// `rows[i][j]`: value of `names[j]` at the group's i-th step.
    rows: Vec<Vec<Value>>,
}

/// A validated plan.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The command (`fp stationary`).
    pub command: String,
    /// The plan seed.
    pub seed: u64,
    /// Work items per point (simulate only; 1 otherwise).
    pub particle_parts: u64,
    /// The fixed keywords, in plan order.
    pub fixed: Vec<(String, Value)>,
    groups: Vec<Group>,
    /// Whether the command takes a seed.
    pub seeded: bool,
    /// The plan's TOML text, as given.
    pub text: String,
}

/// One grid point.
#[derive(Clone, Debug)]
pub struct Point {
    /// Position in the plan (0-based; plan order).
    pub index: usize,
    /// Axis values then fixed values, in plan order.
    pub params: Vec<(String, Value)>,
    /// The seed derived from (plan seed, parameters), when the command takes one.
    pub seed: Option<u64>,
    /// Identifier: signac's job id of the statepoint (32 hex digits of its MD5).
    pub id: String,
}

/// A plan error: `InvalidParameter` naming the plan key.
fn bad(key: &str, value: impl std::fmt::Display, allowed: impl Into<String>) -> Error {
    let value = one_line(&value.to_string());
    let value = match value.char_indices().nth(120) {
        Some((i, _)) => format!("{}…", &value[..i]),
        None => value,
    };
    Error::InvalidParameter {
        name: "plan",
        value: format!("{key} = {value}"),
        allowed: one_line(&allowed.into()),
    }
}

/// Whitespace runs (a TOML error's line breaks among them) as one space.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A TOML value for a message: numbers in their shortest form (toml
/// prints 1e300 as 301 digits), tables and arrays inline.
fn shown(v: &toml::Value) -> String {
    let join = |items: Vec<String>| items.join(", ");
    match v {
        toml::Value::Float(x) => crate::io::format_float(*x),
        toml::Value::Array(a) => format!("[{}]", join(a.iter().map(shown).collect())),
        toml::Value::Table(t) => format!(
            "{{ {} }}",
            join(
                t.iter()
                    .map(|(k, v)| format!("{k} = {}", shown(v)))
                    .collect()
            )
        ),
        other => other.to_string(),
    }
}

/// A TOML scalar as a keyword value.
fn scalar(key: &str, v: &toml::Value) -> Result<Value> {
    match v {
        toml::Value::Boolean(b) => Ok(Value::Bool(*b)),
        toml::Value::Integer(i) => Ok(Value::Int(*i as i128)),
        toml::Value::Float(x) => Ok(Value::Float(*x)),
        toml::Value::String(s) => Ok(Value::Str(s.clone())),
        other => Err(bad(key, shown(other), "a number, string or boolean")),
    }
}

/// An axis: a list of scalars or a range table.
fn axis(key: &str, v: &toml::Value) -> Result<Vec<Value>> {
    let values = match v {
        toml::Value::Array(items) => items
            .iter()
            .map(|x| scalar(key, x))
            .collect::<Result<_>>()?,
        toml::Value::Table(t) => {
            let r: Range = t.clone().try_into().map_err(|e| {
                bad(
                    key,
                    shown(v),
                    format!("a list or {{ from, to, points, spacing }} ({e})"),
                )
            })?;
            range(key, &r)?
        }
        other => {
            return Err(bad(
                key,
                shown(other),
                "a list or a { from, to, points, spacing } table",
            ))
        }
    };
    if values.is_empty() {
        return Err(bad(key, "[]", "a non-empty axis"));
    }
    Ok(values)
}

/// The most points a plan may have: counted from its axes before any point
/// is built or checked (each point's parameters are validated as the
/// command would, about 10 µs each).
pub const MAX_POINTS: usize = 1_000_000;

fn range(key: &str, r: &Range) -> Result<Vec<Value>> {
    let text = format!(
        "{{ from = {}, to = {}, points = {} }}",
        crate::io::format_float(r.from),
        crate::io::format_float(r.to),
        r.points
    );
    if !(r.from.is_finite() && r.to.is_finite()) || r.points == 0 {
        return Err(bad(key, text, "finite from and to, points >= 1"));
    }
    if r.points > MAX_POINTS {
        return Err(bad(
            key,
            text,
            format!("points <= {MAX_POINTS} (a plan has at most {MAX_POINTS} points)"),
        ));
    }
    let xs = match r.spacing {
        Spacing::Linear if r.points == 1 => vec![r.from],
        Spacing::Linear => linspace(r.from, r.to, r.points),
        Spacing::Log if !(r.from > 0.0 && r.to > 0.0) => {
            return Err(bad(key, text, "from > 0 and to > 0 with spacing = \"log\""));
        }
        Spacing::Log if r.points == 1 => vec![r.from],
        Spacing::Log => logspace(r.from, r.to, r.points),
    };
    Ok(xs.into_iter().map(Value::Float).collect())
}

/// Every axis's values (a zipped group's rows) distinct: a value given
/// twice, or a zipped row repeated, would be one point computed twice.
fn check_distinct(groups: &[Group]) -> Result<()> {
    for g in groups {
        let mut seen = std::collections::HashSet::new();
        for row in &g.rows {
            if !seen.insert(format!("{row:?}")) {
                let shown: Vec<String> = row.iter().map(text).collect();
                return Err(bad(
                    &g.names.join("+"),
                    shown.join(", "),
                    "distinct values on an axis (this one appears twice: one point would run twice)",
                ));
            }
        }
    }
    Ok(())
}

/// The product of the axes' lengths, refused above [`MAX_POINTS`] (naming
/// every axis and its length) before anything is enumerated.
fn count_points(groups: &[Group]) -> Result<usize> {
    let n = groups.iter().try_fold(1usize, |n, g| {
        n.checked_mul(g.rows.len()).filter(|&n| n <= MAX_POINTS)
    });
    n.ok_or_else(|| {
        let axes: Vec<String> = groups
            .iter()
            .map(|g| format!("{} ({})", g.names.join("+"), g.rows.len()))
            .collect();
        bad(
            "axes",
            axes.join(" x "),
            format!("at most {MAX_POINTS} points in a plan (split it into several plans)"),
        )
    })
}

/// A TOML error in one line, with the line it is on (`line 2: seed = -1:
/// invalid value ...`), so the key that was typed is named.
fn toml_error(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().lines().next().unwrap_or("").trim().to_string();
    let Some(span) = e.span() else {
        return message;
    };
    let start = span.start.min(text.len());
    let line_no = text[..start].matches('\n').count() + 1;
    let line = text.lines().nth(line_no - 1).unwrap_or("").trim();
    let shown: String = line.chars().take(80).collect();
    format!("line {line_no} (`{shown}`): {message}")
}

impl Plan {
    /// Parse and check a plan: keys, types, axes, and every grid point's
    /// parameters as the command would check them.
    pub fn parse(text: &str) -> Result<Plan> {
        let raw: RawPlan = toml::from_str(text).map_err(|e| Error::InvalidParameter {
            name: "plan",
            value: toml_error(text, &e),
            allowed: "a plan as in docs/sweeps.md".into(),
        })?;
        let plan = Plan::from_raw(raw, text)?;
        plan.check_points()?;
        Ok(plan)
    }

    fn from_raw(raw: RawPlan, text: &str) -> Result<Plan> {
        if !SWEEPABLE.contains(&raw.command.as_str()) {
            return Err(bad(
                "command",
                &raw.command,
                format!("one of {}", SWEEPABLE.join(", ")),
            ));
        }
        let cmd = keywords::command::<crate::Cli>(&raw.command)
            .map_err(|e| bad("command", &raw.command, e))?;
        let known: Vec<String> = keywords::keywords(&cmd)
            .iter()
            .map(|a| a.get_id().to_string())
            .collect();
        let seeded = known.iter().any(|k| k == "seed");
        let parts = raw.particle_parts.unwrap_or(1);
        if parts == 0 || (parts > 1 && !["simulate", "mfpt"].contains(&raw.command.as_str())) {
            return Err(bad(
                "particle_parts",
                parts,
                "1, or >= 1 with command = \"simulate\" or \"mfpt\" (by particles)",
            ));
        }
        let mut names: Vec<String> = Vec::new();
        let mut claim = |key: &str| -> Result<()> {
            if let Some((_, why)) = RESERVED.iter().find(|(r, _)| *r == key) {
                return Err(bad(key, "…", format!("not set by a plan: {why}")));
            }
            if !known.iter().any(|k| k == key) {
                return Err(bad(
                    key,
                    "…",
                    format!("a keyword of `irtp {}`: {}", raw.command, known.join(", ")),
                ));
            }
            if names.iter().any(|n| n == key) {
                return Err(bad(key, "…", "one of [fixed], [axes], [[zip]] only, once"));
            }
            names.push(key.to_string());
            Ok(())
        };
        let mut groups = Vec::new();
        for (k, v) in &raw.axes {
            claim(k)?;
            let rows = axis(k, v)?.into_iter().map(|x| vec![x]).collect();
            groups.push(Group {
                names: vec![k.clone()],
                rows,
            });
        }
        for z in &raw.zip {
            groups.push(zipped(z, &mut claim)?);
        }
        count_points(&groups)?;
        check_distinct(&groups)?;
        let mut fixed = Vec::new();
        for (k, v) in &raw.fixed {
            claim(k)?;
            fixed.push((k.clone(), scalar(k, v)?));
        }
        Ok(Plan {
            command: raw.command,
            seed: raw.seed,
            particle_parts: parts,
            fixed,
            groups,
            seeded,
            text: text.to_string(),
        })
    }

    /// Number of grid points (at most [`MAX_POINTS`], checked when parsed).
    pub fn len(&self) -> usize {
        self.groups.iter().map(|g| g.rows.len()).product()
    }

    /// Whether the plan has no points (never: axes are non-empty).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The crossed axes in plan order (the first varies slowest), each as
    /// its parameter names (one for an `[axes]` entry, several for a
    /// `[[zip]]` group) and its number of values.
    pub fn crossed(&self) -> Vec<(Vec<String>, usize)> {
        self.groups
            .iter()
            .map(|g| (g.names.clone(), g.rows.len()))
            .collect()
    }

    /// The parameter names of every point: axes (plan order), then fixed.
    pub fn names(&self) -> Vec<String> {
        let axes = self.groups.iter().flat_map(|g| g.names.iter().cloned());
        axes.chain(self.fixed.iter().map(|(k, _)| k.clone()))
            .collect()
    }

    /// Grid point `index` (plan order: the first axis varies slowest).
    pub fn point(&self, index: usize) -> Point {
        let mut params = Vec::new();
        let mut rest = index;
        let mut picks = vec![0; self.groups.len()];
        for (i, g) in self.groups.iter().enumerate().rev() {
            picks[i] = rest % g.rows.len();
            rest /= g.rows.len();
        }
        for (g, &pick) in self.groups.iter().zip(&picks) {
            params.extend(g.names.iter().cloned().zip(g.rows[pick].iter().cloned()));
        }
        params.extend(self.fixed.iter().cloned());
        let seed =
            (self.seeded && self.draws_random_numbers(&params)).then(|| self.point_seed(&params));
        let id = super::signac::calc_id(&statepoint(&self.command, &params, seed));
        Point {
            index,
            params,
            seed,
            id,
        }
    }

    /// All points, in plan order.
    pub fn points(&self) -> impl Iterator<Item = Point> + '_ {
        (0..self.len()).map(|i| self.point(i))
    }

    /// Whether the point's computation is random (a particle method): only
    /// then it gets a seed (a deterministic solver refuses `--seed`). A point
    /// whose flags do not parse counts as random; `check_points` reports it.
    fn draws_random_numbers(&self, params: &[(String, Value)]) -> bool {
        keywords::build::<crate::Cli>(&self.command, params.to_vec())
            .ok()
            .and_then(|argv| keywords::parse::<crate::Cli>(&self.command, &argv).ok())
            .map_or(true, |cli| crate::uses_seed(&cli.command))
    }

    /// The seed of a point: the first 8 bytes of SHA-256(plan seed,
    /// parameters); adding points to a plan never changes existing ones.
    fn point_seed(&self, params: &[(String, Value)]) -> u64 {
        let text = format!("irtp sweep seed {} {}", self.seed, canonical(params));
        let h = Sha256::digest(text);
        u64::from_le_bytes(h[..8].try_into().expect("8 bytes"))
    }

    /// Check every point as the command would, before any work.
    fn check_points(&self) -> Result<()> {
        for p in self.points() {
            let argv = self
                .argv(&p, None)
                .map_err(|e| at_point(&p, bad("parameters", "…", e)))?;
            let cli = keywords::parse::<crate::Cli>(&self.command, &argv)
                .map_err(|e| at_point(&p, bad("parameters", "…", e)))?;
            crate::validate(&cli.command).map_err(|e| at_point(&p, e))?;
            super::parts::check(self, &p, &cli)?;
        }
        Ok(())
    }

    /// The point's command line (`out`: its output directory).
    pub fn argv(
        &self,
        p: &Point,
        out: Option<&std::path::Path>,
    ) -> std::result::Result<Vec<String>, String> {
        let mut opts = p.params.clone();
        if let Some(s) = p.seed {
            opts.push(("seed".into(), Value::Int(s as i128)));
        }
        if let Some(dir) = out {
            opts.push(("out".into(), Value::Str(dir.display().to_string())));
            // The point directory also holds the sweep's own files
            // (statepoint, parts, result), which the command leaves alone.
            opts.push(("force".into(), Value::Bool(true)));
        }
        keywords::build::<crate::Cli>(&self.command, opts)
    }
}

/// A `[[zip]]` table: axes of equal length advancing together.
fn zipped(z: &toml::Table, claim: &mut impl FnMut(&str) -> Result<()>) -> Result<Group> {
    let mut names = Vec::new();
    let mut columns: Vec<Vec<Value>> = Vec::new();
    for (k, v) in z {
        claim(k)?;
        let col = axis(k, v)?;
        if let Some(first) = columns.first() {
            if col.len() != first.len() {
                return Err(bad(
                    k,
                    format!("{} values", col.len()),
                    format!(
                        "as many values as `{}` ({}) in its [[zip]]",
                        names[0],
                        first.len()
                    ),
                ));
            }
        }
        names.push(k.clone());
        columns.push(col);
    }
    if names.is_empty() {
        return Err(bad("zip", "{}", "at least one axis in each [[zip]]"));
    }
    let rows = (0..columns[0].len())
        .map(|i| columns.iter().map(|c| c[i].clone()).collect())
        .collect();
    Ok(Group { names, rows })
}

/// A point error: the message prefixed with the point and its parameters.
fn at_point(p: &Point, e: Error) -> Error {
    let msg = e.message_with(|n| n.to_string());
    Error::InvalidParameter {
        name: "plan",
        value: format!("point {} ({})", p.index, describe(&p.params)),
        allowed: format!("parameters the command accepts: {msg}"),
    }
}

/// `sigma = 3, rate = 0.1` for messages.
pub fn describe(params: &[(String, Value)]) -> String {
    let parts: Vec<String> = params
        .iter()
        .map(|(k, v)| format!("{k} = {}", text(v)))
        .collect();
    parts.join(", ")
}

/// A value as the CSV and messages show it.
pub fn text(v: &Value) -> String {
    match v {
        Value::Bool(b) => b.to_string(),
        Value::Int(i) => i.to_string(),
        Value::Float(x) => crate::io::format_float(*x),
        Value::Str(s) => s.clone(),
        Value::List(items) => items.join(" "),
    }
}

/// A value as JSON.
pub fn json(v: &Value) -> serde_json::Value {
    match v {
        Value::Bool(b) => (*b).into(),
        Value::Int(i) => serde_json::Value::from(*i as i64),
        Value::Float(x) => (*x).into(),
        Value::Str(s) => s.clone().into(),
        Value::List(items) => items.clone().into(),
    }
}

/// Parameters as a JSON object with sorted keys (canonical text).
fn canonical(params: &[(String, Value)]) -> serde_json::Value {
    let sorted: std::collections::BTreeMap<&str, serde_json::Value> =
        params.iter().map(|(k, v)| (k.as_str(), json(v))).collect();
    serde_json::to_value(sorted).expect("JSON of scalars")
}

/// The id irtp gave a point before ids were signac's: the first 32 hex
/// digits of the SHA-256 of the statepoint's compact JSON. A sweep
/// directory written then is renamed to the new ids when opened.
pub fn legacy_id(statepoint: &serde_json::Value) -> String {
    hex(&Sha256::digest(statepoint.to_string()))[..32].to_string()
}

/// The statepoint of a point (its `signac_statepoint.json`): the command,
/// its parameters (keys sorted) and its seed. The point's id is signac's
/// job id of it ([`super::signac::calc_id`]).
pub fn statepoint(
    command: &str,
    params: &[(String, Value)],
    seed: Option<u64>,
) -> serde_json::Value {
    serde_json::json!({"command": command, "parameters": canonical(params), "seed": seed})
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
