use irtp::fp::{self, TransientOptions};
use irtp::model::noise::NoiseModel;
use irtp::{DragLaw, Params};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let cells: usize = args[1].parse().unwrap();
    let rtol: f64 = args[2].parse().unwrap();
    let spec = &args[3];
    let temp: f64 = args[4].parse().unwrap();
    let p = Params::with_noise(
        DragLaw::Linear,
        NoiseModel::parse(spec, temp).unwrap(),
        0.5,
        0.1,
    )
    .unwrap();
    let o = TransientOptions {
        cells,
        t_max: 40.0,
        times: vec![0.25, 1.0, 40.0],
        snapshot_times: vec![],
        rtol,
        atol: rtol * 1e-4,
        ..TransientOptions::default()
    };
    let t0 = std::time::Instant::now();
    let tr = fp::transient(&p, &o).unwrap();
    println!(
        "steps {} wall {:.3} v {:?}",
        tr.steps,
        t0.elapsed().as_secs_f64(),
        tr.v_mean
    );
}
