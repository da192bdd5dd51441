//! Docs that run: every `irtp …` command printed in a shell block of
//! README.md, REPRODUCTION.md, bench/README.md and docs/*.md (and README's
//! `cargo run --release -- …` line) is run as printed, in the repository
//! root, with the changes docs/reference/conventions.md states: each `--out` (and a
//! later argument naming the same directory) goes to a temporary directory,
//! `--particles` is at most [`MAX_PARTICLES`], `reproduce` runs `--quick`
//! and `--submit` is left out (the SLURM test submits); documented commands
//! that become the same command this way run once, and `reproduce all
//! --out DIR` is run (with `--seed 7`) and checked by the reproduce test. Each example sweep plan
//! runs as its header comment says, the long ones ([`LONG_PLANS`]) as one
//! shard of [`LONG_PLAN_SHARDS`] (`--shard 1/N`: every N-th point, through
//! the same plan parsing, point seeds and store). A non-zero exit fails,
//! naming the file and line. Every repository path a doc names in
//! backquotes exists, and so does every file a Markdown link points to
//! (or docs/build.sh generates it: the command reference, the Python API,
//! the reproduction report, a tutorial's figure from its script).

use super::common::BIN;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The particle cap of the documented commands' test runs.
const MAX_PARTICLES: u64 = 4000;

/// The example plans too long to run whole in a test (measured: 58 s and
/// 26 s on 2 cores), run as one shard of [`LONG_PLAN_SHARDS`].
const LONG_PLANS: [&str; 2] = ["fp_stationary_10k.toml", "simulate.toml"];

/// The shards a long plan is cut into in the test: 1/40 of its points.
const LONG_PLAN_SHARDS: usize = 40;

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The documentation files, relative to the repository root: the top-level
/// ones and every page under docs/ (the site's tutorials, how-to guides,
/// reference and explanation), but for `docs/figures`, which `irtp
/// reproduce` writes.
fn doc_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["README.md", "REPRODUCTION.md", "bench/README.md"]
        .iter()
        .map(PathBuf::from)
        .collect();
    let mut docs = Vec::new();
    markdown_under(Path::new("docs"), &mut docs);
    docs.sort();
    files.extend(docs);
    files
}

/// The `.md` files under `dir` (relative to the root), recursively, but for
/// `docs/figures`.
fn markdown_under(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(root().join(dir)).unwrap() {
        let name = e.unwrap().file_name();
        let rel = dir.join(&name);
        if root().join(&rel).is_dir() {
            if rel != Path::new("docs/figures") {
                markdown_under(&rel, out);
            }
        } else if rel.extension().is_some_and(|x| x == "md") {
            out.push(rel);
        }
    }
}

/// (line, arguments after `irtp`) of every command in the shell blocks of
/// `text`: continuation lines (`\`) joined, `# comments` dropped.
fn commands(text: &str) -> Vec<(usize, Vec<String>)> {
    let (mut out, mut in_shell, mut pending) = (Vec::new(), false, None::<(usize, String)>);
    for (i, line) in text.lines().enumerate() {
        if let Some(fence) = line.trim_start().strip_prefix("```") {
            in_shell = !in_shell && matches!(fence.trim(), "sh" | "bash" | "console");
            continue;
        }
        if !in_shell {
            continue;
        }
        let (n, joined) = match pending.take() {
            Some((n, head)) => (n, head + " " + line.trim()),
            None => (i + 1, line.trim().to_string()),
        };
        if let Some(head) = joined.strip_suffix('\\') {
            pending = Some((n, head.to_string()));
            continue;
        }
        let body = joined.strip_prefix("$ ").unwrap_or(&joined);
        let rest = body
            .strip_prefix("irtp ")
            .or_else(|| body.strip_prefix("cargo run --release -- "));
        if let Some(rest) = rest {
            out.push((n, words(rest)));
        }
    }
    out
}

/// Shell words of `s` up to an unquoted `#` comment.
pub fn words(s: &str) -> Vec<String> {
    let mut lexer = shlex::Shlex::new(s);
    let mut w: Vec<String> = (&mut lexer).take_while(|w| !w.starts_with('#')).collect();
    assert!(!lexer.had_error, "unbalanced quotes in {s}");
    w.retain(|x| !x.is_empty());
    w
}

