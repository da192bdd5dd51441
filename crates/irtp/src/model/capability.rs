//! Which method runs which combination of model and protocol: the one
//! table behind docs/reference/support.md, README's pointer to it and the
//! `--help` of `--noise` and `--temperature`.
//!
//! Every method calls [`check`] with its [`Solver`] before any work
//! ([`crate::Params::require`] is that call). A combination the method
//! does not run is refused there as [`Error::Unsupported`]: one line naming
//! the flag, the method and the methods that do run it, never approximated.
//!
//! The table has three dimensions, each one `match` below:
//! - [`noise_runs`]: method × [`NoiseClass`] (the paper's telegraph noise,
//!   another finite-state noise at T = 0, thermal noise T > 0);
//! - [`protocol_runs`]: method × protocol [`Feature`] × noise class (a
//!   noise model runs with the Poisson protocol only in the solvers of
//!   the N-state equations);
//! - [`drag_runs`]: method × drag capability ([`Drag::thermal_backward`]:
//!   the N-state backward equations at T > 0).
//!
//! A method that learns to run a combination changes one arm here; the
//! support table, the help text and the refusals follow.

use std::fmt;

use crate::error::{Error, Result};
use crate::model::noise::NoiseModel;
use crate::model::{Drag, Params};

/// A method, as the user names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solver {
    /// `simulate --method exact`.
    Exact,
    /// `simulate --method euler`.
    Euler,
    /// `fp stationary` (density, moments, D_eff).
    FpStationary,
    /// `fp transient`.
    FpTransient,
    /// `fp msd` (position moments).
    FpMsd,
    /// `mfpt --method backward`, `mfpt scan` (stationary backward equations).
    Backward,
    /// `mfpt --method exact`.
    MfptExact,
    /// `mfpt --method euler`.
    MfptEuler,
    /// `mfpt distribution --method backward`.
    FptDistribution,
    /// `mfpt distribution --method exact` (the histogram of first-passage
    /// times from the ±Sigma starts).
    FptDistributionExact,
    /// `mfpt optimize`.
    MfptOptimize,
    /// `analytic` and the linear-drag closed forms.
    ClosedForm,
    /// The search (`mfpt --xt`, `--interval`) by its 2-D backward equation
    /// (`--method backward`, `mfpt scan`, `mfpt optimize` with `--xt`).
    SearchBackward,
    /// The search by the renewal route (`--method renewal`).
    SearchRenewal,
    /// The search's exact sampler (`--method exact`).
    SearchExact,
    /// The search's Euler scheme (`--method euler`).
    SearchEuler,
    /// The search's first-passage-time distribution (`mfpt distribution --xt`).
    SearchDistribution,
}

impl Solver {
    /// Every solver, in the order of the support table.
    pub const ALL: [Solver; 17] = [
        Solver::Exact,
        Solver::Euler,
        Solver::FpStationary,
        Solver::FpTransient,
        Solver::FpMsd,
        Solver::Backward,
        Solver::MfptExact,
        Solver::MfptEuler,
        Solver::FptDistribution,
        Solver::FptDistributionExact,
        Solver::MfptOptimize,
        Solver::ClosedForm,
        Solver::SearchBackward,
        Solver::SearchRenewal,
        Solver::SearchExact,
        Solver::SearchEuler,
        Solver::SearchDistribution,
    ];

    /// The command and, where the command has several, the method:
    /// `("simulate", Some("exact"))`.
    pub fn parts(&self) -> (&'static str, Option<&'static str>) {
        match self {
            Solver::Exact => ("simulate", Some("exact")),
            Solver::Euler => ("simulate", Some("euler")),
            Solver::FpStationary => ("fp", Some("stationary")),
            Solver::FpTransient => ("fp", Some("transient")),
            Solver::FpMsd => ("fp", Some("msd")),
            Solver::Backward => ("mfpt", Some("backward")),
            Solver::MfptExact => ("mfpt", Some("exact")),
            Solver::MfptEuler => ("mfpt", Some("euler")),
            Solver::FptDistribution => ("mfpt distribution", Some("backward")),
            Solver::FptDistributionExact => ("mfpt distribution", Some("exact")),
            Solver::MfptOptimize => ("mfpt optimize", None),
            Solver::ClosedForm => ("analytic", None),
            Solver::SearchBackward => ("mfpt --xt", Some("backward")),
            Solver::SearchRenewal => ("mfpt --xt", Some("renewal")),
            Solver::SearchExact => ("mfpt --xt", Some("exact")),
            Solver::SearchEuler => ("mfpt --xt", Some("euler")),
            Solver::SearchDistribution => ("mfpt distribution --xt", None),
        }
    }

