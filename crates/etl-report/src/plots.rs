//! The figures of the calibration report, each drawn on any plotters backend (SVG, PNG).

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::data::Data;
use crate::figure::{tick, Canvas, DrawResult, PALETTE};
use crate::uncertainty::{correlation, curve_names, curve_std, curve_values, CurveSet, MAX_CURVES};

/// Colour of view `k` of `n`: hues spread around the wheel, so that neighbouring views
/// differ and every view keeps its colour across the figures.
pub(crate) fn view_colour(k: usize, n: usize) -> RGBColor {
    // Steps of 7/n of the wheel (n not a multiple of 7) keep consecutive views apart.
    let step = if n % 7 == 0 { 1 } else { 7 };
    let hue = ((k * step) % n.max(1)) as f64 / n.max(1) as f64;
    let (r, g, b) = HSLColor(hue, 0.8, 0.42).rgb();
    RGBColor(r, g, b)
}

/// The viridis-like sequential colour map, t in [0, 1].
pub(crate) fn sequential(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let x = t * 4.0;
    let k = (x.floor() as usize).min(3);
    let f = x - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |p: f64, q: f64| (p + f * (q - p)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// The diverging blue-white-red map, r in [-1, 1].
pub(crate) fn diverging(r: f64) -> RGBColor {
    let r = if r.is_finite() { r.clamp(-1.0, 1.0) } else { 0.0 };
    let (c, t) = if r < 0.0 { ((33.0, 102.0, 172.0), -r) } else { ((178.0, 24.0, 43.0), r) };
    let mix = |p: f64| (255.0 + t * (p - 255.0)).round() as u8;
    RGBColor(mix(c.0), mix(c.1), mix(c.2))
}

/// A pixel coordinate as a tick label: whole pixels.
fn px(v: &f64) -> String {
    format!("{v:.0}")
}

fn range_of(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(1e-9 * hi.abs().max(lo.abs()).max(1e-300));
    (lo - pad, hi + pad)
}

/// The frame of a chart on `area`: `margin` px around it, and when text is drawn its
/// caption (`caption.0` in sans-serif of size `caption.1`) and room for the axis labels
/// (`label_px`: below the plot, left of it).
fn panel_frame<'a, DB: Canvas>(
    area: &'a DrawingArea<DB, Shift>,
    margin: u32,
    caption: (impl AsRef<str>, u32),
    [below, left]: [u32; 2],
    text: bool,
) -> ChartBuilder<'a, 'static, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin(margin);
    if text {
        b.caption(caption.0, ("sans-serif", caption.1)).x_label_area_size(below).y_label_area_size(left);
    }
    b
}

/// The axes of a panel over the image (u to the right, v down, px; five labels each and no
/// grid lines over the picture), when text is drawn.
fn draw_image_axes<DB: Canvas>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    text: bool,
) -> DrawResult {
    if text {
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("u (px)")
            .y_desc("v (px)")
            .x_labels(5)
            .y_labels(5)
            .x_label_formatter(&px)
            .y_label_formatter(&px)
            .draw()?;
    }
    Ok(())
}

/// A curve against the current with its 1- and 3-sigma bands and points.
struct BandPanel {
    title: String,
    y_label: String,
    /// (E, value, std).
    curve: Vec<(f64, f64, f64)>,
    points: Vec<(f64, f64)>,
    colour: RGBColor,
    /// The calibration's setting: its name and unit ([`crate::data::setting_axis`]).
    setting: (&'static str, &'static str),
}

