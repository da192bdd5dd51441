//! Range fuzz of every command's library entry point (`irtp_app`): rates,
//! amplitudes, times and counts drawn log-uniformly over 1e-300..1e300, with
//! the edges (0, subnormals, negative values, values next to the bounds such
//! as Sigma just below tanh's limit 1). Every case must give either a clean
//! error (bad input or numerical failure, one line) or an answer that passes
//! the invariants its results claim; never a panic, a NaN or inf where none
//! is documented, a wrong answer with success, or an unbounded run time.
//!
//! Every case runs under `--max-work 2e7 --max-memory 2e8`, so an accepted
//! case costs well under a second; a case slower than [`MAX_CASE_SECONDS`]
//! fails. The cases are drawn from a fixed seed (reproducible in CI); all
//! failures of a command are collected and reported together;
//! `IRTP_FUZZ_SHOW_REFUSALS=1` prints every refusal (to see what a generator
//! exercises); `IRTP_FUZZ_EXPLORE=K,N` draws N times the cases from other
//! seeds (K = 1, 2, ...) to look further by hand.

use clap::Parser;
use irtp::{DragLaw, Params};
use irtp_app::{self as app, Cli, Context, Outcome, Table};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use serde_json::Value;
use std::time::{Duration, Instant};

/// Wall-time bound of one case (generous: the machine may be loaded; an
/// accepted case costs at most ~2e7 operations).
const MAX_CASE_SECONDS: u64 = 20;

/// Meshes (`--cells`) below this may have no Richardson error estimate
/// (halving them gives the same mesh).
const SMALL_MESH: f64 = 20.0;

/// Relative slack of the mass checks (quadrature sums of densities).
const MASS_TOL: f64 = 1e-6;

const SEED: [u8; 32] = *b"irtp range fuzz, fixed seed 0001";

mod surfaces;

/// One drawn command line with the model it describes.
#[derive(Clone, Debug)]
struct Case {
    args: Vec<String>,
    /// The drawn law; None for a drawn spec that does not parse.
    drag: Option<DragLaw>,
    sigma: f64,
    lambda: f64,
    rate: f64,
    vr: f64,
    /// With a drawn reset protocol: the velocities a reset can land on,
    /// [lo, hi] (resets may happen at rate 0: a periodic protocol).
    reach: Option<(f64, f64)>,
}

impl Case {
    /// v_u of the drawn model (when it is admissible).
    fn v_upper(&self) -> Option<f64> {
        Params::new(
            self.drag.clone()?,
            self.sigma,
            self.lambda,
            self.rate,
            self.vr,
        )
        .ok()
        .map(|p| p.v_upper())
    }

    /// The least time to go from v0 (or, after a reset, from where a reset
    /// lands) to vt at reset rate `rate`: the velocity changes at most at
    /// |g(v)| + Sigma <= 2 Sigma.
    fn least_time(&self, rate: f64, v0: f64, vt: f64) -> f64 {
        let direct = (vt - v0).abs();
        // A reset that lands on or beyond vt, seen from v0, is a passage
        // at the reset instant; otherwise it shortens the way to vt.
        let across = |lo: f64, hi: f64| {
            let gap = if v0 < vt { vt - hi } else { lo - vt };
            direct.min(gap.max(0.0))
        };
        let d = match self.reach {
            Some((lo, hi)) => across(lo, hi),
            None if rate > 0.0 => across(self.vr, self.vr),
            None => direct,
        };
        d / (2.0 * self.sigma)
    }
}

fn s(x: f64) -> String {
    format!("{x:e}")
}

/// Any real: log-uniform magnitudes 1e-300..1e300 of either sign, the edges.
fn any_real() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => (-300.0f64..300.0).prop_map(|e| 10f64.powf(e)),
        1 => (-300.0f64..300.0).prop_map(|e| -(10f64.powf(e))),
        2 => prop::sample::select(vec![
            0.0,
            -0.0,
            5e-324,
            -5e-324,
            f64::MIN_POSITIVE,
            1e-300,
            1e300,
            f64::MAX,
            -1.0,
            1.0,
            1.0 - f64::EPSILON / 2.0,
            1.0 + f64::EPSILON,
        ]),
    ]
}

/// A positive quantity: mostly where answers exist (1e-3..1e3, log-uniform),
/// else anything.
fn magnitude() -> impl Strategy<Value = f64> {
    prop_oneof![
        9 => (-3.0f64..3.0).prop_map(|e| 10f64.powf(e)),
        1 => any_real(),
    ]
}

/// Sigma: as [`magnitude`], plus values next to tanh's limit 1.
fn sigma() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => magnitude(),
        1 => prop::sample::select(vec![
            1.0 - f64::EPSILON / 2.0,
            1.0 - 1e-12,
            1.0 - 1e-6,
            0.999,
            1.0,
            1.0 + f64::EPSILON,
        ]),
    ]
}

