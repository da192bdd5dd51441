use irtp::analytic::linear_moments;
use irtp::fp::{msd, Mesh, MsdOptions};
use irtp::model::{DragLaw, Params};
use irtp::numerics::time_grid::TimeGrid;
use irtp::parallel::NoProgress;

#[test]
#[ignore]
fn explore() {
    let times = TimeGrid::log(0.01, 100.0, 36).unwrap().times().to_vec();
    let cells: usize = std::env::var("CELLS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(200);
    let levels: usize = std::env::var("LEVELS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(3);
    let rtol: f64 = std::env::var("RTOL")
        .map(|s| s.parse().unwrap())
        .unwrap_or(1e-10);
    let r: f64 = std::env::var("RATE")
        .map(|s| s.parse().unwrap())
        .unwrap_or(0.0);
    let mesh = if std::env::var("UNIFORM").is_ok() {
        Mesh::Uniform
    } else {
        Mesh::Graded
    };
    let p = Params::new(DragLaw::Linear, 1.0, 0.5, r, 0.0).unwrap();
    let ex = linear_moments::moments(&p, &times).unwrap();
    let t0 = std::time::Instant::now();
    let o = MsdOptions {
        cells,
        mesh,
        levels,
        times: times.clone(),
        rtol,
    };
    let m = msd(&p, &o, &NoProgress).unwrap();
    println!("wall {:.2}s steps {}", t0.elapsed().as_secs_f64(), m.steps);
    let mut worst = (0.0f64, 0.0f64);
    for k in 1..times.len() {
        let e2 = m.x2[k] / ex.x2[k] - 1.0;
        let ev = m.v2[k] / ex.v2[k] - 1.0;
        println!(
            "{:9.4} x2 {:+.2e} v2 {:+.2e} a {:.4}",
            times[k], e2, ev, m.alpha[k]
        );
        worst = (worst.0.max(e2.abs()), worst.1.max(ev.abs()));
    }
    println!("worst x2 {:.2e} v2 {:.2e}", worst.0, worst.1);
}

#[test]
#[ignore]
fn explore_sim() {
    use irtp::figures::compute;
    use irtp::sim::SimSpec;
    let times = TimeGrid::log(0.01, 100.0, 36).unwrap();
    let cells: usize = std::env::var("CELLS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(200);
    let levels: usize = std::env::var("LEVELS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(3);
    let rtol: f64 = std::env::var("RTOL")
        .map(|s| s.parse().unwrap())
        .unwrap_or(1e-8);
    let np: u64 = std::env::var("NP")
        .map(|s| s.parse().unwrap())
        .unwrap_or(20000);
    for (d, s) in [(DragLaw::Tan, 3.0), (DragLaw::Tanh, 0.6)] {
        for r in [0.0, 0.1, 1.0, 10.0] {
            let p = Params::new(d, s, 0.5, r, 0.0).unwrap();
            let t0 = std::time::Instant::now();
            let o = MsdOptions {
                cells,
                mesh: Mesh::Graded,
                levels,
                times: times.times().to_vec(),
                rtol,
            };
            let m = msd(&p, &o, &NoProgress).unwrap();
            let wd = t0.elapsed().as_secs_f64();
            let t0 = std::time::Instant::now();
            let spec = SimSpec::new(np, times.clone(), 50.0, 1, 7).unwrap();
            let obs = compute::simulate(&p, &spec, &NoProgress).unwrap();
            let sim = compute::moments(&obs);
            let ws = t0.elapsed().as_secs_f64();
            let mut zmax = (0.0f64, 0.0);
            for k in 1..sim.len() {
                let z = (m.x2[k] - sim[k].x2) / sim[k].x2_err;
                if z.abs() > zmax.0.abs() {
                    zmax = (z, sim[k].t);
                }
            }
            println!(
                "{d:?} r {r}: det {wd:.2}s steps {} sim {ws:.2}s zmax {:.2} at {}",
                m.steps, zmax.0, zmax.1
            );
        }
    }
}

#[test]
#[ignore]
fn explore_cheap() {
    let times = TimeGrid::log(0.01, 100.0, 36).unwrap().times().to_vec();
    let cells: usize = std::env::var("CELLS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(200);
    let levels: usize = std::env::var("LEVELS")
        .map(|s| s.parse().unwrap())
        .unwrap_or(3);
    let rtol: f64 = std::env::var("RTOL")
        .map(|s| s.parse().unwrap())
        .unwrap_or(1e-8);
    for (d, s) in [(DragLaw::Tan, 3.0), (DragLaw::Tanh, 0.6)] {
        for r in [0.0, 10.0] {
            let p = Params::new(d, s, 0.5, r, 0.0).unwrap();
            let o = MsdOptions {
                cells: 200,
                mesh: Mesh::Graded,
                levels: 3,
                times: times.clone(),
                rtol: 1e-9,
            };
            let refm = msd(&p, &o, &NoProgress).unwrap();
            let t0 = std::time::Instant::now();
            let o = MsdOptions {
                cells,
                mesh: Mesh::Graded,
                levels,
                times: times.clone(),
                rtol,
            };
            let m = msd(&p, &o, &NoProgress).unwrap();
            let wd = t0.elapsed().as_secs_f64();
            let mut e = (0.0f64, 0.0);
            for k in 1..times.len() {
                let x = (m.x2[k] / refm.x2[k] - 1.0).abs();
                if x > e.0 {
                    e = (x, times[k]);
                }
            }
            println!(
                "{d:?} r {r}: {wd:.2}s steps {} maxrel {:.2e} at {}",
                m.steps, e.0, e.1
            );
        }
    }
}
