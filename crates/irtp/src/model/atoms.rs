//! Point masses (atoms) of the stationary velocity law.
//!
//! Without thermal noise a particle put at a velocity it cannot leave
//! stays there: a reset to v_r in a noise state s whose fixed point
//! g⁻¹(a_s) is v_r (the pause of run-pause-tumble noise at v_r = 0) holds
//! the velocity at v_r until the state changes, and a refractory period
//! holds it at v_r until the period ends. The stationary law then has a
//! point mass at v_r beside its density: every method reports it as an
//! atom (velocity, mass, error) and its density without it.

use super::reset::Reset;
use super::{Drag, Params};
use serde::{Deserialize, Serialize};

/// A point mass of a stationary velocity law.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct VelocityAtom {
    /// Where it sits.
    pub v: f64,
    /// Its probability.
    pub mass: f64,
    /// Error estimate of `mass` (a standard error for a sampler, a mesh
    /// error estimate for a solver).
    pub err: f64,
}

/// The noise states s that hold a point mass at the reset velocity v_r: at
/// T = 0, with a point target v_r and resets, those whose fixed point
/// g⁻¹(a_s) is exactly v_r (compared as the N-state mesh merges its
/// breakpoints). Empty for the paper's noise (its fixed points are the
/// interval's edges).
pub fn reset_atom_states(p: &Params) -> Vec<usize> {
    let resets = p.rate() > 0.0 || p.schedule().periodic.is_some() || p.schedule().clock.is_some();
    let (Some(vr), true) = (p.reset().point(), resets) else {
        return Vec::new();
    };
    match (p.noise(), p.chain()) {
        (Some(_), Ok(c)) if c.temperature == 0.0 => c
            .levels
            .iter()
            .enumerate()
            .filter(|(_, &a)| p.drag().inverse(a) == vr)
            .map(|(s, _)| s)
            .collect(),
        _ => Vec::new(),
    }
}

/// The velocities at which the stationary law has a point mass: v_r when
/// a noise state holds it there ([`reset_atom_states`]) or a refractory
/// period holds it (a point target); empty otherwise.
pub fn atom_velocities(p: &Params) -> Vec<f64> {
    let held = p.schedule().refractory.is_some();
    match p.reset().point() {
        Some(vr) if held || !reset_atom_states(p).is_empty() => vec![vr],
        _ => Vec::new(),
    }
}

/// The states that hold a point mass of the time-dependent law started at
/// v = 0 (`fp transient`, Eq. (N52)), as (velocity, state): at T = 0 a
/// state whose fixed point is v_r holds the resets there
/// ([`reset_atom_states`]); one whose fixed point is the start v = 0 holds
/// its share π_s of the start until it leaves the state or is reset.
/// Empty for the paper's noise and at T > 0.
pub fn transient_atom_states(p: &Params) -> Vec<(f64, usize)> {
    let resets = reset_atom_states(p);
    match (p.noise(), p.chain(), p.reset().point()) {
        (Some(_), Ok(c), vr) if c.temperature == 0.0 => c
            .levels
            .iter()
            .enumerate()
            .filter_map(|(s, &a)| match vr {
                Some(v) if resets.contains(&s) => Some((v, s)),
                _ if p.drag().inverse(a) == 0.0 => Some((0.0, s)),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    }
}
