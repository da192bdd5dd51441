//! Sharding: disjoint particle ranges of one run (`SimSpec::shard`), merged
//! with `Observables::merge`, give the statistics of the whole run, for both
//! samplers. Counts and event totals agree exactly; sums and sums of squares
//! agree up to the rounding of a different summation order.
//!
//! Unit-aligned shards (`sim::simulate_units`, `sim::combine_units`) give the
//! whole run bit for bit, for both samplers and any thread count, also after
//! a JSON round trip of every shard.

use crate::common::models;
use irtp::parallel::NoProgress;
use irtp::parallel::UNIT;
use irtp::sim::{self, Method, Observables, SimSpec, TimeGrid};
use irtp::stats::MeanAcc;

fn spec(particles: u64) -> SimSpec {
    SimSpec::new(particles, TimeGrid::linear(3.0, 7).unwrap(), 1.0, 12, 99).unwrap()
}

fn same(a: &MeanAcc, b: &MeanAcc, what: &str) {
    assert_eq!(a.n, b.n, "{what}: counts");
    for (x, y) in [(a.sum, b.sum), (a.sum_sq, b.sum_sq)] {
        assert!(
            (x - y).abs() <= 1e-12 * x.abs().max(y.abs()).max(1e-300),
            "{what}: {x} vs {y}"
        );
    }
}

fn all_same(a: &Observables, b: &Observables) {
    assert_eq!(a.steps, b.steps, "events / steps");
    same(&a.v2_time_avg, &b.v2_time_avg, "time-averaged v²");
    same(&a.v_time_avg, &b.v_time_avg, "time-averaged v");
    for k in 0..a.times.len() {
        same(&a.v2[k], &b.v2[k], "v²(t)");
        same(&a.x2[k], &b.x2[k], "x²(t)");
        same(&a.x[k], &b.x[k], "x(t)");
    }
    for k in 0..a.density_time.len() {
        same(&a.density_time[k], &b.density_time[k], "occupation density");
        same(&a.density_final[k], &b.density_final[k], "final histogram");
    }
}

#[test]
fn shards_merge_into_the_whole_run() {
    let p = models::tan(0.9, 2.0);
    for method in [Method::Exact, Method::euler(1e-3)] {
        let whole = sim::simulate(&p, &spec(1000), method, &NoProgress).unwrap();
        // Uneven split, not on chunk boundaries.
        let cuts = [0u64, 300, 301 + 2, 777, 1000];
        let mut merged: Option<Observables> = None;
        for w in cuts.windows(2) {
            let s = spec(w[1] - w[0]).shard(w[0]).unwrap();
            let part = sim::simulate(&p, &s, method, &NoProgress).unwrap();
            match &mut merged {
                None => merged = Some(part),
                Some(m) => m.merge(&part),
            }
        }
        let merged = merged.unwrap();
        assert_eq!(merged.particles(), 1000);
        all_same(&whole, &merged);
        // Shards are different particles, not the same ones again.
        let a = sim::simulate(&p, &spec(200), method, &NoProgress).unwrap();
        let b = sim::simulate(&p, &spec(200).shard(200).unwrap(), method, &NoProgress).unwrap();
        assert_ne!(a.v2_time_avg.sum, b.v2_time_avg.sum);
    }
}

#[test]
fn shard_range_is_validated() {
    assert!(spec(10).shard(u64::MAX - 5).is_err());
    assert!(spec(10).shard(u64::MAX - 10).is_ok());
}

/// Three units and a bit, on a short run (t_max = 0.5) so Euler stays fast.
fn unit_spec() -> SimSpec {
    SimSpec::new(
        3 * UNIT + 123,
        TimeGrid::linear(0.5, 6).unwrap(),
        0.2,
        12,
        7,
    )
    .unwrap()
}

/// A shard's unit totals as they come back from disk: JSON text, parsed.
fn round_trip(units: &[Observables]) -> Vec<Observables> {
    let text = serde_json::to_string(units).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn unit_shards_combine_into_the_whole_run_bit_for_bit() {
    let p = models::tan(0.9, 2.0);
    let s = unit_spec();
    assert_eq!(sim::unit_count(s.particles), 4);
    let bernoulli = Method::Euler {
        dt: 1e-3,
        events: irtp::sim::euler::EventSampling::Bernoulli,
    };
    for method in [Method::Exact, Method::euler(1e-3), bernoulli] {
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let whole = sim::simulate(&p, &s, method, &NoProgress).unwrap();
                assert_eq!(whole.particles(), s.particles);
                let mut units = Vec::new();
                for shard in [0..1, 1..3, 3..4] {
                    let part = sim::simulate_units(&p, &s, method, shard, &NoProgress).unwrap();
                    units.extend(round_trip(&part));
                }
                assert_eq!(units.len(), 4);
                let combined = sim::combine_units(&p, &s, method, &units).unwrap();
                assert!(combined == whole, "{method:?}, {threads} threads");
                let bits = |o: &Observables| o.v2_time_avg.sum.to_bits();
                assert_eq!(bits(&combined), bits(&whole));
                // Every unit at once is the same again.
                let all = sim::simulate_units(&p, &s, method, 0..4, &NoProgress).unwrap();
                assert!(sim::combine_units(&p, &s, method, &all).unwrap() == whole);
            });
        }
    }
}

#[test]
fn observables_survive_a_json_round_trip() {
    let p = models::tan(0.9, 2.0);
    for method in [Method::Exact, Method::euler(1e-3)] {
        let o = sim::simulate(&p, &spec(300), method, &NoProgress).unwrap();
        let text = serde_json::to_string(&o).unwrap();
        let back: Observables = serde_json::from_str(&text).unwrap();
        assert!(back == o, "{method:?}");
        let bits = |o: &Observables| -> Vec<u64> {
            let k = o.times.len() - 1;
            [
                o.v2[k].sum,
                o.x2[k].sum_sq,
                o.v_time_avg.sum,
                o.density_time[3].sum,
            ]
            .map(f64::to_bits)
            .to_vec()
        };
        assert_eq!(bits(&back), bits(&o));
    }
}

#[test]
fn unit_ranges_and_foreign_units_are_refused() {
    let p = models::tan(0.9, 2.0);
    let s = spec(1000);
    assert_eq!(sim::unit_count(1000), 1);
    assert!(sim::simulate_units(&p, &s, Method::Exact, 0..2, &NoProgress).is_err());
    #[allow(clippy::reversed_empty_ranges)]
    let backwards = 1..0;
    assert!(sim::simulate_units(&p, &s, Method::Exact, backwards, &NoProgress).is_err());
    assert!(
        sim::simulate_units(&p, &s, Method::Exact, 1..1, &NoProgress)
            .unwrap()
            .is_empty()
    );
    // Units of a run with another time grid are refused.
    let other = SimSpec::new(1000, TimeGrid::linear(2.0, 5).unwrap(), 1.0, 12, 99).unwrap();
    let exact = sim::simulate_units(&p, &other, Method::Exact, 0..1, &NoProgress).unwrap();
    assert!(sim::combine_units(&p, &s, Method::Exact, &exact).is_err());
    let empty = sim::combine_units(&p, &s, Method::Exact, &[]).unwrap();
    assert_eq!(empty.particles(), 0);
}
