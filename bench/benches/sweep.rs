//! Sweep overhead: 100 small `fp stationary` points through `irtp_app::sweep::run`
//! (plan checks, point directories, statepoints, results, results.csv)
//! against the same 100 computations through `irtp_app::run` writing the
//! same outputs, side by side. (sweep - app) / 100 is the overhead per
//! point; the target is under 5 ms.
//!
//!     cargo bench -p irtp-bench --bench sweep

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use irtp_app::sweep::{self, Plan, RunOptions, Shard};
use irtp_app::{self as app, keywords, Context, Quiet};
use rayon::prelude::*;

const PLAN: &str = r#"
command = "fp stationary"
[fixed]
drag = "tan"
lambda = 0.5
cells = 200
[axes]
sigma = { from = 0.5, to = 5.0, points = 10 }
rate = { from = 0.01, to = 100.0, points = 10, spacing = "log" }
"#;

fn bench(c: &mut Criterion) {
    let plan = Plan::parse(PLAN).unwrap();
    let mut g = c.benchmark_group("sweep_100_points");
    g.sample_size(10);
    g.bench_function("app_run_each_point", |b| {
        b.iter_batched(
            || tempfile::tempdir().unwrap(),
            |tmp| {
                plan.points().collect::<Vec<_>>().par_iter().for_each(|p| {
                    let argv = plan.argv(p, Some(&tmp.path().join(&p.id))).unwrap();
                    let cli = keywords::parse::<app::Cli>(&plan.command, &argv).unwrap();
                    let ctx = Context {
                        reporter: &Quiet,
                        argv,
                    };
                    app::run(&cli.command, &ctx).unwrap();
                });
                tmp
            },
            BatchSize::PerIteration,
        )
    });
    g.bench_function("sweep_run", |b| {
        b.iter_batched(
            || tempfile::tempdir().unwrap(),
            |tmp| {
                let opts = RunOptions {
                    shard: Shard::ALL,
                    retry_failed: false,
                };
                let r = sweep::run(&plan, tmp.path(), opts, &()).unwrap();
                assert!(r.table.is_some());
                tmp
            },
            BatchSize::PerIteration,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
