//! `etlcal study NAME [--trials N] [--seed S] [--out DIR] [--json]`: the paper's
//! simulations and comparisons (`etl_studies`).
//!
//! NAME is one of `fig5`, `fig6`, `subsets`, `baseline`, `crlb`, or `all`; `crlb --rig
//! strong` runs the strong-distortion rig's study (crlb-strong.json, .md, plots). Each writes
//! NAME.json, NAME.md and its plots (PNG and SVG) into DIR, prints the markdown summary
//! (or, with `--json`, one JSON object: for `all`, the studies' objects by name) and draws
//! a progress bar on stderr while its Monte Carlo trials run (in parallel).

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use etl_formats::{Error, Result};
use etl_studies::{Study, StudyOptions, MAX_TRIALS};

use crate::progress::Bar;

/// The studies, as named on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Name {
    /// Modelling error of polynomial degrees 1..6 (Fig. 5).
    Fig5,
    /// Pixel noise, current noise, number of images; plain and errors-in-variables BA (Fig. 6).
    Fig6,
    /// 6..9 of 9 views and all 84 six-view subsets (Tables 1-2, Fig. 11).
    Subsets,
    /// Per-setting Zhang + cubic against the proposed method (Fig. 12).
    Baseline,
    /// Cramer-Rao bound of every parameter against the Monte Carlo spread.
    Crlb,
    /// Every study in turn.
    All,
}

/// The simulated rig of `--rig`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigArg {
    /// The paper's rig (docs/METHOD.md).
    Paper,
    /// The strong-distortion rig (k1 about -0.3, k2 about 0.15, OpenCV's normalised units).
    Strong,
}

/// Arguments of `etlcal study`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The study.
    #[arg(value_enum)]
    pub name: Name,
    /// Monte Carlo trials (per level where the study has levels), 1..=100000 [default: the
    /// study's: fig6 100, subsets 5 data sets, baseline 200, crlb 300].
    #[arg(long)]
    pub trials: Option<usize>,
    /// Base random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The simulated rig: the paper's, or `strong` (the strong-distortion rig: OpenCV's
    /// distortion family against its bound, the paper family's bias; `crlb` only).
    #[arg(long, value_enum, default_value = "paper")]
    pub rig: RigArg,
    /// Output directory (created with its missing parents).
    #[arg(long, value_name = "DIR", default_value = "etlcal-study")]
    pub out: PathBuf,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Runs `etlcal study`.
pub fn run(args: Args) -> Result<()> {
    if let Some(n) = args.trials.filter(|n| !(1..=MAX_TRIALS).contains(n)) {
        return Err(Error::invalid_value("--trials", n, format!("--trials {n} must lie in 1..={MAX_TRIALS}")));
    }
    if args.rig == RigArg::Strong && args.name != Name::Crlb {
        return Err(Error::invalid("--rig", "--rig strong is for `study crlb` only"));
    }
    // Read before the work: a malformed SOURCE_DATE_EPOCH is refused first; a set one
    // keeps the wall time out of the files.
    let wall_time = crate::output::source_date_epoch()?.is_none();
    crate::output::create_dir(&args.out)?;
    let bar = Bar::new(true);
    let opts = StudyOptions { trials: args.trials.unwrap_or(0), seed: args.seed, progress: &bar, wall_time };
    let studies = match args.name {
        Name::All => Study::ALL.to_vec(),
        Name::Fig5 => vec![Study::Fig5],
        Name::Fig6 => vec![Study::Fig6],
        Name::Subsets => vec![Study::Subsets],
        Name::Baseline => vec![Study::Baseline],
        Name::Crlb if args.rig == RigArg::Strong => vec![Study::CrlbStrong],
        Name::Crlb => vec![Study::Crlb],
    };
    let mut all = serde_json::Map::new();
    for study in studies {
        let out = study.run(&opts)?;
        out.write(&args.out)?;
        if args.json {
            all.insert(out.name.clone(), out.json.clone());
        } else {
            outln!("{}", out.markdown);
        }
    }
    if args.json {
        if all.len() == 1 {
            if let Some((_, v)) = all.into_iter().next() {
                print_json(&v);
            }
        } else {
            print_json(&json!(all));
        }
    } else {
        outln!("wrote the studies' .json, .md and plots to {}", args.out.display());
    }
    Ok(())
}
