//! `exp:rate=R`: the Poisson clock written as a renewal clock,
//! W(t) = e^{-Rt}. Drawn as Exp1 × (1/R) (the ziggurat of
//! `rand_distr::Exp1`), the same arithmetic as [`super::GammaClock`] with
//! k = 1 and theta = 1/R, so the two give the same bits.

use super::{bad, check_mean, keyed, Law};
use crate::error::Result;
use crate::model::drag::spec::number;
use rand::Rng;

/// Exponential waiting times of rate R.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExpClock {
    /// The rate R > 0.
    pub rate: f64,
}

impl Law for ExpClock {
    const KIND: &'static str = "exp";
    const USAGE: &'static str = "exp:rate=R (R > 0)";
    fn parse(args: &str, spec: &str) -> Result<Self> {
        let v = keyed(args, spec, &["rate"], Self::USAGE)?;
        if !(v[0] > 0.0) {
            return Err(bad(spec, "rate > 0", Self::USAGE));
        }
        Ok(ExpClock { rate: v[0] })
    }
    fn spec(&self) -> String {
        format!("exp:rate={}", number(self.rate))
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        rng.sample::<f64, _>(rand_distr::Exp1) * (1.0 / self.rate)
    }
    fn survival(&self, t: f64) -> f64 {
        (-self.rate * t.max(0.0)).exp()
    }
    fn cdf(&self, t: f64) -> f64 {
        -(-self.rate * t.max(0.0)).exp_m1()
    }
    fn density(&self, t: f64) -> Option<f64> {
        Some(if t < 0.0 {
            0.0
        } else {
            self.rate * (-self.rate * t).exp()
        })
    }
    fn mean(&self) -> f64 {
        1.0 / self.rate
    }
    fn with_mean(&self, mean: f64) -> Result<Self> {
        Ok(ExpClock {
            rate: 1.0 / check_mean(mean)?,
        })
    }
    fn tail_integral(&self, t: f64) -> f64 {
        self.survival(t) / self.rate
    }
    fn survival_integral(&self, a: f64, b: f64) -> f64 {
        self.survival(a) * -(-self.rate * (b - a)).exp_m1() / self.rate
    }
    /// Closed form: on step n, ∫ rho (1 - s) = e_n (i0 - i1) and
    /// ∫ rho s = e_n i1 with e_n = e^{-R n dt}, z = R dt, i0 = 1 - e^{-z},
    /// i1 = i0/z - e^{-z}; W = rho / R.
    fn renewal_weights(&self, t_max: f64, steps: usize) -> (Vec<f64>, Vec<f64>, f64) {
        let rate = self.rate;
        let dt = t_max / steps as f64;
        let z = rate * dt;
        let i0 = -(-z).exp_m1();
        let i1 = i0 / z - (-z).exp();
        let mut rq = vec![0.0; steps + 1];
        for n in 0..steps {
            let e = (-rate * n as f64 * dt).exp();
            rq[n] += e * (i0 - i1);
            rq[n + 1] += e * i1;
        }
        let wq = rq.iter().map(|x| x / rate).collect();
        (wq, rq, (-rate * t_max).exp())
    }
    fn horizon(&self, tail: f64) -> f64 {
        (1.0 / tail).ln() / self.rate
    }
}
