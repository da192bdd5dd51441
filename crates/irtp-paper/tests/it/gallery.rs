//! The gallery: `irtp plot`'s figure of every command's output (small runs)
//! and of sweeps over one, two and three axes, rendered to PNG and checked
//! as a reader would look at it:
//! - the data occupy a sensible part of the plot: the central 98 % of the
//!   drawn values (`robust_range`, guides left out) lies inside the
//!   vertical range and spans at least a quarter of it (no flat line under
//!   a range set by an edge singularity or an atom);
//! - a heat map's cells are not all one colour, and the plotting area of
//!   every panel has drawn pixels of the data's colours;
//! - no two texts (tick labels, axis labels, colour-bar ticks and label)
//!   overlap, by the boxes the layout computed from the backend's text sizes;
//! - titles name parameters in symbols, not the directory.
//!
//! With `IRTP_GALLERY_DIR` set the PNGs are kept there, to be looked at.

use irtp_paper::plot::{robust_range, Figure, PanelDrawn};
use irtp_paper::quicklook;
use std::path::{Path, PathBuf};

/// Run `irtp ARGS --out DIR` through the library.
fn run(args: &[&str], out: &Path) {
    use clap::Parser;
    let mut argv = vec!["irtp"];
    argv.extend(args);
    argv.extend(["--out", out.to_str().unwrap()]);
    let cli = irtp_paper::Cli::try_parse_from(&argv).unwrap_or_else(|e| panic!("{argv:?}: {e}"));
    let quiet = irtp_app::Quiet;
    let ctx = irtp_app::Context::new(&quiet);
    cli.command
        .run(&ctx)
        .unwrap_or_else(|e| panic!("{argv:?}: {e}"));
}

/// Run the sweep `plan` (TOML) into `dir`.
fn sweep(plan: &str, dir: &Path) {
    let plan = irtp_app::sweep::Plan::parse(plan).unwrap();
    let opts = irtp_app::sweep::RunOptions {
        shard: irtp_app::sweep::Shard::ALL,
        retry_failed: false,
    };
    irtp_app::sweep::run(&plan, dir, opts, &()).unwrap();
    assert!(dir.join("results.csv").is_file());
}

/// Where the PNG of `name` goes: `IRTP_GALLERY_DIR` or the temporary dir.
fn png_path(tmp: &Path, name: &str) -> PathBuf {
    match std::env::var_os("IRTP_GALLERY_DIR") {
        Some(d) => {
            std::fs::create_dir_all(&d).unwrap();
            Path::new(&d).join(format!("{name}.png"))
        }
        None => tmp.join(format!("{name}.png")),
    }
}

/// Decode a PNG: width, height, RGB pixels.
fn decode(path: &Path) -> (usize, usize, Vec<[u8; 3]>) {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(bytes.as_slice()).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    let px = buf[..info.buffer_size()]
        .chunks(ch)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width as usize, info.height as usize, px)
}

/// Whether a pixel is drawn in colour or black (not white, not a grey of
/// the grid or frame).
fn inked(p: [u8; 3]) -> bool {
    let (lo, hi) = (p.iter().min().unwrap(), p.iter().max().unwrap());
    hi - lo > 40 || *hi < 90
}

