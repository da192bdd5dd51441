//! Point masses of the stationary velocity law (`atoms` in `results`):
//! run-pause-tumble noise reset to the pause's fixed point v = 0 has an
//! atom of mass π₀ r/(r + β) (1/9 below), reported by `fp stationary`
//! and `simulate` beside densities without it, which agree.

use crate::common::{irtp, json, stats};
use std::path::Path;

const MODEL: [&str; 6] = [
    "--drag",
    "tan",
    "--noise",
    "rpt:sigma=3,alpha=1,beta=2",
    "--rate",
    "1",
];
/// π₀ r/(r + β) with π₀ = α/(α + β) = 1/3, r = 1, β = 2.
const ATOM: f64 = 1.0 / 9.0;

/// The columns of a CSV file by header name.
fn columns(path: &Path) -> Vec<(String, Vec<f64>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); header.len()];
    for l in lines {
        for (c, x) in cols.iter_mut().zip(l.split(',')) {
            c.push(x.parse().unwrap());
        }
    }
    header.into_iter().zip(cols).collect()
}

fn col<'a>(t: &'a [(String, Vec<f64>)], name: &str) -> &'a [f64] {
    &t.iter().find(|(h, _)| h == name).unwrap().1
}

/// The one atom of `results`: (v, mass, err).
fn atom(r: &serde_json::Value) -> (f64, f64, f64) {
    let a = r["atoms"].as_array().unwrap();
    assert_eq!(a.len(), 1, "{r}");
    let f = |k: &str| a[0][k].as_f64().unwrap();
    (f("v"), f("mass"), f("err"))
}

/// ∫ p over [a, b] of a finite-volume density (cell averages on cells
/// [v - dv/2, v + dv/2]).
fn bin_mass(v: &[f64], p: &[f64], dv: &[f64], a: f64, b: f64) -> f64 {
    v.iter()
        .zip(p)
        .zip(dv)
        .map(|((&c, &p), &h)| {
            let overlap = (c + 0.5 * h).min(b) - (c - 0.5 * h).max(a);
            p * overlap.max(0.0)
        })
        .sum()
}

#[test]
fn rpt_atom_from_fp_and_simulate_and_the_densities_agree() {
    let dir = tempfile::tempdir().unwrap();
    let (fp_dir, sim_dir) = (dir.path().join("fp"), dir.path().join("sim"));
    let mut a = vec![
        "fp",
        "stationary",
        "--json",
        "--out",
        fp_dir.to_str().unwrap(),
    ];
    a.extend(MODEL);
    let fp = json(&irtp(&a));
    let (v, m, e) = atom(&fp);
    assert_eq!(v, 0.0);
    assert!(e > 0.0 && e < 1e-3, "fp atom error {e}");
    assert!((m - ATOM).abs() <= e, "fp atom {m} ± {e} vs {ATOM}");
    let mut a = vec!["simulate", "--particles", "40000", "--json", "--out"];
    a.push(sim_dir.to_str().unwrap());
    a.extend(MODEL);
    let sim = json(&irtp(&a));
    let (v, ms, es) = atom(&sim);
    assert_eq!(v, 0.0);
    assert!(es > 0.0, "{sim}");
    // Two comparisons of the sampler's atom: with the closed form, with fp.
    let z = stats::bonferroni_z(2);
    assert!(
        (ms - ATOM).abs() <= z * es,
        "simulate atom {ms} ± {es} vs {ATOM}"
    );
    assert!(
        (ms - m).abs() <= z * es.hypot(e),
        "simulate {ms} ± {es} vs fp {m} ± {e}"
    );
    // The densities without the atom: every histogram bin against the fp
    // density's mass in it.
    let f = columns(&fp_dir.join("density.csv"));
    let s = columns(&sim_dir.join("density.csv"));
    let (vs, ps, se) = (col(&s, "v"), col(&s, "p"), col(&s, "p_err"));
    let w = vs[1] - vs[0];
    let z = stats::bonferroni_z(vs.len());
    let mut total = 0.0;
    for ((&c, &p), &err) in vs.iter().zip(ps).zip(se) {
        let want = bin_mass(
            col(&f, "v"),
            col(&f, "p"),
            col(&f, "dv"),
            c - 0.5 * w,
            c + 0.5 * w,
        ) / w;
        assert!(
            (p - want).abs() <= z * err.max(1e-12),
            "bin at {c}: simulate {p} ± {err}, fp {want}"
        );
        total += p * w;
    }
    // The histogram holds the rest of the mass (to rounding of the
    // per-particle fractions).
    assert!(
        (total + ms - 1.0).abs() < 1e-9,
        "histogram {total} + atom {ms}"
    );
    let fp_total: f64 = col(&f, "p")
        .iter()
        .zip(col(&f, "dv"))
        .map(|(p, h)| p * h)
        .sum();
    assert!(
        (fp_total + m - 1.0).abs() <= e + 1e-12,
        "fp density {fp_total} + atom {m}"
    );
}

