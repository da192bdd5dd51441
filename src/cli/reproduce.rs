//! `irtp reproduce {fig1,fig2,fig3,fig5,fig6,fig7,all} --out DIR [--quick] [--seed N]`.

use super::progress::Bar;
use clap::Args;
use irtp::figures::{self, Options, Which, SCALE};
use irtp::io::OutputDir;
use irtp::parallel::Progress;
use std::path::PathBuf;

/// Regenerate the paper's figures 1, 2, 3, 5, 6, 7: data (CSV), plots (PNG,
/// SVG; with the cargo feature `plot`, on by default), parameters.json,
/// claims.json / claims.md, REPORT.md and run.json in DIR.
#[derive(Args, Debug)]
pub struct ReproduceArgs {
    /// Figures: fig1 fig2 fig3 fig5 fig6 fig7, or all.
    #[arg(required = true, value_parser = parse_figure)]
    pub figures: Vec<Selection>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
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
    s.parse::<Which>()
        .map(Selection::One)
        .map_err(|_| "expected one of fig1, fig2, fig3, fig5, fig6, fig7, all".to_string())
}

struct BarProgress(Bar);
impl Progress for BarProgress {
    fn update(&self, done: u64, total: u64) {
        self.0.update(done, total);
    }
}
impl Drop for BarProgress {
    fn drop(&mut self) {
        self.0.finish();
    }
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

/// Run the subcommand.
pub fn run(args: ReproduceArgs) -> anyhow::Result<()> {
    let (which, opts) = args.config();
    // Validate the output directory before computing anything.
    let out = OutputDir::new(&args.out)?;
    let t0 = std::time::Instant::now();
    let outputs = figures::reproduce(&which, &opts, |w| {
        Box::new(BarProgress(Bar::new(w.name(), SCALE)))
    })?;
    let files = figures::write_outputs(out, &outputs, &opts, t0.elapsed().as_secs_f64())?;
    for o in &outputs {
        eprintln!("{}: {:.1} s", o.which.name(), o.wall_time_s);
    }
    eprintln!(
        "wrote {} files to {} in {:.1} s",
        files.len(),
        args.out.display(),
        t0.elapsed().as_secs_f64()
    );
    if !figures::IMAGES {
        println!("{}", figures::NO_IMAGES);
    }
    Ok(())
}
