//! Interruptions keep finished work and leave nothing half-written: SIGINT
//! and SIGTERM stop a run with exit 130 / 143 and no staging directory; a
//! SIGKILLed run's staging directory is removed by the next run; a rerun of
//! `reproduce` skips finished figures and gives the same bytes; an `--out`
//! holding another run is refused (exit 2) unless `--force`.

use std::fs;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_irtp"))
}

/// Entries of `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// A simulation long enough to be killed while it computes (1e8 particles).
fn long_run(out: &Path) -> Child {
    bin()
        .args(["simulate", "--particles", "1e8", "--out"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Wait until the run's staging directory exists (it is computing).
/// Wait until a staging directory exists and records its host (a process
/// killed before that record is written leaves a directory that the next
/// run cannot attribute, and keeps).
fn wait_for_staging(parent: &Path) {
    let t0 = Instant::now();
    let recorded =
        |e: &String| e.contains(".partial-") && parent.join(e).join(".irtp-host").exists();
    while !entries(parent).iter().any(recorded) {
        assert!(t0.elapsed() < Duration::from_secs(20), "no staging dir");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(child: &Child, sig: i32) {
    // SAFETY: sends a signal to our own child process.
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, sig) }, 0);
}

#[test]
fn sigint_and_sigterm_stop_cleanly() {
    for (sig, code) in [(libc::SIGINT, 130), (libc::SIGTERM, 143)] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("res");
        let child = long_run(&out);
        wait_for_staging(tmp.path());
        std::thread::sleep(Duration::from_millis(200));
        let t0 = Instant::now();
        signal(&child, sig);
        let o = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "signal {sig}: {stderr}");
        assert!(t0.elapsed() < Duration::from_secs(10), "slow to stop");
        assert!(stderr.contains("interrupted"), "{stderr}");
        assert_eq!(entries(tmp.path()), Vec::<String>::new(), "signal {sig}");
    }
}

