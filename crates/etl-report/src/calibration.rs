//! The calibration report: PNG and SVG plots and an `index.html` that shows them with
//! the numbers.
//!
//! - `focal`: fx(E) and fy(E) over the calibrated range, with every view's own estimate
//!   (fx, fy refitted to that view alone; [`etl_calib::pipeline::view_focal`]);
//! - `distortion`: k1, p1, p2 against the current (Eq. 18; the paper's Fig. 11), with
//!   every view's own Eq. 23 estimate when observations are given;
//! - `residual_map`: the reprojection residual of every point as a vector at its place in
//!   the image (magnified);
//! - `residual_hist`: the histogram of the residual components.
//!
//! The residual plots need the observations. Text needs a TrueType font: the first of
//! `$ETLCAL_FONT` and a few usual system fonts that exists is used; without one the plots
//! are drawn without text and index.html carries the labels.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use etl_core::calib::distortion_init::view_distortion;
use etl_core::calib::View;
use etl_core::model::CameraModel;
use etl_formats::calibration::ThermalRef;
use plotters::coord::Shift;
use plotters::prelude::*;

use etl_formats::calibration::Calibration;
use etl_formats::observations::Observations;
use etl_formats::write_atomic;
use etl_formats::{Error, Result};

const SIZE: (u32, u32) = (900, 600);

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

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// One residual: where (observed pixel) and the residual (model - observed), px.
#[derive(Debug, Clone, Copy)]
struct Residual {
    at: [f64; 2],
    d: [f64; 2],
}

struct Data {
    cal: Calibration,
    model: CameraModel,
    /// (E, fx, fy) of every view's own estimate.
    view_focal: Vec<(f64, f64, f64)>,
    /// (E, k1, p1, p2) of every view's own estimate.
    view_dist: Vec<(f64, [f64; 3])>,
    residuals: Vec<Residual>,
}

fn series<F: Fn(f64) -> f64>(range: [f64; 2], f: F) -> Vec<(f64, f64)> {
    (0..=200).map(|k| range[0] + (range[1] - range[0]) * k as f64 / 200.0).map(|e| (e, f(e))).collect()
}

fn bounds(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(1e-12 * hi.abs().max(1e-300));
    (lo - pad, hi + pad)
}

fn draw_focal<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let r = d.cal.e_com_range_ma;
    let fx = series(r, |e| d.model.focal_lengths(e).0);
    let fy = series(r, |e| d.model.focal_lengths(e).1);
    let (ylo, yhi) = bounds(
        fx.iter().chain(&fy).map(|p| p.1).chain(d.view_focal.iter().flat_map(|v| [v.1, v.2]).filter(|v| *v > 0.0)),
    );
    let mut b = ChartBuilder::on(root);
    b.margin(15);
    if text {
        b.caption("fx(E), fy(E): curves and each view's own estimate", ("sans-serif", 22))
            .x_label_area_size(45)
            .y_label_area_size(70);
    }
    let mut chart = b.build_cartesian_2d(r[0] - 5.0..r[1] + 5.0, ylo..yhi)?;
    if text {
        chart.configure_mesh().x_desc("E_com (mA)").y_desc("focal length (px)").draw()?;
    }
    chart
        .draw_series(LineSeries::new(fx.clone(), BLUE.stroke_width(2)))?
        .label("fx(E)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(fy.clone(), RED.stroke_width(2)))?
        .label("fy(E)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    chart.draw_series(d.view_focal.iter().filter(|v| v.1 > 0.0).map(|v| Circle::new((v.0, v.1), 4, BLUE.filled())))?;
    chart.draw_series(
        d.view_focal.iter().filter(|v| v.2 > 0.0).map(|v| Cross::new((v.0, v.2), 5, RED.stroke_width(2))),
    )?;
    if text {
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    }
    root.present()?;
    Ok(())
}

fn draw_distortion<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let panels = root.split_evenly((1, 3));
    let names = ["k1 (1/px^2)", "p1 (1/px)", "p2 (1/px)"];
    let colours = [BLUE, RED, GREEN];
    let r = d.cal.e_com_range_ma;
    for (k, panel) in panels.iter().enumerate() {
        let curve = series(r, |e| d.model.distortion(e).map_or(f64::NAN, |dd| [dd.k1, dd.p1, dd.p2][k]));
        // Plot in scaled units so that tick labels stay short.
        let scale = if k == 0 { 1e9 } else { 1e6 };
        let curve: Vec<(f64, f64)> = curve.into_iter().map(|(e, v)| (e, v * scale)).collect();
        let pts: Vec<(f64, f64)> = d.view_dist.iter().map(|(e, v)| (*e, v[k] * scale)).collect();
        let (lo, hi) = bounds(curve.iter().chain(&pts).map(|p| p.1));
        let mut b = ChartBuilder::on(panel);
        b.margin(10);
        if text {
            let cap = format!("{} x {}", names[k], if k == 0 { "1e9" } else { "1e6" });
            b.caption(cap, ("sans-serif", 16)).x_label_area_size(35).y_label_area_size(50);
        }
        let mut chart = b.build_cartesian_2d(r[0] - 5.0..r[1] + 5.0, lo..hi)?;
        if text {
            chart.configure_mesh().x_desc("E_com (mA)").x_labels(5).draw()?;
        }
        chart.draw_series(LineSeries::new(curve, colours[k].stroke_width(2)))?;
        chart.draw_series(pts.iter().map(|p| Circle::new(*p, 3, colours[k].filled())))?;
    }
    root.present()?;
    Ok(())
}

