//! Exact r = 0 density: construction (normalisation + <v²>) and per-call
//! pdf / cdf / 100-bin probabilities, for the paper's most singular case
//! (tan, Sigma = 3, lambda = 0.5, a = -0.95) and a smooth one (lambda = 25).
//! Run: `cargo bench -p irtp-bench --bench analytic`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irtp::analytic::r0::R0Density;
use irtp::DragLaw;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("r0");
    for (name, lambda) in [("tan_l0.5", 0.5), ("tan_l25", 25.0)] {
        g.bench_function(format!("new_{name}"), |b| {
            b.iter(|| R0Density::new(DragLaw::Tan, 3.0, black_box(lambda)).unwrap())
        });
        let d = R0Density::new(DragLaw::Tan, 3.0, lambda).unwrap();
        let vu = d.bounds().1;
        g.bench_function(format!("pdf_{name}"), |b| {
            b.iter(|| d.pdf(black_box(0.37 * vu)))
        });
        g.bench_function(format!("cdf_bulk_{name}"), |b| {
            b.iter(|| d.cdf(black_box(0.37 * vu)))
        });
        g.bench_function(format!("cdf_edge_{name}"), |b| {
            b.iter(|| d.cdf(black_box(0.999 * vu)))
        });
        let edges: Vec<f64> = (0..=100)
            .map(|i| -vu + 2.0 * vu * i as f64 / 100.0)
            .collect();
        g.bench_function(format!("bins100_{name}"), |b| {
            b.iter(|| d.bin_probabilities(black_box(&edges)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
