//! The numerics of a finite-state Markov chain with generator Q: its
//! validation, stationary law (Eq. (N2)), mirror symmetry and the Poisson
//! equation Q β = b (Eq. (N7)). The chains are small (at most
//! [`MAX_STATES`] states), so every solve is a dense LU with partial
//! pivoting on [`crate::numerics::band::Band`] with full bandwidth.

use crate::error::{Error, Result};
use crate::numerics::band::Band;

/// The most states a noise may have.
pub const MAX_STATES: usize = 32;

/// Relative tolerance of a generator's row sums: |Σ_s' Q_ss'| must be at
/// most this times Σ_s' |Q_ss'| (rates written in decimal, `0.1`, `0.2`,
/// `-0.3`, sum to ~1e-17 of their size).
pub const ROW_SUM_TOL: f64 = 1e-12;

/// Check that (levels, q) is an irreducible generator: 1 ≤ N ≤
/// [`MAX_STATES`] states, Q N×N, every entry finite, Q_ss' ≥ 0 off the
/// diagonal, rows summing to 0 within [`ROW_SUM_TOL`], and every state
/// reaching every other (one stationary law, positive everywhere). Errors
/// name `noise`, with `spec` and `usage` for the message.
pub fn validate(levels: &[f64], q: &[Vec<f64>], spec: &str, usage: &str) -> Result<()> {
    let bad = |what: String| super::spec::bad(spec, what, usage);
    let n = levels.len();
    if n > MAX_STATES {
        return Err(bad(format!("at most {MAX_STATES} states, not {n}")));
    }
    if q.len() != n || q.iter().any(|row| row.len() != n) {
        return Err(bad(format!(
            "a {n}×{n} generator (one row of rates per level)"
        )));
    }
    if levels
        .iter()
        .chain(q.iter().flatten())
        .any(|x| !x.is_finite())
    {
        return Err(bad("finite levels and rates".into()));
    }
    for (i, row) in q.iter().enumerate() {
        if let Some(j) = (0..n).find(|&j| j != i && !(row[j] >= 0.0)) {
            return Err(bad(format!(
                "rates >= 0 off the diagonal (rate {i}->{j} = {})",
                row[j]
            )));
        }
        let (sum, size) = (
            row.iter().sum::<f64>(),
            row.iter().map(|x| x.abs()).sum::<f64>(),
        );
        if !(sum.abs() <= ROW_SUM_TOL * size) {
            return Err(bad(format!(
                "generator rows summing to 0 (row {i} sums to {})",
                crate::error::short(sum)
            )));
        }
    }
    if let Some((i, j)) = unreachable_pair(q) {
        return Err(bad(format!(
            "an irreducible generator (state {j} is not reached from state {i})"
        )));
    }
    Ok(())
}

/// A pair (i, j) with j not reachable from i through positive rates, or
/// None when the chain is irreducible.
fn unreachable_pair(q: &[Vec<f64>]) -> Option<(usize, usize)> {
    let n = q.len();
    let mut reach: Vec<Vec<bool>> = (0..n)
        .map(|i| (0..n).map(|j| i == j || q[i][j] > 0.0).collect())
        .collect();
    for k in 0..n {
        let via = reach[k].clone();
        for row in reach.iter_mut().filter(|row| row[k]) {
            row.iter_mut().zip(&via).for_each(|(x, y)| *x |= *y);
        }
    }
    (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .find(|&(i, j)| !reach[i][j])
}

/// Solve the dense system a x = b (LU with partial pivoting); a zero or
/// non-finite pivot is an [`Error::Numerical`] of `method`.
pub fn solve(a: &[Vec<f64>], b: &[f64], method: &'static str) -> Result<Vec<f64>> {
    let n = b.len();
    let k = n.saturating_sub(1);
    let mut m = Band::new(n, k, k);
    for (i, row) in a.iter().enumerate() {
        for (j, &x) in row.iter().enumerate() {
            m.set(i, j, x);
        }
    }
    m.factor()
        .map_err(|e| e.into_error(method, format!("singular {n}×{n} system ({e})")))?;
    let mut x = b.to_vec();
    m.solve(&mut x);
    if x.iter().any(|v| !v.is_finite()) {
        return Err(Error::Numerical {
            method,
            reason: "non-finite solution".into(),
        });
    }
    Ok(x)
}

/// max_s |Σ_s' Q_ss'| relative scale of Q: max |Q_ss'|.
fn scale(q: &[Vec<f64>]) -> f64 {
    q.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The stationary law π: Qᵀ π = 0 with Σ π = 1 (Eq. (N2)), from Qᵀ with its
/// last row replaced by ones (nonsingular exactly when the stationary law
/// is unique). Checked: π ≥ 0 and |Qᵀ π| ≤ 1e-12 max |Q| componentwise;
/// tiny negative rounding (above -1e-14) is set to 0.
pub fn stationary(q: &[Vec<f64>]) -> Result<Vec<f64>> {
    const METHOD: &str = "noise stationary law";
    let n = q.len();
    let mut a: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| q[j][i]).collect()).collect();
    let mut b = vec![0.0; n];
    a[n - 1] = vec![1.0; n];
    b[n - 1] = 1.0;
    let mut pi = solve(&a, &b, METHOD)?;
    let tol = 1e-12 * scale(q);
    let worst = (0..n)
        .map(|i| (0..n).map(|j| q[j][i] * pi[j]).sum::<f64>().abs())
        .fold(0.0f64, f64::max);
    if !(worst <= tol) || pi.iter().any(|p| !(*p >= -1e-14)) {
        return Err(Error::Numerical {
            method: METHOD,
            reason: format!(
                "the solution is not a probability law (residual {worst:e}, pi = {pi:?})"
            ),
        });
    }
    pi.iter_mut().for_each(|p| *p = p.max(0.0));
    Ok(pi)
}

