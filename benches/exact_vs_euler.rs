//! Per-event cost of the exact sampler's kernels and one particle of each
//! method over the same simulated time (tan Sigma = 3, lambda = 0.5, r = 2).
//! The efficiency comparison at equal statistical error is
//! `cargo run --release --example efficiency`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irtp::model::drag::Flow;
use irtp::model::Drag;
use irtp::parallel::NoProgress;
use irtp::sim::exact::{self, DeficitTable};
use irtp::sim::{SimSpec, TimeGrid};
use irtp::{DragLaw, Params};
use rand::Rng as _;

fn kernels(c: &mut Criterion) {
    for (d, sigma) in [
        (DragLaw::Tan, 3.0),
        (DragLaw::Tanh, 0.6),
        (DragLaw::Linear, 1.0),
    ] {
        let f = Flow::new(d, sigma);
        let vu = d.inverse(sigma);
        c.bench_function(&format!("flow_velocity/{d}"), |b| {
            let mut k = 0u32;
            b.iter(|| {
                k = k.wrapping_add(1);
                let v0 = -0.9 * vu + 1.8 * vu * ((k % 97) as f64 / 97.0);
                let t = 0.05 + (k % 13) as f64 * 0.3;
                black_box(f.velocity(black_box(v0), black_box(t)))
            })
        });
        let guide = irtp::model::drag::InverseGuide::new(&f);
        c.bench_function(&format!("flow_velocity_guided/{d}"), |b| {
            let mut k = 0u32;
            b.iter(|| {
                k = k.wrapping_add(1);
                let v0 = -0.9 * vu + 1.8 * vu * ((k % 97) as f64 / 97.0);
                let t = 0.05 + (k % 13) as f64 * 0.3;
                black_box(f.velocity_guided(black_box(v0), black_box(t), &guide))
            })
        });
        c.bench_function(&format!("flow_time/{d}"), |b| {
            b.iter(|| black_box(f.time(black_box(-0.5 * vu), black_box(0.8 * vu))))
        });
        let t = DeficitTable::new(&d, sigma, -vu, vu).unwrap();
        c.bench_function(&format!("deficit_table/{d}"), |b| {
            b.iter(|| black_box(t.deficits(black_box(-0.5 * vu), black_box(0.8 * vu))))
        });
    }
}

fn particles(c: &mut Criterion) {
    let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap();
    let spec = SimSpec::new(
        256,
        TimeGrid::from_times(vec![0.0, 20.0]).unwrap(),
        5.0,
        100,
        1,
    )
    .unwrap();
    let mut g = c.benchmark_group("256_particles_t20");
    g.sample_size(10);
    g.bench_function("exact", |b| {
        b.iter(|| black_box(exact::simulate(&p, &spec, &NoProgress).unwrap().steps))
    });
    g.bench_function("first_passage_exact", |b| {
        let mut r = irtp::rng::stream(3, 0);
        let fpt = exact::FirstPassage::new(&p);
        b.iter(|| black_box(fpt.run(0.0, 0.8, true, 1e6, &mut r)))
    });
    // The paper's Euler scheme over the same time span (dt = 1e-3, one
    // uniform per step for the flip and one for the reset), for scale.
    g.bench_function("euler_dt1e-3", |b| {
        let (dt, sigma, lambda, r) = (1e-3, 3.0, 0.5, 2.0);
        let pf = 0.5 * (1.0 - (-2.0f64 * lambda * dt).exp());
        b.iter(|| {
            let mut acc = 0.0;
            for i in 0..256u64 {
                let mut rng = irtp::rng::stream(1, i);
                let mut eta: f64 = if rng.gen::<bool>() { sigma } else { -sigma };
                let mut v = 0.0f64;
                for _ in 0..20_000 {
                    v += dt * (eta - v.tan());
                    if rng.gen::<f64>() < pf {
                        eta = -eta;
                    }
                    if rng.gen::<f64>() < r * dt {
                        v = 0.0;
                    }
                    acc += v * v;
                }
            }
            black_box(acc)
        })
    });
    g.finish();
}

criterion_group!(benches, kernels, particles);
criterion_main!(benches);
