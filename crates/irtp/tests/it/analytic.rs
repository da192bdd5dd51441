//! Exact r = 0 densities: normalisation, moments and CDF by an independent
//! quadrature, the linear-drag Beta law, the stationary forward equations,
//! agreement with the paper's closed forms, and the regime classification.

use crate::common::models;
use irtp::analytic::linear;
use irtp::analytic::r0::{paper_formula, regime, EdgeBehaviour, ExtremumKind, R0Density};
use irtp::{Drag, DragLaw};

/// The paper's parameter sets (Figs. 2, 3) plus extra singular/peaked cases.
const CASES: [(DragLaw, f64, f64); 12] = [
    (DragLaw::Tan, 3.0, 0.5),
    (DragLaw::Tan, 3.0, 0.9),
    (DragLaw::Tan, 3.0, 7.0),
    (DragLaw::Tan, 3.0, 15.0),
    (DragLaw::Tan, 3.0, 25.0),
    (DragLaw::Tan, 0.5, 300.0),
    (DragLaw::Tanh, 0.6, 0.5),
    (DragLaw::Tanh, 0.6, 0.85),
    (DragLaw::Tanh, 0.6, 1.2),
    (DragLaw::Tanh, 0.6, 3.0),
    (DragLaw::Tanh, 0.95, 0.02),
    (DragLaw::Linear, 1.3, 0.3),
];

/// Gauss–Legendre nodes and weights on [-1, 1] (Newton on P_n).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// Method B (independent of the library's u = w^m Gauss–Kronrod scheme):
/// ∫_0^{w_max} h(v_u - w) p(w) dw in y = -ln w on fixed GL panels of width 1/4
/// up to w = e^{-700}, plus the analytic edge tail p ≈ κ w^a beyond.
fn integrate_from_edge(d: &R0Density, w_max: f64, h: impl Fn(f64) -> f64) -> f64 {
    let gl = gauss_legendre(20);
    let vu = d.bounds().1;
    let c = d.edge_exponent() + 1.0;
    let y0 = -w_max.ln();
    let y_end = 700.0;
    let n = ((y_end - y0) / 0.25).ceil() as usize;
    let dy = (y_end - y0) / n as f64;
    let mut sum = 0.0;
    for i in 0..n {
        let a = y0 + i as f64 * dy;
        for &(x, wt) in &gl {
            let y = a + 0.5 * dy * (x + 1.0);
            let w = (-y).exp();
            sum += 0.5 * dy * wt * d.pdf_at_edge_distance(w) * w * h(vu - w);
        }
    }
    let w_end = (-y_end).exp();
    sum + d.pdf_at_edge_distance(w_end) * w_end / c * h(vu)
}

#[test]
fn normalised_to_1e10_by_independent_quadrature() {
    for (drag, s, l) in CASES {
        let d = R0Density::new(drag.clone(), s, l).unwrap();
        let vu = d.bounds().1;
        let total = 2.0 * integrate_from_edge(&d, vu, |_| 1.0);
        let b2 = 2.0 * integrate_from_edge(&d, vu, |v| v * v);
        eprintln!(
            "{drag} {s} {l}: |∫P - 1| = {:.1e}, <v²> = {:.15} (method B rel. diff {:.1e})",
            (total - 1.0).abs(),
            d.v2(),
            (d.v2() - b2).abs() / b2
        );
        assert!((total - 1.0).abs() < 1e-12, "{drag} {s} {l}: ∫P = {total}");
        let n = d.normalisation();
        assert!(n.relative_error_bound < 1e-12, "{n:?}");
    }
}

