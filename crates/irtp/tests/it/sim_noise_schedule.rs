//! The exact sampler's schedule modifiers (periodic and renewal clocks,
//! refractory periods, position resetting) with a finite-state noise: the
//! one event loop over the noise's states runs them for every noise.
//! Linear drag against the exact mean velocity under periodic resetting
//! (with and without a fixed refractory period); tan drag with the paper's
//! noise spelt as a generator (the N-state states) against the paper's
//! two-state states under every modifier. Tolerances: 4 standard errors,
//! Bonferroni-corrected per test.

use irtp::model::noise::NoiseModel;
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::sim::{self, Method, Observables, SimSpec, TimeGrid};
use irtp::stats::MeanAcc;
use irtp::{DragLaw, Params};
use irtp_testkit::noises::PAPER_AS_STATES;
use irtp_testkit::stats::bonferroni_z;

fn run(p: &Params, spec: &SimSpec) -> Observables {
    sim::simulate(p, spec, Method::Exact, &NoProgress).unwrap()
}

/// `noise` (T = 0) with Poisson rate `rate`, point target `vr` and the
/// schedule `sched`.
fn noisy(drag: DragLaw, noise: &str, rate: f64, vr: f64, sched: Schedule) -> Params {
    let model = NoiseModel::parse(noise, 0.0).unwrap();
    let p = Params::with_noise(drag, model, rate, vr).unwrap();
    assert!(p.noise().is_some(), "{noise}: not carried as a noise model");
    p.with_schedule(sched).unwrap()
}

/// The stationary mean level m = Σ π_s a_s.
fn mean_level(p: &Params) -> f64 {
    let c = p.chain().unwrap();
    c.pi.iter().zip(&c.levels).map(|(p, a)| p * a).sum()
}

/// <v(t)> for linear drag g(v) = v with a noise started stationary and kept
/// at a reset, resets at T, 2T, ... to v_r, each followed by a hold of
/// length d at v_r (d = 0: none): between resets d<v>/dt = m - <v>, so
/// <v> = v0 e^{-u} + m (1 - e^{-u}) with u the free time since the last
/// reset (v0 = 0 before the first, v_r after), v_r during a hold. A time
/// t = kT sees the state before the reset there (module doc of sim::exact).
fn periodic_mean(t: f64, period: f64, hold: f64, vr: f64, m: f64) -> f64 {
    let mut k = (t / period).floor();
    let mut s = t - k * period;
    if s == 0.0 && k > 0.0 {
        (k, s) = (k - 1.0, period);
    }
    if k == 0.0 {
        return m * (1.0 - (-s).exp());
    }
    if s <= hold {
        return vr;
    }
    let u = s - hold;
    vr * (-u).exp() + m * (1.0 - (-u).exp())
}

/// Linear drag, an asymmetric telegraph noise (m ≠ 0) and run-pause-tumble
/// (three levels, one at 0), periodic resetting at T = 1 with and without
/// a fixed refractory period of 0.25 (the chain runs on at its exit rates
/// while v is held, so it stays stationary): the sampled <v(t)> at every
/// grid time against [`periodic_mean`].
#[test]
fn linear_drag_periodic_mean_is_exact() {
    let cases = [
        ("telegraph:plus=2,minus=1,rate_plus=1,rate_minus=0.5", 0.5),
        ("rpt:sigma=3,alpha=1,beta=2", -0.5),
    ];
    let grid = TimeGrid::linear(3.0, 25).unwrap();
    let spec = SimSpec::new(20_000, grid, 0.0, 8, 17).unwrap();
    let holds = [0.0, 0.25];
    let z = bonferroni_z(cases.len() * holds.len() * (spec.grid.len() - 1));
    for (noise, vr) in cases {
        for hold in holds {
            let refractory = (hold > 0.0).then(|| format!("fixed:t={hold}"));
            let sched = Schedule::parse(Some(1.0), None, refractory.as_deref()).unwrap();
            let p = noisy(DragLaw::Linear, noise, 0.0, vr, sched);
            let m = mean_level(&p);
            let o = run(&p, &spec);
            for (k, &t) in o.times.iter().enumerate().skip(1) {
                let want = periodic_mean(t, 1.0, hold, vr, m);
                let (got, se) = (o.v[k].mean(), o.v[k].sem());
                assert!(
                    (got - want).abs() <= z * se,
                    "{noise} hold {hold} t = {t}: <v> = {got} ± {se}, exact {want}"
                );
            }
        }
    }
}