/// A fraction of v_u: inside, next to the edges, beyond them.
fn fraction() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -1.0f64..1.0,
        1 => prop::sample::select(vec![
            0.0,
            1.0 - f64::EPSILON / 2.0,
            -(1.0 - f64::EPSILON / 2.0),
            1.0 - 1e-9,
            -(1.0 - 1e-9),
            1.0,
            -1.0,
            1.0 + 1e-9,
        ]),
    ]
}

/// A velocity: a fraction of v_u (when the model has one), or any real.
fn velocity(vu: f64) -> impl Strategy<Value = f64> {
    prop_oneof![9 => fraction().prop_map(move |f| f * vu), 1 => any_real()]
}

/// A count: small values and their edges, or log-uniform up to 1e12.
fn count() -> impl Strategy<Value = String> {
    prop_oneof![
        1 => prop::sample::select(vec![0u64, 1, 2, 3, 4, 5]),
        8 => (0.0f64..3.5).prop_map(|e| 10f64.powf(e) as u64),
        1 => (0.0f64..12.0).prop_map(|e| 10f64.powf(e) as u64),
    ]
    .prop_map(|n| n.to_string())
}

fn drag() -> impl Strategy<Value = DragLaw> {
    prop::sample::select(vec![
        DragLaw::Tan,
        DragLaw::Tanh,
        DragLaw::Linear,
        DragLaw::Cubic,
    ])
}

/// The model flags, the reset velocity drawn relative to v_u. `reset`: the
/// command takes `--reset-velocity`.
fn model(reset: bool) -> impl Strategy<Value = Case> {
    (drag(), sigma(), magnitude(), magnitude())
        .prop_flat_map(move |(drag, sigma, lambda, rate)| {
            let vu = Params::new(drag.clone(), sigma, 0.0, 0.0, 0.0).map_or(1.0, |p| p.v_upper());
            let vr = if reset {
                prop_oneof![1 => Just(0.0), 2 => velocity(vu)].boxed()
            } else {
                Just(0.0).boxed()
            };
            (Just((drag, sigma, lambda, rate)), vr)
        })
        .prop_map(move |((drag, sigma, lambda, rate), vr)| {
            let mut args = vec![
                "--drag".into(),
                drag.to_string(),
                "--sigma".into(),
                s(sigma),
                "--lambda".into(),
                s(lambda),
                "--rate".into(),
                s(rate),
            ];
            if reset {
                args.extend(["--reset-velocity".into(), s(vr)]);
            }
            Case {
                args,
                drag: Some(drag),
                sigma,
                lambda,
                rate,
                vr,
                reach: None,
            }
        })
}

/// `case` with the command words in front and `flags` after its model flags.
fn with(words: &[&str], mut case: Case, flags: Vec<String>) -> Case {
    let mut args: Vec<String> = words.iter().map(|w| w.to_string()).collect();
    args.append(&mut case.args);
    args.extend(flags);
    case.args = args;
    case
}

fn flag(name: &str, value: String) -> Vec<String> {
    vec![format!("--{name}"), value]
}

/// `IRTP_FUZZ_EXPLORE=K,N`: draw N times the cases from seeds perturbed by K
/// (to look further afield by hand; CI and plain `cargo test` use the fixed
/// seeds, K = 0, N = 1).
fn explore() -> (u8, u32) {
    let v = std::env::var("IRTP_FUZZ_EXPLORE").unwrap_or_default();
    let mut it = v.split(',').map(|x| x.trim().parse::<u32>().ok());
    match (it.next().flatten(), it.next().flatten()) {
        (Some(k), Some(n)) if n >= 1 => (k as u8, n),
        _ => (0, 1),
    }
}

/// The generator of the fuzz named `name`: the fixed seed with the name
/// (and the [`explore`] perturbation) mixed in.
fn rng(name: &str) -> TestRng {
    let mut seed = SEED;
    for (b, n) in seed.iter_mut().zip(name.bytes()) {
        *b ^= n;
    }
    seed[31] ^= explore().0;
    TestRng::from_seed(RngAlgorithm::ChaCha, &seed)
}

/// Draw `cases` cases of `strategy` from the fixed seed, run each through
/// [`check`], and fail with every failure listed.
fn fuzz(name: &str, cases: u32, strategy: impl Strategy<Value = Case>) {
    let config = Config {
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config, rng(name));
    let mut failures = Vec::new();
    let (mut ok, mut refused) = (0, 0);
    for _ in 0..cases * explore().1 {
        let case = strategy.new_tree(&mut runner).expect("a case").current();
        match check(&case) {
            Ok(true) => ok += 1,
            Ok(false) => refused += 1,
            Err(why) => failures.push(format!("irtp {}: {why}", case.args.join(" "))),
        }
    }
    eprintln!(
        "{name}: {ok} answered, {refused} refused, {} failed",
        failures.len()
    );
    assert!(failures.is_empty(), "{name}:\n{}", failures.join("\n"));
}

