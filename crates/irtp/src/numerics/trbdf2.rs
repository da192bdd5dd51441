//! Adaptive TR-BDF2 for linear systems M u' = A u (+ F(t), an optional
//! forcing, [`ShiftedLinear::forcing`]).
//!
//! TR-BDF2 (Bank, Coughran, Fichtner, Grosse, Rose & Smith, IEEE Trans.
//! Electron Devices 32, 1985) written as the three-stage ESDIRK of Hosea &
//! Shampine (Appl. Numer. Math. 20, 1996): a trapezoidal stage to
//! t + γh followed by a BDF2 stage to t + h, γ = 2 - √2. Both implicit
//! stages share one shifted operator M - d h A (d = γ/2), the method is
//! second order and L-stable, so the step is set by accuracy and not by the
//! fastest rate of A (the smallest cell of a graded mesh, a fast flip rate).
//! The embedded third-order solution gives an error estimate; it is filtered
//! through (M - d h A)⁻¹ as Hosea & Shampine recommend, which keeps it bounded
//! for the stiff components a plain difference would overestimate.
//!
//! Hand-written: the solvers that use it (forward Fokker-Planck, backward
//! survival equations) own O(N) shifted solves that no ODE crate can take as
//! a linear-solver callback without dense Jacobians, and the linear,
//! autonomous case needs no Newton iteration.
//!
//! The local error is controlled per step, so the global error of a run of
//! n steps is about n × rtol ∝ rtol^(2/3): ask for rtol ≈ (target)^(3/2).
//!
//! Steps are clipped to land exactly on every output time, where the caller
//! observes the state; no interpolation enters an output.

use super::Failure;
use crate::error::{Error, Result};

/// A linear autonomous system M u' = A u, with its shifted solve.
pub trait ShiftedLinear {
    /// Number of unknowns.
    fn dim(&self) -> usize;
    /// out = A u.
    fn apply(&self, u: &[f64], out: &mut [f64]);
    /// out = M u (default: M = identity).
    fn apply_mass(&self, u: &[f64], out: &mut [f64]) {
        out.copy_from_slice(u);
    }
    /// Solve (M - c A) x = b for c > 0. Every solve of one step uses the
    /// same c, so an implementation may cache a factorisation keyed on c.
    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure>;
    /// Absolute tolerance of unknown `i` (default: the common `atol`).
    fn atol(&self, i: usize, atol: f64) -> f64 {
        let _ = i;
        atol
    }
    /// The error norm: None (default) for the max over all unknowns of
    /// |err_i| / (atol_i + rtol |u_i|); Some(rows) for the larger of the
    /// root-mean-square of those ratios over all unknowns (the usual norm of
    /// SUNDIALS or Hairer & Wanner, which a single row's kink does not
    /// dominate) and their max over `rows` (the unknowns the caller reports).
    fn rms_norm_with_max_over(&self) -> Option<&[usize]> {
        None
    }
    /// A forcing F(t) (time measured from the start of [`integrate`]):
    /// fill `out` and return true to integrate M u' = A u + F(t) instead.
    /// Default: none (false, `out` untouched). F is sampled at t, t + γh and
    /// t + h of every step, so a jump of F in time must be an output time
    /// (where the step lands), with F(t) there its limit from the side the
    /// step comes from.
    fn forcing(&self, t: f64, out: &mut [f64]) -> bool {
        let _ = (t, out);
        false
    }
}

/// Accuracy and effort limits of [`integrate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Relative tolerance of the local error.
    pub rtol: f64,
    /// Absolute tolerance of the local error (see [`ShiftedLinear::atol`]).
    pub atol: f64,
    /// First step (None: chosen from ‖u0‖ / ‖M⁻¹A u0‖, then adapted).
    pub h0: Option<f64>,
    /// Largest step.
    pub h_max: f64,
    /// Most steps (accepted + rejected) before giving up.
    pub max_steps: usize,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            rtol: 1e-8,
            atol: 1e-12,
            h0: None,
            h_max: f64::INFINITY,
            max_steps: 1_000_000,
        }
    }
}

/// Effort spent by [`integrate`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Shifted solves.
    pub solves: usize,
}

