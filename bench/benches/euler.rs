//! Euler kernel throughput (particle-steps per second), single thread:
//! tan drag, Sigma = 3, lambda = 0.5, r = 2, dt = 1e-3 (the CLI defaults).
//! Run: `cargo bench -p irtp-bench --bench euler`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use irtp::parallel::NoProgress;
use irtp::sim::euler::{self, EventSampling};
use irtp::sim::{SimSpec, TimeGrid};
use irtp::{DragLaw, Params};

fn bench(c: &mut Criterion) {
    let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap();
    let (particles, t_max, dt) = (256u64, 4.0, 1e-3);
    let spec = SimSpec::new(particles, TimeGrid::linear(t_max, 41).unwrap(), 2.0, 100, 1).unwrap();
    let steps = particles * (t_max / dt).round() as u64;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("euler_tan_1thread");
    g.throughput(Throughput::Elements(steps));
    g.sample_size(10);
    for (name, sampling) in [
        ("geometric", EventSampling::Geometric),
        ("bernoulli", EventSampling::Bernoulli),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                pool.install(|| euler::simulate_with(&p, &spec, dt, sampling, &NoProgress).unwrap())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
