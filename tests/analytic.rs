use irtp::analytic::r0::*;
use irtp::DragLaw;

#[test]
fn explore() {
    for (d, s, l) in [
        (DragLaw::Tan, 3.0, 0.9),
        (DragLaw::Tan, 3.0, 0.5),
        (DragLaw::Tan, 3.0, 7.0),
        (DragLaw::Tan, 3.0, 15.0),
        (DragLaw::Tan, 3.0, 25.0),
        (DragLaw::Tanh, 0.6, 0.5),
        (DragLaw::Tanh, 0.6, 0.85),
        (DragLaw::Tanh, 0.6, 1.2),
        (DragLaw::Tanh, 0.6, 3.0),
        (DragLaw::Linear, 1.0, 0.5),
        (DragLaw::Linear, 2.0, 3.0),
        (DragLaw::Tan, 3.0, 1e4),
    ] {
        let t = std::time::Instant::now();
        let p = R0Density::new(d, s, l).unwrap();
        let el = t.elapsed();
        eprintln!(
            "{d} {s} {l}: v2 {:.15} v4 {:.15} norm {:?} cdf0 {} t {:?} {}",
            p.v2(),
            p.moment(4),
            p.normalisation(),
            p.cdf(0.0),
            el,
            p.regime().description
        );
    }
}