/// No atom in the paper's noise (nothing holds the velocity): `atoms` is
/// an empty list.
#[test]
fn no_atom_for_the_paper_noise() {
    let r = json(&irtp(&["fp", "stationary", "--cells", "2000", "--json"]));
    assert_eq!(r["atoms"], serde_json::json!([]), "{r}");
    let r = json(&irtp(&["simulate", "--particles", "200", "--json"]));
    assert_eq!(r["atoms"], serde_json::json!([]), "{r}");
}

/// `fp stationary` reports D_eff's error estimate (`d_eff_err`) for the
/// paper's noise and a noise model, and prints D_eff to the digits it
/// supports (`D_eff = x ± e`).
#[test]
fn fp_stationary_reports_the_d_eff_error() {
    for noise in [None, Some("rpt:sigma=3,alpha=1,beta=2")] {
        let mut a = vec!["fp", "stationary", "--cells", "4000", "--json"];
        a.extend(noise.map(|n| ["--noise", n]).into_iter().flatten());
        let r = json(&irtp(&a));
        let e = r["d_eff_err"].as_f64().unwrap();
        assert!(e > 0.0 && e < 1e-4 * r["d_eff"].as_f64().unwrap(), "{r}");
        a.retain(|x| *x != "--json");
        let out = irtp(&a);
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.contains("D_eff = ") && text.contains(" ± "), "{text}");
    }
}

/// The samplers' atoms of a refractory hold (the paper's noise, `--refractory
/// exp:mean=M`: mass r M/(1 + r M) at v_r) and of the pause (Euler), against
/// their closed forms, within the Bonferroni bound of the standard errors:
/// the exact sampler as it is; Euler, biased by O(r dt), extrapolated to
/// dt -> 0 from dt and dt/2 (2 m(dt/2) - m(dt), its standard error
/// sqrt(4 e(dt/2)² + e(dt)²)), never given a bias allowance.
#[test]
fn samplers_report_refractory_and_pause_atoms() {
    let hold = [
        "--drag",
        "linear",
        "--sigma",
        "1",
        "--lambda",
        "0.3",
        "--rate",
        "2",
        "--refractory",
        "exp:mean=0.5",
        "--reset-velocity",
        "0.2",
    ];
    // (model flags, Euler's dt or None for the exact sampler, v_r, closed form)
    type Case<'a> = (&'a [&'a str], Option<&'a str>, f64, f64);
    let cases: [Case; 3] = [
        (&hold, None, 0.2, 0.5),
        (&hold, Some("0.002"), 0.2, 0.5),
        (&MODEL, Some("0.002"), 0.0, ATOM),
    ];
    let run = |model: &[&str], method: &[&str]| {
        let mut a = vec!["simulate", "--particles", "4000", "--json"];
        a.extend(model);
        a.extend(method);
        let (v, m, e) = atom(&json(&irtp(&a)));
        assert!(e > 0.0, "{a:?}");
        (v, m, e)
    };
    let z = stats::bonferroni_z(cases.len());
    for (model, dt, v_r, want) in cases {
        let (v, m, e) = match dt {
            None => run(model, &[]),
            Some(dt) => {
                let half = (dt.parse::<f64>().unwrap() / 2.0).to_string();
                let (v, m1, e1) = run(model, &["--method", "euler", "--dt", dt]);
                let (_, m2, e2) = run(model, &["--method", "euler", "--dt", &half]);
                (v, 2.0 * m2 - m1, (4.0 * e2 * e2 + e1 * e1).sqrt())
            }
        };
        assert_eq!(v, v_r, "{model:?} {dt:?}");
        assert!(
            (m - want).abs() <= z * e,
            "{model:?} {dt:?}: {m} ± {e} vs {want}"
        );
    }
}

