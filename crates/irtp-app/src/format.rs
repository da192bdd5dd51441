//! Numbers in the text reports: significant digits, never a fixed number of
//! decimals (`0.000000 ± 0.000000` for 3.8e-14) nor hundreds of digits of a
//! huge float. The files (CSV, JSON) keep every digit; only the text for
//! people is rounded here.

/// Significant digits of a plain value.
const SIG: usize = 6;

/// Magnitudes printed without an exponent: 1e-4 <= |x| < 1e6.
fn plain_range(exp: i32) -> bool {
    (-4..6).contains(&exp)
}

/// The decimal exponent of `x` (`floor(log10 |x|)`; 0 for 0).
fn exponent(x: f64) -> i32 {
    if x == 0.0 {
        0
    } else {
        x.abs().log10().floor() as i32
    }
}

/// Drop trailing zeros of a decimal fraction (`2.500` → `2.5`, `3.000` → `3`).
fn trim(s: String) -> String {
    if !s.contains('.') {
        return s;
    }
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// A plain value to 6 significant digits (trailing zeros dropped), in
/// scientific notation outside 1e-4 <= |x| < 1e6: `0.5`, `1.20735`,
/// `3.8e-14`, `1e300`.
pub fn fmt_sig(x: f64) -> String {
    fmt_digits(x, SIG)
}

/// A plain value to `digits` significant digits, as [`fmt_sig`] (used for
/// deterministic results accurate to more than 6 digits).
pub fn fmt_digits(x: f64, digits: usize) -> String {
    let digits = digits.max(1);
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let e = exponent(x);
    if plain_range(e) {
        let decimals = (digits as i32 - 1 - e).max(0) as usize;
        trim(format!("{x:.decimals$}"))
    } else {
        let s = format!("{x:.prec$e}", prec = digits - 1);
        match s.split_once('e') {
            Some((m, exp)) => format!("{}e{exp}", trim(m.to_string())),
            None => s,
        }
    }
}

/// A value with its standard error: the error to 2 significant digits, the
/// value to the same decimal place (`0.0019063 ± 0.0000052`); with a
/// common exponent outside 1e-4 <= |x| < 1e6 (`(3.80 ± 0.10)e-14`). A zero
/// or non-finite error prints both with [`fmt_sig`].
pub fn fmt_pm(value: f64, err: f64) -> String {
    if !(err > 0.0 && err.is_finite() && value.is_finite()) {
        return format!("{} ± {}", fmt_sig(value), fmt_sig(err));
    }
    // Round the error first: 0.0996 becomes 0.10, one place coarser.
    let mut last = exponent(err) - 1;
    if exponent(round_at(err, last)) - 1 > last {
        last += 1;
    }
    let top = exponent(value).max(last + 1);
    if plain_range(top) {
        let decimals = (-last).max(0) as usize;
        format!("{value:.decimals$} ± {err:.decimals$}")
    } else {
        let scale = 10f64.powi(top);
        let decimals = (top - last).max(0) as usize;
        format!(
            "({:.decimals$} ± {:.decimals$})e{top}",
            value / scale,
            err / scale
        )
    }
}

/// `x` rounded to the decimal place `10^place`.
fn round_at(x: f64, place: i32) -> f64 {
    let s = 10f64.powi(place);
    (x / s).round() * s
}
