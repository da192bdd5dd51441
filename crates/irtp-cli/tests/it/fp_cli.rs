//! `irtp fp ...` end to end: JSON, output files with provenance, bad input.

use crate::common::{assert_rejected, irtp, json, read_json, summary};

#[test]
fn stationary_json_and_files() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("st");
    let out = irtp(&[
        "fp",
        "stationary",
        "--drag",
        "linear",
        "--sigma",
        "1",
        "--lambda",
        "0.3",
        "--rate",
        "2",
        "--reset-velocity",
        "-0.3",
        "--cells",
        "4000",
        "--json",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let v = json(&out);
    // summary.json is exactly the object --json printed.
    let printed = summary(&out);
    assert_eq!(read_json(&dir.join("summary.json")), printed);
    assert_eq!(printed["command"], "fp stationary");
    assert_eq!(printed["params"]["model"]["rate"], 2.0);
    assert_eq!(printed["provenance"]["version"], env!("CARGO_PKG_VERSION"));
    // Exact: <vη> = 1/3.6, <v²> = (2<vη> + r v_r²)/(2 + r).
    let v2 = (2.0 / 3.6 + 2.0 * 0.09) / 4.0;
    assert!((v["v2"].as_f64().unwrap() / v2 - 1.0).abs() < 1e-6);
    assert!(v["d_eff"].as_f64().unwrap() > 0.0);
    assert_eq!(v["cells"].as_u64(), Some(4000));
    assert!((v["mass"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(v["mesh"], "graded");
    let csv = std::fs::read_to_string(dir.join("density.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("v,p,p_plus,p_minus,dv"));
    assert_eq!(csv.lines().count(), 4001);
    let run = read_json(&dir.join("run.json"));
    assert_eq!(run["command"], "fp stationary");
    assert_eq!(run["parameters"]["model"]["reset_velocity"], -0.3);
}

#[test]
fn transient_json_and_files() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("tr");
    let out = irtp(&[
        "fp",
        "transient",
        "--drag",
        "tanh",
        "--sigma",
        "0.6",
        "--lambda",
        "0.5",
        "--rate",
        "1",
        "--t-max",
        "2",
        "--cells",
        "300",
        "--samples",
        "11",
        "--snapshots",
        "2",
        "--json",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let v = json(&out);
    assert!(v["v2_final"].as_f64().unwrap() > 0.0);
    assert!((v["mass"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    // Default scheme: adaptive TR-BDF2 on the graded mesh (no fixed step).
    assert_eq!(v["scheme"], "trbdf2");
    assert_eq!(v["mesh"], "graded");
    assert_eq!(v["extrapolated"], true);
    assert!(v["dt"].is_null());
    assert!(v["steps"].as_u64().unwrap() > 0);
    let m = std::fs::read_to_string(dir.join("moments.csv")).unwrap();
    assert_eq!(m.lines().next(), Some("t,v_mean,v2,mass"));
    assert_eq!(m.lines().count(), 12);
    let s = std::fs::read_to_string(dir.join("snapshots.csv")).unwrap();
    assert_eq!(s.lines().next(), Some("t,v,p,p_plus,p_minus"));
    assert_eq!(s.lines().count(), 1 + 2 * 300);
    assert!(dir.join("run.json").exists());
    let run = std::fs::read_to_string(dir.join("run.json")).unwrap();
    assert!(run.contains("\"scheme\": \"trbdf2\""), "{run}");
}

#[test]
fn paper_scheme_records_its_step() {
    let out = irtp(&[
        "fp",
        "transient",
        "--scheme",
        "paper",
        "--t-max",
        "0.5",
        "--cells",
        "100",
        "--json",
    ]);
    let v = json(&out);
    assert_eq!(v["scheme"], "paper");
    assert_eq!(v["mesh"], "uniform");
    assert!(v["dt"].as_f64().unwrap() > 0.0);
}

#[test]
fn bad_input_one_line_exit_2_nothing_written() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("bad");
    let d = dir.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["fp", "stationary", "--cells", "3", "--out", d],
            "--cells",
        ),
        (
            vec!["fp", "stationary", "--cells", "2001", "--out", d],
            "--cells",
        ),
        (
            vec!["fp", "stationary", "--sigma", "nan", "--out", d],
            "--sigma",
        ),
        (
            vec![
                "fp",
                "stationary",
                "--drag",
                "tanh",
                "--sigma",
                "1.2",
                "--out",
                d,
            ],
            "--sigma",
        ),
        (
            vec![
                "fp",
                "stationary",
                "--rate",
                "0",
                "--lambda",
                "0",
                "--out",
                d,
            ],
            "--lambda",
        ),
        (
            vec!["fp", "transient", "--t-max", "0", "--out", d],
            "--t-max",
        ),
        (
            vec!["fp", "transient", "--t-max", "-1", "--out", d],
            "--t-max",
        ),
        (
            vec![
                "fp",
                "transient",
                "--scheme",
                "paper",
                "--t-max",
                "1",
                "--cfl",
                "2",
                "--out",
                d,
            ],
            "--cfl",
        ),
        // Flags of the other scheme.
        (
            vec![
                "fp",
                "transient",
                "--t-max",
                "1",
                "--cfl",
                "0.5",
                "--out",
                d,
            ],
            "--cfl",
        ),
        (
            vec![
                "fp",
                "transient",
                "--scheme",
                "paper",
                "--t-max",
                "1",
                "--rtol",
                "1e-6",
                "--out",
                d,
            ],
            "--rtol",
        ),
        (
            vec![
                "fp",
                "transient",
                "--scheme",
                "paper",
                "--t-max",
                "1",
                "--atol",
                "1e-9",
                "--out",
                d,
            ],
            "--atol",
        ),
        (
            vec!["fp", "transient", "--t-max", "1", "--rtol", "0", "--out", d],
            "--rtol",
        ),
        (
            vec![
                "fp",
                "transient",
                "--t-max",
                "1",
                "--atol",
                "nan",
                "--out",
                d,
            ],
            "--atol",
        ),
        (
            vec![
                "fp",
                "transient",
                "--t-max",
                "1",
                "--cells",
                "301",
                "--out",
                d,
            ],
            "--cells",
        ),
        (
            vec![
                "fp",
                "transient",
                "--t-max",
                "1",
                "--cells",
                "8",
                "--out",
                d,
            ],
            "--cells",
        ),
        (
            vec![
                "fp",
                "transient",
                "--t-max",
                "1",
                "--reset-velocity",
                "-2",
                "--out",
                d,
            ],
            "--reset-velocity",
        ),
    ];
    for (args, name) in cases {
        assert_rejected(&irtp(&args), name, &dir);
    }
}
