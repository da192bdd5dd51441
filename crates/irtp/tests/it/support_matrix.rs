//! Cross-method agreement over the support table: every drag law × every
//! resetting protocol, each quantity computed by every method the table
//! says runs the cell (`Params::require`), compared with one reference.
//!
//! - Stationary <v²> (time average over the window): exact sampler,
//!   Euler (Richardson over dt and dt/2, which removes the O(rate·dt) bias
//!   and leaves O(dt²)) and the Fokker-Planck solver; reference FP where it
//!   runs the cell, else the exact sampler.
//! - With position resetting, the stationary <x²> (FP's x-weighted chain,
//!   the samplers' ensemble at t_max) as well.
//! - Mean first-passage time of the velocity from v_0 = -0.2 v_u to
//!   v_t = 0.4 v_u: exact first-passage sampler, Euler (Richardson), the
//!   backward equations; reference backward where it runs the cell, else
//!   the exact sampler.
//!
//! Each comparison is a z score against the combined standard error (the
//! deterministic solvers' error estimates added in quadrature), all
//! within the Bonferroni bound of 4 sigma over every comparison made
//! (fixed seeds). A method the table lists must run the cell: its error
//! fails the test; a method it does not list must refuse it.

use crate::common::stats::bonferroni_z;
use irtp::fp::{stationary, StationaryOptions};
use irtp::mfpt::{self, BackwardOptions, Method, ParticleOptions, Problem};
use irtp::model::reset::target::{LaplaceTarget, TargetLaw};
use irtp::model::reset::{
    Clock, NoiseAtReset, Periodic, PositionReset, Refractory, Schedule, Solver, Target,
};
use irtp::parallel::NoProgress;
use irtp::sim::{simulate, Method as SimMethod, SimSpec, TimeGrid};
use irtp::{DragLaw, Params};

/// The laws: every shipped family once, at a Sigma inside its range
/// (`irtp_testkit::laws::CROSS`, the lines marked `in_matrix`).
fn laws() -> Vec<(&'static str, f64)> {
    crate::common::laws::matrix_laws()
}

const LAMBDA: f64 = 0.5;
const RATE: f64 = 1.5;

/// One protocol: a target (in units of v_u), the noise rule, the modifiers.
struct Protocol {
    name: &'static str,
    target: fn(f64) -> Target,
    noise: NoiseAtReset,
    schedule: fn() -> Schedule,
}

fn point(vu: f64) -> Target {
    Target::point(0.1 * vu)
}

fn plain() -> Schedule {
    Schedule::default()
}

fn protocols() -> Vec<Protocol> {
    vec![
        Protocol {
            name: "kept",
            target: point,
            noise: NoiseAtReset::Kept,
            schedule: plain,
        },
        Protocol {
            name: "redrawn",
            target: point,
            noise: NoiseAtReset::Redrawn,
            schedule: plain,
        },
        Protocol {
            name: "gauss",
            target: |vu| Target::gauss(0.1 * vu, 0.2 * vu),
            noise: NoiseAtReset::Kept,
            schedule: plain,
        },
        Protocol {
            name: "uniform",
            target: |vu| Target::uniform(-0.3 * vu, 0.2 * vu),
            noise: NoiseAtReset::Redrawn,
            schedule: plain,
        },
        Protocol {
            name: "laplace",
            target: |vu| Target::Laplace(LaplaceTarget::from_values(&[-0.2 * vu, 0.15 * vu])),
            noise: NoiseAtReset::Kept,
            schedule: plain,
        },
        Protocol {
            name: "position",
            target: point,
            noise: NoiseAtReset::Kept,
            schedule: || Schedule {
                position: Some(PositionReset::new(0.5).unwrap()),
                ..Schedule::default()
            },
        },
        Protocol {
            name: "refractory exp",
            target: point,
            noise: NoiseAtReset::Kept,
            schedule: || Schedule {
                refractory: Some(Refractory::Exp { mean: 0.3 }),
                ..Schedule::default()
            },
        },
        Protocol {
            name: "refractory fixed",
            target: point,
            noise: NoiseAtReset::Redrawn,
            schedule: || Schedule {
                refractory: Some(Refractory::Fixed { duration: 0.3 }),
                ..Schedule::default()
            },
        },
        Protocol {
            name: "renewal gamma",
            target: point,
            noise: NoiseAtReset::Kept,
            // Gamma waiting times of mean 2/3 = 1/RATE.
            schedule: || Schedule {
                clock: Some(Clock::parse("gamma:k=2,theta=0.3333333333333333").unwrap()),
                ..Schedule::default()
            },
        },
        Protocol {
            name: "periodic",
            target: point,
            noise: NoiseAtReset::Kept,
            // The window [4, 16] holds 8 whole periods.
            schedule: || Schedule {
                periodic: Some(Periodic::new(1.5).unwrap()),
                ..Schedule::default()
            },
        },
    ]
}

