//! The surfaces added after the first range fuzz, drawn the same way (fixed
//! seeds, every failure listed): drag laws written as expressions, reset
//! protocols (targets, noise rules, periodic clocks, refractory periods,
//! position resetting), and sweep plans. The generators draw what a hostile
//! user types: odd expressions that should answer, deep and long ones that
//! must be refused by size (never a stack overflow), numbers in every
//! notation, protocols with parameters at the edges of the range, plans with
//! reserved or unknown keys, duplicate points, bad TOML, huge axes.

use super::*;
use irtp_app::sweep::Plan;
use std::collections::HashSet;

// ------------------------------------------------------------ expressions

/// A number as a user writes it: `0.3`, `3e-1`, `3E-1`, `2.5E+2`, `1e-300`.
fn coefficient() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-3.0f64..3.0).prop_map(|e| format!("{}", (10f64.powf(e) * 1e3).round() / 1e3)),
        2 => (-3.0f64..3.0).prop_map(|e| format!("{:e}", 10f64.powf(e))),
        1 => (-3.0f64..3.0).prop_map(|e| format!("{:E}", 10f64.powf(e))),
        1 => prop::sample::select(vec![
            "0", "1", "2", "0.001", "1e-3", "1E-3", "2.5E+2", "1e-300", "1e300", "5e-324",
            "1.7976931348623157e308", "0.0000001",
        ])
        .prop_map(String::from),
    ]
}

/// An odd function of exmex that is increasing (or not: sin) near 0.
fn odd_function() -> impl Strategy<Value = &'static str> {
    prop::sample::select(vec!["sinh", "tanh", "atan", "asinh", "sin", "tan", "atanh"])
}

/// An odd expression in v (odd by construction; monotone or not).
fn odd_expression() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        2 => Just("v".to_string()),
        1 => coefficient().prop_map(|c| format!("{c}*v")),
    ];
    leaf.prop_recursive(5, 48, 2, |inner| {
        prop_oneof![
            3 => (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("{a} + {b}")),
            1 => (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("{a} - ({b})")),
            2 => (coefficient(), inner.clone()).prop_map(|(c, a)| format!("{c}*({a})")),
            2 => (odd_function(), inner.clone()).prop_map(|(f, a)| format!("{f}({a})")),
            1 => (inner.clone(), prop::sample::select(vec![3, 5])).prop_map(|(a, k)| format!("({a})^{k}")),
            1 => (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a})*cosh({b})")),
            1 => (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a})/(1 + ({b})^2)")),
        ]
    })
}

/// What else users type: even or undefined laws, unknown names, bad syntax,
/// and expressions far beyond the size bounds (a sum of up to 3·10⁴ terms,
/// functions nested up to 3000 deep: a stack overflow before the bounds).
fn other_expression() -> impl Strategy<Value = String> {
    let n = || (0.0f64..4.5).prop_map(|e| 10f64.powf(e) as usize);
    prop_oneof![
        3 => prop::sample::select(vec![
            "v^2", "v^3", "abs(v)", "1/v", "ln(v)", "sqrt(v)", "v/0", "0*v", "v*0 + 1", "x",
            "foo(v)", "sinh(v", "v)", "", " ", "v +", "(v)", "v^-1", "exp(v) - 1", "E*v",
            "PI*v", "signum(v)", "v^0.5", "v*v*v", "2^v", "v^v", "0.5*v + v^3/3",
            "v + 1e400*v", "nan*v", "inf*v", "v + 0x10*v", "1e-3*v + v",
        ])
        .prop_map(String::from),
        2 => (n(), coefficient()).prop_map(|(k, c)| format!("v{}", format!(" + {c}*v").repeat(k))),
        1 => n().prop_map(|k| vec!["v"; k.max(1)].join("*")),
        2 => (odd_function(), n()).prop_map(|(f, k)| format!("{}v{}", format!("{f}(").repeat(k), ")".repeat(k))),
        1 => n().prop_map(|k| format!("{}v{}", "(".repeat(k), ")".repeat(k))),
        1 => n().prop_map(|k| format!("{}v", "-".repeat(k))),
    ]
}

fn expression() -> impl Strategy<Value = String> {
    prop_oneof![3 => odd_expression(), 2 => other_expression()]
}