    /// The command that runs it.
    pub fn command(&self) -> &'static str {
        match self {
            Solver::Exact => "simulate --method exact",
            Solver::Euler => "simulate --method euler",
            Solver::FpStationary => "fp stationary",
            Solver::FpTransient => "fp transient",
            Solver::FpMsd => "fp msd",
            Solver::Backward => "mfpt --method backward/scan",
            Solver::MfptExact => "mfpt --method exact",
            Solver::MfptEuler => "mfpt --method euler",
            Solver::FptDistribution => "mfpt distribution",
            Solver::FptDistributionExact => "mfpt distribution --method exact",
            Solver::MfptOptimize => "mfpt optimize",
            Solver::ClosedForm => "analytic's closed forms",
            Solver::SearchBackward => "mfpt --xt --method backward",
            Solver::SearchRenewal => "mfpt --xt --method renewal",
            Solver::SearchExact => "mfpt --xt --method exact",
            Solver::SearchEuler => "mfpt --xt --method euler",
            Solver::SearchDistribution => "mfpt distribution --xt",
        }
    }

    /// Whether it solves the N-state backward equations of the velocity
    /// (`crate::mfpt::backward` over a noise model's chain), whose thermal operator needs a drag with
    /// [`Drag::thermal_backward`].
    fn velocity_backward(&self) -> bool {
        matches!(
            self,
            Solver::Backward | Solver::FptDistribution | Solver::MfptOptimize
        )
    }
}

impl fmt::Display for Solver {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.command())
    }
}

/// A feature of a resetting protocol beyond the paper's (Poisson clock,
/// point target, position kept, no refractory period).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// Position reset to x_r with the velocity (`--reset-position`).
    Position,
    /// Exponentially distributed refractory period (`--refractory exp:..`).
    RefractoryExp,
    /// Fixed-length refractory period (`--refractory fixed:..`).
    RefractoryFixed,
    /// Resets every T instead of at Poisson times (`--reset-period`).
    Periodic,
    /// Resets at the renewal times of a waiting-time law (`--reset-clock`).
    Renewal,
}

impl Feature {
    /// Every feature, in the order of the support table.
    pub const ALL: [Feature; 5] = [
        Feature::Position,
        Feature::RefractoryExp,
        Feature::RefractoryFixed,
        Feature::Periodic,
        Feature::Renewal,
    ];

    /// The flag (parameter name) that asks for it.
    pub fn flag(&self) -> &'static str {
        match self {
            Feature::Position => "reset_position",
            Feature::RefractoryExp | Feature::RefractoryFixed => "refractory",
            Feature::Periodic => "reset_period",
            Feature::Renewal => "reset_clock",
        }
    }

    /// What it is, for messages.
    pub fn describe(&self) -> &'static str {
        match self {
            Feature::Position => "position resetting",
            Feature::RefractoryExp => "an exponential refractory period",
            Feature::RefractoryFixed => "a fixed refractory period",
            Feature::Periodic => "periodic resetting",
            Feature::Renewal => "a renewal reset clock",
        }
    }
}

/// The class of a noise model, as the methods tell them apart
/// (docs/equations.md, "Noise kinds").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseClass {
    /// The paper's symmetric telegraph noise at T = 0 (no noise model).
    Paper,
    /// Any other finite-state noise (`--noise`), T = 0.
    FiniteState,
    /// Thermal noise: `--temperature T > 0` with any finite-state noise.
    Thermal,
}

impl NoiseClass {
    /// Every class, in the order of the support table.
    pub const ALL: [NoiseClass; 3] = [
        NoiseClass::Paper,
        NoiseClass::FiniteState,
        NoiseClass::Thermal,
    ];

    /// The class of the noise of `params`.
    pub fn of(params: &Params) -> NoiseClass {
        params
            .noise()
            .map_or(NoiseClass::Paper, NoiseClass::of_model)
    }

    /// The class of noise model `m` (never the paper's default, which
    /// [`Params`] carries as no model).
    pub fn of_model(m: &NoiseModel) -> NoiseClass {
        match m.temperature() > 0.0 {
            true => NoiseClass::Thermal,
            false => NoiseClass::FiniteState,
        }
    }