/// The checks of the module's documentation, for one figure.
fn check(name: &str, fig: &Figure, drawn: &[PanelDrawn], png: &Path) {
    assert_eq!(fig.panels.len(), drawn.len(), "{name}");
    assert!(!fig.title.contains("/tmp"), "{name}: title {}", fig.title);
    let (w, _, px) = decode(png);
    for (k, (p, d)) in fig.panels.iter().zip(drawn).enumerate() {
        let at = format!("{name} panel {k} ({})", p.title);
        let overlaps = d.overlaps();
        assert!(overlaps.is_empty(), "{at}: texts overlap: {overlaps:?}");
        let (l, t, r, b) = d.plot_box;
        let inside: Vec<[u8; 3]> = (t.max(0)..b)
            .flat_map(|y| (l.max(0)..r).map(move |x| (x, y)))
            .map(|(x, y)| px[y as usize * w + x as usize])
            .collect();
        let ink = inside.iter().filter(|&&q| inked(q)).count();
        assert!(
            ink * 200 > inside.len(),
            "{at}: {ink} of {} pixels drawn",
            inside.len()
        );
        if let Some(h) = &p.heat {
            let mut levels: Vec<i64> = h
                .values
                .iter()
                .flatten()
                .flatten()
                .map(|&v| (h.level(v) * 100.0).round() as i64)
                .collect();
            levels.sort();
            levels.dedup();
            assert!(levels.len() >= 3, "{at}: cells of {} colours", levels.len());
            let mut colours: Vec<[u8; 3]> = inside.clone();
            colours.sort();
            colours.dedup();
            assert!(colours.len() >= 3, "{at}: {} colours drawn", colours.len());
            continue;
        }
        let (qlo, qhi) = robust_range(p).expect("a panel with data");
        let lo = p.y.tr(d.y_range.0).unwrap();
        let hi = p.y.tr(d.y_range.1).unwrap();
        let tol = 1e-9 * (hi - lo);
        assert!(
            qlo >= lo - tol && qhi <= hi + tol,
            "{at}: data {qlo}..{qhi} outside {lo}..{hi}"
        );
        assert!(
            qhi - qlo >= 0.25 * (hi - lo),
            "{at}: data {qlo}..{qhi} squeezed into range {lo}..{hi}"
        );
    }
}

/// Run, plot, render and check one command's output.
fn gallery(name: &str, args: &[&str]) -> (Figure, Vec<PanelDrawn>) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    run(args, &out);
    plot_dir(name, &out, None, tmp.path())
}

/// Plot the directory `dir`, render and check it.
fn plot_dir(name: &str, dir: &Path, var: Option<&str>, tmp: &Path) -> (Figure, Vec<PanelDrawn>) {
    let fig = quicklook::picture(dir, var).unwrap_or_else(|e| panic!("{name}: {e}"));
    let png = png_path(tmp, name);
    let drawn = fig.render_png_drawn(&png).unwrap();
    check(name, &fig, &drawn, &png);
    (fig, drawn)
}

#[test]
fn simulate_density_and_moments() {
    let (fig, _) = gallery(
        "simulate",
        &[
            "simulate",
            "--particles",
            "300",
            "--t-max",
            "10",
            "--burn-in",
            "3",
        ],
    );
    assert!(fig.title.contains("Σ = 3, λ = 0.5, r = 2"), "{}", fig.title);
    // The moments on log axes: the linear time grid (200 steps, 180 of them
    // in the last decade) thinned to about 40 points evenly spaced in log t.
    let t = &fig.panels[1].series[0].x;
    let decades = (t[t.len() - 1] / t[0]).log10();
    let late = t.iter().filter(|&&x| x > t[t.len() - 1] / 10.0).count();
    assert!(t.len() >= 20, "{} times", t.len());
    assert!(
        late as f64 <= 40.0 / decades + 2.0,
        "{late} of {} times in the last decade",
        t.len()
    );
}

#[test]
fn simulate_with_a_reset_position() {
    let a = [
        "simulate",
        "--particles",
        "200",
        "--t-max",
        "4",
        "--burn-in",
        "2",
        "--reset-position",
        "0",
    ];
    gallery("simulate-position", &a);
}

#[test]
fn readme_fp_stationary_is_not_a_flat_line() {
    let a = [
        "fp",
        "stationary",
        "--drag",
        "tan",
        "--sigma",
        "3",
        "--lambda",
        "0.9",
        "--rate",
        "2",
        "--cells",
        "400",
    ];
    let (fig, drawn) = gallery("fp-stationary", &a);
    // The edge cells (p up to 530) are beyond the axis, marked, not its range.
    assert!(
        drawn[0].clipped >= 2 && drawn[0].y_range.1 < 5.0,
        "{:?}",
        drawn[0].y_range
    );
    let legend = fig.panels[0].legend_lines().join("; ");
    assert!(
        legend.contains("η = +Σ") && legend.contains("η = −Σ") && legend.contains("exact at r = 0"),
        "{legend}"
    );
    assert!(
        fig.title.contains("tan drag, Σ = 3, λ = 0.9, r = 2"),
        "{}",
        fig.title
    );
}

