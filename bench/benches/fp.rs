//! Fokker-Planck solver speed.
//! Targets: stationary solve at 20,000 cells under 50 ms; the two transient
//! schemes at equal accuracy (tan, Sigma = 3, lambda = 0.5, r = 2, to t = 20):
//! the paper's explicit scheme at its resolution (2000 uniform cells, cfl
//! 0.5) has <v²>(20) = 0.6538788570, relative error -1.68e-4 against the
//! reference 0.6539889492 (the state is stationary by t = 20: the stationary
//! solver, 4e5 and 8e5 graded cells extrapolated, agreeing to 5e-11);
//! TR-BDF2 on 120 graded cells (the nested meshes of 120, 60 and 30 cells,
//! extrapolated twice) at rtol 1e-2, atol 1e-6 has error +1.64e-4. The ratio of the two times is the speed-up at equal
//! accuracy.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irtp::fp::{stationary, transient, Mesh, Scheme, StationaryOptions, TransientOptions};
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

fn transient_equal_accuracy(c: &mut Criterion) {
    let mut g = c.benchmark_group("fp_transient");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap();
    let paper = TransientOptions {
        scheme: Scheme::Paper,
        cells: 2000,
        t_max: 20.0,
        times: vec![20.0],
        snapshot_times: vec![],
        cfl: 0.5,
        ..Default::default()
    };
    let trbdf2 = TransientOptions {
        scheme: Scheme::TrBdf2,
        cells: 120,
        rtol: 1e-2,
        atol: 1e-6,
        ..paper.clone()
    };
    for (name, o) in [
        ("paper_2000cells_to_t20", paper),
        ("trbdf2_120cells_to_t20", trbdf2),
    ] {
        g.bench_function(format!("tan_s3_l0.5_r2/{name}"), |b| {
            b.iter(|| black_box(transient(&p, &o).unwrap().v2[0]))
        });
    }
    g.finish();
}

criterion_group!(benches, stationary_20k, transient_equal_accuracy);
criterion_main!(benches);
