//! The paper's simulations and comparisons, reproduced with etlcal: one file per
//! study, [`common`] for what they share (trials in parallel, errors against the truth,
//! statistics, plots, markdown).
//!
//! - [`fig5`]: modelling error of polynomial degrees 1..6 (section 5.1.1, Fig. 5);
//! - [`fig6`]: pixel noise, current noise and number of images (section 5.1.2, Fig. 6), the
//!   plain and the errors-in-variables bundle adjustment side by side, with the
//!   Cramer-Rao bound;
//! - [`subsets`]: 6..9 of 9 views and all 84 six-view subsets (Tables 1-2, Fig. 11);
//! - [`baseline`]: per-setting Zhang + cubic against the proposed method (Fig. 12);
//! - [`model`]: the camera model and lens physics over currents; polynomial fits of f_com(E);
//! - [`demo`]: the demo's validation of a calibration against the truth;
//! - [`crlb`]: the Cramer-Rao bound of every parameter and of fx(E) against the Monte
//!   Carlo spread of etlcal's estimates (statistical efficiency);
//! - [`strong`]: the same on the strong-distortion rig for OpenCV's distortion family,
//!   with the paper family's bias there (`crlb --rig strong`);
//! - [`rig_efficiency`]: the joint calibration of a simulated 2-camera rig against the
//!   Cramer-Rao bound of the joint problem (extrinsics and each camera's fx(E));
//! - [`rig_triangulation`]: the acceptance of a calibrated 2-camera rig: triangulated
//!   points at random settings against their propagated covariance, and a 2 mm move;
//! - [`rig_traced`]: the same acceptance on a ray-traced two-camera rig, the coverage
//!   measured in the stage's world frame;
//! - [`optics`]: a 2 mm move by PnP on the ray-traced rigs, the ETL model against a
//!   per-current calibration, and ([`optics::floor`]) what any central model can reach there.
//!
//! Each study returns a result struct; its `output()` gives the `--json` object, a
//! markdown summary and the plots ([`common::StudyOutput`]).

pub mod baseline;
pub mod common;
pub mod crlb;
pub mod demo;
pub mod fig5;
pub mod fig6;
pub mod model;
pub mod optics;
pub mod rig_efficiency;
pub mod rig_traced;
pub mod rig_triangulation;
mod run;
pub mod strong;
pub mod subsets;

pub use common::{StudyOptions, StudyOutput, MAX_TRIALS};
pub use etl_formats::{Error, Result};
pub use run::Study;