fn draw_band<DB: Canvas>(area: &DrawingArea<DB, Shift>, p: &BandPanel, text: bool) -> DrawResult {
    let band = |k: f64| p.curve.iter().flat_map(move |c| [c.1 - k * c.2, c.1 + k * c.2]);
    let (lo, hi) = range_of(band(3.0).chain(p.points.iter().map(|q| q.1)));
    let (e0, e1) = (p.curve.first().map_or(0.0, |c| c.0), p.curve.last().map_or(1.0, |c| c.0));
    let mut b = panel_frame(area, 12, (&p.title, 17), [42, 78], text);
    // 5 mA either side (the run-time margin of a current), 0.25 dpt (that of a power).
    let (name, unit) = p.setting;
    let pad = if unit == "dpt" { etl_core::runtime::FOCAL_POWER_MARGIN_DPT } else { 5.0 };
    let mut chart = b.build_cartesian_2d(e0 - pad..e1 + pad, lo..hi)?;
    let x_desc = format!("{name} ({unit})");
    if text {
        chart
            .configure_mesh()
            .x_desc(x_desc.as_str())
            .y_desc(p.y_label.as_str())
            .x_labels(6)
            .y_labels(6)
            .x_label_formatter(&|v| tick(*v, e1 - e0 + 10.0))
            .y_label_formatter(&|v| tick(*v, hi - lo))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()?;
    }
    for (k, alpha) in [(3.0, 0.15), (1.0, 0.35)] {
        let mut poly: Vec<(f64, f64)> = p.curve.iter().map(|c| (c.0, c.1 + k * c.2)).collect();
        poly.extend(p.curve.iter().rev().map(|c| (c.0, c.1 - k * c.2)));
        chart.draw_series(std::iter::once(Polygon::new(poly, p.colour.mix(alpha).filled())))?;
    }
    chart.draw_series(LineSeries::new(p.curve.iter().map(|c| (c.0, c.1)), p.colour.stroke_width(2)))?;
    chart.draw_series(p.points.iter().map(|q| Circle::new(*q, 4, BLACK.filled())))?;
    Ok(())
}

/// (E, values, stds) of the curves ([`curve_names`]) at 101 currents over the calibrated
/// range; zero std without a covariance.
fn curves(d: &Data) -> Vec<(f64, CurveSet, CurveSet)> {
    let r = d.cal.setting_range();
    (0..=100)
        .map(|k| r[0] + (r[1] - r[0]) * k as f64 / 100.0)
        .map(|e| {
            let zero = [0.0; MAX_CURVES];
            (e, curve_values(&d.model, e), d.covariance.map_or(zero, |c| curve_std(&d.model, &c, e)))
        })
        .collect()
}

/// One curve of [`curves`] drawn as two band panels: the curve with each view's own
/// estimate (top), and the same minus the curve (bottom: bands too narrow to see on top
/// show there).
struct CurvePanels<'a> {
    /// Index of the curve ([`curve_names`]).
    index: usize,
    /// The curve's name and its unit after `scale`.
    name: &'a str,
    unit: &'a str,
    /// The factor on every value (units that keep the tick labels short).
    scale: f64,
    /// Titles of the top and bottom panels.
    titles: [String; 2],
    /// Each view's own estimate (E, value), already scaled.
    points: Vec<(f64, f64)>,
    colour: RGBColor,
}

fn draw_curve_panels<DB: Canvas>(
    [top_area, bottom_area]: [&DrawingArea<DB, Shift>; 2],
    d: &Data,
    c: &[(f64, CurveSet, CurveSet)],
    p: CurvePanels<'_>,
    text: bool,
) -> DrawResult {
    let (i, scale, name, unit) = (p.index, p.scale, p.name, p.unit);
    let [top_title, bottom_title] = p.titles;
    let top = BandPanel {
        title: top_title,
        y_label: format!("{name} ({unit})"),
        curve: c.iter().map(|q| (q.0, q.1[i] * scale, q.2[i] * scale)).collect(),
        points: p.points.clone(),
        colour: p.colour,
        setting: crate::data::setting_axis(&d.cal),
    };
    draw_band(top_area, &top, text)?;
    let deviation = BandPanel {
        title: bottom_title,
        y_label: format!("{name} − {name}(E) ({unit})"),
        curve: c.iter().map(|q| (q.0, 0.0, q.2[i] * scale)).collect(),
        points: p.points.iter().map(|v| (v.0, v.1 - curve_values(&d.model, v.0)[i] * scale)).collect(),
        colour: p.colour,
        setting: crate::data::setting_axis(&d.cal),
    };
    draw_band(bottom_area, &deviation, text)
}

