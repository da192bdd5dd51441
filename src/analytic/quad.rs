//! Adaptive Gauss–Kronrod (G7/K15) quadrature that keeps its final panels.
//!
//! Hand-written because the r = 0 density code needs the *partition* (to build
//! a cumulative table for the CDF) and full control of the integrand near the
//! singular edges; no crate in the dependency tree offers that.

/// Kronrod abscissae on [-1, 1] (QUADPACK qk15), positive half, descending.
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
/// Kronrod weights matching [`XGK`].
const WGK: [f64; 8] = [
    0.022_935_322_010_529_225,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_18,
    0.140_653_259_715_525_92,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_83,
];
/// Gauss weights of the embedded 7-point rule (abscissae XGK[1], [3], [5], [7]).
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// K15 estimate of ∫_a^b f and the embedded-G7 error indicator |K15 - G7|.
pub fn gk15<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64) -> (f64, f64) {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let fc = f(c);
    let mut k = WGK[7] * fc;
    let mut g = WG[3] * fc;
    for j in 0..7 {
        let x = h * XGK[j];
        let s = f(c - x) + f(c + x);
        k += WGK[j] * s;
        if j % 2 == 1 {
            g += WG[j / 2] * s;
        }
    }
    (k * h, ((k - g) * h).abs())
}

/// Result of [`adaptive`]: panel boundaries (ascending), the K15 integral on
/// each panel, and the summed error indicator.
#[derive(Clone, Debug)]
pub struct Panels {
    /// Boundaries x_0 < x_1 < ... < x_n.
    pub edges: Vec<f64>,
    /// ∫ over panel i (K15).
    pub values: Vec<f64>,
    /// Σ |K15 - G7| over the panels (a pessimistic error bound).
    pub error: f64,
    /// Whether the tolerance was met within the panel budget (and the integrand stayed finite).
    pub converged: bool,
}

impl Panels {
    /// Sum of the panel integrals (pairwise-safe enough for ≤ 10⁴ positive terms).
    pub fn total(&self) -> f64 {
        self.values.iter().sum()
    }
}

/// Globally adaptive bisection of the initial partition `start`: repeatedly
/// split the panel with the largest |K15 - G7| until the summed indicator is
/// ≤ `tol_abs` (panels with |K15 - G7| ≤ 1e-13 |K15| are final) or `max_panels` is
/// reached. Global (not per-panel) control matters for endpoint singularities
/// w^a with small a, whose leftmost panel error shrinks only like h^{1+a}.
/// Panels are returned in ascending order.
pub fn adaptive<F: Fn(f64) -> f64>(
    f: &F,
    start: &[f64],
    tol_abs: f64,
    max_panels: usize,
) -> Panels {
    use std::cmp::Ordering;
    use std::collections::BinaryHeap;
    struct P {
        a: f64,
        b: f64,
        k: f64,
        e: f64,
    }
    impl PartialEq for P {
        fn eq(&self, o: &Self) -> bool {
            self.e.total_cmp(&o.e) == Ordering::Equal
        }
    }
    impl Eq for P {}
    impl PartialOrd for P {
        fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for P {
        fn cmp(&self, o: &Self) -> Ordering {
            self.e.total_cmp(&o.e)
        }
    }
    let eval = |a: f64, b: f64| {
        let (k, e) = gk15(f, a, b);
        P { a, b, k, e }
    };
    // A panel whose G7 already agrees with K15 to 1e-13 relative is final: K15
    // is then far more accurate still, and the integrand's own rounding noise
    // (e.g. exp of a large logarithm) would otherwise keep it splitting forever.
    let round_off = |p: &P| p.e <= 1e-13 * p.k.abs();
    let mut heap = BinaryHeap::new();
    let mut done: Vec<P> = Vec::new();
    let mut active = 0.0;
    let mut finite = true;
    for w in start.windows(2) {
        let p = eval(w[0], w[1]);
        finite &= p.k.is_finite() && p.e.is_finite();
        if round_off(&p) {
            done.push(p);
        } else {
            active += p.e;
            heap.push(p);
        }
    }
    let mut converged = finite;
    while finite && active > tol_abs {
        if heap.len() + done.len() >= max_panels {
            converged = false;
            break;
        }
        let Some(p) = heap.pop() else { break };
        active -= p.e;
        let m = 0.5 * (p.a + p.b);
        if !(m > p.a && m < p.b) {
            // Cannot split further at double precision.
            converged = false;
            done.push(p);
            continue;
        }
        for q in [eval(p.a, m), eval(m, p.b)] {
            if !(q.k.is_finite() && q.e.is_finite()) {
                finite = false;
                converged = false;
            }
            if round_off(&q) {
                done.push(q);
            } else {
                active += q.e;
                heap.push(q);
            }
        }
        // Re-sum occasionally to stop drift of the running error total.
        if heap.len() % 256 == 0 {
            active = heap.iter().map(|p| p.e).sum();
        }
    }
    let mut all: Vec<P> = done.into_iter().chain(heap).collect();
    all.sort_by(|x, y| x.a.total_cmp(&y.a));
    let mut out = Panels {
        edges: Vec::with_capacity(all.len() + 1),
        values: Vec::with_capacity(all.len()),
        error: 0.0,
        converged,
    };
    out.edges.push(start[0]);
    for p in &all {
        out.edges.push(p.b);
        out.values.push(p.k);
        out.error += p.e;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kronrod_exact_for_degree_22_gauss_for_13() {
        for deg in 0..=22u32 {
            let f = |x: f64| x.powi(deg as i32);
            let exact = (1.0 - (-1f64).powi(deg as i32 + 1)) / (deg as f64 + 1.0);
            let (k, e) = gk15(&f, -1.0, 1.0);
            assert!((k - exact).abs() < 1e-14, "deg {deg}: {k} vs {exact}");
            if deg <= 13 {
                assert!(e < 1e-14, "G7 should be exact at degree {deg}: {e}");
            }
        }
    }

    #[test]
    fn adaptive_handles_endpoint_singularity() {
        // ∫_0^1 x^{-1/2} dx = 2 needs many bisections toward 0.
        let f = |x: f64| if x > 0.0 { x.powf(-0.5) } else { 0.0 };
        let p = adaptive(&f, &[0.0, 1.0], 1e-12, 10_000);
        assert!(p.converged);
        assert!((p.total() - 2.0).abs() < 1e-12, "{}", p.total());
        let g = |x: f64| x.sqrt();
        let p = adaptive(&g, &[0.0, 0.5, 1.0], 1e-14, 10_000);
        assert!(p.converged);
        assert!((p.total() - 2.0 / 3.0).abs() < 1e-14, "{}", p.total());
        assert_eq!(p.edges.len(), p.values.len() + 1);
        assert!(p.edges.windows(2).all(|w| w[0] < w[1]));
    }
}
