//! `irtp reproduce all --quick`: every expected file is written, and the
//! numeric claims hold (D_eff ∝ r⁻² asymptotically, optimal resetting rate
//! for tan at lambda = 0.5 but not for tanh).

use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// The command [`reproduce_all_quick`] runs, with `--out DIR`.
pub const ALL_QUICK: [&str; 5] = ["reproduce", "all", "--quick", "--seed", "7"];

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_irtp"))
}

fn claim<'a>(claims: &'a [Value], id: &str) -> &'a Value {
    claims
        .iter()
        .find(|c| c["id"] == id)
        .unwrap_or_else(|| panic!("claim {id} missing"))
}

/// Legend text each figure must show: what its points and lines are.
fn legend_entries(fig: &str) -> &'static [&'static str] {
    match fig {
        "fig1" => &[
            "exact sampler, 4",
            "stationary FP, Eq. (33)",
            "transient FP",
            "r = 10",
        ],
        "fig2" | "fig3" => &[
            "exact sampler, ",
            "Fokker-Planck (FP), stationary",
            "analytic r = 0, Eq. (3",
            "r = 0, FP",
        ],
        "fig5" => &[
            "exact sampler with linear-proxy control variate, ",
            "guide (ballistic)",
            "guide (diffusive)",
            "r = 10",
        ],
        "fig6" => &[
            "exact sampler with linear-proxy control variate (",
            "fit of Eq. (36)",
            "(FP generator)",
            "guide",
            "λ = 5",
        ],
        "fig7" => &[
            "exact sampler with martingale control variate, ",
            "backward eqs. (26)-(27)",
            "tanh λ = 5",
        ],
        "fpt" => &[
            "exact sampler, ",
            "backward equations (bin averages)",
            "(r*)",
        ],
        "media" => &[
            "exact sampler with martingale control variate, ",
            "backward equations / Fokker-Planck",
            "dτ/dr(0) negative",
        ],
        "search" => &[
            "exact sampler, ",
            "2-D backward equation",
            "velocity-only, interval",
            "sampled S(t)",
        ],
        "noise" => &["run-pause-tumble", "telegraph + thermal", "large-r limit"],
        _ => &[],
    }
}