/// Title of a deviation panel with room for the bands' legend.
fn deviation_title(name: &str) -> String {
    format!("{name} − {name}(E): bands ±1σ (dark), ±3σ (light)")
}

/// fx(E), fy(E) (top) and their deviations from the curve with the 1- and 3-sigma bands
/// (bottom), with each view's own estimate.
pub(crate) fn draw_focal<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let c = curves(d);
    let panels = root.split_evenly((2, 2));
    for (k, name) in ["fx", "fy"].into_iter().enumerate() {
        let own = |v: &(f64, f64, f64)| if k == 0 { v.1 } else { v.2 };
        let points = d.view_focal.iter().filter(|v| own(v) > 0.0).map(|v| (v.0, own(v))).collect();
        let titles = [format!("{name}(E) (line) and each view's own {name} (dots)"), deviation_title(name)];
        let curve = CurvePanels { index: k, name, unit: "px", scale: 1.0, titles, points, colour: PALETTE[k] };
        draw_curve_panels([&panels[k], &panels[2 + k]], d, &c, curve, text)?;
    }
    Ok(())
}

/// The distortion coefficients (the family's: k1, p1, p2 or k1, k2, p1, p2, k3) against
/// the current with the 1- and 3-sigma bands and each view's own estimate (Eq. 23) (top),
/// and the same minus the curve (bottom: bands too narrow to see on the top row show
/// there).
pub(crate) fn draw_distortion<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let c = curves(d);
    let names = curve_names(&d.model);
    let coefficients = &names[2..];
    let panels = root.split_evenly((2, coefficients.len()));
    let colours = [PALETTE[0], PALETTE[1], PALETTE[2], PALETTE[4], PALETTE[3]];
    // Five panels a row leave room for short titles only.
    let narrow = coefficients.len() > 3;
    for (k, &(name, unit)) in coefficients.iter().enumerate() {
        // Scaled units keep the tick labels short (the paper's coefficients are per px).
        let (scale, unit) = match unit {
            "1/px²" => (1e9, "1e-9 / px²"),
            "1/px" => (1e6, "1e-6 / px"),
            _ => (1.0, unit),
        };
        let points = d.view_dist.iter().map(|(e, v)| (*e, v[k] * scale)).collect();
        let titles = if narrow {
            [format!("{name}(E), views (dots)"), format!("{name} − {name}(E), ±1σ, ±3σ")]
        } else {
            [format!("{name}(E) (line) and each view's own (dots)"), deviation_title(name)]
        };
        let colour = colours[k % colours.len()];
        let curve = CurvePanels { index: 2 + k, name, unit, scale, titles, points, colour };
        draw_curve_panels([&panels[k], &panels[coefficients.len() + k]], d, &c, curve, text)?;
    }
    Ok(())
}

/// A vertical colour bar for values lo..hi, labelled `label`.
fn colour_bar<DB: Canvas>(
    area: &DrawingArea<DB, Shift>,
    (lo, hi): (f64, f64),
    label: &str,
    map: fn(f64) -> RGBColor,
    text: bool,
) -> DrawResult {
    let mut b = ChartBuilder::on(area);
    b.margin_top(40).margin_bottom(50).margin_right(10);
    if text {
        b.y_label_area_size(80);
    }
    let mut chart = b.build_cartesian_2d(0.0..1.0, lo..hi)?;
    if text {
        chart
            .configure_mesh()
            .disable_x_mesh()
            .disable_y_mesh()
            .disable_x_axis()
            .y_desc(label)
            .y_labels(8)
            .y_label_formatter(&|v| tick(*v, hi - lo))
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .draw()?;
    }
    let n = 100;
    chart.draw_series((0..n).map(|k| {
        let (a, b) = (lo + (hi - lo) * k as f64 / n as f64, lo + (hi - lo) * (k + 1) as f64 / n as f64);
        Rectangle::new([(0.0, a), (1.0, b)], map((k as f64 + 0.5) / n as f64).filled())
    }))?;
    Ok(())
}

