//! An independent reference for the transient moments: the backward
//! (Kolmogorov) equations solved by Chebyshev collocation in v and the
//! exact exponential in time.
//!
//! u_s(v, t) = E[h(v(t)) | v(0) = v, eta(0) = s Sigma] solves
//!   ∂_t u_s = (s Sigma - g(v)) ∂_v u_s + lambda (u_{-s} - u_s) + r (u_s(v_r) - u_s),
//! u_s(v, 0) = h(v), the generator of the simulated process acting on h
//! (noise state kept at a reset). No boundary condition enters: the
//! characteristic speed s Sigma - g(v) vanishes at the edge the state flows
//! to and points inward at the other. For an analytic drag law u is
//! analytic on the closed interval (compositions of analytic flows averaged
//! over event times), so collocation converges exponentially in the number
//! of nodes, unlike the forward density, which is singular at the edges. The
//! forward solver's <v²>(t) from v(0) = 0, eta = ±Sigma equally likely, is
//! (u_+(0, t) + u_-(0, t)) / 2 with h(v) = v².
//!
//! Hand-written (dense, O(n³) with n = 2(N + 1) ≈ 100): the test suite has
//! no dense linear-algebra dependency, and the construction is short.

/// Chebyshev points x_j = cos(j π / N) and the differentiation matrix
/// (Trefethen, Spectral Methods in MATLAB, `cheb`), row-major.
fn cheb(n: usize) -> (Vec<f64>, Vec<f64>) {
    let x: Vec<f64> = (0..=n)
        .map(|j| (std::f64::consts::PI * j as f64 / n as f64).cos())
        .collect();
    let c = |j: usize| {
        let w = if j == 0 || j == n { 2.0 } else { 1.0 };
        if j % 2 == 0 {
            w
        } else {
            -w
        }
    };
    let m = n + 1;
    let mut d = vec![0.0; m * m];
    for i in 0..m {
        let mut row = 0.0;
        for j in (0..m).filter(|&j| j != i) {
            let v = c(i) / c(j) / (x[i] - x[j]);
            d[i * m + j] = v;
            row += v;
        }
        // Negative-sum trick: rows of D annihilate constants exactly.
        d[i * m + i] = -row;
    }
    (x, d)
}

/// Barycentric interpolation weights of the Chebyshev points at `xe`.
fn interpolation_row(x: &[f64], xe: f64) -> Vec<f64> {
    let n = x.len() - 1;
    if let Some(j) = x.iter().position(|&xj| xj == xe) {
        let mut r = vec![0.0; n + 1];
        r[j] = 1.0;
        return r;
    }
    let w: Vec<f64> = (0..=n)
        .map(|j| {
            let s = if j % 2 == 0 { 1.0 } else { -1.0 };
            let h = if j == 0 || j == n { 0.5 } else { 1.0 };
            s * h / (xe - x[j])
        })
        .collect();
    let total: f64 = w.iter().sum();
    w.iter().map(|wj| wj / total).collect()
}

fn matmul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for k in 0..n {
            let aik = a[i * n + k];
            if aik != 0.0 {
                for j in 0..n {
                    c[i * n + j] += aik * b[k * n + j];
                }
            }
        }
    }
    c
}

/// exp(a) by scaling and squaring of the Taylor series (terms summed until
/// they fall below 1e-18 of the scaled matrix's norm).
fn expm(a: &[f64], n: usize) -> Vec<f64> {
    let norm = (0..n)
        .map(|j| (0..n).map(|i| a[i * n + j].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let s = if norm > 0.5 {
        (norm / 0.5).log2().ceil() as i32
    } else {
        0
    };
    let scale = 0.5f64.powi(s);
    let a: Vec<f64> = a.iter().map(|x| x * scale).collect();
    let mut e = vec![0.0; n * n];
    let mut term = vec![0.0; n * n];
    for i in 0..n {
        e[i * n + i] = 1.0;
        term[i * n + i] = 1.0;
    }
    for k in 1..40 {
        term = matmul(&term, &a, n);
        term.iter_mut().for_each(|x| *x /= k as f64);
        e.iter_mut().zip(&term).for_each(|(e, t)| *e += t);
        if term.iter().fold(0.0f64, |m, x| m.max(x.abs())) < 1e-18 {
            break;
        }
    }
    for _ in 0..s {
        e = matmul(&e, &e, n);
    }
    e
}

/// <v²>(k dt), k = 0..=steps, from v(0) = v0, eta(0) = ±Sigma equally likely,
/// for drift g on (-v_u, v_u), flip rate `lambda`, reset rate `rate` to `v_r`,
/// with `nodes` + 1 Chebyshev points.
#[allow(clippy::too_many_arguments)]
pub fn v2_of_t(
    g: &dyn Fn(f64) -> f64,
    v_u: f64,
    sigma: f64,
    lambda: f64,
    rate: f64,
    v_r: f64,
    v0: f64,
    nodes: usize,
    dt: f64,
    steps: usize,
) -> Vec<f64> {
    let (x, d) = cheb(nodes);
    let m = nodes + 1;
    let n = 2 * m;
    let v: Vec<f64> = x.iter().map(|&x| v_u * x).collect();
    let reset = interpolation_row(&x, v_r / v_u);
    let mut a = vec![0.0; n * n];
    for (b, s) in [(0, sigma), (1, -sigma)] {
        for i in 0..m {
            let row = (b * m + i) * n;
            let speed = (s - g(v[i])) / v_u;
            for j in 0..m {
                a[row + b * m + j] = speed * d[i * m + j] + rate * reset[j];
            }
            a[row + b * m + i] -= lambda + rate;
            a[row + (1 - b) * m + i] += lambda;
        }
    }
    let step: Vec<f64> = a.iter().map(|x| x * dt).collect();
    let e = expm(&step, n);
    let probe = interpolation_row(&x, v0 / v_u);
    let mut u: Vec<f64> = v.iter().chain(&v).map(|v| v * v).collect();
    let mut out = Vec::with_capacity(steps + 1);
    for k in 0..=steps {
        if k > 0 {
            u = (0..n)
                .map(|i| (0..n).map(|j| e[i * n + j] * u[j]).sum())
                .collect();
        }
        let at = |b: usize| -> f64 { (0..m).map(|j| probe[j] * u[b * m + j]).sum() };
        out.push(0.5 * (at(0) + at(1)));
    }
    out
}
