//! `irtp sweep`: plans checked before work, shards that merge into the
//! single run's table, resume after SIGKILL, foreign directories refused.

use std::path::Path;
use std::process::{Command, Output};

fn irtp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_irtp"))
        .args(args)
        .output()
        .expect("run irtp")
}

fn ok(args: &[&str]) -> String {
    let o = irtp(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// A seeded plan: 3 x 2 simulate points crossed with a zipped pair.
const PLAN: &str = r#"
command = "simulate"
seed = 7

[fixed]
particles = 300
t_max = 2.0
burn_in = 1.0
samples = 5
bins = 10

[axes]
sigma = [1.0, 2.0, 3.0]
rate = { from = 0.5, to = 2.0, points = 2, spacing = "log" }

[[zip]]
lambda = [0.5, 2.0]
reset_velocity = [0.0, 0.1]
"#;

fn write_plan(dir: &Path, text: &str) -> String {
    write_plan_as(dir, "plan.toml", text)
}

fn write_plan_as(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

/// results.csv without the wall_time_s column (it times the run).
fn table(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let wall = header.iter().position(|h| h == "wall_time_s").unwrap();
    let mut out = vec![header.join(",")];
    for rec in r.records() {
        let rec = rec.unwrap();
        let cells: Vec<&str> = rec
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != wall)
            .map(|(_, c)| c)
            .collect();
        out.push(cells.join(","));
    }
    out
}

#[test]
fn shards_merge_into_the_single_run_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = write_plan(tmp.path(), PLAN);
    let single = tmp.path().join("single");
    ok(&["sweep", "run", &plan, "--out", single.to_str().unwrap()]);
    let reference = table(&single);
    assert_eq!(reference.len(), 1 + 12, "12 points");
    assert!(
        reference.iter().skip(1).all(|r| r.contains(",ok,")),
        "{reference:?}"
    );
    for n in [2, 7] {
        let dirs: Vec<String> = (1..=n)
            .map(|k| {
                let d = tmp.path().join(format!("n{n}-k{k}"));
                let d = d.to_str().unwrap().to_string();
                ok(&[
                    "sweep",
                    "run",
                    &plan,
                    "--out",
                    &d,
                    "--shard",
                    &format!("{k}/{n}"),
                ]);
                d
            })
            .collect();
        let mut args = vec!["sweep", "merge"];
        args.extend(dirs.iter().map(String::as_str));
        ok(&args);
        assert_eq!(table(Path::new(&dirs[0])), reference, "{n} shards");
    }
}

#[test]
fn resumes_after_sigkill_without_losing_or_mixing_points() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = write_plan(
        tmp.path(),
        &PLAN.replace("particles = 300", "particles = 4000"),
    );
    let whole = tmp.path().join("whole");
    ok(&["sweep", "run", &plan, "--out", whole.to_str().unwrap()]);
    let out = tmp.path().join("killed");
    // Kill at several moments (fixed, spread over the run), then finish.
    for delay_ms in [40u64, 120, 250, 400] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_irtp"))
            .args(["sweep", "run", &plan, "--out", out.to_str().unwrap()])
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        if !out.join("plan.toml").exists() {
            // Killed while checking the plan, before the store existed (a
            // loaded machine): nothing to resume yet.
            continue;
        }
        let status = irtp(&["sweep", "status", out.to_str().unwrap()]);
        let code = status.status.code();
        assert!(
            code == Some(0) || code == Some(3),
            "{code:?} {}",
            String::from_utf8_lossy(&status.stderr)
        );
    }
    ok(&["sweep", "run", &plan, "--out", out.to_str().unwrap()]);
    assert_eq!(table(&out), table(&whole));
    let s = ok(&["sweep", "status", out.to_str().unwrap()]);
    assert!(s.contains("12 finished (0 failed), 0 missing"), "{s}");
}