fn draw_residual_map<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let [w, h] = d.cal.image_size;
    let rms = d.cal.rms_reprojection_px.max(1e-6);
    // Arrows of RMS length become 1.5 % of the image width.
    let gain = 0.015 * w as f64 / rms;
    let mut b = ChartBuilder::on(root);
    b.margin(15);
    if text {
        b.caption(format!("residuals (model - observed) x {gain:.0}"), ("sans-serif", 22))
            .x_label_area_size(40)
            .y_label_area_size(60);
    }
    // Image rows grow downwards.
    let mut chart = b.build_cartesian_2d(0.0..w as f64, h as f64..0.0)?;
    if text {
        chart.configure_mesh().x_desc("u (px)").y_desc("v (px)").draw()?;
    }
    chart.draw_series(d.residuals.iter().map(|r| {
        PathElement::new(vec![(r.at[0], r.at[1]), (r.at[0] + gain * r.d[0], r.at[1] + gain * r.d[1])], BLUE)
    }))?;
    chart.draw_series(d.residuals.iter().map(|r| Circle::new((r.at[0], r.at[1]), 1, BLACK.filled())))?;
    root.present()?;
    Ok(())
}

fn draw_histogram<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let vals: Vec<f64> = d.residuals.iter().flat_map(|r| r.d).collect();
    let m = vals.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(1e-6);
    let bins = 41usize;
    let width = 2.0 * m / bins as f64;
    let mut counts = vec![0u32; bins];
    for v in &vals {
        let k = (((v + m) / width) as usize).min(bins - 1);
        counts[k] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1);
    let mut b = ChartBuilder::on(root);
    b.margin(15);
    if text {
        b.caption("residual components u, v (px)", ("sans-serif", 22)).x_label_area_size(40).y_label_area_size(60);
    }
    let mut chart = b.build_cartesian_2d(-m..m, 0u32..top + top / 10 + 1)?;
    if text {
        chart.configure_mesh().x_desc("residual (px)").y_desc("count").draw()?;
    }
    chart.draw_series(counts.iter().enumerate().map(|(k, &c)| {
        let x0 = -m + k as f64 * width;
        Rectangle::new([(x0, 0), (x0 + width, c)], BLUE.mix(0.6).filled())
    }))?;
    root.present()?;
    Ok(())
}

/// Draws `$draw` as SVG and PNG into `$dir/$name.{svg,png}` (atomic writes).
macro_rules! plot {
    ($dir:expr, $name:expr, $d:expr, $text:expr, $draw:ident, $files:expr) => {{
        let name: &str = $name;
        let fail = |e: Box<dyn std::error::Error>| Error::InvalidInput(format!("plot {name}: {e}"));
        let mut s = String::new();
        {
            let root = SVGBackend::with_string(&mut s, SIZE).into_drawing_area();
            $draw(&root, $d, $text).map_err(fail)?;
        }
        let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
            $draw(&root, $d, $text).map_err(fail)?;
        }
        finish_plot($dir, name, buf, &s, $files)?;
    }};
}

