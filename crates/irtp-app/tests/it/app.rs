//! The library's command layer (`irtp_app`), as the front ends use it:
//! a cancelled run writes nothing; the outcome's tables are the CSV files.

use clap::Parser;
use irtp::parallel::{NoProgress, Progress};
use irtp_app::{self as app, Cli, Context, Reporter};
use std::sync::atomic::{AtomicU64, Ordering};

/// Cancels once `after` progress stages have been opened.
struct CancelAfter {
    stages: AtomicU64,
    after: u64,
}

impl Reporter for CancelAfter {
    fn stage(&self, _label: &str, _total: u64) -> Box<dyn Progress + '_> {
        self.stages.fetch_add(1, Ordering::Relaxed);
        Box::new(NoProgress)
    }
    fn cancelled(&self) -> bool {
        self.stages.load(Ordering::Relaxed) >= self.after
    }
}

fn cli(args: &[&str]) -> Cli {
    Cli::try_parse_from(std::iter::once("irtp").chain(args.iter().copied())).expect("valid flags")
}

#[test]
fn a_cancelled_run_is_refused_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let out_s = out.to_str().unwrap();
    let runs: [&[&str]; 3] = [
        &["simulate", "--particles", "5000", "--out", out_s],
        &[
            "simulate",
            "--method",
            "euler",
            "--particles",
            "500",
            "--out",
            out_s,
        ],
        &[
            "fp",
            "transient",
            "--t-max",
            "2",
            "--cells",
            "200",
            "--out",
            out_s,
        ],
    ];
    for args in runs {
        let reporter = CancelAfter {
            stages: AtomicU64::new(0),
            after: 1,
        };
        let ctx = Context::new(&reporter);
        let r = app::run(&cli(args).command, &ctx);
        assert_eq!(r.err(), Some(irtp::Error::Interrupted), "{args:?}");
        assert!(!out.exists(), "{args:?}");
        assert_eq!(
            std::fs::read_dir(tmp.path()).unwrap().count(),
            0,
            "{args:?}"
        );
    }
}

#[test]
fn outcome_tables_are_the_written_csv_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let args = [
        "simulate",
        "--particles",
        "300",
        "--out",
        out.to_str().unwrap(),
    ];
    let ctx = Context::new(&app::Quiet);
    let o = app::run(&cli(&args).command, &ctx).unwrap();
    assert_eq!(o.results.tables.len(), 2);
    for t in &o.results.tables {
        let text = std::fs::read_to_string(out.join(format!("{}.csv", t.name))).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), t.header.join(","));
        for (i, line) in lines.enumerate() {
            let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            let row: Vec<f64> = t.columns.iter().map(|c| c[i]).collect();
            assert_eq!(cells.len(), row.len());
            for (a, b) in cells.iter().zip(&row) {
                assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()));
            }
        }
    }
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run, o.provenance);
}
