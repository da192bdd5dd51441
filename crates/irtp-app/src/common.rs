//! Flags shared by every subcommand (the CLI contract: add, never rename).

use clap::Args;
use irtp::model::noise::NoiseModel;
use irtp::model::reset::support::{runners, Feature};
use irtp::model::reset::{spec as reset_spec, NoiseAtReset, Schedule, Target};
use irtp::model::Drag;
use irtp::{DragLaw, Params};
use std::path::PathBuf;

/// Medium and noise flags: `--drag --sigma --lambda --noise --temperature`
/// (every subcommand, including `analytic`, which has no resetting flags
/// of its own).
#[derive(Args, Clone, Debug)]
pub struct NoiseArgs {
    /// Drag law g(v) (help text generated from the registry by `drag_help`).
    #[arg(long, default_value = "tan", value_parser = parse_drag, help = drag_names(), long_help = drag_help())]
    pub drag: DragLaw,
    /// Noise amplitude Sigma (eta = ±Sigma).
    #[arg(long, default_value_t = 3.0, allow_hyphen_values = true)]
    pub sigma: f64,
    /// Flip rate lambda of the telegraph noise.
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub lambda: f64,
    /// The active noise as a spec, instead of --sigma and --lambda
    /// (help text with the methods that run it: `noise_help`).
    #[arg(
        long,
        value_name = "SPEC",
        conflicts_with_all = ["sigma", "lambda"],
        help = "The active noise as a spec, instead of --sigma and --lambda: telegraph, rpt, states or none",
        long_help = noise_help()
    )]
    pub noise: Option<String>,
    /// Temperature T >= 0 of a thermal noise sqrt(2T) dW added to the
    /// active noise (help text: `temperature_help`).
    #[arg(
        long,
        value_name = "T",
        allow_hyphen_values = true,
        help = "Temperature T >= 0 of a thermal noise sqrt(2T) dW added to the active noise [default: 0]",
        long_help = temperature_help()
    )]
    pub temperature: Option<f64>,
}

/// Where a noise other than the paper's runs: one line per class, from
/// the core's table ([`irtp::capability::noise_runners`]).
pub fn noise_runs_in() -> String {
    use irtp::capability::{noise_runners, NoiseClass};
    format!(
        "Runs in (docs/reference/support.md):\nT = 0: {};\nT > 0: {} (mfpt backward, \
         distribution, optimize: drags linear, tanh, tan with T <= 1).",
        noise_runners(NoiseClass::FiniteState),
        noise_runners(NoiseClass::Thermal)
    )
}

/// The long help of `--noise`: the spec of every kind and where it runs.
fn noise_help() -> String {
    format!(
        "The active noise as a spec, instead of --sigma and --lambda (docs/equations.md, \
         \"Noise kinds\"): telegraph:sigma=S,lambda=L (the paper's, the same as --sigma S \
         --lambda L), telegraph:plus=P,minus=M,rate_plus=KP,rate_minus=KM, \
         rpt:sigma=S,alpha=A,beta=B, states:levels=[..],rates=[[..],..] or none.\n\n{}",
        noise_runs_in()
    )
}

/// The long help of `--temperature`.
fn temperature_help() -> String {
    format!(
        "Temperature T >= 0 of a thermal noise sqrt(2T) dW added to the active noise \
         [default: 0]. T > 0 is a noise other than the paper's.\n\n{}",
        noise_runs_in()
    )
}

impl NoiseArgs {
    /// Validate into [`Params`] with the given reset rate and velocity:
    /// `--sigma --lambda`, or the noise model of `--noise` (the paper's
    /// telegraph noise by `--sigma --lambda` when absent) with
    /// `--temperature`. The paper's noise at temperature 0 gives the same
    /// value as `--sigma --lambda` ([`Params::with_noise`]).
    pub fn params(&self, rate: f64, reset_velocity: f64) -> irtp::Result<Params> {
        let kind = match &self.noise {
            None if self.temperature.unwrap_or(0.0) == 0.0 => {
                return Params::new(
                    self.drag.clone(),
                    self.sigma,
                    self.lambda,
                    rate,
                    reset_velocity,
                )
            }
            None => NoiseModel::telegraph(self.sigma, self.lambda)?
                .kind()
                .clone(),
            Some(spec) => spec.parse()?,
        };
        let model = NoiseModel::new(kind, self.temperature.unwrap_or(0.0))?;
        Params::with_noise(self.drag.clone(), model, rate, reset_velocity)
    }
}