/// Run one case: Ok(true) for a checked answer, Ok(false) for a clean
/// refusal, Err(what went wrong).
fn check(case: &Case) -> Result<bool, String> {
    let mut argv = vec!["irtp".to_string()];
    argv.extend(case.args.iter().cloned());
    argv.extend(["--max-work", "2e7", "--max-memory", "2e8"].map(String::from));
    let cli = match Cli::try_parse_from(&argv) {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind::*;
            return match e.kind() {
                ValueValidation | InvalidValue => Ok(false),
                k => Err(format!("clap refused the drawn flags: {k:?}: {e}")),
            };
        }
    };
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let start = Instant::now();
        let r = std::panic::catch_unwind(|| {
            let ctx = Context {
                reporter: &app::Quiet,
                argv: vec![],
            };
            app::run(&cli.command, &ctx)
        });
        let _ = tx.send((r, start.elapsed()));
    });
    let (result, wall) = match rx.recv_timeout(Duration::from_secs(MAX_CASE_SECONDS)) {
        Ok(x) => x,
        Err(_) => return Err(format!("no answer within {MAX_CASE_SECONDS} s")),
    };
    if wall > Duration::from_secs(MAX_CASE_SECONDS) {
        return Err(format!("took {wall:?}"));
    }
    match result {
        Err(_) => Err("panicked".into()),
        Ok(Err(e)) => {
            let msg = e.to_string();
            if !(e.is_input_error() || e.is_numerical()) {
                Err(format!("undocumented error kind: {e:?}"))
            } else if msg.trim().is_empty() || msg.contains('\n') {
                Err(format!("error message not one line: {msg:?}"))
            } else {
                if std::env::var_os("IRTP_FUZZ_SHOW_REFUSALS").is_some() {
                    eprintln!("refused: irtp {}: {msg}", case.args.join(" "));
                }
                Ok(false)
            }
        }
        Ok(Ok(o)) => invariants(case, &o).map(|()| true),
    }
}

fn ensure(ok: bool, what: impl FnOnce() -> String) -> Result<(), String> {
    if ok {
        Ok(())
    } else {
        Err(what())
    }
}

fn column<'a>(t: &'a Table, name: &str) -> &'a [f64] {
    let i = t.header.iter().position(|h| h == name);
    &t.columns[i.unwrap_or_else(|| panic!("{} has no column {name}", t.name))]
}

fn num(v: &Value, key: &str) -> Result<f64, String> {
    v[key]
        .as_f64()
        .ok_or_else(|| format!("{key} is not a number: {}", v[key]))
}

/// Every JSON null (a NaN or inf serialised) outside `nullable`.
fn nulls(v: &Value, path: &str, nullable: &[&str], found: &mut Vec<String>) {
    match v {
        Value::Null if !nullable.iter().any(|k| path.ends_with(k)) => found.push(path.into()),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| nulls(x, &format!("{path}[{i}]"), nullable, found)),
        Value::Object(o) => o
            .iter()
            .for_each(|(k, x)| nulls(x, &format!("{path}.{k}"), nullable, found)),
        _ => {}
    }
}

fn no_nulls(v: &Value, nullable: &[&str]) -> Result<(), String> {
    let mut found = Vec::new();
    nulls(v, "", nullable, &mut found);
    ensure(found.is_empty(), || format!("null (NaN/inf) at {found:?}"))
}

/// Every table entry finite, except in `except` columns.
fn finite_tables(o: &Outcome, except: &[&str]) -> Result<(), String> {
    for t in &o.results.tables {
        for (h, c) in t.header.iter().zip(&t.columns) {
            if except.contains(&h.as_str()) {
                continue;
            }
            if let Some(x) = c.iter().find(|x| !x.is_finite()) {
                return Err(format!("{h} = {x} in {}.csv", t.name));
            }
        }
    }
    Ok(())
}

/// 0 <= x <= vu² (with rounding slack).
fn in_v2_range(what: &str, x: f64, vu: f64) -> Result<(), String> {
    ensure(x >= 0.0 && x <= vu * vu * (1.0 + 1e-12), || {
        format!("{what} = {x} outside [0, v_u² = {}]", vu * vu)
    })
}

fn nonneg(what: &str, xs: &[f64]) -> Result<(), String> {
    match xs.iter().position(|x| !(*x >= 0.0)) {
        Some(i) => Err(format!("{what}[{i}] = {} < 0", xs[i])),
        None => Ok(()),
    }
}

