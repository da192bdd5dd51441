//! The search's 2-D backward equation with a finite-state noise model
//! (`irtp::search::backward`, docs/equations.md, "Search: the 2-D backward
//! equation and the renewal route"): the paper's noise written as a chain,
//! and a lumpable 3-state chain of it, give the paper solver's tau; the
//! run-and-pause-tumble noise resolves on the three-mesh ladder and agrees
//! with an Euler particle loop; a temperature is refused.

use irtp::model::noise::NoiseModel;
use irtp::model::reset::Schedule;
use irtp::model::Drag;
use irtp::search::backward::{solve, BackwardOptions, SearchSolution};
use irtp::search::{PositionTarget, SearchProblem};
use irtp::{DragLaw, Params};

/// The paper's telegraph noise ±sigma at lambda = 0.5 as a 2-state chain.
fn two_state(sigma: f64) -> String {
    format!(
        "states:levels=[{sigma},{}],rates=[[-0.5,0.5],[0.5,-0.5]]",
        -sigma
    )
}

/// A 3-state chain lumpable to the telegraph at rate 0.5: two hidden
/// states at +sigma (each leaves to -sigma at 0.5, and to the other at
/// `h`), one at -sigma (leaves to each hidden state at 0.25).
fn lumpable(sigma: f64, h: f64) -> String {
    format!(
        "states:levels=[{sigma},{sigma},{}],rates=[[{},{h},0.5],[{h},{},0.5],[0.25,0.25,-0.5]]",
        -sigma,
        -0.5 - h,
        -0.5 - h
    )
}

/// Full resetting to (x_r, v_r) = (0, 0) at rate `r`, noise kept; the
/// paper's noise for `noise` None.
fn params(drag: DragLaw, sigma: f64, noise: Option<&str>, r: f64) -> Params {
    let p = match noise {
        None => Params::new(drag, sigma, 0.5, r, 0.0).unwrap(),
        Some(n) => Params::with_noise(drag, NoiseModel::parse(n, 0.0).unwrap(), r, 0.0).unwrap(),
    };
    p.with_schedule(Schedule::parse(None, Some(0.0), None).unwrap())
        .unwrap()
}

fn search(p: Params, target: PositionTarget, cells: (usize, usize)) -> SearchSolution {
    let problem = SearchProblem::new(p, 0.0, 0.0, target).unwrap();
    solve(&problem, &BackwardOptions::with_cells(cells.0, cells.1)).unwrap()
}

/// The cases: linear and tanh drag, a level (x_t = 1) and an interval
/// (-1, 1), r = 0.5 and 2.
fn cases() -> Vec<(DragLaw, f64, PositionTarget, f64)> {
    let mut out = vec![];
    for (drag, sigma) in [(DragLaw::Linear, 1.0), (DragLaw::Tanh, 0.8)] {
        for target in [
            PositionTarget::Level(1.0),
            PositionTarget::Interval(-1.0, 1.0),
        ] {
            for r in [0.5, 2.0] {
                out.push((drag.clone(), sigma, target, r));
            }
        }
    }
    out
}

/// The paper's noise as a chain is the same process on the same mesh (the
/// layout's far scale uses the mean jump rate, lambda for both), so tau
/// agrees to round-off: within 1e-9 relative (measured ≤ 1e-13); the
/// per-state values are tau+ and tau-.
#[test]
fn two_state_chain_is_the_paper_noise() {
    for (drag, sigma, target, r) in cases() {
        let paper = search(params(drag.clone(), sigma, None, r), target, (16, 8));
        let chain = search(
            params(drag.clone(), sigma, Some(&two_state(sigma)), r),
            target,
            (16, 8),
        );
        let what = format!("{drag:?} {target:?} r = {r}");
        assert!(
            paper.tau_states.is_none() && paper.tau_plus.is_finite(),
            "{what}"
        );
        assert!(
            chain.tau_plus.is_nan() && chain.tau_minus.is_nan(),
            "{what}"
        );
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        assert!(
            close(chain.tau, paper.tau),
            "{what}: {} vs {}",
            chain.tau,
            paper.tau
        );
        let states = chain.tau_states.as_ref().unwrap();
        assert!(close(states[0], paper.tau_plus), "{what}: {states:?}");
        assert!(close(states[1], paper.tau_minus), "{what}: {states:?}");
        assert!(paper.error_estimate.is_finite() && chain.error_estimate.is_finite());
    }
}

