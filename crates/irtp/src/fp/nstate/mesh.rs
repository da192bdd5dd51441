//! The mesh and the fluxes of the N-state forward operator (Eq. (N20)).
//!
//! Breakpoints: every state's fixed point v*_s = g⁻¹(a_s), v_r, v = 0 (the
//! transient's initial velocity) and the ends of the domain. Without
//! thermal noise the state s piles up at v*_s with p_s ~ |v - v*_s|^a,
//! a = (q_s + r)/g'(v*_s) - 1 (Eq. (N21)); where a < 0 the cells are
//! graded towards v*_s with x ~ s^(1/(1+a)) from both sides (the
//! [`Piece`]s of the two-state kinked mesh), so that the densities are
//! smooth in the mesh parameter. Every node keeps its signed distance to
//! the breakpoint it was solved from, and a state's drift next to its own
//! fixed point is evaluated from that distance
//! ([`Drag::drift_at_distance`]), free of cancellation.
//!
//! Fluxes (Eq. (N22)): Scharfetter-Gummel across every inner face,
//! F = (T/δ) [B(-z) ρ_L - B(z) ρ_R], z = d δ/T, B(z) = z/(eᶻ - 1), which
//! is exact for a constant drift d, keeps the operator a Markov generator
//! (both coefficients ≥ 0) and tends to the upwind flux d⁺ρ_L - d⁻ρ_R as
//! T → 0 (used as is at T = 0). No flux through the domain's ends.

use super::super::grid::{piece_counts, End, Piece, LAYER, MAX_GRADING};
use crate::error::{Error, Result};
use crate::model::noise::chain::Chain;
use crate::model::reset::Reset;
use crate::model::{Drag, Params};

/// Ratio ∫ (g - a_max) dv / T beyond the outermost fixed point at which
/// an unbounded domain is truncated (the stationary tail beyond carries
/// about e^-40 of the mass; the solver checks the mass it finds there).
const TAIL_EXPONENT: f64 = 40.0;

/// A breakpoint of the mesh.
#[derive(Clone, Debug)]
struct Point {
    v: f64,
    /// Grading exponent q ≥ 1 of the cells next to it (1: none).
    q: f64,
    /// The states whose fixed point it is.
    states: Vec<usize>,
}

/// The mesh of the N-state operator and its transport rates.
#[derive(Clone, Debug)]
pub(crate) struct NMesh {
    /// Number of noise states N.
    pub states: usize,
    pub edges: Vec<f64>,
    pub widths: Vec<f64>,
    pub centres: Vec<f64>,
    /// `fwd[j N + s]`: rate at which state-s mass of cell j-1 crosses face
    /// j to cell j (0 on the outer faces j = 0, n).
    pub fwd: Vec<f64>,
    /// `back[j N + s]`: rate at which state-s mass of cell j crosses face j
    /// to cell j-1.
    pub back: Vec<f64>,
    /// Per state: the cells (and weights) receiving mass put at v_r.
    pub target: Vec<Vec<(usize, f64)>>,
    /// Per state: the cells (and weights) receiving mass put at v = 0.
    pub origin: Vec<Vec<(usize, f64)>>,
    /// Largest grading exponent.
    pub grading: f64,
    /// Whether the domain was truncated (an unbounded drag with T > 0).
    pub truncated: bool,
}