/// The mirror map of (levels, q): a permutation m with a_{m(s)} = -a_s and
/// Q_{m(s) m(s')} = Q_ss' exactly, found by backtracking over the states of
/// opposite level; None if there is none.
pub fn mirror(levels: &[f64], q: &[Vec<f64>]) -> Option<Vec<usize>> {
    let mut m = Vec::with_capacity(levels.len());
    let mut used = vec![false; levels.len()];
    extend_mirror(levels, q, &mut m, &mut used).then_some(m)
}

/// Extend the partial map `m` (states 0..m.len() mapped) to a full mirror
/// map; false if no extension exists.
fn extend_mirror(levels: &[f64], q: &[Vec<f64>], m: &mut Vec<usize>, used: &mut [bool]) -> bool {
    let s = m.len();
    if s == levels.len() {
        return true;
    }
    for t in 0..levels.len() {
        let consistent = !used[t]
            && levels[t] == -levels[s]
            && q[t][t] == q[s][s]
            && (0..s).all(|u| q[t][m[u]] == q[s][u] && q[m[u]][t] == q[u][s]);
        if consistent {
            m.push(t);
            used[t] = true;
            if extend_mirror(levels, q, m, used) {
                return true;
            }
            m.pop();
            used[t] = false;
        }
    }
    false
}

/// The solution β of the Poisson equation Q β = b with π·β = 0 (needs
/// π·b = 0, checked to 1e-12 of the scale of b): β = -(1 πᵀ - Q)⁻¹ b, since
/// (1 πᵀ - Q) β = -b gives π·β = -π·b = 0 and then Q β = b (Eq. (N7)).
pub fn poisson(q: &[Vec<f64>], pi: &[f64], b: &[f64]) -> Result<Vec<f64>> {
    const METHOD: &str = "noise Poisson equation";
    let n = q.len();
    let pb: f64 = pi.iter().zip(b).map(|(p, x)| p * x).sum();
    let size = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if !(pb.abs() <= 1e-12 * size.max(f64::MIN_POSITIVE)) && pb != 0.0 {
        return Err(Error::Numerical {
            method: METHOD,
            reason: format!("the right side has stationary mean {pb:e}, not 0"),
        });
    }
    let a: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| pi[j] - q[i][j]).collect())
        .collect();
    let minus_b: Vec<f64> = b.iter().map(|x| -x).collect();
    solve(&a, &minus_b, METHOD)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rpt() -> (Vec<f64>, Vec<Vec<f64>>) {
        let q = vec![
            vec![-1.0, 1.0, 0.0],
            vec![0.5, -1.0, 0.5],
            vec![0.0, 1.0, -1.0],
        ];
        (vec![2.0, 0.0, -2.0], q)
    }

    #[test]
    fn stationary_and_mirror_of_run_pause_tumble() {
        let (levels, q) = rpt();
        let pi = stationary(&q).unwrap();
        for (p, e) in pi.iter().zip([0.25, 0.5, 0.25]) {
            assert!((p - e).abs() < 1e-15, "{pi:?}");
        }
        assert_eq!(mirror(&levels, &q), Some(vec![2, 1, 0]));
        let skew = vec![2.0, 0.0, -1.0];
        assert_eq!(mirror(&skew, &q), None);
        validate(&levels, &q, "s", "u").unwrap();
    }

    #[test]
    fn poisson_solves_and_centres() {
        let (levels, q) = rpt();
        let pi = stationary(&q).unwrap();
        let beta = poisson(&q, &pi, &levels).unwrap();
        for i in 0..3 {
            let qb: f64 = (0..3).map(|j| q[i][j] * beta[j]).sum();
            assert!((qb - levels[i]).abs() < 1e-14);
        }
        let mean: f64 = pi.iter().zip(&beta).map(|(p, b)| p * b).sum();
        assert!(mean.abs() < 1e-15);
        assert!(poisson(&q, &pi, &[1.0, 1.0, 1.0]).is_err());
    }

    #[test]
    fn rejects_reducible_chains() {
        let q = vec![vec![-1.0, 1.0], vec![0.0, 0.0]];
        let e = validate(&[1.0, -1.0], &q, "s", "u").unwrap_err();
        assert!(e.to_string().contains("irreducible"), "{e}");
    }
}