/// (mean, standard error) pairs of the estimators both runs report: v, v²
/// and x² at the grid times after 0, the time averages, the MSD-fit D
/// where recorded and the occupation density of every bin.
fn estimates(o: &Observables) -> Vec<(f64, f64)> {
    let pair = |a: &MeanAcc| (a.mean(), a.sem());
    let mut out = Vec::new();
    for k in 1..o.times.len() {
        out.extend([pair(&o.v[k]), pair(&o.v2[k]), pair(&o.x2[k])]);
    }
    out.extend([pair(&o.v_time_avg), pair(&o.v2_time_avg)]);
    // The MSD fit is recorded only where the run asks for it.
    if o.msd_fit_d.n > 0 {
        out.push(pair(&o.msd_fit_d));
    }
    out.extend(o.density_time.iter().map(pair));
    out
}

/// The paper's noise (Sigma = 1, lambda = 0.5) spelt as a generator runs
/// the N-state states of the event loop; under each modifier (periodic,
/// gamma renewal clock, exponential and fixed refractory periods, position
/// resetting) its estimators agree with the paper's two-state states
/// within 4 combined standard errors (independent streams).
#[test]
fn paper_noise_as_states_agrees_under_every_modifier() {
    let parse = |period: Option<f64>, position: Option<f64>, refr: Option<&str>| {
        Schedule::parse(period, position, refr).unwrap()
    };
    let gamma = parse(None, None, None)
        .with_clock(Some("gamma:k=2,theta=0.5"))
        .unwrap();
    let cases = [
        ("periodic", 0.0, parse(Some(1.0), None, None)),
        ("gamma clock", 0.0, gamma),
        (
            "exp refractory",
            1.0,
            parse(None, None, Some("exp:mean=1.5")),
        ),
        (
            "fixed refractory",
            1.0,
            parse(None, None, Some("fixed:t=1.5")),
        ),
        ("position", 1.0, parse(None, Some(0.0), None)),
    ];
    // Long enough for several holds per path: x² sees whether the noise
    // decorrelates across a hold (it jumps on while v is held).
    let grid = TimeGrid::linear(12.0, 7).unwrap();
    let spec = SimSpec::new(10_000, grid, 2.0, 8, 23).unwrap();
    let (vr, drag) = (0.2, DragLaw::Tan);
    let mut rows = Vec::new();
    for (name, rate, sched) in cases {
        let paper = Params::new(drag.clone(), 1.0, 0.5, rate, vr)
            .unwrap()
            .with_schedule(sched.clone())
            .unwrap();
        let states = noisy(drag.clone(), PAPER_AS_STATES, rate, vr, sched);
        let (a, b) = (run(&paper, &spec), run(&states, &spec));
        if name == "position" {
            assert!(a.position.is_some() && b.position.is_some(), "{name}");
        }
        let (ea, eb) = (estimates(&a), estimates(&b));
        assert_eq!(ea.len(), eb.len(), "{name}");
        for (i, (x, y)) in ea.into_iter().zip(eb).enumerate() {
            rows.push((name, i, x, y));
        }
    }
    let z = bonferroni_z(rows.len());
    for (name, i, (ma, sa), (mb, sb)) in rows {
        let se = (sa * sa + sb * sb).sqrt();
        assert!(
            (ma - mb).abs() <= z * se || (ma == mb && se == 0.0),
            "{name} estimator {i}: paper {ma} ± {sa}, states {mb} ± {sb}"
        );
    }
}