    /// What it is, for messages.
    pub fn describe(&self) -> &'static str {
        match self {
            NoiseClass::Paper => "the paper's noise",
            NoiseClass::FiniteState => "a noise model",
            NoiseClass::Thermal => "thermal noise",
        }
    }
}

/// Whether `solver` runs noise of class `noise` (any drag, unless
/// [`drag_runs`] says otherwise). The closed forms of `irtp analytic`
/// answer `false`: [`crate::analytic::noise`] checks its own cases.
pub fn noise_runs(solver: Solver, noise: NoiseClass) -> bool {
    use NoiseClass as N;
    use Solver as S;
    match (solver, noise) {
        (_, N::Paper) => true,
        (S::ClosedForm, _) => false,
        // No exact flow with thermal noise.
        (S::MfptExact, N::Thermal) => false,
        // The exact first-passage kernel: any finite-state noise at T = 0.
        (S::FptDistributionExact, N::FiniteState) => true,
        (S::FptDistributionExact, N::Thermal) => false,
        // The search: its backward equations (mean, renewal route,
        // distribution) and samplers at T = 0.
        (
            S::SearchBackward
            | S::SearchRenewal
            | S::SearchDistribution
            | S::SearchExact
            | S::SearchEuler,
            N::FiniteState,
        ) => true,
        (
            S::SearchBackward
            | S::SearchRenewal
            | S::SearchDistribution
            | S::SearchExact
            | S::SearchEuler,
            N::Thermal,
        ) => false,
        (
            S::Exact
            | S::Euler
            | S::FpStationary
            | S::FpTransient
            | S::FpMsd
            | S::Backward
            | S::MfptExact
            | S::MfptEuler
            | S::FptDistribution
            | S::MfptOptimize,
            _,
        ) => true,
    }
}

/// Whether `solver` runs protocol `feature` with noise of class `noise`
/// (exactly, or with its stated discretisation error).
pub fn protocol_runs(solver: Solver, feature: Feature, noise: NoiseClass) -> bool {
    if noise != NoiseClass::Paper
        && !modifiers_with_noise(solver, noise)
        && !hold_with_noise(solver, feature)
    {
        return false;
    }
    supports(solver, feature)
}

/// Whether `solver` runs `feature` with a noise model although it runs no
/// other modifier with one: the N-state Fokker-Planck and backward
/// equations run an exponential refractory period, one held state per
/// noise state (docs/equations.md, (R10), (R11)), the time-dependent one
/// too, the moment chain of `fp msd` ((R14)), the optimal rate over the
/// backward mean ((R13)) and the first-passage distribution ((R15)); the
/// time-dependent one also runs periodic resetting (all mass to the target
/// at every kT).
fn hold_with_noise(solver: Solver, feature: Feature) -> bool {
    match feature {
        Feature::RefractoryExp => matches!(
            solver,
            Solver::FpStationary
                | Solver::FpTransient
                | Solver::FpMsd
                | Solver::Backward
                | Solver::FptDistribution
                | Solver::MfptOptimize
        ),
        Feature::Periodic => solver == Solver::FpTransient,
        _ => false,
    }
}

/// Whether `solver` runs the protocol features it runs ([`supports`])
/// with noise of class `noise` too. The particle samplers run them with
/// any finite-state noise at T = 0, one event loop over the noise's states
/// each (the exact samplers of `simulate`, `mfpt` and `mfpt distribution`,
/// the Euler schemes of `simulate` and `mfpt`, which also run them at
/// T > 0); the search's methods run every protocol they run. The N-state
/// Fokker-Planck and backward equations and the exact sampler's
/// Ornstein-Uhlenbeck loop (T > 0) run a noise model with Poisson
/// resetting only (any target, noise kept or re-drawn), some of them with
/// an exponential refractory period, the time-dependent Fokker-Planck
/// solver with periodic resetting ([`protocol_runs`]).
pub fn modifiers_with_noise(solver: Solver, noise: NoiseClass) -> bool {
    use NoiseClass as N;
    use Solver as S;
    match solver {
        S::Exact | S::MfptExact | S::FptDistributionExact => noise == N::FiniteState,
        S::Euler | S::MfptEuler => true,
        S::SearchBackward
        | S::SearchRenewal
        | S::SearchExact
        | S::SearchEuler
        | S::SearchDistribution => true,
        _ => false,
    }
}

