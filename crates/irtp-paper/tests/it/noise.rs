//! The noise figure (`irtp_paper::noise`): the large-rate limit and the
//! admissible noises of both media.

use irtp_paper::noise::{large_rate_limit, NoiseKind, Spec};

#[test]
fn the_large_rate_limit_of_the_paper_is_sigma2_over_2lambda() {
    let spec = Spec::new(true);
    let m = &spec.media[0];
    let p = spec.params(m, NoiseKind::Paper, 1.0).unwrap();
    let want = m.sigma * m.sigma / (2.0 * spec.lambda);
    assert!((large_rate_limit(&p).unwrap() - want).abs() < 1e-12 * want);
    // Thermal alone: 2T.
    let p = spec.params(m, NoiseKind::Thermal, 1.0).unwrap();
    let t = p.chain().unwrap().temperature;
    assert!((large_rate_limit(&p).unwrap() - 2.0 * t).abs() < 1e-14);
}

#[test]
fn every_noise_is_admissible_in_both_media() {
    let spec = Spec::new(true);
    for m in &spec.media {
        for &n in &spec.noises {
            let p = spec.params(m, n, 1.0).unwrap();
            let (lo, hi) = p.bounds();
            assert!(
                lo < spec.passage.0 && spec.passage.1 < hi,
                "{n:?} in {}",
                m.drag
            );
            assert_eq!(p.noise().is_none(), n == NoiseKind::Paper);
        }
    }
}
