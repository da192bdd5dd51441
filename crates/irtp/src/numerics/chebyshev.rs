//! Piecewise Chebyshev tables: fit a few smooth functions on a piece by
//! interpolation at Chebyshev points, refine the pieces adaptively until
//! the fits are resolved ([`fit_adaptive`]), integrate the series exactly,
//! and sum series by Clenshaw's recurrence. Hand-written because the tables are
//! evaluated once per event in the exact sampler: a fixed-degree,
//! allocation-free kernel is faster than any general crate.

/// Interpolation nodes per piece (series degree NODES - 1).
pub const NODES: usize = 16;
/// Coefficients of an antiderivative series (degree NODES).
pub const NC: usize = NODES + 1;

/// Chebyshev fit of K functions on one piece [a, b].
#[derive(Clone, Debug)]
pub struct Fit<const K: usize> {
    /// Series of each function, Σ_j c_j T_j(x) with x ∈ [-1, 1] (c_0 already
    /// halved, last coefficient 0), ready for [`clenshaw`].
    pub series: [[f64; NC]; K],
    /// Antiderivatives (zero at a), in the same variable.
    pub anti: [[f64; NC]; K],
    /// Largest of the last three coefficients, per function.
    pub tail: [f64; K],
    /// Largest coefficient, per function.
    pub scale: [f64; K],
    /// All sampled values finite.
    pub finite: bool,
    /// Half the piece width, (b - a) / 2.
    pub half_width: f64,
}

impl<const K: usize> Fit<K> {
    /// Resolved to relative accuracy `rel`: every function's tail at most
    /// `rel` times its scale (or identically zero), and all values finite.
    pub fn resolved(&self, rel: f64) -> bool {
        self.finite
            && (0..K).all(|k| {
                !(self.scale[k] > 0.0) || self.tail[k] <= rel * self.scale[k].max(f64::MIN_POSITIVE)
            })
    }

    /// [`resolved`](Self::resolved), or else resolved down to the rounding
    /// noise of the sampled values: a function evaluated at an abscissa of
    /// size `abscissa` carries an error of about |f'| ulp(abscissa) from the
    /// abscissa's own rounding, which no refinement removes (a steep drag law
    /// near its pole: tan at Sigma = 3000). |f'| is bounded by the series,
    /// Σ j² |c_j| / half_width.
    pub fn resolved_to_noise(&self, rel: f64, abscissa: f64) -> bool {
        self.resolved(rel)
            || (self.finite
                && (0..K).all(|k| {
                    let slope: f64 = self.series[k]
                        .iter()
                        .enumerate()
                        .map(|(j, c)| (j * j) as f64 * c.abs())
                        .sum::<f64>()
                        / self.half_width;
                    let noise = 8.0 * f64::EPSILON * abscissa.abs() * slope;
                    self.tail[k] <= (rel * self.scale[k]).max(noise)
                }))
    }
}

/// Fit `f` (K functions at once) on [a, b].
pub fn fit<const K: usize>(f: &dyn Fn(f64) -> [f64; K], a: f64, b: f64) -> Fit<K> {
    let n = NODES;
    let h = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    let vals: Vec<[f64; K]> = (0..n)
        .map(|j| {
            let x = (std::f64::consts::PI * (j as f64 + 0.5) / n as f64).cos();
            f(mid + h * x)
        })
        .collect();
    let mut out = Fit {
        series: [[0.0; NC]; K],
        anti: [[0.0; NC]; K],
        tail: [0.0; K],
        scale: [0.0; K],
        finite: vals.iter().all(|v| v.iter().all(|x| x.is_finite())),
        half_width: h,
    };
    for k in 0..K {
        // Coefficients c_j of f = c_0/2 + Σ_{j≥1} c_j T_j.
        let mut c = [0.0; NODES + 2];
        for (j, cj) in c.iter_mut().enumerate().take(n) {
            let mut s = 0.0;
            for (i, v) in vals.iter().enumerate() {
                s += v[k] * (std::f64::consts::PI * j as f64 * (i as f64 + 0.5) / n as f64).cos();
            }
            *cj = 2.0 * s / n as f64;
        }
        out.scale[k] = c[..n].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        out.tail[k] = c[n - 3..n].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        // Antiderivative: C_j = h (c_{j-1} - c_{j+1}) / (2j), C_0 from F(-1) = 0.
        let d = &mut out.anti[k];
        for j in 1..NC {
            d[j] = h * (c[j - 1] - c[j + 1]) / (2.0 * j as f64);
        }
        let mut at_minus1 = 0.0;
        for (j, dj) in d.iter().enumerate().skip(1) {
            at_minus1 += if j % 2 == 0 { *dj } else { -*dj };
        }
        d[0] = -at_minus1;
        out.series[k][..n].copy_from_slice(&c[..n]);
        out.series[k][0] *= 0.5;
    }
    out
}

