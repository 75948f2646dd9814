//! The calibration report: PNG and SVG figures and an `index.html` that shows them with
//! the numbers (the figures are listed in [`crate::REPORT_FIGURES`]).
//!
//! The uncertainty shown is first order, from the calibration's covariance C of the 25
//! numbers: a curve value q(E) has the std sqrt(J_q C J_q^T), a projected pixel the 2 x 2
//! covariance J_p C J_p^T ([`etl_core::calib::projection_uncertainty`]). A calibration
//! without a covariance (older files) gets the figures without bands and a note saying so.
//!
//! The residual, coverage and per-view figures need the observations. Text needs a
//! TrueType font: the first of `$ETLCAL_FONT` and a few usual system fonts that exists is
//! used; without one the plots are drawn without text and index.html carries the labels.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use etl_formats::calibration::{Calibration, ThermalRef};
use etl_formats::observations::Observations;
use etl_formats::write_atomic;
use etl_formats::{Error, Result};
use plotters::prelude::*;

use crate::data::{gather, Provenance};
use crate::figure::{page, DrawResult};
use crate::plots;

const FONT_CANDIDATES: [&str; 6] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// Registers a font for plot text once; false when none was found.
pub(crate) fn font_available() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        let env = std::env::var_os("ETLCAL_FONT").map(PathBuf::from);
        for path in env.into_iter().chain(FONT_CANDIDATES.iter().map(PathBuf::from)) {
            if let Ok(bytes) = std::fs::read(&path) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                    return true;
                }
            }
        }
        false
    })
}

/// The files a report wrote.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ReportFiles {
    /// Every file written, in `dir`.
    pub files: Vec<PathBuf>,
    /// Whether plot text could be drawn (a font was found).
    pub text: bool,
}

/// Draws `$draw` as SVG and PNG into `$dir/$name.{svg,png}` (atomic writes).
macro_rules! plot {
    ($dir:expr, $name:expr, $size:expr, $d:expr, $text:expr, $draw:path, $files:expr) => {{
        let (name, size): (&str, (u32, u32)) = ($name, $size);
        // No input of the user's is at fault when a plot fails: `what` names the plot.
        let fail = |e: Box<dyn std::error::Error>| Error::invalid(format!("plot {name}"), format!("plot {name}: {e}"));
        let mut s = String::new();
        {
            let root = SVGBackend::with_string(&mut s, size).into_drawing_area();
            let r: DrawResult = page(&root, || $draw(&root, $d, $text));
            r.map_err(fail)?;
        }
        let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
            let r: DrawResult = page(&root, || $draw(&root, $d, $text));
            r.map_err(fail)?;
        }
        finish_plot($dir, name, size, buf, &s, $files)?;
    }};
}

fn finish_plot(
    dir: &Path,
    name: &str,
    size: (u32, u32),
    buf: Vec<u8>,
    svg: &str,
    files: &mut Vec<PathBuf>,
) -> Result<()> {
    let img = image::RgbImage::from_raw(size.0, size.1, buf)
        .ok_or_else(|| Error::invalid(format!("plot {name}"), format!("plot {name}: bitmap size mismatch")))?;
    let mut bytes = std::io::Cursor::new(vec![]);
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| Error::invalid(format!("plot {name}"), format!("plot {name}: PNG encoding: {e}")))?;
    let (p, q) = (dir.join(format!("{name}.png")), dir.join(format!("{name}.svg")));
    write_atomic(&p, bytes.get_ref())?;
    write_atomic(&q, svg.as_bytes())?;
    files.push(p);
    files.push(q);
    Ok(())
}

/// Writes the report of `cal` into the existing directory `dir`: the figures of
/// [`crate::REPORT_FIGURES`] as SVG and PNG (those of the views only when `obs` is given; E_com
/// of views without one through `thermal`) and `index.html`, which shows them with the
/// parameter table (value, std, a flag where |value| < 2 std), the strongly correlated
/// pairs (|r| > 0.9) and `provenance`.
///
/// Errors: `dir` missing; observations that fail validation; a plot that cannot be drawn.
pub fn write_report(
    cal: &Calibration,
    obs: Option<&Observations>,
    thermal: Option<&ThermalRef>,
    provenance: &Provenance,
    dir: &Path,
) -> Result<ReportFiles> {
    if !dir.is_dir() {
        return Err(Error::Output {
            path: dir.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "the output directory does not exist"),
        });
    }
    let d = gather(cal, obs, thermal)?;
    let text = font_available();
    let mut files = vec![];
    plot!(dir, "focal", (1100, 760), &d, text, plots::draw_focal, &mut files);
    plot!(dir, "distortion", (1300, 800), &d, text, plots::draw_distortion, &mut files);
    if !d.std_maps.is_empty() {
        plot!(dir, "projection_std", (1400, 440), &d, text, plots::draw_projection_std, &mut files);
    }
    if !d.views.is_empty() {
        let rows = plots::coverage_groups(&d).len().div_ceil(3) as u32;
        plot!(dir, "coverage", (1300, 40 + 360 * rows), &d, text, plots::draw_coverage, &mut files);
    }
    if d.residual_count() > 0 {
        plot!(dir, "residual_map", (1000, 760), &d, text, plots::draw_residual_map, &mut files);
        plot!(dir, "view_rms", (1000, 420), &d, text, plots::draw_view_rms, &mut files);
        plot!(dir, "residual_hist", (900, 500), &d, text, plots::draw_histogram, &mut files);
    }
    plot!(dir, "distortion_field", (1400, 440), &d, text, plots::draw_distortion_field, &mut files);
    if d.covariance.is_some() {
        plot!(dir, "correlation", (860, 800), &d, text, plots::draw_correlation, &mut files);
    }
    let index = dir.join("index.html");
    write_atomic(&index, crate::html::index(&d, text, provenance, &files).as_bytes())?;
    files.push(index);
    Ok(ReportFiles { files, text })
}