/// The mesh of `n << refine` cells (meshes with the same `n` nest).
pub(crate) fn mesh(p: &Params, c: &Chain, n: usize, refine: usize, graded: bool) -> Result<NMesh> {
    let (points, truncated) = points(p, c, graded)?;
    let pieces: Vec<Piece> = points
        .windows(2)
        .map(|w| {
            let len = w[1].v - w[0].v;
            let end = |q: f64| End {
                grade: (q > 1.0).then(|| (q, (LAYER * len).powf(1.0 - 1.0 / q))),
                cluster: None,
            };
            Piece {
                a: w[0].v,
                len,
                ends: [end(w[0].q), end(w[1].q)],
            }
        })
        .collect();
    if n < pieces.len() {
        return Err(Error::invalid(
            "cells",
            n,
            format!("at least {} cells (one per mesh piece)", pieces.len()),
        ));
    }
    let counts = piece_counts(&pieces, n);
    // Node k: position, and (breakpoint, signed distance from it).
    let (mut edges, mut anchor, mut widths) = (vec![points[0].v], vec![(0, 0.0)], Vec::new());
    for (k, (piece, &m)) in pieces.iter().zip(&counts).enumerate() {
        let m = m << refine;
        let nodes = piece.nodes(m)?;
        for w in nodes.windows(2) {
            let ((x0, y0), (x1, y1)) = (w[0], w[1]);
            widths.push(if x1 <= y1 {
                x1 - x0
            } else if x0 >= y0 {
                y0 - y1
            } else {
                piece.len - x0 - y1
            });
            // Each node from its nearer breakpoint (the piece's last node
            // is the next breakpoint itself, exactly).
            let (v, a) = if x1 > y1 {
                (points[k + 1].v - y1, (k + 1, -y1))
            } else {
                (piece.a + x1, (k, x1))
            };
            edges.push(v);
            anchor.push(a);
        }
    }
    let centres = (0..widths.len())
        .map(|i| 0.5 * (edges[i] + edges[i + 1]))
        .collect();
    let drift = |j: usize, s: usize| {
        let (k, off) = anchor[j];
        let a = c.levels[s];
        if points[k].states.contains(&s) {
            p.drag().drift_at_distance(a, -off)
        } else {
            a - p.drag().force(edges[j])
        }
    };
    let (fwd, back) = rates(&widths, c, &drift);
    let node = |w: f64| edges.iter().position(|&e| e == w);
    let place = |w: f64| -> Vec<Vec<(usize, f64)>> {
        let j = node(w).expect("a breakpoint is a node");
        (0..c.states())
            .map(|s| placement(j, &widths, drift(j, s), c.temperature))
            .collect()
    };
    let target = match p.reset().point() {
        Some(v) => place(v),
        None => spread(p, &edges, c.states())?,
    };
    let origin = if node(0.0).is_some() {
        place(0.0)
    } else {
        Vec::new()
    };
    Ok(NMesh {
        states: c.states(),
        edges,
        widths,
        centres,
        fwd,
        back,
        target,
        origin,
        grading: points.iter().fold(1.0, |m, p| m.max(p.q)),
        truncated,
    })
}

/// A random reset target's cell masses on the mesh (Eq. (N20)'s δ(v - v_r)
/// replaced by the target's law), the same for every state; refused (naming
/// `reset_to`) where the domain holds less than 1 - 1e-10 of the law.
fn spread(p: &Params, edges: &[f64], states: usize) -> Result<Vec<Vec<(usize, f64)>>> {
    let t = p.reset().target();
    let m: Vec<f64> = edges.windows(2).map(|e| t.mass(e[0], e[1])).collect();
    let (inside, all) = (
        m.iter().sum::<f64>(),
        t.mass(f64::NEG_INFINITY, f64::INFINITY),
    );
    if !(inside >= (1.0 - 1e-10) * all && inside > 0.0) {
        return Err(Error::invalid(
            "reset_to",
            p.reset_spec().unwrap_or_default(),
            format!(
                "a target law inside the computational domain [{}, {}] (it holds {:e} of it)",
                edges[0],
                edges[edges.len() - 1],
                inside / all
            ),
        ));
    }
    let cells: Vec<(usize, f64)> = m
        .iter()
        .enumerate()
        .filter(|(_, &x)| x > 0.0)
        .map(|(i, &x)| (i, x / inside))
        .collect();
    Ok(vec![cells; states])
}

/// Cells receiving mass put at node j in a state with drift d there: at
/// T = 0 the cell the state moves into; with thermal noise (or d = 0) the
/// two cells next to the node, weighted h_L/(h_L + h_R) to the right one
/// so that the mean of the cell centres is the node (first moment exact);
/// one cell at the domain's ends.
fn placement(j: usize, widths: &[f64], d: f64, t: f64) -> Vec<(usize, f64)> {
    let n = widths.len();
    if j == 0 {
        return vec![(0, 1.0)];
    }
    if j == n {
        return vec![(n - 1, 1.0)];
    }
    match (t > 0.0, d) {
        (false, d) if d > 0.0 => vec![(j, 1.0)],
        (false, d) if d < 0.0 => vec![(j - 1, 1.0)],
        _ => {
            let (hl, hr) = (widths[j - 1], widths[j]);
            vec![(j - 1, hr / (hl + hr)), (j, hl / (hl + hr))]
        }
    }
}

/// The transport rates (fwd, back) of every inner face and state from the
/// drift at the face (Scharfetter-Gummel, Eq. (N22)).
fn rates(widths: &[f64], c: &Chain, drift: &dyn Fn(usize, usize) -> f64) -> (Vec<f64>, Vec<f64>) {
    let (n, ns) = (widths.len(), c.states());
    let mut fwd = vec![0.0; (n + 1) * ns];
    let mut back = vec![0.0; (n + 1) * ns];
    for j in 1..n {
        let delta = 0.5 * (widths[j - 1] + widths[j]);
        for s in 0..ns {
            let (f, b) = face_flux(drift(j, s), c.temperature, delta);
            fwd[j * ns + s] = f / widths[j - 1];
            back[j * ns + s] = b / widths[j];
        }
    }
    (fwd, back)
}