/// One piece [a, b] of a piecewise fit.
#[derive(Clone, Debug)]
pub struct Piece<const K: usize> {
    /// Left end.
    pub a: f64,
    /// Right end.
    pub b: f64,
    /// The fit on [a, b].
    pub fit: Fit<K>,
}

/// How [`fit_adaptive`] refines a piece whose fit is not resolved.
#[derive(Clone, Copy)]
pub enum Refine<'a> {
    /// Halve the unresolved piece alone, depth first (pieces come out left
    /// to right), until it is resolved or narrower than `min_width(a, b)`
    /// (which may depend on where the piece lies, e.g. finer at a kink).
    /// There a piece with finite values is kept unresolved where
    /// `keep_at_floor(a, b)` says so; anywhere else the fit fails.
    Bisect {
        /// Width below which a piece [a, b] is not halved again.
        min_width: &'a dyn Fn(f64, f64) -> f64,
        /// Whether an unresolved piece at that width is kept.
        keep_at_floor: &'a dyn Fn(f64, f64) -> bool,
    },
    /// Cover each interval with 2^d equal pieces, the smallest
    /// d ≤ `max_depth` for which every piece is resolved (for tables that
    /// find a piece by arithmetic instead of a search).
    Uniform {
        /// Largest d tried.
        max_depth: u32,
    },
}

/// The options of [`fit_adaptive`].
#[derive(Clone, Copy)]
pub struct Adaptive<'a, const K: usize> {
    /// Whether the fit on [a, b] (the arguments after the fit) is accurate
    /// enough to keep; the caller's tolerance (coefficient decay, rounding
    /// noise, integrated error, ...).
    pub resolved: &'a dyn Fn(&Fit<K>, f64, f64) -> bool,
    /// The refinement strategy.
    pub refine: Refine<'a>,
    /// Most pieces the fit may keep.
    pub max_pieces: usize,
}

/// Why [`fit_adaptive`] gave up: the function is too rough (or not finite)
/// for the tolerance.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Unresolved {
    /// A piece at the smallest width is neither resolved nor kept.
    #[error("Chebyshev fit not resolved on [{a}, {b}] at the smallest piece width")]
    Piece {
        /// Left end of the piece.
        a: f64,
        /// Right end of the piece.
        b: f64,
    },
    /// No uniform subdivision up to 2^`max_depth` pieces is resolved.
    #[error("Chebyshev fit not resolved on [{a}, {b}] with up to 2^{max_depth} pieces")]
    Depth {
        /// Left end of the interval.
        a: f64,
        /// Right end of the interval.
        b: f64,
        /// Deepest subdivision tried.
        max_depth: u32,
    },
    /// More than `max` pieces would be needed.
    #[error("Chebyshev fit needs more than {max} pieces")]
    TooManyPieces {
        /// The limit.
        max: usize,
    },
}

/// Fit `f` (K functions at once) piecewise on consecutive `intervals`,
/// refining each as `opts` says until every kept piece is resolved. The
/// pieces come out left to right, covering the intervals.
pub fn fit_adaptive<const K: usize>(
    f: &dyn Fn(f64) -> [f64; K],
    intervals: &[(f64, f64)],
    opts: &Adaptive<K>,
) -> Result<Vec<Piece<K>>, Unresolved> {
    match opts.refine {
        Refine::Bisect {
            min_width,
            keep_at_floor,
        } => bisect(f, intervals, opts, min_width, keep_at_floor),
        Refine::Uniform { max_depth } => {
            let mut pieces = Vec::new();
            for &(a, b) in intervals {
                let budget = opts.max_pieces - pieces.len();
                pieces.extend(uniform(f, a, b, opts.resolved, max_depth, budget)?);
            }
            Ok(pieces)
        }
    }
}