/// The reset rate when `--rate` is not given.
pub const DEFAULT_RATE: f64 = 2.0;

/// Model flags: `--drag --sigma --lambda --rate --reset-velocity`.
#[derive(Args, Clone, Debug)]
pub struct ModelArgs {
    /// `--drag --sigma --lambda`.
    #[command(flatten)]
    pub noise: NoiseArgs,
    /// Velocity reset rate r [default: 2; not accepted by `mfpt optimize`,
    /// which searches r].
    #[arg(long, short = 'r', allow_hyphen_values = true)]
    pub rate: Option<f64>,
    /// Reset velocity v_r.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub reset_velocity: f64,
    /// The noise state at a reset: kept (the paper's protocol) or redrawn
    /// (±Sigma with probability 1/2 each) [default: kept].
    #[arg(long, value_name = "kept|redrawn")]
    pub reset_noise: Option<String>,
    /// Where a reset sends the velocity, as a spec (instead of
    /// --reset-velocity): point:v=V, gauss:mean=M,std=S or uniform:a=A,b=B.
    ///
    /// point:v=V, gauss:mean=M,std=S (a Gaussian
    /// truncated to the velocity interval, M inside it, S > 0) or
    /// uniform:a=A,b=B (inside the interval, A < B); optionally
    /// ,noise=kept|redrawn. A random target runs in every method.
    #[arg(long, value_name = "SPEC", conflicts_with = "reset_velocity")]
    pub reset_to: Option<String>,
    /// Periodic (sharp) resetting (help text: `feature_help`).
    #[arg(
        long,
        value_name = "T",
        allow_hyphen_values = true,
        help = "Periodic (sharp) resetting: a reset at every multiple of T > 0, instead of a Poisson clock",
        long_help = feature_help(PERIOD_HELP, &[Feature::Periodic])
    )]
    pub reset_period: Option<f64>,
    /// Renewal resetting (help text: `feature_help`).
    #[arg(
        long,
        value_name = "SPEC",
        help = "Renewal resetting: waiting times between resets drawn from a law (exp, gamma, weibull, pareto, fixed, table, hazard)",
        long_help = feature_help(CLOCK_HELP, &[Feature::Renewal])
    )]
    pub reset_clock: Option<String>,
    /// Position resetting (help text: `feature_help`).
    #[arg(
        long,
        value_name = "X",
        allow_hyphen_values = true,
        help = "Position resetting: at every reset the position jumps to X with the velocity",
        long_help = feature_help(POSITION_HELP, &[Feature::Position])
    )]
    pub reset_position: Option<f64>,
    /// A refractory period after every reset (help text: `feature_help`).
    #[arg(
        long,
        value_name = "SPEC",
        help = "A refractory period after every reset: exp:mean=M or fixed:t=T",
        long_help = feature_help(REFRACTORY_HELP, &[Feature::RefractoryExp, Feature::RefractoryFixed])
    )]
    pub refractory: Option<String>,
}

/// The long help of `--reset-period`, before where it runs.
const PERIOD_HELP: &str = "Periodic (sharp) resetting: a reset at every multiple of T > 0 of the \
     time since the start, instead of a Poisson clock (then no --rate, or --rate 0).";

/// The long help of `--reset-clock`, before where it runs.
const CLOCK_HELP: &str = "Renewal resetting: the waiting times between resets drawn from a law, \
     the clock restarting at every reset (then no --rate, or --rate 0; not with --reset-period): \
     exp:rate=R, gamma:k=K,theta=TH, weibull:k=K,scale=L, pareto:alpha=A,scale=X (Pareto I, \
     t >= X), fixed:t=T, table:0:1;T1:W1;...;Tn:0 (survival W, linear between points) or \
     table:file=PATH (lines 't,W'), hazard:EXPR (a rate r(a) in the age a since the last reset).";

/// The long help of `--reset-position`, before where it runs.
const POSITION_HELP: &str = "Position resetting: at every reset the position jumps to X with the \
     velocity (full resetting); the position then has a stationary distribution.";

