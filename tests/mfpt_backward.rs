//! Backward-equation MFPT solver against exact answers.

use irtp::mfpt::backward::{fixed_point_upwind, profile, rate_derivative_at_zero};
use irtp::mfpt::{solve, BackwardOptions, Problem};
use irtp::{DragLaw, Params};

fn problem(drag: DragLaw, sigma: f64, lambda: f64, r: f64, vr: f64, v0: f64, vt: f64) -> Problem {
    Problem::new(Params::new(drag, sigma, lambda, r, vr).unwrap(), v0, vt).unwrap()
}

fn tau(p: &Problem, cells: usize) -> f64 {
    profile(p, &BackwardOptions::with_cells(cells)).unwrap().at_start().tau
}

/// Composite Gauss-Legendre (10 nodes per panel) on [a, b].
fn gauss<F: Fn(f64) -> f64>(f: F, a: f64, b: f64, panels: usize) -> f64 {
    const X: [f64; 5] = [
        0.148_874_338_981_631_2,
        0.433_395_394_129_247_2,
        0.679_409_568_299_024_4,
        0.865_063_366_688_984_5,
        0.973_906_528_517_171_7,
    ];
    const W: [f64; 5] = [
        0.295_524_224_714_752_9,
        0.269_266_719_309_996_4,
        0.219_086_362_515_982_0,
        0.149_451_349_150_580_6,
        0.066_671_344_308_688_1,
    ];
    let h = (b - a) / panels as f64;
    let mut s = 0.0;
    for k in 0..panels {
        let c = a + (k as f64 + 0.5) * h;
        for (x, w) in X.iter().zip(W) {
            s += w * (f(c - 0.5 * h * x) + f(c + 0.5 * h * x));
        }
    }
    0.5 * h * s
}

/// Exact r = 0 MFPT for linear drag, from the 2×2 system with correct signs.
/// With T = tau+ + tau-, D = tau+ - tau-, adding and subtracting the backward
/// equations gives Sigma D' - g T' = -2 and Sigma T' - g D' = 2 lambda D, hence
/// D = [(Sigma² - g²) T' + 2g] / (2 lambda Sigma) and
/// (Sigma² - g²) T'' - 2 g (lambda + g') T' = -2 (2 lambda + g')
/// (the paper's Eq. neqn10 at r = 0 has the sign of g flipped). For g = v:
/// T'(v) = -(4 lambda + 2) (Sigma² - v²)^{-(lambda+1)} ∫_{-Sigma}^v (Sigma² - u²)^lambda du
/// (the regular solution at v_l = -Sigma), and tau+(v_t) = 0 means
/// D(v_t) = -T(v_t). Returns (tau, tau+, tau-) at v0.
fn linear_exact(sigma: f64, lambda: f64, v0: f64, vt: f64) -> (f64, f64, f64) {
    let s2 = sigma * sigma;
    // ∫_{-Sigma}^v (Sigma² - u²)^lambda du with u = -Sigma cos(th).
    let inner = |v: f64| {
        let th = (-v / sigma).acos();
        sigma.powf(2.0 * lambda + 1.0) * gauss(|t: f64| t.sin().powf(2.0 * lambda + 1.0), 0.0, th, 60)
    };
    let w = |v: f64| -(4.0 * lambda + 2.0) * (s2 - v * v).powf(-(lambda + 1.0)) * inner(v);
    let d_of = |v: f64| ((s2 - v * v) * w(v) + 2.0 * v) / (2.0 * lambda * sigma);
    let t_vt = -d_of(vt);
    let t0 = t_vt - gauss(w, v0, vt, 60);
    let d0 = d_of(v0);
    (0.5 * t0, 0.5 * (t0 + d0), 0.5 * (t0 - d0))
}

#[test]
fn scratch() {
    for (s, l, v0, vt) in [(1.0, 0.5, -0.3, 0.6), (2.0, 1.7, -0.249, 0.5), (1.0, 3.0, 0.2, 0.9)] {
        let p = problem(DragLaw::Linear, s, l, 0.0, 0.0, v0, vt);
        let ex = linear_exact(s, l, v0, vt);
        let t = std::time::Instant::now();
        let sol = profile(&p, &BackwardOptions::with_cells(40000)).unwrap().at_start();
        println!("{ex:?} {sol:?} {:?}", t.elapsed());
        for n in [1000, 2000, 4000, 8000] { println!("{n} {}", tau(&p, n) - ex.0); }
        let (fp, it) = fixed_point_upwind(&p, 2000, 1e-12, 1_000_000).unwrap();
        println!("fp {fp:?} {it}");
    }
    for (d, s) in [(DragLaw::Tan, 3.0), (DragLaw::Tanh, 0.6)] {
        for r in [0.0, 0.2, 2.0, 10.0] {
            let p = problem(d, s, 0.5, r, 0.0, -0.249, 0.5);
            println!("{d} r={r} {:?} {:?}", solve(&p, &BackwardOptions::default()).unwrap(), rate_derivative_at_zero(&p, &BackwardOptions::default()).unwrap());
        }
    }
}
