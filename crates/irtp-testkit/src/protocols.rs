//! The protocol test models of the cross-method suite
//! (`crates/irtp/tests/it/protocol_conformance.rs`): the schedule modifiers
//! (periodic resetting, renewal clocks, exponential and fixed refractory
//! periods, position resetting) and random reset targets, crossed with the
//! paper's telegraph noise, finite-state noise models and thermal noise,
//! each with the quantity it is checked on. A case lists the model once;
//! which methods run it is `irtp::capability`'s answer, not this file's.

use irtp::model::noise::NoiseModel;
use irtp::model::reset::{NoiseAtReset, Schedule, Target};
use irtp::model::Reset;
use irtp::search::PositionTarget;
use irtp::{DragLaw, Params};

/// The noise of a case.
#[derive(Clone, Copy, Debug)]
pub enum Noise {
    /// The paper's telegraph noise ±Sigma flipping at rate lambda.
    Paper { sigma: f64, lambda: f64 },
    /// A noise spec (`rpt:..`, `telegraph:..`, `none`) at temperature T.
    Model {
        spec: &'static str,
        temperature: f64,
    },
}

/// The reset target (the rule's velocity law).
#[derive(Clone, Copy, Debug)]
pub enum Goal {
    /// v_r.
    Point(f64),
    /// A Gaussian (mean, std), cut to the velocity interval.
    Gauss(f64, f64),
    /// Uniform on (a, b).
    Uniform(f64, f64),
}

/// The modifiers, as their flags spell them.
#[derive(Clone, Copy, Debug, Default)]
pub struct Protocol {
    /// `--reset-period`.
    pub period: Option<f64>,
    /// `--reset-clock`.
    pub clock: Option<&'static str>,
    /// `--reset-position`.
    pub position: Option<f64>,
    /// `--refractory`.
    pub refractory: Option<&'static str>,
}

/// What the methods of a case are held to.
#[derive(Clone, Copy, Debug)]
pub enum Quantity {
    /// Stationary <v>, <v²> (time average over [burn_in, t_max] for the
    /// samplers), with position resetting <x>, <x²> at t_max, and D_eff
    /// (the samplers' Eq. (36) fit over the window) where `d_eff`.
    Stationary {
        t_max: f64,
        burn_in: f64,
        d_eff: bool,
    },
    /// <v>(t), <v²>(t) from v = x = 0 at `times` (none a multiple of a
    /// period: the closed forms differ in the side they take there).
    Transient { times: [f64; 3] },
    /// Mean first passage of the velocity v0 → vt.
    Passage { v0: f64, vt: f64 },
    /// Mean first passage of the position from (x0, v0) to `target`.
    Search {
        x0: f64,
        v0: f64,
        target: PositionTarget,
    },
}

/// One protocol test model.
#[derive(Clone, Copy, Debug)]
pub struct ProtocolCase {
    /// Short name for messages.
    pub name: &'static str,
    /// The `--drag` spec.
    pub drag: &'static str,
    /// The noise.
    pub noise: Noise,
    /// The Poisson rate (0 with a periodic or renewal clock).
    pub rate: f64,
    /// The reset target.
    pub goal: Goal,
    /// Whether a reset re-draws the noise state.
    pub redrawn: bool,
    /// The modifiers.
    pub protocol: Protocol,
    /// The quantity compared.
    pub quantity: Quantity,
    /// In the fast tier.
    pub fast: bool,
    /// Why fewer than two methods run it (None: at least two must).
    pub single: Option<&'static str>,
}

