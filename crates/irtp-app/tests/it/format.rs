//! Numbers as the commands print them (`irtp_app::format`).

use irtp_app::format::{fmt_digits, fmt_pm, fmt_sig};

#[test]
fn plain_values_have_six_significant_digits() {
    assert_eq!(fmt_sig(0.5), "0.5");
    assert_eq!(fmt_sig(3.0), "3");
    assert_eq!(fmt_sig(1.2074918336908644), "1.20749");
    assert_eq!(fmt_sig(-0.000123456789), "-0.000123457");
    assert_eq!(fmt_sig(3.8e-14), "3.8e-14");
    assert_eq!(fmt_sig(1e300), "1e300");
    assert_eq!(fmt_sig(123456.7), "123457");
    assert_eq!(fmt_sig(1234567.0), "1.23457e6");
    assert_eq!(fmt_sig(0.0), "0");
    assert_eq!(fmt_sig(f64::INFINITY), "inf");
    assert_eq!(fmt_digits(0.654137267678795, 12), "0.654137267679");
    assert_eq!(fmt_digits(-4.675079767757495e-16, 12), "-4.67507976776e-16");
}

#[test]
fn errors_have_two_significant_digits_and_values_follow() {
    assert_eq!(fmt_pm(0.0019063, 5.2e-6), "0.0019063 ± 0.0000052");
    assert_eq!(fmt_pm(1.2074918, 0.0123), "1.207 ± 0.012");
    assert_eq!(fmt_pm(3.8e-14, 1.0e-15), "(3.80 ± 0.10)e-14");
    assert_eq!(fmt_pm(2.5e8, 3.1e6), "(2.500 ± 0.031)e8");
    assert_eq!(fmt_pm(12.34, 0.0996), "12.34 ± 0.10");
    assert_eq!(fmt_pm(1234.0, 56.0), "1234 ± 56");
    assert_eq!(fmt_pm(0.5, 0.0), "0.5 ± 0");
    assert_eq!(fmt_pm(1e-20, 1e-9), "(0.0 ± 1.0)e-9");
}