fn mass_one(what: &str, m: f64) -> Result<(), String> {
    ensure((m - 1.0).abs() <= MASS_TOL, || {
        format!("{what} mass = {m}, not 1")
    })
}

fn invariants(case: &Case, o: &Outcome) -> Result<(), String> {
    let vu = case
        .v_upper()
        .ok_or_else(|| "an answer for an inadmissible model".to_string())?;
    let json = &o.results.json;
    match o.command {
        "analytic" => analytic(json, o, vu),
        "simulate" => simulate(json, o, vu),
        "fp stationary" => fp_stationary(case, json, o, vu),
        "fp transient" => fp_transient(json, o, vu),
        "mfpt" => mfpt_direct(case, json, o),
        "mfpt scan" => mfpt_scan(case, o),
        "mfpt optimize" => mfpt_optimize(case, json, o),
        c => Err(format!("unexpected command {c}")),
    }
}

fn analytic(json: &Value, o: &Outcome, vu: f64) -> Result<(), String> {
    no_nulls(json, &[])?;
    finite_tables(o, &[])?;
    in_v2_range("v2", num(json, "v2")?, vu)?;
    if json.get("d_eff").is_some() {
        // Linear drag with resetting: the noise moments (N3)-(N6), no density.
        let d = num(json, "d_eff")?;
        return ensure(d >= 0.0 && d.is_finite(), || format!("d_eff = {d}"));
    }
    let v4 = num(json, "v4")?;
    ensure(v4 >= 0.0 && v4 <= vu.powi(4) * (1.0 + 1e-12), || {
        format!("v4 = {v4}")
    })?;
    let t = o.results.table("density").ok_or("no density table")?;
    nonneg("p", column(t, "p"))?;
    let cdf = column(t, "cdf");
    ensure(cdf.iter().all(|c| (0.0..=1.0 + 1e-12).contains(c)), || {
        "cdf outside [0, 1]".into()
    })?;
    ensure(cdf.windows(2).all(|w| w[1] >= w[0] - 1e-12), || {
        "cdf decreases".into()
    })?;
    ensure(column(t, "v").iter().all(|v| v.abs() <= vu), || {
        "v outside (v_l, v_u)".into()
    })
}

/// Sum of p * dv over equal bins of the table's v column spanning [-vu, vu].
fn binned_mass(v: &[f64], p: &[f64], vu: f64) -> f64 {
    let dv = 2.0 * vu / v.len() as f64;
    p.iter().sum::<f64>() * dv
}

fn simulate(json: &Value, o: &Outcome, vu: f64) -> Result<(), String> {
    // Documented: the counters of the other method are null (exact: events,
    // events_per_s; Euler: steps, particle_steps_per_s, event_sampling, dt).
    let (own, other): (&[&str], &[&str]) = if json["method"] == "exact" {
        (
            &["events", "events_per_s"],
            &["steps", "particle_steps_per_s", "event_sampling", "dt"],
        )
    } else {
        (
            &["steps", "particle_steps_per_s", "event_sampling", "dt"],
            &["events", "events_per_s"],
        )
    };
    // Documented: null without --reset-position (the P_s(x) histogram's
    // range and the mass outside it).
    let mut nullable = vec![
        "out",
        "d_eff_msd",
        "d_eff_msd_err",
        "x_range",
        "x_outside",
        "x_outside_err",
    ];
    nullable.extend_from_slice(other);
    no_nulls(json, &nullable)?;
    for key in own {
        ensure(!json[*key].is_null(), || format!("{key} is null"))?;
    }
    finite_tables(o, &[])?;
    in_v2_range("v2", num(json, "v2")?, vu)?;
    in_v2_range("v2_final", num(json, "v2_final")?, vu)?;
    let m = o.results.table("moments").ok_or("no moments table")?;
    for (i, x) in column(m, "v2").iter().enumerate() {
        in_v2_range(&format!("moments v2[{i}]"), *x, vu)?;
    }
    nonneg("x2", column(m, "x2"))?;
    let d = o.results.table("density").ok_or("no density table")?;
    let (v, p, pf) = (column(d, "v"), column(d, "p"), column(d, "p_final"));
    nonneg("p", p)?;
    nonneg("p_final", pf)?;
    // Atoms (docs/output-formats.md): the time spent exactly at an atom's
    // velocity is in no bin, so Σ p dv + Σ mass = 1; at t_max the
    // particles held at an atom are in no bin of p_final either.
    let atoms: f64 = json["atoms"]
        .as_array()
        .ok_or("no atoms field")?
        .iter()
        .map(|a| a["mass"].as_f64().unwrap_or(f64::NAN))
        .sum();
    ensure((0.0..=1.0 + MASS_TOL).contains(&atoms), || {
        format!("atoms' mass = {atoms}")
    })?;
    let mf = binned_mass(v, pf, vu);
    if atoms == 0.0 {
        mass_one("p_final", mf)?;
    } else {
        ensure(mf <= 1.0 + MASS_TOL, || format!("p_final mass = {mf} > 1"))?;
    }
    // The time-averaged density is empty when no recording time lies in the
    // window [burn_in, t_max].
    let mp = binned_mass(v, p, vu);
    if mp != 0.0 {
        mass_one("p + atoms", mp + atoms)?;
    }
    Ok(())
}