/// The parameters of a cell.
fn cell(law: &str, sigma: f64, proto: &Protocol) -> Params {
    let drag: DragLaw = law.parse().unwrap();
    let base = Params::new(drag, sigma, LAMBDA, RATE, 0.0).unwrap();
    let vu = base.v_upper();
    let p = base
        .with_reset((proto.target)(vu), proto.noise)
        .unwrap_or_else(|e| panic!("{law} {}: {e}", proto.name));
    let sched = (proto.schedule)();
    if sched.scheduled_clock() {
        p.with_rate(0.0).unwrap().with_schedule(sched).unwrap()
    } else {
        p.with_schedule(sched).unwrap()
    }
}

/// An estimate with its standard error.
#[derive(Clone, Copy, Debug)]
struct Est {
    value: f64,
    se: f64,
}

/// Richardson over dt and dt/2: 2 E(dt/2) - E(dt), errors independent.
fn richardson(coarse: Est, fine: Est) -> Est {
    Est {
        value: 2.0 * fine.value - coarse.value,
        se: (4.0 * fine.se * fine.se + coarse.se * coarse.se).sqrt(),
    }
}

/// Run `f` if the table lists `solver` for `p`; else check it refuses.
fn listed<T>(p: &Params, solver: Solver, f: impl FnOnce() -> T) -> Option<T> {
    match p.require(solver) {
        Ok(()) => Some(f()),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("invalid "), "{solver}: {msg}");
            None
        }
    }
}

/// The Euler step for a cell: 2e-3, or a fifth of the stability bound.
fn euler_dt(p: &Params) -> f64 {
    (0.2 * p.max_euler_dt()).min(2e-3)
}

/// The stationary <v²> (window average) and, with position resetting,
/// <x²> at t_max = 16 (stationary to e^{-16 r}).
fn sim(p: &Params, method: SimMethod, particles: u64, seed: u64) -> (Est, Est) {
    let spec = SimSpec::new(particles, TimeGrid::linear(16.0, 2).unwrap(), 4.0, 10, seed).unwrap();
    let s = simulate(p, &spec, method, &NoProgress).unwrap().summary();
    let v2 = Est {
        value: s.v2,
        se: s.v2_err,
    };
    let x2 = Est {
        value: s.x2_final,
        se: s.x2_final_err,
    };
    (v2, x2)
}

fn richardson2(coarse: (Est, Est), fine: (Est, Est)) -> (Est, Est) {
    (richardson(coarse.0, fine.0), richardson(coarse.1, fine.1))
}