/// [`Refine::Bisect`]: a stack of pieces, the leftmost on top.
fn bisect<const K: usize>(
    f: &dyn Fn(f64) -> [f64; K],
    intervals: &[(f64, f64)],
    opts: &Adaptive<K>,
    min_width: &dyn Fn(f64, f64) -> f64,
    keep_at_floor: &dyn Fn(f64, f64) -> bool,
) -> Result<Vec<Piece<K>>, Unresolved> {
    let mut pieces = Vec::new();
    let mut stack: Vec<(f64, f64)> = intervals.iter().rev().copied().collect();
    while let Some((a, b)) = stack.pop() {
        let fit = fit(f, a, b);
        let keep = if (opts.resolved)(&fit, a, b) {
            true
        } else if b - a < min_width(a, b) {
            if !(fit.finite && keep_at_floor(a, b)) {
                return Err(Unresolved::Piece { a, b });
            }
            true
        } else {
            false
        };
        if keep {
            if pieces.len() >= opts.max_pieces {
                return Err(Unresolved::TooManyPieces {
                    max: opts.max_pieces,
                });
            }
            pieces.push(Piece { a, b, fit });
        } else {
            let m = 0.5 * (a + b);
            stack.push((m, b));
            stack.push((a, m));
        }
    }
    Ok(pieces)
}

/// [`Refine::Uniform`] on [a, b] with at most `max_pieces` pieces.
fn uniform<const K: usize>(
    f: &dyn Fn(f64) -> [f64; K],
    a: f64,
    b: f64,
    resolved: &dyn Fn(&Fit<K>, f64, f64) -> bool,
    max_depth: u32,
    max_pieces: usize,
) -> Result<Vec<Piece<K>>, Unresolved> {
    'depth: for d in 0..=max_depth {
        let m = 1usize << d;
        if m > max_pieces {
            return Err(Unresolved::TooManyPieces { max: max_pieces });
        }
        let mut pieces = Vec::with_capacity(m);
        for j in 0..m {
            let pa = a + (b - a) * j as f64 / m as f64;
            let pb = if j + 1 == m {
                b
            } else {
                a + (b - a) * (j + 1) as f64 / m as f64
            };
            let fit = fit(f, pa, pb);
            if !resolved(&fit, pa, pb) {
                continue 'depth;
            }
            pieces.push(Piece { a: pa, b: pb, fit });
        }
        return Ok(pieces);
    }
    Err(Unresolved::Depth { a, b, max_depth })
}

/// Fits of `f` on the dyadic pieces [lo 2^i, lo 2^(i+1)] whose right end
/// is at most `limit` (towards a singular end at 0, where the scale of
/// variation shrinks with the distance), and the right end of the last
/// one (`lo` when there is none).
pub fn fit_dyadic<const K: usize>(
    f: &dyn Fn(f64) -> [f64; K],
    lo: f64,
    limit: f64,
) -> (Vec<Piece<K>>, f64) {
    let mut pieces = Vec::new();
    let mut a = lo;
    while 2.0 * a <= limit {
        pieces.push(Piece {
            a,
            b: 2.0 * a,
            fit: fit(f, a, 2.0 * a),
        });
        a *= 2.0;
    }
    (pieces, a)
}

