//! The report's index.html: the figures written, each under its heading with what to look
//! for, the parameter table, the strongly correlated pairs, the views and the provenance.

use std::fmt::Write as _;
use std::path::PathBuf;

use etl_core::calib::jacobian::to_params;

use crate::data::{Data, Provenance, REPORT_FIGURES};
use crate::uncertainty::{
    correlation, curve_names, curve_std, curve_values, param_meaning, param_unit, strong_pairs, CurveSet, MAX_CURVES,
};

/// |r| above which a pair of numbers is listed as strongly correlated.
pub(crate) const STRONG_CORRELATION: f64 = 0.9;

/// A number with 6 significant digits, fixed or scientific as its size asks.
fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-3..1e5).contains(&a) {
        let digits = (5 - a.log10().floor().max(-3.0) as i32).clamp(0, 8) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.5e}")
    }
}

/// A standard deviation with 2 significant digits.
fn sd(v: f64) -> String {
    if v == 0.0 {
        "0 (held)".into()
    } else if (1e-3..1e5).contains(&v.abs()) {
        let digits = (1 - v.abs().log10().floor() as i32).clamp(0, 8) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.1e}")
    }
}

/// The time `unix_s` (seconds since 1970, UTC; `None`: the system clock now) as
/// yyyy-mm-dd hh:mm UTC (civil from days, H. Hinnant).
fn utc_text(unix_s: Option<i64>) -> String {
    let secs = unix_s.unwrap_or_else(|| {
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs()) as i64
    });
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02} {:02}:{:02} UTC", rem / 3600, rem % 3600 / 60)
}

pub(crate) fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The parameter table: name, meaning, unit, value, std, relative std, flag.
fn parameter_table(d: &Data) -> String {
    let x = to_params(&d.model);
    let layout = d.model.layout();
    let std = d.cal.std.to_params(&layout).unwrap_or([f64::NAN; etl_core::calib::params::MAX_PARAMS]);
    let mut t = String::from(
        "<table class=\"num\"><tr><th>name</th><th>meaning</th><th>unit</th><th>value</th><th>std</th>\
         <th>std / |value|</th><th>flag</th></tr>\n",
    );
    for i in 0..layout.len() {
        let flagged = std[i] > 0.0 && x[i].abs() < 2.0 * std[i];
        let rel = if x[i] != 0.0 && std[i] > 0.0 { sd(std[i] / x[i].abs()) } else { "-".into() };
        let _ = writeln!(
            t,
            "<tr{}><td><b>{}</b></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{rel}</td><td>{}</td></tr>",
            if flagged { " class=\"flag\"" } else { "" },
            layout.name(i),
            param_meaning(&layout, i),
            param_unit(&layout, i),
            num(x[i]),
            sd(std[i]),
            if flagged { "⚠ |value| &lt; 2 std: not determined" } else { "" }
        );
    }
    t + "</table>\n"
}

/// fx, fy and the distortion coefficients with their std at the three map currents.
fn curve_table(d: &Data) -> String {
    let mut t = String::from("<table class=\"num\"><tr><th>quantity</th><th>unit</th>");
    for e in d.map_currents {
        let _ = write!(t, "<th>at {e:.1} mA</th>");
    }
    t += "</tr>\n";
    let nan = [f64::NAN; MAX_CURVES];
    let at: Vec<(CurveSet, CurveSet)> = d
        .map_currents
        .iter()
        .map(|&e| (curve_values(&d.model, e), d.covariance.map_or(nan, |c| curve_std(&d.model, &c, e))))
        .collect();
    for (k, (name, unit)) in curve_names(&d.model).into_iter().enumerate() {
        let cells: String = at.iter().map(|(v, s)| format!("<td>{} &plusmn; {}</td>", num(v[k]), sd(s[k]))).collect();
        let _ = writeln!(t, "<tr><td><b>{name}</b></td><td>{unit}</td>{cells}</tr>");
    }
    t + "</table>\n"
}

