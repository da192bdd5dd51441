//! Telegraph (dichotomous) noise: two levels, +P and -M, leaving +P at rate
//! k₊ (`rate_plus`) and -M at rate k₋ (`rate_minus`). Symmetric (P = M =
//! Sigma, k₊ = k₋ = lambda) it is the paper's noise, Eq. (6), written
//! `telegraph:sigma=S,lambda=L`; otherwise
//! `telegraph:plus=P,minus=M,rate_plus=KP,rate_minus=KM`.

use super::spec::{self, bad};
use super::Noise;
use crate::error::Result;

/// Levels (+P, -M), rates (k₊, k₋).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Telegraph {
    plus: f64,
    minus: f64,
    rate_plus: f64,
    rate_minus: f64,
}

const USAGE: &str = "telegraph:sigma=S,lambda=L or telegraph:plus=P,minus=M,rate_plus=KP,rate_minus=KM (levels +P > -M, rates > 0)";
const KEYS: [&str; 6] = [
    "sigma",
    "lambda",
    "plus",
    "minus",
    "rate_plus",
    "rate_minus",
];

impl Telegraph {
    /// Levels +P and -M (P + M > 0: +P is the upper level), leaving +P at
    /// rate k₊ > 0 and -M at rate k₋ > 0; every value finite.
    pub fn new(plus: f64, minus: f64, rate_plus: f64, rate_minus: f64) -> Result<Self> {
        let t = Telegraph {
            plus,
            minus,
            rate_plus,
            rate_minus,
        };
        let s = t.write();
        spec::finite(&s, "plus", plus, USAGE)?;
        spec::finite(&s, "minus", minus, USAGE)?;
        if !(plus + minus > 0.0) {
            return Err(bad(
                &s,
                format!(
                    "plus + minus > 0 (the level +P above -M; plus + minus = {})",
                    plus + minus
                ),
                USAGE,
            ));
        }
        spec::positive(&s, "rate_plus", rate_plus, USAGE)?;
        spec::positive(&s, "rate_minus", rate_minus, USAGE)?;
        Ok(t)
    }

    /// The paper's noise ±Sigma flipping at rate lambda (Eq. (6)).
    /// Errors name the keys `sigma` (> 0) and `lambda` (> 0).
    pub fn symmetric(sigma: f64, lambda: f64) -> Result<Self> {
        let s = format!(
            "telegraph:sigma={},lambda={}",
            spec::number(sigma),
            spec::number(lambda)
        );
        spec::positive(&s, "sigma", sigma, USAGE)?;
        spec::positive(&s, "lambda", lambda, USAGE)?;
        Self::new(sigma, sigma, lambda, lambda)
    }

    /// (P, M, k₊, k₋).
    pub fn values(&self) -> (f64, f64, f64, f64) {
        (self.plus, self.minus, self.rate_plus, self.rate_minus)
    }

    fn is_symmetric(&self) -> bool {
        self.plus == self.minus && self.rate_plus == self.rate_minus
    }
}

impl Noise for Telegraph {
    const NAME: &'static str = "telegraph";

    fn levels(&self) -> Vec<f64> {
        vec![self.plus, -self.minus]
    }
    fn generator(&self) -> Vec<Vec<f64>> {
        let (kp, km) = (self.rate_plus, self.rate_minus);
        vec![vec![-kp, kp], vec![km, -km]]
    }
    /// π₊ = k₋/(k₊ + k₋), π₋ = k₊/(k₊ + k₋) (Eq. (N2)).
    fn stationary(&self) -> Result<Vec<f64>> {
        let (kp, km) = (self.rate_plus, self.rate_minus);
        Ok(vec![km / (kp + km), kp / (kp + km)])
    }
    fn mirror(&self) -> Option<Vec<usize>> {
        self.is_symmetric().then(|| vec![1, 0])
    }
    fn symmetric_telegraph(&self) -> Option<(f64, f64)> {
        self.is_symmetric().then_some((self.plus, self.rate_plus))
    }
    fn example() -> Self {
        Telegraph {
            plus: 3.0,
            minus: 1.0,
            rate_plus: 0.5,
            rate_minus: 1.5,
        }
    }
    fn usage() -> &'static str {
        USAGE
    }
    /// Either `sigma` and `lambda` (symmetric) or all four of `plus`,
    /// `minus`, `rate_plus`, `rate_minus`.
    fn parse(s: &str, args: Option<&str>) -> Result<Self> {
        let v = spec::pairs(s, args, &KEYS, USAGE)?;
        let num = |i: usize| -> Result<f64> {
            spec::finite_number(s, KEYS[i], spec::required(s, KEYS[i], v[i], USAGE)?, USAGE)
        };
        let short = v[0].is_some() || v[1].is_some();
        let long = v[2..].iter().any(Option::is_some);
        match (short, long) {
            (true, false) => Self::symmetric(num(0)?, num(1)?),
            (false, true) => Self::new(num(2)?, num(3)?, num(4)?, num(5)?),
            (true, true) => Err(bad(
                s,
                "either sigma, lambda or plus, minus, rate_plus, rate_minus, not both",
                USAGE,
            )),
            (false, false) => Err(bad(s, "the levels and rates", USAGE)),
        }
    }
    fn write(&self) -> String {
        let n = spec::number;
        if self.is_symmetric() {
            format!(
                "telegraph:sigma={},lambda={}",
                n(self.plus),
                n(self.rate_plus)
            )
        } else {
            format!(
                "telegraph:plus={},minus={},rate_plus={},rate_minus={}",
                n(self.plus),
                n(self.minus),
                n(self.rate_plus),
                n(self.rate_minus)
            )
        }
    }
}
