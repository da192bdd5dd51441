//! `irtp analytic` with a noise model other than the paper's
//! (docs/equations.md, "Noise kinds"): the closed forms of
//! [`irtp::analytic::noise`]. `summary.json` holds, for linear drag, `pi`,
//! `conditional_mean`, `v_mean`, `v2`, `drift` and `d_eff` (Eqs.
//! (N2)-(N6)) and/or `density` (an
//! asymmetric telegraph noise at r = 0: its edges, moments and the mass in
//! the + state, Eq. (N8)); `density.csv` (v, p, p_plus, p_minus) only with
//! the density. What does not exist for the case is absent, never filled.

use super::analytic::AnalyticArgs;
use super::format::{fmt_digits, fmt_sig};
use super::{finish, open_out, to_value, Context, Outcome, Results, Table};
use irtp::analytic::linear_noise::NoiseMoments;
use irtp::analytic::noise::{solve, NoiseClosedForm};
use irtp::analytic::telegraph_r0::TelegraphR0Density;
use irtp::numerics::grid::chebyshev;
use irtp::{DragLaw, Params};
use serde::Serialize;
use std::time::Instant;

/// The stationary density's summary (Eq. (N8)).
#[derive(Serialize)]
struct DensityReport {
    v_lower: f64,
    v_upper: f64,
    edge_exponents: (f64, f64),
    mass_plus: f64,
    v_mean: f64,
    v2: f64,
    v4: f64,
}

#[derive(Serialize)]
struct Report {
    drag: DragLaw,
    noise: String,
    temperature: f64,
    rate: f64,
    reset_velocity: f64,
    /// Flattened, so a sweep's table has `v_mean`, `v2`, `drift`, `d_eff`.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    moments: Option<NoiseMoments>,
    #[serde(skip_serializing_if = "Option::is_none")]
    density: Option<DensityReport>,
}

#[derive(Serialize)]
struct RunParams {
    drag: DragLaw,
    noise: String,
    temperature: f64,
    rate: f64,
    reset_velocity: f64,
    /// The points of `density.csv`, absent without the density.
    #[serde(skip_serializing_if = "Option::is_none")]
    points: Option<usize>,
}

fn density_report(d: &TelegraphR0Density) -> irtp::Result<DensityReport> {
    let (v_lower, v_upper) = d.bounds();
    Ok(DensityReport {
        v_lower,
        v_upper,
        edge_exponents: d.edge_exponents(),
        mass_plus: d.state_mass()?.0,
        v_mean: d.moment(1)?,
        v2: d.moment(2)?,
        v4: d.moment(4)?,
    })
}

fn report(p: &Params, c: &NoiseClosedForm) -> irtp::Result<Report> {
    Ok(Report {
        drag: p.drag(),
        noise: c.noise.spec(),
        temperature: c.noise.temperature(),
        rate: p.rate(),
        reset_velocity: p.reset_velocity(),
        moments: c.moments.clone(),
        density: c.density.as_ref().map(density_report).transpose()?,
    })
}

/// Run `irtp analytic` for `params` (a noise model other than the paper's).
pub(crate) fn run(
    args: &AnalyticArgs,
    params: &Params,
    points: usize,
    ctx: &Context,
    t0: Instant,
) -> irtp::Result<Outcome> {
    let c = solve(params)?;
    let report = report(params, &c)?;
    let out = open_out("analytic", args.out.as_deref(), args.force.force)?;
    let tables = match &c.density {
        Some(d) => {
            let (vl, vu) = d.bounds();
            let rows = chebyshev(vl, vu, points).into_iter().map(|v| {
                let (plus, minus) = d.state_pdf(v);
                [v, d.pdf(v), plus, minus]
            });
            vec![Table::from_rows(
                "density",
                &["v", "p", "p_plus", "p_minus"],
                rows,
            )]
        }
        None => Vec::new(),
    };
    let run = RunParams {
        drag: report.drag.clone(),
        noise: report.noise.clone(),
        temperature: report.temperature,
        rate: report.rate,
        reset_velocity: report.reset_velocity,
        points: c.density.is_some().then_some(points),
    };
    let method = match (&c.moments, &c.density) {
        (Some(_), Some(_)) => {
            "linear-drag noise moments (N3)-(N6); exact r=0 telegraph density (N8)"
        }
        (Some(_), None) => "linear-drag noise moments (N3)-(N6)",
        _ => "exact r=0 telegraph density (N8); adaptive Gauss-Kronrod normalisation",
    };
    let results = Results {
        method: method.into(),
        seed: None,
        json: to_value(&report),
        parameters: to_value(&run),
        tables,
        json_files: Vec::new(),
        text: text_report(&report),
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    finish("analytic", results, out, ctx)
}

fn text_report(r: &Report) -> String {
    let f = fmt_sig;
    let mut s = format!(
        "{} drag, noise {}, T = {}, r = {}, v_r = {}\n",
        r.drag,
        r.noise,
        f(r.temperature),
        f(r.rate),
        f(r.reset_velocity)
    );
    if let Some(m) = &r.moments {
        s += &format!(
            "<v> = {}   <v^2> = {}   drift = {}   D_eff = {}\n",
            fmt_digits(m.v_mean, 15),
            fmt_digits(m.v2, 15),
            fmt_digits(m.drift, 15),
            fmt_digits(m.d_eff, 15)
        );
    }
    if let Some(d) = &r.density {
        s += &format!(
            "r = 0 density on ({}, {}): mass in + = {}   <v> = {}   <v^2> = {}   <v^4> = {}\n",
            f(d.v_lower),
            f(d.v_upper),
            fmt_digits(d.mass_plus, 15),
            fmt_digits(d.v_mean, 15),
            fmt_digits(d.v2, 15),
            fmt_digits(d.v4, 15)
        );
    }
    s
}