/// Whether `d_eff_err` is documented to be null for `case`
/// (docs/output-formats.md): `--no-extrapolate`, fewer than 32 cells,
/// λ = 0, or no D_eff (position resetting).
fn d_eff_err_null(case: &Case) -> bool {
    let flag = |f: &str| case.args.iter().position(|a| a == f);
    let cells = flag("--cells")
        .and_then(|i| case.args.get(i + 1))
        .and_then(|c| c.parse::<usize>().ok());
    flag("--no-extrapolate").is_some()
        || cells.is_some_and(|c| c < 32)
        || case.lambda == 0.0
        || flag("--reset-position").is_some()
}

fn fp_stationary(case: &Case, json: &Value, o: &Outcome, vu: f64) -> Result<(), String> {
    finite_tables(o, &[])?;
    in_v2_range("v2", num(json, "v2")?, vu)?;
    if d_eff_err_null(case) {
        ensure(json["d_eff_err"].is_null(), || {
            "d_eff_err where none is documented".into()
        })?;
    } else {
        let e = num(json, "d_eff_err")?;
        ensure(e >= 0.0, || format!("d_eff_err = {e} < 0"))?;
    }
    if case.args.iter().any(|a| a == "--reset-position") {
        // Documented: with position resetting x is stationary, D_eff is
        // omitted (null) and x_moments is given.
        no_nulls(json, &["fine", "coarse", "grading", "d_eff", "d_eff_err"])?;
        ensure(json["d_eff"].is_null(), || {
            "d_eff with position resetting".into()
        })?;
    } else if case.lambda == 0.0 {
        // Documented: D_eff = ∞ at lambda = 0 (ballistic), JSON null.
        no_nulls(
            json,
            &[
                "fine",
                "coarse",
                "grading",
                "d_eff",
                "d_eff_err",
                "x_moments",
            ],
        )?;
        ensure(json["d_eff"].is_null(), || {
            "finite d_eff at lambda = 0".into()
        })?;
    } else {
        // fine, coarse: null without Richardson extrapolation; their
        // x_moments null without --reset-position; d_eff_err checked above.
        no_nulls(
            json,
            &["fine", "coarse", "grading", "x_moments", "d_eff_err"],
        )?;
        let d = num(json, "d_eff")?;
        ensure(d >= 0.0, || format!("d_eff = {d} < 0"))?;
    }
    mass_one("summary", num(json, "mass")?)?;
    let t = o.results.table("density").ok_or("no density table")?;
    for c in ["p", "p_plus", "p_minus"] {
        nonneg(c, column(t, c))?;
    }
    // With a refractory period the held point mass is not in the density.
    let held = num(json, "refractory_mass")?;
    ensure((0.0..=1.0).contains(&held), || {
        format!("refractory_mass = {held}")
    })?;
    let (p, dv) = (column(t, "p"), column(t, "dv"));
    let continuous: f64 = p.iter().zip(dv).map(|(p, d)| p * d).sum();
    mass_one("density.csv + refractory_mass", continuous + held)
}

fn fp_transient(json: &Value, o: &Outcome, vu: f64) -> Result<(), String> {
    // dt: null for the adaptive scheme (documented).
    let adaptive = json["scheme"] == "trbdf2";
    no_nulls(json, if adaptive { &[".dt"] } else { &[] })?;
    finite_tables(o, &[])?;
    let m = o.results.table("moments").ok_or("no moments table")?;
    for (i, x) in column(m, "v2").iter().enumerate() {
        in_v2_range(&format!("v2[{i}]"), *x, vu)?;
    }
    for (i, x) in column(m, "mass").iter().enumerate() {
        mass_one(&format!("moments row {i}"), *x)?;
    }
    let s = o.results.table("snapshots").ok_or("no snapshots table")?;
    for c in ["p", "p_plus", "p_minus"] {
        nonneg(c, column(s, c))?;
    }
    Ok(())
}