/// What the calibration's covariance accounts for, in words (`"covariance_noise"`).
fn covariance_text(cal: &etl_formats::calibration::Calibration, recorded: bool) -> String {
    if !recorded {
        return "absent: no bands, no uncertainty map, no correlations".into();
    }
    let n = cal.model().map_or(0, |m| m.layout().len());
    let accounts = match &cal.covariance_noise {
        Some(c) => {
            let inputs = match (c.sigma_z_mm, c.sigma_e_ma) {
                (Some(z), Some(e)) => format!(", stage position {:.1} um and current {e} mA per view", z * 1000.0),
                _ => ", the recorded stage positions and currents taken as exact".into(),
            };
            format!("pixel noise {:.3} px{inputs}", c.sigma_px)
        }
        None if cal.estimator == "paper" => {
            "the pixel noise alone (written before covariance_noise was recorded)".into()
        }
        None => "not recorded in the file".into(),
    };
    format!("recorded ({n} x {n}); accounts for {accounts}")
}

/// What each figure shows and what to look for.
fn caption(stem: &str, d: &Data) -> String {
    match stem {
        "focal" => "Top: the calibrated fx(E) and fy(E) (lines) and each view's own estimate (dots: the focal lengths \
             refitted to that view alone). Bottom: the same dots minus the curve, with the curve's own uncertainty \
             as bands of one (dark) and three (light) standard deviations. The bands are the uncertainty of the \
             curve, not of a single view: single views scatter more."
            .into(),
        "distortion" => format!(
            "Top: {} (each a quadratic in 1/f, Eq. 18; the {} distortion model) against the current (lines) and \
             each view's own estimate (dots). Bottom: the dots minus the curve, with the curve's uncertainty as \
             bands of one (dark) and three (light) standard deviations. A band as wide as the curve's values means \
             that coefficient is not determined by these views.",
            d.model.distortion_model().coefficient_names().join(", "),
            d.model.distortion_model().name()
        ),
        "projection_std" => format!(
            "The standard deviation (longest axis of the 1σ ellipse) of where the calibrated model puts a point, due \
             to the uncertainty of the model's {} numbers (J C Jᵀ), over the image at the ends and the middle of the \
             calibrated range; one colour scale for the three. The points are at {}. Large values at the edges \
             call for corners there (see the coverage map).",
            d.model.layout().len(),
            d.depth_source
        ),
        "coverage" => "Every detected corner at its place in the image, one panel per current (views within 0.5 mA \
             together), coloured by view. Empty regions are where the model is extrapolated."
            .into(),
        "residual_map" => "Each corner's residual (model − observed) as a vector, magnified (the black bar is the \
             overall RMS), coloured by view. Systematic patterns (all arrows alike in a region) mean a model error; \
             random directions mean noise."
            .into(),
        "view_rms" => "The RMS residual of each view (same colours as the residual map); the dashed line is the \
             RMS of all views. A view far above the line is worth checking (blur, wrong current, moved board)."
            .into(),
        "residual_hist" => "Histogram of the u and v components of the residuals together: near-Gaussian around \
             zero when the model fits."
            .into(),
        "distortion_field" => "Where distortion moves an ideal pixel (Eq. 17): arrows from the ideal position \
             (dots) to the distorted one, magnified by the same factor in the three panels; the red cross is the \
             principal point."
            .into(),
        "correlation" => {
            let layout = d.model.layout();
            format!(
                "Correlation r_ij = C_ij / sqrt(C_ii C_jj) of the model's {} numbers (blue −1, white 0, red +1); \
                 the lines separate rotation, translation, kf_x, kf_y, principal point and a1..a{}. Strongly \
                 correlated pairs are listed below.",
                layout.len(),
                layout.distortion_a().len
            )
        }
        _ => String::new(),
    }
}

