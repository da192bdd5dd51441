//! `irtp plot DIR`: the natural figure of every command's output (tiny
//! runs) is a PNG of the expected size with drawn content, a sweep's is a
//! line plot or heat maps, SVG goes where `--out` says, a plot never damages a sweep
//! point, and bad input is one line, exit 2, nothing written.

use super::common::{assert_success, irtp};
use std::path::Path;
use std::process::Output;

/// Assert the bad-input contract: exit 2, nothing on stdout, one stderr
/// line `irtp: error: invalid <flag> = ...: allowed ...`, and `path` not
/// written. Returns the stderr text.
fn assert_rejected(out: &Output, flag: &str, path: &Path) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{flag}: {err}");
    assert!(out.stdout.is_empty(), "{flag}: stdout not empty");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with(&format!("irtp: error: invalid {flag} = ")),
        "{err}"
    );
    assert!(err.contains(": allowed "), "{err}");
    assert!(!path.exists(), "{flag}: {path:?} was written");
    err
}

/// The names of the entries of `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Width and height of a figure of one panel and of two (640 × 480 each,
/// and the 34-pixel title row); a heat map is one panel.
const ONE_PANEL: (u32, u32) = (640, 514);
const TWO_PANELS: (u32, u32) = (1280, 514);
const HEAT_MAP: (u32, u32) = ONE_PANEL;

/// Decode the PNG at `path`: its size and the number of pixels that are
/// not white (the drawing).
fn decode(path: &Path) -> ((u32, u32), usize) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{path:?} is not a PNG");
    assert_eq!(&bytes[12..16], b"IHDR");
    let mut reader = png::Decoder::new(bytes.as_slice()).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert!(channels >= 3, "{:?}", info.color_type);
    let drawn = buf[..info.buffer_size()]
        .chunks(channels)
        .filter(|px| px[..3].iter().any(|&c| c < 250))
        .count();
    ((info.width, info.height), drawn)
}

/// Run `irtp args... --out DIR/run`, then `irtp plot DIR/run`: the image
/// has size `size` and at least 1 % of its pixels drawn.
fn plots(args: &[&str], size: (u32, u32)) {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let mut a = args.to_vec();
    a.extend(["--out", run.to_str().unwrap()]);
    assert_success(&irtp(&a));
    let o = irtp(&["plot", run.to_str().unwrap()]);
    assert_success(&o);
    let png = run.join("plot.png");
    assert!(String::from_utf8_lossy(&o.stdout).contains("plot.png"));
    let (got, drawn) = decode(&png);
    assert_eq!(got, size, "{args:?}");
    let pixels = (size.0 * size.1) as usize;
    assert!(
        drawn * 100 > pixels,
        "{args:?}: {drawn} of {pixels} pixels drawn"
    );
    // The same run again into the directory: the plot is not in its way.
    assert_success(&irtp(&a));
    assert!(png.is_file());
}

#[test]
fn simulate_densities_and_moments() {
    let a = [
        "simulate",
        "--particles",
        "100",
        "--t-max",
        "1",
        "--burn-in",
        "0.5",
    ];
    plots(&a, TWO_PANELS);
}

#[test]
fn simulate_with_a_reset_position_adds_p_of_x() {
    let a = [
        "simulate",
        "--particles",
        "100",
        "--t-max",
        "1",
        "--burn-in",
        "0.5",
        "--reset-position",
        "0",
    ];
    // Three panels on two columns: two rows.
    plots(&a, (1280, 994));
}

#[test]
fn analytic_and_fp_stationary_densities() {
    plots(&["analytic", "--points", "200"], ONE_PANEL);
    plots(&["fp", "stationary", "--cells", "100"], ONE_PANEL);
}

#[test]
fn fp_transient_snapshots_and_fp_msd() {
    plots(
        &["fp", "transient", "--t-max", "0.5", "--cells", "100"],
        TWO_PANELS,
    );
    plots(&["fp", "msd", "--samples", "10"], TWO_PANELS);
}

