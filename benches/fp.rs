//! Fokker-Planck solver speed.
//! Targets: stationary solve at 20,000 cells under 50 ms; the paper-style
//! explicit time stepping to steady state at the paper's resolution is timed
//! for reference (tan, Sigma = 3, 2000 cells, to t = 20).

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irtp::fp::{stationary, transient, Mesh, StationaryOptions, TransientOptions};
use irtp::{DragLaw, Params};
use std::time::Duration;

fn stationary_20k(c: &mut Criterion) {
    let mut g = c.benchmark_group("fp_stationary");
    for (name, p) in [
        (
            "tan_s3_l0.9_r0",
            Params::new(DragLaw::Tan, 3.0, 0.9, 0.0, 0.0).unwrap(),
        ),
        (
            "tan_s3_l0.5_r2",
            Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap(),
        ),
        (
            "tanh_s0.6_l0.5_r2",
            Params::new(DragLaw::Tanh, 0.6, 0.5, 2.0, 0.0).unwrap(),
        ),
    ] {
        for (mesh, extrapolate) in [
            (Mesh::Graded, true),
            (Mesh::Graded, false),
            (Mesh::Uniform, false),
        ] {
            let o = StationaryOptions {
                cells: 20_000,
                mesh,
                extrapolate,
            };
            let id = format!(
                "{name}/{}/{}",
                mesh.name(),
                if extrapolate { "extrap" } else { "single" }
            );
            g.bench_function(id, |b| b.iter(|| black_box(stationary(&p, &o).unwrap().v2)));
        }
    }
    g.finish();
}

fn transient_paper(c: &mut Criterion) {
    let mut g = c.benchmark_group("fp_transient");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap();
    let o = TransientOptions {
        cells: 2000,
        t_max: 20.0,
        times: vec![20.0],
        snapshot_times: vec![],
        cfl: 0.5,
    };
    g.bench_function("tan_s3_l0.5_r2_2000cells_to_t20", |b| {
        b.iter(|| black_box(transient(&p, &o).unwrap().v2[0]))
    });
    g.finish();
}

criterion_group!(benches, stationary_20k, transient_paper);
criterion_main!(benches);
