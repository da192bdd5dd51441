//! Per-event cost of the exact sampler's kernels and one particle of each
//! method over the same simulated time (tan Sigma = 3, lambda = 0.5, r = 2).
//! The efficiency comparison at equal statistical error is
//! `cargo run --release --example efficiency`.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use irtp::model::drag::{Cubic, Linear, PotentialTable, Power, Tan, Tanh};
use irtp::model::reset::periodic::Periodic;
use irtp::model::reset::position::PositionReset;
use irtp::model::reset::Schedule;
use irtp::model::{Drag, FlowMap};
use irtp::parallel::NoProgress;
use irtp::sim::exact::{self, DeficitTable};
use irtp::sim::{SimSpec, TimeGrid};
use irtp::{DragLaw, Params};
use rand::Rng as _;

fn kernels(c: &mut Criterion) {
    kernels_for(c, "tan", Tan, 3.0);
    kernels_for(c, "tanh", Tanh, 0.6);
    kernels_for(c, "linear", Linear, 1.0);
    kernels_for(c, "cubic", Cubic, 3.0);
    kernels_for(c, "power:n=0.5", Power::new(0.5, 1.0).unwrap(), 3.0);
    kernels_for(c, "power:n=2", Power::new(2.0, 1.0).unwrap(), 3.0);
}

/// Flow velocity (plain and accelerated), flow time and deficit lookup of
/// one law (`name`, its spec), monomorphised as the sampler runs it.
fn kernels_for<D: Drag>(c: &mut Criterion, name: &str, d: D, sigma: f64) {
    let f = d.flow(sigma);
    let vu = d.inverse(sigma);
    let bench_velocity = |c: &mut Criterion, label: &str, f: &D::Flow| {
        c.bench_function(&format!("{label}/{name}"), |b| {
            let mut k = 0u32;
            b.iter(|| {
                k = k.wrapping_add(1);
                let v0 = -0.9 * vu + 1.8 * vu * ((k % 97) as f64 / 97.0);
                let t = 0.05 + (k % 13) as f64 * 0.3;
                black_box(f.velocity(black_box(v0), black_box(t)))
            })
        });
    };
    bench_velocity(c, "flow_velocity", &f);
    bench_velocity(c, "flow_velocity_guided", &f.clone().accelerated());
    c.bench_function(&format!("flow_time/{name}"), |b| {
        b.iter(|| black_box(f.time(black_box(-0.5 * vu), black_box(0.8 * vu))))
    });
    // The exact sampler's segment: velocity, potential and both deficit
    // antiderivatives after time t from two table lookups.
    if let Some(tab) = PotentialTable::new(&d, sigma) {
        c.bench_function(&format!("potential_table_advance/{name}"), |b| {
            let mut k = 0u32;
            b.iter(|| {
                k = k.wrapping_add(1);
                let v0 = -0.9 * vu + 1.8 * vu * ((k % 97) as f64 / 97.0);
                let t = 0.05 + (k % 13) as f64 * 0.3;
                let p = tab.at(black_box(v0));
                black_box(tab.advance(&p, black_box(t)))
            })
        });
    }
    let t = DeficitTable::new(&d, sigma, -vu, vu).unwrap();
    c.bench_function(&format!("deficit_table/{name}"), |b| {
        b.iter(|| black_box(t.deficits(black_box(-0.5 * vu), black_box(0.8 * vu))))
    });
}

/// 256 particles to t = 20: moments at t = 0 and 20, a 100-bin histogram
/// over [5, 20] (the Fig. 2 workload).
fn fig2_workload() -> SimSpec {
    SimSpec::new(
        256,
        TimeGrid::from_times(vec![0.0, 20.0]).unwrap(),
        5.0,
        100,
        1,
    )
    .unwrap()
}

