//! The search's methods as the command layer runs them: `irtp mfpt --xt
//! --method renewal` is the library's renewal route (same options, same
//! bits), `--method euler` its Euler extrapolation.

use clap::Parser;
use irtp::model::reset::Schedule;
use irtp::parallel::NoProgress;
use irtp::search::renewal::{self, RenewalOptions, WaitingTime};
use irtp::search::{self, PositionTarget, SearchMethod, SearchProblem};
use irtp::{DragLaw, Params};
use irtp_app::{self as app, Cli, Context};

fn run(args: &[&str]) -> serde_json::Value {
    let cli = Cli::try_parse_from(std::iter::once("irtp").chain(args.iter().copied()))
        .expect("valid flags");
    let ctx = Context::new(&app::Quiet);
    app::run(&cli.command, &ctx).unwrap().results.json
}

/// The linear-drag level search of both runs: full resetting to (0, 0) at
/// rate 0.5, sigma 1, lambda 1.
fn problem() -> SearchProblem {
    let schedule = Schedule::parse(None, Some(0.0), None).unwrap();
    let p = Params::new(DragLaw::Linear, 1.0, 1.0, 0.5, 0.0)
        .unwrap()
        .with_schedule(schedule)
        .unwrap();
    SearchProblem::new(p, 0.0, 0.0, PositionTarget::Level(0.8)).unwrap()
}

const BASE: [&str; 14] = [
    "mfpt",
    "--xt",
    "0.8",
    "--v0",
    "0",
    "--drag",
    "linear",
    "--sigma",
    "1",
    "--lambda",
    "1",
    "--rate",
    "0.5",
    "--reset-position",
];

#[test]
fn the_renewal_route_on_the_command_line_is_the_librarys() {
    let extra = [
        "0",
        "--method",
        "renewal",
        "--cells-x",
        "16",
        "--cells-v",
        "8",
        "--time-steps",
        "40",
        "--horizon-tail",
        "1e-6",
    ];
    let cli = run(&[&BASE[..], &extra[..]].concat());
    let opts = RenewalOptions {
        cells_x: 16,
        cells_v: 8,
        steps: 40,
        tail: 1e-6,
        ..Default::default()
    };
    let pr = problem();
    let lib = renewal::solve(&pr, &WaitingTime::of(pr.params()).unwrap(), &opts).unwrap();
    for (k, x) in [
        ("tau", lib.tau),
        ("tau_plus", lib.tau_plus),
        ("tau_minus", lib.tau_minus),
        ("error_estimate", lib.error_estimate),
        ("textbook", lib.textbook),
    ] {
        assert_eq!(cli[k].as_f64().unwrap().to_bits(), x.to_bits(), "{k}");
    }
    assert_eq!(cli["options"]["horizon_tail"], serde_json::Value::Null);
    assert_eq!(cli["options"]["tail"], 1e-6);
}

#[test]
fn the_euler_search_on_the_command_line_is_the_librarys() {
    let extra = [
        "0",
        "--method",
        "euler",
        "--dt",
        "0.05",
        "--particles",
        "2000",
        "--seed",
        "4",
    ];
    let cli = run(&[&BASE[..], &extra[..]].concat());
    let method = SearchMethod::Euler {
        dt: 0.05,
        run: irtp::mfpt::ParticleOptions {
            particles: 2000,
            t_max: 1e4,
            seed: 4,
        },
    };
    let lib = search::solve(&problem(), &method, &NoProgress).unwrap();
    let (tau, _, _, err) = lib.tau();
    assert_eq!(cli["tau"].as_f64().unwrap().to_bits(), tau.to_bits());
    assert_eq!(cli["tau_err"].as_f64().unwrap().to_bits(), err.to_bits());
}