#[test]
fn mfpt_profile_survival_scan_optimize() {
    let base = ["--v0", "0", "--vt", "0.5"];
    plots(&[&["mfpt"][..], &base].concat(), ONE_PANEL);
    let exact = ["--method", "exact", "--particles", "100"];
    plots(&[&["mfpt"][..], &base, &exact].concat(), ONE_PANEL);
    let scan = [
        "mfpt", "scan", "--over", "vt", "--v0", "0", "--from", "0.2", "--to", "0.5",
    ];
    plots(&[&scan[..], &["--points", "4"]].concat(), ONE_PANEL);
    plots(&[&["mfpt", "optimize"][..], &base].concat(), ONE_PANEL);
}

#[test]
fn mfpt_distribution_backward_and_sampled() {
    let base = ["mfpt", "distribution", "--v0", "0", "--vt", "0.5"];
    plots(&base, TWO_PANELS);
    plots(
        &[&base[..], &["--method", "exact", "--particles", "100"]].concat(),
        TWO_PANELS,
    );
}

/// A finished two-axis sweep of `fp stationary` in `dir`.
fn sweep(dir: &Path, axes: &str) {
    let plan = dir.with_extension("toml");
    let text = format!("command = \"fp stationary\"\n[fixed]\ncells = 60\n[axes]\n{axes}");
    std::fs::write(&plan, text).unwrap();
    let o = irtp(&[
        "sweep",
        "run",
        plan.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_success(&o);
}

#[test]
fn a_sweep_is_a_heat_map_and_its_points_stay_sound() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sw");
    sweep(&dir, "sigma = [2.0, 3.0]\nrate = [0.5, 1.0, 2.0]\n");
    let d = dir.to_str().unwrap();
    assert_success(&irtp(&["plot", d]));
    let (size, drawn) = decode(&dir.join("plot.png"));
    assert_eq!(size, HEAT_MAP);
    assert!(drawn > 100_000, "{drawn} pixels drawn");
    // The image carries irtp's mark, so drawing it again replaces it.
    assert_success(&irtp(&["plot", d]));
    assert_eq!(decode(&dir.join("plot.png")).0, HEAT_MAP);
    for var in ["d_eff", "result.v2"] {
        let out = tmp.path().join(format!("{var}.png"));
        assert_success(&irtp(&[
            "plot",
            d,
            "--var",
            var,
            "--out",
            out.to_str().unwrap(),
        ]));
        assert_eq!(decode(&out).0, HEAT_MAP);
    }
    // A third crossed axis (a zip group): one heat map per value of it.
    let three = tmp.path().join("three");
    let zip = "[[zip]]\nlambda = [0.5, 5.0]\nreset_velocity = [0.0, 0.0]\n";
    sweep(
        &three,
        &format!("sigma = [2.0, 3.0]\nrate = [0.5, 1.0]\n{zip}"),
    );
    assert_success(&irtp(&["plot", three.to_str().unwrap(), "--var", "v2"]));
    assert_eq!(decode(&three.join("plot.png")).0, TWO_PANELS);
    // One crossed axis: the values against it, one panel.
    let one = tmp.path().join("one");
    sweep(&one, "sigma = [2.0, 3.0]\n");
    assert_success(&irtp(&["plot", one.to_str().unwrap()]));
    assert_eq!(decode(&one.join("plot.png")).0, ONE_PANEL);
    // A plot inside a point directory damages nothing.
    let ws = dir.join("workspace");
    let point = std::fs::read_dir(&ws)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    assert_success(&irtp(&["plot", point.to_str().unwrap()]));
    assert!(point.join("plot.png").is_file());
    let o = irtp(&["sweep", "status", d]);
    assert_success(&o);
    let text = String::from_utf8_lossy(&o.stdout).to_lowercase();
    assert!(text.contains(" 0 damaged"), "{text}");
}

#[test]
fn svg_goes_where_out_says() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    assert_success(&irtp(&[
        "analytic",
        "--points",
        "50",
        "--out",
        run.to_str().unwrap(),
    ]));
    let svg = tmp.path().join("density.svg");
    assert_success(&irtp(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        svg.to_str().unwrap(),
    ]));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.starts_with("<svg") && text.contains("<polyline"),
        "{}",
        &text[..80]
    );
    assert!(!run.join("plot.png").exists());
}

