//! Model parameters, validated in one place.

use super::drag::{Drag, DragLaw};
use super::noise::{chain::Chain, NoiseModel};
use super::reset::{
    spec, NoiseAtReset, PoissonReset, RandomReset, RedrawnReset, Reset, ResetRule, Schedule,
    Solver, Target,
};
use crate::error::{finite, Error, Result};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Parameters of the IRTP with velocity resetting:
/// dv/dt = -g(v) + eta(t), eta = ±Sigma flipping at rate lambda (paper Eqs. (5)-(6)),
/// and the resetting rule (today Poissonian to v_r, position and noise state
/// kept, paper Eq. (3); see [`crate::model::reset`]).
///
/// Another noise kind or thermal noise (docs/equations.md, "Noise kinds",
/// Eq. (N1)) is carried by [`Params::with_noise`]; every method that does
/// not run it refuses it in [`Params::require`].
///
/// Construct with [`Params::new`]; every field is then guaranteed admissible.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawParams", into = "RawParams")]
pub struct Params {
    drag: DragLaw,
    sigma: f64,
    lambda: f64,
    reset: ResetRule,
    schedule: Schedule,
    /// None: the paper's symmetric telegraph noise ±sigma at rate lambda,
    /// no thermal noise. Some: any other noise model (shared by the
    /// parameters derived from these: [`Params::with_rate`], ...).
    noise: Option<Arc<NoiseModel>>,
}

/// Unvalidated mirror of [`Params`] used for (de)serialisation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RawParams {
    /// Drag law.
    pub drag: DragLaw,
    /// Noise amplitude Sigma (absent with `noise`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// Flip rate lambda (absent with `noise`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f64>,
    /// Reset rate r.
    pub rate: f64,
    /// Reset velocity v_r.
    #[serde(default)]
    pub reset_velocity: f64,
    /// The resetting protocol as a reset spec (`point:v=0.2,noise=redrawn`),
    /// absent for the paper's (point target v_r, noise kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reset: Option<String>,
    /// Periodic resetting: the period T (absent for a Poisson clock).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reset_period: Option<f64>,
    /// A renewal reset clock as a spec (`gamma:k=2,theta=0.5`), absent
    /// for none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reset_clock: Option<String>,
    /// Position resetting: x_r (absent when the position is kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reset_position: Option<f64>,
    /// The refractory period as a spec (`exp:mean=0.5`, `fixed:t=0.5`),
    /// absent for none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refractory: Option<String>,
    /// The noise as a spec (`rpt:sigma=1,alpha=1,beta=1`), absent for the
    /// paper's symmetric telegraph noise (then `sigma` and `lambda` are
    /// its; with a spec they are absent, and refused on the way in).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<String>,
    /// The temperature T of the thermal noise, absent with `noise`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature: Option<f64>,
}

impl TryFrom<RawParams> for Params {
    type Error = Error;
    fn try_from(r: RawParams) -> Result<Self> {
        let p = match &r.noise {
            None => {
                let sigma = r.sigma.ok_or_else(|| missing("sigma"))?;
                let lambda = r.lambda.ok_or_else(|| missing("lambda"))?;
                Params::new(r.drag, sigma, lambda, r.rate, r.reset_velocity)?
            }
            Some(_) if r.sigma.is_some() || r.lambda.is_some() => {
                return Err(Error::invalid(
                    "noise",
                    r.noise.unwrap_or_default(),
                    "no sigma or lambda with a noise spec (its levels and rates are in it)",
                ))
            }
            Some(n) => {
                let model = NoiseModel::parse(n, r.temperature.unwrap_or(0.0))?;
                Params::with_noise(r.drag, model, r.rate, r.reset_velocity)?
            }
        };
        let p = match r.reset {
            None => p,
            Some(s) => {
                let (target, noise) = spec::parse(&s)?;
                p.with_reset(target, noise.unwrap_or(NoiseAtReset::Kept))?
            }
        };
        p.with_schedule(
            Schedule::parse(r.reset_period, r.reset_position, r.refractory.as_deref())?
                .with_clock(r.reset_clock.as_deref())?,
        )
    }
}