/// A noise model as the engines run it (Eq. (N1)): state s has level a_s,
/// leaves at rate q_s = -Q_ss to s' with probability Q_ss'/q_s; π is the
/// stationary law (Eq. (N2)); T the temperature of the thermal noise.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    /// Levels a_s.
    pub levels: Vec<f64>,
    /// Generator Q (rows summing to 0).
    pub q: Vec<Vec<f64>>,
    /// Exit rates q_s = Σ_{s'≠s} Q_ss'.
    pub exit: Vec<f64>,
    /// Stationary law π.
    pub pi: Vec<f64>,
    /// Temperature T ≥ 0.
    pub temperature: f64,
}

impl Chain {
    /// The chain of a noise model (its stationary law checked).
    pub fn new(m: &super::NoiseModel) -> Result<Self> {
        let q = m.generator();
        let exit = q
            .iter()
            .enumerate()
            .map(|(s, row)| {
                row.iter()
                    .enumerate()
                    .filter(|&(j, _)| j != s)
                    .map(|(_, r)| r)
                    .sum()
            })
            .collect();
        Ok(Chain {
            levels: m.levels(),
            pi: m.stationary()?,
            q,
            exit,
            temperature: m.temperature(),
        })
    }

    /// Number of states N.
    pub fn states(&self) -> usize {
        self.levels.len()
    }

    /// The state a jump from s goes to, given u uniform on [0, q_s): the
    /// first s' ≠ s whose cumulative rate Σ_{j ≤ s', j ≠ s} Q_sj exceeds u
    /// (the same uniform that chose a jump over a reset can be reused,
    /// scaled). For two states it is the other state whatever u.
    #[inline]
    pub fn jump(&self, s: usize, u: f64) -> usize {
        let row = &self.q[s];
        let mut acc = 0.0;
        let mut last = s;
        for (j, &r) in row.iter().enumerate() {
            if j == s || !(r > 0.0) {
                continue;
            }
            acc += r;
            last = j;
            if u < acc {
                return j;
            }
        }
        last
    }

    /// A state drawn from π given u uniform on [0, 1).
    #[inline]
    pub fn draw_stationary(&self, u: f64) -> usize {
        let mut acc = 0.0;
        for (j, &p) in self.pi.iter().enumerate() {
            acc += p;
            if u < acc {
                return j;
            }
        }
        self.pi.len() - 1
    }
}

#[cfg(test)]
mod chain_tests {
    use super::*;

    #[test]
    fn jumps_follow_the_rates() {
        let m = super::super::NoiseModel::parse("rpt:sigma=1,alpha=2,beta=4", 0.0).unwrap();
        let c = Chain::new(&m).unwrap();
        assert_eq!(c.states(), 3);
        // Each state's jump targets in proportion to its rates.
        for s in 0..3 {
            let n = 100_000;
            let mut hits = [0usize; 3];
            for k in 0..n {
                let u = (k as f64 + 0.5) / n as f64 * c.exit[s];
                hits[c.jump(s, u)] += 1;
            }
            assert_eq!(hits[s], 0);
            for j in (0..3).filter(|&j| j != s) {
                let want = c.q[s][j] / c.exit[s];
                assert!((hits[j] as f64 / n as f64 - want).abs() < 1e-4, "{s}->{j}");
            }
        }
        let pi_sum: f64 = c.pi.iter().sum();
        assert!((pi_sum - 1.0).abs() < 1e-14);
        assert_eq!(c.draw_stationary(0.0), 0);
        assert_eq!(c.draw_stationary(1.0 - 1e-16), 2);
    }
}