#[test]
fn bad_input_is_one_line_exit_2_nothing_written() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    assert_success(&irtp(&[
        "analytic",
        "--points",
        "50",
        "--out",
        run.to_str().unwrap(),
    ]));
    let r = run.to_str().unwrap();
    let before = entries(&run);
    let fresh = || tempfile::tempdir().unwrap();
    // Not an irtp directory.
    let empty = fresh();
    let o = irtp(&["plot", empty.path().to_str().unwrap()]);
    assert_rejected(&o, "DIR", &empty.path().join("plot.png"));
    // irtp reproduce drew its figures already.
    let fig = fresh();
    let prov = r#"{"software": "irtp", "command": "reproduce", "files": []}"#;
    std::fs::write(fig.path().join("run.json"), prov).unwrap();
    let o = irtp(&["plot", fig.path().to_str().unwrap()]);
    let err = assert_rejected(&o, "DIR", &fig.path().join("plot.png"));
    assert!(err.contains("figN.png"), "{err}");
    // --out: not .png/.svg, a missing directory, not writable.
    let out = fresh();
    let jpg = out.path().join("x.jpg");
    assert_rejected(
        &irtp(&["plot", r, "--out", jpg.to_str().unwrap()]),
        "--out",
        &jpg,
    );
    let deep = out.path().join("no/such/x.png");
    assert_rejected(
        &irtp(&["plot", r, "--out", deep.to_str().unwrap()]),
        "--out",
        &deep,
    );
    // --var with a single run.
    assert_rejected(
        &irtp(&["plot", r, "--var", "v2"]),
        "--var",
        &run.join("plot.png"),
    );
    // An unknown --var.
    let sw = tmp.path().join("sw");
    sweep(&sw, "sigma = [2.0, 3.0]\nrate = [0.5, 1.0]\n");
    let o = irtp(&["plot", sw.to_str().unwrap(), "--var", "nope"]);
    let err = assert_rejected(&o, "--var", &sw.join("plot.png"));
    assert!(err.contains("result.d_eff"), "{err}");
    // A column that holds no numbers: refused listing those that do.
    let o = irtp(&["plot", sw.to_str().unwrap(), "--var", "status"]);
    let err = assert_rejected(&o, "--var", &sw.join("plot.png"));
    assert!(err.contains("not") && err.contains("result.d_eff"), "{err}");
    // A missing input directory is the input's fault, not --out's.
    let missing = tmp.path().join("missing");
    assert_rejected(&irtp(&["plot", missing.to_str().unwrap()]), "DIR", &missing);
    // An existing file irtp plot did not draw is not replaced.
    let mine = out.path().join("mine.png");
    std::fs::write(&mine, "the user's").unwrap();
    let o = irtp(&["plot", r, "--out", mine.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "the user's");
    std::fs::remove_file(&mine).unwrap();
    assert_eq!(entries(&run), before);
    assert!(entries(out.path()).is_empty());
}

#[cfg(unix)]
#[test]
fn an_unwritable_out_is_refused() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    assert_success(&irtp(&[
        "analytic",
        "--points",
        "50",
        "--out",
        run.to_str().unwrap(),
    ]));
    let ro = tmp.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    // root writes anyway: then there is nothing to check.
    if std::fs::write(ro.join("probe"), b"").is_ok() {
        return;
    }
    let png = ro.join("x.png");
    let o = irtp(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]);
    assert_rejected(&o, "--out", &png);
    assert!(entries(&ro).is_empty());
}