/// Estimates of one quantity: (method, estimate), the reference first.
type Ests = Vec<(&'static str, Est)>;

/// Stationary <v²> and (with position resetting) <x²> by every listed
/// method.
fn stationary_all(p: &Params, seed: u64) -> (Ests, Ests) {
    let (mut v2, mut x2) = (Vec::new(), Vec::new());
    if let Some(s) = listed(p, Solver::FpStationary, || {
        stationary(p, &StationaryOptions::default()).unwrap()
    }) {
        let err = s.coarse.as_ref().map_or(0.0, |c| (c.v2 - s.v2).abs());
        v2.push((
            "fp",
            Est {
                value: s.v2,
                se: err,
            },
        ));
        if let Some(x) = s.x2 {
            // The mesh error of <x²>: relative as that of <v²>, times 10.
            x2.push((
                "fp",
                Est {
                    value: x,
                    se: 10.0 * x * err / s.v2,
                },
            ));
        }
    }
    let position = p.schedule().position.is_some();
    let mut push = |name, (a, b): (Est, Est)| {
        v2.push((name, a));
        if position {
            x2.push((name, b));
        }
    };
    if let Some(e) = listed(p, Solver::Exact, || sim(p, SimMethod::Exact, 20_000, seed)) {
        push("exact", e);
    }
    if let Some(e) = listed(p, Solver::Euler, || {
        let dt = euler_dt(p);
        richardson2(
            sim(p, SimMethod::euler(dt), 1_000, seed + 1),
            sim(p, SimMethod::euler(0.5 * dt), 1_000, seed + 2),
        )
    }) {
        push("euler", e);
    }
    (v2, x2)
}

fn tau_particles(prob: &Problem, method: Method) -> Est {
    let s = mfpt::solve(prob, &method, &NoProgress)
        .unwrap()
        .summary()
        .unwrap();
    Est {
        value: s.tau,
        se: s.tau_err,
    }
}

/// The MFPT by every listed method: (method, estimate).
fn tau_all(p: &Params, seed: u64) -> Vec<(&'static str, Est)> {
    let vu = p.v_upper();
    let prob = Problem::new(p.clone(), -0.2 * vu, 0.4 * vu).unwrap();
    let run = |particles, seed| ParticleOptions {
        particles,
        t_max: f64::INFINITY,
        seed,
    };
    let mut out = Vec::new();
    if let Some(b) = listed(p, Solver::Backward, || {
        mfpt::backward::solve(&prob, &BackwardOptions::default()).unwrap()
    }) {
        let err = if b.error_estimate.is_finite() {
            b.error_estimate
        } else {
            0.0
        };
        out.push((
            "backward",
            Est {
                value: b.tau,
                se: err,
            },
        ));
    }
    if let Some(e) = listed(p, Solver::MfptExact, || {
        tau_particles(&prob, Method::Exact(run(8_000, seed)))
    }) {
        out.push(("exact", e));
    }
    if let Some(e) = listed(p, Solver::MfptEuler, || {
        let dt = euler_dt(p);
        let at = |dt, seed| {
            tau_particles(
                &prob,
                Method::Euler {
                    dt,
                    run: ParticleOptions {
                        t_max: 1e4,
                        ..run(2_000, seed)
                    },
                },
            )
        };
        richardson(at(dt, seed + 1), at(0.5 * dt, seed + 2))
    }) {
        out.push(("euler", e));
    }
    out
}

/// z scores of every estimate against the first (the reference).
fn z_scores(what: &str, ests: &[(&'static str, Est)]) -> Vec<(String, f64)> {
    let Some((rname, r)) = ests.first() else {
        return Vec::new();
    };
    ests[1..]
        .iter()
        .map(|(name, e)| {
            let se = r.se.hypot(e.se);
            let z = (e.value - r.value) / se;
            eprintln!(
                "{what}: {name} {:.6} ± {:.2e} vs {rname} {:.6} ± {:.2e}: z = {z:.2}",
                e.value, e.se, r.value, r.se
            );
            (format!("{what} {name} vs {rname}"), z)
        })
        .collect()
}

/// Every protocol for the law `laws()[i]`. The Bonferroni bound counts the
/// most comparisons the whole matrix can make (two per quantity and cell:
/// three methods, one reference; three quantities with position
/// resetting), which is conservative.
fn law_agrees_across_methods(i: usize) {
    let (law, sigma) = laws()[i];
    let most = laws().len() * protocols().len() * 6;
    let bound = bonferroni_z(most);
    let mut zs = Vec::new();
    let mut cells_with_two = 0;
    for (j, proto) in protocols().iter().enumerate() {
        let p = cell(law, sigma, proto);
        let seed = 10_000 + 100 * (i * 16 + j) as u64;
        let what = format!("{law} {}", proto.name);
        let (v2, x2) = stationary_all(&p, seed);
        let tau = tau_all(&p, seed + 50);
        cells_with_two += usize::from(v2.len() > 1 || tau.len() > 1);
        zs.extend(z_scores(&format!("{what} <v²>"), &v2));
        zs.extend(z_scores(&format!("{what} <x²>"), &x2));
        zs.extend(z_scores(&format!("{what} tau"), &tau));
    }
    assert!(zs.len() <= most);
    assert_eq!(
        cells_with_two,
        protocols().len(),
        "{law}: a cell with one method"
    );
    for (name, z) in &zs {
        assert!(z.abs() < bound, "{name}: z = {z:.2} (bound {bound:.2})");
    }
}

/// The time-dependent Fokker-Planck methods run every protocol the table
/// lists for them and refuse the others (tan and linear laws): `fp
/// transient` (TR-BDF2, 200 cells, t = 0.5) and `fp msd` (50 cells, one
/// level, t = 0.5) each with mass 1 at t (1e-9) and, where `fp
/// stationary` runs the cell, `fp transient` at t = 12 within 1e-3
/// relative of its `<v²>` (the relaxation rates are >= min(r, 2 lambda) = 1).
#[test]
fn time_dependent_fp_methods_run_what_the_table_lists() {
    use irtp::fp::{msd, transient, MsdOptions, TransientOptions};
    for (law, sigma) in [laws()[0], laws()[2]] {
        for proto in protocols() {
            let p = cell(law, sigma, &proto);
            let what = format!("{law} {}", proto.name);
            let tr = listed(&p, Solver::FpTransient, || {
                let o = |t: f64| TransientOptions {
                    cells: 200,
                    t_max: t,
                    times: vec![t],
                    ..TransientOptions::default()
                };
                let tr = transient(&p, &o(0.5)).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert!((tr.mass[0] - 1.0).abs() < 1e-9, "{what}: {}", tr.mass[0]);
                transient(&p, &o(12.0)).unwrap_or_else(|e| panic!("{what}: {e}"))
            });
            let st = listed(&p, Solver::FpStationary, || {
                let o = StationaryOptions {
                    cells: 800,
                    mesh: irtp::fp::Mesh::Graded,
                    extrapolate: true,
                };
                stationary(&p, &o).unwrap().v2
            });
            if let (Some(tr), Some(v2)) = (&tr, st) {
                let rel = (tr.v2[0] / v2 - 1.0).abs();
                assert!(
                    rel < 1e-3,
                    "{what}: transient {} vs stationary {v2}",
                    tr.v2[0]
                );
            }
            listed(&p, Solver::FpMsd, || {
                let o = MsdOptions {
                    cells: 50,
                    levels: 1,
                    times: vec![0.5],
                    ..MsdOptions::default()
                };
                let m = msd(&p, &o, &NoProgress).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert!((m.mass[0] - 1.0).abs() < 1e-9, "{what}: {}", m.mass[0]);
            });
        }
    }
}

/// The laws in `SHARDS` tests (law i in shard i mod SHARDS), so the
/// matrix runs in parallel and a new law needs no line here.
const SHARDS: usize = 3;

fn shard(k: usize) {
    for i in (k..laws().len()).step_by(SHARDS) {
        law_agrees_across_methods(i);
    }
}

#[test]
fn laws_shard_1_of_3() {
    shard(0);
}

#[test]
fn laws_shard_2_of_3() {
    shard(1);
}

#[test]
fn laws_shard_3_of_3() {
    shard(2);
}

/// Every registered drag law is in the matrix.
#[test]
fn every_law_family_is_in_the_matrix() {
    let kinds: Vec<&str> = laws()
        .iter()
        .map(|(s, _)| crate::common::laws::kind(s))
        .collect();
    for d in DragLaw::examples() {
        let spec = d.to_string();
        let k = crate::common::laws::kind(&spec);
        assert!(
            kinds.contains(&k),
            "drag law '{k}' is not in the support matrix"
        );
    }
}

/// docs/reference/support.md carries the table the methods consult,
/// rendered by `irtp::model::support_table::markdown` between its markers;
/// `IRTP_BLESS=1` rewrites the block.
#[test]
fn the_support_page_is_the_code_s_table() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/reference/support.md");
    let page = std::fs::read_to_string(&path).expect("docs/reference/support.md");
    let (begin, end) = (
        "<!-- generated: support table -->\n",
        "<!-- end of the generated table -->",
    );
    let a = page.find(begin).expect("the begin marker") + begin.len();
    let b = page.find(end).expect("the end marker");
    let table = irtp::model::support_table::markdown();
    if std::env::var_os("IRTP_BLESS").is_some() {
        std::fs::write(&path, format!("{}{table}{}", &page[..a], &page[b..])).unwrap();
        return;
    }
    assert_eq!(
        &page[a..b],
        table,
        "docs/reference/support.md is stale: rerun with IRTP_BLESS=1"
    );
}