impl std::ops::AddAssign for Stats {
    fn add_assign(&mut self, o: Stats) {
        self.steps += o.steps;
        self.rejected += o.rejected;
        self.solves += o.solves;
    }
}

const GAMMA: f64 = 2.0 - std::f64::consts::SQRT_2;
const D: f64 = GAMMA / 2.0;
const W: f64 = std::f64::consts::SQRT_2 / 4.0;
/// Embedded third-order weights minus the method's weights (w, w, d).
const E0: f64 = (1.0 - 4.0 * W) / 3.0;
const E1: f64 = 1.0 / 3.0;
const E2: f64 = -2.0 * D / 3.0;
/// Step-size controller: safety factor and bounds of the change per step.
const SAFETY: f64 = 0.9;
const GROW_MAX: f64 = 5.0;
const SHRINK_MIN: f64 = 0.2;

/// Work vectors of one step.
struct Work {
    f0: Vec<f64>,
    f1: Vec<f64>,
    f2: Vec<f64>,
    ug: Vec<f64>,
    un: Vec<f64>,
    mu: Vec<f64>,
    rhs: Vec<f64>,
    err: Vec<f64>,
    /// Forcing at a stage time.
    fc: Vec<f64>,
}

impl Work {
    fn new(n: usize) -> Self {
        let z = || vec![0.0; n];
        Work {
            f0: z(),
            f1: z(),
            f2: z(),
            ug: z(),
            un: z(),
            mu: z(),
            rhs: z(),
            err: z(),
            fc: z(),
        }
    }
}

/// Integrate M u' = A u from u(0) = `u` (overwritten with the state at the
/// last output time). `times` must be sorted and ≥ 0; the step lands exactly
/// on each, where `observe(k, times[k], u)` is called (at t = 0 too when
/// `times[0] == 0`). Fails with [`Failure::NotConverged`] when `max_steps`
/// is spent or the step underflows, and [`Failure::NonFinite`] on a
/// non-finite state; an error from `observe` stops the integration, and
/// so does a stop request ([`crate::stop::check_stop`], polled every
/// step).
pub fn integrate<O: ShiftedLinear>(
    op: &mut O,
    u: &mut [f64],
    times: &[f64],
    tol: &Tolerances,
    mut observe: impl FnMut(usize, f64, &[f64]) -> Result<()>,
) -> Result<Stats> {
    check_inputs(op, u, times, tol)?;
    let mut w = Work::new(u.len());
    let mut stats = Stats::default();
    let mut t = 0.0;
    let mut h = f64::NAN;
    for (k, &t_out) in times.iter().enumerate() {
        while t < t_out {
            // One relaxed load a step: a stop request ends the run here.
            crate::stop::check_stop()?;
            if h.is_nan() {
                h = first_step(op, u, t_out, tol, &mut w);
            }
            let last = t + 1.1 * h >= t_out;
            let h_step = if last { t_out - t } else { h };
            let (err, accepted) = step(op, u, t, h_step, tol, &mut w, &mut stats)?;
            let factor = (SAFETY * err.powf(-1.0 / 3.0)).clamp(SHRINK_MIN, GROW_MAX);
            if accepted {
                t = if last { t_out } else { t + h_step };
                // A clipped last step says little about the next one.
                h = if last {
                    h.max(h_step * factor)
                } else {
                    h_step * factor
                };
            } else {
                h = h_step * factor.min(1.0);
            }
            h = h.min(tol.h_max);
            if stats.steps + stats.rejected >= tol.max_steps || !(h > 16.0 * f64::EPSILON * t) {
                return Err(Failure::NotConverged {
                    method: "TR-BDF2 time stepping",
                    iterations: stats.steps + stats.rejected,
                    residual: h,
                    tolerance: t_out,
                }
                .into());
            }
        }
        observe(k, t_out, u)?;
    }
    Ok(stats)
}