/// A model with an expression drag: the law as the library parses it (None:
/// refused), its flags, v_u where it exists.
fn expression_model(reset: bool) -> impl Strategy<Value = Case> {
    (expression(), magnitude(), magnitude(), magnitude())
        .prop_flat_map(move |(text, sigma, lambda, rate)| {
            let spec = format!("expr:{text}");
            let drag = spec.parse::<DragLaw>().ok();
            let vu = drag
                .clone()
                .and_then(|d| Params::new(d, sigma, 0.0, 0.0, 0.0).ok())
                .map_or(1.0, |p| p.v_upper());
            let vr = if reset {
                velocity(vu).boxed()
            } else {
                Just(0.0).boxed()
            };
            (Just((spec, drag, sigma, lambda, rate)), vr)
        })
        .prop_map(move |((spec, drag, sigma, lambda, rate), vr)| {
            let rate = if reset { rate } else { 0.0 };
            let mut args = vec!["--drag".into(), spec];
            for (f, x) in [("--sigma", sigma), ("--lambda", lambda), ("--rate", rate)] {
                args.extend([f.to_string(), s(x)]);
            }
            if reset {
                args.extend(["--reset-velocity".into(), s(vr)]);
            }
            Case {
                args,
                drag,
                sigma,
                lambda,
                rate,
                vr,
                reach: None,
            }
        })
}

/// A mesh a solver takes (a multiple of 4, 64..2000) mostly, else any count:
/// the generators here exercise the model surface, not the mesh bounds.
fn mesh() -> impl Strategy<Value = String> {
    prop_oneof![6 => (16u32..500).prop_map(|k| (4 * k).to_string()), 1 => count()]
}

/// A start and a target velocity drawn relative to the case's v_u.
fn start_and_target(m: Case) -> impl Strategy<Value = (Case, f64, f64)> {
    let vu = m.v_upper().unwrap_or(1.0);
    (Just(m), velocity(vu), velocity(vu))
}

fn mfpt_case(m: Case, v0: f64, vt: f64, cells: String) -> Case {
    let mut f = flag("v0", s(v0));
    f.extend(flag("vt", s(vt)));
    f.extend(flag("cells", cells));
    with(&["mfpt"], m, f)
}

#[test]
fn expression_drag_range() {
    let analytic = (expression_model(false), count())
        .prop_map(|(m, points)| with(&["analytic"], m, flag("points", points)));
    fuzz("expr analytic", 150, analytic);
    let fp = (expression_model(true), mesh())
        .prop_map(|(m, cells)| with(&["fp", "stationary"], m, flag("cells", cells)));
    fuzz("expr fp stationary", 100, fp);
    let mfpt = (
        expression_model(true).prop_flat_map(start_and_target),
        mesh(),
    )
        .prop_map(|((m, v0, vt), cells)| mfpt_case(m, v0, vt, cells));
    fuzz("expr mfpt", 100, mfpt);
    let sim = (expression_model(true), 2u32..500, -1.0f64..1.5).prop_map(|(m, particles, t)| {
        let t = 10f64.powf(t);
        let mut f = flag("particles", particles.to_string());
        f.extend(flag("t-max", s(t)));
        f.extend(flag("burn-in", s(t / 2.0)));
        with(&["simulate"], m, f)
    });
    fuzz("expr simulate", 60, sim);
}

// -------------------------------------------------------------- protocols

/// A drawn reset protocol: its flags and the velocities a reset lands on.
#[derive(Clone, Debug)]
struct Protocol {
    flags: Vec<String>,
    reach: (f64, f64),
    periodic: bool,
}

/// A reset target drawn relative to v_u: a point, a Gaussian, a uniform or
/// a Laplace law (their parameters at the edges too), maybe re-drawing the
/// noise state; the interval a reset lands in.
fn target(vu: f64) -> impl Strategy<Value = (String, (f64, f64))> {
    let rule = prop::sample::select(vec!["", ",noise=redrawn", ",noise=kept"]);
    prop_oneof![
        (velocity(vu), rule.clone()).prop_map(|(v, n)| (format!("point:v={}{n}", s(v)), (v, v))),
        (velocity(vu), magnitude(), rule.clone()).prop_map(move |(m, sd, n)| (
            format!("gauss:mean={},std={}{n}", s(m), s(sd * vu)),
            (-vu, vu)
        )),
        (velocity(vu), velocity(vu), rule.clone()).prop_map(|(a, b, n)| (
            format!("uniform:a={},b={}{n}", s(a), s(b)),
            (a.min(b), a.max(b))
        )),
        (velocity(vu), magnitude(), rule).prop_map(move |(m, b, n)| (
            format!("laplace:mean={},scale={}{n}", s(m), s(b * vu)),
            (-vu, vu)
        )),
    ]
}

