//! `irtp reproduce {fig1,fig2,fig3,fig5,fig6,fig7,fpt,media,search,noise,all} --out DIR [--quick] [--seed N]`.

use crate::{self as figures, store, Options, Which, SCALE};
use clap::Args;
use irtp_app::common::ForceArgs;
use irtp_app::{Context, Outcome, Results};
use serde_json::json;
use std::path::PathBuf;

/// Regenerate the paper's figures 1, 2, 3, 5, 6, 7: data (CSV), plots (PNG,
/// SVG; with the cargo feature `plot`, on by default), parameters.json,
/// claims.json / claims.md, REPORT.md and run.json in DIR. Each figure is
/// committed when finished (with its provenance `<fig>.json`); rerun, the
/// same command skips the figures already finished.
#[derive(Args, Debug)]
pub struct ReproduceArgs {
    /// Figures: fig1 fig2 fig3 fig5 fig6 fig7 (the paper's), fpt, media, search, noise (beyond it), or all.
    ///
    /// fpt (first-passage-time densities, beyond the paper), media (every drag law: Figs. 2 and 7 questions, beyond the paper), search (first passage in position: tau(r) and r* in every medium, beyond the paper), noise (the questions of Figs. 2, 6 and 7 under asymmetric, run-pause-tumble and thermal noise, beyond the paper), or all.
    #[arg(required = true, value_parser = parse_figure)]
    pub figures: Vec<Selection>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// `--force`.
    #[command(flatten)]
    pub force: ForceArgs,
    /// Small sizes for CI (seconds): same code path, fewer particles and points.
    #[arg(long)]
    pub quick: bool,
    /// Master seed; each curve derives its own seed from it.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true)]
    pub seed: u64,
}

/// One figure or all of them.
#[derive(Clone, Copy, Debug)]
pub enum Selection {
    /// Every figure.
    All,
    /// One figure.
    One(Which),
}

fn parse_figure(s: &str) -> Result<Selection, String> {
    if s == "all" {
        return Ok(Selection::All);
    }
    s.parse::<Which>().map(Selection::One).map_err(|_| {
        "expected one of fig1, fig2, fig3, fig5, fig6, fig7, fpt, media, search, noise, all"
            .to_string()
    })
}

impl ReproduceArgs {
    /// Flags → the figures (paper order, no duplicates) and their options.
    fn config(&self) -> (Vec<Which>, Options) {
        let mut which: Vec<Which> = Vec::new();
        for s in &self.figures {
            match s {
                Selection::All => which.extend(Which::ALL),
                Selection::One(w) => which.push(*w),
            }
        }
        which.sort_by_key(|w| *w as u8);
        which.dedup();
        let opts = Options {
            quick: self.quick,
            seed: self.seed,
        };
        (which, opts)
    }
}

/// Run `irtp reproduce`: compute the figures one by one, committing each
/// finished figure into `--out` (skipping those already there from the same
/// options and build), the index after each.
pub fn run(args: &ReproduceArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let (which, opts) = args.config();
    // Refuse a bad or occupied output directory before computing anything.
    let mut dir = store::Dir::open(&args.out, &opts, args.force.force)?;
    let t0 = std::time::Instant::now();
    let mut text = String::new();
    for &w in &which {
        if dir.finished(w).is_some() {
            text += &format!(
                "{}: skipped (finished in --out, same parameters and build)\n",
                w.name()
            );
            continue;
        }
        let progress = ctx.reporter.stage(w.name(), SCALE);
        let o = figures::run_figure(w, &opts, progress.as_ref())?;
        drop(progress);
        ctx.check()?;
        dir.commit_figure(&o, &ctx.argv)?;
        text += &format!("{}: {:.1} s\n", w.name(), o.wall_time_s);
    }
    let wall = t0.elapsed().as_secs_f64();
    let (provenance, files) = dir.write_index(&ctx.argv)?;
    if !figures::IMAGES {
        text += figures::NO_IMAGES;
        text += "\n";
    }
    let names: Vec<&str> = which.iter().map(|w| w.name()).collect();
    let claims = dir.claims(&which);
    let parameters = provenance["parameters"].clone();
    let results = Results {
        method: "figures".into(),
        seed: Some(opts.seed),
        json: json!({"figures": names, "claims": claims, "files": files}),
        parameters,
        tables: Vec::new(),
        json_files: Vec::new(),
        text,
        wall_time_s: wall,
    };
    let summary = irtp_app::summary("reproduce", &results, &provenance);
    Ok(Outcome {
        command: "reproduce",
        results,
        provenance,
        summary,
        written: Some((args.out.clone(), files)),
        warnings: dir.warnings.clone(),
    })
}

impl irtp_app::Runnable for ReproduceArgs {
    fn json(&self) -> bool {
        false
    }
    fn validate(&self) -> irtp::Result<()> {
        Ok(())
    }
    fn uses_seed(&self) -> bool {
        true
    }
    fn run(&self, ctx: &Context) -> irtp::Result<Outcome> {
        run(self, ctx)
    }
}