/// The projection-uncertainty maps at the three currents, one colour scale.
pub(crate) fn draw_projection_std<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let (maps, bar) = root.split_horizontally(root.dim_in_pixel().0 - 150);
    let top =
        d.std_maps.iter().flat_map(|m| m.cells.iter().flatten()).copied().filter(|v| v.is_finite()).fold(0.0, f64::max);
    let top = if top > 0.0 { top } else { 1.0 };
    let [w, h] = d.cal.image_size;
    for (m, panel) in d.std_maps.iter().zip(maps.split_evenly((1, 3)).iter()) {
        let max = m.cells.iter().flatten().copied().filter(|v| v.is_finite()).fold(0.0, f64::max);
        let (name, unit) = crate::data::setting_axis(&d.cal);
        let caption = format!("{name} {:.1} {unit}, depth {:.1} mm: max {:.3} px", m.e_com_ma, m.depth_mm, max);
        let mut b = panel_frame(panel, 10, (caption, 16), [35, 50], text);
        b.margin_top(16);
        let mut chart = b.build_cartesian_2d(0.0..w as f64, h as f64..0.0)?;
        let (rows, cols) = (m.cells.len(), m.cells.first().map_or(0, |r| r.len()));
        let (cw, ch) = (w as f64 / cols.max(1) as f64, h as f64 / rows.max(1) as f64);
        chart.draw_series(m.cells.iter().enumerate().flat_map(|(r, row)| {
            row.iter().enumerate().map(move |(k, v)| {
                let col = if v.is_finite() { sequential(v / top) } else { RGBColor(200, 200, 200) };
                Rectangle::new(
                    [(k as f64 * cw, r as f64 * ch), ((k + 1) as f64 * cw, (r + 1) as f64 * ch)],
                    col.filled(),
                )
            })
        }))?;
        draw_image_axes(&mut chart, text)?;
    }
    colour_bar(&bar, (0.0, top), "worst-direction std (px)", sequential, text)?;
    Ok(())
}

/// Views grouped by current: (E range, view indices). Views within 0.5 mA share a group;
/// more than 6 groups are merged into 6 equal ranges of the current.
pub(crate) fn coverage_groups(d: &Data) -> Vec<([f64; 2], Vec<usize>)> {
    let mut order: Vec<usize> = (0..d.views.len()).collect();
    order.sort_by(|a, b| d.views[*a].e_com_ma.total_cmp(&d.views[*b].e_com_ma));
    let mut groups: Vec<([f64; 2], Vec<usize>)> = vec![];
    for k in order {
        let e = d.views[k].e_com_ma;
        match groups.last_mut() {
            Some(g) if e - g.0[1] <= 0.5 => {
                g.0[1] = e;
                g.1.push(k);
            }
            _ => groups.push(([e, e], vec![k])),
        }
    }
    if groups.len() <= 6 {
        return groups;
    }
    let (lo, hi) = (groups[0].0[0], groups[groups.len() - 1].0[1]);
    let width = (hi - lo) / 6.0;
    let mut merged: Vec<([f64; 2], Vec<usize>)> =
        (0..6).map(|b| ([lo + b as f64 * width, lo + (b + 1) as f64 * width], vec![])).collect();
    for (k, v) in d.views.iter().enumerate() {
        let b = (((v.e_com_ma - lo) / width.max(1e-12)) as usize).min(5);
        merged[b].1.push(k);
    }
    merged.retain(|g| !g.1.is_empty());
    merged
}

