//! A user's data is never lost: one writer per `--out` (a second is refused
//! naming the lock), sweep workers sharing one directory compute each point
//! once, edited / truncated / deleted files of a finished point are
//! reported by `status`, `merge` and a rerun, and `--force` removes only
//! plain files irtp wrote and nobody changed.

use std::fs;
use std::path::Path;
use std::process::{Command, Output, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_irtp"))
}

fn irtp(args: &[&str]) -> Output {
    bin().args(args).output().expect("run irtp")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn a_second_writer_of_one_out_is_refused_naming_the_lock() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    let spawn = |seed: &str| {
        bin()
            .args(["simulate", "--particles", "2e5", "--seed", seed, "--out"])
            .arg(&out)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("1"), spawn("2"));
    let outs = [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()];
    let won: Vec<&Output> = outs.iter().filter(|o| o.status.success()).collect();
    let lost: Vec<&Output> = outs.iter().filter(|o| !o.status.success()).collect();
    assert_eq!(
        won.len(),
        1,
        "{:?}",
        outs.iter().map(text).collect::<Vec<_>>()
    );
    let msg = text(lost[0]);
    assert_eq!(lost[0].status.code(), Some(2), "{msg}");
    assert!(
        msg.contains("is writing it now") && msg.contains(".res.lock"),
        "{msg}"
    );
    // The winner's files are whole and the lock is gone with it.
    let run: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    for (f, sum) in run["checksums"].as_object().unwrap() {
        let bytes = fs::read(out.join(f)).unwrap();
        assert!(sum.as_str().unwrap().starts_with("sha256:"), "{f}");
        assert!(!bytes.is_empty(), "{f}");
    }
    assert!(!tmp.path().join(".res.lock").exists());
}

/// A run.json in `dir` whose file list names `files` (a hand-made or
/// tampered provenance file).
fn fake_run_json(dir: &Path, files: &[&str]) {
    let v = serde_json::json!({
        "software": "irtp", "command": "simulate", "files": files,
        "checksums": {"data.csv": "sha256:00"},
    });
    fs::write(dir.join("run.json"), v.to_string()).unwrap();
}

#[test]
fn force_removes_only_plain_files_irtp_wrote_unchanged() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("res");
    fs::create_dir_all(out.join("sub")).unwrap();
    fs::write(out.join("sub/keep.txt"), "user data").unwrap();
    fs::write(tmp.path().join("outside.txt"), "user data").unwrap();
    fs::write(out.join("data.csv"), "edited by hand").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(tmp.path().join("outside.txt"), out.join("link")).unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &["sub"],
            "sub, which irtp's provenance lists but which is a directory",
        ),
        (&["link"], "is a symbolic link"),
        (&["data.csv"], "changed since irtp wrote it"),
        (&["../outside.txt"], "is not named as irtp names its files"),
    ];
    for (files, why) in cases {
        if cfg!(not(unix)) && files[0] == "link" {
            continue;
        }
        fake_run_json(&out, files);
        let o = irtp(&[
            "simulate",
            "--particles",
            "100",
            "--force",
            "--out",
            out.to_str().unwrap(),
        ]);
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(2), "{files:?}: {msg}");
        assert!(
            msg.contains(why) && msg.contains("never removes it"),
            "{files:?}: {msg}"
        );
        assert_eq!(msg.trim().lines().count(), 1, "{msg}");
    }
    assert_eq!(
        fs::read_to_string(out.join("sub/keep.txt")).unwrap(),
        "user data"
    );
    assert_eq!(
        fs::read_to_string(tmp.path().join("outside.txt")).unwrap(),
        "user data"
    );
    assert_eq!(
        fs::read_to_string(out.join("data.csv")).unwrap(),
        "edited by hand"
    );
    assert!(!out.join("summary.json").exists(), "nothing written");

    // A real run's file edited afterwards is not replaced either; unedited,
    // --force replaces the run.
    let fresh = tmp.path().join("fresh");
    let f = fresh.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut a = vec!["simulate", "--particles", "100", "--out", f];
        a.extend(extra);
        irtp(&a)
    };
    assert!(run(&[]).status.success());
    assert!(run(&["--seed", "5", "--force"]).status.success());
    fs::write(fresh.join("moments.csv"), "t,v\n0,0\n").unwrap();
    let o = run(&["--seed", "6", "--force"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("moments.csv"), "{}", text(&o));
    assert_eq!(
        fs::read_to_string(fresh.join("moments.csv")).unwrap(),
        "t,v\n0,0\n"
    );
}