fn finish_plot(dir: &Path, name: &str, buf: Vec<u8>, svg: &str, files: &mut Vec<PathBuf>) -> Result<()> {
    let img = image::RgbImage::from_raw(SIZE.0, SIZE.1, buf)
        .ok_or_else(|| Error::InvalidInput(format!("plot {name}: bitmap size mismatch")))?;
    let mut bytes = std::io::Cursor::new(vec![]);
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| Error::InvalidInput(format!("plot {name}: PNG encoding: {e}")))?;
    let (p, q) = (dir.join(format!("{name}.png")), dir.join(format!("{name}.svg")));
    write_atomic(&p, bytes.get_ref())?;
    write_atomic(&q, svg.as_bytes())?;
    files.push(p);
    files.push(q);
    Ok(())
}

fn gather(cal: &Calibration, obs: Option<&Observations>, thermal: Option<&ThermalRef>) -> Result<Data> {
    let model = cal.model();
    let mut view_focal: Vec<(f64, f64, f64)> = cal.views.iter().map(|v| (v.e_com_ma, v.fx_px, v.fy_px)).collect();
    let mut view_dist = vec![];
    let mut residuals = vec![];
    // The per-setting baseline has no stage frame (R, T): the ETL views cannot be
    // reprojected through it.
    if let Some(obs) = obs.filter(|_| cal.estimator != "per-setting") {
        obs.validate()?;
        let e_com = obs.e_com_ma(thermal)?;
        let pts = obs.core_points();
        let recompute = view_focal.len() != obs.views.len() || view_focal.iter().all(|v| v.1 == 0.0);
        if recompute {
            view_focal.clear();
        }
        for (k, (p, &e)) in pts.iter().zip(&e_com).enumerate() {
            let view = View { e_com_ma: e, points: p };
            // The errors-in-variables corrections of the calibration, when it has them.
            let (dz, de) = cal.views.get(k).map_or((0.0, 0.0), |v| (v.dz_mm, v.de_ma));
            let e = e + de;
            if recompute {
                let (fx, fy) = etl_calib::pipeline::view_focal(&model, &view, dz).unwrap_or((0.0, 0.0));
                view_focal.push((e, fx, fy));
            }
            // The points of the final solve: the calibration's outliers (listed in their own
            // table) would swamp the residual plots and the view's distortion estimate.
            let outlier = |i: usize| cal.outliers.iter().any(|o| o.view == k && o.point == i);
            let shifted: Vec<etl_core::calib::Point> = p
                .iter()
                .enumerate()
                .filter(|(i, _)| !outlier(*i))
                .map(|(_, q)| etl_core::calib::Point {
                    world_mm: [q.world_mm[0], q.world_mm[1], q.world_mm[2] + dz],
                    pixel: q.pixel,
                })
                .collect();
            if let Ok(dd) = view_distortion(&model, &View { e_com_ma: e, points: &shifted }) {
                view_dist.push((e, [dd.k1, dd.p1, dd.p2]));
            }
            for q in &shifted {
                if let Ok(m) = model.project(q.world_mm, e) {
                    residuals.push(Residual { at: q.pixel, d: [m[0] - q.pixel[0], m[1] - q.pixel[1]] });
                }
            }
        }
    }
    Ok(Data { cal: cal.clone(), model, view_focal, view_dist, residuals })
}