/// The command as the test runs it (see the module doc); `dirs` maps each
/// documented output directory to its temporary one (its extension kept:
/// `--out fig.svg`).
pub fn adapt(args: &[String], tmp: &Path, dirs: &mut HashMap<String, PathBuf>) -> Vec<String> {
    let mut out = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => {
                let doc = it.next().expect("--out takes a directory").clone();
                let n = dirs.len();
                let ext = Path::new(&doc)
                    .extension()
                    .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
                let dir = dirs
                    .entry(doc)
                    .or_insert_with(|| tmp.join(format!("out{n}{ext}")));
                out.extend(["--out".to_string(), dir.display().to_string()]);
            }
            "--particles" => {
                let n: u64 = it.next().unwrap().parse().expect("a particle count");
                out.extend(["--particles".into(), n.min(MAX_PARTICLES).to_string()]);
            }
            "--submit" => {}
            _ => out.push(match dirs.get(a) {
                Some(d) => d.display().to_string(),
                None => a.clone(),
            }),
        }
    }
    if out.first().map(String::as_str) == Some("reproduce") && !out.iter().any(|a| a == "--quick") {
        out.push("--quick".into());
    }
    out
}

/// Run one documented command; panics with its place and stderr on a
/// non-zero exit.
pub fn run(place: &str, args: &[String]) {
    let t0 = std::time::Instant::now();
    let o = Command::new(BIN)
        .args(args)
        .current_dir(root())
        .output()
        .expect("run irtp");
    eprintln!(
        "{place}: {:.1} s: irtp {}",
        t0.elapsed().as_secs_f64(),
        args.join(" ")
    );
    assert!(
        o.status.success(),
        "{place}: irtp {} exited {:?}: {}",
        args.join(" "),
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The documentation files are run in `SHARDS` tests, so they run in
/// parallel: README.md alone, the command cookbook (the most commands:
/// about 110 s on 2 cores) alone, the other pages together; each file's
/// commands in order in one test.
const SHARDS: usize = 3;
/// Every shard at once.
const ALL: usize = usize::MAX;

/// The shard of a documentation file (one of [`doc_files`]).
fn shard_of(file: &Path) -> usize {
    if file == Path::new("README.md") {
        0
    } else if file == Path::new("docs/how-to/examples.md") {
        1
    } else {
        SHARDS - 1
    }
}

/// Every documented command of the files of `shard`, in order per file;
/// `reproduce all` (also run by the reproduce tests) only when
/// `with_reproduce_all`. A command that
/// is, once adapted, one already run (output directories aside) runs once,
/// and one that [`run_by_the_reproduce_test`] is not run here. Returns the
/// number of commands checked.
fn run_documented(with_reproduce_all: bool, shard: usize) -> usize {
    let mut ran = 0;
    let mut seen = std::collections::HashSet::new();
    let files = doc_files().into_iter();
    for file in files.filter(|f| shard == ALL || shard_of(f) == shard) {
        let text = std::fs::read_to_string(root().join(&file)).unwrap();
        let tmp = tempfile::tempdir().unwrap();
        let mut dirs = HashMap::new();
        for (line, args) in commands(&text) {
            let all = args.len() >= 2 && args[0] == "reproduce" && args[1] == "all";
            if all != with_reproduce_all {
                continue;
            }
            let adapted = adapt(&args, tmp.path(), &mut dirs);
            let key: Vec<String> = adapted
                .iter()
                .map(|a| match a.starts_with(&*tmp.path().to_string_lossy()) {
                    true => "DIR".to_string(),
                    false => a.clone(),
                })
                .collect();
            if !seen.insert(key) {
                continue;
            }
            if !run_by_the_reproduce_test(&adapted) {
                run(&format!("{}:{line}", file.display()), &adapted);
            }
            ran += 1;
        }
    }
    ran
}

/// Whether `adapted` is, but for its output directory and seed, the command
/// [`super::reproduce::reproduce_all_quick`] runs and checks file by file
/// (`irtp reproduce all --out DIR` once `--quick` is added): a second run
/// here (about a minute on 2 cores) would differ only in the seed.
fn run_by_the_reproduce_test(adapted: &[String]) -> bool {
    let strip = |args: &[&str]| {
        let mut kept = Vec::new();
        let mut it = args.iter();
        while let Some(&a) = it.next() {
            match a {
                "--out" | "--seed" => {
                    it.next();
                }
                _ => kept.push(a.to_string()),
            }
        }
        kept.sort();
        kept
    };
    let adapted: Vec<&str> = adapted.iter().map(String::as_str).collect();
    adapted.starts_with(&["reproduce", "all"])
        && strip(&adapted) == strip(&super::reproduce::ALL_QUICK)
}

/// The reproduce test's command is recognised whatever the seed, output
/// directory and order; one more flag is not it.
#[test]
fn only_the_reproduce_tests_command_is_left_to_it() {
    assert!(run_by_the_reproduce_test(&words(
        "reproduce all --out d --quick"
    )));
    assert!(run_by_the_reproduce_test(&words(
        "reproduce all --quick --seed 3 --out e"
    )));
    assert!(!run_by_the_reproduce_test(&words(
        "reproduce all --out d --quick --force"
    )));
    assert!(!run_by_the_reproduce_test(&words(
        "reproduce fig2 --out d --quick"
    )));
    assert!(!run_by_the_reproduce_test(&words("simulate --out d")));
}

#[test]
fn the_docs_print_commands() {
    let n: usize = doc_files()
        .iter()
        .map(|f| commands(&std::fs::read_to_string(root().join(f)).unwrap()).len())
        .sum();
    assert!(n >= 30, "only {n} documented commands found");
}

#[test]
fn documented_commands_run_shard_1_of_3() {
    run_documented(false, 0);
}

#[test]
fn documented_commands_run_shard_2_of_3() {
    run_documented(false, 1);
}

#[test]
fn documented_commands_run_shard_3_of_3() {
    run_documented(false, 2);
}

#[test]
#[ignore = "slow tier"]
fn documented_reproduce_all_runs() {
    assert!(run_documented(true, ALL) >= 1);
}

/// The example plans and the command each one's header prints.
fn plans() -> Vec<(PathBuf, Vec<String>)> {
    let mut plans: Vec<_> = std::fs::read_dir(root().join("examples/sweeps"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    plans.sort();
    plans
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            let cmd = text
                .lines()
                .find_map(|l| l.trim_start_matches(['#', ' ']).strip_prefix("irtp "))
                .unwrap_or_else(|| panic!("{p:?}: no `irtp sweep run` line in its header"));
            (p, words(cmd))
        })
        .collect()
}

/// Run every plan of `plans()` whose name `pick` selects, as its header
/// says; a long plan as its first shard of [`LONG_PLAN_SHARDS`].
fn run_plans(pick: impl Fn(&str) -> bool) {
    for (path, args) in plans() {
        let tmp = tempfile::tempdir().unwrap();
        let name = path.file_name().unwrap().to_str().unwrap();
        if !pick(name) {
            continue;
        }
        let plan = format!("examples/sweeps/{name}");
        assert!(
            args.contains(&plan),
            "{name}: its header runs another plan: {args:?}"
        );
        let mut dirs = HashMap::new();
        let mut cmd = adapt(&args, tmp.path(), &mut dirs);
        if LONG_PLANS.contains(&name) {
            cmd.extend(["--shard".into(), format!("1/{LONG_PLAN_SHARDS}")]);
        }
        run(name, &cmd);
    }
}

#[test]
fn example_plans_run() {
    let commands: Vec<String> = plans()
        .iter()
        .map(|(p, _)| std::fs::read_to_string(p).unwrap())
        .filter_map(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("command = ").map(str::to_string))
        })
        .collect();
    for c in irtp_app::sweep::plan::SWEEPABLE {
        assert!(
            commands.contains(&format!("\"{c}\"")),
            "no example plan for {c}"
        );
    }
    run_plans(|name| !LONG_PLANS.contains(&name));
}