#[test]
fn moments_agree_between_two_quadratures() {
    for (drag, s, l) in CASES {
        let d = R0Density::new(drag.clone(), s, l).unwrap();
        let vu = d.bounds().1;
        for k in [2u32, 4, 6] {
            let b = 2.0 * integrate_from_edge(&d, vu, |v| v.powi(k as i32));
            let a = d.moment(k);
            assert!(
                ((a - b) / b).abs() < 1e-12,
                "{drag} {s} {l} <v^{k}>: {a} vs {b}"
            );
        }
        assert_eq!(d.moment(1), 0.0);
        assert_eq!(d.moment(0), 1.0);
        assert_eq!(d.v2(), d.moment(2));
    }
}

#[test]
fn cdf_matches_independent_tail_integrals() {
    for (drag, s, l) in CASES {
        let d = R0Density::new(drag.clone(), s, l).unwrap();
        let vu = d.bounds().1;
        for frac in [0.0, 0.1, 0.37, 0.5, 0.8, 0.99, 0.999_999] {
            let v = frac * vu;
            let tail = integrate_from_edge(&d, vu - v, |_| 1.0);
            assert!(
                (1.0 - d.cdf(v) - tail).abs() < 1e-12,
                "{drag} {s} {l} v={v}: {} vs {tail}",
                1.0 - d.cdf(v)
            );
            assert!((d.cdf(-v) - tail).abs() < 1e-12);
        }
        // Mass far below the double spacing at v_u (a tenth of the edge mass for a = -0.95).
        for w in [1e-20, 1e-8] {
            let tail = integrate_from_edge(&d, w, |_| 1.0);
            let m = d.edge_mass(w);
            assert!(
                (m - tail).abs() <= 1e-12 * tail,
                "{drag} {s} {l} w={w}: {m} vs {tail}"
            );
        }
        assert_eq!(d.cdf(-vu), 0.0);
        assert_eq!(d.cdf(vu), 1.0);
        assert!((d.cdf(0.0) - 0.5).abs() < 1e-14);
        // Outer edges exactly ±v_u: for tanh Sigma=0.95 lambda=0.02 (a = -0.79) the
        // last 1e-15 below v_u still holds 4e-4 of the mass.
        let mut edges: Vec<f64> = (0..=40).map(|i| -vu + 2.0 * vu * i as f64 / 40.0).collect();
        edges[0] = -vu;
        edges[40] = vu;
        let p = d.bin_probabilities(&edges);
        assert!(p.iter().all(|&x| x >= 0.0));
        for (k, pk) in p.iter().enumerate() {
            let diff = d.cdf(edges[k + 1]) - d.cdf(edges[k]);
            assert!((pk - diff).abs() < 1e-13, "bin {k}: {pk} vs {diff}");
        }
        // A bin straddling 0 and bins beyond the interval.
        let q = d.bin_probabilities(&[-2.0 * vu, -0.3 * vu, 0.2 * vu, 3.0 * vu]);
        assert!((q[0] - d.cdf(-0.3 * vu)).abs() < 1e-14);
        assert!((q[1] - (d.cdf(0.2 * vu) - d.cdf(-0.3 * vu))).abs() < 1e-14);
        assert!((q.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        let sum: f64 = p.iter().sum();
        assert!((sum - 1.0).abs() < 1e-12, "{drag} {s} {l}: {sum} {p:?}");
    }
}

#[test]
fn singular_edge_mass_scaling() {
    // tan, Sigma = 3, lambda = 0.5: a = -0.95, edge mass ∝ w^{0.05}: the mass
    // within 1e-20 of the edge is (1e-20)^{0.05} = 0.1 of the mass within 1.
    let d = R0Density::new(DragLaw::Tan, 3.0, 0.5).unwrap();
    assert!((d.edge_exponent() + 0.95).abs() < 1e-15);
    let r = d.edge_mass(1e-20) / d.edge_mass(1e-10);
    assert!((r - 1e-10f64.powf(0.05)).abs() < 1e-8, "{r}");
    // Edge exponent from the density itself.
    for (drag, s, l) in CASES {
        let d = R0Density::new(drag.clone(), s, l).unwrap();
        let (w1, w2) = (1e-12, 1e-13);
        let slope = (d.pdf_at_edge_distance(w1) / d.pdf_at_edge_distance(w2)).ln() / 10f64.ln();
        if d.pdf_at_edge_distance(w1) > 0.0 {
            assert!(
                (slope - d.edge_exponent()).abs() < 1e-9,
                "{drag} {s} {l}: {slope}"
            );
        }
    }
}

#[test]
fn linear_drag_is_the_beta_law() {
    // lambda = 1/2: arcsine law, a = -1/2.
    let s = 1.7;
    let d = R0Density::new(DragLaw::Linear, s, 0.5).unwrap();
    for v in [-1.6999, -1.2, -0.3, 0.0, 0.5, 1.69, 1.699_99] {
        let exact = 1.0 / (std::f64::consts::PI * (s * s - v * v).sqrt());
        // Relative error of the input distance to the edge is ~ε s/(s - |v|).
        let tol = 1e-13 + 4.0 * f64::EPSILON * s / (s - v.abs());
        assert!(((d.pdf(v) - exact) / exact).abs() < tol, "pdf {v}");
        let f = 0.5 + (v / s).asin() / std::f64::consts::PI;
        assert!((d.cdf(v) - f).abs() < 1e-13, "cdf {v}: {} vs {f}", d.cdf(v));
    }
    // lambda = 3/2: semicircle law.
    let d = R0Density::new(DragLaw::Linear, s, 1.5).unwrap();
    for v in [-1.6, -0.2, 0.0, 0.9, 1.69] {
        let x: f64 = v / s;
        let exact = 2.0 / (std::f64::consts::PI * s) * (1.0 - x * x).sqrt();
        assert!(((d.pdf(v) - exact) / exact).abs() < 1e-12);
        let f = 0.5 + (x * (1.0 - x * x).sqrt() + x.asin()) / std::f64::consts::PI;
        assert!((d.cdf(v) - f).abs() < 1e-13);
    }
    // Moments <v^{2j}> = Sigma^{2j} Π_{i<j} (1/2 + i)/(lambda + 1/2 + i); <v²> = linear::v2 at r = 0.
    for l in [0.05, 0.3, 1.0, 2.5, 40.0] {
        let d = R0Density::new(DragLaw::Linear, s, l).unwrap();
        let p = models::linear(s, l, 0.0, 0.0);
        let v2 = linear::v2(&p).unwrap();
        assert!(
            ((d.v2() - v2) / v2).abs() < 1e-13,
            "lambda {l}: {} vs {v2}",
            d.v2()
        );
        let mut exact = 1.0;
        for j in 1..=4u32 {
            exact *= s * s * (0.5 + (j - 1) as f64) / (l + 0.5 + (j - 1) as f64);
            let m = d.moment(2 * j);
            assert!(
                ((m - exact) / exact).abs() < 1e-12,
                "lambda {l} <v^{}>",
                2 * j
            );
        }
    }
}

/// Finite-difference residuals of the stationary forward equations
/// 0 = -d/dv[(±Sigma - g) P±] + lambda (P∓ - P±), relative to the terms' size.
fn forward_residual(drag: DragLaw, s: f64, l: f64, v: f64, p: impl Fn(f64) -> (f64, f64)) -> f64 {
    // P varies on the scale 1/|d ln P/dv| ~ 1/λ: keep the O(h²) FD error below 1e-7.
    let h = 1e-5 / (1.0 + l);
    let flux = |v: f64| {
        let (pp, pm) = p(v);
        let g = drag.force(v);
        ((s - g) * pp, (-s - g) * pm)
    };
    let (fp1, fm1) = flux(v + h);
    let (fp0, fm0) = flux(v - h);
    let (pp, pm) = p(v);
    let rp = -(fp1 - fp0) / (2.0 * h) + l * (pm - pp);
    let rm = -(fm1 - fm0) / (2.0 * h) + l * (pp - pm);
    let scale = l * (pp + pm) + ((fp1 - fp0) / (2.0 * h)).abs();
    rp.abs().max(rm.abs()) / scale
}

#[test]
fn satisfies_stationary_forward_equations() {
    for (drag, s, l) in CASES {
        let d = R0Density::new(drag.clone(), s, l).unwrap();
        let vu = d.bounds().1;
        for frac in [-0.9, -0.5, -0.1, 0.05, 0.3, 0.7, 0.95] {
            let v = frac * vu;
            let r = forward_residual(drag.clone(), s, l, v, |v| d.state_pdf(v));
            assert!(r < 1e-7, "{drag} {s} {l} v={v}: residual {r}");
            // Zero total flux: (Sigma - g)P+ - (Sigma + g)P- = 0.
            let (pp, pm) = d.state_pdf(v);
            let g = drag.force(v);
            assert!(((s - g) * pp - (s + g) * pm).abs() < 1e-13 * s * (pp + pm));
        }
    }
}

#[test]
fn state_densities_near_the_edge() {
    // P₋/P = (Σ - g)/(2Σ) ≈ g'(v_u) w/(2Σ) at distance w below v_u, to O(w).
    let (s, l) = (3.0, 0.9);
    let d = R0Density::new(DragLaw::Tan, s, l).unwrap();
    let vu = d.bounds().1;
    let v = vu - 1e-9;
    let w = vu - v; // the representable distance
    let (pp, pm) = d.state_pdf(v);
    let expect = (1.0 + s * s) * w / (2.0 * s);
    assert!(
        ((pm / (pp + pm)) / expect - 1.0).abs() < 1e-7,
        "{}",
        pm / (pp + pm)
    );
    let (qp, qm) = d.state_pdf(-v);
    assert_eq!((qp, qm), (pm, pp));
    assert_eq!(d.state_pdf(2.0), (0.0, 0.0));
}

#[test]
fn paper_closed_forms_are_correct_and_wrong_sign_fails() {
    // Eqs. (34) / (35) equal the derived density up to normalisation...
    for (drag, s, l) in CASES {
        let d = R0Density::new(drag.clone(), s, l).unwrap();
        let vu = d.bounds().1;
        let k0 = d.pdf(0.0) / paper_formula(drag.clone(), s, l, 0.0);
        for frac in [-0.95, -0.4, 0.2, 0.6, 0.9] {
            let v = frac * vu;
            let q = paper_formula(drag.clone(), s, l, v);
            if q < 1e-280 {
                continue; // the printed form underflows (λ = 300), ours is scaled by P(0)
            }
            let k = d.pdf(v) / q;
            assert!(((k - k0) / k0).abs() < 1e-11, "{drag} {s} {l} v={v}");
        }
        assert_eq!(paper_formula(drag, s, l, 1.01 * vu), 0.0);
    }
    // ...and the test discriminates: with the sign of the drift flipped in the
    // exponent (P ∝ exp(+2λ∫g/(Σ²-g²))/(Σ²-g²)) the forward equations fail.
    let (s, l) = (3.0, 7.0);
    let c = l / (1.0 + s * s);
    let wrong = |v: f64| {
        let t2 = v.tan().powi(2);
        let p = ((s * s - t2) / (1.0 + t2)).powf(-c) / (s * s - t2);
        let r = v.tan() / s;
        (0.5 * p * (1.0 + r), 0.5 * p * (1.0 - r))
    };
    let r = forward_residual(DragLaw::Tan, s, l, 0.7, wrong);
    assert!(
        r > 0.1,
        "wrong-sign density should violate the equations: {r}"
    );
}

#[test]
fn regimes_of_the_paper_parameter_sets() {
    for (l, label) in [(0.9, "i"), (7.0, "ii"), (15.0, "iii"), (25.0, "iv")] {
        assert_eq!(regime(DragLaw::Tan, 3.0, l).label, label, "tan lambda {l}");
    }
    for (l, label) in [(0.5, "a"), (0.85, "b"), (1.2, "c"), (3.0, "d")] {
        assert_eq!(
            regime(DragLaw::Tanh, 0.6, l).label,
            label,
            "tanh lambda {l}"
        );
    }
    let e = |d, s, l| regime(d, s, l).edge;
    assert_eq!(e(DragLaw::Tan, 3.0, 0.9), EdgeBehaviour::Diverges);
    assert_eq!(e(DragLaw::Tan, 3.0, 7.0), EdgeBehaviour::Diverges);
    assert_eq!(e(DragLaw::Tan, 3.0, 15.0), EdgeBehaviour::Cusp);
    assert_eq!(e(DragLaw::Tan, 3.0, 25.0), EdgeBehaviour::Smooth);
    assert_eq!(e(DragLaw::Tanh, 0.6, 0.5), EdgeBehaviour::Diverges);
    assert_eq!(e(DragLaw::Tanh, 0.6, 0.85), EdgeBehaviour::Cusp);
    assert_eq!(e(DragLaw::Tanh, 0.6, 1.2), EdgeBehaviour::Cusp);
    assert_eq!(e(DragLaw::Tanh, 0.6, 3.0), EdgeBehaviour::Smooth);
    // Boundary values of lambda.
    let r = regime(DragLaw::Tan, 3.0, 1.0);
    assert_eq!((r.label.as_str(), r.extrema.len()), ("i", 1));
    let r = regime(DragLaw::Tan, 3.0, 10.0);
    assert_eq!((r.label.as_str(), r.edge), ("iii", EdgeBehaviour::Finite));
    let r = regime(DragLaw::Tan, 3.0, 20.0);
    assert_eq!((r.label.as_str(), r.edge), ("iii", EdgeBehaviour::Linear));
    let r = regime(DragLaw::Tanh, 0.6, 0.64);
    assert_eq!((r.label.as_str(), r.edge), ("a", EdgeBehaviour::Finite));
    let r = regime(DragLaw::Tanh, 0.8, 1.0);
    assert_eq!((r.label.as_str(), r.extrema.len()), ("d", 1));
    assert_eq!(r.extrema[0].kind, ExtremumKind::Maximum);
    // (degenerate quartic maximum: check monotone decrease on (0, v_u) instead)
    let d = R0Density::new(DragLaw::Tanh, 0.8, 1.0).unwrap();
    let vu = d.bounds().1;
    let p: Vec<f64> = (0..=200).map(|i| d.pdf(vu * i as f64 / 201.0)).collect();
    assert!(p.windows(2).all(|w| w[1] < w[0]));
    // Linear drag: edge-exponent based.
    assert_eq!(regime(DragLaw::Linear, 1.0, 0.5).label, "i");
    assert_eq!(regime(DragLaw::Linear, 1.0, 1.0).label, "uniform");
    assert!(regime(DragLaw::Linear, 1.0, 1.0).extrema.is_empty());
    assert_eq!(regime(DragLaw::Linear, 1.0, 1.5).label, "iii");
    assert_eq!(regime(DragLaw::Linear, 1.0, 3.0).label, "iv");
    // Regime serialises with its label.
    let j = serde_json::to_value(regime(DragLaw::Tan, 3.0, 7.0)).unwrap();
    assert_eq!(j["label"], "ii");
    assert_eq!(j["edge"], "diverges");
}

/// Check each reported extremum against the density: a max/min with
/// P' = 0 there (centred difference) and the right neighbours.
fn check_extrema(drag: DragLaw, s: f64, l: f64) {
    let d = R0Density::new(drag.clone(), s, l).unwrap();
    let reg = d.regime();
    for e in &reg.extrema {
        let h = 1e-4;
        let (p0, pl, pr) = (d.pdf(e.v), d.pdf(e.v - h), d.pdf(e.v + h));
        match e.kind {
            ExtremumKind::Maximum => assert!(pl < p0 && pr < p0, "{drag} {s} {l} {e:?}"),
            ExtremumKind::Minimum => assert!(pl > p0 && pr > p0, "{drag} {s} {l} {e:?}"),
        }
        let h = 1e-6;
        let slope = (d.pdf(e.v + h) - d.pdf(e.v - h)) / (2.0 * h);
        assert!(
            slope.abs() < 1e-6 * p0,
            "{drag} {s} {l} {e:?}: P' = {slope}"
        );
    }
    // No other extremum: P' changes sign only at the reported points.
    let vu = d.bounds().1;
    let n = 4000;
    let mut sign_changes = 0;
    let mut prev = 0.0;
    for i in 1..n {
        let v = vu * ((i as f64 + 0.37) / n as f64 - 0.5) * 1.98;
        let dp = d.pdf(v + 1e-7) - d.pdf(v - 1e-7);
        if i > 1 && dp * prev < 0.0 {
            sign_changes += 1;
        }
        prev = dp;
    }
    assert_eq!(sign_changes, reg.extrema.len(), "{drag} {s} {l}");
}

#[test]
fn extrema_match_the_density() {
    for (drag, s, l) in CASES {
        if !(drag == DragLaw::Linear && l == 1.0) {
            check_extrema(drag, s, l);
        }
    }
    // Tan (ii): minima at ±atan(√(λ-1)) as the paper says.
    let r = regime(DragLaw::Tan, 3.0, 7.0);
    assert!((r.extrema[2].v - 6f64.sqrt().atan()).abs() < 1e-15);
    // Sigma² > 1/2 tanh: two maxima together with zero-slope edges (paper's (b)/(d) overlap).
    check_extrema(DragLaw::Tanh, 0.8, 0.8);
    let r = regime(DragLaw::Tanh, 0.8, 0.8);
    assert_eq!((r.label.as_str(), r.edge), ("b", EdgeBehaviour::Smooth));
}

#[test]
fn paper_tanh_b_statements_corrected() {
    // Paper: maxima at ±atanh(1-λ) and a *global* minimum at 0. Actual: maxima
    // at ±atanh(√(1-λ)); P(0) is only a local minimum since P → 0 at the edges.
    let (s, l) = (0.6, 0.85);
    let d = R0Density::new(DragLaw::Tanh, s, l).unwrap();
    let r = d.regime();
    let vmax = (1.0f64 - l).sqrt().atanh();
    assert_eq!(r.extrema.len(), 3);
    assert!((r.extrema[2].v - vmax).abs() < 1e-15);
    assert_eq!(r.extrema[2].kind, ExtremumKind::Maximum);
    let paper_v = (1.0f64 - l).atanh();
    let h = 1e-5;
    let slope = (d.pdf(paper_v + h) - d.pdf(paper_v - h)) / (2.0 * h);
    assert!(
        slope > 0.1 * d.pdf(paper_v),
        "P' at the paper's location: {slope}"
    );
    let vu = d.bounds().1;
    assert!(d.pdf(0.999 * vu) < d.pdf(0.0));
}

#[test]
fn validation() {
    let bad = |d, s, l| R0Density::new(d, s, l).unwrap_err().to_string();
    assert!(bad(DragLaw::Tan, -1.0, 1.0).contains("invalid sigma = "));
    assert!(bad(DragLaw::Tan, f64::NAN, 1.0).contains("invalid sigma = "));
    assert!(bad(DragLaw::Tanh, 1.0, 1.0).contains("invalid sigma = "));
    assert!(bad(DragLaw::Tan, 3.0, 0.0).contains("invalid lambda = "));
    assert!(bad(DragLaw::Tan, 3.0, f64::NAN).contains("invalid lambda = "));
    assert!(bad(DragLaw::Tan, 3.0, f64::INFINITY).contains("invalid lambda = "));
    let p = models::tan(1.0, 2.0);
    let e = R0Density::from_params(&p).unwrap_err();
    assert!(e.is_input_error() && e.to_string().contains("invalid rate = "));
    let d = R0Density::from_params(&p.with_rate(0.0).unwrap()).unwrap();
    assert_eq!(d.bounds(), p.bounds());
    assert_eq!(d.pdf(2.0), 0.0);
    assert!(d.pdf(f64::NAN).is_nan());
}

/// Independent check against the *simulated process* (not the derived ODE):
/// piecewise-deterministic sampler with exact exponential flip times and RK4
/// for the flow dv/dt = ±Sigma - g(v) (local error ~1e-7, no O(dt) event bias).
/// Each particle starts at v = 0, burns in for 15 time units (memory ~e^{-9}),
/// then records v every 0.5 up to t = 35; particles are independent, so the
/// per-particle averages give honest standard errors. Tolerance: 4 SE.
fn simulate_against_density(drag: DragLaw, s: f64, l: f64, particles: u64, seed: u64) {
    use irtp::parallel::{self, NoProgress};
    use irtp::stats::MeanAcc;
    use rand::Rng;
    let d = R0Density::new(drag.clone(), s, l).unwrap();
    let (vl, vu) = d.bounds();
    const BINS: usize = 16;
    let mut edges: Vec<f64> = (0..=BINS)
        .map(|i| vl + (vu - vl) * i as f64 / BINS as f64)
        .collect();
    edges[0] = vl;
    edges[BINS] = vu;
    let probs = d.bin_probabilities(&edges);
    let (burn, t_end, every, dt) = (15.0, 35.0, 0.5, 0.01f64);
    type Acc = (MeanAcc, Vec<MeanAcc>);
    let init = || (MeanAcc::new(), vec![MeanAcc::new(); BINS]);
    let acc = parallel::reduce(
        particles,
        init,
        |i, acc: &mut Acc| {
            let mut rng = irtp::rng::stream(seed, i);
            let mut eta = if rng.gen::<bool>() { s } else { -s };
            let mut v = 0.0f64;
            let mut t = 0.0;
            let mut next_flip = -(1.0 - rng.gen::<f64>()).ln() / l;
            let mut next_rec = burn;
            let (mut n, mut sum_v2) = (0u32, 0.0);
            let mut counts = [0u32; BINS];
            let f = |v: f64, e: f64| e - drag.force(v);
            while t < t_end {
                let h = dt.min(next_flip - t).min(next_rec - t);
                let k1 = f(v, eta);
                let k2 = f(v + 0.5 * h * k1, eta);
                let k3 = f(v + 0.5 * h * k2, eta);
                let k4 = f(v + h * k3, eta);
                v += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                t += h;
                if t >= next_flip - 1e-12 {
                    eta = -eta;
                    next_flip = t - (1.0 - rng.gen::<f64>()).ln() / l;
                }
                if t >= next_rec - 1e-12 {
                    n += 1;
                    sum_v2 += v * v;
                    let b = (((v - vl) / (vu - vl)) * BINS as f64) as usize;
                    counts[b.min(BINS - 1)] += 1;
                    next_rec += every;
                }
            }
            acc.0.push(sum_v2 / n as f64);
            for (a, &c) in acc.1.iter_mut().zip(&counts) {
                a.push(c as f64 / n as f64);
            }
        },
        |a: &mut Acc, b: Acc| {
            a.0.merge(&b.0);
            for (x, y) in a.1.iter_mut().zip(&b.1) {
                x.merge(y);
            }
        },
        &NoProgress,
    );
    let (m, se) = (acc.0.mean(), acc.0.sem());
    eprintln!(
        "{drag} {s} {l}: simulated <v2> = {m} +- {se}, exact {}",
        d.v2()
    );
    assert!(
        (m - d.v2()).abs() < 4.0 * se,
        "{drag} {s} {l}: simulated <v²> = {m} ± {se}, exact {}",
        d.v2()
    );
    for (k, (a, p)) in acc.1.iter().zip(&probs).enumerate() {
        assert!(
            (a.mean() - p).abs() < 4.0 * a.sem(),
            "{drag} {s} {l} bin {k}: {} ± {} vs {p}",
            a.mean(),
            a.sem()
        );
    }
}

#[test]
fn matches_simulation_of_the_process() {
    simulate_against_density(DragLaw::Tan, 3.0, 0.9, 3000, 11);
    simulate_against_density(DragLaw::Tanh, 0.6, 0.85, 3000, 12);
}

#[test]
fn extreme_parameters_stay_accurate() {
    // Linear drag: exact Beta moments from nearly-all-mass-at-the-edges to a
    // needle at 0 (c = lambda up to 1e4; the density spans 1e±6 in scale).
    for (s, l) in [(1e-6, 1e-3), (1.0, 1e-6), (1e6, 1e4), (2.0, 3e3)] {
        let d = R0Density::new(DragLaw::Linear, s, l).unwrap();
        let exact = s * s / (1.0 + 2.0 * l);
        assert!(
            ((d.v2() - exact) / exact).abs() < 1e-12,
            "linear {s} {l}: {} vs {exact}",
            d.v2()
        );
        assert!((d.cdf(0.3 * s) - d.cdf(-0.3 * s) - (1.0 - 2.0 * d.cdf(-0.3 * s))).abs() < 1e-14);
    }
    // Huge lambda: Gaussian limit <v²> ≈ Sigma²/(2(lambda-1)) (tan) up to O(1/lambda).
    let d = R0Density::new(DragLaw::Tan, 3.0, 1e6).unwrap();
    let approx = 9.0 / (2.0 * (1e6 - 1.0));
    assert!(((d.v2() - approx) / approx).abs() < 1e-4, "{}", d.v2());
    for (drag, s, l) in [
        (DragLaw::Tan, 3.0, 1e6),
        (DragLaw::Tanh, 0.999, 1e3),
        (DragLaw::Tan, 3.0, 1e-6),
    ] {
        let d = R0Density::new(drag.clone(), s, l).unwrap();
        let vu = d.bounds().1;
        let mut prev = 0.0;
        for i in 0..=2000 {
            let v = -vu + 2.0 * vu * i as f64 / 2000.0;
            let f = d.cdf(v);
            assert!(
                f.is_finite() && f >= prev - 1e-15,
                "{drag} {s} {l} cdf({v}) = {f}"
            );
            assert!(d.pdf(v).is_finite());
            prev = f;
        }
        assert_eq!(prev, 1.0);
    }
}

/// Coulomb friction at r = 0: the regime of the density reads the cusp at
/// v = 0 from the sign of gamma - lambda (P ∝ (Sigma² - g²)^(lambda/gamma - 1),
/// g = mu + gamma |v|): a minimum below, a maximum above, flat (the uniform
/// density) at lambda = gamma.
#[test]
fn coulomb_r0_regime_reads_the_cusp() {
    let d: irtp::DragLaw = "coulomb:mu=0.5,gamma=1".parse().unwrap();
    for (lambda, centre) in [(0.5, "minimum"), (2.0, "maximum"), (1.0, "flat")] {
        let lib = irtp::analytic::r0::R0Density::by_quadrature(d.clone(), 2.0, lambda).unwrap();
        let label = lib.regime().label.clone();
        assert!(label.contains(centre), "lambda={lambda}: {label}");
    }
    let lib = irtp::analytic::r0::R0Density::by_quadrature(d, 2.0, 1.0).unwrap();
    for v in [-1.2, -0.3, 0.4, 1.1] {
        assert!((lib.pdf(v) / lib.pdf(0.0) - 1.0).abs() < 1e-10);
    }
}