fn particles(c: &mut Criterion) {
    let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap();
    let spec = fig2_workload();
    let mut g = c.benchmark_group("256_particles_t20");
    g.sample_size(10);
    g.bench_function("exact", |b| {
        b.iter(|| black_box(exact::simulate(&p, &spec, &NoProgress).unwrap().steps))
    });
    g.bench_function("first_passage_exact", |b| {
        let mut r = irtp::rng::stream(3, 0);
        let fpt = irtp::mfpt::FirstPassage::new(&p);
        b.iter(|| black_box(fpt.run(0.0, 0.8, 0, 1e6, &mut r)))
    });
    // The same passage with the martingale control variate alongside
    // (u piecewise constant on 2048 cells): its cost per event.
    g.bench_function("first_passage_controlled", |b| {
        use irtp::mfpt::control::{controlled_walk, PassageControl};
        let mut r = irtp::rng::stream(3, 0);
        let fpt = irtp::mfpt::FirstPassage::new(&p);
        let (vl, _) = p.bounds();
        let ctl =
            PassageControl::new(&fpt, vl, 0.8, 2048, |v, s| v + f64::from(u8::from(s))).unwrap();
        b.iter(|| black_box(controlled_walk(&fpt, &ctl, (0.0, 0.8, 0, 1e6), &mut r)))
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

/// Events per second of the exact sampler on the Fig. 2 workload (moments at
/// two times plus a 100-bin histogram, t = 20 per particle) for the closed-form
/// laws (Coulomb friction: closed-form velocity, deficit table in v) and for
/// `cubic`, the power law (n = 0.5: g'(0) = ∞; n = 2) and two expression
/// laws (`expr:tan(v)`, `expr:v + 0.3*v^3`), laws given by g and g'
/// (tabulated flow). The flow tables of a (law, Sigma, bins) are built once
/// per process and shared ([`irtp::memo`]), as between the curves of a
/// figure or the points of a sweep, so this measures the events; the one
/// cold build per process is not in it (measured with 2 particles: about
/// 2 ms for tan, 5 ms for the power law n = 0.5, 30-90 ms for a law
/// evaluated through an expression).
fn events_per_law(c: &mut Criterion) {
    let mut g = c.benchmark_group("exact_events");
    g.sample_size(10);
    for (law, sigma, lambda, r) in [
        ("tan", 3.0, 0.5, 2.0),
        ("tanh", 0.6, 0.5, 2.0),
        ("linear", 3.0, 0.5, 2.0),
        ("coulomb:mu=0.5", 3.0, 0.5, 2.0),
        ("cubic", 3.0, 0.5, 2.0),
        ("power:n=0.5", 3.0, 0.5, 2.0),
        ("power:n=2", 3.0, 0.5, 2.0),
        ("expr:tan(v)", 3.0, 0.5, 2.0),
        ("expr:v + 0.3*v^3", 3.0, 0.5, 2.0),
    ] {
        let drag: DragLaw = law.parse().expect("registered law");
        let p = Params::new(drag, sigma, lambda, r, 0.0).unwrap();
        let spec = fig2_workload();
        let events = exact::simulate(&p, &spec, &NoProgress).unwrap().steps;
        g.throughput(Throughput::Elements(events));
        g.bench_function(law, |b| {
            b.iter(|| black_box(exact::simulate(&p, &spec, &NoProgress).unwrap().steps))
        });
    }
    g.finish();
}

/// Events per second of the exact sampler's one kernel (`Clocks::walk`
/// with the simulation's recorder) under each modifier of the resetting
/// rule, on the Fig. 2 workload (tan, Sigma = 3, lambda = 0.5): the
/// paper's protocol (r = 2), a refractory period after each Poisson reset,
/// a periodic clock, and a renewal clock with position resetting and a
/// refractory period (events: flips, resets and, during a hold, the
/// noise's jumps and the release).
fn events_per_schedule(c: &mut Criterion) {
    let mut g = c.benchmark_group("exact_events_schedule");
    g.sample_size(10);
    let refractory = Some("exp:mean=0.3".parse().unwrap());
    let cases = [
        ("plain", 2.0, Schedule::default()),
        (
            "refractory",
            2.0,
            Schedule {
                refractory,
                ..Schedule::default()
            },
        ),
        (
            "periodic",
            0.0,
            Schedule {
                periodic: Some(Periodic { period: 0.5 }),
                ..Schedule::default()
            },
        ),
        (
            "renewal_position_refractory",
            0.0,
            Schedule {
                clock: Some("gamma:k=2,theta=0.25".parse().unwrap()),
                position: Some(PositionReset { x: 0.0 }),
                refractory,
                ..Schedule::default()
            },
        ),
    ];
    for (name, r, schedule) in cases {
        let p = Params::new(DragLaw::Tan, 3.0, 0.5, r, 0.0)
            .and_then(|p| p.with_schedule(schedule))
            .unwrap();
        let spec = fig2_workload();
        let events = exact::simulate(&p, &spec, &NoProgress).unwrap().steps;
        g.throughput(Throughput::Elements(events));
        g.bench_function(name, |b| {
            b.iter(|| black_box(exact::simulate(&p, &spec, &NoProgress).unwrap().steps))
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    kernels,
    particles,
    events_per_law,
    events_per_schedule
);
criterion_main!(benches);