/// A piecewise fit of a table with a singular end at 0 (the flow and the
/// r = 0 exponent of a law given by g and g'): dyadic pieces from `lo`
/// while their right end is at most `limit` ([`fit_dyadic`]), then
/// [`Refine::Bisect`] from there to `breaks[0]`, from `breaks[0]` to
/// `breaks[1]`, ..., pieces narrower than `min_width` kept as they are;
/// at most `max_pieces` in all, and [`Unresolved::Piece`] where a fit has
/// non-finite values.
pub fn fit_towards_zero<const K: usize>(
    f: &dyn Fn(f64) -> [f64; K],
    (lo, limit): (f64, f64),
    breaks: &[f64],
    resolved: &dyn Fn(&Fit<K>, f64, f64) -> bool,
    min_width: f64,
    max_pieces: usize,
) -> Result<Vec<Piece<K>>, Unresolved> {
    let (mut pieces, mut a) = fit_dyadic(f, lo, limit);
    let intervals: Vec<(f64, f64)> = breaks
        .iter()
        .map(|&b| (std::mem::replace(&mut a, b), b))
        .collect();
    let opts = Adaptive {
        resolved,
        refine: Refine::Bisect {
            min_width: &|_, _| min_width,
            keep_at_floor: &|_, _| true,
        },
        max_pieces: max_pieces.saturating_sub(pieces.len()),
    };
    pieces.extend(fit_adaptive(f, &intervals, &opts)?);
    match pieces.iter().find(|p| !p.fit.finite) {
        Some(p) => Err(Unresolved::Piece { a: p.a, b: p.b }),
        None => Ok(pieces),
    }
}

/// Σ_{k=0}^{N} c_k T_k(x) by Clenshaw's recurrence.
#[inline]
pub fn clenshaw(c: &[f64; NC], x: f64) -> f64 {
    let (mut b1, mut b2) = (0.0, 0.0);
    let x2 = 2.0 * x;
    for &ck in c[1..].iter().rev() {
        // Plain mul/add: without a target FMA unit, mul_add is a slow soft call.
        let b0 = x2 * b1 + (ck - b2);
        b2 = b1;
        b1 = b0;
    }
    x * b1 + (c[0] - b2)
}

/// Two Chebyshev series Σ_j `c_j[k]` T_j(x), k = 0, 1, in one Clenshaw pass
/// (independent recurrences interleaved for instruction-level parallelism).
#[inline]
pub fn clenshaw2(c: &[[f64; 2]; NC], x: f64) -> [f64; 2] {
    let (mut b1, mut b2) = ([0.0f64; 2], [0.0f64; 2]);
    let x2 = 2.0 * x;
    for cj in c[1..].iter().rev() {
        let b0 = [x2 * b1[0] + (cj[0] - b2[0]), x2 * b1[1] + (cj[1] - b2[1])];
        b2 = b1;
        b1 = b0;
    }
    [x * b1[0] + (c[0][0] - b2[0]), x * b1[1] + (c[0][1] - b2[1])]
}

/// The first M Chebyshev coefficients (`c`, as [`clenshaw`] takes them) as
/// the coefficients of the same polynomial in powers of x: well conditioned
/// on [-1, 1] for a fast-decaying series (|c_j| ≪ (1+√2)^-j), which
/// [`power_sum`] then sums without Clenshaw's serial chain.
pub fn to_power<const M: usize>(c: &[f64]) -> [f64; M] {
    let mut out = [0.0; M];
    // T_{j-1} and T_j in powers of x.
    let (mut prev, mut cur) = ([0.0; M], [0.0; M]);
    cur[0] = 1.0;
    for (j, cj) in c.iter().enumerate().take(M) {
        for (o, t) in out.iter_mut().zip(&cur) {
            *o += cj * t;
        }
        let mut next = [0.0; M];
        for i in 0..M {
            let up = if i > 0 { cur[i - 1] } else { 0.0 };
            next[i] = if j == 0 { up } else { 2.0 * up - prev[i] };
        }
        prev = cur;
        cur = next;
    }
    out
}

/// K polynomials Σ_{j<12} `a_j[k]` x^j at once by Estrin's scheme (depth 4
/// instead of Horner's 11: the K sums and the pairs within each run in
/// parallel).
#[inline(always)]
pub fn power_sum<const K: usize>(a: &[[f64; K]; 12], x: f64) -> [f64; K] {
    let x2 = x * x;
    let x4 = x2 * x2;
    let x8 = x4 * x4;
    std::array::from_fn(|k| {
        let p = |j: usize| a[j][k] + a[j + 1][k] * x;
        let q0 = p(0) + p(2) * x2;
        let q1 = p(4) + p(6) * x2;
        let q2 = p(8) + p(10) * x2;
        (q0 + q1 * x4) + q2 * x8
    })
}

