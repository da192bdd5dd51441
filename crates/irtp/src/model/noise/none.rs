//! No active noise, `none`: one state at level 0 (for thermal noise alone,
//! the Ornstein-Uhlenbeck velocity of linear drag).

use super::spec::bad;
use super::Noise;
use crate::error::Result;

/// The single level 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoNoise;

const USAGE: &str = "none (no parameters)";

impl Noise for NoNoise {
    const NAME: &'static str = "none";

    fn levels(&self) -> Vec<f64> {
        vec![0.0]
    }
    fn generator(&self) -> Vec<Vec<f64>> {
        vec![vec![0.0]]
    }
    fn stationary(&self) -> Result<Vec<f64>> {
        Ok(vec![1.0])
    }
    fn mirror(&self) -> Option<Vec<usize>> {
        Some(vec![0])
    }
    fn example() -> Self {
        NoNoise
    }
    fn usage() -> &'static str {
        USAGE
    }
    fn parse(s: &str, args: Option<&str>) -> Result<Self> {
        match args {
            None => Ok(NoNoise),
            Some(_) => Err(bad(
                s,
                "the bare name 'none' (this kind has no parameters)",
                USAGE,
            )),
        }
    }
    fn write(&self) -> String {
        Self::NAME.to_string()
    }
}