/// A protocol: maybe a target (else `--reset-velocity`, maybe with
/// `--reset-noise`), maybe a period, a refractory period, position resetting.
fn protocol(vu: f64, vr: f64) -> impl Strategy<Value = Protocol> {
    (
        prop::option::weighted(0.6, target(vu)),
        prop::option::of(prop::sample::select(vec!["kept", "redrawn"])),
        prop::option::weighted(0.25, magnitude()),
        prop::option::weighted(0.35, (prop::bool::ANY, magnitude())),
        prop::option::weighted(0.25, any_real()),
    )
        .prop_map(move |(target, noise, period, refractory, position)| {
            let mut flags = Vec::new();
            let reach = match target {
                Some((spec, reach)) => {
                    flags.extend(flag("reset-to", spec));
                    reach
                }
                None => {
                    flags.extend(flag("reset-velocity", s(vr)));
                    if let Some(n) = noise {
                        flags.extend(flag("reset-noise", n.into()));
                    }
                    (vr, vr)
                }
            };
            if let Some(t) = period {
                flags.extend(flag("reset-period", s(t)));
            }
            if let Some((exp, m)) = refractory {
                let spec = if exp { "exp:mean" } else { "fixed:t" };
                flags.extend(flag("refractory", format!("{spec}={}", s(m))));
            }
            if let Some(x) = position {
                flags.extend(flag("reset-position", s(x)));
            }
            Protocol {
                flags,
                reach,
                periodic: period.is_some(),
            }
        })
}

/// A model (no `--reset-velocity` of its own) with a drawn protocol; a
/// periodic protocol mostly at rate 0 (the Poisson clock it replaces).
fn protocol_model() -> impl Strategy<Value = Case> {
    (model(false), fraction(), prop::bool::weighted(0.9))
        .prop_flat_map(|(m, f, zero_rate)| {
            let vu = m.v_upper().unwrap_or(1.0);
            (Just((m, zero_rate)), protocol(vu, f * vu))
        })
        .prop_map(|((mut m, zero_rate), p)| {
            if p.periodic && zero_rate {
                m.rate = 0.0;
                let i = m.args.iter().position(|a| a == "--rate").unwrap();
                m.args[i + 1] = "0".into();
            }
            // vr only enters the admissibility of the model (v_u); where a
            // reset lands is `reach`.
            m.vr = 0.0;
            m.reach = Some(p.reach);
            m.args.extend(p.flags);
            m
        })
}

#[test]
fn reset_protocol_range() {
    let fp = (protocol_model(), mesh())
        .prop_map(|(m, cells)| with(&["fp", "stationary"], m, flag("cells", cells)));
    fuzz("protocol fp stationary", 150, fp);
    let tr = (protocol_model(), -2.0f64..1.0, 16u32..40).prop_map(|(m, t, k)| {
        let mut f = flag("t-max", s(10f64.powf(t)));
        f.extend(flag("cells", (4 * k).to_string()));
        f.extend(flag("samples", "5".into()));
        f.extend(flag("rtol", "1e-4".into()));
        with(&["fp", "transient"], m, f)
    });
    fuzz("protocol fp transient", 100, tr);
    let mfpt = (protocol_model().prop_flat_map(start_and_target), mesh())
        .prop_map(|((m, v0, vt), cells)| mfpt_case(m, v0, vt, cells));
    fuzz("protocol mfpt", 150, mfpt);
    let sim = (protocol_model(), 2u32..500, -1.0f64..1.5).prop_map(|(m, particles, t)| {
        let t = 10f64.powf(t);
        let mut f = flag("particles", particles.to_string());
        f.extend(flag("t-max", s(t)));
        f.extend(flag("burn-in", s(t / 2.0)));
        with(&["simulate"], m, f)
    });
    fuzz("protocol simulate", 100, sim);
}

