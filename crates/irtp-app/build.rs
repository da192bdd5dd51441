//! Records the git revision of a build from a checkout (provenance files
//! carry it as `git_revision`); builds outside a checkout record none.

use std::path::PathBuf;
use std::process::Command;

/// `git rev-parse ARGS` (one line per answer), None outside a checkout or
/// without git.
fn rev_parse(args: &[&str]) -> Option<Vec<String>> {
    let out = Command::new("git")
        .arg("rev-parse")
        .args(args)
        .output()
        .ok()?;
    out.status.success().then(|| {
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(|l| l.trim().to_string())
            .collect()
    })
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    // The files that move with a commit or a checkout: HEAD in the
    // checkout's own git directory (a linked worktree has its own, under
    // the main one's worktrees/), the branches in the common one. Only
    // paths that exist: cargo treats a missing one as changed and would
    // rerun this script, and rebuild everything above irtp-app, on every
    // build (a checkout may have no packed-refs).
    let dirs = rev_parse(&["--path-format=absolute", "--git-dir", "--git-common-dir"]);
    let watched: Vec<PathBuf> = match dirs.as_deref() {
        Some([own, common]) => {
            let (own, common) = (PathBuf::from(own), PathBuf::from(common));
            vec![
                own.join("HEAD"),
                common.join("refs/heads"),
                common.join("packed-refs"),
            ]
        }
        // An older git (no --path-format): the main checkout's files.
        _ => ["HEAD", "refs/heads", "packed-refs"]
            .iter()
            .map(|p| PathBuf::from("../../.git").join(p))
            .collect(),
    };
    for path in watched.iter().filter(|p| p.exists()) {
        println!("cargo:rerun-if-changed={}", path.display());
    }
    let rev = rev_parse(&["HEAD"]).and_then(|l| l.into_iter().next());
    if let Some(rev) = rev.filter(|r| !r.is_empty()) {
        println!("cargo:rustc-env=IRTP_GIT_REVISION={rev}");
    }
}