#[test]
#[ignore = "slow tier"]
fn reproduce_all_quick() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("figs");
    let t0 = std::time::Instant::now();
    let o = bin()
        .args(ALL_QUICK)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    eprintln!("reproduce all --quick: {:.1} s", t0.elapsed().as_secs_f64());

    for f in [
        "fig1", "fig2", "fig3", "fig5", "fig6", "fig7", "fpt", "media", "search", "noise",
    ] {
        let csv = std::fs::read_to_string(out.join(format!("{f}.csv"))).unwrap();
        assert!(
            csv.starts_with("panel,series,source,style,x,y,y_err\n"),
            "{f}"
        );
        assert!(csv.lines().count() > 20, "{f}.csv has data");
        if cfg!(feature = "plot") {
            let png = std::fs::read(out.join(format!("{f}.png"))).unwrap();
            assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{f}.png");
            let svg = std::fs::read_to_string(out.join(format!("{f}.svg"))).unwrap();
            assert!(svg.contains("<svg"), "{f}.svg");
            // Every figure says what its marks are, and no markup shows raw.
            for entry in legend_entries(f) {
                assert!(svg.contains(entry), "{f}.svg lacks legend entry {entry:?}");
            }
            for raw in ["_{", "D_eff", "P_s", "τ_r", "v_t", "v_r"] {
                assert!(!svg.contains(raw), "{f}.svg shows raw markup {raw:?}");
            }
        } else {
            assert!(!out.join(format!("{f}.png")).exists(), "{f}.png");
        }
    }
    for f in ["claims.json", "claims.md", "parameters.json", "run.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // Without the `plot` feature the report and stdout say why there are no images.
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let note = "need the cargo feature `plot`";
    if cfg!(feature = "plot") {
        assert!(report.contains("![fig2](fig2.png)"), "{report}");
        assert!(!report.contains(note) && !stdout.contains(note), "{stdout}");
    } else {
        assert!(report.contains(note) && stdout.contains(note), "{stdout}");
    }
    let run: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["seed"], 7);
    assert_eq!(run["parameters"]["quick"], true);
    let params: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("parameters.json")).unwrap())
            .unwrap();
    assert_eq!(
        params["fig2"]["spec"]["lambdas"],
        serde_json::json!([0.9, 7.0, 15.0, 25.0])
    );
    assert_eq!(params["fig7"]["spec"]["v0"], -0.249);

    let claims: Vec<Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("claims.json")).unwrap()).unwrap();

    // Beyond the paper: the sampled FPT histogram agrees with the backward
    // bin probabilities (max |z| within the Bonferroni limit, per medium);
    // tan has an interior optimum r* whose mean is below tau(0), tanh does not.
    for drag in ["tan", "tanh"] {
        let c = claim(&claims, &format!("fpt_distribution_{drag}"));
        assert_eq!(c["verdict"], "agrees", "{c}");
        let curves = c["values"].as_array().unwrap();
        assert_eq!(curves.len(), 3);
        assert!(
            curves.iter().all(|x| x["compared"].as_u64().unwrap() >= 20),
            "{c}"
        );
    }
    let tan = claim(&claims, "fpt_distribution_tan")["values"].clone();
    assert_eq!(tan[1]["role"], "r*");
    assert!(tan[1]["tau"].as_f64().unwrap() < tan[0]["tau"].as_f64().unwrap());
    let large = tan[2]["tau"].as_f64().unwrap() / tan[0]["tau"].as_f64().unwrap();
    // (the rate is bisected on the box scheme at 2000 cells, tau here is
    // the distribution's own mean: two discretisations, ~1e-5 apart)
    assert!((large - 1.0).abs() < 1e-4, "{large}");
    assert_eq!(
        claim(&claims, "fpt_distribution_tanh")["values"][1]["role"],
        "no interior optimum"
    );

    // D_eff ∝ r⁻² at large r: exact (FP) local exponent at r = 10³..10⁴ is -2
    // within 0.01 for every lambda and both media; the simulation's fitted
    // exponent agrees with the exact one at the same rates within 4 SE.
    for drag in ["tan", "tanh"] {
        let c = claim(&claims, &format!("deff_r_minus_2_{drag}"));
        let fits = c["values"].as_array().unwrap();
        assert!(!fits.is_empty());
        for f in fits {
            let asym = f["exponent_exact_r_1e3_1e4"].as_f64().unwrap();
            assert!((asym + 2.0).abs() < 0.01, "{drag}: {f}");
            let pref = f["d_r2_over_sigma2_2lambda_at_1e4"].as_f64().unwrap();
            assert!((pref - 1.0).abs() < 0.01, "{drag}: D r² -> Σ²/(2λ): {f}");
            let (b, sb, be) = (
                f["exponent_sim"].as_f64().unwrap(),
                f["exponent_sim_err"].as_f64().unwrap(),
                f["exponent_exact_same_rates"].as_f64().unwrap(),
            );
            assert!(sb > 0.0 && (b - be).abs() < 4.0 * sb, "{drag}: {f}");
        }
    }

    // Cusp at v = 0: the FP slope jump equals -r(2λ + r - 1)/Σ² within 1 %
    // (deterministic solver, so a tight check), for every panel and r > 0.
    for drag in ["tan", "tanh"] {
        let c = claim(&claims, &format!("cusp_at_zero_{drag}"));
        let rows = c["values"].as_array().unwrap();
        assert_eq!(rows.len(), 16, "4 panels x 4 rates");
        for r in rows {
            let (a, b) = (
                r["jump_fp"].as_f64().unwrap(),
                r["jump_exact"].as_f64().unwrap(),
            );
            assert!((a - b).abs() < 0.01 * b.abs(), "{drag}: {r}");
        }
        // Simulation vs FP and FP vs analytic r = 0 agree (verdict computed
        // from the standard errors: max |z| below max(4, Bonferroni 1 %)).
        assert_eq!(
            claim(&claims, &format!("fp_vs_simulation_{drag}"))["verdict"],
            "agrees"
        );
        assert_eq!(
            claim(&claims, &format!("v2_ss_{drag}"))["verdict"],
            "agrees"
        );
    }
    assert_eq!(claim(&claims, "mfpt_sim_vs_backward")["verdict"], "agrees");
    assert_eq!(claim(&claims, "deff_sim_vs_exact")["verdict"], "agrees");

    // Optimal resetting rate: interior for tan at lambda = 0.5, none for tanh.
    let opt = claim(&claims, "optimal_reset_rate");
    let find = |drag: &str, lambda: f64| {
        opt["values"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| o["drag"] == drag && o["lambda"].as_f64() == Some(lambda))
            .unwrap()
            .clone()
    };
    let tan = find("tan", 0.5);
    let r_star = tan["optimal_rate"]
        .as_f64()
        .expect("tan lambda=0.5 has an optimum");
    assert!(r_star > 0.0 && r_star.is_finite());
    assert!(tan["tau_at_optimum"].as_f64().unwrap() < tan["tau_r0"].as_f64().unwrap());
    assert!(
        find("tanh", 0.5)["optimal_rate"].is_null(),
        "tanh: no optimum"
    );

    // Every medium: the sampler agrees with the backward equations and the
    // r = 0 FP density with the quadrature (within 4/N of its peak, also at
    // the power law's infinite slope at v = 0), and
    // the medium's optimum is what the backward equations say: interior for
    // the shear-thickening laws at every lambda, none for the power law
    // n = 0.5 (tau rises at once: d tau/dr(0) > 0).
    for id in [
        "media_tan",
        "media_power_n_2_k_1",
        "media_linear",
        "media_tanh",
        "media_power_n_0.5_k_1",
        "media_carreau_n_0.5_a_1",
        "media_coulomb_mu_0.5_gamma_1",
    ] {
        let c = claim(&claims, id);
        assert_eq!(c["verdict"], "agrees", "{id}: {}", c["ours"]);
        let curves = c["values"]["curves"].as_array().unwrap();
        assert_eq!(curves.len(), 3, "{id}");
        for k in curves {
            let (interior, d0) = (
                k["interior"].as_bool().unwrap(),
                k["dtau_dr_r0"].as_f64().unwrap(),
            );
            // A negative slope at r = 0 implies an interior optimum.
            assert!(!(d0 < 0.0) || interior, "{id}: {k}");
            if id == "media_tan" || id == "media_power_n_2_k_1" {
                assert!(interior, "{id}: {k}");
            }
            if id == "media_power_n_0.5_k_1" {
                assert!(!interior && d0 > 0.0, "{id}: {k}");
            }
        }
    }
    assert_eq!(
        claim(&claims, "media_optimum_and_rheology")["verdict"],
        "partly"
    );
    search_claims_hold(&claims);
    noise_claims_hold(&claims);
}