fn check_inputs<O: ShiftedLinear>(
    op: &O,
    u: &[f64],
    times: &[f64],
    tol: &Tolerances,
) -> Result<()> {
    if u.len() != op.dim() {
        return Err(Error::Numerical {
            method: "TR-BDF2 time stepping",
            reason: format!("state has {} unknowns, the operator {}", u.len(), op.dim()),
        });
    }
    if !(tol.rtol > 0.0 && tol.atol >= 0.0 && tol.h_max > 0.0) || tol.h0.is_some_and(|h| !(h > 0.0))
    {
        return Err(Error::invalid(
            "tolerances",
            format!("rtol {} atol {} h_max {}", tol.rtol, tol.atol, tol.h_max),
            "rtol > 0, atol >= 0, h0 > 0, h_max > 0",
        ));
    }
    let sorted = times.windows(2).all(|p| p[0] <= p[1]);
    if !sorted || times.iter().any(|t| !(t.is_finite() && *t >= 0.0)) {
        return Err(Error::invalid(
            "times",
            "unsorted or negative",
            "finite, >= 0, sorted",
        ));
    }
    Ok(Failure::check_finite(u, "TR-BDF2 initial state", 0.0)?)
}

/// The first step: 1% of ‖u0‖ / ‖u0'‖ (weighted), at most the first output
/// interval and h_max; the controller corrects it within a few steps.
fn first_step<O: ShiftedLinear>(
    op: &mut O,
    u: &[f64],
    t_out: f64,
    tol: &Tolerances,
    w: &mut Work,
) -> f64 {
    if let Some(h) = tol.h0 {
        return h.min(tol.h_max);
    }
    op.apply(u, &mut w.f0);
    if op.forcing(0.0, &mut w.fc) {
        for (f, x) in w.f0.iter_mut().zip(&w.fc) {
            *f += x;
        }
    }
    let (mut d0, mut d1) = (0.0f64, 0.0f64);
    for (i, (&x, &f)) in u.iter().zip(&w.f0).enumerate() {
        let sc = op.atol(i, tol.atol) + tol.rtol * x.abs();
        if sc > 0.0 {
            d0 = d0.max(x.abs() / sc);
            d1 = d1.max(f.abs() / sc);
        }
    }
    let h = if d0 > 1e-5 && d1 > 1e-5 {
        0.01 * d0 / d1
    } else {
        1e-6 * t_out
    };
    // A tiny atol makes d1 huge for unknowns that start at 0: keep the
    // first step within 12 decades of the output time (the controller
    // shrinks it further if the error asks for it).
    h.min(t_out)
        .min(tol.h_max)
        .max(1e-12 * t_out.min(tol.h_max))
}

/// One attempted step of size h from time t: on acceptance `u` holds
/// u(t + h). With a forcing, F_i = A u_i + F(t_i) at the stage times.
/// Returns (error norm, accepted).
fn step<O: ShiftedLinear>(
    op: &mut O,
    u: &mut [f64],
    t: f64,
    h: f64,
    tol: &Tolerances,
    w: &mut Work,
    stats: &mut Stats,
) -> Result<(f64, bool)> {
    let c = D * h;
    let n = u.len();
    op.apply(u, &mut w.f0);
    if op.forcing(t, &mut w.fc) {
        for i in 0..n {
            w.f0[i] += w.fc[i];
        }
    }
    op.apply_mass(u, &mut w.mu);
    // Trapezoidal stage: (M - cA) u_γ = M u + c F0 (+ c F(t + γh)).
    for i in 0..n {
        w.rhs[i] = w.mu[i] + c * w.f0[i];
    }
    if op.forcing(t + GAMMA * h, &mut w.fc) {
        for i in 0..n {
            w.rhs[i] += c * w.fc[i];
        }
    }
    op.solve_shifted(c, &w.rhs, &mut w.ug)?;
    // F1 = A u_γ (+ F) from the stage relation (the stiff part is not
    // re-amplified).
    op.apply_mass(&w.ug, &mut w.f1);
    for i in 0..n {
        w.f1[i] = (w.f1[i] - w.mu[i]) / c - w.f0[i];
    }
    // BDF2 stage: (M - cA) u_{n+1} = M u + h w (F0 + F1) (+ c F(t + h)).
    for i in 0..n {
        w.rhs[i] = w.mu[i] + h * W * (w.f0[i] + w.f1[i]);
    }
    let forced = op.forcing(t + h, &mut w.fc);
    if forced {
        // w.err holds the right-hand side with the forcing for the solve.
        for i in 0..n {
            w.err[i] = w.rhs[i] + c * w.fc[i];
        }
        op.solve_shifted(c, &w.err, &mut w.un)?;
    } else {
        op.solve_shifted(c, &w.rhs, &mut w.un)?;
    }
    // F2 = A u_{n+1} (+ F(t + h)) = (M u_{n+1} - M u - h w (F0 + F1)) / c.
    op.apply_mass(&w.un, &mut w.f2);
    for i in 0..n {
        w.f2[i] = (w.f2[i] - w.rhs[i]) / c;
    }
    // Filtered error estimate: (M - cA) err = h Σ e_i F_i.
    for i in 0..n {
        w.rhs[i] = h * (E0 * w.f0[i] + E1 * w.f1[i] + E2 * w.f2[i]);
    }
    op.solve_shifted(c, &w.rhs, &mut w.err)?;
    stats.solves += 3;
    let norm = error_norm(op, u, w, tol, h)?;
    if norm <= 1.0 {
        u.copy_from_slice(&w.un);
        stats.steps += 1;
        Ok((norm.max(1e-10), true))
    } else {
        stats.rejected += 1;
        Ok((norm, false))
    }
}