/// tau at or above its least value (rounding slack of the solvers: 1e-9).
fn tau_bound(what: &str, tau: f64, least: f64) -> Result<(), String> {
    ensure(tau >= 0.0 && tau >= least * (1.0 - 1e-9), || {
        format!("{what} = {tau} below the least passage time {least}")
    })
}

/// The value after `--name` in the case's flags.
fn flag_value(case: &Case, name: &str) -> Option<f64> {
    let i = case.args.iter().position(|a| a == name)?;
    case.args.get(i + 1)?.parse().ok()
}

fn mfpt_direct(case: &Case, json: &Value, o: &Outcome) -> Result<(), String> {
    let (v0, vt) = (
        flag_value(case, "--v0").unwrap(),
        flag_value(case, "--vt").unwrap(),
    );
    let least = case.least_time(case.rate, v0, vt);
    finite_tables(o, &[])?;
    let censored = json.get("censored").and_then(Value::as_u64);
    if let Some(c) = censored {
        let particles = num(json, "particles")? as u64;
        let t_max = num(json, "t_max")?;
        ensure(c <= particles, || format!("censored {c} > particles"))?;
        let rmst = num(json, "rmst")?;
        ensure(rmst >= 0.0 && rmst <= t_max, || {
            format!("rmst = {rmst} outside [0, t_max]")
        })?;
        if c > 0 {
            no_nulls(
                json,
                &[
                    "tau",
                    "tau_plus",
                    "tau_minus",
                    "tau_err",
                    "tau_plus_err",
                    "tau_minus_err",
                ],
            )?;
            ensure(json["tau"].is_null(), || {
                "tau reported over censored particles".into()
            })?;
            ensure(num(json, "tau_lower_bound")? == rmst, || {
                "tau_lower_bound != rmst".into()
            })?;
            return Ok(());
        }
        no_nulls(json, &["tau_lower_bound"])?;
        ensure(json["tau_lower_bound"].is_null(), || {
            "tau_lower_bound without censoring".into()
        })?;
    } else {
        // error_estimate is NaN ("not computed") where halving the mesh
        // gives the same mesh: the smallest meshes only.
        let small = flag_value(case, "--cells").is_some_and(|c| c < SMALL_MESH);
        no_nulls(json, if small { &["error_estimate"] } else { &[] })?;
        let t = o.results.table("profile").ok_or("no profile table")?;
        for c in ["tau_plus", "tau_minus", "tau"] {
            // The node v_t, where tau± = 0 exactly, comes out as ±1e-17:
            // round-off of the solve, allowed at 1e-12 of the largest tau.
            let col = column(t, c);
            let scale = col.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
            if let Some(i) = col.iter().position(|&x| !(x >= -1e-12 * scale)) {
                return Err(format!("profile {c}[{i}] = {} < 0", col[i]));
            }
        }
    }
    for k in ["tau", "tau_plus", "tau_minus"] {
        tau_bound(k, num(json, k)?, least)?;
    }
    Ok(())
}

fn mfpt_scan(case: &Case, o: &Outcome) -> Result<(), String> {
    let t = o.results.table("mfpt_scan").ok_or("no mfpt_scan table")?;
    let over_vt = t.header[0] == "vt";
    let sim = t.header.iter().any(|h| h == "tau_sim");
    // tau beyond the f64 range is marked inf; a censored point has NaN tau_sim.
    let marked = ["tau", "tau_plus", "tau_minus", "error_estimate"];
    let censorable = [
        "tau_sim",
        "tau_sim_err",
        "tau_plus_sim",
        "tau_plus_sim_err",
        "tau_minus_sim",
        "tau_minus_sim_err",
    ];
    let mut except: Vec<&str> = marked.to_vec();
    except.extend(censorable);
    finite_tables(o, &except)?;
    let v0 = flag_value(case, "--v0").unwrap();
    let small = flag_value(case, "--cells").is_some_and(|c| c < SMALL_MESH);
    for i in 0..t.len() {
        let x = t.columns[0][i];
        let (rate, vt) = if over_vt {
            (case.rate, x)
        } else {
            (x, flag_value(case, "--vt").unwrap())
        };
        let least = case.least_time(rate, v0, vt);
        let overflow = column(t, "tau")[i] == f64::INFINITY;
        for c in marked {
            let y = column(t, c)[i];
            // error_estimate: NaN ("not computed") at an overflowed point or
            // on the smallest meshes.
            let nan_ok = c == "error_estimate" && (overflow || small);
            ensure(
                y.is_finite() || y == f64::INFINITY || (nan_ok && y.is_nan()),
                || format!("{c}[{i}] = {y}"),
            )?;
            ensure(
                !(overflow && y.is_finite() && c != "error_estimate"),
                || format!("{c}[{i}] = {y} finite at an overflowed point"),
            )?;
        }
        for c in ["tau", "tau_plus", "tau_minus"] {
            tau_bound(&format!("{c}[{i}]"), column(t, c)[i], least)?;
        }
        if sim {
            let censored = column(t, "censored")[i];
            for c in censorable {
                let y = column(t, c)[i];
                ensure(y.is_finite() || (censored > 0.0 && y.is_nan()), || {
                    format!("{c}[{i}] = {y} with {censored} censored")
                })?;
            }
            if censored == 0.0 {
                for c in ["tau_sim", "tau_plus_sim", "tau_minus_sim"] {
                    tau_bound(&format!("{c}[{i}]"), column(t, c)[i], least)?;
                }
            }
        }
    }
    Ok(())
}