/// `fp transient` reports the atom of the time-dependent law at every
/// recording time (`atoms_t`), the closed form (N52)
/// m(t) = π₀ [r + β e^{-(r+β) t}]/(r + β) within its error; at t_max = 1
/// it agrees with the fraction of `simulate`'s particles exactly at v = 0
/// at t_max (`atoms_final`) within 4 SE (Bonferroni over the two
/// comparisons) + the FP error; the snapshots at t_max (density without
/// the atom) integrate to 1 - atom within the atom's error.
#[test]
fn fp_transient_atom_in_time_against_its_ode_and_simulate() {
    let dir = tempfile::tempdir().unwrap();
    let fp_dir = dir.path().join("fp");
    let mut a = vec!["fp", "transient", "--t-max", "1", "--cells", "800"];
    a.extend(["--samples", "5", "--snapshots", "1", "--json", "--out"]);
    a.push(fp_dir.to_str().unwrap());
    a.extend(MODEL);
    let fp = json(&irtp(&a));
    let series = fp["atoms_t"].as_array().unwrap();
    assert_eq!(series.len(), 5, "{fp}");
    for e in series {
        let t = e["t"].as_f64().unwrap();
        let (v, m, err) = atom(e);
        let want = (1.0 + 2.0 * (-3.0 * t).exp()) / 9.0;
        assert_eq!(v, 0.0);
        assert!((m - want).abs() <= err, "t = {t}: {m} ± {err} vs {want}");
    }
    let (_, m, e) = atom(&fp);
    let mut a = vec!["simulate", "--particles", "40000", "--t-max", "1"];
    a.extend(["--burn-in", "0.5", "--json"]);
    a.extend(MODEL);
    let sim = json(&irtp(&a));
    let f = sim["atoms_final"].as_array().unwrap();
    assert_eq!(f.len(), 1, "{sim}");
    let (ms, es) = (
        f[0]["mass"].as_f64().unwrap(),
        f[0]["err"].as_f64().unwrap(),
    );
    assert!(es > 0.0, "{sim}");
    let z = stats::bonferroni_z(2);
    let want = (1.0 + 2.0 * (-3.0f64).exp()) / 9.0;
    assert!(
        (ms - want).abs() <= z * es,
        "simulate {ms} ± {es} vs {want}"
    );
    assert!(
        (ms - m).abs() <= z * es + e,
        "simulate {ms} ± {es} vs fp {m} ± {e}"
    );
    // The density at t_max without the atom, on the fp stationary mesh
    // (the same cells).
    let st_dir = dir.path().join("st");
    let mut a = vec!["fp", "stationary", "--cells", "800", "--out"];
    a.push(st_dir.to_str().unwrap());
    a.extend(MODEL);
    irtp(&a);
    let snaps = columns(&fp_dir.join("snapshots.csv"));
    let dv = columns(&st_dir.join("density.csv"));
    assert_eq!(col(&snaps, "v"), col(&dv, "v"));
    let density: f64 = col(&snaps, "p")
        .iter()
        .zip(col(&dv, "dv"))
        .map(|(p, h)| p * h)
        .sum();
    assert!(
        (density + m - 1.0).abs() <= e + 1e-8,
        "density {density} + atom {m}"
    );
    let moments = columns(&fp_dir.join("moments.csv"));
    assert_eq!(col(&moments, "atom_mass").last(), Some(&m));
    // atoms.csv: one row per recording time and atom, as atoms_t.
    let rows = columns(&fp_dir.join("atoms.csv"));
    let names: Vec<&str> = rows.iter().map(|(h, _)| h.as_str()).collect();
    assert_eq!(names, ["t", "v", "mass", "err"]);
    assert_eq!(col(&rows, "t").len(), series.len());
    for (k, e) in series.iter().enumerate() {
        let (v, m, err) = atom(e);
        let row = ["t", "v", "mass", "err"].map(|c| col(&rows, c)[k]);
        assert_eq!(row, [e["t"].as_f64().unwrap(), v, m, err], "row {k}");
    }
}