/// Where the corners were in the image, one panel per current group, coloured by view.
pub(crate) fn draw_coverage<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let groups = coverage_groups(d);
    let [w, h] = d.cal.image_size;
    let n = d.views.len();
    let body = root.margin(30, 0, 0, 0);
    for (g, panel) in groups.iter().zip(body.split_evenly((groups.len().div_ceil(3), 3)).iter()) {
        let corners: usize = g.1.iter().map(|&k| d.views[k].pixels.len()).sum();
        let (name, unit) = crate::data::setting_axis(&d.cal);
        let range = if g.0[1] - g.0[0] < 0.05 {
            format!("{:.1} {unit}", g.0[0])
        } else {
            format!("{:.1}–{:.1} {unit}", g.0[0], g.0[1])
        };
        let caption = format!("{name} {range}: {} views, {corners} corners", g.1.len());
        let mut b = panel_frame(panel, 10, (caption, 16), [32, 50], text);
        let mut chart = b.build_cartesian_2d(0.0..w as f64, h as f64..0.0)?;
        if text {
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(5)
                .y_labels(5)
                .x_label_formatter(&px)
                .y_label_formatter(&px)
                .draw()?;
        }
        chart
            .draw_series(std::iter::once(Rectangle::new([(0.0, 0.0), (w as f64, h as f64)], BLACK.stroke_width(1))))?;
        for &k in &g.1 {
            let col = view_colour(k, n);
            chart.draw_series(d.views[k].pixels.iter().map(|p| Circle::new((p[0], p[1]), 2, col.filled())))?;
        }
    }
    if text {
        root.draw(&Text::new(
            "u, v in px; the frame is the whole image; colours: views (as in the residual figures)",
            (12, 8),
            ("sans-serif", 16),
        ))?;
    }
    Ok(())
}

/// Residual vectors (model − observed), magnified, coloured by view.
pub(crate) fn draw_residual_map<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let [w, h] = d.cal.image_size;
    let rms = d.cal.rms_reprojection_px.max(1e-6);
    // Arrows of RMS length become 2 % of the image width.
    let gain = 0.02 * w as f64 / rms;
    let caption = format!("residuals (model − observed) magnified {gain:.0} times; colour: view");
    let mut b = panel_frame(root, 15, (caption, 20), [40, 60], text);
    // Image rows grow downwards.
    let mut chart = b.build_cartesian_2d(0.0..w as f64, h as f64..0.0)?;
    if text {
        chart
            .configure_mesh()
            .x_desc("u (px)")
            .y_desc("v (px)")
            .x_label_formatter(&px)
            .y_label_formatter(&px)
            .draw()?;
    }
    let n = d.views.len();
    for (k, v) in d.views.iter().enumerate() {
        let col = view_colour(k, n);
        chart.draw_series(v.residuals.iter().map(|r| {
            PathElement::new(
                vec![(r.at[0], r.at[1]), (r.at[0] + gain * r.d[0], r.at[1] + gain * r.d[1])],
                col.stroke_width(1),
            )
        }))?;
        chart.draw_series(v.residuals.iter().map(|r| Circle::new((r.at[0], r.at[1]), 1, col.filled())))?;
    }
    // A scale arrow of 1 RMS at the bottom left, inside the image.
    let (x0, y0) = (0.03 * w as f64, 0.96 * h as f64);
    chart
        .draw_series(std::iter::once(PathElement::new(vec![(x0, y0), (x0 + gain * rms, y0)], BLACK.stroke_width(3))))?;
    if text {
        chart.draw_series(std::iter::once(Text::new(
            format!("= {rms:.3} px (the RMS)"),
            (x0 + gain * rms + 0.01 * w as f64, y0 - 0.012 * h as f64),
            ("sans-serif", 14),
        )))?;
    }
    Ok(())
}