/// Whether `solver` runs drag `drag` at temperature `temperature`: at
/// T > 0 the N-state backward equations need [`Drag::thermal_backward`]
/// at least `temperature`, and the exact sampler's Ornstein-Uhlenbeck
/// segments (Eqs. (N40)-(N45)) need [`Drag::newtonian`]; every other
/// method runs every drag (an engine may still refuse a case for a
/// numerical reason).
pub fn drag_runs(solver: Solver, drag: &impl Drag, temperature: f64) -> bool {
    if temperature > 0.0 && solver.velocity_backward() {
        return drag.thermal_backward().is_some_and(|t| temperature <= t);
    }
    if temperature > 0.0 && solver == Solver::Exact {
        return drag.newtonian();
    }
    true
}

/// Whether `solver` runs `feature` with the paper's noise: the protocol
/// dimension of the table.
pub fn supports(solver: Solver, feature: Feature) -> bool {
    use Feature as F;
    use Solver as S;
    match feature {
        // The velocity process does not see the position; the search's
        // renewal route requires it (full resetting, refused there).
        F::Position => true,
        // The particle samplers run every modifier: the exact sampler
        // exactly, the Euler schemes with their O(dt) timing. The
        // exponential refractory period is Markovian: extra states of the
        // chain, extra unknowns of the backward equations, extra moments of
        // the generator.
        F::RefractoryExp => matches!(
            solver,
            S::Exact
                | S::Euler
                | S::MfptExact
                | S::MfptEuler
                | S::FptDistributionExact
                | S::FptDistribution
                | S::SearchExact
                | S::SearchEuler
                | S::SearchBackward
                | S::SearchDistribution
                | S::FpStationary
                | S::FpTransient
                | S::FpMsd
                | S::Backward
                | S::MfptOptimize
                | S::ClosedForm
        ),
        F::RefractoryFixed => matches!(
            solver,
            S::Exact
                | S::Euler
                | S::MfptExact
                | S::MfptEuler
                | S::FptDistributionExact
                | S::SearchExact
                | S::SearchEuler
        ),
        F::Periodic => matches!(
            solver,
            S::Exact
                | S::Euler
                | S::MfptExact
                | S::MfptEuler
                | S::FptDistributionExact
                | S::ClosedForm
                | S::FpTransient
                | S::SearchRenewal
                | S::SearchExact
                | S::SearchEuler
        ),
        // A renewal clock is not Markovian in the state: the particle
        // samplers draw its waiting times; the search's renewal route
        // integrates over its law.
        F::Renewal => matches!(
            solver,
            S::Exact
                | S::Euler
                | S::MfptExact
                | S::MfptEuler
                | S::FptDistributionExact
                | S::SearchRenewal
                | S::SearchExact
                | S::SearchEuler
        ),
    }
}

/// Whether `solver` runs the protocol features `features` together, each
/// of which it runs alone ([`protocol_runs`]). Periodic resetting with an
/// exponential refractory period is Markov (the resets come at the
/// multiples of T, skipped by a particle still held), but the
/// time-dependent Fokker-Planck solver and the linear closed forms reset
/// the whole density at every multiple of T: neither keeps the held mass
/// apart at a periodic reset, so neither runs the pair.
pub fn combination_runs(solver: Solver, features: &[Feature]) -> bool {
    let periodic_hold =
        features.contains(&Feature::Periodic) && features.contains(&Feature::RefractoryExp);
    !(periodic_hold && matches!(solver, Solver::FpTransient | Solver::ClosedForm))
}

/// Refuse what `solver` does not run of `params`: its noise class
/// ([`check_noise`]), then each protocol feature ([`protocol_runs`]), then
/// their combination ([`combination_runs`]).
pub fn check(solver: Solver, params: &Params) -> Result<()> {
    check_noise(solver, params)?;
    let noise = NoiseClass::of(params);
    let features = params.schedule().features();
    for &f in &features {
        if !protocol_runs(solver, f, noise) {
            let feature = match noise {
                NoiseClass::Paper => f.describe(),
                NoiseClass::FiniteState => "this protocol with a noise model",
                NoiseClass::Thermal => "this protocol with thermal noise",
            };
            return Err(unsupported(
                solver,
                f.flag(),
                params.schedule().spec_of(f),
                feature,
                |s| noise_runs(s, noise) && protocol_runs(s, f, noise),
            ));
        }
    }
    if !combination_runs(solver, &features) {
        let f = Feature::RefractoryExp;
        return Err(unsupported(
            solver,
            f.flag(),
            params.schedule().spec_of(f),
            "an exponential refractory period with periodic resetting",
            |s| {
                noise_runs(s, noise)
                    && features.iter().all(|&g| protocol_runs(s, g, noise))
                    && combination_runs(s, &features)
            },
        ));
    }
    Ok(())
}