// ------------------------------------------------------------------ plans

/// A drawn plan: its TOML text and, when every part of it is valid as far
/// as the generator knows, its number of points.
#[derive(Clone, Debug)]
struct PlanCase {
    text: String,
    /// Points, if the axes are well formed and distinct (else None).
    points: Option<u64>,
}

/// A key a plan may set (mostly), or not: reserved ones, unknown ones.
fn plan_key() -> impl Strategy<Value = &'static str> {
    prop_oneof![
        12 => prop::sample::select(vec!["sigma", "lambda", "rate"]),
        1 => prop::sample::select(vec![
            "cells", "drag", "seed", "out", "force", "json", "bogus", "reset_to", "t_max",
            "max_work",
        ]),
    ]
}

/// A TOML float (TOML spells the IEEE specials `nan`, `inf`, `-inf`).
fn toml_float(x: f64) -> String {
    match x {
        x if x.is_nan() => "nan".into(),
        x if x == f64::INFINITY => "inf".into(),
        x if x == f64::NEG_INFINITY => "-inf".into(),
        x => format!("{x:e}"),
    }
}

/// An axis: its TOML value and its length when the generator knows it is a
/// valid axis of distinct values.
fn axis_value() -> impl Strategy<Value = (String, Option<u64>)> {
    let list = prop::collection::vec(magnitude(), 0..5).prop_map(|xs| {
        let distinct = xs.iter().map(|x| x.to_bits()).collect::<HashSet<_>>().len() == xs.len();
        let text: Vec<String> = xs.iter().map(|x| toml_float(*x)).collect();
        let ok = distinct && !xs.is_empty();
        (
            format!("[{}]", text.join(", ")),
            ok.then_some(xs.len() as u64),
        )
    });
    let range = (
        magnitude(),
        magnitude(),
        prop_oneof![
            4 => (0.0f64..3.0).prop_map(|e| 10f64.powf(e) as u64),
            1 => prop::sample::select(vec![0u64, 1, 1_000_001, u64::MAX]),
        ],
        prop::sample::select(vec![
            "",
            ", spacing = \"log\"",
            ", spacing = \"linear\"",
            ", spacing = \"cubic\"",
        ]),
    )
        .prop_map(|(a, b, n, sp)| {
            let text = format!(
                "{{ from = {}, to = {}, points = {n}{sp} }}",
                toml_float(a),
                toml_float(b)
            );
            (text, None)
        });
    let other = prop::sample::select(vec![
        "[]",
        "\"tan\"",
        "[1, \"a\"]",
        "{ from = 1 }",
        "3",
        "[true]",
    ])
    .prop_map(|t| (t.to_string(), None));
    prop_oneof![4 => list, 2 => range, 1 => other]
}

/// A `[fixed]` entry: mostly a model number, else anything.
fn fixed_entry() -> impl Strategy<Value = (&'static str, String)> {
    prop_oneof![
        4 => (plan_key(), magnitude().prop_map(toml_float)),
        1 => (plan_key(), any_real().prop_map(toml_float)),
        1 => (
            prop::sample::select(vec!["drag", "cells", "sigma"]),
            prop::sample::select(vec![
                "\"tan\"", "\"expr:v + v^3\"", "true", "200", "-1", "[1.0]", "\"\"",
            ])
            .prop_map(String::from),
        ),
    ]
}