/// The RMS residual of each view, bars in the view's colour, with the overall RMS.
pub(crate) fn draw_view_rms<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let n = d.views.len();
    let rms: Vec<f64> = d
        .views
        .iter()
        .map(|v| {
            (v.residuals.iter().map(|r| r.d[0] * r.d[0] + r.d[1] * r.d[1]).sum::<f64>()
                / v.residuals.len().max(1) as f64)
                .sqrt()
        })
        .collect();
    let top = rms.iter().copied().fold(d.cal.rms_reprojection_px, f64::max).max(1e-9) * 1.15;
    let caption = "RMS residual per view (bars, colour as in the residual map); dashed: all views";
    let mut b = panel_frame(root, 15, (caption, 18), [45, 65], text);
    let mut chart = b.build_cartesian_2d(-0.6..n as f64 - 0.4, 0.0..top)?;
    let (name, unit) = crate::data::setting_axis(&d.cal);
    let view_desc = format!("view: {name} ({unit})");
    if text {
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n.min(30))
            .x_label_formatter(&|x| {
                let k = x.round();
                match d.views.get(k as usize).filter(|_| (x - k).abs() < 1e-6 && k >= 0.0) {
                    // Up to 20 views the label carries the current too.
                    Some(v) if n <= 20 => format!("{k:.0}: {:.0}", v.e_com_ma),
                    Some(_) => format!("{k:.0}"),
                    None => String::new(),
                }
            })
            .x_desc(if n <= 20 { view_desc.as_str() } else { "view (its setting in the views table)" })
            .y_desc("RMS (px)")
            .draw()?;
    }
    chart.draw_series(
        rms.iter()
            .enumerate()
            .map(|(k, r)| Rectangle::new([(k as f64 - 0.4, 0.0), (k as f64 + 0.4, *r)], view_colour(k, n).filled())),
    )?;
    let all = d.cal.rms_reprojection_px;
    chart.draw_series(DashedLineSeries::new([(-0.6, all), (n as f64 - 0.4, all)], 8, 5, BLACK.stroke_width(2)))?;
    Ok(())
}

/// The histogram of the residual components u and v.
pub(crate) fn draw_histogram<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let vals: Vec<f64> = d.views.iter().flat_map(|v| v.residuals.iter().flat_map(|r| r.d)).collect();
    let m = vals.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(1e-6);
    let bins = 41usize;
    let width = 2.0 * m / bins as f64;
    let mut counts = vec![0u32; bins];
    for v in &vals {
        let k = (((v + m) / width) as usize).min(bins - 1);
        counts[k] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1);
    let mut b = panel_frame(root, 15, ("residual components u and v together (px)", 20), [40, 60], text);
    let mut chart = b.build_cartesian_2d(-m..m, 0u32..top + top / 10 + 1)?;
    if text {
        chart.configure_mesh().x_desc("residual (px)").y_desc("count").draw()?;
    }
    chart.draw_series(counts.iter().enumerate().map(|(k, &c)| {
        let x0 = -m + k as f64 * width;
        Rectangle::new([(x0, 0), (x0 + width, c)], RGBColor(31, 119, 180).mix(0.7).filled())
    }))?;
    Ok(())
}

/// Grid of the distortion field (columns, rows).
const FIELD: (usize, usize) = (16, 12);

/// (ideal pixel, distorted − ideal) over the image at `e_com_ma` (empty where the model
/// cannot be evaluated).
fn field(d: &Data, e_com_ma: f64) -> Vec<([f64; 2], [f64; 2])> {
    let Ok(dist) = d.model.distortion(e_com_ma) else { return vec![] };
    let [w, h] = d.cal.image_size;
    let [u0, v0] = d.model.principal_point;
    (0..FIELD.1)
        .flat_map(|r| {
            (0..FIELD.0).map(move |k| {
                ((k as f64 + 0.5) * w as f64 / FIELD.0 as f64, (r as f64 + 0.5) * h as f64 / FIELD.1 as f64)
            })
        })
        .map(|(x, y)| {
            let [xd, yd] = dist.distort(x - u0, y - v0);
            ([x, y], [xd + u0 - x, yd + v0 - y])
        })
        .collect()
}

