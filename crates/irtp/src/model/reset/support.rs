//! Which method runs which resetting protocol: the one table behind the
//! support table of docs/reference/support.md. A method calls
//! [`crate::Params::require`] with its [`Solver`] before any work; a
//! protocol feature the method does not run is refused there with one line
//! naming the flag and the methods that do run it, never approximated.

use std::fmt;

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
    /// `mfpt optimize`.
    MfptOptimize,
    /// `analytic` and the linear-drag closed forms.
    ClosedForm,
}

impl Solver {
    /// Every solver, in the order of the support table.
    pub const ALL: [Solver; 11] = [
        Solver::Exact,
        Solver::Euler,
        Solver::FpStationary,
        Solver::FpTransient,
        Solver::FpMsd,
        Solver::Backward,
        Solver::MfptExact,
        Solver::MfptEuler,
        Solver::FptDistribution,
        Solver::MfptOptimize,
        Solver::ClosedForm,
    ];

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
            Solver::MfptOptimize => "mfpt optimize",
            Solver::ClosedForm => "analytic's closed forms",
        }
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

/// Whether `solver` runs `feature` (exactly, or with its stated
/// discretisation error). The one table; docs/reference/support.md says
/// the same.
pub fn supports(solver: Solver, feature: Feature) -> bool {
    use Feature as F;
    use Solver as S;
    match feature {
        // The velocity process does not see the position: velocity-only
        // answers are those without position resetting.
        F::Position => matches!(
            solver,
            S::Exact
                | S::Euler
                | S::FpStationary
                | S::ClosedForm
                | S::FpTransient
                | S::FpMsd
                | S::Backward
                | S::MfptExact
                | S::MfptEuler
                | S::FptDistribution
                | S::MfptOptimize
        ),
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
                | S::FpStationary
                | S::FpTransient
                | S::FpMsd
                | S::Backward
                | S::ClosedForm
        ),
        F::RefractoryFixed => matches!(solver, S::Exact | S::Euler | S::MfptExact | S::MfptEuler),
        F::Periodic => matches!(
            solver,
            S::Exact | S::Euler | S::MfptExact | S::MfptEuler | S::ClosedForm | S::FpTransient
        ),
        // A renewal clock is not Markovian in the state: the particle
        // samplers draw its waiting times; the search's renewal route
        // (full resetting) integrates over its law.
        F::Renewal => matches!(solver, S::Exact | S::Euler | S::MfptExact | S::MfptEuler),
    }
}

/// The solvers that run `feature`, for `--help`, the methods of one
/// command together: `simulate (exact, euler), fp transient, mfpt (exact,
/// euler)`.
pub fn runners(feature: Feature) -> String {
    let list = runner_groups(feature);
    if list.is_empty() {
        "no method yet".into()
    } else {
        list.join(", ")
    }
}

/// The groups of [`runners`], in the order of [`Solver::ALL`]: one per
/// command, its methods in parentheses (`simulate (exact, euler)`).
pub fn runner_groups(feature: Feature) -> Vec<String> {
    let mut groups: Vec<(&str, Vec<&str>)> = Vec::new();
    for s in Solver::ALL.iter().filter(|s| supports(**s, feature)) {
        let command = s.command().trim_end_matches("'s closed forms");
        let (name, method) = match command.split_once(" --method ") {
            Some((name, method)) => (name, Some(method)),
            None => (command, None),
        };
        match groups.iter_mut().find(|(n, _)| *n == name) {
            Some((_, methods)) => methods.extend(method),
            None => groups.push((name, method.into_iter().collect())),
        }
    }
    groups
        .iter()
        .map(|(name, methods)| match methods.is_empty() {
            true => name.to_string(),
            false => format!("{name} ({})", methods.join(", ")),
        })
        .collect()
}