/// Refuse the noise of `params` where `solver` does not run its class
/// ([`noise_runs`]) or, at T > 0, its drag ([`drag_runs`]). The paper's
/// noise with T > 0 is blamed on `temperature`, another on `noise`.
pub fn check_noise(solver: Solver, params: &Params) -> Result<()> {
    let Some(m) = params.noise() else {
        return Ok(());
    };
    check_model(solver, m)?;
    let (drag, t) = (params.drag(), m.temperature());
    if !drag_runs(solver, &drag, t) {
        // A law the backward equations never run at T > 0 is blamed on
        // `drag`; one they run at a lower temperature, and any law but
        // linear in the exact sampler, on `temperature`.
        let class = NoiseClass::of(params);
        let (flag, value, feature) = match (solver.velocity_backward(), drag.thermal_backward()) {
            (true, None) => ("drag", drag.to_string(), "this drag with thermal noise"),
            (true, Some(_)) => (
                "temperature",
                t.to_string(),
                "this drag at this temperature",
            ),
            (false, _) => (
                "temperature",
                t.to_string(),
                "thermal noise with a drag other than linear",
            ),
        };
        return Err(unsupported(solver, flag, value, feature, |s| {
            noise_runs(s, class) && drag_runs(s, &drag, t)
        }));
    }
    Ok(())
}

/// Refuse noise model `m` where `solver` does not run its class
/// ([`noise_runs`]): thermal noise where the method runs the noise at
/// T = 0 is blamed on `temperature`, else as
/// [`crate::model::noise::support::blamed`] says.
pub fn check_model(solver: Solver, m: &NoiseModel) -> Result<()> {
    let class = NoiseClass::of_model(m);
    if noise_runs(solver, class) {
        return Ok(());
    }
    let (flag, value) =
        match class == NoiseClass::Thermal && noise_runs(solver, NoiseClass::FiniteState) {
            true => ("temperature", m.temperature().to_string()),
            false => crate::model::noise::support::blamed(m),
        };
    Err(unsupported(solver, flag, value, class.describe(), |s| {
        noise_runs(s, class)
    }))
}

/// The [`Error::Unsupported`] of `solver` for `flag` = `value`, listing
/// the methods for which `runs` answers true ([`fitted`]).
fn unsupported(
    solver: Solver,
    flag: &'static str,
    value: String,
    feature: &'static str,
    runs: impl Fn(Solver) -> bool,
) -> Error {
    // The methods nearest the refusing one first (its own command, then
    // those of the same problem: a search's or the velocity's), as a long
    // list is cut at its end.
    let own = solver.parts().0;
    let search = |g: &str| g.contains("--xt");
    let list = runners_where(runs);
    let mut groups = split_groups(&list);
    groups.sort_by_key(|g| {
        let same = *g == own || g.starts_with(&format!("{own} ("));
        (!same, search(g) != search(own))
    });
    fitted(flag, value, feature, solver.command(), groups.join(", "))
}

/// The longest message of an [`Error::Unsupported`], as a command line
/// prints it (`--flag`), that leaves a line of the front end's
/// `irtp: error: ` under 200 characters.
pub const MAX_MESSAGE: usize = 186;

/// An [`Error::Unsupported`] whose message fits [`MAX_MESSAGE`]: the
/// last groups of `runners` are cut (ending in `…`) where it would not.
pub fn fitted(
    flag: &'static str,
    value: impl fmt::Display,
    feature: &'static str,
    method: &str,
    runners: String,
) -> Error {
    let value = value.to_string();
    let build = |r: &str| Error::unsupported(flag, &value, feature, method, r);
    let len = |e: &Error| {
        e.message_with(|n| format!("--{}", n.replace('_', "-")))
            .chars()
            .count()
    };
    let mut groups: Vec<&str> = split_groups(&runners);
    let mut e = build(&runners);
    while len(&e) > MAX_MESSAGE && !groups.is_empty() {
        groups.pop();
        e = build(&format!("{}, …", groups.join(", ")));
    }
    e
}

