//! etl-report: everything etlcal draws. The calibration report (plots and an index.html,
//! [`write_report`]) and the figures of the studies ([`figure`]).

mod calibration;
pub mod figure;

pub use calibration::*;
pub use etl_formats::{Error, Result};