/// The error of a missing `sigma` or `lambda` (without `noise`).
fn missing(name: &'static str) -> Error {
    Error::invalid(name, "absent", format!("{name} (or a noise spec)"))
}

impl From<Params> for RawParams {
    fn from(p: Params) -> Self {
        RawParams {
            drag: p.drag.clone(),
            sigma: p.noise.is_none().then_some(p.sigma),
            lambda: p.noise.is_none().then_some(p.lambda),
            rate: p.rate(),
            reset_velocity: p.reset_velocity(),
            reset: p.reset_spec(),
            reset_period: p.schedule.periodic.map(|t| t.period),
            reset_clock: p.schedule.clock.map(|c| c.spec()),
            reset_position: p.schedule.position.map(|x| x.x),
            refractory: p.schedule.refractory.map(|r| r.spec()),
            noise: p.noise.as_ref().map(|m| m.spec()),
            temperature: p.noise.as_ref().map(|m| m.temperature()),
        }
    }
}

impl Params {
    /// Validate and build. Rules: Sigma > 0 and finite, Sigma < 1 for tanh
    /// (the velocity bound atanh(Sigma) must exist) and Sigma > mu for
    /// Coulomb friction ([`Drag::static_friction`]: below it the particle
    /// sticks at v = 0); lambda ≥ 0 and r ≥ 0, finite;
    /// v_r strictly inside (v_l, v_u).
    pub fn new(
        drag: DragLaw,
        sigma: f64,
        lambda: f64,
        rate: f64,
        reset_velocity: f64,
    ) -> Result<Self> {
        let sigma = finite("sigma", sigma)?;
        let limit = drag.force_limit();
        if !(sigma > 0.0 && sigma < limit) {
            let allowed = if limit.is_finite() {
                format!("0 < sigma < {limit} for {drag} drag")
            } else {
                format!("sigma > 0 for {drag} drag")
            };
            return Err(Error::invalid("sigma", sigma, allowed));
        }
        let friction = drag.static_friction();
        if !(sigma > friction) {
            return Err(Error::invalid(
                "sigma",
                sigma,
                format!(
                    "sigma > mu = {friction} of drag {drag}: at sigma <= mu the particle sticks \
                     at v = 0 (the noise never overcomes the static friction; the stationary \
                     state is a point mass at v = 0, D_eff = 0)"
                ),
            ));
        }
        drag.admissible(sigma)?;
        let lambda = finite("lambda", lambda)?;
        if !(lambda >= 0.0) {
            return Err(Error::invalid("lambda", lambda, "lambda >= 0"));
        }
        let rate = finite("rate", rate)?;
        if !(rate >= 0.0) {
            return Err(Error::invalid("rate", rate, "rate >= 0"));
        }
        let reset_velocity = finite("reset_velocity", reset_velocity)?;
        let vu = drag.inverse(sigma);
        if !(reset_velocity > -vu && reset_velocity < vu) {
            return Err(Error::invalid(
                "reset_velocity",
                reset_velocity,
                format!("-{vu} < v_r < {vu} (the open velocity interval for {drag} drag, sigma = {sigma})"),
            ));
        }
        Ok(Params {
            drag,
            sigma,
            lambda,
            reset: ResetRule::Poisson(PoissonReset {
                rate,
                velocity: reset_velocity,
            }),
            schedule: Schedule::default(),
            noise: None,
        })
    }

