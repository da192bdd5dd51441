//! Records the git revision of a build from a checkout (provenance files
//! carry it as `git_revision`); builds outside a checkout record none.

use std::process::Command;

fn main() {
    // Only paths that exist: cargo treats a missing one as changed and
    // would rerun this script, and rebuild everything above irtp-app, on
    // every build (a checkout may have no packed-refs; a crate outside a
    // checkout has none of them).
    println!("cargo:rerun-if-changed=build.rs");
    for path in [
        "../../.git/HEAD",
        "../../.git/refs/heads",
        "../../.git/packed-refs",
    ] {
        if std::path::Path::new(path).exists() {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    let rev = Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    if let Some(rev) = rev.filter(|r| !r.is_empty()) {
        println!("cargo:rustc-env=IRTP_GIT_REVISION={rev}");
    }
}
