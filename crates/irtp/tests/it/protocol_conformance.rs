//! The cross-method suite of the resetting protocols: every case of
//! `irtp_testkit::protocols::PROTOCOL_CASES` (periodic and renewal clocks,
//! exponential and fixed refractory periods, position resetting, random
//! targets; the paper's noise, finite-state noise models, thermal noise) is
//! run by every method that computes its quantity and that
//! `irtp::capability::check` admits, so a method that learns a combination
//! joins here without a line changed. Every pair of estimates of one
//! scalar is compared: the samplers (exact; Euler at dt and dt/2,
//! extrapolated 2 E(dt/2) - E(dt)) within their standard errors, the
//! deterministic solvers within their own error estimates (in quadrature),
//! and the linear-drag closed forms (the library's and
//! `irtp_testkit::protocols`'). One bound for the suite: 4 standard errors
//! raised to the Bonferroni bound over every comparison the whole suite
//! can make ([`comparisons_bound`]), the fast and the slow tier alike.
//!
//! Fast tier: `cargo test -p irtp --test it protocol_conformance` (the
//! cases marked fast); slow tier: the same with `-- --ignored` (the
//! others).

use crate::common::protocols::{
    closed_form, transient_closed_form, ProtocolCase, Quantity, PROTOCOL_CASES,
};
use crate::common::stats::bonferroni_z;
use irtp::analytic::{linear, linear_moments};
use irtp::capability::{check, Solver};
use irtp::fp::{stationary, transient, StationaryOptions, TransientOptions};
use irtp::mfpt::distribution::{distribution, DistributionOptions};
use irtp::mfpt::{self, BackwardOptions, Method as MfptMethod, ParticleOptions, Problem};
use irtp::parallel::NoProgress;
use irtp::search::{self, SearchMethod, SearchProblem};
use irtp::sim::{self, Method, SimSpec, TimeGrid};
use irtp::{Error, Params};

/// An estimate: the method, its value and its error (a standard error for
/// particles, an error estimate for a deterministic solver).
#[derive(Clone, Debug)]
struct Est {
    method: String,
    value: f64,
    err: f64,
}