fn mfpt_optimize(case: &Case, json: &Value, o: &Outcome) -> Result<(), String> {
    no_nulls(json, &[])?;
    finite_tables(o, &[])?;
    let (v0, vt) = (
        flag_value(case, "--v0").unwrap(),
        flag_value(case, "--vt").unwrap(),
    );
    let (r_opt, tau_opt, tau_r0) = (
        num(json, "r_opt")?,
        num(json, "tau_opt")?,
        num(json, "tau_r0")?,
    );
    let (r_min, r_max) = (num(json, "r_min")?, num(json, "r_max")?);
    ensure(r_opt == 0.0 || (r_opt >= r_min && r_opt <= r_max), || {
        format!("r_opt = {r_opt} outside {{0}} ∪ [{r_min}, {r_max}]")
    })?;
    tau_bound("tau_opt", tau_opt, case.least_time(r_opt, v0, vt))?;
    tau_bound("tau_r0", tau_r0, case.least_time(0.0, v0, vt))?;
    let grid = o.results.table("rate_grid").ok_or("no rate_grid table")?;
    let best = column(grid, "tau").iter().fold(tau_r0, |a, &b| a.min(b));
    ensure(tau_opt <= best * (1.0 + 1e-9), || {
        format!("tau_opt = {tau_opt} above the grid's least tau {best}")
    })
}

// ---------------------------------------------------------------- commands

#[test]
fn analytic_range() {
    // The density exists for r = 0 only (linear drag: moments at any r): mostly r = 0.
    let s = (model(false), count(), prop::bool::weighted(0.8)).prop_map(|(mut m, points, r0)| {
        if r0 {
            m.rate = 0.0;
            let i = m.args.iter().position(|a| a == "--rate").unwrap();
            m.args[i + 1] = "0".into();
        }
        with(&["analytic"], m, flag("points", points))
    });
    fuzz("analytic", 300, s);
}

fn simulate_flags(euler: bool) -> impl Strategy<Value = Vec<String>> {
    (
        count(),
        magnitude(),
        count(),
        count(),
        magnitude(),
        magnitude(),
        prop::bool::ANY,
    )
        .prop_map(move |(particles, t_max, samples, bins, burn_in, dt, log)| {
            let mut f = flag("particles", particles);
            f.extend(flag("t-max", s(t_max)));
            f.extend(flag("samples", samples));
            f.extend(flag("bins", bins));
            f.extend(flag("burn-in", s(burn_in)));
            if log {
                f.extend(flag("grid", "log".into()));
                f.extend(flag("t-min", s(burn_in * 1e-2)));
            }
            if euler {
                f.extend(flag("method", "euler".into()));
                f.extend(flag("dt", s(dt)));
            }
            f
        })
}

/// Known limitation, excluded: the exact sampler with tanh drag and Sigma
/// within 1e-12 of 1 (v_u > 14) returns <v²> far outside [0, v_u²] (e.g.
/// -8e6 at Sigma = 1 - 2^-53): the closed-form flow integrals lose all
/// precision there.
fn tanh_next_to_its_limit(m: &Case) -> bool {
    m.drag == Some(DragLaw::Tanh) && m.sigma > 1.0 - 1e-12
}

#[test]
fn simulate_exact_range() {
    let s = (model(true), simulate_flags(false))
        .prop_filter("tanh next to Sigma = 1", |(m, _)| {
            !tanh_next_to_its_limit(m)
        })
        .prop_map(|(m, f)| with(&["simulate"], m, f));
    fuzz("simulate exact", 150, s);
}

#[test]
fn simulate_euler_range() {
    let s = (model(true), simulate_flags(true)).prop_map(|(m, f)| with(&["simulate"], m, f));
    fuzz("simulate euler", 150, s);
}

#[test]
fn fp_stationary_range() {
    let s = (model(true), count(), prop::bool::ANY, prop::bool::ANY).prop_map(
        |(m, cells, uniform, no_extrapolate)| {
            let mut f = flag("cells", cells);
            if uniform {
                f.extend(flag("mesh", "uniform".into()));
            }
            if no_extrapolate {
                f.push("--no-extrapolate".into());
            }
            with(&["fp", "stationary"], m, f)
        },
    );
    fuzz("fp stationary", 200, s);
}

