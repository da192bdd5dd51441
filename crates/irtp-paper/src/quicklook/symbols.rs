//! Physics symbols for `irtp plot`'s titles, axes and colour bars: the
//! dimensionless quantities as the paper writes them (Σ, λ, r, v_r, D_eff,
//! τ, ⟨x²⟩), from the parameter names of `run.json` and a plan and the
//! column names of `results.csv`.

use crate::plot::fmt_sig;
use serde_json::Value;

/// The symbol of a parameter (a flag's keyword): `sigma` → Σ, `rate` → r,
/// `reset_velocity` → v_{r}; an unknown name as it is.
pub fn param(name: &str) -> String {
    let s = match name {
        "sigma" => "Σ",
        "lambda" => "λ",
        "rate" => "r",
        "reset_velocity" => "v_{r}",
        "reset_position" => "x_{r}",
        "reset_period" => "T_{r}",
        "temperature" => "T",
        "alpha" => "α",
        "beta" => "β",
        "v0" => "v_{0}",
        "vt" => "v_{t}",
        "xt" => "x_{t}",
        "t_max" => "t_{max}",
        "t_min" => "t_{min}",
        "burn_in" => "t_{burn-in}",
        "dt" => "Δt",
        "particles" => "N",
        "plus" => "η_{+}",
        "minus" => "η_{-}",
        "rate_plus" => "λ_{+}",
        "rate_minus" => "λ_{-}",
        _ => return name.replace('_', " "),
    };
    s.to_string()
}

/// The symbol of a result column (`result.` may lead): `d_eff` → D_{eff},
/// `v2` → ⟨v²⟩, `tau` → τ; an unknown name with `_` as spaces.
pub fn result(column: &str) -> String {
    let name = column.strip_prefix("result.").unwrap_or(column);
    let s = match name {
        "d_eff" => "D_{eff}",
        "d_eff_msd" => "D_{eff} (from ⟨x²⟩)",
        "v2" => "⟨v²⟩",
        "v_mean" => "⟨v⟩",
        "v2_final" => "⟨v²⟩(t_{max})",
        "x2_final" => "⟨x²⟩(t_{max})",
        "x_final" => "⟨x⟩(t_{max})",
        "tau" => "τ",
        "tau_plus" => "τ_{+}",
        "tau_minus" => "τ_{-}",
        "tau_opt" => "τ_{opt}",
        "r_opt" => "r_{opt}",
        "refractory_mass" => "refractory mass",
        "error_estimate" => "error estimate of τ",
        "edge_exponent" => "edge exponent",
        _ => return name.replace('_', " "),
    };
    s.to_string()
}

/// A number as a title writes it: shortest form, at most 4 significant digits.
pub fn number(v: f64) -> String {
    let short = v.to_string();
    if short.len() <= 6 {
        return short;
    }
    fmt_sig(v, 4)
}

/// `Σ = 3` from a parameter's name and JSON value (`tan drag` for the
/// drag, the noise spec with its keys as symbols); `None` for a value that
/// says nothing (null, a zero reset velocity or temperature).
pub fn assignment(name: &str, v: &Value) -> Option<String> {
    let text = match v {
        Value::Null => return None,
        Value::Number(n) => {
            let x = n.as_f64()?;
            if x == 0.0 && matches!(name, "reset_velocity" | "temperature") {
                return None;
            }
            number(x)
        }
        Value::String(s) => s.clone(),
        Value::Bool(b) => b.to_string(),
        _ => return None,
    };
    Some(match name {
        "drag" => format!("{text} drag"),
        "noise" => noise(&text),
        _ => format!("{} = {text}", param(name)),
    })
}

/// A noise spec with its keys as symbols: `rpt:sigma=1,alpha=1,beta=1` →
/// `rpt noise (Σ = 1, α = 1, β = 1)`.
pub fn noise(spec: &str) -> String {
    let Some((kind, rest)) = spec.split_once(':') else {
        return format!("{spec} noise");
    };
    if rest.contains('[') {
        return format!("{kind} noise");
    }
    let keys: Vec<String> = rest
        .split(',')
        .map(|kv| match kv.split_once('=') {
            Some((k, v)) => format!("{} = {v}", param(k.trim())),
            None => kv.to_string(),
        })
        .collect();
    format!("{kind} noise ({})", keys.join(", "))
}

/// The model object of a run's `parameters` (the one with a `drag`, at
/// any depth: `model`, `problem.params`, `base.params`).
pub fn model(params: &Value) -> Option<&Value> {
    if params.get("drag").is_some() {
        return Some(params);
    }
    params.as_object()?.values().find_map(model)
}

/// The model's parameters a title names, in this order.
const MODEL_KEYS: [&str; 8] = [
    "drag",
    "noise",
    "sigma",
    "lambda",
    "rate",
    "reset_velocity",
    "reset_period",
    "temperature",
];

/// The parameters a physicist reads a figure by, for a title: drag,
/// noise (Σ, λ or the noise spec), reset rate and velocity, temperature,
/// then a search's v₀, v_t, x_t where the run has them; not the
/// parameters in `scanned` (a scan's axis, the rate `mfpt optimize` searches).
pub fn title_parameters(params: &Value, scanned: &[&str]) -> String {
    let mut out: Vec<String> = Vec::new();
    if let Some(m) = model(params) {
        for k in MODEL_KEYS.iter().filter(|k| !scanned.contains(k)) {
            out.extend(m.get(*k).and_then(|v| assignment(k, v)));
        }
    }
    let search = params
        .get("problem")
        .or_else(|| params.get("base"))
        .unwrap_or(params);
    for k in ["v0", "vt", "xt", "reset_position"]
        .into_iter()
        .filter(|k| !scanned.contains(k))
    {
        if let Some(v) = search.get(k).or_else(|| params.get(k)) {
            out.extend(assignment(k, v));
        }
    }
    out.join(", ")
}
