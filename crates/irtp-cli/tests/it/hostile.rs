//! Hostile and extreme inputs on the newer surfaces: each class is either
//! answered correctly or refused in one line naming what was typed (exit
//! 2, nothing written), never a crash or a hang.
//!
//! (a) Huge expressions (200-term sums and products, 300 nested functions,
//!     60 kB): refused by size before exmex's recursive parser sees them,
//!     in well under a second; sizes below the bounds run without a crash.
//! (b) Valid expressions once refused: `v^3` (g' vanishes only at 0) is the
//!     power law n = 3; numbers in exponent notation (`1e-3`) read as the
//!     same double written out (`0.001`).
//! (c) SLURM scripts: a partition or time limit SLURM would not accept, or
//!     a zero count, is refused naming its flag before --out is created.
//! (d) An --out with a control character is refused naming --out.
//! (e) Combinations a method does not run (`irtp::capability`): one line
//!     under 200 characters naming the flag and the method, nothing written.

use crate::common::{assert_rejected, irtp, json};
use std::time::{Duration, Instant};

fn expr_of(parts: &[&str], sep: &str) -> String {
    format!("expr:{}", parts.join(sep))
}

/// (a) Over the bounds: exit 2, one line naming --drag and the bound,
/// within a second (no parse is attempted).
#[test]
fn huge_expressions_are_refused_by_size() {
    let sum = expr_of(&["v"; 250], "+");
    let product = expr_of(&["v"; 250], "*");
    let nested = format!("expr:{}v{}", "sinh(".repeat(300), ")".repeat(300));
    let long = format!("expr:v{}", "+0.000001*v".repeat(6000));
    let deep = format!("expr:{}v{}", "(".repeat(60), ")".repeat(60));
    for (spec, bound) in [
        (&sum, "at most 200"),
        (&product, "at most 200"),
        (&nested, "at most 200"),
        (&long, "at most 4000"),
        (&deep, "at most 50"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let t0 = Instant::now();
        let o = irtp(&["analytic", "--drag", spec, "--out", out.to_str().unwrap()]);
        assert!(t0.elapsed() < Duration::from_secs(2), "{}", &spec[..40]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("--drag") && err.contains(bound), "{err}");
        assert!(
            err.len() < 600,
            "the message repeats the input: {} bytes",
            err.len()
        );
        assert!(!out.exists());
    }
}

/// (a) Below the bounds, deep expressions compile (on the compile thread's
/// large stack) and every command runs them: no stack overflow, in the
/// binary's main thread or in a worker thread.
#[test]
fn large_expressions_below_the_bounds_run() {
    let sum = expr_of(&["0.01*v"; 100], " + ");
    let nested = format!("expr:{}v{}", "sinh(".repeat(40), ")".repeat(40));
    for spec in [&sum, &nested] {
        for cmd in [
            &["analytic"][..],
            &["fp", "stationary", "--cells", "200"][..],
            &[
                "simulate",
                "--particles",
                "200",
                "--t-max",
                "4",
                "--burn-in",
                "1",
            ][..],
        ] {
            let o = irtp(&[cmd, &["--drag", spec, "--sigma", "0.5", "--json"]].concat());
            let err = String::from_utf8_lossy(&o.stderr);
            // An answer, or a refusal or numerical failure with its exit
            // code; never a signal.
            assert!(
                matches!(o.status.code(), Some(0 | 2 | 4)),
                "{cmd:?} {}: {:?} {err}",
                &spec[..30],
                o.status
            );
        }
    }
    let o = irtp(&["analytic", "--drag", &sum, "--sigma", "0.5", "--json"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// (a) A long expression law is dearer per evaluation than a shipped law:
/// the cost estimate of every mesh method weighs it, so a run the budget
/// admits for `tan` is refused for a 45-factor product (about 700 times
/// dearer) before any work, naming `--drag` among the drivers, and nothing
/// is written.
#[test]
fn an_expensive_law_counts_in_the_cost_estimate() {
    let product = format!("expr:{}*v", ["(1+0.01*v^2)"; 45].join("*"));
    for (cmd, budget) in [
        (&["fp", "stationary", "--cells", "2000"][..], "1e7"),
        (
            &["mfpt", "--v0", "0", "--vt", "0.2", "--cells", "2000"][..],
            "1e7",
        ),
        (
            &[
                "fp",
                "msd",
                "--cells",
                "200",
                "--levels",
                "2",
                "--t-min",
                "0.1",
                "--t-max",
                "2",
                "--samples",
                "5",
            ][..],
            "1e9",
        ),
    ] {
        let run = |drag: &str, out: &[&str]| {
            let args = [
                cmd,
                &["--drag", drag, "--sigma", "0.5", "--max-work", budget],
                out,
            ];
            irtp(&args.concat())
        };
        let o = run("tan", &["--json"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{cmd:?}: {err}");
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let o = run(&product, &["--out", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{cmd:?}: {err}");
        assert!(
            err.contains("too costly") && err.contains("--drag"),
            "{cmd:?}: {err}"
        );
        assert!(!out.exists());
    }
}

/// (b) `expr:v^3` runs and equals `power:n=3` (the r = 0 density's <v²>,
/// the same law through two code paths, to 1e-9); `1e-3` reads as 0.001.
#[test]
fn valid_expressions_are_accepted() {
    let v2 = |drag: &str| {
        let o = irtp(&[
            "analytic", "--drag", drag, "--sigma", "3", "--lambda", "2", "--json",
        ]);
        json(&o)["v2"]
            .as_f64()
            .unwrap_or_else(|| panic!("{drag}: {}", json(&o)))
    };
    let (a, b) = (v2("expr:v^3"), v2("power:n=3"));
    assert!((a - b).abs() <= 1e-9 * b, "{a} vs {b}");
    let (a, b) = (v2("expr:1e-3*v + v"), v2("expr:0.001*v + v"));
    assert_eq!(a, b);
    let (a, b) = (v2("expr:v + 2.5E-1*v^3"), v2("expr:v + 0.25*v^3"));
    assert_eq!(a, b);
}

/// (c) Every value that enters a generated script is checked first.
#[test]
fn slurm_values_are_checked_before_anything_is_written() {
    let cases: [(&[&str], &str); 10] = [
        (&["--partition", "a\nb"], "--partition"),
        (&["--partition", "a b"], "--partition"),
        (&["--partition", "$(reboot)"], "--partition"),
        (&["--time", "banana"], "--time"),
        (&["--time", "1:2:3:4"], "--time"),
        (&["--cpus-per-task", "0"], "--cpus-per-task"),
        (&["--throttle", "0"], "--throttle"),
        (&["--points-per-task", "0"], "--points-per-task"),
        (&["--max-array", "0"], "--max-array"),
        (&["--max-tasks", "0"], "--max-tasks"),
    ];
    for (args, flag) in cases {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("sw");
        let base = [
            "sweep",
            "slurm",
            "../../examples/sweeps/mfpt.toml",
            "--out",
            out.to_str().unwrap(),
        ];
        assert_rejected(&irtp(&[&base[..], args].concat()), flag, &out);
    }
    // SLURM's own formats are accepted.
    for t in [
        "30",
        "30:00",
        "01:00:00",
        "2-0",
        "2-12:30",
        "1-00:00:00",
        "UNLIMITED",
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("sw");
        let args = [
            "sweep",
            "slurm",
            "../../examples/sweeps/mfpt.toml",
            "--out",
            out.to_str().unwrap(),
            "--time",
            t,
            "--partition",
            "gpu,short.q",
            "--max-array",
            "1000",
        ];
        let o = irtp(&args);
        assert_eq!(
            o.status.code(),
            Some(0),
            "--time {t}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let run = std::fs::read_to_string(out.join("slurm/run-1.sbatch")).unwrap();
        assert!(run.contains(&format!("#SBATCH --time={t}\n")), "{run}");
    }
}

/// (d) A newline or tab in --out.
#[test]
fn control_characters_in_out_are_refused() {
    for name in ["a\nb", "a\tb"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join(name);
        let o = irtp(&["analytic", "--out", out.to_str().unwrap()]);
        let err = assert_rejected(&o, "--out", &out);
        assert!(err.contains("control characters"), "{err}");
    }
}

/// A refractory period far below every time scale (mean 1e-300) used to
/// leak probability in `fp transient` (mass 0.0025 at exit 0): the
/// total probability is now checked at every recorded time and a loss is a
/// numerical failure (exit 4, one line, nothing written).
#[test]
fn fp_transient_refuses_an_answer_that_lost_mass() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tr");
    let o = irtp(&[
        "fp",
        "transient",
        "--cells",
        "1000",
        "--t-max",
        "3",
        "--refractory",
        "exp:mean=1e-300",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("total probability"), "{err}");
    assert!(!out.exists());
    // A short but resolved refractory period answers with mass 1.
    let o = irtp(&[
        "fp",
        "transient",
        "--cells",
        "400",
        "--t-max",
        "1",
        "--refractory",
        "exp:mean=0.05",
        "--json",
    ]);
    let r = json(&o);
    let mass = r["mass"].as_f64();
    assert!(mass.is_some_and(|m| (m - 1.0).abs() < 1e-8), "{r}");
}

/// A case the range fuzz found: TR-BDF2 left a density of -1.8e-34 in a
/// snapshot (exit 0). Snapshots are now non-negative: round-off (within
/// 1e-12 of the largest density) is written as 0, more is refused.
#[test]
fn fp_transient_snapshots_are_nonnegative() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tr");
    let o = irtp(&[
        "fp",
        "transient",
        "--drag",
        "linear",
        "--sigma",
        "640.4",
        "--lambda",
        "1.569e-3",
        "--rate",
        "795.7",
        "--reset-velocity",
        "-277.8",
        "--reset-noise",
        "redrawn",
        "--refractory",
        "exp:mean=1.12e-14",
        "--t-max",
        "0.1532",
        "--cells",
        "72",
        "--samples",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(out.join("snapshots.csv")).unwrap();
    let mut rows = 0;
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
    {
        let x: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        assert!(x[2..].iter().all(|p| *p >= 0.0), "{line}");
        rows += 1;
    }
    assert!(rows >= 72, "{rows} rows");
}

/// A plan of 10⁷ or 4·10⁶ points is refused from its axes' lengths, before
/// any point is built or checked (it ran silently past a minute), naming
/// the axis or the axes; nothing is written.
#[test]
fn huge_plans_are_counted_before_they_are_enumerated() {
    let cases = [
        ("sigma = { from = 0.5, to = 5.0, points = 10000000 }\n", "sigma"),
        ("sigma = { from = 0.5, to = 5.0, points = 1000000000000000000 }\n", "sigma"),
        (
            "sigma = { from = 0.5, to = 5.0, points = 2000 }\nrate = { from = 0.1, to = 10.0, points = 2000 }\n",
            "sigma (2000) x rate (2000)",
        ),
    ];
    for (axes, named) in cases {
        let text = format!("command = \"fp stationary\"\n[fixed]\ncells = 200\n[axes]\n{axes}");
        for cmd in ["run", "slurm"] {
            let err = refused_plan(&text, cmd);
            assert!(err.contains(named) && err.contains("1000000"), "{err}");
        }
    }
}

/// A value given twice on an axis, or a zipped row repeated, is refused
/// naming the axis (it was one point run twice, or an i/o error).
#[test]
fn duplicate_points_are_refused_naming_the_axis() {
    let cases = [
        ("[axes]\nsigma = [1.0, 2.0, 1.0]\n", "sigma = 1.0:"),
        (
            "[axes]\nsigma = [1.0, 2.0]\n[[zip]]\nrate = [1.0, 1.0]\nlambda = [0.5, 0.5]\n",
            "rate+lambda = 1.0, 0.5:",
        ),
    ];
    for (axes, named) in cases {
        let text = format!("command = \"fp stationary\"\n[fixed]\ncells = 200\n{axes}");
        let err = refused_plan(&text, "run");
        // The values as typed, not as the parser holds them.
        assert!(err.contains(named) && err.contains("twice"), "{err}");
        assert!(!err.contains("Float("), "{err}");
    }
}

/// A plan may not set `force` (nor `out`, `seed`) in any of its tables:
/// refused naming the key before --out is written (a `[fixed]` force was
/// refused only after the sweep directory had been created; an axis of
/// force values was accepted by `sweep slurm`).
#[test]
fn plans_may_not_set_what_the_sweep_owns() {
    let tables = [
        "[fixed]\nforce = true\n[axes]\nsigma = [1.0, 2.0]\n",
        "[axes]\nsigma = [1.0, 2.0]\nforce = [true, false]\n",
        "[axes]\nsigma = [1.0, 2.0]\n[[zip]]\nforce = [true, false]\nrate = [0.5, 1.0]\n",
        "[fixed]\nout = \"x\"\n[axes]\nsigma = [1.0, 2.0]\n",
        "[fixed]\nseed = 3\n[axes]\nsigma = [1.0, 2.0]\n",
    ];
    for (i, t) in tables.iter().enumerate() {
        let text = format!("command = \"fp stationary\"\n{t}");
        let key = ["force", "force", "force", "out", "seed"][i];
        for cmd in ["run", "slurm"] {
            let err = refused_plan(&text, cmd);
            assert!(
                err.contains(&format!("invalid --plan = {key} = …"))
                    && err.contains("not set by a plan"),
                "{cmd} {t}: {err}"
            );
        }
    }
}

/// A plan's TOML error is one line naming the line and what is on it (a
/// seed of -1 or 2^64 was reported without naming `seed`).
#[test]
fn plan_errors_name_the_line() {
    for seed in ["-1", "18446744073709551616"] {
        let text =
            format!("command = \"fp stationary\"\nseed = {seed}\n[axes]\nsigma = [1.0, 2.0]\n");
        let err = refused_plan(&text, "run");
        assert!(err.contains(&format!("line 2 (`seed = {seed}`)")), "{err}");
    }
}

/// `irtp sweep CMD` of a plan with the TOML `text` refused: exit 2, one
/// line, nothing written, in under 5 s; its stderr.
fn refused_plan(text: &str, cmd: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan.toml");
    std::fs::write(&plan, text).unwrap();
    let out = dir.path().join("sw");
    let t0 = Instant::now();
    let o = irtp(&[
        "sweep",
        cmd,
        plan.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        t0.elapsed() < Duration::from_secs(5),
        "{cmd}: {:?}",
        t0.elapsed()
    );
    assert_eq!(o.status.code(), Some(2), "{cmd}: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!out.exists(), "{cmd} wrote --out");
    err
}

/// (a) A law no table resolves (an expression growing like
/// cosh(asinh(v)^5), Sigma = 5e206; found by the expression fuzz): the
/// exact sampler's table attempts are bounded by the law's evaluation
/// cost, so the numerical failure (exit 4) comes within seconds (it took
/// 18 s), and its message prints Sigma in short form, not 207 digits.
#[test]
fn an_unresolvable_law_fails_fast_with_short_numbers() {
    let t0 = Instant::now();
    let o = irtp(&[
        "simulate",
        "--drag",
        "expr:((1.5805886672038444E-2*v)*cosh(2.9559526457315466e-2*(v)))*cosh((asinh(v))^5)",
        "--sigma",
        "5.0110866728289255e206",
        "--particles",
        "50",
        "--t-max",
        "0.9",
        "--burn-in",
        "0.45",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    assert!(err.contains("5.011087e206") && err.len() < 300, "{err}");
}

/// Combinations a method does not run (`irtp::capability`): each refused
/// before any work, exit 2, one line under 200 characters naming the flag
/// and the method that refuses it, nothing written.
#[test]
fn refused_combinations_are_one_short_line_naming_the_flag() {
    const RPT: &str = "rpt:sigma=3,alpha=1,beta=2";
    let fpt = ["--v0", "0", "--vt", "0.5"];
    let search = [
        "--xt",
        "1",
        "--v0",
        "0",
        "--reset-position",
        "0",
        "--rate",
        "1",
    ];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "mfpt",
                "distribution",
                "--method",
                "exact",
                "--noise",
                RPT,
                "--temperature",
                "0.5",
                "--v0",
                "0",
                "--vt",
                "1",
            ],
            "--temperature",
        ),
        (
            [
                &["mfpt", "--method", "exact", "--temperature", "0.5"][..],
                &fpt,
            ]
            .concat(),
            "--temperature",
        ),
        (
            [
                &["mfpt", "--drag", "cubic", "--temperature", "0.5"][..],
                &fpt,
            ]
            .concat(),
            "--drag",
        ),
        (
            [&["mfpt", "--drag", "tan", "--temperature", "2"][..], &fpt].concat(),
            "--temperature",
        ),
        (
            [
                &[
                    "mfpt",
                    "optimize",
                    "--drag",
                    "cubic",
                    "--noise",
                    RPT,
                    "--temperature",
                    "0.5",
                ][..],
                &fpt,
            ]
            .concat(),
            "--drag",
        ),
        (
            [&["mfpt", "--reset-clock", "gamma:k=2,theta=1"][..], &fpt].concat(),
            "--reset-clock",
        ),
        (
            [
                &[
                    "mfpt",
                    "distribution",
                    "--noise",
                    RPT,
                    "--reset-position",
                    "0",
                    "--rate",
                    "1",
                ][..],
                &fpt,
            ]
            .concat(),
            "--reset-position",
        ),
        (
            vec!["fp", "stationary", "--reset-period", "2"],
            "--reset-period",
        ),
        (
            vec![
                "fp",
                "stationary",
                "--refractory",
                "fixed:t=1",
                "--rate",
                "1",
            ],
            "--refractory",
        ),
        (
            vec![
                "fp",
                "msd",
                "--noise",
                RPT,
                "--rate",
                "1",
                "--reset-position",
                "0",
            ],
            "--reset-position",
        ),
        (
            vec!["analytic", "--noise", RPT, "--drag", "tan", "--rate", "1"],
            "--noise",
        ),
        (
            [
                &["mfpt", "--method", "renewal", "--refractory", "exp:mean=1"][..],
                &search,
            ]
            .concat(),
            "--refractory",
        ),
        (
            [
                &["mfpt", "--method", "backward", "--refractory", "fixed:t=1"][..],
                &search,
            ]
            .concat(),
            "--refractory",
        ),
        (
            [
                &["mfpt", "distribution", "--refractory", "fixed:t=1"][..],
                &search,
            ]
            .concat(),
            "--refractory",
        ),
    ];
    let tmp = tempfile::tempdir().unwrap();
    for (i, (args, flag)) in cases.iter().enumerate() {
        let dir = tmp.path().join(format!("o{i}")).join("out");
        std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
        let all = [&args[..], &["--out", dir.to_str().unwrap()][..]].concat();
        let err = assert_rejected(&irtp(&all), flag, &dir);
        let line = err.trim_end();
        assert!(line.chars().count() < 200, "{all:?}: {line}");
        assert!(line.contains(" not run by "), "{all:?}: {line}");
    }
}
