//! Sharding: disjoint particle ranges of one run (`SimSpec::shard`), merged
//! with `Observables::merge`, give the statistics of the whole run, for both
//! samplers. Counts and event totals agree exactly; sums and sums of squares
//! agree up to the rounding of a different summation order.

mod common;

use common::models;
use irtp::parallel::NoProgress;
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
    for method in [Method::Exact, Method::Euler { dt: 1e-3 }] {
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