    /// Validate and build with a noise model (docs/equations.md, "Noise
    /// kinds"). The paper's symmetric telegraph noise without thermal
    /// noise normalises to [`Params::new`] (the same value bit for bit as
    /// `sigma`/`lambda` give); any other is checked against the drag
    /// ([`NoiseModel::check_drag`], errors naming `noise`) and carried, with
    /// `sigma` the largest |level| and `lambda` 0 (no method reads them: each
    /// refuses the noise in [`Params::require`] or runs it from the model),
    /// and v_r inside the velocity interval of Eq. (N1).
    pub fn with_noise(
        drag: DragLaw,
        noise: NoiseModel,
        rate: f64,
        reset_velocity: f64,
    ) -> Result<Self> {
        if noise.temperature() == 0.0 {
            if let Some((sigma, lambda)) = noise.kind().symmetric_telegraph() {
                return Params::new(drag, sigma, lambda, rate, reset_velocity);
            }
        }
        noise.check_drag(&drag)?;
        let rate = finite("rate", rate)?;
        if !(rate >= 0.0) {
            return Err(Error::invalid("rate", rate, "rate >= 0"));
        }
        let reset_velocity = finite("reset_velocity", reset_velocity)?;
        let (lo, hi) = noise.velocity_interval(&drag);
        if !(lo < hi) {
            // Equal levels: no interval for any v_r, the noise's fault.
            return Err(Error::invalid(
                "noise",
                noise.spec(),
                "a noise with two different levels (equal levels leave no velocity interval)",
            ));
        }
        if !(reset_velocity > lo && reset_velocity < hi) {
            return Err(Error::invalid(
                "reset_velocity",
                reset_velocity,
                format!(
                    "{lo} < v_r < {hi} (the open velocity interval of noise {} with drag {drag})",
                    noise.spec()
                ),
            ));
        }
        let sigma = noise.levels().iter().fold(0.0f64, |m, a| m.max(a.abs()));
        Ok(Params {
            drag,
            sigma,
            lambda: 0.0,
            reset: ResetRule::Poisson(PoissonReset {
                rate,
                velocity: reset_velocity,
            }),
            schedule: Schedule::default(),
            noise: Some(Arc::new(noise)),
        })
    }

    /// The noise model other than the paper's: None for the symmetric
    /// telegraph noise ±sigma at rate lambda without thermal noise.
    pub fn noise(&self) -> Option<&NoiseModel> {
        self.noise.as_deref()
    }

    /// The noise model, the paper's included.
    pub fn noise_model(&self) -> Result<NoiseModel> {
        match self.noise() {
            Some(m) => Ok(m.clone()),
            None => NoiseModel::telegraph(self.sigma, self.lambda),
        }
    }

    /// [`Params::new`] or [`Params::with_noise`] with this drag and noise,
    /// another rate and reset velocity (the resetting rule's point target,
    /// noise kept).
    fn rebuilt(&self, rate: f64, reset_velocity: f64) -> Result<Self> {
        match self.noise() {
            None => Params::new(
                self.drag.clone(),
                self.sigma,
                self.lambda,
                rate,
                reset_velocity,
            ),
            Some(m) => Params::with_noise(self.drag.clone(), m.clone(), rate, reset_velocity),
        }
    }

    /// Same parameters with another reset rate (validated), the rest of the
    /// resetting rule kept.
    pub fn with_rate(&self, rate: f64) -> Result<Self> {
        let base = self.rebuilt(rate, self.reset_velocity())?;
        let p = Params {
            reset: self.reset.with_rate(base.rate()),
            ..base
        };
        p.with_schedule(self.schedule.clone())
    }

    /// Same parameters with another flip rate (validated).
    pub fn with_lambda(&self, lambda: f64) -> Result<Self> {
        if let Some(m) = self.noise() {
            return Err(Error::invalid(
                "lambda",
                lambda,
                format!(
                    "no lambda with noise {} (its rates are in the spec)",
                    m.spec()
                ),
            ));
        }
        let base = Params::new(
            self.drag.clone(),
            self.sigma,
            lambda,
            self.rate(),
            self.reset_velocity(),
        )?;
        Ok(Params {
            reset: self.reset,
            schedule: self.schedule.clone(),
            ..base
        })
    }

    /// Same parameters with another reset velocity (validated), the noise
    /// rule kept.
    pub fn with_reset_velocity(&self, reset_velocity: f64) -> Result<Self> {
        self.point_target("another reset velocity")?;
        self.rebuilt(self.rate(), reset_velocity)?
            .with_reset(Target::point(reset_velocity), self.reset.noise())?
            .with_schedule(self.schedule.clone())
    }