/// Four quick simulate points.
const PLAN: &str = r#"
command = "simulate"
seed = 11

[fixed]
particles = 400
t_max = 1.0
burn_in = 0.5
samples = 4
bins = 8

[axes]
sigma = [1.0, 2.0]
rate = [0.5, 2.0]
"#;

/// results.csv without the wall_time_s column (it times the run).
fn table(dir: &Path) -> Vec<Vec<String>> {
    let t = fs::read_to_string(dir.join("results.csv")).unwrap();
    let mut r = csv::Reader::from_reader(t.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let wall = header.iter().position(|h| h == "wall_time_s").unwrap();
    let mut rows = vec![header.clone()];
    for rec in r.records() {
        let rec = rec.unwrap();
        rows.push(
            rec.iter()
                .enumerate()
                .filter(|(i, _)| *i != wall)
                .map(|(_, c)| c.to_string())
                .collect(),
        );
    }
    rows
}

/// The number after "ran " in a `sweep run` report.
fn ran(stdout: &str) -> usize {
    let rest = stdout.split("ran ").nth(1).expect("a run report");
    rest.split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn concurrent_sweep_workers_compute_each_point_once() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = tmp.path().join("plan.toml");
    fs::write(&plan, PLAN.replace("particles = 400", "particles = 40000")).unwrap();
    let single = tmp.path().join("single");
    let o = irtp(&[
        "sweep",
        "run",
        plan.to_str().unwrap(),
        "--out",
        single.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let shared = tmp.path().join("shared");
    let spawn = || {
        bin()
            .args(["sweep", "run"])
            .arg(&plan)
            .arg("--out")
            .arg(&shared)
            .env("RAYON_NUM_THREADS", "1")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let workers: Vec<_> = (0..3).map(|_| spawn()).collect();
    let mut total = 0;
    for w in workers {
        let o = w.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", text(&o));
        total += ran(&String::from_utf8_lossy(&o.stdout));
    }
    assert_eq!(total, 4, "every point computed exactly once");
    assert_eq!(table(&shared), table(&single));
    let status = irtp(&["sweep", "status", shared.to_str().unwrap()]);
    assert!(status.status.success(), "{}", text(&status));
    assert!(!text(&status).contains("leftovers"), "{}", text(&status));
}

/// The point directories of a sweep, in plan order.
fn points(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = fs::read_dir(dir.join("workspace"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.file_name().unwrap().to_string_lossy().starts_with('.'))
        .collect();
    v.sort();
    v
}

#[test]
fn edited_truncated_and_deleted_point_files_are_reported_everywhere() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = tmp.path().join("plan.toml");
    fs::write(&plan, PLAN).unwrap();
    let dir = tmp.path().join("sw");
    let (p, d) = (plan.to_str().unwrap(), dir.to_str().unwrap());
    assert!(irtp(&["sweep", "run", p, "--out", d]).status.success());
    let clean = table(&dir);
    let pts = points(&dir);
    // Edit a number in one result, truncate one output, delete another.
    let r = pts[0].join("result.json");
    let edited = fs::read_to_string(&r)
        .unwrap()
        .replacen("\"v2\": ", "\"v2\": 1", 1);
    assert_ne!(edited, fs::read_to_string(&r).unwrap(), "v2 in the summary");
    fs::write(&r, edited).unwrap();
    let m = pts[1].join("moments.csv");
    let len = fs::metadata(&m).unwrap().len();
    fs::OpenOptions::new()
        .write(true)
        .open(&m)
        .unwrap()
        .set_len(len / 2)
        .unwrap();
    fs::remove_file(pts[2].join("density.csv")).unwrap();
    let why = [
        "result.json was changed since the point finished",
        "moments.csv was changed since the point finished",
        "density.csv is missing",
    ];

    let status = irtp(&["sweep", "status", d]);
    assert_eq!(status.status.code(), Some(3), "{}", text(&status));
    let merge = irtp(&["sweep", "merge", d]);
    assert_eq!(merge.status.code(), Some(3), "{}", text(&merge));
    for w in why {
        assert!(text(&status).contains(w), "status: {w}: {}", text(&status));
        assert!(text(&merge).contains(w), "merge: {w}: {}", text(&merge));
    }
    assert!(text(&status).contains("3 damaged"), "{}", text(&status));
    let rows = table(&dir);
    assert_eq!(
        rows.iter()
            .filter(|r| r.contains(&"damaged".to_string()))
            .count(),
        3
    );

    // A rerun moves the damaged points aside (kept) and computes them again.
    let rerun = irtp(&["sweep", "run", p, "--out", d]);
    assert!(rerun.status.success(), "{}", text(&rerun));
    for w in why {
        assert!(text(&rerun).contains(w), "rerun: {w}: {}", text(&rerun));
    }
    assert_eq!(ran(&String::from_utf8_lossy(&rerun.stdout)), 3);
    assert_eq!(table(&dir), clean, "recomputed bit for bit");
    let status = irtp(&["sweep", "status", d]);
    assert!(status.status.success(), "{}", text(&status));
    assert!(
        text(&status).contains("3 damaged point directories moved aside"),
        "{}",
        text(&status)
    );
}

/// Every entry under `dir` with its content (files) or kind.
fn tree(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let name = p.strip_prefix(dir).unwrap().display().to_string();
            if p.is_dir() {
                stack.push(p.clone());
                out.push((name, b"dir".to_vec()));
            } else {
                out.push((name, fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// No command writes into a sweep but `irtp sweep` (and a plot beside it
/// or in a point): an --out equal to the sweep or inside any of its parts
/// is one line naming --out, exit 2, the sweep untouched; a directory
/// that is no sweep given to a sweep command is refused naming DIR.
#[test]
fn no_writer_touches_a_sweep() {
    let tmp = tempfile::tempdir().unwrap();
    let plan = tmp.path().join("plan.toml");
    let plan_text = "command = \"analytic\"\n[fixed]\npoints = 20\n[axes]\nsigma = [2.0, 3.0]\n";
    fs::write(&plan, plan_text).unwrap();
    let sw = tmp.path().join("sw");
    let plan_s = plan.to_str().unwrap();
    let o = irtp(&["sweep", "run", plan_s, "--out", sw.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let point = fs::read_dir(sw.join("workspace"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| !p.file_name().unwrap().to_string_lossy().starts_with('.'))
        .unwrap();
    let before = tree(tmp.path());
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let inside = [
        sw.clone(),
        sw.join("workspace"),
        sw.join("workspace/new"),
        point.clone(),
        sw.join("runs/x"),
        sw.join(".signac"),
    ];
    let mut cases: Vec<Vec<String>> = Vec::new();
    for o in &inside {
        cases.push(vec![
            "analytic".into(),
            "--points".into(),
            "20".into(),
            "--force".into(),
        ]);
        cases.last_mut().unwrap().extend(["--out".into(), s(o)]);
        if *o != sw {
            // (into the sweep itself, `sweep run` resumes it)
            cases.push(vec![
                "sweep".into(),
                "run".into(),
                plan_s.into(),
                "--out".into(),
                s(o),
            ]);
            cases.push(vec![
                "sweep".into(),
                "slurm".into(),
                plan_s.into(),
                "--max-array".into(),
                "100".into(),
                "--out".into(),
                s(o),
            ]);
        }
        cases.push(vec![
            "sweep".into(),
            "merge".into(),
            s(&o.join("m")),
            s(&sw),
        ]);
    }
    cases.push(vec![
        "plot".into(),
        s(&point),
        "--out".into(),
        s(&sw.join("workspace/x.png")),
    ]);
    cases.push(vec![
        "plot".into(),
        s(&point),
        "--out".into(),
        s(&sw.join("runs/x.png")),
    ]);
    for args in &cases {
        let o = bin().args(args).output().unwrap();
        let err = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains("invalid --out"), "{args:?}: {err}");
    }
    // Not a sweep: named as the DIR argument.
    let user = tmp.path().join("user");
    fs::create_dir(&user).unwrap();
    for sub in ["status", "merge", "collect"] {
        let mut args = vec!["sweep", sub, user.to_str().unwrap()];
        if sub == "collect" {
            args.extend(["--out", "x.nc"]);
        }
        let o = irtp(&args);
        let err = text(&o);
        assert_eq!(o.status.code(), Some(2), "{sub}: {err}");
        assert!(
            err.contains("invalid DIR") && err.contains("plan.toml"),
            "{err}"
        );
    }
    fs::remove_dir(&user).unwrap();
    assert!(
        tree(tmp.path()) == before,
        "a refused command changed the tree"
    );
    let o = irtp(&["sweep", "status", sw.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
}

/// A fixed-seed generator (SplitMix64) for the fuzz test.
struct Draw(u64);

impl Draw {
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        &items[((z ^ (z >> 31)) % items.len() as u64) as usize]
    }
}

/// Whether every file `dir/run.json` lists verifies against its checksum.
fn run_verifies(dir: &Path) -> bool {
    use sha2::Digest as _;
    let Ok(text) = fs::read_to_string(dir.join("run.json")) else {
        return false;
    };
    let run: serde_json::Value = serde_json::from_str(&text).unwrap();
    run["checksums"]
        .as_object()
        .unwrap()
        .iter()
        .all(|(f, sum)| {
            let bytes = fs::read(dir.join(f)).unwrap_or_default();
            let hex: String = sha2::Sha256::digest(&bytes)
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            sum.as_str() == Some(&format!("sha256:{hex}"))
        })
}

/// Fuzz (fixed seed) of the writers and readers of the binary over input
/// directories and output paths (the sweep, its parts, the user's files and
/// directories, missing parents, non-sweep directories, new paths): each
/// answer is verified output (only the output path changed) or one line,
/// exit 2, with the whole tree unchanged. `sweep collect` through Python is
/// fuzzed by python/tests/test_out_safety.py.
#[test]
#[ignore = "slow tier: 400 commands"]
fn fuzz_writers_never_touch_what_they_did_not_write() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let plan = root.join("plan.toml");
    let plan_text =
        "command = \"analytic\"\n[fixed]\npoints = 20\n[axes]\nsigma = [2.0, 3.0]\nrate = [0.0]\n";
    fs::write(&plan, plan_text).unwrap();
    let sw = root.join("sw");
    assert!(irtp(&[
        "sweep",
        "run",
        plan.to_str().unwrap(),
        "--out",
        sw.to_str().unwrap()
    ])
    .status
    .success());
    fs::create_dir_all(root.join("user/sub")).unwrap();
    fs::write(root.join("user/a.txt"), "the user's").unwrap();
    fs::write(root.join("user.png"), "not an image of irtp").unwrap();
    fs::create_dir(root.join("empty")).unwrap();
    let point = fs::read_dir(sw.join("workspace"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| !p.file_name().unwrap().to_string_lossy().starts_with('.'))
        .unwrap();
    let inputs = [
        sw.clone(),
        point.clone(),
        root.join("user"),
        root.join("missing"),
    ];
    let mut draw = Draw(20_261_206);
    let mut answered: std::collections::BTreeMap<(String, Option<i32>), u32> = Default::default();
    for case in 0..400 {
        let fresh = root.join(format!("new{case}"));
        let outs = [
            sw.clone(),
            sw.join("workspace"),
            point.clone(),
            sw.join("runs/x"),
            sw.join("x.png"),
            sw.join("workspace/x.png"),
            root.join("user"),
            root.join("user/a.txt"),
            root.join("user.png"),
            root.join("empty"),
            root.join("missing/dir/x"),
            root.to_path_buf(),
            fresh.clone(),
            fresh.with_extension("png"),
            fresh.with_extension("svg"),
        ];
        let src = draw.pick(&inputs).to_str().unwrap().to_string();
        let out = draw.pick(&outs).clone();
        let o_s = out.to_str().unwrap().to_string();
        let plan_s = plan.to_str().unwrap().to_string();
        let args: Vec<String> = match *draw.pick(&[0, 1, 2, 3, 4]) {
            0 => ["analytic", "--points", "20", "--out", &o_s]
                .iter()
                .map(|s| s.to_string())
                .collect(),
            1 => vec!["plot".into(), src.clone(), "--out".into(), o_s.clone()],
            2 => vec!["sweep".into(), "merge".into(), o_s.clone(), src.clone()],
            3 => vec![
                "sweep".into(),
                "run".into(),
                plan_s,
                "--out".into(),
                o_s.clone(),
            ],
            _ => vec!["sweep".into(), "status".into(), src.clone()],
        };
        let before = tree(root);
        let o = bin().args(&args).output().unwrap();
        let after = tree(root);
        let msg = text(&o);
        let code = o.status.code();
        *answered.entry((args[0].clone(), code)).or_insert(0) += 1;
        assert!(
            !after.iter().any(|(f, _)| f.contains(".partial-")),
            "{args:?}"
        );
        match (args[0].as_str(), args.get(1).map(String::as_str)) {
            ("sweep", Some("status")) => {
                assert!(matches!(code, Some(0 | 2 | 3)), "{args:?}: {msg}");
                assert!(after == before, "{args:?} changed the tree");
                continue;
            }
            _ if code != Some(0) => {
                assert_eq!(code, Some(2), "{args:?}: {msg}");
                assert_eq!(msg.trim().lines().count(), 1, "{args:?}: {msg}");
                assert!(
                    msg.contains("invalid --out") || msg.contains("invalid DIR"),
                    "{msg}"
                );
                assert!(after == before, "{args:?} was refused but changed the tree");
                continue;
            }
            _ => {}
        }
        // Verified answers, and nothing changed but the output (and, for
        // `sweep run` into the sweep itself, its run record).
        let rel = out.strip_prefix(root).unwrap().display().to_string();
        let changed: Vec<&String> = before
            .iter()
            .chain(after.iter())
            .map(|(f, _)| f)
            .filter(|f| before.iter().find(|e| &e.0 == *f) != after.iter().find(|e| &e.0 == *f))
            .collect();
        // (a run creates the missing directories above its --out)
        let mine = |f: &&String| {
            *f == &rel || f.starts_with(&format!("{rel}/")) || rel.starts_with(&format!("{f}/"))
        };
        assert!(changed.iter().all(mine), "{args:?}: {changed:?}");
        match args[0].as_str() {
            "analytic" => assert!(run_verifies(&out), "{args:?}"),
            "plot" => assert!(fs::read(&out)
                .unwrap()
                .windows(9)
                .any(|w| w == b"irtp plot")),
            _ => assert!(out.join("results.csv").is_file(), "{args:?}"),
        }
    }
    let o = irtp(&["sweep", "status", sw.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(
        fs::read_to_string(root.join("user/a.txt")).unwrap(),
        "the user's"
    );
    // The draw reaches both answers of every writer.
    for w in ["analytic", "plot", "sweep"] {
        for c in [Some(0), Some(2)] {
            assert!(answered.contains_key(&(w.to_string(), c)), "{answered:?}");
        }
    }
}
