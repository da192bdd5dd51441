//! `irtp analytic` contract: JSON fields, output files, bad input.

use crate::common::{assert_rejected, assert_success, irtp, json, read_json};
use irtp::analytic::r0::R0Density;
use irtp::DragLaw;

#[test]
fn json_contract() {
    let j = json(&irtp(&[
        "analytic", "--drag", "tan", "--sigma", "3", "--lambda", "0.9", "--json",
    ]));
    let d = R0Density::new(DragLaw::Tan, 3.0, 0.9).unwrap();
    assert_eq!(j["v2"].as_f64().unwrap(), d.v2());
    assert_eq!(j["regime"], "i");
    assert!(j["regime_description"]
        .as_str()
        .unwrap()
        .contains("diverges"));
    assert!((j["edge_exponent"].as_f64().unwrap() + 0.91).abs() < 1e-12);
    assert_eq!(j["extrema"][0]["v"].as_f64().unwrap(), 0.0);
    assert_eq!(j["extrema"][0]["kind"], "minimum");
    assert!(
        (j["normalisation"]["integral"].as_f64().unwrap() - d.normalisation().integral).abs()
            < 1e-12
    );

    let j = json(&irtp(&[
        "analytic", "--drag", "tanh", "--sigma", "0.6", "--lambda", "0.85", "--json",
    ]));
    assert_eq!(j["regime"], "b");
    assert_eq!(j["extrema"].as_array().unwrap().len(), 3);
}

#[test]
fn writes_density_and_provenance() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("r0");
    let out = irtp(&[
        "analytic",
        "--drag",
        "tanh",
        "--sigma",
        "0.6",
        "--lambda",
        "0.5",
        "--points",
        "101",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_success(&out);
    let text = std::fs::read_to_string(dir.join("density.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "v,p,cdf");
    let d = R0Density::new(DragLaw::Tanh, 0.6, 0.5).unwrap();
    let (vl, vu) = d.bounds();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 101);
    for w in rows.windows(2) {
        assert!(w[0][0] < w[1][0] && w[0][0] > vl && w[1][0] < vu);
    }
    for r in &rows {
        assert_eq!(r[1], d.pdf(r[0]));
        assert_eq!(r[2], d.cdf(r[0]));
    }
    let run = read_json(&dir.join("run.json"));
    assert_eq!(run["command"], "analytic");
    assert_eq!(run["parameters"]["lambda"], 0.5);
}

#[test]
fn bad_input_one_line_exit_2_nothing_written() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("never");
    let d = dir.to_str().unwrap();
    for (args, flag) in [
        (
            vec!["--drag", "tanh", "--sigma", "1.2", "--lambda", "1"],
            "--sigma",
        ),
        (
            vec!["--drag", "tan", "--sigma", "-3", "--lambda", "1"],
            "--sigma",
        ),
        (
            vec!["--drag", "tan", "--sigma", "3", "--lambda", "0"],
            "--lambda",
        ),
        (
            vec!["--drag", "tan", "--sigma", "3", "--lambda", "nan"],
            "--lambda",
        ),
        (
            vec![
                "--drag", "tan", "--sigma", "3", "--lambda", "1", "--rate", "2",
            ],
            "--rate",
        ),
        (
            vec![
                "--drag", "tan", "--sigma", "3", "--lambda", "1", "--points", "1",
            ],
            "--points",
        ),
    ] {
        let mut all = vec!["analytic"];
        all.extend(&args);
        all.extend(["--out", d]);
        assert_rejected(&irtp(&all), flag, &dir);
    }
    // Unknown drag: clap usage error, also exit 2.
    let out = irtp(&[
        "analytic", "--drag", "honey", "--sigma", "3", "--lambda", "1",
    ]);
    assert_eq!(out.status.code(), Some(2));
}

/// The paper's noise with linear drag and resetting takes the closed forms
/// of any noise (N3)-(N6): `--sigma --lambda` and the same process as a
/// `states:` generator give the same moments.
#[test]
fn linear_drag_with_resetting_answers_for_both_spellings_of_the_paper_noise() {
    for (rate, vr) in [("1", "0"), ("0.3", "0.7"), ("5", "-1.2")] {
        let paper = [
            "analytic", "--drag", "linear", "--rate", rate, "--sigma", "3",
        ];
        let paper = [
            &paper[..],
            &["--lambda", "0.5", "--reset-velocity", vr, "--json"],
        ]
        .concat();
        let states = "states:levels=[3,-3],rates=[[-0.5,0.5],[0.5,-0.5]]";
        let other = [
            "analytic", "--drag", "linear", "--rate", rate, "--noise", states,
        ];
        let other = [&other[..], &["--reset-velocity", vr, "--json"]].concat();
        let (a, b) = (json(&irtp(&paper)), json(&irtp(&other)));
        for key in ["v_mean", "v2", "drift", "d_eff"] {
            let (x, y) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
            assert!(
                (x - y).abs() <= 1e-12 * y.abs().max(1.0),
                "{key}: {x} vs {y}"
            );
        }
    }
}