/// The distortion field (distorted − ideal pixel, Eq. 17) at the three currents, one
/// magnification for the three.
pub(crate) fn draw_distortion_field<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let fields: Vec<Vec<([f64; 2], [f64; 2])>> = d.map_currents.iter().map(|&e| field(d, e)).collect();
    let norm = |v: &[f64; 2]| v[0].hypot(v[1]);
    let max = fields.iter().flatten().map(|f| norm(&f.1)).fold(0.0, f64::max).max(1e-9);
    let [w, h] = d.cal.image_size;
    // The longest arrow becomes 8 % of the image width.
    let gain = 0.08 * w as f64 / max;
    for ((f, e), panel) in fields.iter().zip(d.map_currents).zip(root.split_evenly((1, 3)).iter()) {
        let m = f.iter().map(|q| norm(&q.1)).fold(0.0, f64::max);
        let (name, unit) = crate::data::setting_axis(&d.cal);
        let caption = format!("{name} {e:.1} {unit}: max {m:.2} px, arrows x{gain:.0}");
        let mut b = panel_frame(panel, 10, (caption, 16), [35, 50], text);
        let mut chart = b.build_cartesian_2d(0.0..w as f64, h as f64..0.0)?;
        draw_image_axes(&mut chart, text)?;
        let col = RGBColor(140, 40, 160);
        chart.draw_series(f.iter().map(|(p, v)| {
            PathElement::new(vec![(p[0], p[1]), (p[0] + gain * v[0], p[1] + gain * v[1])], col.stroke_width(2))
        }))?;
        chart.draw_series(f.iter().map(|(p, _)| Circle::new((p[0], p[1]), 2, BLACK.filled())))?;
        let pp = d.model.principal_point;
        chart.draw_series(std::iter::once(Cross::new((pp[0], pp[1]), 6, RED.stroke_width(2))))?;
    }
    Ok(())
}

/// The correlation matrix as a heat map (−1 blue, 0 white, +1 red), names on both axes.
pub(crate) fn draw_correlation<DB: Canvas>(root: &DrawingArea<DB, Shift>, d: &Data, text: bool) -> DrawResult {
    let Some(c) = d.covariance else { return Ok(()) };
    let r = correlation(&c);
    let layout = d.model.layout();
    let n_params = layout.len();
    let (mat, bar) = root.split_horizontally(root.dim_in_pixel().0 - 150);
    let (w, h) = mat.dim_in_pixel();
    let (left, topm) = (60i32, 40i32);
    let cell = ((w as i32 - left - 10).min(h as i32 - topm - 60) / n_params as i32).max(1);
    for (i, row) in r.iter().enumerate().take(n_params) {
        for (j, v) in row.iter().enumerate().take(n_params) {
            let (x, y) = (left + j as i32 * cell, topm + i as i32 * cell);
            mat.draw(&Rectangle::new([(x, y), (x + cell, y + cell)], diverging(*v).filled()))?;
        }
    }
    // Lines between the groups of numbers (rotation, translation, kf_x, kf_y, u0 v0, a).
    let groups = [layout.translation(), layout.kf_x(), layout.kf_y(), layout.principal_point(), layout.distortion_a()];
    for g in groups.map(|s| s.start as i32) {
        let p = g * cell;
        let n = n_params as i32 * cell;
        mat.draw(&PathElement::new(vec![(left + p, topm), (left + p, topm + n)], BLACK.stroke_width(1)))?;
        mat.draw(&PathElement::new(vec![(left, topm + p), (left + n, topm + p)], BLACK.stroke_width(1)))?;
    }
    if text {
        let font = ("sans-serif", 13).into_font();
        for (k, name) in layout.names().enumerate() {
            let at = k as i32 * cell + cell / 2;
            mat.draw(&Text::new(name, (6, topm + at - 6), font.clone()))?;
            mat.draw(&Text::new(
                name,
                (left + at - 5, topm + n_params as i32 * cell + 6),
                font.clone().transform(FontTransform::Rotate90),
            ))?;
        }
        mat.draw(&Text::new("correlation r_ij = C_ij / sqrt(C_ii C_jj)", (left, 10), ("sans-serif", 18)))?;
    }
    colour_bar(&bar, (-1.0, 1.0), "r", |t| diverging(2.0 * t - 1.0), text)?;
    Ok(())
}