/// A plan: a command, maybe a seed and particle parts, up to three fixed
/// keys, up to three axes, maybe a zip; sometimes a line of bad TOML.
fn plan() -> impl Strategy<Value = PlanCase> {
    let command = prop_oneof![
        6 => Just("fp stationary"),
        3 => prop::sample::select(vec!["analytic", "mfpt", "simulate", "fp transient", "mfpt optimize"]),
        1 => prop::sample::select(vec!["fp msd", "sweep run", "bogus", ""]),
    ];
    let seed = prop::option::weighted(
        0.3,
        prop::sample::select(vec![
            "1",
            "0",
            "-1",
            "18446744073709551615",
            "18446744073709551616",
            "1.5",
            "\"x\"",
        ]),
    );
    let parts = prop::option::weighted(0.2, prop::sample::select(vec!["0", "1", "2", "-1", "1e3"]));
    (
        command,
        seed,
        parts,
        prop::collection::vec(fixed_entry(), 0..3),
        prop::collection::vec((plan_key(), axis_value()), 0..3),
        prop::option::weighted(0.2, (plan_key(), axis_value(), plan_key(), axis_value())),
        prop::option::weighted(
            0.1,
            prop::sample::select(vec!["sigma = ", "[axes", "= 1", "sigma = 1\nsigma = 2"]),
        ),
    )
        .prop_map(|(command, seed, parts, fixed, axes, zip, junk)| {
            let mut text = format!("command = \"{command}\"\n");
            text += &seed.map(|s| format!("seed = {s}\n")).unwrap_or_default();
            text += &parts
                .map(|p| format!("particle_parts = {p}\n"))
                .unwrap_or_default();
            text += &junk.map(|j| format!("{j}\n")).unwrap_or_default();
            text += "[fixed]\n";
            for (k, v) in &fixed {
                text += &format!("{k} = {v}\n");
            }
            text += "[axes]\n";
            let mut points = Some(1u64);
            for (k, (v, n)) in &axes {
                text += &format!("{k} = {v}\n");
                points = points.zip(*n).map(|(a, b)| a * b);
            }
            if let Some((k1, (v1, n1), k2, (v2, n2))) = &zip {
                text += &format!("[[zip]]\n{k1} = {v1}\n{k2} = {v2}\n");
                points = points
                    .zip(n1.filter(|a| Some(*a) == *n2))
                    .map(|(a, b)| a * b);
            }
            PlanCase { text, points }
        })
}

/// Parse one drawn plan (in a thread, under the time bound): a clean
/// one-line refusal, or a plan whose points are counted as drawn, distinct,
/// each a command line its command parses.
fn check_plan(case: &PlanCase) -> Result<bool, String> {
    let (tx, rx) = std::sync::mpsc::channel();
    let text = case.text.clone();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(|| Plan::parse(&text));
        let _ = tx.send(r);
    });
    let plan = match rx.recv_timeout(Duration::from_secs(MAX_CASE_SECONDS)) {
        Err(_) => return Err(format!("no answer within {MAX_CASE_SECONDS} s")),
        Ok(Err(_)) => return Err("panicked".into()),
        Ok(Ok(Err(e))) => {
            let msg = e.to_string();
            return if !e.is_input_error() {
                Err(format!("not a bad-input error: {e:?}"))
            } else if msg.trim().is_empty() || msg.contains('\n') {
                Err(format!("error message not one line: {msg:?}"))
            } else {
                Ok(false)
            };
        }
        Ok(Ok(Ok(plan))) => plan,
    };
    let n = plan.len() as u64;
    if let Some(want) = case.points {
        ensure(n == want, || format!("{n} points, drawn {want}"))?;
    }
    ensure(n <= 1_000_000, || format!("{n} points accepted"))?;
    let owned = ["\nseed =", "\nout =", "\nforce ="];
    let body = &case.text[case.text.find("[fixed]").unwrap_or(0)..];
    ensure(!owned.iter().any(|k| body.contains(k)), || {
        "a plan setting what the sweep owns was accepted".into()
    })?;
    let ids: HashSet<String> = plan.points().take(10_000).map(|p| p.id.clone()).collect();
    ensure(ids.len() as u64 == n.min(10_000), || "points repeat".into())?;
    Ok(true)
}

#[test]
fn sweep_plan_range() {
    let config = Config {
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config, rng("sweep plans"));
    let (mut ok, mut refused, mut failures) = (0, 0, Vec::new());
    for _ in 0..400 * explore().1 {
        let case = plan().new_tree(&mut runner).expect("a case").current();
        match check_plan(&case) {
            Ok(true) => ok += 1,
            Ok(false) => refused += 1,
            Err(why) => failures.push(format!("{why}:\n{}", case.text)),
        }
    }
    eprintln!(
        "plans: {ok} accepted, {refused} refused, {} failed",
        failures.len()
    );
    assert!(failures.is_empty(), "plans:\n{}", failures.join("\n"));
    assert!(
        ok >= 40,
        "only {ok} of the drawn plans were valid: the generator drifted"
    );
}