impl ProtocolCase {
    /// The validated parameters: noise, then target, then modifiers.
    pub fn params(&self) -> Params {
        let drag: DragLaw = self.drag.parse().expect("drag spec");
        let vr = match self.goal {
            Goal::Point(v) => v,
            _ => 0.0,
        };
        let base = match self.noise {
            Noise::Paper { sigma, lambda } => Params::new(drag, sigma, lambda, self.rate, vr),
            Noise::Model { spec, temperature } => {
                let m = NoiseModel::parse(spec, temperature).expect("noise spec");
                Params::with_noise(drag, m, self.rate, vr)
            }
        }
        .unwrap_or_else(|e| panic!("{}: {e}", self.name));
        let target = match self.goal {
            Goal::Point(v) => Target::point(v),
            Goal::Gauss(m, s) => Target::gauss(m, s),
            Goal::Uniform(a, b) => Target::uniform(a, b),
        };
        let rule = match self.redrawn {
            true => NoiseAtReset::Redrawn,
            false => NoiseAtReset::Kept,
        };
        let pr = &self.protocol;
        let schedule = Schedule::parse(pr.period, pr.position, pr.refractory)
            .and_then(|s| s.with_clock(pr.clock))
            .unwrap_or_else(|e| panic!("{}: {e}", self.name));
        base.with_reset(target, rule)
            .and_then(|p| p.with_schedule(schedule))
            .unwrap_or_else(|e| panic!("{}: {e}", self.name))
    }

    /// Whether the drag is linear (the closed forms of [`closed_form`]).
    pub fn linear(&self) -> bool {
        self.drag == "linear"
    }

    /// The temperature of the thermal noise (0 without).
    pub fn temperature(&self) -> f64 {
        match self.noise {
            Noise::Model { temperature, .. } => temperature,
            Noise::Paper { .. } => 0.0,
        }
    }
}

/// Run-pause-tumble: ±3 → 0 at rate 1, 0 → ±3 at rate 2 each.
pub const RPT: &str = "rpt:sigma=3,alpha=1,beta=2";
/// Run-pause-tumble at ±1 (the search: slower, so targets are cheap).
pub const RPT1: &str = "rpt:sigma=1,alpha=1,beta=2";
/// Asymmetric telegraph noise (<a> ≠ 0).
pub const ASYM: &str = "telegraph:plus=1.5,minus=0.75,rate_plus=0.8,rate_minus=0.4";

const PAPER: Noise = Noise::Paper {
    sigma: 1.0,
    lambda: 0.5,
};

const fn model(spec: &'static str, temperature: f64) -> Noise {
    Noise::Model { spec, temperature }
}

const NONE: Protocol = Protocol {
    period: None,
    clock: None,
    position: None,
    refractory: None,
};

const STATIONARY: Quantity = Quantity::Stationary {
    t_max: 16.0,
    burn_in: 6.0,
    d_eff: false,
};

/// The velocity passage of every passage case, in units of v_u.
pub const PASSAGE: (f64, f64) = (-0.2, 0.4);

/// A case with the defaults: point target 0.1, noise kept, fast tier off,
/// at least two methods.
const fn case(
    name: &'static str,
    drag: &'static str,
    noise: Noise,
    rate: f64,
    protocol: Protocol,
    quantity: Quantity,
) -> ProtocolCase {
    ProtocolCase {
        name,
        drag,
        noise,
        rate,
        goal: Goal::Point(0.1),
        redrawn: false,
        protocol,
        quantity,
        fast: false,
        single: None,
    }
}

impl ProtocolCase {
    const fn fast(self) -> Self {
        ProtocolCase { fast: true, ..self }
    }
    const fn goal(self, goal: Goal, redrawn: bool) -> Self {
        ProtocolCase {
            goal,
            redrawn,
            ..self
        }
    }
    const fn single(self, why: &'static str) -> Self {
        ProtocolCase {
            single: Some(why),
            ..self
        }
    }
}

const fn refractory(spec: &'static str) -> Protocol {
    Protocol {
        refractory: Some(spec),
        ..NONE
    }
}

const fn periodic(period: f64, position: Option<f64>) -> Protocol {
    Protocol {
        period: Some(period),
        position,
        ..NONE
    }
}

const fn passage(vu: f64) -> Quantity {
    Quantity::Passage {
        v0: PASSAGE.0 * vu,
        vt: PASSAGE.1 * vu,
    }
}

/// v_u of tan drag at Sigma = 1 (atan 1).
const TAN_VU: f64 = std::f64::consts::FRAC_PI_4;