#[test]
fn three_state_noise_names_its_states() {
    let a = [
        "fp",
        "stationary",
        "--noise",
        "rpt:sigma=1,alpha=1,beta=1",
        "--drag",
        "tan",
        "--rate",
        "2",
        "--cells",
        "200",
    ];
    let (fig, _) = gallery("fp-stationary-rpt", &a);
    let legend = fig.panels[0].legend_lines().join("; ");
    assert!(
        legend.contains("pause (η = 0)") && legend.contains("run (η = −1)"),
        "{legend}"
    );
    assert!(!legend.contains("p₊") && !legend.contains("p+"), "{legend}");
    // The reset into the pause is a point mass, drawn as an atom (a stem
    // no taller than the continuous density's range, its mass in the legend).
    assert!(legend.contains("atom at v = 0: mass 0.3"), "{legend}");
    let ((_, hi), _) = irtp_paper::plot::fit_y(&fig.panels[0]);
    let stem = fig.panels[0]
        .series
        .iter()
        .find(|s| s.source == "atom")
        .expect("a stem");
    assert!(stem.y.iter().all(|&y| y <= hi), "{:?} above {hi}", stem.y);
}

#[test]
fn analytic_and_fp_transient() {
    gallery("analytic", &["analytic", "--points", "300"]);
    let a = [
        "fp",
        "transient",
        "--t-max",
        "0.5",
        "--cells",
        "64",
        "--samples",
        "5",
        "--snapshots",
        "3",
    ];
    gallery("fp-transient", &a);
}

#[test]
fn fp_msd_has_power_law_guides() {
    let a = [
        "fp", "msd", "--drag", "tanh", "--sigma", "0.6", "--rate", "1", "--cells", "64",
    ];
    let (fig, _) = gallery("fp-msd", &a);
    let notes: Vec<&str> = fig.panels[0]
        .notes
        .iter()
        .map(|n| n.text.as_str())
        .collect();
    assert!(notes.contains(&"∝ t"), "{notes:?}");
    assert!(
        notes
            .iter()
            .any(|n| n.starts_with("∝ t") && n.len() > "∝ t".len()),
        "{notes:?}"
    );
}

#[test]
fn mfpt_profile_survival_and_distributions() {
    gallery(
        "mfpt",
        &["mfpt", "--v0", "-0.249", "--vt", "0.5", "--cells", "200"],
    );
    let a = [
        "mfpt",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--method",
        "exact",
        "--particles",
        "300",
    ];
    gallery("mfpt-exact", &a);
    let a = [
        "mfpt",
        "distribution",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--cells",
        "200",
    ];
    gallery("mfpt-distribution", &a);
    let a = [
        "mfpt",
        "distribution",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--method",
        "exact",
        "--particles",
        "300",
    ];
    gallery("mfpt-distribution-exact", &a);
}

#[test]
fn mfpt_scan_marks_its_optimum() {
    let a = [
        "mfpt", "scan", "--v0", "-0.249", "--vt", "0.5", "--over", "rate", "--from", "0.1", "--to",
        "10", "--points", "9", "--log", "--cells", "200",
    ];
    let (fig, _) = gallery("mfpt-scan", &a);
    let legend = fig.panels[0].legend_lines().join("; ");
    assert!(legend.contains("smallest τ"), "{legend}");
    assert!(
        !fig.title.contains("r = 2"),
        "the scanned rate is no title parameter: {}",
        fig.title
    );
    let a = [
        "mfpt",
        "optimize",
        "--v0",
        "-0.249",
        "--vt",
        "0.5",
        "--cells",
        "1000",
        "--grid-points",
        "7",
    ];
    // τ(r) reaches 10⁷⁹ at r = 1000 on this grid: cut, the optimum in view.
    let (_, drawn) = gallery("mfpt-optimize", &a);
    assert!(
        drawn[0].clipped >= 1 && drawn[0].y_range.1 < 5.0,
        "{:?}",
        drawn[0].y_range
    );
}

