//! The crate root (`irtp_paper`): figure names, number format, critical
//! values of the claims and curve seeds.

use irtp_paper::{bonferroni_z, curve_seed, erfc, fmt_num, z_crit, Which};

#[test]
fn names_round_trip() {
    for w in Which::ALL {
        assert_eq!(w.name().parse::<Which>().unwrap(), w);
    }
    assert!("fig4".parse::<Which>().is_err());
}

#[test]
fn number_format() {
    assert_eq!(fmt_num(0.5), "0.5");
    assert_eq!(fmt_num(15.0), "15");
    assert_eq!(fmt_num(0.85), "0.85");
    assert_eq!(fmt_num(2.0), "2");
    assert_eq!(fmt_num(0.123456), "0.123");
}

#[test]
fn critical_z() {
    assert!(
        (bonferroni_z(1) - 2.5758).abs() < 1e-3,
        "{}",
        bonferroni_z(1)
    );
    assert!(
        (bonferroni_z(100) - 3.8906).abs() < 2e-3,
        "{}",
        bonferroni_z(100)
    );
    assert_eq!(z_crit(3), 4.0);
    assert!(z_crit(600) > 4.3 && z_crit(600) < 4.4);
    assert!((erfc(0.0) - 1.0).abs() < 1e-7 && (erfc(-1.0) - 1.842_700_79).abs() < 1e-6);
}

#[test]
fn curve_seeds_differ() {
    let a = curve_seed(1, Which::Fig1, 0);
    assert_ne!(a, curve_seed(1, Which::Fig1, 1));
    assert_ne!(a, curve_seed(1, Which::Fig2, 0));
    assert_ne!(a, curve_seed(2, Which::Fig1, 0));
    assert_eq!(a, curve_seed(1, Which::Fig1, 0));
}
