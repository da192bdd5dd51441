//! `irtp plot` (`irtp_paper::quicklook`): plan order, the sweep column,
//! PNG chunk checksums and the image path.

use irtp_paper::quicklook::{choose_var, crc32, digits, image_kind};

mod symbols;

fn axes(ns: &[usize]) -> Vec<(Vec<String>, usize)> {
    ns.iter().map(|&n| (vec![format!("a{n}")], n)).collect()
}

#[test]
fn digits_follow_plan_order_first_axis_slowest() {
    let c = axes(&[3, 2, 2]);
    assert_eq!(digits(0, &c), Some(vec![0, 0, 0]));
    assert_eq!(digits(1, &c), Some(vec![0, 0, 1]));
    assert_eq!(digits(6, &c), Some(vec![1, 1, 0]));
    assert_eq!(digits(11, &c), Some(vec![2, 1, 1]));
    assert_eq!(digits(12, &c), None);
}

#[test]
fn var_takes_the_prefix_or_not_and_defaults_to_the_first_result() {
    let h: Vec<String> = ["point", "sigma", "status", "result.v2", "result.d_eff"]
        .map(String::from)
        .to_vec();
    let r = vec![
        csv::StringRecord::from(vec!["0", "1.0", "ok", "0.5", "2.0"]),
        csv::StringRecord::from(vec!["1", "2.0", "failed", "", ""]),
    ];
    assert_eq!(choose_var(&h, &r, None).unwrap(), "result.v2");
    assert_eq!(choose_var(&h, &r, Some("d_eff")).unwrap(), "result.d_eff");
    assert_eq!(
        choose_var(&h, &r, Some("result.d_eff")).unwrap(),
        "result.d_eff"
    );
    assert_eq!(choose_var(&h, &r, Some("sigma")).unwrap(), "sigma");
    let err = choose_var(&h, &r, Some("tau")).unwrap_err().to_string();
    assert!(err.contains("result.v2, result.d_eff"), "{err}");
    let err = choose_var(&h, &r, Some("status")).unwrap_err().to_string();
    assert!(err.contains("not") && err.contains("result.v2"), "{err}");
    assert!(choose_var(&h[..3], &r, None).is_err());
}

#[test]
fn crc32_of_png_chunks() {
    // The IEND chunk's CRC, as every PNG ends with it.
    assert_eq!(crc32(b"IEND"), 0xAE42_6082);
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
}

#[test]
fn out_must_be_png_or_svg_in_an_existing_directory() {
    let tmp = tempfile::tempdir().unwrap();
    assert!(!image_kind(&tmp.path().join("a.png")).unwrap());
    assert!(image_kind(&tmp.path().join("a.SVG")).unwrap());
    assert!(image_kind(&tmp.path().join("a.pdf")).is_err());
    assert!(image_kind(&tmp.path().join("no/a.png")).is_err());
    let dir = tmp.path().join("d.png");
    std::fs::create_dir(&dir).unwrap();
    assert!(image_kind(&dir).is_err());
}