/// The long help of `--refractory`, before where it runs.
const REFRACTORY_HELP: &str = "A refractory period after every reset (velocity held at the reset \
     velocity, resets ignored, noise flipping on): exp:mean=M (exponential duration of mean M) \
     or fixed:t=T.";

/// `text`, then the methods that run each of `features`, from the core's
/// support table ([`irtp::model::reset::support::runners`]).
fn feature_help(text: &str, features: &[Feature]) -> String {
    let runs: Vec<String> = features
        .iter()
        .map(|f| format!("{} runs in: {}.", capitalised(f.describe()), runners(*f)))
        .collect();
    format!("{text}\n\n{}", runs.join(" "))
}

/// `text` with its first letter in upper case.
fn capitalised(text: &str) -> String {
    let mut chars = text.chars();
    chars
        .next()
        .map_or_else(String::new, |c| c.to_uppercase().chain(chars).collect())
}

/// `Drag law g(v): tan, tanh, ...`: every registered law by name, for
/// `-h` (`--help` gives [`drag_help`]).
fn drag_names() -> String {
    let laws: Vec<String> = DragLaw::examples().iter().map(|d| d.to_string()).collect();
    format!("Drag law g(v): {}", laws.join(", "))
}

/// `Drag law g(v): tan (shear-thickening, g = tan v), ...`, every registered
/// law with its description (and, for a law with parameters, its spec and
/// keys).
fn drag_help() -> String {
    let laws: Vec<String> = DragLaw::examples()
        .iter()
        .map(|d| {
            let limit = d.force_limit();
            let keys = d.keys_help();
            if limit.is_finite() {
                format!("{d} ({}, needs sigma < {limit})", d.description())
            } else if !keys.is_empty() {
                format!("{d} ({}; {keys})", d.description())
            } else {
                format!("{d} ({})", d.description())
            }
        })
        .collect();
    format!("Drag law g(v): {}", laws.join("; "))
}

/// Largest count accepted in scientific notation (every integer up to it is
/// an exact f64).
const MAX_FLOAT_COUNT: f64 = 9_007_199_254_740_992.0; // 2^53

/// A count flag (`--particles`, `--cells`, ...): an integer, also in
/// scientific notation when it is a whole number (`1e6`, `2.5e3`).
pub fn parse_count(s: &str) -> Result<u64, String> {
    if let Ok(n) = s.parse::<u64>() {
        return Ok(n);
    }
    let whole = "a whole number >= 0, such as 20000 or 2e4";
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("not a count: expected {whole}"))?;
    if !(x >= 0.0 && x.fract() == 0.0 && x <= MAX_FLOAT_COUNT) {
        return Err(format!(
            "not a count: expected {whole} (at most 2^53 in scientific notation)"
        ));
    }
    Ok(x as u64)
}

/// [`parse_count`] for sizes (`--cells`, `--bins`, ...).
pub fn parse_size(s: &str) -> Result<usize, String> {
    let n = parse_count(s)?;
    usize::try_from(n).map_err(|_| format!("{n} is too large for this machine"))
}

/// A drag law or its spec with parameters (`power:n=0.5,k=1`); the error
/// names the parameter and its range.
fn parse_drag(s: &str) -> Result<DragLaw, String> {
    s.parse::<DragLaw>().map_err(|e| match e {
        irtp::Error::InvalidParameter { allowed, .. } => format!("expected {allowed}"),
        other => other.to_string(),
    })
}

impl ModelArgs {
    /// Validate into [`Params`]: the paper's protocol (point target
    /// `--reset-velocity`, noise kept) unless `--reset-to` or
    /// `--reset-noise` names another.
    pub fn params(&self) -> irtp::Result<Params> {
        let schedule = Schedule::parse(
            self.reset_period,
            self.reset_position,
            self.refractory.as_deref(),
        )?
        .with_clock(self.clock_spec()?.as_deref())?;
        self.rule_params()?.with_schedule(schedule)
    }

    /// `--reset-clock`, with a `table:file=PATH` read into the inline
    /// table spec (so the provenance holds the points themselves).
    fn clock_spec(&self) -> irtp::Result<Option<String>> {
        match self.reset_clock.as_deref() {
            Some(s) => match s.trim().strip_prefix("table:file=") {
                Some(path) => read_table(s, path).map(Some),
                None => Ok(Some(s.to_string())),
            },
            None => Ok(None),
        }
    }

