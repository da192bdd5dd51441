//! The output contract (`irtp_app::io`): nothing without a commit, the
//! files and `run.json` with one.

use irtp_app::io::{OutputDir, Provenance};
use std::fs;

#[test]
fn uncommitted_leaves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("res");
    {
        let mut o = OutputDir::new(&target).unwrap();
        o.write_csv("a.csv", &["x"], [[1.0]]).unwrap();
    }
    assert!(!target.exists());
    assert_eq!(fs::read_dir(tmp.path()).unwrap().count(), 0);
}

#[test]
fn commit_moves_files_with_provenance() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("res");
    let mut o = OutputDir::new(&target).unwrap();
    o.write_csv("a.csv", &["x", "y"], [[1.0, 0.1], [2.0, 1e-300]])
        .unwrap();
    o.commit_with_provenance(Provenance::new(
        "test",
        "none",
        Some(1),
        serde_json::json!({"a": 1}),
        0.0,
    ))
    .unwrap();
    let csv = fs::read_to_string(target.join("a.csv")).unwrap();
    assert_eq!(csv, "x,y\n1.0,0.1\n2.0,1e-300\n");
    let run: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(target.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["software"], "irtp");
    assert_eq!(run["files"][0], "a.csv");
    assert_eq!(fs::read_dir(tmp.path()).unwrap().count(), 1);
}