/// The estimates of every scalar of a case: (scalar, estimates).
type Table = Vec<(&'static str, Vec<Est>)>;

/// The relative error given a closed form: rounding.
const ROUNDING: f64 = 1e-12;

fn est(method: impl Into<String>, value: f64, err: f64) -> Est {
    Est {
        method: method.into(),
        value,
        err,
    }
}

/// Whether `solver` computes the quantity `q` (the solvers a case may
/// admit; the others never see it).
fn computes(q: &Quantity, solver: Solver) -> bool {
    use Solver as S;
    match q {
        Quantity::Stationary { .. } => {
            matches!(
                solver,
                S::Exact | S::Euler | S::FpStationary | S::ClosedForm
            )
        }
        Quantity::Transient { .. } => {
            matches!(solver, S::Exact | S::Euler | S::FpTransient | S::ClosedForm)
        }
        Quantity::Passage { .. } => matches!(
            solver,
            S::Backward | S::MfptExact | S::MfptEuler | S::FptDistribution
        ),
        Quantity::Search { .. } => matches!(
            solver,
            S::SearchBackward | S::SearchRenewal | S::SearchExact | S::SearchEuler
        ),
    }
}

/// The methods of `c`: those that compute its quantity and that the
/// capability module admits; the closed forms for linear drag only (the
/// table admits `analytic` for any drag, its closed forms are Newtonian).
fn admitted(c: &ProtocolCase) -> Vec<Solver> {
    let p = c.params();
    Solver::ALL
        .into_iter()
        .filter(|&s| computes(&c.quantity, s) && check(s, &p).is_ok())
        .filter(|&s| s != Solver::ClosedForm || c.linear())
        .collect()
}

/// The references of the test kit `c` has (closed forms beyond the
/// library's, counted as methods).
fn references(c: &ProtocolCase) -> usize {
    let transient = match c.quantity {
        Quantity::Transient { times } => transient_closed_form(c, times[0]).is_some(),
        _ => false,
    };
    let stationary = matches!(c.quantity, Quantity::Stationary { .. }) && closed_form(c).is_some();
    usize::from(transient || stationary)
}

/// The scalars a case's quantity has at most.
fn scalars(c: &ProtocolCase) -> usize {
    match c.quantity {
        Quantity::Stationary { d_eff, .. } => {
            2 + 2 * usize::from(c.protocol.position.is_some()) + usize::from(d_eff)
        }
        Quantity::Transient { times } => 2 * times.len(),
        Quantity::Passage { .. } | Quantity::Search { .. } => 1,
    }
}

/// The most comparisons the whole suite can make: every pair of methods
/// and references on every scalar of every case.
fn comparisons_bound() -> usize {
    PROTOCOL_CASES
        .iter()
        .map(|c| {
            let k = admitted(c).len() + references(c);
            scalars(c) * k * k.saturating_sub(1) / 2
        })
        .sum()
}

/// Richardson over dt and dt/2 with independent seeds.
fn richardson(coarse: (f64, f64), fine: (f64, f64)) -> (f64, f64) {
    (
        2.0 * fine.0 - coarse.0,
        (4.0 * fine.1 * fine.1 + coarse.1 * coarse.1).sqrt(),
    )
}

/// Euler's step: a fifth of the stability bound, at most 0.01 (the
/// periods, holds and grid times are multiples of dt and dt/2).
fn euler_dt(p: &Params) -> f64 {
    (0.2 * p.max_euler_dt()).min(0.01)
}

/// A sampler's scalars as (mean, se) pairs, in the order of `names`.
type Sampled = Vec<(&'static str, (f64, f64))>;

/// The stationary scalars of one sampler run.
fn sim_stationary(c: &ProtocolCase, m: Method, seed: u64) -> Sampled {
    let Quantity::Stationary { t_max, burn_in, .. } = c.quantity else {
        unreachable!()
    };
    let p = c.params();
    let grid = TimeGrid::linear(t_max, 31).unwrap();
    let spec = SimSpec::new(10_000, grid, burn_in, 10, seed).unwrap();
    let s = sim::simulate(&p, &spec, m, &NoProgress)
        .unwrap_or_else(|e| panic!("{}: {m:?}: {e}", c.name))
        .summary();
    let mut out = vec![
        ("<v>", (s.v_mean, s.v_mean_err)),
        ("<v²>", (s.v2, s.v2_err)),
    ];
    if c.protocol.position.is_some() {
        out.push(("<x>", (s.x_final, s.x_final_err)));
        out.push(("<x²>", (s.x2_final, s.x2_final_err)));
    }
    if let (Some(d), Some(e)) = (s.d_eff_msd, s.d_eff_msd_err) {
        out.push(("D_eff", (d, e)));
    }
    out
}

/// The transient scalars <v>(t), <v²>(t) of one sampler run.
fn sim_transient(c: &ProtocolCase, m: Method, seed: u64) -> Sampled {
    let Quantity::Transient { times } = c.quantity else {
        unreachable!()
    };
    let grid = TimeGrid::from_times([&[0.0][..], &times].concat()).unwrap();
    // The window (unused here) of whole periods, as the samplers require.
    let period = c.protocol.period.unwrap_or(1.0);
    let burn_in = times[2] % period;
    let spec = SimSpec::new(20_000, grid, burn_in, 10, seed).unwrap();
    let o = sim::simulate(&c.params(), &spec, m, &NoProgress)
        .unwrap_or_else(|e| panic!("{}: {m:?}: {e}", c.name));
    let mut out = Vec::new();
    for k in 0..times.len() {
        out.push((V_AT[k], (o.v[k + 1].mean(), o.v[k + 1].sem())));
        out.push((V2_AT[k], (o.v2[k + 1].mean(), o.v2[k + 1].sem())));
    }
    out
}

const V_AT: [&str; 3] = ["<v>(t1)", "<v>(t2)", "<v>(t3)"];
const V2_AT: [&str; 3] = ["<v²>(t1)", "<v²>(t2)", "<v²>(t3)"];

/// A sampler's scalars into the table: exact as run, Euler at dt and dt/2
/// extrapolated.
fn sampler(c: &ProtocolCase, t: &mut Table, s: Solver, seed: u64) {
    let run = |m: Method, seed: u64| match c.quantity {
        Quantity::Transient { .. } => sim_transient(c, m, seed),
        _ => sim_stationary(c, m, seed),
    };
    let rows = match s {
        Solver::Exact => run(Method::Exact, seed),
        _ => {
            let dt = euler_dt(&c.params());
            let (a, b) = (
                run(Method::euler(dt), seed + 1),
                run(Method::euler(dt / 2.0), seed + 2),
            );
            a.iter()
                .zip(&b)
                .map(|((name, x), (_, y))| (*name, richardson(*x, *y)))
                .collect()
        }
    };
    for (name, (v, e)) in rows {
        push(t, name, est(s.command(), v, e));
    }
}

fn push(t: &mut Table, name: &'static str, e: Est) {
    match t.iter_mut().find(|(n, _)| *n == name) {
        Some((_, v)) => v.push(e),
        None => t.push((name, vec![e])),
    }
}

/// The stationary Fokker-Planck solver: the extrapolated moments, each
/// with the change from the coarse mesh (or the N-state error estimates).
fn fp_stationary(c: &ProtocolCase, t: &mut Table) {
    let s = stationary(&c.params(), &StationaryOptions::default())
        .unwrap_or_else(|e| panic!("{}: fp: {e}", c.name));
    let name = Solver::FpStationary.command();
    let (ev, ev2, ed) = match (&s.noise, &s.coarse) {
        (Some(n), _) => n.errors.map_or((0.0, 0.0, 0.0), |e| (e[0], e[1], e[2])),
        (None, Some(m)) => (
            (m.v_mean - s.v_mean).abs(),
            (m.v2 - s.v2).abs(),
            s.d_eff_err.unwrap_or(0.0),
        ),
        (None, None) => (0.0, 0.0, 0.0),
    };
    push(t, "<v>", est(name, s.v_mean, ev));
    push(t, "<v²>", est(name, s.v2, ev2));
    if let (Some(x), Some(x2)) = (s.x_mean, s.x2) {
        let coarse = s.coarse.as_ref().and_then(|m| m.x_moments);
        let (ex, ex2) = coarse.map_or((0.0, 0.0), |m| ((m[0] - x).abs(), (m[1] - x2).abs()));
        push(t, "<x>", est(name, x, ex));
        push(t, "<x²>", est(name, x2, ex2));
    }
    if matches!(c.quantity, Quantity::Stationary { d_eff: true, .. }) {
        push(t, "D_eff", est(name, s.d_eff, ed));
    }
}

/// The library's and the test kit's stationary closed forms.
fn closed_stationary(c: &ProtocolCase, t: &mut Table, library: bool) {
    let p = c.params();
    let tol = |x: f64| ROUNDING * x.abs().max(1.0);
    if library {
        let name = Solver::ClosedForm.command();
        let (v, v2) = (linear::v_mean(&p), linear::v2(&p));
        let (v, v2) = (v.unwrap(), v2.unwrap());
        push(t, "<v>", est(name, v, tol(v)));
        push(t, "<v²>", est(name, v2, tol(v2)));
        if c.protocol.position.is_some() {
            let (x, x2) = linear::position_moments(&p).unwrap();
            push(t, "<x>", est(name, x, tol(x)));
            push(t, "<x²>", est(name, x2, tol(x2)));
        }
        if matches!(c.quantity, Quantity::Stationary { d_eff: true, .. }) {
            let d = linear::d_eff(&p).unwrap();
            push(t, "D_eff", est(name, d, tol(d)));
        }
    }
    if let Some((v, v2, x)) = closed_form(c) {
        let name = "closed form (testkit)";
        push(t, "<v>", est(name, v, tol(v)));
        push(t, "<v²>", est(name, v2, tol(v2)));
        if let Some((x, x2)) = x {
            push(t, "<x>", est(name, x, tol(x)));
            push(t, "<x²>", est(name, x2, tol(x2)));
        }
    }
}

/// The transient Fokker-Planck solver (<v²>(t) with its mesh error; it
/// states no error of <v>(t)) and the closed forms.
fn deterministic_transient(c: &ProtocolCase, t: &mut Table, admitted: &[Solver]) {
    let Quantity::Transient { times } = c.quantity else {
        unreachable!()
    };
    let p = c.params();
    let tol = |x: f64| ROUNDING * x.abs().max(1.0);
    if admitted.contains(&Solver::FpTransient) {
        let o = TransientOptions {
            cells: 200,
            t_max: times[2],
            times: times.to_vec(),
            ..TransientOptions::default()
        };
        let tr = transient(&p, &o).unwrap_or_else(|e| panic!("{}: fp transient: {e}", c.name));
        let name = Solver::FpTransient.command();
        for (k, at) in V2_AT.iter().enumerate() {
            push(t, at, est(name, tr.v2[k], tr.v2_mesh_error[k]));
        }
    }
    if admitted.contains(&Solver::ClosedForm) {
        let m = linear_moments::moments(&p, &times).unwrap();
        for k in 0..times.len() {
            let name = Solver::ClosedForm.command();
            push(t, V_AT[k], est(name, m.v_mean[k], tol(m.v_mean[k])));
            push(t, V2_AT[k], est(name, m.v2[k], tol(m.v2[k])));
        }
    }
    for (k, &tk) in times.iter().enumerate() {
        if let Some((v, v2)) = transient_closed_form(c, tk) {
            push(t, V_AT[k], est("closed form (testkit)", v, tol(v)));
            push(t, V2_AT[k], est("closed form (testkit)", v2, tol(v2)));
        }
    }
}

fn particles(n: u64, seed: u64, t_max: f64) -> ParticleOptions {
    ParticleOptions {
        particles: n,
        t_max,
        seed,
    }
}

/// The mean first passage of the velocity by one admitted method.
fn passage(c: &ProtocolCase, s: Solver, seed: u64) -> Est {
    let Quantity::Passage { v0, vt } = c.quantity else {
        unreachable!()
    };
    let prob = Problem::new(c.params(), v0, vt).unwrap_or_else(|e| panic!("{}: {e}", c.name));
    let fail = |e: Error| -> ! { panic!("{}: {s}: {e}", c.name) };
    let sampled = |m: MfptMethod| {
        let r = mfpt::solve(&prob, &m, &NoProgress).unwrap_or_else(|e| fail(e));
        let s = r.summary().expect("a particle estimate");
        assert_eq!(s.censored, 0, "{}: censored particles", c.name);
        (s.tau, s.tau_err)
    };
    let (value, err) = match s {
        Solver::Backward => {
            let b = MfptMethod::Backward(BackwardOptions::default());
            let r = mfpt::solve(&prob, &b, &NoProgress).unwrap_or_else(|e| fail(e));
            let e = r.backward().map_or(0.0, |b| b.error_estimate);
            (r.tau(), if e.is_finite() { e } else { 0.0 })
        }
        Solver::MfptExact => sampled(MfptMethod::Exact(particles(20_000, seed, f64::INFINITY))),
        Solver::MfptEuler => {
            let dt = euler_dt(prob.params());
            let at = |dt, seed| {
                sampled(MfptMethod::Euler {
                    dt,
                    run: particles(10_000, seed, 1e4),
                })
            };
            richardson(at(dt, seed + 1), at(dt / 2.0, seed + 2))
        }
        Solver::FptDistribution => {
            let d = distribution(&prob, &[1.0], &DistributionOptions::default())
                .unwrap_or_else(|e| fail(e));
            (d.mean, d.mean_error)
        }
        _ => unreachable!("{s} does not compute a velocity passage"),
    };
    est(s.command(), value, err)
}

/// The search's backward mesh (the default; its error estimate enters
/// the comparisons).
const BACKWARD_MESH: search::backward::BackwardOptions = search::backward::BackwardOptions {
    cells_x: 64,
    cells_v: 32,
    refine: true,
    climb: true,
    truncation: 1e-8,
    max_work: 1e11,
    max_memory: 4e9,
};

/// The renewal route's mesh and steps: half the default's (7 s there,
/// 0.2 s here for the fast case; its error estimate enters the
/// comparisons).
const RENEWAL_MESH: search::renewal::RenewalOptions = search::renewal::RenewalOptions {
    cells_x: 16,
    cells_v: 8,
    refine: true,
    climb: true,
    steps: 50,
    tail: 1e-8,
    max_work: 1e11,
    max_memory: 4e9,
};

/// The mean search time by one admitted method.
fn search_time(c: &ProtocolCase, s: Solver, seed: u64) -> Est {
    let Quantity::Search { x0, v0, target } = c.quantity else {
        unreachable!()
    };
    let prob = SearchProblem::new(c.params(), x0, v0, target)
        .unwrap_or_else(|e| panic!("{}: {e}", c.name));
    let run = particles(20_000, seed, 1e4);
    let m = match s {
        Solver::SearchBackward => SearchMethod::Backward(BACKWARD_MESH),
        Solver::SearchRenewal => SearchMethod::Renewal(RENEWAL_MESH),
        Solver::SearchExact => SearchMethod::Exact(run),
        Solver::SearchEuler => SearchMethod::Euler {
            dt: euler_dt(prob.params()),
            run,
        },
        _ => unreachable!("{s} does not compute a search"),
    };
    let r =
        search::solve(&prob, &m, &NoProgress).unwrap_or_else(|e| panic!("{}: {s}: {e}", c.name));
    let (tau, _, _, err) = r.tau();
    est(s.command(), tau, if err.is_finite() { err } else { 0.0 })
}

/// Every admitted method's estimates of every scalar of `c`.
fn table(c: &ProtocolCase, seed: u64) -> Table {
    let admitted = admitted(c);
    let mut t = Table::new();
    for (k, &s) in admitted.iter().enumerate() {
        let seed = seed + 10 * k as u64;
        let start = std::time::Instant::now();
        match (c.quantity, s) {
            (Quantity::Passage { .. }, _) => push(&mut t, "tau", passage(c, s, seed)),
            (Quantity::Search { .. }, _) => push(&mut t, "tau", search_time(c, s, seed)),
            (_, Solver::Exact | Solver::Euler) => sampler(c, &mut t, s, seed),
            (Quantity::Stationary { .. }, Solver::FpStationary) => fp_stationary(c, &mut t),
            _ => {}
        }
        eprintln!("  {s}: {:.2} s", start.elapsed().as_secs_f64());
    }
    match c.quantity {
        Quantity::Stationary { .. } => {
            closed_stationary(c, &mut t, admitted.contains(&Solver::ClosedForm))
        }
        Quantity::Transient { .. } => deterministic_transient(c, &mut t, &admitted),
        _ => {}
    }
    t
}

/// z of every pair of estimates of every scalar: (label, z).
fn pairs(c: &ProtocolCase, t: &Table) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    for (name, ests) in t {
        for (i, a) in ests.iter().enumerate() {
            for b in &ests[i + 1..] {
                let z = (a.value - b.value) / a.err.hypot(b.err);
                let label = format!(
                    "{} {name}: {} {:.6} ± {:.2e} vs {} {:.6} ± {:.2e}",
                    c.name, a.method, a.value, a.err, b.method, b.value, b.err
                );
                eprintln!("{label}: z = {z:.2}");
                out.push((label, z));
            }
        }
    }
    out
}

/// Run the cases `which` selects and hold every pair to the suite's bound.
fn conform(which: impl Fn(&ProtocolCase) -> bool) {
    let most = comparisons_bound();
    let zmax = bonferroni_z(most);
    let mut zs = Vec::new();
    for (i, c) in PROTOCOL_CASES.iter().enumerate().filter(|(_, c)| which(c)) {
        let start = std::time::Instant::now();
        let t = table(c, 50_000 + 1000 * i as u64);
        eprintln!("{}: {:.2} s", c.name, start.elapsed().as_secs_f64());
        let before = zs.len();
        zs.extend(pairs(c, &t));
        let k = admitted(c).len() + references(c);
        assert!(
            zs.len() - before <= scalars(c) * k * k.saturating_sub(1) / 2,
            "{}: more comparisons than counted",
            c.name
        );
    }
    eprintln!("{} comparisons, bound z < {zmax:.2} (m = {most})", zs.len());
    let bad: Vec<_> = zs.iter().filter(|(_, z)| !(z.abs() < zmax)).collect();
    assert!(bad.is_empty(), "beyond z = {zmax:.2}: {bad:#?}");
}

/// The fast tier: the cases marked fast.
#[test]
fn protocol_methods_agree_fast_tier() {
    conform(|c| c.fast);
}

/// The slow tier: the stationary and transient cases not in the fast tier.
#[test]
#[ignore = "slow tier: protocol moments by every admitted method"]
fn protocol_moments_agree_slow_tier() {
    conform(|c| {
        !c.fast
            && matches!(
                c.quantity,
                Quantity::Stationary { .. } | Quantity::Transient { .. }
            )
    });
}

/// The slow tier: the passage and search cases not in the fast tier.
#[test]
#[ignore = "slow tier: protocol first passages by every admitted method"]
fn protocol_passages_agree_slow_tier() {
    conform(|c| {
        !c.fast
            && matches!(
                c.quantity,
                Quantity::Passage { .. } | Quantity::Search { .. }
            )
    });
}

/// Periodic resetting with an exponential refractory period is refused
/// before any work by `fp transient` and the closed forms (they reset the
/// whole density at every multiple of T, held mass included), as
/// `Error::Unsupported` naming `refractory` and a method that runs it; the
/// particle samplers run it.
#[test]
fn periodic_with_exp_refractory_is_refused_by_the_table_alone() {
    let c = PROTOCOL_CASES
        .iter()
        .find(|c| c.name == "tan-periodic-refr-exp")
        .unwrap();
    let p = c.params();
    let linear = Params::new(irtp::DragLaw::Linear, 1.0, 0.5, 0.0, 0.1)
        .and_then(|l| l.with_schedule(p.schedule().clone()))
        .unwrap();
    for (solver, params) in [(Solver::FpTransient, &p), (Solver::ClosedForm, &linear)] {
        match check(solver, params) {
            Err(Error::Unsupported { flag, runners, .. }) => {
                assert_eq!(flag, "refractory", "{solver}");
                assert!(runners.contains("simulate"), "{solver}: {runners}");
            }
            other => panic!("{solver}: {other:?}"),
        }
    }
    assert!(check(Solver::Exact, &p).is_ok() && check(Solver::Euler, &p).is_ok());
    let opts = TransientOptions::default();
    assert!(matches!(
        transient(&p, &opts),
        Err(Error::Unsupported { .. })
    ));
    assert!(matches!(
        linear_moments::moments(&linear, &[0.5]),
        Err(Error::Unsupported { .. })
    ));
}

/// Every case has at least two methods (references included) for its
/// quantity, or says why not; a stated reason goes stale (fails) when a
/// second method learns the case.
#[test]
fn every_case_has_two_methods_or_a_reason() {
    for c in &PROTOCOL_CASES {
        let k = admitted(c).len() + references(c);
        match c.single {
            None => assert!(k >= 2, "{}: {k} method(s): {:?}", c.name, admitted(c)),
            Some(why) => assert!(k < 2, "{}: {k} methods now, stale reason: {why}", c.name),
        }
        assert!(k >= 1 || c.single.is_some(), "{}: no method", c.name);
    }
}

/// Every combination of a case that a method of its quantity refuses is
/// refused as `Error::Unsupported`, one line under 200 characters as the
/// front end prints it (`irtp: error: ` and the flag as `--flag`).
#[test]
fn refusals_are_one_short_line() {
    let mut refused = 0;
    for c in &PROTOCOL_CASES {
        let p = c.params();
        for s in Solver::ALL {
            let Err(e) = check(s, &p) else { continue };
            assert!(
                matches!(e, Error::Unsupported { .. }),
                "{}: {s}: {e:?}",
                c.name
            );
            let line = format!(
                "irtp: error: {}",
                e.message_with(|n| format!("--{}", n.replace('_', "-")))
            );
            assert!(!line.contains('\n'), "{}: {s}: {line}", c.name);
            assert!(line.chars().count() < 200, "{}: {s}: {line}", c.name);
            refused += 1;
        }
    }
    assert!(refused > 0, "no case is refused by any method");
}
