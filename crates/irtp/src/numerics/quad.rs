//! Gauss–Kronrod (G7/K15) quadrature: one kernel, two adaptive drivers.
//!
//! Hand-written because the r = 0 density code needs the *partition* (to build
//! a cumulative table for the CDF) and full control of the integrand near the
//! singular edges, and the exact flow evaluates cheap closures millions of
//! times; no crate in the dependency tree offers that.
//!
//! - [`adaptive`]: globally adaptive, keeps its final panels (r = 0 densities).
//! - [`integrate`]: locally adaptive recursive bisection to a relative
//!   tolerance, value only (flow times and deficit integrals of the drag laws).
//!
//! Both stop at the first non-finite panel value and within a panel budget,
//! reporting [`Failure`] instead of an unconverged sum.

use super::Failure;

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
/// Gauss weights of the embedded 7-point rule (abscissae `XGK[1]`, `XGK[3]`, `XGK[5]`, `XGK[7]`).
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// One G7/K15 evaluation on a panel [a, b].
#[derive(Clone, Copy, Debug)]
pub struct Gk15 {
    /// Kronrod-15 estimate of ∫_a^b f.
    pub kronrod: f64,
    /// Embedded Gauss-7 estimate of ∫_a^b f.
    pub gauss: f64,
    /// Error indicator |K15 - G7|.
    pub error: f64,
}

