//! etl-report: everything etlcal draws. The calibration report (figures with the
//! calibration's uncertainty, and an index.html, [`write_report`]) and the figures of the
//! studies ([`figure`]), and the page of a monofocal calibration ([`zhang`]).

mod calibration;
mod data;
pub mod figure;
pub mod heat_map;
mod html;
pub mod lens_dynamics;
mod plots;
mod uncertainty;
pub mod zhang;

pub use calibration::*;
pub use data::{Provenance, REPORT_FIGURES};
pub use etl_formats::{Error, Result};
