//! Parameters as symbols in titles (`irtp_paper::quicklook::symbols`).

use irtp_paper::quicklook::symbols::{number, param, result, title_parameters};
use serde_json::json;

#[test]
fn titles_name_parameters_as_symbols() {
    let p = json!({"model": {"drag": "tan", "sigma": 3.0, "lambda": 0.9, "rate": 2.0,
                   "reset_velocity": 0.0}, "options": {"cells": 400}});
    assert_eq!(title_parameters(&p, &[]), "tan drag, Σ = 3, λ = 0.9, r = 2");
    assert_eq!(title_parameters(&p, &["rate"]), "tan drag, Σ = 3, λ = 0.9");
    let p = json!({"problem": {"params": {"drag": "tan", "noise": "rpt:sigma=1,alpha=1,beta=1"},
                   "v0": -0.249, "vt": 0.5}});
    assert_eq!(
        title_parameters(&p, &[]),
        "tan drag, rpt noise (Σ = 1, α = 1, β = 1), v_{0} = -0.249, v_{t} = 0.5"
    );
    assert_eq!(result("result.d_eff"), "D_{eff}");
    assert_eq!(param("lambda"), "λ");
    assert_eq!(number(0.31622776601683794), "0.3162");
}
