//! The support table of docs/reference/support.md, rendered from
//! [`crate::capability`], the table every method consults before any
//! work. A test compares the page with [`markdown`], so the page cannot
//! say what the code does not do.

use super::drag::{Drag, DragLaw};
use super::noise::support::CLOSED_FORMS;
use crate::capability::{drag_runs, noise_runs, protocol_runs, Feature, NoiseClass, Solver};

fn cell(yes: bool) -> String {
    match yes {
        true => "yes".into(),
        false => "—".into(),
    }
}

/// The drags `solver` runs at T > 0, when not every law: `linear, tanh,
/// tan (T ≤ 1)` ([`Drag::thermal_backward`]).
fn thermal_drags(solver: Solver) -> Option<String> {
    let laws = DragLaw::ALL;
    if laws.iter().all(|d| drag_runs(solver, d, f64::MAX)) {
        return None;
    }
    let named: Vec<String> = laws
        .iter()
        .filter(|d| drag_runs(solver, *d, f64::MIN_POSITIVE))
        .map(|d| match d.thermal_backward() {
            Some(t) if t.is_finite() => format!("{} (T ≤ {t})", d.name()),
            _ => d.name().to_string(),
        })
        .collect();
    Some(named.join(", "))
}

/// The cell of `solver` for noise of class `noise`.
fn noise_cell(solver: Solver, noise: NoiseClass) -> String {
    if solver == Solver::ClosedForm {
        return CLOSED_FORMS.into();
    }
    match (noise_runs(solver, noise), noise) {
        (true, NoiseClass::Thermal) => thermal_drags(solver).unwrap_or_else(|| "yes".into()),
        (yes, _) => cell(yes),
    }
}

/// Whether `solver` runs, with a noise model, every feature it runs with
/// the paper's noise ([`crate::capability::modifiers_with_noise`]): "yes"
/// for every class of noise it runs, "T = 0" for finite-state noise only;
/// else Poisson resetting, with an exponential refractory period and
/// periodic resetting where it runs them with finite-state noise.
fn with_noise(solver: Solver) -> String {
    if !noise_runs(solver, NoiseClass::FiniteState) {
        return "—".into();
    }
    let same = |noise: NoiseClass| {
        Feature::ALL.iter().all(|f| {
            protocol_runs(solver, *f, noise) == protocol_runs(solver, *f, NoiseClass::Paper)
        })
    };
    let thermal = noise_runs(solver, NoiseClass::Thermal);
    match (
        same(NoiseClass::FiniteState),
        thermal && !same(NoiseClass::Thermal),
    ) {
        (true, false) => "yes".into(),
        (true, true) => "T = 0".into(),
        (false, _) => {
            let extra: Vec<&str> = [
                (Feature::RefractoryExp, "exp refractory"),
                (Feature::Periodic, "periodic"),
            ]
            .into_iter()
            .filter(|&(f, _)| protocol_runs(solver, f, NoiseClass::FiniteState))
            .map(|(_, name)| name)
            .collect();
            match extra.is_empty() {
                true => "Poisson only".into(),
                false => format!("Poisson, {}", extra.join(", ")),
            }
        }
    }
}

/// The table as Markdown: one row per [`Solver`] (in [`Solver::ALL`]'s
/// order), one column per protocol feature (with the paper's noise), then
/// one per class of noise model and one for the protocol with a noise
/// model. "yes": the method runs it (exactly, or with its stated
/// discretisation error); "—": refused before any work, naming the flag.
pub fn markdown() -> String {
    let mut heads: Vec<String> = Feature::ALL
        .iter()
        .map(|f| format!("`--{}`: {}", f.flag().replace('_', "-"), f.describe()))
        .collect();
    heads.push("`--noise` (e.g. `rpt:…`), T = 0".into());
    heads.push("`--temperature T > 0`".into());
    heads.push("modifiers with `--noise` or T > 0".into());
    let mut s = format!("| method | {} |\n|---|", heads.join(" | "));
    s += &"---|".repeat(heads.len());
    s.push('\n');
    for m in Solver::ALL {
        let mut cells: Vec<String> = Feature::ALL
            .iter()
            .map(|f| cell(protocol_runs(m, *f, NoiseClass::Paper)))
            .collect();
        cells.push(noise_cell(m, NoiseClass::FiniteState));
        cells.push(noise_cell(m, NoiseClass::Thermal));
        cells.push(with_noise(m));
        s += &format!("| `{}` | {} |\n", m.command(), cells.join(" | "));
    }
    s
}
