//! Any finite-state Markov noise,
//! `states:levels=[a1,...,aN],rates=[[q11,...,q1N],...,[qN1,...,qNN]]`:
//! N levels and the generator Q (Q_ij ≥ 0 the rate of i → j for i ≠ j,
//! each row summing to 0 within [`super::chain::ROW_SUM_TOL`] of its
//! absolute sum), 2 ≤ N ≤ [`super::chain::MAX_STATES`], irreducible.
//! Levels may repeat (a hidden state, e.g. an Erlang-distributed run).
//!
//! The diagonal written is kept for the spec (so it round-trips); the
//! generator the methods use has its diagonal recomputed as minus the sum
//! of the row's other rates, so its rows sum to 0 to rounding.

use super::spec::{self, bad};
use super::{chain, Noise};
use crate::error::Result;

/// Levels and the generator as written.
#[derive(Clone, Debug, PartialEq)]
pub struct States {
    levels: Vec<f64>,
    rates: Vec<Vec<f64>>,
}

const USAGE: &str =
    "states:levels=[A1,..,AN],rates=[[Q11,..,Q1N],..,[QN1,..,QNN]] (a generator, 2 <= N <= 32)";
const KEYS: [&str; 2] = ["levels", "rates"];

impl States {
    /// Validated (see the module doc); errors name `noise`.
    pub fn new(levels: Vec<f64>, rates: Vec<Vec<f64>>) -> Result<Self> {
        let s = States { levels, rates };
        let spec = s.write();
        if s.levels.len() < 2 {
            return Err(bad(
                &spec,
                format!("at least 2 states (got {}; `none` has one)", s.levels.len()),
                USAGE,
            ));
        }
        chain::validate(&s.levels, &s.rates, &spec, USAGE)?;
        Ok(s)
    }
}

impl Noise for States {
    const NAME: &'static str = "states";

    fn levels(&self) -> Vec<f64> {
        self.levels.clone()
    }
    fn generator(&self) -> Vec<Vec<f64>> {
        let mut q = self.rates.clone();
        for (i, row) in q.iter_mut().enumerate() {
            let off: f64 = row
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, x)| x)
                .sum();
            row[i] = -off;
        }
        q
    }
    fn example() -> Self {
        States {
            levels: vec![2.0, 0.5, -1.0],
            rates: vec![
                vec![-1.0, 1.0, 0.0],
                vec![0.5, -1.0, 0.5],
                vec![1.0, 0.0, -1.0],
            ],
        }
    }
    fn usage() -> &'static str {
        USAGE
    }
    fn parse(s: &str, args: Option<&str>) -> Result<Self> {
        let v = spec::pairs(s, args, &KEYS, USAGE)?;
        let levels = spec::number_list(
            s,
            "levels",
            spec::required(s, "levels", v[0], USAGE)?,
            USAGE,
        )?;
        let rates =
            spec::number_matrix(s, "rates", spec::required(s, "rates", v[1], USAGE)?, USAGE)?;
        Self::new(levels, rates)
    }
    fn write(&self) -> String {
        let rows: Vec<String> = self.rates.iter().map(|r| spec::list(r)).collect();
        format!(
            "states:levels={},rates=[{}]",
            spec::list(&self.levels),
            rows.join(",")
        )
    }
}
