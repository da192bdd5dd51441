//! Progress bars (`irtp_cli::cli::progress`): the unit of each stage and
//! the estimate of the time left.

use irtp_cli::cli::progress::{fmt_left, time_left, unit_of, Unit};
use std::time::Duration;

#[test]
fn units_and_estimates() {
    assert_eq!(unit_of("simulate"), Unit::Count("particles"));
    assert_eq!(unit_of("point 3"), Unit::Count("particles"));
    assert_eq!(unit_of("mfpt scan"), Unit::Count("points"));
    assert_eq!(unit_of("fig7"), Unit::Percent);
    let s = Duration::from_secs;
    assert_eq!(time_left(s(10), 0.25), Some(s(30)));
    assert_eq!(time_left(s(10), 0.01), None, "too little done");
    assert_eq!(
        time_left(Duration::from_millis(500), 0.5),
        None,
        "too early"
    );
    assert_eq!(time_left(s(10), f64::NAN), None);
    assert_eq!(fmt_left(Some(s(185))), "~3 min 05 s left");
    assert_eq!(fmt_left(Some(s(12))), "~12 s left");
    assert_eq!(fmt_left(None), "");
}
