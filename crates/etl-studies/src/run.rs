//! The studies by name: what `etlcal study NAME` and `etlcal.studies.run` run.

use etl_formats::{Error, Result};

use crate::{StudyOptions, StudyOutput};

/// One of the paper's studies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Study {
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
    /// The same on the strong-distortion rig, OpenCV's family, and the paper family's
    /// bias there (`crlb --rig strong`; not in [`Study::ALL`]).
    CrlbStrong,
}

impl Study {
    /// Every study, in the order `etlcal study all` runs them.
    pub const ALL: [Study; 5] = [Study::Fig5, Study::Fig6, Study::Subsets, Study::Baseline, Study::Crlb];

    /// The study's name (its file stem and its name on the command line).
    pub fn name(self) -> &'static str {
        match self {
            Study::Fig5 => "fig5",
            Study::Fig6 => "fig6",
            Study::Subsets => "subsets",
            Study::Baseline => "baseline",
            Study::Crlb => "crlb",
            Study::CrlbStrong => "crlb-strong",
        }
    }

    /// The study named `name` (`fig5`, `fig6`, `subsets`, `baseline`, `crlb`,
    /// `crlb-strong`).
    pub fn from_name(name: &str) -> Result<Study> {
        let every = Study::ALL.into_iter().chain([Study::CrlbStrong]);
        every.clone().find(|s| s.name() == name).ok_or_else(|| {
            let names: Vec<&str> = every.map(|s| s.name()).collect();
            Error::invalid_value("study", name, format!("no study named {name:?} (one of {})", names.join(", ")))
        })
    }

    /// Runs the study with `opts` (trials 0: the study's own default count).
    pub fn run(self, opts: &StudyOptions) -> Result<StudyOutput> {
        Ok(match self {
            Study::Fig5 => crate::fig5::fig5()?.output(),
            Study::Fig6 => crate::fig6::fig6(opts)?.output(),
            Study::Subsets => crate::subsets::subsets(opts)?.output(),
            Study::Baseline => crate::baseline::baseline(opts)?.output(),
            Study::Crlb => crate::crlb::crlb(opts)?.output(),
            Study::CrlbStrong => crate::strong::strong_crlb(opts)?.output(),
        })
    }
}