/// The suite: stationary moments, transient moments under periodic
/// resetting, the velocity's mean first passage and the search, each under
/// modifiers and noises the methods run differently.
pub const PROTOCOL_CASES: [ProtocolCase; 17] = [
    case(
        "tan-refr-exp-deff",
        "tan",
        PAPER,
        1.5,
        refractory("exp:mean=0.3"),
        Quantity::Stationary {
            t_max: 40.0,
            burn_in: 10.0,
            d_eff: true,
        },
    )
    .goal(Goal::Point(0.0), false),
    case(
        "linear-refr-exp-gauss-redrawn-deff",
        "linear",
        PAPER,
        1.0,
        refractory("exp:mean=0.5"),
        Quantity::Stationary {
            t_max: 40.0,
            burn_in: 10.0,
            d_eff: true,
        },
    )
    .goal(Goal::Gauss(0.0, 0.3), true)
    .fast(),
    case(
        "linear-position",
        "linear",
        Noise::Paper {
            sigma: 1.3,
            lambda: 0.7,
        },
        1.5,
        Protocol {
            position: Some(0.5),
            ..NONE
        },
        STATIONARY,
    )
    .goal(Goal::Point(0.2), false)
    .fast(),
    case(
        "tan-refr-fixed-uniform-redrawn",
        "tan",
        PAPER,
        1.0,
        refractory("fixed:t=0.3"),
        STATIONARY,
    )
    .goal(Goal::Uniform(-0.3, 0.2), true),
    case(
        "tan-rpt-refr-exp",
        "tan",
        model(RPT, 0.0),
        1.0,
        refractory("exp:mean=0.5"),
        STATIONARY,
    )
    .fast(),
    case(
        "tan-asym-position",
        "tan",
        model(ASYM, 0.0),
        1.0,
        Protocol {
            position: Some(0.0),
            ..NONE
        },
        STATIONARY,
    ),
    case(
        "linear-thermal-refr-exp",
        "linear",
        model("telegraph:sigma=1,lambda=0.5", 0.2),
        1.0,
        refractory("exp:mean=0.5"),
        STATIONARY,
    )
    .fast(),
    case(
        "linear-periodic",
        "linear",
        PAPER,
        0.0,
        periodic(1.0, None),
        Quantity::Transient {
            times: [0.5, 1.5, 2.5],
        },
    )
    .goal(Goal::Point(0.2), false)
    .fast(),
    case(
        "tan-periodic-refr-exp",
        "tan",
        PAPER,
        0.0,
        Protocol {
            refractory: Some("exp:mean=0.2"),
            ..periodic(1.0, None)
        },
        Quantity::Transient {
            times: [0.5, 1.5, 2.5],
        },
    ),
    case(
        "tan-refr-exp-passage",
        "tan",
        PAPER,
        1.5,
        refractory("exp:mean=0.3"),
        passage(TAN_VU),
    )
    .fast(),
    case(
        "tan-position-passage",
        "tan",
        PAPER,
        1.5,
        Protocol {
            position: Some(0.5),
            ..NONE
        },
        passage(TAN_VU),
    ),
    case(
        "tan-periodic-passage",
        "tan",
        PAPER,
        0.0,
        periodic(1.0, None),
        passage(TAN_VU),
    ),
    case(
        "tanh-gamma-refr-fixed-passage",
        "tanh",
        Noise::Paper {
            sigma: 0.6,
            lambda: 0.5,
        },
        0.0,
        Protocol {
            clock: Some("gamma:k=2,theta=0.5"),
            refractory: Some("fixed:t=0.2"),
            ..NONE
        },
        // v_u = atanh 0.6 = ln 2.
        passage(std::f64::consts::LN_2),
    ),
    case(
        "tan-rpt-periodic-passage",
        "tan",
        model(RPT, 0.0),
        0.0,
        periodic(1.0, None),
        // v_u = atan 3.
        passage(1.249_045_772_398_254_4),
    ),
    case(
        "tan-thermal-refr-exp-passage",
        "tan",
        model("telegraph:sigma=1,lambda=0.5", 0.2),
        1.5,
        refractory("exp:mean=0.3"),
        passage(TAN_VU),
    ),
    case(
        "linear-search-poisson",
        "linear",
        PAPER,
        0.5,
        Protocol {
            position: Some(0.0),
            ..NONE
        },
        Quantity::Search {
            x0: 0.0,
            v0: 0.0,
            target: PositionTarget::Interval(-0.8, 0.6),
        },
    )
    .goal(Goal::Point(0.0), false)
    .fast(),
    case(
        "linear-rpt-search-periodic",
        "linear",
        model(RPT1, 0.0),
        0.0,
        periodic(1.5, Some(0.0)),
        Quantity::Search {
            x0: 0.0,
            v0: 0.0,
            target: PositionTarget::Interval(-0.6, 0.5),
        },
    )
    .goal(Goal::Point(0.0), false),
];