#[test]
fn long_example_plans_run_one_shard() {
    run_plans(|name| LONG_PLANS.contains(&name));
}

/// Backquoted repository paths (`crates/…`, `docs/…`, `examples/…`,
/// `tests/…`, `python/…`, `bench/…`, `src/…`) in the docs.
fn named_paths(text: &str) -> Vec<String> {
    const ROOTS: [&str; 8] = [
        "crates/",
        "docs/",
        "examples/",
        "tests/",
        "python/",
        "bench/",
        "src/",
        ".ci/",
    ];
    let mut out = Vec::new();
    for (i, chunk) in text.split('`').enumerate() {
        let p = chunk.trim_end_matches(['/', ',', '.', ':']);
        let pathlike =
            !p.contains([' ', '*', '{', '<', '$']) && ROOTS.iter().any(|r| p.starts_with(r));
        if i % 2 == 1 && pathlike {
            out.push(p.split_once(':').map_or(p, |(f, _)| f).to_string());
        }
    }
    out
}

#[test]
fn every_path_the_docs_name_exists() {
    let mut missing = Vec::new();
    let mut files = doc_files();
    files.push("python/README.md".into());
    for file in files.iter().filter(|f| root().join(f).exists()) {
        let text = std::fs::read_to_string(root().join(file)).unwrap();
        for p in named_paths(&text) {
            if !root().join(&p).exists() {
                missing.push(format!("{}: {p}", file.display()));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "paths the docs name but the tree lacks:\n{}",
        missing.join("\n")
    );
}

/// The targets of the relative Markdown links `](target)` of `text`, without
/// their `#anchor`.
fn link_targets(text: &str) -> Vec<String> {
    text.split("](")
        .skip(1)
        .filter_map(|rest| rest.split_once(')').map(|(t, _)| t))
        .filter(|t| !t.contains("://") && !t.starts_with('#') && !t.starts_with('<'))
        .map(|t| t.split_once('#').map_or(t, |(f, _)| f).to_string())
        .collect()
}

/// Whether docs/build.sh writes `path` (relative to the root) into the
/// staged site: the generated pages, and `docs/tutorials/figures/NAME.png`
/// drawn by `docs/tutorials/NAME.py`, which build.sh runs.
fn generated_by_the_docs_build(path: &Path) -> bool {
    let build = std::fs::read_to_string(root().join("docs/build.sh")).unwrap();
    let p = path.to_string_lossy();
    let generated = [
        "docs/reference/cli.md",
        "docs/reference/python-api.md",
        "docs/reproduction.md",
    ];
    if generated.contains(&p.as_ref()) {
        let name = path
            .strip_prefix("docs")
            .unwrap()
            .to_string_lossy()
            .into_owned();
        return build.contains(&name);
    }
    let figure = p.strip_prefix("docs/tutorials/figures/");
    let tutorials: Vec<&str> = build
        .lines()
        .find_map(|l| l.strip_prefix("TUTORIALS=("))
        .and_then(|l| l.strip_suffix(')'))
        .expect("docs/build.sh lists its TUTORIALS")
        .split_whitespace()
        .collect();
    figure
        .and_then(|f| f.strip_suffix(".png"))
        .is_some_and(|name| {
            tutorials.contains(&name) && root().join(format!("docs/tutorials/{name}.py")).exists()
        })
}

/// `a/b/../c` as `a/c` (the link targets are relative, without symlinks).
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

#[test]
fn every_file_the_docs_link_exists() {
    let mut missing = Vec::new();
    let mut checked = 0;
    for file in doc_files() {
        let text = std::fs::read_to_string(root().join(&file)).unwrap();
        let dir = file.parent().unwrap_or(Path::new(""));
        for t in link_targets(&text) {
            let target = normalise(&dir.join(&t));
            checked += 1;
            if !root().join(&target).exists() && !generated_by_the_docs_build(&target) {
                missing.push(format!("{}: {t}", file.display()));
            }
        }
    }
    assert!(checked >= 50, "only {checked} links found");
    assert!(
        missing.is_empty(),
        "links the docs make to files neither the tree nor docs/build.sh has:\n{}",
        missing.join("\n")
    );
}