fn figures_html(d: &Data, files: &[PathBuf]) -> (String, String) {
    let written = |name: String| files.iter().any(|f| f.file_name().is_some_and(|n| n.to_string_lossy() == name));
    let (mut toc, mut body) = (String::new(), String::new());
    for (stem, title) in REPORT_FIGURES {
        if !written(format!("{stem}.svg")) {
            continue;
        }
        let _ = writeln!(toc, "<li><a href=\"#{stem}\">{title}</a></li>");
        // Heat maps are shown as PNG: browsers draw seams between adjacent SVG cells.
        let shown = if matches!(stem, "projection_std" | "correlation") { "png" } else { "svg" };
        let _ = writeln!(
            body,
            "<h2 id=\"{stem}\">{title}</h2>\n<figure><a href=\"{stem}.{shown}\"><img src=\"{stem}.{shown}\" alt=\"{title}\"></a>\
             <figcaption>{} <span class=\"files\">Files: <a href=\"{stem}.svg\">SVG</a>, <a href=\"{stem}.png\">PNG</a>.\
             </span></figcaption></figure>",
            caption(stem, d)
        );
        if stem == "correlation" {
            body += &correlated_pairs(d);
        }
    }
    (toc, body)
}

fn correlated_pairs(d: &Data) -> String {
    let Some(c) = d.covariance else { return String::new() };
    let layout = d.model.layout();
    let pairs = strong_pairs(&correlation(&c), layout.len(), STRONG_CORRELATION);
    if pairs.is_empty() {
        return format!("<p>No pair of numbers has |r| &gt; {STRONG_CORRELATION}.</p>\n");
    }
    let rows: String = pairs
        .iter()
        .map(|(i, j, r)| format!("<li><b>{}</b> &amp; <b>{}</b>: {r:+.4}</li>", layout.name(*i), layout.name(*j)))
        .collect();
    format!(
        "<p>{} pairs with |r| &gt; {STRONG_CORRELATION}: their numbers are not separately determined by these views \
         (only a combination is); the curves and the projection are, as the bands and the map show.</p>\n\
         <ul class=\"pairs\">{rows}</ul>\n",
        pairs.len()
    )
}

fn views_table(d: &Data) -> String {
    let rows: String = d
        .cal
        .views
        .iter()
        .enumerate()
        .map(|(k, v)| {
            format!(
                "<tr><td>{k}</td><td>{:.2}</td><td>{}</td><td>{:.3}</td><td>{:.2}</td><td>{:.2}</td><td>{:.4}</td><td>{:.3}</td></tr>\n",
                v.setting(), v.points, v.rms_px, v.fx_px, v.fy_px, v.dz_mm, v.setting_correction()
            )
        })
        .collect();
    let (name, unit) = crate::data::setting_axis(&d.cal);
    format!(
        "<p>dZ, dE: the errors-in-variables corrections of the view's stage position and setting (0 for the paper's \
         estimator, which takes both as exact).</p>\n<table class=\"num\"><tr><th>view</th><th>{name} ({unit})</th>\
         <th>points</th><th>RMS (px)</th><th>own fx (px)</th><th>own fy (px)</th><th>dZ (mm)</th><th>dE ({unit})</th></tr>\n\
         {rows}</table>\n"
    )
}