fn html(d: &Data, text: bool) -> String {
    let c = &d.cal;
    let row = |name: &str, v: &[f64], s: &[f64]| {
        let cells: Vec<String> = v.iter().zip(s).map(|(a, b)| format!("{a:.6e} &plusmn; {b:.1e}")).collect();
        format!("<tr><td>{name}</td><td>{}</td></tr>\n", cells.join("<br>"))
    };
    let mut t = String::new();
    t += &row("rotation_rodrigues (rad)", &c.rotation_rodrigues, &c.std.rotation_rodrigues);
    t += &row("translation_mm", &c.translation_mm, &c.std.translation_mm);
    t += &row("kf_x", &c.kf_x, &c.std.kf_x);
    t += &row("kf_y", &c.kf_y, &c.std.kf_y);
    t += &row("principal_point (px)", &c.principal_point, &c.std.principal_point);
    t += &row("distortion_a", &c.distortion_a, &c.std.distortion_a);
    let views: String = c
        .views
        .iter()
        .map(|v| {
            format!(
                "<tr><td>{:.2}</td><td>{}</td><td>{:.3}</td><td>{:.2}</td><td>{:.2}</td><td>{:.4}</td><td>{:.3}</td></tr>\n",
                v.e_com_ma, v.points, v.rms_px, v.fx_px, v.fy_px, v.dz_mm, v.de_ma
            )
        })
        .collect();
    let residual_note = if d.residuals.is_empty() {
        "<p>No observations were given (<code>--observations</code>): no residual plots.</p>".to_string()
    } else {
        format!(
            "<h2>Residuals</h2><p>{} points. Left: each point's residual (model &minus; observed) as a vector, magnified; \
             right: histogram of the u and v components.</p><img src=\"residual_map.svg\" width=\"49%\"> \
             <img src=\"residual_hist.svg\" width=\"49%\">",
            d.residuals.len()
        )
    };
    let esc = |t: &str| t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;");
    let warnings: String = if c.warnings.is_empty() {
        String::new()
    } else {
        let items: String = c.warnings.iter().map(|w| format!("<li>{}</li>", esc(w))).collect();
        format!("<h2>Warnings</h2><ul>{items}</ul>\n")
    };
    let outliers: String = if c.outliers.is_empty() {
        String::new()
    } else {
        let rows: String = c
            .outliers
            .iter()
            .map(|o| format!("<tr><td>{}</td><td>{}</td><td>{:.2}</td></tr>\n", o.view, o.point, o.residual_px))
            .collect();
        format!(
            "<h2>Outliers</h2><p>{} corners left out of the final solve (not in the residual plots).</p>\
             <table><tr><th>view</th><th>point</th><th>residual (px)</th></tr>\n{rows}</table>\n",
            c.outliers.len()
        )
    };
    let text_note =
        if text { "" } else { "<p>(No TrueType font was found: the plots carry no text; set ETLCAL_FONT.)</p>" };
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>etlcal calibration report</title>\
         <style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}td{{padding:2px 10px;border-bottom:1px solid #ddd}}</style>\
         </head><body>\n<h1>etlcal calibration report</h1>{text_note}\n\
         <p>Estimator <b>{}</b>, {} views, E_com {:.1} .. {:.1} mA, RMS reprojection error <b>{:.4} px</b> \
         (before bundle adjustment {:.4} px), {} iterations.</p>\n{warnings}\
         <h2>Focal lengths</h2><p>fx(E) (blue) and fy(E) (red) with every view's own estimate (dots: fx, crosses: fy).</p>\
         <img src=\"focal.svg\" width=\"80%\">\n\
         <h2>Distortion</h2><p>k1, p1, p2 against the current (Eq. 18; the paper's Fig. 11), with each view's own Eq. 23 estimate.</p>\
         <img src=\"distortion.svg\" width=\"100%\">\n{residual_note}\n\
         <h2>Parameters (value &plusmn; one standard deviation)</h2><table>\n{t}</table>\n\
         <h2>Views</h2><table><tr><th>E_com (mA)</th><th>points</th><th>RMS (px)</th><th>own fx</th><th>own fy</th>\
         <th>dZ (mm)</th><th>dE (mA)</th></tr>\n{views}</table>\n{outliers}</body></html>\n",
        c.estimator,
        c.views.len(),
        c.e_com_range_ma[0],
        c.e_com_range_ma[1],
        c.rms_reprojection_px,
        c.initial_rms_px,
        c.iterations
    )
}

/// Writes the report of `cal` (with residual plots when `obs` is given; E_com of views
/// without one through `thermal`) into the existing directory `dir`.
///
/// Errors: `dir` missing; observations that fail validation; a plot that cannot be drawn.
pub fn write_report(
    cal: &Calibration,
    obs: Option<&Observations>,
    thermal: Option<&ThermalRef>,
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
    plot!(dir, "focal", &d, text, draw_focal, &mut files);
    plot!(dir, "distortion", &d, text, draw_distortion, &mut files);
    if !d.residuals.is_empty() {
        plot!(dir, "residual_map", &d, text, draw_residual_map, &mut files);
        plot!(dir, "residual_hist", &d, text, draw_histogram, &mut files);
    }
    let index = dir.join("index.html");
    write_atomic(&index, html(&d, text).as_bytes())?;
    files.push(index);
    Ok(ReportFiles { files, text })
}
