//! The drag laws of the cross-method conformance suite
//! (`crates/irtp/tests/it/conformance.rs`): one line per law and parameter
//! set in each list, every check of the suite runs over the whole list. A
//! new law is a line in [`CROSS`], marked `.in_matrix(sigma)` for the
//! support matrix (both suites fail until every registered kind has one),
//! plus lines in [`TWINS`], [`R0_CASES`] or [`EULER_BOUNDS`]
//! where the law has a twin, an r = 0 density worth its own line or a
//! non-trivial Euler step bound.
//!
//! Each reference is independent of the method it checks: a twin is a
//! different law with the same g (so the same answer to rounding), the
//! r = 0 reference is the quadrature formula of the generator's stationary
//! equation (composite Simpson here, Gauss-Kronrod in the library) or a
//! closed form, the sampler is checked against the Fokker-Planck and
//! backward solvers within its standard error.

use irtp::model::{Drag, DragLaw};

/// A law and parameter set of the r = 2 cross-method checks: exact sampler
/// against the Fokker-Planck density and <v²>, exact first passage against
/// the backward equations, Euler against Fokker-Planck where listed.
#[derive(Clone, Copy, Debug)]
pub struct Cross {
    /// The `--drag` spec.
    pub spec: &'static str,
    /// Noise amplitude Sigma.
    pub sigma: f64,
    /// Flip rate lambda.
    pub lambda: f64,
    /// Reset velocity v_r.
    pub vr: f64,
    /// The Sigma at which the support matrix
    /// (`crates/irtp/tests/it/support_matrix.rs`: every resetting protocol
    /// by every method that runs it) takes this law, for one line per law.
    pub matrix_sigma: Option<f64>,
}

impl Cross {
    /// This case, also run by the support matrix at `sigma`.
    pub const fn in_matrix(self, sigma: f64) -> Cross {
        Cross {
            matrix_sigma: Some(sigma),
            ..self
        }
    }
}

/// The laws of the support matrix, (spec, Sigma), in [`CROSS`] order.
pub fn matrix_laws() -> Vec<(&'static str, f64)> {
    CROSS
        .iter()
        .filter_map(|c| c.matrix_sigma.map(|s| (c.spec, s)))
        .collect()
}

/// The reset rate of every [`CROSS`] case.
pub const CROSS_RATE: f64 = 2.0;
/// The first-passage problem of every [`CROSS`] case: v_0 and v_t (the
/// setting of Fig. 7, across v = 0 where the Coulomb drag jumps).
pub const CROSS_PASSAGE: (f64, f64) = (-0.249, 0.5);

const fn cross(spec: &'static str, sigma: f64, lambda: f64, vr: f64) -> Cross {
    Cross {
        spec,
        sigma,
        lambda,
        vr,
        matrix_sigma: None,
    }
}

/// Every registered law at least once (paper media at the paper's Sigma),
/// and each law family once in the support matrix (at a Sigma inside its
/// range where every protocol's targets are cheap to reach).
pub const CROSS: [Cross; 11] = [
    cross("tan", 3.0, 0.5, 0.0).in_matrix(3.0),
    cross("tanh", 0.6, 0.5, 0.0).in_matrix(0.6),
    cross("linear", 1.3, 0.7, 0.2).in_matrix(1.0),
    cross("cubic", 3.0, 0.5, 0.0).in_matrix(1.5),
    cross("cubic", 3.0, 5.0, 0.0),
    cross("power:n=0.5", 3.0, 0.5, 0.0).in_matrix(1.5),
    cross("power:n=2", 3.0, 0.5, 0.0).in_matrix(1.5),
    cross("carreau:n=0.5,a=1", 3.0, 0.5, 0.0).in_matrix(0.8),
    cross("coulomb:mu=0.5,gamma=1", 2.0, 0.5, 0.0).in_matrix(1.5),
    cross("coulomb:mu=1,gamma=2", 3.0, 1.0, 0.3),
    cross("expr:v + 0.3*v^3", 3.0, 0.5, 0.0).in_matrix(1.5),
];

