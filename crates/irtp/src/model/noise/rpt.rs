//! Run-pause-tumble noise `rpt:sigma=S,alpha=A,beta=B`: three levels
//! (+S, 0, -S); a run (±S) pauses at rate alpha, a pause (0) resumes at
//! rate beta, in either direction with probability ½ (rate beta/2 each).

use super::spec;
use super::Noise;
use crate::error::Result;

/// Run speed S, pause rate alpha, resume rate beta.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunPauseTumble {
    sigma: f64,
    alpha: f64,
    beta: f64,
}

const USAGE: &str = "rpt:sigma=S,alpha=A,beta=B (S, A, B > 0)";
const KEYS: [&str; 3] = ["sigma", "alpha", "beta"];

impl RunPauseTumble {
    /// Levels ±S and 0, pause rate alpha, resume rate beta; all > 0 and
    /// finite.
    pub fn new(sigma: f64, alpha: f64, beta: f64) -> Result<Self> {
        let r = RunPauseTumble { sigma, alpha, beta };
        let s = r.write();
        spec::positive(&s, "sigma", sigma, USAGE)?;
        spec::positive(&s, "alpha", alpha, USAGE)?;
        spec::positive(&s, "beta", beta, USAGE)?;
        Ok(r)
    }

    /// (S, alpha, beta).
    pub fn values(&self) -> (f64, f64, f64) {
        (self.sigma, self.alpha, self.beta)
    }
}

impl Noise for RunPauseTumble {
    const NAME: &'static str = "rpt";

    /// (+S, 0, -S).
    fn levels(&self) -> Vec<f64> {
        vec![self.sigma, 0.0, -self.sigma]
    }
    fn generator(&self) -> Vec<Vec<f64>> {
        let (a, b) = (self.alpha, self.beta);
        vec![
            vec![-a, a, 0.0],
            vec![0.5 * b, -b, 0.5 * b],
            vec![0.0, a, -a],
        ]
    }
    /// π± = beta / (2 (alpha + beta)), π₀ = alpha / (alpha + beta)
    /// (balance of each run state: π± alpha = π₀ beta/2).
    fn stationary(&self) -> Result<Vec<f64>> {
        let (a, b) = (self.alpha, self.beta);
        let run = 0.5 * b / (a + b);
        Ok(vec![run, a / (a + b), run])
    }
    fn mirror(&self) -> Option<Vec<usize>> {
        Some(vec![2, 1, 0])
    }
    fn example() -> Self {
        RunPauseTumble {
            sigma: 3.0,
            alpha: 0.5,
            beta: 2.0,
        }
    }
    fn usage() -> &'static str {
        USAGE
    }
    fn parse(s: &str, args: Option<&str>) -> Result<Self> {
        let v = spec::pairs(s, args, &KEYS, USAGE)?;
        let mut x = [0.0; 3];
        for (i, key) in KEYS.iter().enumerate() {
            x[i] = spec::finite_number(s, key, spec::required(s, key, v[i], USAGE)?, USAGE)?;
        }
        Self::new(x[0], x[1], x[2])
    }
    fn write(&self) -> String {
        let n = spec::number;
        format!(
            "rpt:sigma={},alpha={},beta={}",
            n(self.sigma),
            n(self.alpha),
            n(self.beta)
        )
    }
}