#[test]
fn sigkill_staging_is_removed_by_the_next_run() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    let mut child = long_run(&out);
    wait_for_staging(tmp.path());
    child.kill().unwrap();
    child.wait().unwrap();
    // A killed run leaves its staging directory and its (now unlocked)
    // lock file: the kernel released the lock with the process.
    let stale: Vec<String> = entries(tmp.path());
    assert_eq!(stale.len(), 2, "{stale:?}");
    assert_eq!(stale[0], ".res.lock", "{stale:?}");
    assert!(stale[1].starts_with(".res.partial-"), "{stale:?}");
    // A staging dir of a live process (ours) or of another host is kept.
    let live = tmp
        .path()
        .join(format!(".res.partial-{}", std::process::id()));
    fs::create_dir(&live).unwrap();
    fs::write(live.join(".irtp-host"), "here").unwrap();
    let other = tmp.path().join(".res.partial-999999999");
    fs::create_dir(&other).unwrap();
    fs::write(other.join(".irtp-host"), "another-node-of-the-cluster").unwrap();

    let o = bin()
        .args(["simulate", "--particles", "1000", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut expect = vec![
        ".res.partial-999999999".to_string(),
        format!(".res.partial-{}", std::process::id()),
        "res".into(),
    ];
    expect.sort();
    assert_eq!(entries(tmp.path()), expect);
}

fn reproduce(figs: &[&str], out: &Path, extra: &[&str]) -> std::process::Output {
    bin()
        .arg("reproduce")
        .args(figs)
        .args(["--quick", "--seed", "3", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// Figure data files of a directory: name → bytes.
fn figure_bytes(dir: &Path) -> Vec<(String, Vec<u8>)> {
    entries(dir)
        .into_iter()
        .filter(|f| f.starts_with("fig") && !f.ends_with(".json"))
        .map(|f| (f.clone(), fs::read(dir.join(&f)).unwrap()))
        .collect()
}

#[test]
#[ignore = "slow tier"]
fn reproduce_resumes_finished_figures() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    // Uninterrupted run of two figures.
    let o = reproduce(&["fig3", "fig5"], &a, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // One figure, then both: the finished one is skipped.
    let o = reproduce(&["fig5"], &b, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mtime = |f: &str| fs::metadata(b.join(f)).unwrap().modified().unwrap();
    let before = mtime("fig5.csv");
    let index: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(b.join("run.json")).unwrap()).unwrap();
    assert_eq!(index["command"], "reproduce fig5");
    std::thread::sleep(Duration::from_millis(20));
    let o = reproduce(&["fig3", "fig5"], &b, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("fig5: skipped"), "{stdout}");
    assert_eq!(mtime("fig5.csv"), before);
    assert_eq!(figure_bytes(&a), figure_bytes(&b));
    assert_eq!(
        fs::read(a.join("claims.json")).unwrap(),
        fs::read(b.join("claims.json")).unwrap()
    );
    // The index lists exactly the figures present, and every file.
    let index: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(b.join("run.json")).unwrap()).unwrap();
    assert_eq!(index["command"], "reproduce fig3 fig5");
    let mut listed: Vec<String> = index["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect();
    listed.sort();
    assert_eq!(listed, entries(&b));
}

#[test]
#[ignore = "slow tier"]
fn reproduce_interrupted_keeps_finished_figures() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("figs");
    let child = bin()
        .args(["reproduce", "fig5", "fig6", "--quick", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Fig. 5 (about 1 s) is committed with its record; stop during Fig. 6.
    let t0 = Instant::now();
    while !out.join("fig5.json").exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "fig5 never finished"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // Fig. 6 takes about 20 s with --quick.
    signal(&child, libc::SIGINT);
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.join("fig6.json").exists() && !out.join("fig6.csv").exists());
    assert!(!entries(tmp.path()).iter().any(|e| e.contains(".partial-")));
    let index: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(index["command"], "reproduce fig5");
}

#[test]
fn out_holding_another_run_is_refused_unless_force() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    let sim = |n: &str, extra: &[&str]| {
        bin()
            .args(["simulate", "--particles", n, "--samples", "5", "--out"])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    assert!(sim("1000", &[]).status.success());
    // The same run again replaces it.
    assert!(sim("1000", &[]).status.success());
    let snapshot = |d: &Path| -> Vec<(String, Vec<u8>)> {
        entries(d)
            .into_iter()
            .map(|f| (f.clone(), fs::read(d.join(&f)).unwrap()))
            .collect()
    };
    let before = snapshot(&out);
    // Other parameters, another command, a foreign file: refused, nothing changed.
    let o = sim("2000", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--out") && err.contains("particles"), "{err}");
    let o = bin()
        .args(["analytic", "--sigma", "3", "--lambda", "0.9", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("irtp simulate"));
    assert_eq!(snapshot(&out), before);
    fs::write(out.join("notes.txt"), "mine").unwrap();
    let o = sim("1000", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("notes.txt"), "{err}");
    let o = reproduce(&["fig5"], &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("notes.txt"));
    assert!(!out.join("fig5.csv").exists());
    // --force replaces irtp's outputs and leaves the foreign file alone.
    let o = bin()
        .args([
            "analytic", "--sigma", "3", "--lambda", "0.9", "--force", "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning") && err.contains("notes.txt"),
        "{err}"
    );
    let run: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["command"], "analytic");
    let mut expect: Vec<String> = run["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .chain(["notes.txt".to_string()])
        .collect();
    expect.sort();
    assert_eq!(entries(&out), expect, "simulate's moments.csv is gone");
    assert_eq!(fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");
    assert_eq!(entries(tmp.path()), ["res"]);
}

#[test]
#[ignore = "slow tier"]
fn reproduce_over_another_seed_is_refused_unless_force() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("figs");
    assert!(reproduce(&["fig5"], &out, &[]).status.success());
    let o = bin()
        .args(["reproduce", "fig5", "--quick", "--seed", "4", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--out") && err.contains("--seed 3"), "{err}");
    let o = bin()
        .args([
            "reproduce",
            "fig5",
            "--quick",
            "--seed",
            "4",
            "--force",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["seed"], 4);
}

/// How long a command may take to exit after SIGTERM: well inside a batch
/// system's grace period and a user's patience with Ctrl-C. The commands
/// poll the stop request every time step, linear-solve row block, mesh,
/// point and particle chunk, so they stop in milliseconds; the margin is
/// for a loaded test machine.
const STOP_WITHIN: Duration = Duration::from_secs(1);

/// Run `irtp ARGS --out DIR/res`, let it work 1.5 s, send SIGTERM and
/// measure the time to exit. Asserts it was still running at the signal,
/// then the documented exit (143, "interrupted" on stderr) and that
/// nothing is left beside it: no `res`, no staging directory, no lock.
fn sigterm_latency(args: &[&str]) -> Duration {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    let mut child = bin()
        .args(args)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    assert!(
        child.try_wait().unwrap().is_none(),
        "{args:?} ended before the signal: make it longer"
    );
    let t0 = Instant::now();
    signal(&child, libc::SIGTERM);
    let o = child.wait_with_output().unwrap();
    let latency = t0.elapsed();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(143), "{args:?}: {stderr}");
    assert!(
        stderr.contains("interrupted by SIGTERM"),
        "{args:?}: {stderr}"
    );
    assert_eq!(entries(tmp.path()), Vec::<String>::new(), "{args:?}");
    latency
}

/// Every command line of `cases` stops within [`STOP_WITHIN`] of SIGTERM;
/// all are measured before the verdict, which lists each latency.
fn assert_prompt_stops(cases: &[&str]) {
    let measured: Vec<(&str, Duration)> = cases
        .iter()
        .map(|line| {
            let args: Vec<&str> = line.split_whitespace().collect();
            (*line, sigterm_latency(&args))
        })
        .collect();
    let report: Vec<String> = measured
        .iter()
        .map(|(cmd, d)| format!("irtp {cmd}: {:.3} s", d.as_secs_f64()))
        .collect();
    eprintln!("{}", report.join("\n"));
    assert!(
        measured.iter().all(|(_, d)| *d < STOP_WITHIN),
        "slow to stop after SIGTERM:\n{}",
        report.join("\n")
    );
}

/// The fast tier: a time-stepping solver (TR-BDF2), the 2-D search
/// solver (a band factorisation of tens of seconds) and a search Euler
/// sampler.
#[test]
fn sigterm_stops_long_solvers_within_a_second() {
    assert_prompt_stops(&[
        "fp transient --t-max 200 --cells 20000 --max-work 1e13",
        "mfpt --v0 0 --xt 1 --reset-position 0 --cells-x 200 --cells-v 60 --max-work 1e16",
        "mfpt --v0 0 --xt 1 --reset-position 0 --method euler --dt 1e-3 --particles 1e6 \
         --max-work 1e14",
    ]);
}

/// Every other long command: particles (exact, Euler), the Fokker-Planck
/// solvers, the velocity and search targets' backward, distribution,
/// scan, optimize and renewal routes, and figures. Each runs for many
/// seconds uninterrupted.
#[test]
#[ignore = "slow tier: 21 commands of about 2 s each"]
fn sigterm_stops_every_long_command_within_a_second() {
    assert_prompt_stops(&[
        "simulate --particles 1e8",
        "simulate --method euler --particles 1e6 --dt 1e-3",
        "fp stationary --cells 2000000",
        "fp msd --cells 50000",
        "mfpt --v0 0 --vt 1 --cells 2000000",
        "mfpt --v0 0 --vt 1 --method exact --particles 1e9",
        "mfpt --v0 0 --vt 1 --method euler --dt 1e-4 --particles 1e6",
        "mfpt distribution --v0 0 --vt 1 --cells 50000",
        "mfpt distribution --v0 0 --vt 1 --method exact --particles 1e9",
        "mfpt scan --v0 0 --vt 1 --over rate --from 0.1 --to 10 --points 200 --cells 2000000",
        "mfpt optimize --v0 0 --vt 1 --cells 2000000",
        "mfpt --v0 0 --xt 1 --reset-position 0 --method exact --particles 1e8",
        "mfpt --v0 0 --xt 1 --reset-position 0 --method renewal --reset-clock gamma:k=2,theta=0.5 \
         --rate 0 --cells-x 60 --cells-v 60 --max-work 1e16",
        "mfpt distribution --v0 0 --xt 1 --reset-position 0 --cells-x 100 --cells-v 60 \
         --max-work 1e16",
        "mfpt distribution --v0 0 --xt 1 --reset-position 0 --method exact --particles 1e8",
        "mfpt scan --v0 0 --xt 1 --reset-position 0 --over rate --from 0.5 --to 5 --points 20 \
         --cells-x 100 --cells-v 60 --max-work 1e16",
        "mfpt optimize --v0 0 --xt 1 --reset-position 0 --r-min 0.5 --cells-x 60 --cells-v 60 \
         --max-work 1e16",
        "mfpt scan --interval=-1,1 --v0 0 --over rate --from 0.5 --to 5 --points 20 \
         --cells-x 100 --cells-v 60 --max-work 1e16",
        "reproduce fig2",
        "reproduce fig6 --quick",
        "reproduce fig7 --quick",
    ]);
}