/// Map v ∈ [a, b] to x ∈ [-1, 1] (clamped against rounding).
#[inline]
pub fn to_unit(v: f64, a: f64, b: f64) -> f64 {
    ((2.0 * v - a - b) / (b - a)).clamp(-1.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_and_integrates_exp() {
        let f = fit(&|x: f64| [x.exp(), x.sin()], 0.5, 1.5);
        assert!(f.resolved(1e-14));
        for &v in &[0.5, 0.8, 1.2, 1.5] {
            let x = to_unit(v, 0.5, 1.5);
            assert!((clenshaw(&f.series[0], x) - v.exp()).abs() < 1e-14);
            assert!((clenshaw(&f.anti[0], x) - (v.exp() - 0.5f64.exp())).abs() < 1e-14);
            assert!((clenshaw(&f.anti[1], x) - (0.5f64.cos() - v.cos())).abs() < 1e-14);
        }
        // The same series in powers of the unit variable.
        let mut c = [[0.0; 1]; 12];
        for (cj, pj) in c.iter_mut().zip(to_power::<12>(&f.series[0])) {
            cj[0] = pj;
        }
        for &v in &[0.5, 0.8, 1.2, 1.5] {
            let x = to_unit(v, 0.5, 1.5);
            assert!((power_sum(&c, x)[0] - v.exp()).abs() < 1e-14);
        }
        let g = fit(&|x: f64| [1.0 / (x - 0.49)], 0.5, 1.5);
        assert!(!g.resolved(1e-14));
    }

    /// A pole just left of the interval: bisection refines towards it, the
    /// uniform subdivision refines everywhere, both resolve, and a too
    /// small budget or floor is reported.
    #[test]
    fn adaptive_fits_refine_towards_a_pole() {
        let f = |x: f64| [1.0 / (x - 0.49)];
        let resolved = |fit: &Fit<1>, _: f64, _: f64| fit.resolved(1e-13);
        let bisect = Refine::Bisect {
            min_width: &|_, _| 1e-6,
            keep_at_floor: &|_, _| false,
        };
        let mut opts = Adaptive {
            resolved: &resolved,
            refine: bisect,
            max_pieces: 1000,
        };
        let pieces = fit_adaptive(&f, &[(0.5, 1.0), (1.0, 1.5)], &opts).unwrap();
        assert_eq!((pieces[0].a, pieces.last().unwrap().b), (0.5, 1.5));
        assert!(pieces.windows(2).all(|w| w[0].b == w[1].a));
        assert!(pieces[0].b - pieces[0].a < pieces.last().unwrap().b - pieces.last().unwrap().a);
        for &v in &[0.5, 0.5001, 0.7, 1.5] {
            let p = pieces.iter().find(|p| p.a <= v && v <= p.b).unwrap();
            let y = clenshaw(&p.fit.series[0], to_unit(v, p.a, p.b));
            assert!((y - f(v)[0]).abs() < 1e-11 * f(v)[0], "{v}: {y}");
        }
        opts.max_pieces = 3;
        assert_eq!(
            fit_adaptive(&f, &[(0.5, 1.5)], &opts).unwrap_err(),
            Unresolved::TooManyPieces { max: 3 }
        );
        opts.max_pieces = 1000;
        opts.refine = Refine::Bisect {
            min_width: &|_, _| 0.1,
            keep_at_floor: &|_, _| false,
        };
        assert!(matches!(
            fit_adaptive(&f, &[(0.5, 1.5)], &opts),
            Err(Unresolved::Piece { a: 0.5, .. })
        ));
        opts.refine = Refine::Uniform { max_depth: 12 };
        let pieces = fit_adaptive(&f, &[(0.5, 1.5)], &opts).unwrap();
        assert!(pieces.len().is_power_of_two() && pieces.len() > 8);
        opts.refine = Refine::Uniform { max_depth: 2 };
        assert!(matches!(
            fit_adaptive(&f, &[(0.5, 1.5)], &opts),
            Err(Unresolved::Depth { max_depth: 2, .. })
        ));
        let (dyadic, end) = fit_dyadic(&f, 1e-3, 0.5);
        assert_eq!((dyadic.len(), end), (8, 0.256));
    }
}