/// The coefficients (f, b) ≥ 0 of F = f ρ_L - b ρ_R: upwind at T = 0,
/// Scharfetter-Gummel at T > 0.
pub(crate) fn face_flux(d: f64, t: f64, delta: f64) -> (f64, f64) {
    if !(t > 0.0) {
        return (d.max(0.0), (-d).max(0.0));
    }
    let z = d * delta / t;
    let k = t / delta;
    (k * bernoulli(-z), k * bernoulli(z))
}

/// B(z) = z/(eᶻ - 1), accurate for every z (B(0) = 1, B(z) → -z as
/// z → -∞, → 0 as z → ∞).
fn bernoulli(z: f64) -> f64 {
    if z.abs() < 1e-8 {
        1.0 - 0.5 * z
    } else if z > 700.0 {
        z * (-z).exp()
    } else if z < -700.0 {
        -z
    } else {
        z / z.exp_m1()
    }
}

/// The breakpoints, sorted, and whether the domain was truncated.
fn points(p: &Params, c: &Chain, graded: bool) -> Result<(Vec<Point>, bool)> {
    let drag = p.drag();
    let (r, t) = (p.rate(), c.temperature);
    let mut pts: Vec<Point> = Vec::new();
    let mut add = |v: f64, q: f64, s: Option<usize>| match pts.iter_mut().find(|x| x.v == v) {
        Some(x) => {
            x.q = x.q.max(q);
            x.states.extend(s);
        }
        None => pts.push(Point {
            v,
            q,
            states: s.into_iter().collect(),
        }),
    };
    for (s, &a) in c.levels.iter().enumerate() {
        let v = drag.inverse(a);
        let e = (c.exit[s] + r) / drag.derivative(v) - 1.0;
        let q = if graded && t == 0.0 && e < 0.0 {
            (1.0 / (1.0 + e)).min(MAX_GRADING)
        } else {
            1.0
        };
        add(v, q, Some(s));
    }
    let (lo, hi) = p.bounds();
    let vr = p.reset_velocity();
    add(vr, 1.0, None);
    // A random target's finite support ends are nodes (its law's kinks).
    let (s_lo, s_hi) = p.reset().target().support();
    let (lo, hi, truncated) = if lo.is_finite() && hi.is_finite() {
        (lo, hi, false)
    } else {
        let (a, b) = tails(p, c)?;
        let fin = |x: f64| if x.is_finite() { x } else { vr };
        (a.min(vr).min(fin(s_lo)), b.max(vr).max(fin(s_hi)), true)
    };
    if lo < 0.0 && hi > 0.0 {
        add(0.0, 1.0, None);
    }
    for e in [s_lo, s_hi] {
        if e > lo && e < hi {
            add(e, 1.0, None);
        }
    }
    add(lo, 1.0, None);
    add(hi, 1.0, None);
    pts.sort_by(|a, b| a.v.total_cmp(&b.v));
    if !(pts[0].v == lo && pts[pts.len() - 1].v == hi) {
        return Err(Error::invalid(
            "reset_velocity",
            vr,
            format!("inside the velocity interval ({lo}, {hi})"),
        ));
    }
    Ok((pts, truncated))
}

/// The truncated domain of an unbounded drag with T > 0: beyond the
/// outermost fixed point v* (of level a) by the smallest W with
/// ∫_0^W (g(v* + u) - a) du ≥ 40 T (doubling W from the thermal width
/// sqrt(T/g'(v*))), on each side.
fn tails(p: &Params, c: &Chain) -> Result<(f64, f64)> {
    let drag = p.drag();
    let t = c.temperature;
    let side = |a: f64, sign: f64| -> Result<f64> {
        let v0 = drag.inverse(a);
        let mut w = (t / drag.derivative(v0)).sqrt();
        for _ in 0..200 {
            let m = 256;
            let h = w / m as f64;
            let f = |u: f64| sign * (drag.force(v0 + sign * u) - a);
            let integral: f64 = (0..m)
                .map(|k| {
                    h / 6.0
                        * (f(k as f64 * h) + 4.0 * f((k as f64 + 0.5) * h) + f((k + 1) as f64 * h))
                })
                .sum();
            if integral >= TAIL_EXPONENT * t {
                return Ok(v0 + sign * w);
            }
            w *= 2.0;
        }
        Err(Error::Numerical {
            method: "fp (thermal domain)",
            reason: format!("no truncation width found beyond v* = {v0}"),
        })
    };
    let lo = c.levels.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = c.levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Ok((side(lo, -1.0)?, side(hi, 1.0)?))
}