/// The groups of a runners list (`mfpt (backward, euler), fp` has two):
/// split at the commas outside parentheses.
fn split_groups(list: &str) -> Vec<&str> {
    let (mut out, mut depth, mut start) = (Vec::new(), 0i32, 0);
    for (i, c) in list.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                out.push(list[start..i].trim());
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(list[start..].trim());
    out
}

/// The methods for which `runs` answers true, one group per command:
/// `simulate, fp (stationary, msd), mfpt --xt (exact, euler)` (a command
/// all of whose methods run it is named alone).
pub fn runners_where(runs: impl Fn(Solver) -> bool) -> String {
    let mut groups: Vec<(&str, Vec<&str>, bool)> = Vec::new();
    for s in Solver::ALL {
        let (name, method) = s.parts();
        let at = match groups.iter().position(|(n, _, _)| *n == name) {
            Some(i) => i,
            None => {
                groups.push((name, Vec::new(), true));
                groups.len() - 1
            }
        };
        let group = &mut groups[at];
        match runs(s) {
            true => group.1.extend(method),
            false => group.2 = false,
        }
    }
    let list: Vec<String> = groups
        .iter()
        .filter(|(_, methods, all)| *all || !methods.is_empty())
        .map(|(name, methods, all)| match *all || methods.is_empty() {
            true => name.to_string(),
            false => format!("{name} ({})", methods.join(", ")),
        })
        .collect();
    match list.is_empty() {
        true => "no method yet".into(),
        false => list.join(", "),
    }
}

/// The methods that run `feature` with the paper's noise.
pub fn runners(feature: Feature) -> String {
    runners_where(|s| supports(s, feature))
}

/// The methods that run noise of class `noise` (with some drag).
pub fn noise_runners(noise: NoiseClass) -> String {
    runners_where(|s| noise_runs(s, noise))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    /// Every refusal the table can give, with a value as long as a message
    /// echoes, is one line that fits [`MAX_MESSAGE`] and names the method.
    #[test]
    fn every_refusal_fits_one_line() {
        let value = "v".repeat(60);
        for s in Solver::ALL {
            for c in NoiseClass::ALL {
                for f in Feature::ALL {
                    let e = unsupported(s, f.flag(), value.clone(), f.describe(), |m| {
                        protocol_runs(m, f, c)
                    });
                    let msg = e.message_with(|n| format!("--{}", n.replace('_', "-")));
                    assert!(msg.chars().count() <= MAX_MESSAGE, "{msg}");
                    assert!(!msg.contains('\n') && msg.contains(s.command()), "{msg}");
                }
                let e = unsupported(s, "temperature", value.clone(), c.describe(), |m| {
                    noise_runs(m, c)
                });
                let msg = e.message_with(|n| format!("--{n}"));
                assert!(msg.chars().count() <= MAX_MESSAGE, "{msg}");
            }
        }
    }

    /// The runners group by command; a cut list ends in `…`.
    #[test]
    fn runners_group_by_command() {
        assert_eq!(
            runners(Feature::RefractoryFixed),
            "simulate, mfpt (exact, euler), mfpt distribution (exact), mfpt --xt (exact, euler)"
        );
        let e = fitted(
            "noise",
            "x".repeat(48),
            "a noise model",
            &"m".repeat(60),
            "a, b (c, d), e".repeat(20),
        );
        assert!(e.to_string().ends_with(", …"), "{e}");
    }

    /// The thermal backward equations run the laws that say so, up to
    /// their temperature: tan to T = 1, linear and tanh at any T.
    #[test]
    fn drag_capabilities_decide_the_thermal_backward_equations() {
        let runs = |d: DragLaw, t| drag_runs(Solver::Backward, &d, t);
        assert!(runs(DragLaw::Tan, 1.0) && !runs(DragLaw::Tan, 1.5));
        assert!(runs(DragLaw::Linear, 50.0) && runs(DragLaw::Tanh, 50.0));
        assert!(!runs(DragLaw::Cubic, 0.1) && runs(DragLaw::Cubic, 0.0));
        assert!(drag_runs(Solver::Euler, &DragLaw::Cubic, 5.0));
    }
}