/// Stationary linear-drag closed forms of this file's cases, from
/// [`crate::linear_protocols`] (paper noise; the thermal case adds the
/// term below): (<v>, <v²>, (<x>, <x²>) with position resetting), None
/// where the case has none.
pub type Closed = (f64, f64, Option<(f64, f64)>);

/// The closed form of `c`'s stationary moments where
/// [`crate::linear_protocols`] has one: linear drag, the telegraph noise
/// (thermal noise of temperature T added: it adds 2T to d<v²>/dt in the
/// flowing phase only, so 2 T p_F / (2 + r) to <v²>; the held phase keeps
/// v = v_r), Poisson resetting with position resetting or an exponential
/// refractory period.
pub fn closed_form(c: &ProtocolCase) -> Option<Closed> {
    let (sigma, lambda) = match c.noise {
        Noise::Paper { sigma, lambda } => (sigma, lambda),
        Noise::Model {
            spec: "telegraph:sigma=1,lambda=0.5",
            ..
        } => (1.0, 0.5),
        Noise::Model { .. } => return None,
    };
    let p = c.params();
    let m = p.reset().target().moments();
    let (r, t) = (c.rate, c.temperature());
    let pr = &c.protocol;
    if !c.linear() || pr.period.is_some() || pr.clock.is_some() || !(r > 0.0) {
        return None;
    }
    match (pr.position, pr.refractory) {
        (Some(x_r), None) if t == 0.0 => {
            let s = crate::linear_protocols::position_poisson(sigma, lambda, r, m, x_r);
            Some((s.v, s.v2, Some((s.x, s.x2))))
        }
        (None, Some(spec)) => {
            let mean: f64 = spec.strip_prefix("exp:mean=")?.parse().ok()?;
            let (v, v2) = crate::linear_protocols::refractory_exp(sigma, lambda, r, m, mean);
            let p_f = 1.0 / (1.0 + r * mean);
            Some((v, v2 + 2.0 * t * p_f / (2.0 + r), None))
        }
        _ => None,
    }
}

/// The transient closed form (<v>(t), <v²>(t)) of a linear periodic case
/// without modifiers beyond the period ([`crate::linear_protocols::periodic`]).
pub fn transient_closed_form(c: &ProtocolCase, t: f64) -> Option<(f64, f64)> {
    let Noise::Paper { sigma, lambda } = c.noise else {
        return None;
    };
    let pr = &c.protocol;
    match (c.linear(), pr.period, pr.refractory, pr.position, pr.clock) {
        (true, Some(period), None, None, None) => {
            let m = c.params().reset().target().moments();
            Some(crate::linear_protocols::periodic(
                sigma, lambda, period, m, t,
            ))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_builds_with_its_modifiers() {
        for c in &PROTOCOL_CASES {
            let p = c.params();
            let n = [
                c.protocol.period.is_some(),
                c.protocol.clock.is_some(),
                c.protocol.position.is_some(),
                c.protocol.refractory.is_some(),
            ];
            let want = n.iter().filter(|b| **b).count();
            assert_eq!(p.schedule().features().len(), want, "{}", c.name);
            // At T > 0 the velocity is unbounded: the passage is the
            // telegraph's.
            if let (Quantity::Passage { v0, vt }, 0.0) = (c.quantity, c.temperature()) {
                let vu = p.v_upper();
                assert!((v0 - PASSAGE.0 * vu).abs() < 1e-12, "{}", c.name);
                assert!((vt - PASSAGE.1 * vu).abs() < 1e-12, "{}", c.name);
            }
        }
    }
}