/// The weighted norm of the error estimate `w.err` of the step from `u` to
/// `w.un` (see [`ShiftedLinear::rms_norm_with_max_over`]).
fn error_norm<O: ShiftedLinear>(
    op: &O,
    u: &[f64],
    w: &Work,
    tol: &Tolerances,
    h: f64,
) -> Result<f64> {
    let ratio = |i: usize| {
        let (old, new) = (u[i], w.un[i]);
        let sc = op.atol(i, tol.atol) + tol.rtol * old.abs().max(new.abs());
        let e = w.err[i].abs();
        if sc > 0.0 {
            e / sc
        } else if e > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    };
    Failure::check_finite(&w.un, "TR-BDF2 time stepping", h)?;
    Ok(match op.rms_norm_with_max_over() {
        None => (0..u.len()).map(ratio).fold(0.0, f64::max),
        Some(rows) => {
            let ms = (0..u.len()).map(|i| ratio(i).powi(2)).sum::<f64>() / u.len() as f64;
            rows.iter().map(|&i| ratio(i)).fold(ms.sqrt(), f64::max)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×2 rotation-decay system u' = A u with a known exponential, plus a
    /// stiff decoupled component (rate 1e8) that an explicit scheme could not
    /// step over.
    struct Test {
        a: [[f64; 3]; 3],
    }

    impl Test {
        fn new() -> Self {
            Test {
                a: [[-0.5, 2.0, 0.0], [-2.0, -0.5, 0.0], [0.0, 0.0, -1e8]],
            }
        }
    }

    impl ShiftedLinear for Test {
        fn dim(&self) -> usize {
            3
        }
        fn apply(&self, u: &[f64], out: &mut [f64]) {
            for (o, row) in out.iter_mut().zip(&self.a) {
                *o = row.iter().zip(u).map(|(a, x)| a * x).sum();
            }
        }
        fn solve_shifted(
            &mut self,
            c: f64,
            b: &[f64],
            x: &mut [f64],
        ) -> std::result::Result<(), Failure> {
            // 2×2 block by Cramer's rule, the stiff component apart.
            let (p, q) = (1.0 - c * self.a[0][0], -c * self.a[0][1]);
            let (r, s) = (-c * self.a[1][0], 1.0 - c * self.a[1][1]);
            let det = p * s - q * r;
            x[0] = (b[0] * s - q * b[1]) / det;
            x[1] = (p * b[1] - r * b[0]) / det;
            x[2] = b[2] / (1.0 - c * self.a[2][2]);
            Ok(())
        }
    }

    fn exact(t: f64) -> [f64; 2] {
        let e = (-0.5 * t).exp();
        [e * (2.0 * t).cos(), -e * (2.0 * t).sin()]
    }

    fn run(rtol: f64) -> (f64, Stats) {
        let times: Vec<f64> = (0..=20).map(|k| 0.25 * k as f64).collect();
        let mut u = [1.0, 0.0, 1.0];
        let mut worst = 0.0f64;
        let stats = integrate(
            &mut Test::new(),
            &mut u,
            &times,
            &Tolerances {
                rtol,
                atol: rtol,
                ..Default::default()
            },
            |_, t, u| {
                let e = exact(t);
                worst = worst.max((u[0] - e[0]).abs()).max((u[1] - e[1]).abs());
                if t > 0.0 {
                    assert!(u[2].abs() < 1e-12, "stiff component {} at t = {t}", u[2]);
                }
                Ok(())
            },
        )
        .unwrap();
        (worst, stats)
    }

    #[test]
    fn error_follows_the_tolerance_and_steps_scale_as_third_root() {
        let (e6, s6) = run(1e-6);
        let (e9, s9) = run(1e-9);
        eprintln!("errors {e6:e} {e9:e}, steps {} {}", s6.steps, s9.steps);
        // Per-step control of a second-order method: the global error grows
        // like (number of steps) × tolerance ~ tol^(2/3).
        assert!(
            e6 < 200.0 * 1e-6 && e9 < 2000.0 * 1e-9,
            "errors {e6:e} {e9:e}"
        );
        assert!(e9 < e6 / 50.0, "errors {e6:e} {e9:e}");
        // Local error ~ h³: 1000x tighter → about 10x more steps.
        let ratio = s9.steps as f64 / s6.steps as f64;
        assert!(
            (5.0..20.0).contains(&ratio),
            "steps {} -> {}",
            s6.steps,
            s9.steps
        );
    }

    /// u' = -u + 1 (scalar, forcing 1): u = 1 - e^{-t} from u(0) = 0.
    struct Forced;

    impl ShiftedLinear for Forced {
        fn dim(&self) -> usize {
            1
        }
        fn apply(&self, u: &[f64], out: &mut [f64]) {
            out[0] = -u[0];
        }
        fn solve_shifted(
            &mut self,
            c: f64,
            b: &[f64],
            x: &mut [f64],
        ) -> std::result::Result<(), Failure> {
            x[0] = b[0] / (1.0 + c);
            Ok(())
        }
        fn forcing(&self, _t: f64, out: &mut [f64]) -> bool {
            out[0] = 1.0;
            true
        }
    }

    #[test]
    fn forcing_enters_at_every_stage() {
        let times: Vec<f64> = (0..=10).map(|k| 0.5 * k as f64).collect();
        let mut u = [0.0];
        let tol = Tolerances {
            rtol: 1e-9,
            atol: 1e-9,
            ..Default::default()
        };
        let mut worst = 0.0f64;
        integrate(&mut Forced, &mut u, &times, &tol, |_, t, u| {
            worst = worst.max((u[0] - (1.0 - (-t).exp())).abs());
            Ok(())
        })
        .unwrap();
        // Without the forcing u stays 0: an error of order 1.
        assert!(worst < 1e-6, "error {worst:e}");
    }

    #[test]
    fn stiff_component_does_not_limit_the_step() {
        let (_, s) = run(1e-6);
        // An explicit scheme would need > 5e8 steps for rate 1e8 over t = 5.
        assert!(s.steps < 2000, "{} steps", s.steps);
    }

    #[test]
    fn max_steps_is_reported_as_non_convergence() {
        let mut u = [1.0, 0.0, 1.0];
        let tol = Tolerances {
            rtol: 1e-12,
            atol: 1e-12,
            max_steps: 10,
            ..Default::default()
        };
        let e = integrate(&mut Test::new(), &mut u, &[5.0], &tol, |_, _, _| Ok(())).unwrap_err();
        assert!(e.to_string().contains("TR-BDF2"), "{e}");
    }

    #[test]
    fn bad_times_are_refused() {
        let mut u = [1.0, 0.0, 1.0];
        let tol = Tolerances::default();
        assert!(integrate(
            &mut Test::new(),
            &mut u,
            &[1.0, 0.5],
            &tol,
            |_, _, _| Ok(())
        )
        .is_err());
        assert!(integrate(
            &mut Test::new(),
            &mut u,
            &[f64::NAN],
            &tol,
            |_, _, _| Ok(())
        )
        .is_err());
    }
}
