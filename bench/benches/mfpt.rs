//! Speed target: one backward-equation solve at 40,000 cells under 50 ms.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irtp::mfpt::backward::profile;
use irtp::mfpt::{BackwardOptions, Problem};
use irtp::{DragLaw, Params};

fn backward(c: &mut Criterion) {
    let opts = BackwardOptions::with_cells(40_000);
    for (name, drag, sigma, rate) in [
        ("backward_40k_tan_r2", DragLaw::Tan, 3.0, 2.0),
        ("backward_40k_tanh_r0.2", DragLaw::Tanh, 0.6, 0.2),
    ] {
        let p = Problem::new(
            Params::new(drag, sigma, 0.5, rate, 0.0).unwrap(),
            -0.249,
            0.5,
        )
        .unwrap();
        c.bench_function(name, |b| {
            b.iter(|| profile(black_box(&p), &opts).unwrap().at_start().tau)
        });
    }
}

criterion_group!(benches, backward);
criterion_main!(benches);
