//! Events per second of the exact sampler with a finite-state noise
//! against the paper's two-state path on the same drag (tan) and run
//! length: the default `--sigma 1 --lambda 1`, the same noise spelt as a
//! two-state generator (the N-state loop, same levels and rates), the
//! run-pause-tumble noise `rpt:sigma=1,alpha=1,beta=1` (every state left at
//! rate 1, as the default's: the same event rate) and an asymmetric
//! telegraph noise. r = 0.5, 256 particles to t = 20, moments at two
//! times and a 100-bin histogram over [5, 20]. The flow tables are built
//! once per process (memoised) and not in the measurement.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use irtp::model::noise::NoiseModel;
use irtp::parallel::NoProgress;
use irtp::sim::exact;
use irtp::sim::{SimSpec, TimeGrid};
use irtp::{DragLaw, Params};

fn spec() -> SimSpec {
    SimSpec::new(
        256,
        TimeGrid::from_times(vec![0.0, 20.0]).unwrap(),
        5.0,
        100,
        1,
    )
    .unwrap()
}

fn noises(c: &mut Criterion) {
    let with = |noise: &str| {
        let m = NoiseModel::parse(noise, 0.0).unwrap();
        Params::with_noise(DragLaw::Tan, m, 0.5, 0.0).unwrap()
    };
    let cases = [
        (
            "default_two_state",
            Params::new(DragLaw::Tan, 1.0, 1.0, 0.5, 0.0).unwrap(),
        ),
        (
            "states_two_state",
            with("states:levels=[1,-1],rates=[[-1,1],[1,-1]]"),
        ),
        ("rpt_three_state", with("rpt:sigma=1,alpha=1,beta=1")),
        (
            "asymmetric_telegraph",
            with("telegraph:plus=1,minus=0.5,rate_plus=1,rate_minus=1"),
        ),
    ];
    let spec = spec();
    let mut g = c.benchmark_group("exact_noise_tan_256_particles_t20");
    g.sample_size(10);
    for (name, p) in &cases {
        // Events of one run (the same every run: fixed seed).
        let events = exact::simulate(p, &spec, &NoProgress).unwrap().steps;
        g.throughput(Throughput::Elements(events));
        g.bench_function(*name, |b| {
            b.iter(|| black_box(exact::simulate(p, &spec, &NoProgress).unwrap().steps))
        });
    }
    g.finish();
}

criterion_group!(benches, noises);
criterion_main!(benches);