#[test]
fn bad_plans_are_refused_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: [(&str, &str); 7] = [
        ("command = \"simulate\"\ncolour = 1\n", "colour"),
        (
            "command = \"simulate\"\n[axes]\nsigma = \"three\"\n",
            "sigma",
        ),
        ("command = \"simulate\"\n[axes]\nsigma = []\n", "sigma"),
        ("command = \"simulate\"\n[fixed]\nwidth = 2\n", "width"),
        ("command = \"simulate\"\n[fixed]\nseed = 2\n", "seed"),
        ("command = \"reproduce\"\n", "command"),
        (
            "command = \"simulate\"\n[fixed]\ndrag = \"tanh\"\n[axes]\nsigma = [0.5, 1.5]\n",
            "point 1",
        ),
    ];
    for (text, needle) in cases {
        let plan = write_plan(tmp.path(), text);
        let out = tmp.path().join("out");
        let o = irtp(&["sweep", "run", &plan, "--out", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{text}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{text}: {err}");
        assert!(!out.exists(), "{text}: nothing written");
    }
}

#[test]
fn foreign_points_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = write_plan(tmp.path(), PLAN);
    let out = tmp.path().join("out");
    ok(&["sweep", "run", &plan, "--out", out.to_str().unwrap()]);
    // Another plan into the same directory: its points are foreign there.
    let other = write_plan_as(
        tmp.path(),
        "other.toml",
        &PLAN.replace("seed = 7", "seed = 8"),
    );
    let o = irtp(&["sweep", "run", &other, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a point of this plan"));
    // A point whose statepoint was edited.
    let ws = out.join("workspace");
    let first = std::fs::read_dir(&ws)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    std::fs::write(
        first.join("signac_statepoint.json"),
        "{\"command\": \"simulate\"}",
    )
    .unwrap();
    let o = irtp(&["sweep", "run", &plan, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("other parameters"), "{err}");
}

#[test]
fn a_failing_point_is_recorded_and_the_sweep_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    // r = 1e6 from v0 far below vt: tau overflows (a numerical failure), r = 1 is fine.
    let plan = write_plan(
        tmp.path(),
        "command = \"mfpt\"\n[fixed]\nv0 = -0.249\nvt = 0.5\ncells = 2000\n[axes]\nrate = [1.0, 1e6]\n",
    );
    let out = tmp.path().join("out");
    let o_s = out.to_str().unwrap();
    // A failed point is not success: exit 3 from run, status, merge and a
    // retry that fails again (pipelines must not take the table as done).
    let exit3 = |args: &[&str]| {
        let o = irtp(args);
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert_eq!(
            o.status.code(),
            Some(3),
            "{args:?}: {text} {}",
            String::from_utf8_lossy(&o.stderr)
        );
        text
    };
    let s = exit3(&["sweep", "run", &plan, "--out", o_s]);
    assert!(s.contains("1 points of this shard failed"), "{s}");
    let t = table(&out);
    assert!(t[1].contains(",ok,"), "{t:?}");
    assert!(t[2].contains(",failed,numerical failure in mfpt"), "{t:?}");
    let s = exit3(&["sweep", "status", o_s]);
    assert!(
        s.contains("2 finished (1 failed)") && s.contains("--retry-failed"),
        "{s}"
    );
    exit3(&["sweep", "merge", o_s]);
    exit3(&["sweep", "run", &plan, "--out", o_s, "--retry-failed"]);
    // A shard whose own points all succeed exits 0 (shard 1/2 holds r = 1).
    let out2 = tmp.path().join("out2");
    ok(&[
        "sweep",
        "run",
        &plan,
        "--out",
        out2.to_str().unwrap(),
        "--shard",
        "1/2",
    ]);
}

#[test]
fn points_split_into_particle_parts_merge_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    // 3 units and a bit of particles per point, in 3 parts: 2 points x 3 parts = 6 items.
    let whole_plan = r#"
command = "simulate"
seed = 3
[fixed]
particles = 12400
t_max = 0.5
burn_in = 0.25
samples = 3
bins = 8
[axes]
method = ["exact", "euler"]
"#;
    let split_plan = format!("particle_parts = 3\n{whole_plan}");
    let whole = write_plan_as(tmp.path(), "whole.toml", whole_plan);
    let split = write_plan_as(tmp.path(), "split.toml", &split_plan);
    let reference = tmp.path().join("whole");
    ok(&["sweep", "run", &whole, "--out", reference.to_str().unwrap()]);
    let one = tmp.path().join("split-one");
    let s = ok(&["sweep", "run", &split, "--out", one.to_str().unwrap()]);
    assert!(s.contains("2 points, 6 work items"), "{s}");
    assert_eq!(table(&one), table(&reference), "parts in one run");
    // 4 shards over the 6 items: every point's parts land in different shards.
    let dirs: Vec<String> = (1..=4)
        .map(|k| {
            let d = tmp
                .path()
                .join(format!("k{k}"))
                .to_str()
                .unwrap()
                .to_string();
            ok(&[
                "sweep",
                "run",
                &split,
                "--out",
                &d,
                "--shard",
                &format!("{k}/4"),
            ]);
            d
        })
        .collect();
    let mut args = vec!["sweep", "merge"];
    args.extend(dirs.iter().map(String::as_str));
    ok(&args);
    assert_eq!(
        table(Path::new(&dirs[0])),
        table(&reference),
        "parts across shards"
    );
    // The assembled outputs are the whole run's, byte for byte.
    let id = std::fs::read_dir(reference.join("workspace"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .file_name();
    for f in ["moments.csv", "density.csv"] {
        let a = std::fs::read(reference.join("workspace").join(&id).join(f)).unwrap();
        let b = std::fs::read(Path::new(&dirs[0]).join("workspace").join(&id).join(f)).unwrap();
        assert_eq!(a, b, "{f}");
    }
}

/// `mfpt` points by particles (a velocity target and a search, exact and
/// Euler) split into 3 parts and run on 1 thread give the table and the
/// outputs of the points run whole on 2 threads, bit for bit; a
/// deterministic method is refused with parts.
#[test]
fn mfpt_points_split_into_particle_parts_merge_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    // Fixed keywords and the axis of two points.
    let targets = [
        ("v0 = 0.0\nvt = 0.5\n", "method = [\"exact\", \"euler\"]"),
        (
            "v0 = 0.0\nxt = 0.5\nreset_position = 0.0\nmethod = \"exact\"\n",
            "rate = [1.0, 2.0]",
        ),
        (
            "v0 = 0.0\nxt = 0.5\nreset_position = 0.0\nmethod = \"euler\"\ndt = 0.02\n",
            "rate = [1.0, 2.0]",
        ),
    ];
    for (i, (target, axis)) in targets.iter().enumerate() {
        let whole_plan = format!(
            "command = \"mfpt\"\nseed = 5\n[fixed]\nparticles = 8200\nt_max = 1000\n{target}\
             [axes]\n{axis}\n"
        );
        let split_plan = format!("particle_parts = 3\n{whole_plan}");
        let whole = write_plan_as(tmp.path(), &format!("whole{i}.toml"), &whole_plan);
        let split = write_plan_as(tmp.path(), &format!("split{i}.toml"), &split_plan);
        let (a, b) = (
            tmp.path().join(format!("w{i}")),
            tmp.path().join(format!("s{i}")),
        );
        let run = |plan: &str, out: &Path, threads: &str| {
            let o = Command::new(env!("CARGO_BIN_EXE_irtp"))
                .args(["sweep", "run", plan, "--out", out.to_str().unwrap()])
                .env("RAYON_NUM_THREADS", threads)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            String::from_utf8(o.stdout).unwrap()
        };
        run(&whole, &a, "2");
        let s = run(&split, &b, "1");
        assert!(s.contains("2 points, 6 work items"), "{s}");
        assert_eq!(table(&b), table(&a), "{target}");
        for entry in std::fs::read_dir(a.join("workspace")).unwrap() {
            let id = entry.unwrap().file_name();
            for f in ["survival.csv", "mfpt.json"] {
                let x = std::fs::read(a.join("workspace").join(&id).join(f)).unwrap();
                let y = std::fs::read(b.join("workspace").join(&id).join(f)).unwrap();
                assert_eq!(x, y, "{f} of {target}");
            }
        }
    }
    let plan = write_plan(
        tmp.path(),
        "command = \"mfpt\"\nparticle_parts = 2\n[fixed]\nv0 = 0.0\nvt = 0.5\n",
    );
    let o = irtp(&[
        "sweep",
        "run",
        &plan,
        "--out",
        tmp.path().join("o").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("particle_parts") && err.contains("deterministic"),
        "{err}"
    );
}

#[test]
fn too_many_parts_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = write_plan(
        tmp.path(),
        "command = \"simulate\"\nparticle_parts = 3\n[fixed]\nparticles = 5000\n",
    );
    let o = irtp(&[
        "sweep",
        "run",
        &plan,
        "--out",
        tmp.path().join("o").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("particle_parts") && err.contains("1 ..= 2"),
        "{err}"
    );
}

/// A point directory named by the ids of an older irtp (SHA-256 of the
/// compact statepoint) is renamed to its signac id when the sweep is
/// opened again: nothing is computed twice, nothing lost, the table the
/// same.
#[test]
fn point_directories_of_an_older_irtp_are_renamed_to_signac_ids() {
    use sha2::{Digest, Sha256};
    let tmp = tempfile::tempdir().unwrap();
    let plan = write_plan(tmp.path(), PLAN);
    let out = tmp.path().join("sw");
    let out_s = out.to_str().unwrap();
    ok(&["sweep", "run", &plan, "--out", out_s]);
    let before = table(&out);
    let ws = out.join("workspace");
    let mut renamed = 0;
    for e in std::fs::read_dir(&ws).unwrap() {
        let path = e.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let sp = std::fs::read_to_string(path.join("signac_statepoint.json")).unwrap();
        let sp: serde_json::Value = serde_json::from_str(&sp).unwrap();
        let old: String = Sha256::digest(sp.to_string())
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        std::fs::rename(&path, ws.join(&old[..32])).unwrap();
        renamed += 1;
    }
    assert_eq!(renamed, 12);
    let s = ok(&["sweep", "run", &plan, "--out", out_s]);
    assert!(s.contains("ran 0 "), "{s}");
    assert_eq!(table(&out), before);
}

/// `irtp sweep collect` with a Python that cannot run the module: refused
/// naming --python, nothing written (the Python tests run it for real).
#[test]
fn collect_without_the_python_module_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = write_plan(
        tmp.path(),
        PLAN.replace("particles = 300", "particles = 50").as_str(),
    );
    let out = tmp.path().join("sw");
    ok(&[
        "sweep",
        "run",
        &plan,
        "--out",
        out.to_str().unwrap(),
        "--shard",
        "1/12",
    ]);
    let nc = tmp.path().join("sw.nc");
    let missing = tmp.path().join("no-python");
    let o = irtp(&[
        "sweep",
        "collect",
        out.to_str().unwrap(),
        "--out",
        nc.to_str().unwrap(),
        "--python",
        missing.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--python") && err.contains("xarray extra"),
        "{err}"
    );
    assert!(!nc.exists());
}

/// `sweep status`, `sweep merge` and `sweep run` apply one rule to a
/// directory holding what the sweep does not know about: merge and run
/// refuse it, status reports it as not complete (exit 3) with that refusal.
#[test]
fn status_merge_and_run_agree_on_a_foreign_entry() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = write_plan(
        tmp.path(),
        "command = \"analytic\"\n[fixed]\npoints = 20\n[axes]\nsigma = [2.0, 3.0]\n",
    );
    let out = tmp.path().join("sw");
    let o_s = out.to_str().unwrap();
    ok(&["sweep", "run", &plan, "--out", o_s]);
    for foreign in [out.join("workspace/notes.txt"), out.join("mine/a.txt")] {
        std::fs::create_dir_all(foreign.parent().unwrap()).unwrap();
        std::fs::write(&foreign, "the user's").unwrap();
        let name = foreign.strip_prefix(&out).unwrap().components().next();
        let name = name.unwrap().as_os_str().to_string_lossy().into_owned();
        let status = irtp(&["sweep", "status", o_s]);
        let text = String::from_utf8_lossy(&status.stdout).into_owned();
        assert_eq!(status.status.code(), Some(3), "{text}");
        assert!(
            text.contains("not complete")
                && text.contains(&name)
                && !text.lines().any(|l| l.starts_with("complete:")),
            "{text}"
        );
        for args in [
            vec!["sweep", "merge", o_s],
            vec!["sweep", "run", &plan, "--out", o_s],
        ] {
            let o = irtp(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains(&name), "{err}");
        }
        assert_eq!(std::fs::read_to_string(&foreign).unwrap(), "the user's");
        std::fs::remove_dir_all(out.join("mine")).ok();
        std::fs::remove_file(out.join("workspace/notes.txt")).ok();
    }
    let status = irtp(&["sweep", "status", o_s]);
    assert_eq!(status.status.code(), Some(0));
}