/// Two specs of the same g: every solver must give the same answer to
/// `rtol` (relative, with a floor), the exact sampler the same events from
/// the same seed (its flows agree to ~1e-14).
#[derive(Clone, Copy, Debug)]
pub struct Twin {
    /// The law under test.
    pub spec: &'static str,
    /// A law with the same g.
    pub twin: &'static str,
    /// Noise amplitude Sigma.
    pub sigma: f64,
    /// Flip rate lambda.
    pub lambda: f64,
    /// Relative tolerance: 1e-10 where g, g', g⁻¹ agree to rounding, 1e-9
    /// for expressions (evaluated through the expression tree).
    pub rtol: f64,
}

/// The reset velocity of every twin comparison.
pub const TWIN_VR: f64 = 0.2;

const fn twin(spec: &'static str, twin: &'static str, sigma: f64, lambda: f64, rtol: f64) -> Twin {
    Twin {
        spec,
        twin,
        sigma,
        lambda,
        rtol,
    }
}

/// Newtonian limits (n = 1, mu = 0) and expression twins of built-in laws.
pub const TWINS: [Twin; 8] = [
    twin("power:n=1", "linear", 1.3, 0.7, 1e-10),
    twin("power:n=1,k=1", "linear", 1.3, 0.7, 1e-10),
    twin("carreau:n=1", "linear", 1.3, 0.7, 1e-10),
    twin("carreau:n=1,a=3", "linear", 1.3, 0.7, 1e-10),
    twin("coulomb:mu=0", "linear", 1.3, 0.7, 1e-10),
    twin("expr:tan(v)", "tan", 3.0, 0.9, 1e-9),
    twin("expr:v", "linear", 1.3, 0.7, 1e-9),
    twin("expr:v + v^3/3", "cubic", 3.0, 0.9, 1e-9),
];

/// An independent reference for the r = 0 density P(v), unnormalised.
#[derive(Clone, Copy, Debug)]
pub enum R0Reference {
    /// The quadrature formula P ∝ (Sigma² - g²)⁻¹ exp(-2 lambda ∫_0^v g /
    /// (Sigma² - g²)), by composite Simpson on graded panels
    /// ([`r0_simpson`]); needs a smooth g' at the edge.
    Simpson,
    /// Coulomb friction g = mu sign v + gamma v: P ∝ (Sigma² - g²)^(lambda/gamma - 1)
    /// (the formula integrated on each side of v = 0), pointwise.
    Coulomb { mu: f64, gamma: f64 },
}

/// A law at r = 0: the library's density and the Fokker-Planck solver
/// against the reference.
#[derive(Clone, Copy, Debug)]
pub struct R0Case {
    /// The `--drag` spec.
    pub spec: &'static str,
    /// Noise amplitude Sigma.
    pub sigma: f64,
    /// Flip rate lambda.
    pub lambda: f64,
    /// The reference.
    pub reference: R0Reference,
}

const fn r0(spec: &'static str, sigma: f64, lambda: f64, reference: R0Reference) -> R0Case {
    R0Case {
        spec,
        sigma,
        lambda,
        reference,
    }
}

/// Edge exponents a = lambda / g'(v_u) - 1 of either sign: where a <= 0
/// the density is singular at the edges and only the Fokker-Planck <v²>
/// is compared (with the library's density, not the bins).
pub const R0_CASES: [R0Case; 11] = [
    r0("tan", 3.0, 15.0, R0Reference::Simpson),
    r0("cubic", 3.0, 0.5, R0Reference::Simpson),
    r0("cubic", 3.0, 2.0, R0Reference::Simpson),
    r0("cubic", 3.0, 10.0, R0Reference::Simpson),
    r0("power:n=0.5", 3.0, 0.5, R0Reference::Simpson),
    r0("power:n=2", 3.0, 5.0, R0Reference::Simpson),
    r0("carreau:n=0.5,a=1", 3.0, 0.5, R0Reference::Simpson),
    r0("expr:sinh(v)", 3.0, 5.0, R0Reference::Simpson),
    r0(
        "coulomb:mu=0.5,gamma=1",
        2.0,
        2.5,
        R0Reference::Coulomb {
            mu: 0.5,
            gamma: 1.0,
        },
    ),
    r0(
        "coulomb:mu=1,gamma=2",
        3.0,
        1.0,
        R0Reference::Coulomb {
            mu: 1.0,
            gamma: 2.0,
        },
    ),
    r0("linear", 1.0, 2.0, R0Reference::Simpson),
];

impl R0Case {
    /// The law.
    pub fn law(&self) -> DragLaw {
        law(self.spec)
    }