    /// Same parameters and rate with another resetting protocol: the target
    /// (validated against the velocity interval) and what a reset does to
    /// the noise state. The pair picks the rule of [`crate::model::reset`].
    pub fn with_reset(&self, target: Target, noise: NoiseAtReset) -> Result<Self> {
        let rate = self.rate();
        let vu = self.v_upper();
        let written = || spec::write(&target, noise);
        let reset = match target.point_velocity() {
            Some(v) => {
                let base = self.rebuilt(rate, v)?;
                match noise {
                    NoiseAtReset::Kept => {
                        return Ok(Params {
                            schedule: self.schedule.clone(),
                            ..base
                        })
                    }
                    NoiseAtReset::Redrawn => ResetRule::Redrawn(RedrawnReset {
                        rate,
                        velocity: base.reset_velocity(),
                    }),
                }
            }
            None => ResetRule::Random(RandomReset {
                rate,
                target: target
                    .fit(vu)
                    .map_err(|allowed| Error::invalid("reset_to", written(), allowed))?,
                noise,
            }),
        };
        Ok(Params {
            reset,
            ..self.clone()
        })
    }

    /// Same parameters with the modifiers of the resetting rule (periodic
    /// clock, position reset, refractory period), validated: a periodic
    /// clock replaces the Poisson clock, so the rate must then be 0.
    pub fn with_schedule(&self, schedule: Schedule) -> Result<Self> {
        if let Some(t) = schedule.periodic {
            if self.rate() != 0.0 {
                return Err(Error::invalid(
                    "rate",
                    self.rate(),
                    format!(
                        "0 (or no --rate) with --reset-period {} (periodic resetting replaces the Poisson clock)",
                        t.period
                    ),
                ));
            }
        }
        if schedule.clock.is_some() && self.rate() != 0.0 {
            return Err(Error::invalid(
                "rate",
                self.rate(),
                "0 (or no --rate) with --reset-clock (the renewal clock replaces the Poisson \
                 clock; its law exp is the Poisson clock as a renewal clock)",
            ));
        }
        Ok(Params {
            schedule,
            ..self.clone()
        })
    }

    /// The modifiers of the resetting rule.
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// Refuse what `solver` does not run of these parameters: the one
    /// check of [`crate::capability::check`], called by every method
    /// before any work.
    pub fn require(&self, solver: Solver) -> Result<()> {
        crate::capability::check(solver, self)
    }

    /// The point target v_r, or an error naming `method` and the rule for a
    /// random target (a method that needs a point target refuses the
    /// others through it, never treating them as a point).
    pub fn point_target(&self, method: &str) -> Result<f64> {
        match self.reset.point() {
            Some(v) => Ok(v),
            None => Err(Error::invalid(
                "reset_to",
                spec::write(&self.reset.target(), self.reset.noise()),
                format!(
                    "a point target (point:v=V) for {method}: the {} rule's random target has \
                     no single reset velocity",
                    self.reset.name()
                ),
            )),
        }
    }

    /// The canonical reset spec (`point:v=0.2,noise=redrawn`), None for the
    /// paper's protocol (point target, noise kept), which provenance files
    /// record by `rate` and `reset_velocity` alone.
    pub fn reset_spec(&self) -> Option<String> {
        match self.reset {
            ResetRule::Poisson(_) => None,
            _ => Some(spec::write(&self.reset.target(), self.reset.noise())),
        }
    }

    /// Drag law.
    pub fn drag(&self) -> DragLaw {
        self.drag.clone()
    }
    /// Noise amplitude Sigma of the paper's noise. With another noise model
    /// ([`Params::noise`]): its largest |level|, which no method reads.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
    /// Flip rate lambda (eta correlation Sigma² e^{-2 lambda |t|}). With
    /// another noise model ([`Params::noise`]): 0, which no method reads.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
    /// Reset rate r.
    pub fn rate(&self) -> f64 {
        self.reset.rate()
    }
    /// Reset velocity v_r.
    ///
    /// The point target of the resetting rule. The methods that assume a
    /// point target (the FP mesh's reset cell, the backward equations' reset
    /// term) read it here and the noise rule through the exhaustive
    /// [`NoiseAtReset::mix`]: a rule with another kind of target extends
    /// this exhaustive match, and each such method must then handle it or
    /// refuse it.
    ///
    /// For a random target: its centre ([`Target::centre`]), where meshes
    /// put a node; the methods that need a point target take it from
    /// [`Params::point_target`] instead, which refuses random targets.
    pub fn reset_velocity(&self) -> f64 {
        self.reset.target().centre()
    }