/// G7/K15 estimates of ∫_a^b f (QUADPACK qk15 nodes and weights).
pub fn gk15<F: Fn(f64) -> f64 + ?Sized>(f: &F, a: f64, b: f64) -> Gk15 {
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
    Gk15 {
        kronrod: k * h,
        gauss: g * h,
        error: ((k - g) * h).abs(),
    }
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
/// Panels are returned in ascending order. Fails with
/// [`Failure::NonFinite`] on the first panel with a non-finite K15 or error,
/// and with [`Failure::NotConverged`] when the budget runs out or a panel
/// that still misses the tolerance cannot be split at double precision.
pub fn adaptive<F: Fn(f64) -> f64>(
    f: &F,
    start: &[f64],
    tol_abs: f64,
    max_panels: usize,
) -> Result<Panels, Failure> {
    use std::collections::BinaryHeap;
    let eval = |a: f64, b: f64| {
        let q = gk15(f, a, b);
        P {
            a,
            b,
            k: q.kronrod,
            e: q.error,
        }
    };
    // A panel whose G7 already agrees with K15 to 1e-13 relative is final: K15
    // is then far more accurate still, and the integrand's own rounding noise
    // (e.g. exp of a large logarithm) would otherwise keep it splitting forever.
    let round_off = |p: &P| p.e <= 1e-13 * p.k.abs();
    let non_finite = |p: &P| {
        (!(p.k.is_finite() && p.e.is_finite())).then_some(Failure::NonFinite {
            method: ADAPTIVE,
            at: 0.5 * (p.a + p.b),
        })
    };
    let mut heap = BinaryHeap::new();
    let mut done: Vec<P> = Vec::new();
    let mut active = 0.0;
    for w in start.windows(2) {
        let p = eval(w[0], w[1]);
        if let Some(fail) = non_finite(&p) {
            return Err(fail);
        }
        if round_off(&p) {
            done.push(p);
        } else {
            active += p.e;
            heap.push(p);
        }
    }
    let mut converged = true;
    while active > tol_abs {
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
            if let Some(fail) = non_finite(&q) {
                return Err(fail);
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
    if !converged {
        return Err(Failure::NotConverged {
            method: ADAPTIVE,
            iterations: heap.len() + done.len(),
            residual: heap.iter().chain(&done).map(|p| p.e).sum(),
            tolerance: tol_abs,
        });
    }
    Ok(assemble(start[0], done.into_iter().chain(heap).collect()))
}

/// One panel of [`adaptive`]: [a, b], its K15 value and error estimate,
/// ordered by error (the heap pops the worst panel first).
struct P {
    a: f64,
    b: f64,
    k: f64,
    e: f64,
}

impl PartialEq for P {
    fn eq(&self, o: &Self) -> bool {
        self.e.total_cmp(&o.e) == std::cmp::Ordering::Equal
    }
}
impl Eq for P {}
impl PartialOrd for P {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for P {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.e.total_cmp(&o.e)
    }
}

/// The final panels of [`adaptive`] in order from `start`.
fn assemble(start: f64, mut all: Vec<P>) -> Panels {
    all.sort_by(|x, y| x.a.total_cmp(&y.a));
    let mut out = Panels {
        edges: Vec::with_capacity(all.len() + 1),
        values: Vec::with_capacity(all.len()),
        error: 0.0,
    };
    out.edges.push(start);
    for p in &all {
        out.edges.push(p.b);
        out.values.push(p.k);
        out.error += p.e;
    }
    out
}

const ADAPTIVE: &str = "adaptive Gauss-Kronrod quadrature";
const LOCAL: &str = "Gauss-Kronrod quadrature";
/// Recursion depth limit of [`integrate`] (panels down to 2^-60 of the interval).
const MAX_DEPTH: u32 = 60;
/// Panel budget of [`integrate`] (K15 evaluations, 15 function calls each).
const MAX_LOCAL_PANELS: usize = 100_000;

/// Locally adaptive Gauss-Kronrod: ∫_a^b f to relative tolerance `rel` by
/// recursive bisection until |K15 - G7| ≤ `rel` |K15(a, b)| on each panel
/// (the estimate is pessimistic, the result is usually far better). Fails
/// with [`Failure::NonFinite`] at the first non-finite panel value (so a NaN
/// integrand costs one panel, not 2^60), and with [`Failure::NotConverged`]
/// when a panel misses the tolerance at depth 60 or the budget of 10⁵
/// panels runs out.
pub fn integrate(f: &dyn Fn(f64) -> f64, a: f64, b: f64, rel: f64) -> Result<f64, Failure> {
    if a == b {
        return Ok(0.0);
    }
    let q = gk15(f, a, b);
    let tol = (rel * q.kronrod.abs()).max(1e-300);
    let mut panels = 1;
    rec(f, a, b, q, tol, MAX_DEPTH, &mut panels)
}

fn rec(
    f: &dyn Fn(f64) -> f64,
    a: f64,
    b: f64,
    q: Gk15,
    tol: f64,
    depth: u32,
    panels: &mut usize,
) -> Result<f64, Failure> {
    if !(q.kronrod.is_finite() && q.gauss.is_finite()) {
        return Err(Failure::NonFinite {
            method: LOCAL,
            at: 0.5 * (a + b),
        });
    }
    let residual = (q.kronrod - q.gauss).abs();
    if residual <= tol {
        return Ok(q.kronrod);
    }
    if depth == 0 || *panels + 2 > MAX_LOCAL_PANELS {
        return Err(Failure::NotConverged {
            method: LOCAL,
            iterations: *panels,
            residual,
            tolerance: tol,
        });
    }
    *panels += 2;
    let m = 0.5 * (a + b);
    let (l, r) = (gk15(f, a, m), gk15(f, m, b));
    let left = rec(f, a, m, l, tol, depth - 1, panels)?;
    Ok(left + rec(f, m, b, r, tol, depth - 1, panels)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kronrod_exact_for_degree_22_gauss_for_13() {
        for deg in 0..=22u32 {
            let f = |x: f64| x.powi(deg as i32);
            let exact = (1.0 - (-1f64).powi(deg as i32 + 1)) / (deg as f64 + 1.0);
            let q = gk15(&f, -1.0, 1.0);
            let (k, e) = (q.kronrod, q.error);
            assert!((k - exact).abs() < 1e-14, "deg {deg}: {k} vs {exact}");
            if deg <= 13 {
                assert!(e < 1e-14, "G7 should be exact at degree {deg}: {e}");
                assert!((q.gauss - exact).abs() < 1e-14, "deg {deg}: {}", q.gauss);
            }
        }
    }

    #[test]
    fn adaptive_handles_endpoint_singularity() {
        // ∫_0^1 x^{-1/2} dx = 2 needs many bisections toward 0.
        let f = |x: f64| if x > 0.0 { x.powf(-0.5) } else { 0.0 };
        let p = adaptive(&f, &[0.0, 1.0], 1e-12, 10_000).unwrap();
        assert!((p.total() - 2.0).abs() < 1e-12, "{}", p.total());
        let g = |x: f64| x.sqrt();
        let p = adaptive(&g, &[0.0, 0.5, 1.0], 1e-14, 10_000).unwrap();
        assert!((p.total() - 2.0 / 3.0).abs() < 1e-14, "{}", p.total());
        assert_eq!(p.edges.len(), p.values.len() + 1);
        assert!(p.edges.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn integrate_matches_adaptive_and_closed_forms() {
        let f = |x: f64| (3.0 * x).cos() * (-x).exp();
        // ∫_0^2 e^{-x} cos 3x dx = [e^{-x}(3 sin 3x - cos 3x)]_0^2 / 10.
        let exact = ((-2f64).exp() * (3.0 * 6f64.sin() - 6f64.cos()) + 1.0) / 10.0;
        let v = integrate(&f, 0.0, 2.0, 1e-14).unwrap();
        assert!((v - exact).abs() < 1e-15, "{v} vs {exact}");
        let p = adaptive(&f, &[0.0, 2.0], 1e-15, 10_000).unwrap();
        assert!((p.total() - v).abs() < 1e-15);
        assert_eq!(integrate(&f, 1.0, 1.0, 1e-14), Ok(0.0));
        // Reversed limits flip the sign.
        assert!((integrate(&f, 2.0, 0.0, 1e-14).unwrap() + v).abs() < 1e-15);
    }

    #[test]
    fn non_finite_integrands_fail_at_once() {
        use std::cell::Cell;
        let calls = Cell::new(0usize);
        let nan = |x: f64| {
            calls.set(calls.get() + 1);
            if x > 0.7 {
                f64::NAN
            } else {
                1.0
            }
        };
        let e = integrate(&nan, 0.0, 1.0, 1e-14).unwrap_err();
        assert!(matches!(e, Failure::NonFinite { .. }), "{e:?}");
        assert!(calls.get() <= 15, "{} calls", calls.get());
        let inf = |x: f64| 1.0 / (x - 0.5);
        let e = integrate(&inf, 0.0, 1.0, 1e-14).unwrap_err();
        assert!(matches!(e, Failure::NonFinite { .. }), "{e:?}");
        let e = adaptive(&nan, &[0.0, 0.5, 1.0], 1e-12, 10_000).unwrap_err();
        assert!(
            matches!(e, Failure::NonFinite { at, .. } if at > 0.5),
            "{e:?}"
        );
    }

    #[test]
    fn unresolvable_integrands_report_non_convergence() {
        // A sawtooth with 2^20 teeth is linear only on panels of depth 20:
        // ~10⁶ panels, so the budget stops the recursion first.
        let saw = |x: f64| (x * 1_048_576.0).fract();
        match integrate(&saw, 0.0, 1.0, 1e-14).unwrap_err() {
            Failure::NotConverged { iterations, .. } => {
                assert!(iterations + 2 > MAX_LOCAL_PANELS, "{iterations}")
            }
            other => panic!("{other:?}"),
        }
        // x^-0.9: the edge panel [0, h] misses 1e-10 relative until
        // h^0.1 ~ 1e-10, ~330 levels down: the depth limit stops the one
        // refining branch at level 60 (the old code returned its sum).
        let sing = |x: f64| x.powf(-0.9);
        match integrate(&sing, 0.0, 1.0, 1e-10).unwrap_err() {
            Failure::NotConverged { iterations, .. } => assert!(iterations < 1000, "{iterations}"),
            other => panic!("{other:?}"),
        }
        // The global driver: budget too small for the singularity.
        let f = |x: f64| if x > 0.0 { x.powf(-0.5) } else { 0.0 };
        match adaptive(&f, &[0.0, 1.0], 1e-12, 10).unwrap_err() {
            Failure::NotConverged {
                iterations,
                residual,
                tolerance,
                ..
            } => {
                assert_eq!(iterations, 10);
                assert!(residual > tolerance, "{residual} {tolerance}");
            }
            other => panic!("{other:?}"),
        }
    }
}