/// A plan of `fp stationary` over `axes` (TOML lines).
fn plan(axes: &str) -> String {
    format!("command = \"fp stationary\"\n[fixed]\ndrag = \"tan\"\ncells = 100\n{axes}")
}

#[test]
fn one_axis_sweep_is_a_line_on_log_axes_with_the_r_minus_two_law() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sweep");
    let axes = "[axes]\nrate = { from = 0.1, to = 30.0, points = 7, spacing = \"log\" }\n";
    sweep(&plan(axes), &dir);
    let (fig, _) = plot_dir("sweep-one-axis", &dir, Some("d_eff"), tmp.path());
    let p = &fig.panels[0];
    assert_eq!(fig.panels.len(), 1);
    assert_eq!(
        (p.x.scale, p.y.scale),
        (irtp_paper::plot::Scale::Log, irtp_paper::plot::Scale::Log)
    );
    assert!(p.notes.iter().any(|n| n.text == "∝ r⁻²"));
    assert_eq!((p.x.label.as_str(), p.y.label.as_str()), ("r", "D_{eff}"));
    let ticks: Vec<&str> =
        p.x.ticks
            .as_ref()
            .unwrap()
            .iter()
            .map(|t| t.1.as_str())
            .collect();
    assert_eq!(ticks, ["0.1", "0.26", "0.67", "1.7", "4.5", "12", "30"]);
}

#[test]
fn two_axis_sweep_is_a_heat_map_on_geometric_cells() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sweep");
    let axes = "[axes]\nsigma = [1.0, 2.0, 3.0]\nrate = { from = 0.1, to = 10.0, points = 5, spacing = \"log\" }\n";
    sweep(&plan(axes), &dir);
    let (fig, _) = plot_dir("sweep-two-axes", &dir, Some("d_eff"), tmp.path());
    let h = fig.panels[0].heat.as_ref().unwrap();
    assert_eq!(h.label, "D_{eff}");
    // Edges between 0.1, 0.316, 1, ...: geometric means, 10^-0.75 the first inner one.
    assert!(
        (h.x_edges[1] / 10f64.powf(-0.75) - 1.0).abs() < 1e-9,
        "{:?}",
        h.x_edges
    );
    assert_eq!(h.y_edges, [0.5, 1.5, 2.5, 3.5]);
    let ticks: Vec<&str> = fig.panels[0]
        .x
        .ticks
        .as_ref()
        .unwrap()
        .iter()
        .map(|t| t.1.as_str())
        .collect();
    assert_eq!(ticks, ["0.1", "0.32", "1", "3.2", "10"]);
    assert!(
        fig.title
            .starts_with("D_{eff} over a sweep of fp stationary: tan drag"),
        "{}",
        fig.title
    );
}

#[test]
fn three_axis_sweep_is_small_multiples_on_one_scale() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sweep");
    let axes = "[axes]\nsigma = [1.0, 3.0]\nrate = [0.5, 2.0, 8.0]\n[[zip]]\nlambda = [0.5, 5.0]\nreset_velocity = [0.0, 0.1]\n";
    sweep(&plan(axes), &dir);
    let (fig, _) = plot_dir("sweep-three-axes", &dir, Some("v2"), tmp.path());
    assert_eq!(fig.panels.len(), 2);
    assert_eq!(fig.panels[1].title, "λ = 5.0, v_{r} = 0.1");
    let (a, b) = (
        fig.panels[0].heat.as_ref().unwrap(),
        fig.panels[1].heat.as_ref().unwrap(),
    );
    assert_eq!(a.value_range(), b.value_range());
}