    /// The resetting rule: rate, target, noise state at a reset.
    pub fn reset(&self) -> &ResetRule {
        &self.reset
    }

    /// Same parameters with the resetting rule mirrored under v → -v
    /// (downward first passages run in the mirrored frame), and a noise
    /// model other than the paper's mirrored too
    /// ([`NoiseModel::mirrored`]: every level negated, state for state).
    pub fn mirrored_reset(&self) -> Self {
        let noise = self.noise.as_ref().map(|m| match m.mirrored() {
            Ok(n) => Arc::new(n),
            // The mirror of a valid generator is valid.
            Err(_) => Arc::clone(m),
        });
        Params {
            reset: self.reset.mirrored(),
            noise,
            ..self.clone()
        }
    }

    /// Upper velocity bound v_u = g⁻¹(Sigma) (paper Eqs. (8)-(10)). With
    /// another noise model: the larger |edge| of its velocity interval
    /// ([`NoiseModel::velocity_interval`], Eq. (N1); ∞ with thermal noise
    /// and an unbounded drag).
    pub fn v_upper(&self) -> f64 {
        match self.noise() {
            None => self.drag.inverse(self.sigma),
            Some(m) => {
                let (lo, hi) = m.velocity_interval(&self.drag);
                lo.abs().max(hi.abs())
            }
        }
    }
    /// The Newtonian medium on the same velocity interval: g(v) = v with
    /// Sigma' = v_u, the flip rate, resetting rule and schedule unchanged.
    /// Driven by the same random stream, the exact sampler gives it the
    /// same events as this model, and its moments are known exactly
    /// ([`crate::analytic::linear_moments`]): the control variate of
    /// [`crate::sim::control`].
    pub fn linear_proxy(&self) -> Params {
        Params {
            drag: DragLaw::Linear,
            sigma: self.v_upper(),
            ..self.clone()
        }
    }
    /// Lower velocity bound v_l = -v_u.
    pub fn v_lower(&self) -> f64 {
        -self.v_upper()
    }

    /// Where g'(0) = ∞ (g ≈ c sign(v) |v|^n near 0 with 0 < n < 1, as for
    /// the power law with n < 1): Some(n), the law's local exponent
    /// ln(g(2δ)/g(δ)) / ln 2 at δ = 1e-12 v_u (exact for the power law).
    /// None where g'(0) is finite or g jumps at 0 (Coulomb friction). The
    /// meshes of the forward and backward solvers are graded towards such a
    /// kink. Fails (typed) if g'(0) = ∞ but the exponent is not in (0, 1).
    pub fn kink_exponent(&self) -> Result<Option<f64>> {
        let drag = self.drag();
        if drag.derivative(0.0).is_finite() || drag.static_friction() > 0.0 {
            return Ok(None);
        }
        let delta = 1e-12 * self.v_upper();
        let n = (drag.force(2.0 * delta) / drag.force(delta)).log2();
        if !(n > 0.0 && n < 1.0) {
            return Err(Error::Numerical {
                method: "kink exponent of g at v = 0",
                reason: format!(
                    "g'(0) = ∞ but the local exponent n of g ~ |v|^n at 0 is {n}, not in (0, 1)"
                ),
            });
        }
        Ok(Some(n))
    }
    /// (v_l, v_u): (-g⁻¹(Sigma), g⁻¹(Sigma)) for the paper's noise; with
    /// another noise model its velocity interval
    /// ([`NoiseModel::velocity_interval`], Eq. (N1)): (g⁻¹(min a), g⁻¹(max a))
    /// without thermal noise (asymmetric for an asymmetric noise), the
    /// drag's own domain (±∞ for an unbounded law) with T > 0.
    pub fn bounds(&self) -> (f64, f64) {
        match self.noise() {
            None => (self.v_lower(), self.v_upper()),
            Some(m) => m.velocity_interval(&self.drag),
        }
    }