    /// The edge exponent a = lambda / g'(v_u) - 1 (P ~ (v_u - v)^a).
    pub fn edge_exponent(&self) -> f64 {
        let d = self.law();
        self.lambda / d.derivative(d.inverse(self.sigma)) - 1.0
    }

    /// The reference's normalised mass of each of `bins` equal bins of
    /// (v_l, v_u) and its <v²> (needs [`R0Case::edge_exponent`] > 0).
    pub fn reference_bins(&self, bins: usize) -> (Vec<f64>, f64) {
        match self.reference {
            R0Reference::Simpson => r0_simpson(self.law(), self.sigma, self.lambda, bins),
            R0Reference::Coulomb { mu, gamma } => {
                let (sigma, lambda) = (self.sigma, self.lambda);
                let p = |v: f64| coulomb_r0(mu, gamma, sigma, lambda, v);
                simpson_bins(&p, (sigma - mu) / gamma, bins)
            }
        }
    }

    /// The reference pdf P(v) / P(0) where it is known pointwise.
    pub fn reference_shape(&self, v: f64) -> Option<f64> {
        match self.reference {
            R0Reference::Simpson => None,
            R0Reference::Coulomb { mu, gamma } => {
                let p = |v| coulomb_r0(mu, gamma, self.sigma, self.lambda, v);
                Some(p(v) / p(0.0))
            }
        }
    }
}

/// The Euler step bound is the steepest secant of the drift to the edge
/// (finite even where g' is not, as for power n < 1 and Coulomb): a step
/// just below it keeps every velocity inside (v_l, v_u), `over` times it
/// throws some out.
#[derive(Clone, Copy, Debug)]
pub struct EulerBound {
    /// The `--drag` spec.
    pub spec: &'static str,
    /// Noise amplitude Sigma.
    pub sigma: f64,
    /// A step `over` times the bound must throw velocities out (1.01; 1.02
    /// for expressions, whose bound carries a 1 % margin).
    pub over: f64,
    /// The bound in closed form, where known.
    pub exact: Option<f64>,
    /// Also compare the Euler scheme's stationary <v²> at dt = 2e-3 with
    /// the Fokker-Planck solver (lambda = 0.5, r = 2).
    pub against_fp: bool,
}

/// Laws whose Euler step bound is not 1/max g'.
pub const EULER_BOUNDS: [EulerBound; 5] = [
    EulerBound {
        spec: "power:n=0.5",
        sigma: 3.0,
        over: 1.01,
        exact: None,
        against_fp: true,
    },
    EulerBound {
        spec: "power:n=0.2,k=3",
        sigma: 3.0,
        over: 1.01,
        exact: None,
        against_fp: false,
    },
    // gamma + 2 mu / v_u, just left of the jump at v = 0 (v_u = 1.5).
    EulerBound {
        spec: "coulomb:mu=0.5,gamma=1",
        sigma: 2.0,
        over: 1.01,
        exact: Some(1.0 / (1.0 + 2.0 * 0.5 / 1.5)),
        against_fp: true,
    },
    EulerBound {
        spec: "expr:sinh(v)",
        sigma: 3.0,
        over: 1.02,
        exact: None,
        against_fp: false,
    },
    EulerBound {
        spec: "expr:v - v^3/3",
        sigma: 0.6,
        over: 1.02,
        exact: None,
        against_fp: false,
    },
];

/// Parse a spec of these lists.
pub fn law(spec: &str) -> DragLaw {
    spec.parse()
        .unwrap_or_else(|e| panic!("test law {spec}: {e}"))
}

/// The kind of a spec: its name before `:`.
pub fn kind(spec: &str) -> &str {
    spec.split(':').next().unwrap_or(spec)
}

fn coulomb_r0(mu: f64, gamma: f64, sigma: f64, lambda: f64, v: f64) -> f64 {
    let g = mu + gamma * v.abs();
    ((sigma - g) * (sigma + g)).powf(lambda / gamma - 1.0)
}

/// Panels per bin of the Simpson references.
const PANELS: usize = 4000;