/// A lumpable 3-state chain: without hidden jumps (h = 0) the mesh
/// generator lumps exactly (same mesh: round-off agreement, 1e-9 relative),
/// the two hidden states giving the same T; with hidden jumps (h = 0.25)
/// the far stretch's scale changes with the mean jump rate, so the meshes
/// differ and tau agrees within the two error estimates.
#[test]
fn lumpable_three_state_chain_is_the_paper_noise() {
    for (drag, sigma, target, r) in cases() {
        let paper = search(params(drag.clone(), sigma, None, r), target, (16, 8));
        let what = format!("{drag:?} {target:?} r = {r}");
        let exact = search(
            params(drag.clone(), sigma, Some(&lumpable(sigma, 0.0)), r),
            target,
            (16, 8),
        );
        let s = exact.tau_states.as_ref().unwrap();
        assert!(
            (exact.tau - paper.tau).abs() <= 1e-9 * paper.tau,
            "{what}: {s:?}"
        );
        assert!((s[0] - s[1]).abs() <= 1e-9 * s[0], "{what}: {s:?}");
        let hidden = search(
            params(drag, sigma, Some(&lumpable(sigma, 0.25)), r),
            target,
            (16, 8),
        );
        let bound = hidden.error_estimate + paper.error_estimate;
        assert!(
            (hidden.tau - paper.tau).abs() <= bound,
            "{what}: {} vs {} (bound {bound:e})",
            hidden.tau,
            paper.tau
        );
    }
}

/// Run-and-pause-tumble noise (levels +1, 0, -1; the pause's fixed point
/// v = 0 inside the velocity interval): the three-mesh ladder is
/// asymptotic, the error estimate finite and small, tau positive and above
/// the speed bound, the pause state's T between the run states'.
#[test]
fn rpt_noise_resolves() {
    let p = params(
        DragLaw::Linear,
        1.0,
        Some("rpt:sigma=1,alpha=1,beta=2"),
        0.5,
    );
    let s = search(p, PositionTarget::Level(1.0), (32, 16));
    assert!(s.asymptotic, "{s:?}");
    assert!(
        s.error_estimate.is_finite() && s.error_estimate < 0.05 * s.tau,
        "{s:?}"
    );
    let t = s.tau_states.as_ref().unwrap();
    assert_eq!(t.len(), 3);
    assert!(s.tau > 1.0 && t.iter().all(|&x| x > 1.0), "{s:?}");
    assert!(t[0] < t[1] && t[1] < t[2], "+1 reaches x = 1 first: {t:?}");
    assert!(s.reset_states.as_ref().is_some_and(|r| r.len() == 3));
}

/// splitmix64: a small fixed-seed generator for the particle loop.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Euler particles of the search from (0, 0) to x = 1, full resets to
/// (0, 0) at rate `r` (noise kept), the start state drawn from π: the
/// mean and standard error of n passage times at step dt.
fn euler_mean(p: &Params, r: f64, dt: f64, n: usize, seed: u64) -> (f64, f64) {
    let c = p.chain().unwrap();
    let mut rng = Rng(seed);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..n {
        let mut s = c.draw_stationary(rng.uniform());
        let (mut x, mut v, mut t) = (0.0f64, 0.0f64, 0.0f64);
        while x < 1.0 {
            let u = rng.uniform();
            let jump = c.exit[s] * dt;
            if u < jump {
                s = c.jump(s, u / dt);
            } else if u < jump + r * dt {
                (x, v) = (0.0, 0.0);
            }
            let dv = p.drag().drift(c.levels[s], v) * dt;
            x += v * dt;
            v += dv;
            t += dt;
        }
        sum += t;
        sum2 += t * t;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean) * n as f64 / (n as f64 - 1.0);
    (mean, (var / n as f64).sqrt())
}

/// rpt noise against an Euler particle loop written here (steps 0.02 and
/// 0.01, extrapolated to dt → 0 as 2 T(dt/2) - T(dt), fixed seeds): within
/// 4 standard errors plus the backward solver's error estimate.
#[test]
fn rpt_noise_matches_euler_particles() {
    let r = 0.5;
    let p = params(DragLaw::Linear, 1.0, Some("rpt:sigma=1,alpha=1,beta=2"), r);
    let s = search(p.clone(), PositionTarget::Level(1.0), (32, 16));
    let n = 20_000;
    let (coarse, se_c) = euler_mean(&p, r, 0.02, n, 11);
    let (fine, se_f) = euler_mean(&p, r, 0.01, n, 12);
    let tau = 2.0 * fine - coarse;
    let se = (4.0 * se_f * se_f + se_c * se_c).sqrt();
    let bound = 4.0 * se + s.error_estimate;
    assert!(
        (tau - s.tau).abs() <= bound,
        "Euler {tau} ± {se} vs backward {} ± {} (dt 0.02: {coarse}, 0.01: {fine})",
        s.tau,
        s.error_estimate
    );
}

/// A noise model with a temperature is refused by the search problem in
/// one line naming `temperature`.
#[test]
fn temperature_is_refused() {
    let noise = NoiseModel::parse("rpt:sigma=1,alpha=1,beta=2", 0.5).unwrap();
    let p = Params::with_noise(DragLaw::Linear, noise, 0.5, 0.0)
        .unwrap()
        .with_schedule(Schedule::parse(None, Some(0.0), None).unwrap())
        .unwrap();
    let e = SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(1.0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("temperature"), "{e}");
    assert!(!e.contains('\n') && e.len() < 200, "{} chars: {e}", e.len());
}