    /// [`Self::params`] without the schedule's modifiers (the rate
    /// defaults to 0 with a periodic or renewal clock).
    fn rule_params(&self) -> irtp::Result<Params> {
        let default = if self.reset_period.is_some() || self.reset_clock.is_some() {
            0.0
        } else {
            DEFAULT_RATE
        };
        let base = self
            .noise
            .params(self.rate.unwrap_or(default), self.reset_velocity)?;
        let flag = match &self.reset_noise {
            Some(s) => Some(s.parse::<NoiseAtReset>()?),
            None => None,
        };
        let (target, in_spec) = match &self.reset_to {
            Some(s) => reset_spec::parse(s)?,
            None if flag.is_none() => return Ok(base),
            None => (Target::point(self.reset_velocity), None),
        };
        let noise = match (flag, in_spec) {
            (Some(a), Some(b)) if a != b => {
                return Err(irtp::Error::invalid(
                    "reset_noise",
                    a.name(),
                    format!(
                        "the noise rule of --reset-to ({}), or no --reset-noise",
                        b.name()
                    ),
                ))
            }
            (a, b) => a.or(b).unwrap_or(NoiseAtReset::Kept),
        };
        base.with_reset(target, noise).map_err(|e| match e {
            // A target out of range that --reset-to typed is blamed on it.
            irtp::Error::InvalidParameter {
                name: "reset_velocity",
                value,
                allowed,
            } if self.reset_to.is_some() => irtp::Error::InvalidParameter {
                name: "reset_to",
                value,
                allowed,
            },
            e => e,
        })
    }
}

/// Output flags: `--seed --out --json`.
#[derive(Args, Clone, Debug)]
pub struct OutputArgs {
    /// Master seed; particle i uses a stream derived from (seed, i)
    /// [default: 1; only for particle methods: a deterministic solver
    /// refuses it].
    #[arg(long, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Directory to write CSV files and run.json into.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// `--force`.
    #[command(flatten)]
    pub force: ForceArgs,
    /// Print one JSON object with the results on stdout.
    #[arg(long)]
    pub json: bool,
    /// `--max-work --max-memory`.
    #[command(flatten)]
    pub budget: super::budget::BudgetArgs,
}

impl OutputArgs {
    /// The master seed of a particle method (1 when `--seed` is not given).
    pub fn seed(&self) -> u64 {
        self.seed.unwrap_or(1)
    }

    /// Refuse `--seed` where nothing is random (`what`: the computation).
    pub fn no_seed(&self, what: &str) -> irtp::Result<()> {
        match self.seed {
            Some(s) => Err(irtp::Error::invalid(
                "--seed",
                s,
                format!("only with a particle method ({what} is deterministic)"),
            )),
            None => Ok(()),
        }
    }
}

/// `--force`, of every command with `--out`.
#[derive(Args, Clone, Debug, Default)]
pub struct ForceArgs {
    /// Write into an --out that holds another run or files irtp did not write.
    ///
    /// The previous run's outputs (as its run.json lists them) are replaced,
    /// other files are left alone (and named in a warning).
    #[arg(long)]
    pub force: bool,
}

/// The table of `table:file=PATH`: lines `t,W` (blank lines, `#` comments
/// and a non-numeric header skipped), checked by the core
/// ([`irtp::model::reset::clock::TableClock::new`]); its inline spec.
fn read_table(spec: &str, path: &str) -> irtp::Result<String> {
    let bad = |what: String| {
        irtp::Error::invalid(
            "reset_clock",
            spec,
            format!("table:file=PATH of a readable file of 't,W' lines ({what})"),
        )
    };
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("{path}: {e}")))?;
    let (mut t, mut w) = (Vec::new(), Vec::new());
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut cols = line.split(',').map(|c| c.trim().parse::<f64>());
        match (cols.next(), cols.next(), cols.next()) {
            (Some(Ok(a)), Some(Ok(b)), None) => {
                t.push(a);
                w.push(b);
            }
            _ if t.is_empty() && i == 0 => continue,
            _ => return Err(bad(format!("line {} is not 't,W': '{line}'", i + 1))),
        }
    }
    irtp::model::reset::clock::TableClock::new(t, w).map(|c| {
        use irtp::model::reset::clock::Law;
        c.spec()
    })
}