    /// The noise chain the engines run: levels, generator, exit rates,
    /// stationary law and temperature ([`Chain`]); the paper's noise is the
    /// two-state chain (+Sigma, -Sigma) flipping at rate lambda, T = 0.
    pub fn chain(&self) -> Result<Chain> {
        Chain::new(&self.noise_model()?)
    }

    /// The largest event rate of an event-driven sampler, for cost
    /// estimates: max_s q_s + r with a noise model other than the paper's
    /// (Eq. (N10)), else the schedule's bound on lambda + r
    /// ([`crate::model::reset::Schedule::event_rate_bound`]).
    pub fn event_rate_bound(&self) -> f64 {
        match self.chain() {
            Ok(c) if self.noise().is_some() => {
                c.exit.iter().copied().fold(0.0, f64::max) + self.rate()
            }
            _ => self.schedule().event_rate_bound(self.lambda(), self.rate()),
        }
    }

    /// Largest Euler step that keeps the velocity inside (v_l, v_u):
    /// dt < 1 / [`Drag::euler_slope`], the largest secant slope
    /// (Sigma - g(v)) / (v_u - v) on the interval, so that
    /// v + dt (Sigma - g(v)) < v_u for every v < v_u (and symmetrically at
    /// v_l). For the shipped laws without parameters this is 1 / max g'
    /// (tan: 1/(1+Sigma²); tanh and linear: 1); the power law with n < 1,
    /// whose g' is unbounded at v = 0, gets its finite secant bound.
    pub fn max_euler_dt(&self) -> f64 {
        1.0 / self.drag.euler_slope(self.sigma)
    }

    /// Validate an Euler time step against [`Params::max_euler_dt`].
    pub fn check_dt(&self, dt: f64) -> Result<f64> {
        let dt = finite("dt", dt)?;
        let max = self.max_euler_dt();
        if !(dt > 0.0 && dt < max) {
            return Err(Error::invalid(
                "dt",
                dt,
                format!("0 < dt < {max} (= 1/max g'(v) on the velocity interval, or the steepest secant to its edge where g' is unbounded or g jumps, so an Euler step cannot leave it)"),
            ));
        }
        Ok(dt)
    }

    /// Exponent of the stationary density at the upper edge, P ~ (v_u - v)^a,
    /// a = (lambda + r)/g'(v_u) - 1 (negative: integrable divergence).
    pub fn edge_exponent(&self) -> f64 {
        (self.lambda + self.rate()) / self.drag.derivative(self.v_upper()) - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::super::reset::support;
    use super::*;

    fn ok(drag: DragLaw, s: f64, l: f64, r: f64, vr: f64) -> bool {
        Params::new(drag, s, l, r, vr).is_ok()
    }

    #[test]
    fn accepts_paper_values() {
        assert!(ok(DragLaw::Tan, 3.0, 0.9, 0.0, 0.0));
        assert!(ok(DragLaw::Tanh, 0.6, 0.85, 2.0, 0.0));
        assert!(ok(DragLaw::Linear, 1.0, 0.5, 10.0, 0.3));
    }

    #[test]
    fn rejects_each_rule() {
        for bad in [f64::NAN, f64::INFINITY, -1.0, 0.0] {
            assert!(!ok(DragLaw::Tan, bad, 1.0, 0.0, 0.0), "sigma {bad}");
        }
        assert!(!ok(DragLaw::Tanh, 1.0, 1.0, 0.0, 0.0));
        assert!(!ok(DragLaw::Tanh, 1.5, 1.0, 0.0, 0.0));
        for bad in [f64::NAN, f64::NEG_INFINITY, f64::INFINITY, -0.1] {
            assert!(!ok(DragLaw::Tan, 3.0, bad, 0.0, 0.0), "lambda {bad}");
            assert!(!ok(DragLaw::Tan, 3.0, 1.0, bad, 0.0), "rate {bad}");
        }
        let vu = 3f64.atan();
        for bad in [f64::NAN, vu, -vu, 2.0] {
            assert!(!ok(DragLaw::Tan, 3.0, 1.0, 1.0, bad), "v_r {bad}");
        }
    }

    #[test]
    fn error_names_parameter_and_range() {
        let e = Params::new(DragLaw::Tanh, 1.2, 1.0, 0.0, 0.0).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.starts_with("invalid sigma = 1.2") && msg.contains("< 1"),
            "{msg}"
        );
    }

