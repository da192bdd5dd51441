//! Cost budgets (`irtp_app::budget`): a refusal names the drivers and the limit.

use irtp_app::budget::{mesh, particles, BudgetArgs};

#[test]
fn over_budget_names_drivers_and_limit() {
    let c = particles(
        1_000_000_000_000,
        50.0,
        "particle events",
        vec!["particles", "t_max"],
        201,
        100,
    );
    let e = BudgetArgs::default().check(&c).unwrap_err();
    assert!(e.is_input_error());
    let msg = e.message_with(|n| format!("--{}", n.replace('_', "-")));
    assert!(msg.contains("5.00e13 particle events"), "{msg}");
    assert!(
        msg.contains("--particles, --t-max") && msg.contains("--max-work"),
        "{msg}"
    );
    let small = particles(20_000, 250.0, "particle events", vec![], 201, 100);
    BudgetArgs::default().check(&small).unwrap();
    let huge_samples = particles(20_000, 250.0, "particle events", vec![], 1 << 30, 100);
    let e = BudgetArgs::default().check(&huge_samples).unwrap_err();
    assert!(e.to_string().contains("bytes of memory"), "{e}");
    let nan = mesh(10, f64::NAN, 8.0, vec![]);
    assert!(BudgetArgs::default().check(&nan).is_err());
}
