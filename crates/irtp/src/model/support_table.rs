//! The support table of docs/reference/support.md, rendered from the two
//! tables the methods consult before any work: [`super::reset::support::supports`]
//! (method × protocol feature) and [`super::noise::support::supports`] (method ×
//! noise model). A test compares the page with [`markdown`], so the page
//! cannot say what the code does not do.

use super::noise::{self, NoiseModel};
use super::reset::support::{self as reset_support, Feature, Solver};

/// The protocol features, in the rows' order.
const FEATURES: [Feature; 5] = [
    Feature::Position,
    Feature::RefractoryExp,
    Feature::RefractoryFixed,
    Feature::Periodic,
    Feature::Renewal,
];

/// The noise rows: a label and the model asked for (each stands for its
/// class: the table's noise arm answers by finite-state-ness and
/// temperature, not by kind).
fn noise_rows() -> Vec<(&'static str, NoiseModel)> {
    let parse = |spec: &str, t: f64| NoiseModel::parse(spec, t).expect("a valid spec");
    vec![
        (
            "`--noise` another finite-state noise (e.g. `rpt:…`), T = 0",
            parse("rpt:sigma=1,alpha=1,beta=2", 0.0),
        ),
        (
            "`--temperature T > 0` (thermal noise)",
            parse("telegraph:sigma=1,lambda=0.5", 0.5),
        ),
    ]
}

fn cell(yes: bool) -> &'static str {
    if yes {
        "yes"
    } else {
        "—"
    }
}

/// The table as Markdown: one column per [`Solver`] (in [`Solver::ALL`]'s
/// order), one row per protocol feature, then one per class of noise
/// model. "yes": the method runs it (exactly, or with its stated
/// discretisation error); "—": refused before any work, naming the flag.
pub fn markdown() -> String {
    let mut s = String::from("| | ");
    let heads: Vec<String> = Solver::ALL
        .iter()
        .map(|m| format!("`{}`", m.command()))
        .collect();
    s += &heads.join(" | ");
    s += " |\n|---|";
    s += &"---|".repeat(Solver::ALL.len());
    s.push('\n');
    for f in FEATURES {
        let cells: Vec<&str> = Solver::ALL
            .iter()
            .map(|m| cell(reset_support::supports(*m, f)))
            .collect();
        s += &format!(
            "| `--{}`: {} | {} |\n",
            f.flag().replace('_', "-"),
            f.describe(),
            cells.join(" | ")
        );
    }
    for (label, model) in noise_rows() {
        let cells: Vec<&str> = Solver::ALL
            .iter()
            .map(|m| match (*m, noise::support::supports(*m, &model)) {
                (Solver::ClosedForm, false) => noise::support::CLOSED_FORMS,
                (_, yes) => cell(yes),
            })
            .collect();
        s += &format!("| {label} | {} |\n", cells.join(" | "));
    }
    s
}