    #[test]
    fn dt_limit() {
        let p = Params::new(DragLaw::Tan, 3.0, 1.0, 0.0, 0.0).unwrap();
        assert!((p.max_euler_dt() - 0.1).abs() < 1e-15);
        assert!(p.check_dt(1e-3).is_ok());
        for bad in [0.0, -1e-3, 0.1, 0.5, f64::NAN] {
            assert!(p.check_dt(bad).is_err(), "dt {bad}");
        }
    }

    #[test]
    fn serde_round_trip_validates() {
        let p = Params::new(DragLaw::Tan, 3.0, 0.9, 2.0, 0.0).unwrap();
        let s = serde_json::to_string(&p).unwrap();
        let q: Params = serde_json::from_str(&s).unwrap();
        assert_eq!(p, q);
        let bad = s.replace("3.0", "-3.0");
        assert!(serde_json::from_str::<Params>(&bad).is_err());
    }

    #[test]
    fn schedule_round_trip_and_refusal() {
        let p = Params::new(DragLaw::Tan, 3.0, 0.9, 0.0, 0.1).unwrap();
        let sched = Schedule::parse(Some(2.0), Some(-0.5), Some("exp:mean=0.25")).unwrap();
        let q = p.with_schedule(sched.clone()).unwrap();
        let s = serde_json::to_string(&q).unwrap();
        assert!(s.contains("\"refractory\":\"exp:mean=0.25\""), "{s}");
        let back: Params = serde_json::from_str(&s).unwrap();
        assert_eq!(back, q);
        // The paper's protocol writes none of the new keys.
        assert!(!serde_json::to_string(&p).unwrap().contains("reset_period"));
        // A periodic clock with a Poisson rate is refused, naming rate.
        let r = Params::new(DragLaw::Tan, 3.0, 0.9, 1.0, 0.1).unwrap();
        let e = r.with_schedule(sched).unwrap_err().to_string();
        assert!(e.starts_with("invalid rate = 1"), "{e}");
        // Every solver that lacks a feature refuses it, naming the flag.
        for solver in Solver::ALL {
            for f in q.schedule().features() {
                let one = match f {
                    support::Feature::Periodic => Schedule::parse(Some(2.0), None, None),
                    support::Feature::Position => Schedule::parse(None, Some(1.0), None),
                    _ => Schedule::parse(None, None, Some("exp:mean=0.25")),
                }
                .unwrap();
                let res = p.with_schedule(one).unwrap().require(solver);
                match res {
                    Ok(()) => assert!(support::supports(solver, f)),
                    Err(e) => {
                        let msg = e.to_string();
                        assert!(!support::supports(solver, f));
                        assert!(msg.starts_with(&format!("invalid {}", f.flag())), "{msg}");
                        assert!(msg.contains(solver.command()), "{msg}");
                    }
                }
            }
        }
        // Bad values are refused at the door.
        assert!(Schedule::parse(Some(0.0), None, None).is_err());
        assert!(Schedule::parse(None, Some(f64::NAN), None).is_err());
        assert!(Schedule::parse(None, None, Some("exp:mean=-1")).is_err());
    }

    #[test]
    fn edge_exponent_paper_case() {
        // Paper Fig. 2a: tan, Sigma = 3, lambda = 0.9 -> 0.9/10 - 1 = -0.91.
        let p = Params::new(DragLaw::Tan, 3.0, 0.9, 0.0, 0.0).unwrap();
        assert!((p.edge_exponent() + 0.91).abs() < 1e-12);
    }
}
