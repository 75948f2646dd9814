//! The report of a monofocal (Zhang) calibration: its numbers with their standard
//! deviations, and its projection uncertainty over the image in mrcal's sense
//! (`ZhangResult::projection_std`) as two heat maps, at infinity and at the views' distance.

use std::path::{Path, PathBuf};

use etl_calib::zhang::ZhangResult;

use crate::heat_map::heat_map_png;
use crate::html::esc;
use crate::{Error, Result};

/// The files [`write_zhang_report`] writes, in its output directory.
pub const ZHANG_REPORT_FILES: [&str; 3] = ["index.html", "uncertainty_infinity.png", "uncertainty_views_distance.png"];

/// Cells of the uncertainty maps across and down the image.
const MAP_CELLS: [usize; 2] = [32, 24];
/// Pixels a cell in the PNGs.
const CELL_PX: u32 = 20;

/// The worst-direction standard deviation (mrcal's "worstdirection-stdev": the 1-sigma
/// ellipse's major half-axis, px) at each cell centre of an image of `size`, at
/// `distance_mm` (None: infinity); NaN where a pixel does not unproject.
fn uncertainty_map(z: &ZhangResult, size: [u32; 2], distance_mm: Option<f64>) -> Vec<f64> {
    let [cols, rows] = MAP_CELLS;
    let (cw, ch) = (f64::from(size[0]) / cols as f64, f64::from(size[1]) / rows as f64);
    (0..rows)
        .flat_map(|j| (0..cols).map(move |i| [(i as f64 + 0.5) * cw - 0.5, (j as f64 + 0.5) * ch - 0.5]))
        .map(|q| match z.projection_std(q, distance_mm) {
            Ok(u) => {
                let [[a, b], [_, c]] = u.covariance_px2;
                (0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt()).max(0.0).sqrt()
            }
            Err(_) => f64::NAN,
        })
        .collect()
}

/// Writes [`ZHANG_REPORT_FILES`] for `z` (an image of `size`) into `dir` (which exists);
/// returns their paths. The two maps share one logarithmic colour scale, from the smaller
/// of their smallest values to the larger of their largest (the corners' uncertainty is
/// often a hundred times the centre's), stated on the page. Errors: a file that cannot be
/// written.
pub fn write_zhang_report(z: &ZhangResult, size: [u32; 2], dir: &Path) -> Result<Vec<PathBuf>> {
    let d = z.views_distance_mm();
    let maps = [uncertainty_map(z, size, None), uncertainty_map(z, size, Some(d))];
    let finite = || maps.iter().flatten().copied().filter(|v| v.is_finite() && *v > 0.0);
    let (lo, hi) = (finite().fold(f64::INFINITY, f64::min), finite().fold(0.0f64, f64::max));
    let (lo, hi) = if lo < hi { (lo, hi) } else { (1e-3, 1.0) };
    let mut files = vec![];
    for (map, name) in maps.iter().zip(&ZHANG_REPORT_FILES[1..]) {
        let log: Vec<f64> = map.iter().map(|v| (v / lo).log10()).collect();
        let png = heat_map_png(&log, MAP_CELLS[0], MAP_CELLS[1], (hi / lo).log10(), CELL_PX)?;
        files.push(write(dir, name, &png)?);
    }
    let html = page(z, size, d, &maps, [lo, hi]);
    files.insert(0, write(dir, ZHANG_REPORT_FILES[0], html.as_bytes())?);
    Ok(files)
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf> {
    let path = dir.join(name);
    std::fs::write(&path, bytes).map_err(|source| Error::Output { path: path.clone(), source })?;
    Ok(path)
}

/// The page: the numbers, then the maps with their scale and their centre and worst values.
fn page(z: &ZhangResult, size: [u32; 2], distance_mm: f64, maps: &[Vec<f64>; 2], scale: [f64; 2]) -> String {
    let names: &[&str] = match z.options.model {
        etl_core::model::DistortionModel::Paper => &["fx", "fy", "u0", "v0", "k1", "p1", "p2"],
        etl_core::model::DistortionModel::OpenCv => &["fx", "fy", "u0", "v0", "k1", "k2", "p1", "p2", "k3"],
    };
    let values = [z.fx, z.fy, z.u0, z.v0].into_iter().chain(z.distortion_coefficients().iter().copied());
    let rows: String = names
        .iter()
        .zip(values)
        .zip(&z.std)
        .map(|((n, v), s)| format!("<tr><td>{n}</td><td>{v:.6e}</td><td>{s:.3e}</td></tr>"))
        .collect();
    let summary = |m: &Vec<f64>| {
        let centre = m[(MAP_CELLS[1] / 2) * MAP_CELLS[0] + MAP_CELLS[0] / 2];
        let worst = m.iter().filter(|v| v.is_finite()).fold(0.0f64, |a, &b| a.max(b));
        let none = m.iter().filter(|v| !v.is_finite()).count();
        format!(
            "{centre:.4} px near the centre, {worst:.4} px at worst; {none} of {} cells do not unproject (grey)",
            m.len()
        )
    };
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Zhang calibration</title></head><body>\n\
         <h1>Zhang calibration ({model}, {w} x {h} px)</h1>\n<p>{views} views, RMS reprojection error {rms:.4} px, \
         {iters} iterations.</p>\n<table><tr><th>number</th><th>value</th><th>std</th></tr>{rows}</table>\n\
         <h2>Projection uncertainty</h2>\n<p>In mrcal's sense: the standard deviation, in its worst direction, of \
         where a calibration re-solved from new corner noise projects the point seen at a pixel (the point held in \
         the boards' frames). Colour on a logarithmic scale from {lo:.4} px (dark blue) to {hi:.4} px (yellow), one cell per \
         {cw} x {ch} px.</p>\n\
         <h3>At infinity (a direction)</h3>\n<p>{s0}</p><img src=\"{f1}\" alt=\"uncertainty at infinity\">\n\
         <h3>At the views' distance, {distance_mm:.1} mm</h3>\n<p>{s1}</p><img src=\"{f2}\" alt=\"uncertainty at \
         the views' distance\">\n</body></html>\n",
        model = esc(z.options.model.name()),
        lo = scale[0],
        hi = scale[1],
        w = size[0],
        h = size[1],
        views = z.views_used,
        rms = z.rms_px,
        iters = z.iterations,
        cw = size[0] as usize / MAP_CELLS[0],
        ch = size[1] as usize / MAP_CELLS[1],
        s0 = summary(&maps[0]),
        s1 = summary(&maps[1]),
        f1 = ZHANG_REPORT_FILES[1],
        f2 = ZHANG_REPORT_FILES[2],
    )
}
