//! Particle estimates of the MFPT behind one switch: the Euler scheme or the
//! exact event-driven sampler ([`crate::sim::Method`]). To add a particle
//! method: a `Method` variant and an arm in [`check`] and [`first_passage`].

use super::{EulerFpt, FptStats, Problem};
use crate::error::{Error, Result};
use crate::parallel::Progress;
use crate::sim::{exact, Method};

/// Validate a particle run before anything runs: `particles >= 2`, then the
/// method's own limits (Euler: step and time cap; exact: time cap).
pub fn check(problem: &Problem, method: Method, particles: u64, t_max: f64) -> Result<()> {
    if particles < 2 {
        return Err(Error::invalid("particles", particles, "particles >= 2"));
    }
    match method {
        Method::Euler { dt } => EulerFpt::new(*problem, dt, t_max).map(|_| ()),
        Method::Exact => exact::check_t_max(t_max).map(|_| ()),
    }
}

/// First-passage statistics of `problem` from `particles` particles of
/// `method` (particle i: stream (seed, i); capped at `t_max`).
pub fn first_passage(
    problem: &Problem,
    method: Method,
    t_max: f64,
    particles: u64,
    seed: u64,
    progress: &dyn Progress,
) -> Result<FptStats> {
    match method {
        Method::Euler { dt } => {
            super::euler_first_passage(problem, dt, t_max, particles, seed, progress)
        }
        Method::Exact => exact::exact_first_passage(problem, t_max, particles, seed, progress),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DragLaw, Params};
    use crate::parallel::NoProgress;

    fn problem() -> Problem {
        let p = Params::new(DragLaw::Tanh, 0.6, 0.5, 0.2, 0.0).unwrap();
        Problem::new(p, -0.249, 0.1).unwrap()
    }

    fn name(e: Error) -> &'static str {
        match e {
            Error::InvalidParameter { name, .. } => name,
            e => panic!("{e}"),
        }
    }

    #[test]
    fn check_particles_first_then_method() {
        let pr = problem();
        let euler = Method::Euler { dt: 1e-3 };
        assert!(check(&pr, euler, 10, 1e4).is_ok());
        assert!(check(&pr, Method::Exact, 10, f64::INFINITY).is_ok());
        assert_eq!(
            name(check(&pr, Method::Exact, 1, -1.0).unwrap_err()),
            "particles"
        );
        assert_eq!(
            name(check(&pr, Method::Exact, 10, 0.0).unwrap_err()),
            "t_max"
        );
        let bad_dt = Method::Euler { dt: -1.0 };
        assert_eq!(name(check(&pr, bad_dt, 10, 1e4).unwrap_err()), "dt");
    }

    #[test]
    fn dispatch_matches_the_samplers() {
        let pr = problem();
        let a = first_passage(&pr, Method::Exact, 1e4, 20, 7, &NoProgress).unwrap();
        let b = exact::exact_first_passage(&pr, 1e4, 20, 7, &NoProgress).unwrap();
        assert_eq!(a.summary(), b.summary());
        let e = Method::Euler { dt: 1e-2 };
        let a = first_passage(&pr, e, 1e4, 20, 7, &NoProgress).unwrap();
        let b = crate::mfpt::euler_first_passage(&pr, 1e-2, 1e4, 20, 7, &NoProgress).unwrap();
        assert_eq!(a.summary(), b.summary());
    }
}