/// The noise figure's claims at the quick size: sampler and FP agree
/// under every noise (the verdict is computed from the standard errors),
/// D_eff r² reaches D_a + 2T in both media, and the paper's answer on the
/// optimal rate (tan: an interior optimum, tanh: none) holds for every
/// noise with telegraph states; its values carry one row per noise.
fn noise_claims_hold(claims: &[Value]) {
    assert_eq!(claim(claims, "noise_sampler_vs_fp")["verdict"], "agrees");
    for drag in ["tan", "tanh"] {
        let c = claim(claims, &format!("noise_deff_r_minus_2_{drag}"));
        assert_eq!(c["verdict"], "agrees", "{c}");
        assert_eq!(c["values"].as_array().unwrap().len(), 5, "{c}");
        for n in c["values"].as_array().unwrap() {
            let (r, d) = n["d_eff"]
                .as_array()
                .unwrap()
                .last()
                .map(|x| (x[0].as_f64().unwrap(), x[1].as_f64().unwrap()))
                .unwrap();
            let limit = n["d_eff_limit"].as_f64().unwrap();
            assert!((d * r * r / limit - 1.0).abs() < 0.1, "{drag}: {n}");
        }
        let o = claim(claims, &format!("noise_optimum_{drag}"));
        assert_eq!(o["verdict"], "agrees", "{o}");
    }
}

/// The search's claims at the quick size: full resetting gives every
/// medium an interior optimum for the level and for the asymmetric
/// interval, velocity-only resetting none for the interval; the
/// velocity-only level's tail exponent is 1/2; the sampler agrees with the
/// backward equation; so the medium does not decide whether resetting
/// helps the search.
fn search_claims_hold(claims: &[Value]) {
    for id in [
        "search_full_level",
        "search_full_interval",
        "search_velocity_interval",
        "search_velocity_level_tail",
        "search_sampler_vs_backward",
    ] {
        assert_eq!(
            claim(claims, id)["verdict"],
            "agrees",
            "{id}: {}",
            claim(claims, id)
        );
    }
    let curves = |id: &str| claim(claims, id)["values"].as_array().unwrap().clone();
    for c in curves("search_full_level") {
        assert!(c["tau_r0"].is_null(), "{c}");
        let r = c["r_opt"].as_f64().unwrap();
        assert!(c["interior"] == true && r > 0.01 && r < 100.0, "{c}");
        assert_eq!(c["checks"].as_array().unwrap().len(), 2, "{c}");
    }
    for c in curves("search_velocity_interval") {
        assert_eq!(c["r_opt"], 0.0, "{c}");
    }
    let medium = claim(claims, "search_medium_decides");
    assert_eq!(medium["verdict"], "differs", "{medium}");
}

#[test]
fn bad_figure_name_is_an_input_error() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x");
    let o = bin()
        .args(["reproduce", "fig4", "--quick", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(!Path::new(&out).exists());
}

#[test]
fn out_is_a_file_fails_before_work() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("f");
    std::fs::write(&file, "x").unwrap();
    let t0 = std::time::Instant::now();
    let o = bin()
        .args(["reproduce", "all", "--out"])
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--out"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        t0.elapsed().as_secs_f64() < 5.0,
        "validated before computing"
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}