/// Bin masses (normalised) and <v²> of a symmetric pdf `p` on (-v_u, v_u)
/// by composite Simpson, the panels graded quadratically into each bin's
/// upper edge (into v_u, where P ~ (v_u - v)^a with a > 0).
fn simpson_bins(p: &dyn Fn(f64) -> f64, vu: f64, bins: usize) -> (Vec<f64>, f64) {
    let half = bins / 2;
    let (mut mass, mut v2) = (vec![0.0; half], 0.0);
    for (j, m) in mass.iter_mut().enumerate() {
        let (e0, e1) = (
            vu * j as f64 / half as f64,
            vu * (j + 1) as f64 / half as f64,
        );
        let at = |t: f64| e1 - (e1 - e0) * (1.0 - t) * (1.0 - t);
        for i in 0..PANELS {
            let (xa, xb) = (
                at(i as f64 / PANELS as f64),
                at((i + 1) as f64 / PANELS as f64),
            );
            let xm = 0.5 * (xa + xb);
            let (pa, pm, pb) = (p(xa), p(xm), p(xb));
            *m += (xb - xa) / 6.0 * (pa + 4.0 * pm + pb);
            v2 += (xb - xa) / 6.0 * (xa * xa * pa + 4.0 * xm * xm * pm + xb * xb * pb);
        }
    }
    normalised(mass, v2)
}

fn normalised(mass: Vec<f64>, v2: f64) -> (Vec<f64>, f64) {
    let z = 2.0 * mass.iter().sum::<f64>();
    let out = mass
        .iter()
        .rev()
        .chain(mass.iter())
        .map(|m| m / z)
        .collect();
    (out, 2.0 * v2 / z)
}

/// The r = 0 density P(v) ∝ (Sigma² - g²)⁻¹ exp(-2 lambda Φ(v)),
/// Φ(v) = ∫_0^|v| g / (Sigma² - g²), by composite Simpson on graded panels
/// (a different rule from the library's Gauss-Kronrod): the normalised mass
/// of each of `bins` equal bins of (v_l, v_u) and <v²>.
///
/// The logarithmic edge singularity of Φ is subtracted in closed form:
/// g / (Sigma² - g²) ≈ c [1/(v_u - w) - 1/(v_u + w)] near ±v_u with
/// c = 1 / (2 g'(v_u)), whose integral from 0 is -c ln(1 - v²/v_u²); the
/// remainder is bounded. Panels (`PANELS` per bin, on the half line by
/// symmetry) are graded quadratically into v = 0 (where g may behave like
/// |v|^n) and into v_u (where P ~ (v_u - v)^a, a > 0 here); at v_u, P = 0.
pub fn r0_simpson(d: DragLaw, sigma: f64, lambda: f64, bins: usize) -> (Vec<f64>, f64) {
    let vu = d.inverse(sigma);
    let c = 0.5 / d.derivative(vu);
    let h = |w: f64| {
        let g = d.force(w);
        g / ((sigma - g) * (sigma + g)) - c / (vu - w) + c / (vu + w)
    };
    let p = |x: f64, rem: f64| {
        if x >= vu {
            return 0.0;
        }
        let g = d.force(x);
        let phi = rem - c * (-(x / vu) * (x / vu)).ln_1p();
        (-2.0 * lambda * phi).exp() / ((sigma - g) * (sigma + g))
    };
    let simpson = |a: f64, b: f64| (b - a) / 6.0 * (h(a) + 4.0 * h(0.5 * (a + b)) + h(b));
    let half = bins / 2;
    let edge = |j: usize| vu * j as f64 / half as f64;
    let (mut mass, mut v2, mut rem) = (vec![0.0; half], 0.0, 0.0);
    for (j, m) in mass.iter_mut().enumerate() {
        let (e0, e1) = (edge(j), edge(j + 1));
        let at = |t: f64| match j {
            0 => e1 * t * t,
            _ if j + 1 == half => vu - (vu - e0) * (1.0 - t) * (1.0 - t),
            _ => e0 + (e1 - e0) * t,
        };
        for i in 0..PANELS {
            let xa = at(i as f64 / PANELS as f64);
            let xb = at((i + 1) as f64 / PANELS as f64);
            let xm = 0.5 * (xa + xb);
            let rem_m = rem + simpson(xa, xm);
            let rem_b = if xb < vu {
                rem_m + simpson(xm, xb)
            } else {
                rem_m
            };
            let (pa, pm, pb) = (p(xa, rem), p(xm, rem_m), p(xb, rem_b));
            *m += (xb - xa) / 6.0 * (pa + 4.0 * pm + pb);
            v2 += (xb - xa) / 6.0 * (xa * xa * pa + 4.0 * xm * xm * pm + xb * xb * pb);
            rem = rem_b;
        }
    }
    normalised(mass, v2)
}