fn provenance_html(d: &Data, p: &Provenance) -> String {
    let inputs: String = if p.inputs.is_empty() {
        "<li>not given by the caller</li>".into()
    } else {
        p.inputs.iter().map(|(role, at)| format!("<li>{}: <code>{}</code></li>", esc(role), esc(at))).collect()
    };
    let thermal = d.cal.thermal.as_ref().map_or("none recorded".to_string(), |t| {
        t.source.clone().unwrap_or_else(|| "recorded, source not named".into())
    });
    let priors = p.priors.clone().unwrap_or_else(|| {
        "not recorded in the calibration file (see the options the calibration was run with)".into()
    });
    format!(
        "<table><tr><td>etlcal version</td><td>{}</td></tr><tr><td>report written</td><td>{}</td></tr>\
         <tr><td>inputs</td><td><ul>{inputs}</ul></td></tr><tr><td>estimator</td><td>{}</td></tr>\
         <tr><td>priors</td><td>{}</td></tr><tr><td>thermal compensation</td><td>{}</td></tr>\
         <tr><td>bundle adjustment</td><td>{} iterations, RMS {:.4} px (before: {:.4} px)</td></tr>\
         <tr><td>covariance</td><td>{}</td></tr></table>\n",
        env!("CARGO_PKG_VERSION"),
        utc_text(p.written_unix_s),
        esc(&d.cal.estimator),
        esc(&priors),
        esc(&thermal),
        d.cal.iterations,
        d.cal.rms_reprojection_px,
        d.cal.initial_rms_px,
        esc(&covariance_text(&d.cal, d.covariance.is_some()))
    )
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1300px;margin:auto;padding:0 1em;line-height:1.4}\
    td,th{padding:2px 10px;border-bottom:1px solid #ddd;text-align:left;vertical-align:top}\
    table.num td{font-variant-numeric:tabular-nums}tr.flag{background:#fff1c2}\
    figure{margin:0 0 1.5em 0}figure img{max-width:100%;border:1px solid #eee}\
    figcaption{color:#333;max-width:1000px}.files{color:#777}.note{background:#f3f3f3;padding:.5em 1em}\
    ul.pairs{columns:4;max-width:1000px}tr.chosen{background:#e3f2e1}";

/// The corners the calibration left out of its final solve (empty when none): the bundle
/// adjustment's (of the observations' views) and Zhang's at the per-setting baseline's
/// settings (of their setting views).
fn outliers_table(d: &Data) -> String {
    let c = &d.cal;
    let lists = [("view", &c.outliers), ("setting view", &c.setting_outliers)];
    let count: usize = lists.iter().map(|(_, l)| l.len()).sum();
    if count == 0 {
        return String::new();
    }
    let rows: String = lists
        .iter()
        .flat_map(|(kind, list)| {
            list.iter().map(move |o| {
                format!("<tr><td>{kind} {}</td><td>{}</td><td>{:.2}</td></tr>\n", o.view, o.point, o.residual_px)
            })
        })
        .collect();
    format!(
        "<h2 id=\"outliers\">Outliers</h2>\n<p>{count} corners left out of the final solve (not in the residual plots).</p>\n\
         <table class=\"num\"><tr><th>view</th><th>point</th><th>residual (px)</th></tr>\n{rows}</table>\n"
    )
}

/// The comparison `calibrate --distortion auto` / `--focal-degree auto` chose the model
/// by (the file's `"model_selection"`), or nothing when the model was given.
fn model_selection_html(c: &etl_formats::Calibration) -> String {
    let Some(sel) = &c.model_selection else { return String::new() };
    let cell = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.4}"));
    let rows: String = sel
        .candidates
        .iter()
        .map(|r| {
            let note = match (&r.error, r.chosen) {
                (Some(e), _) => format!("not fitted: {}", esc(e)),
                (None, true) => "<b>chosen</b>".into(),
                (None, false) => String::new(),
            };
            format!(
                "<tr{}><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{note}</td></tr>\n",
                if r.chosen { " class=\"chosen\"" } else { "" },
                esc(&r.distortion_model),
                r.focal_degree,
                r.parameters,
                cell(r.fit_rms_px),
                cell(r.prediction_rms_px),
                cell(r.excess_mse_px2),
                cell(r.excess_se_px2),
            )
        })
        .collect();
    format!(
        "<h2 id=\"model-selection\">Model selection</h2>\n<p>The model was chosen by the data: each candidate was \
         fitted to all views (fit RMS) and, {}, to all views but one, then asked to predict the view left out from \
         its world points, recorded current and stage position (prediction RMS: the error in the estimator's noise \
         model, px). The chosen model is the simplest whose held-out mean squared error exceeds the best's by no \
         more than one standard error of that excess (the larger of its spread over the views and its value from the \
         views' noise model; rule: {}).</p>\n\
         <table class=\"num\"><tr><th>distortion</th><th>focal degree</th><th>numbers</th><th>fit RMS (px)</th>\
         <th>prediction RMS (px)</th><th>excess MSE (px²)</th><th>its std error (px²)</th><th></th></tr>\n{rows}\
         </table>\n",
        esc(&sel.method),
        esc(&sel.rule)
    )
}

/// The whole index.html.
pub(crate) fn index(d: &Data, text: bool, p: &Provenance, files: &[PathBuf]) -> String {
    let c = &d.cal;
    let (toc, figures) = figures_html(d, files);
    let mut notes = String::new();
    if !text {
        notes += "<p class=\"note\">No TrueType font was found: the plots carry no text (set ETLCAL_FONT).</p>";
    }
    if d.covariance.is_none() {
        notes += "<p class=\"note\">This calibration has no covariance (written before it was recorded): no \
                  uncertainty bands, projection-uncertainty map or correlations. Calibrate again to get them.</p>";
    }
    if d.views.is_empty() {
        notes += "<p class=\"note\">No observations were given (<code>--observations</code>): no coverage, \
                  residual or per-view figures.</p>";
    }
    if !c.warnings.is_empty() {
        let items: String = c.warnings.iter().map(|w| format!("<li>{}</li>", esc(w))).collect();
        notes += &format!("<h2 id=\"warnings\">Warnings</h2><ul>{items}</ul>\n");
    }
    let flagged = parameter_table(d).matches("class=\"flag\"").count();
    let setting_in = match c.setting_kind() {
        etl_formats::SettingKind::Current => "E_com in mA",
        etl_formats::SettingKind::FocalPower => "the commanded focal power in dpt",
    };
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>etlcal calibration report</title>\
         <style>{STYLE}</style></head><body>\n<h1>etlcal calibration report</h1>\n{notes}\n\
         <p>Estimator <b>{}</b>, {} views, {} {:.1} .. {:.1} {}, RMS reprojection error <b>{:.4} px</b>; \
         model: {} distortion, focal degree {} ({} numbers), {flagged} of them flagged as not determined \
         (|value| &lt; 2 std).</p>\n{}\
         <ul><li><a href=\"#parameters\">Parameters</a></li>{toc}<li><a href=\"#views\">Views</a></li>\
         <li><a href=\"#provenance\">Provenance</a></li></ul>\n\
         <h2 id=\"parameters\">Parameters (value and one standard deviation)</h2>\n\
         <p>The model (the paper's Eq. 16-18): fx(E) = kf0x + kf1x E + kf2x E² + kf3x E³ with E = {setting_in} (fy(E) \
         likewise); the distortion coefficients of Eq. 17 are k1 = a1 w² + a2 w + a3, p1 = a4 w² + a5 w + a6, \
         p2 = a7 w² + a8 w + a9 with w = 2 / (fx(E) + fy(E)) in 1/px (Eq. 18).</p>\n\
         <p>Std from the covariance of the bundle adjustment (first order). Rows flagged ⚠ have |value| &lt; 2 std: \
         the views do not determine that number (it is consistent with zero). That alone is no fault when the \
         curves below are well determined (a flagged number is usually strongly correlated with another); if a \
         curve's band or the projection-uncertainty map is too wide, add views: more currents, the board nearer \
         the image corners.</p>\n{}\n\
         <h3>The curves at the ends and the middle of the range</h3>\n{}\n{figures}\n\
         <h2 id=\"views\">Views</h2>\n{}\n{}<h2 id=\"provenance\">Provenance</h2>\n{}</body></html>\n",
        esc(&c.estimator),
        c.views.len().max(d.views.len()),
        match c.setting_kind() {
            etl_formats::SettingKind::Current => "E_com",
            etl_formats::SettingKind::FocalPower => "setting: commanded focal power",
        },
        c.setting_range()[0],
        c.setting_range()[1],
        c.setting_kind().unit(),
        c.rms_reprojection_px,
        d.model.distortion_model().name(),
        d.model.focal_degree(),
        d.model.layout().len(),
        model_selection_html(c),
        parameter_table(d),
        curve_table(d),
        views_table(d),
        outliers_table(d),
        provenance_html(d, p),
    )
}