#[test]
fn fp_transient_range() {
    let s = (
        model(true),
        magnitude(),
        count(),
        count(),
        count(),
        any_real(),
        any::<bool>(),
        magnitude(),
    )
        .prop_map(|(m, t_max, cells, samples, snapshots, cfl, paper, tol)| {
            let mut f = flag("t-max", s(t_max));
            f.extend(flag("cells", cells));
            f.extend(flag("samples", samples));
            f.extend(flag("snapshots", snapshots));
            if paper {
                f.extend(flag("scheme", "paper".to_string()));
                f.extend(flag("cfl", s(cfl.abs().min(2.0))));
            } else {
                f.extend(flag("rtol", s(1e-3 * tol)));
                f.extend(flag("atol", s(1e-7 * tol)));
            }
            with(&["fp", "transient"], m, f)
        });
    fuzz("fp transient", 200, s);
}

/// A model with a start v0 and a target vt drawn relative to its v_u.
fn problem() -> impl Strategy<Value = (Case, f64, f64)> {
    model(true).prop_flat_map(|m| {
        let vu = m.v_upper().unwrap_or(1.0);
        (Just(m), velocity(vu), velocity(vu))
    })
}

fn mfpt_method_flags(method: &'static str) -> impl Strategy<Value = Vec<String>> {
    (count(), magnitude(), magnitude(), count()).prop_map(move |(particles, t_max, dt, cells)| {
        let mut f = flag("method", method.into());
        f.extend(flag("cells", cells));
        if method != "backward" {
            f.extend(flag("particles", particles));
            f.extend(flag("t-max", s(t_max)));
        }
        if method == "euler" {
            f.extend(flag("dt", s(dt)));
        }
        f
    })
}

/// With Sigma astronomically large (8e252, tan drag) the exact sampler's
/// passage times (~1e-253) come out as exactly 0; the method now checks them
/// against the least passage time and refuses (exit 4), so the whole range
/// is drawn.
const MAX_PARTICLE_SIGMA: f64 = f64::INFINITY;

fn mfpt_range(method: &'static str, cases: u32) {
    let s = (problem(), mfpt_method_flags(method))
        .prop_filter(
            "Sigma beyond the particle samplers' range",
            move |((m, _, _), _)| method == "backward" || !(m.sigma > MAX_PARTICLE_SIGMA),
        )
        .prop_map(|((m, v0, vt), mut f)| {
            f.extend(flag("v0", s(v0)));
            f.extend(flag("vt", s(vt)));
            with(&["mfpt"], m, f)
        });
    fuzz(&format!("mfpt {method}"), cases, s);
}

#[test]
fn mfpt_ode_range() {
    mfpt_range("backward", 300);
}

#[test]
#[ignore = "slow tier"]
fn mfpt_exact_range() {
    mfpt_range("exact", 150);
}

#[test]
fn mfpt_euler_range() {
    mfpt_range("euler", 150);
}

#[test]
fn mfpt_scan_range() {
    let s = (
        problem(),
        prop::bool::ANY,
        fraction(),
        magnitude(),
        count(),
        prop::bool::ANY,
        count(),
    )
        .prop_map(|((m, v0, vt), over_vt, to, r_to, points, log, cells)| {
            let vu = m.v_upper().unwrap_or(1.0);
            let mut f = flag("v0", s(v0));
            f.extend(flag("cells", cells));
            f.extend(flag("points", points));
            if over_vt {
                f.extend(flag("over", "vt".into()));
                f.extend(flag("from", s(vt)));
                f.extend(flag("to", s(to * vu)));
            } else {
                f.extend(flag("over", "rate".into()));
                f.extend(flag("vt", s(vt)));
                f.extend(flag("from", s(m.rate)));
                f.extend(flag("to", s(r_to)));
            }
            if log {
                f.push("--log".into());
            }
            with(&["mfpt", "scan"], m, f)
        });
    fuzz("mfpt scan", 150, s);
}

#[test]
fn mfpt_optimize_range() {
    let s = (problem(), magnitude(), magnitude(), count(), count()).prop_map(
        |((m, v0, vt), r_min, r_max, grid_points, cells)| {
            let mut f = flag("v0", s(v0));
            f.extend(flag("vt", s(vt)));
            f.extend(flag("r-min", s(r_min)));
            f.extend(flag("r-max", s(r_max)));
            f.extend(flag("grid-points", grid_points));
            f.extend(flag("cells", cells));
            with(&["mfpt", "optimize"], m, f)
        },
    );
    fuzz("mfpt optimize", 100, s);
}
