//! Figures of the studies: line and scatter charts drawn with plotters into SVG and PNG.
//!
//! The legend of each panel is drawn beside its plot area (never over the data); every
//! series has its own colour from a palette of 12 (a figure with more series reuses them
//! in order); reference lines (bounds, the paper's values) are dashed; a series with
//! standard errors gets error bars of one standard error; a band (a spread around a curve)
//! is a translucent area.

use std::path::{Path, PathBuf};

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use etl_formats::{write_atomic, Error, Result};

/// One curve of a chart.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// (x, y) points; non-finite y are skipped.
    pub points: Vec<(f64, f64)>,
    /// Index into the palette.
    pub colour: usize,
    /// A thin line without markers (bounds, references) instead of a line with markers.
    pub reference: bool,
    /// Markers only, no line (scatter).
    pub scatter: bool,
    /// One standard error of each y (same length as `points`): drawn as error bars.
    pub y_se: Option<Vec<f64>>,
    /// A band: the area between y - w and y + w for these half widths (same length as
    /// `points`), drawn translucent without a line or markers.
    pub band: Option<Vec<f64>>,
}

impl Series {
    /// A line with markers.
    pub fn line(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: false, y_se: None, band: None }
    }
    /// A thin reference line (a bound, the paper's value).
    pub fn reference(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: true, scatter: false, y_se: None, band: None }
    }
    /// Markers only.
    pub fn scatter(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: true, y_se: None, band: None }
    }
    /// A translucent band from y - `half_width` to y + `half_width` around `points` (e.g. a
    /// spread of ± 1 std; a non-finite half width leaves a gap).
    pub fn band(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>, half_width: Vec<f64>) -> Self {
        Series {
            name: name.into(),
            points,
            colour,
            reference: false,
            scatter: false,
            y_se: None,
            band: Some(half_width),
        }
    }
    /// The same series with error bars of one standard error `se` (one per point, px or
    /// the y unit; a non-finite or missing entry draws no bar).
    pub fn with_se(mut self, se: Vec<f64>) -> Self {
        self.y_se = Some(se);
        self
    }
}

/// One panel.
#[derive(Debug, Clone)]
pub struct Chart {
    /// Caption.
    pub title: String,
    /// Axis descriptions.
    pub x_label: String,
    /// Axis descriptions.
    pub y_label: String,
    /// Plot log10(y) (positive y only).
    pub log_y: bool,
    /// Curves.
    pub series: Vec<Series>,
    /// Names of the categories at x = 0, 1, 2, ... (e.g. parameters), written as the x
    /// tick labels instead of the numbers; empty for a numeric x axis.
    pub x_names: Vec<String>,
}

/// A figure of panels on a grid, written as `name.png` and `name.svg`.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File stem.
    pub name: String,
    /// (rows, columns) of panels.
    pub grid: (usize, usize),
    /// Panels, row by row.
    pub panels: Vec<Chart>,
}

/// Twelve distinct colours (Tableau 10 and two dark ones), as their hex codes.
pub(crate) const PALETTE: [RGBColor; 12] = hex_colours([
    0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0xe377c2, 0x5a5a5a, 0xbcbd22, 0x17becf, 0x000080,
    0x800000,
]);

/// `0xRRGGBB` codes as colours.
const fn hex_colours<const N: usize>(codes: [u32; N]) -> [RGBColor; N] {
    let mut colours = [RGBColor(0, 0, 0); N];
    let mut i = 0;
    while i < N {
        let [_, r, g, b] = codes[i].to_be_bytes();
        colours[i] = RGBColor(r, g, b);
        i += 1;
    }
    colours
}

/// What every drawing function returns: plotters' errors boxed, whatever the backend.
pub(crate) type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// A plotters backend whose errors can be boxed into a [`DrawResult`]: the one bound of
/// every drawing function (SVG and bitmap alike).
pub(crate) trait Canvas: DrawingBackend<ErrorType: 'static> {}

impl<DB: DrawingBackend<ErrorType: 'static>> Canvas for DB {}

/// One page: a white background, then `draw`, then the page presented (written out).
pub(crate) fn page<DB: Canvas>(root: &DrawingArea<DB, Shift>, draw: impl FnOnce() -> DrawResult) -> DrawResult {
    root.fill(&WHITE)?;
    draw()?;
    root.present()?;
    Ok(())
}

fn y_of(c: &Chart, y: f64) -> f64 {
    if c.log_y {
        if y > 0.0 {
            y.log10()
        } else {
            f64::NAN
        }
    } else {
        y
    }
}

/// Opacity of a band's fill.
const BAND_ALPHA: f64 = 0.22;

/// The width of the legend column beside each plot of `f`, px: room for its longest series
/// name (13 px sans-serif, about 7 px a character), within 120..=360 px.
fn legend_px(f: &Figure) -> u32 {
    let longest = f.panels.iter().flat_map(|c| &c.series).map(|s| s.name.chars().count()).max().unwrap_or(0);
    (44 + 7 * longest as u32).clamp(120, 360)
}

/// A tick label on an axis `span` long: the number as short as it reads (80, 2.5, 0.3,
/// 1e-5, 2.5e6), and 0 for what is zero but for rounding (-5.55e-17 on a span of 2).
pub(crate) fn tick(v: f64, span: f64) -> String {
    if v.abs() <= 1e-9 * span.abs() {
        return "0".into();
    }
    let trim = |t: &str| t.trim_end_matches('0').trim_end_matches('.').to_string();
    if v.abs() < 1e-3 || v.abs() >= 1e6 {
        // Four significant digits, rounding away the axis steps' float noise.
        let t = format!("{v:.3e}");
        let (mantissa, exponent) = t.split_once('e').unwrap_or((&t, "0"));
        return format!("{}e{exponent}", trim(mantissa));
    }
    trim(&format!("{v:.6}"))
}

/// The (x, y, y - w, y + w) of a series in plot coordinates (log10 when `log_y`), finite
/// points only, with w its standard error (error bars) or its band's half width; the ends
/// are y itself where there is neither.
fn plotted(c: &Chart, s: &Series) -> Vec<(f64, f64, f64, f64)> {
    let widths = s.band.as_ref().or(s.y_se.as_ref());
    s.points
        .iter()
        .enumerate()
        .filter_map(|(k, &(x, y))| {
            let se = widths.and_then(|v| v.get(k)).copied().filter(|v| v.is_finite() && *v > 0.0).unwrap_or(0.0);
            let (lo, hi) = (y_of(c, y - se), y_of(c, y + se));
            let yy = y_of(c, y);
            // On a log axis a bar reaching zero or below ends at the point.
            let lo = if lo.is_finite() { lo } else { yy };
            (x.is_finite() && yy.is_finite()).then_some((x, yy, lo, if hi.is_finite() { hi } else { yy }))
        })
        .collect()
}

/// The legend in its own column: a sample of each series' line, marker or band and its name.
fn draw_legend<DB: Canvas>(area: &DrawingArea<DB, Shift>, c: &Chart) -> DrawResult {
    for (k, s) in c.series.iter().enumerate() {
        let col = PALETTE[s.colour % PALETTE.len()];
        let y = 50 + 20 * k as i32;
        if s.band.is_some() {
            area.draw(&Rectangle::new([(4, y - 6), (30, y + 6)], col.mix(BAND_ALPHA).filled()))?;
        } else if s.reference {
            for x in [4, 15, 26] {
                area.draw(&PathElement::new(vec![(x, y), (x + 5, y)], col.stroke_width(2)))?;
            }
        } else {
            if !s.scatter {
                area.draw(&PathElement::new(vec![(4, y), (30, y)], col.stroke_width(2)))?;
            }
            area.draw(&Circle::new((17, y), 3, col.filled()))?;
        }
        area.draw(&Text::new(s.name.as_str(), (36, y - 7), ("sans-serif", 13)))?;
    }
    Ok(())
}

fn draw_chart<DB: Canvas>(area: &DrawingArea<DB, Shift>, c: &Chart, legend: u32, text: bool) -> DrawResult {
    let (plot_area, legend_area) = area.split_horizontally(area.dim_in_pixel().0.saturating_sub(legend));
    let pts: Vec<Vec<(f64, f64, f64, f64)>> = c.series.iter().map(|s| plotted(c, s)).collect();
    let (mut xl, mut xh, mut yl, mut yh) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in pts.iter().flatten() {
        xl = xl.min(p.0);
        xh = xh.max(p.0);
        yl = yl.min(p.2);
        yh = yh.max(p.3);
    }
    if !(xl.is_finite() && yl.is_finite()) {
        (xl, xh, yl, yh) = (0.0, 1.0, 0.0, 1.0);
    }
    let (px, py) = (((xh - xl) * 0.05).max(1e-9), ((yh - yl) * 0.08).max(1e-9 * yh.abs().max(1e-12)));
    let mut b = ChartBuilder::on(&plot_area);
    b.margin(10);
    if text {
        let x_area = if c.x_names.is_empty() { 40 } else { 60 };
        b.caption(&c.title, ("sans-serif", 17)).x_label_area_size(x_area).y_label_area_size(65);
    }
    let mut chart = b.build_cartesian_2d(xl - px..xh + px, yl - py..yh + py)?;
    if text {
        let y_desc = if c.log_y { format!("log10 {}", c.y_label) } else { c.y_label.clone() };
        let named = !c.x_names.is_empty();
        // Named categories are written below (draw_x_names); the mesh only marks them.
        let (x_span, y_span) = (xh - xl + 2.0 * px, yh - yl + 2.0 * py);
        let x_tick = |v: &f64| if named { String::new() } else { tick(*v, x_span) };
        let y_tick = |v: &f64| tick(*v, y_span);
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(c.x_label.as_str())
            .y_desc(y_desc)
            .light_line_style(WHITE)
            .x_label_formatter(&x_tick)
            .y_label_formatter(&y_tick);
        if named {
            // A tick at each whole x: the axis' steps come from 1, 2, 5 x 10^k, and more
            // ticks than categories but fewer than twice them gives steps of 1.
            mesh.x_labels(c.x_names.len() + 8);
        }
        mesh.draw()?;
        draw_x_names(&plot_area, &chart, c, yl - py)?;
    }
    for (s, p) in c.series.iter().zip(pts) {
        let col = PALETTE[s.colour % PALETTE.len()];
        let xy = p.iter().map(|q| (q.0, q.1));
        if s.band.is_some() {
            // The upper edge left to right, then the lower edge back.
            let outline: Vec<(f64, f64)> =
                p.iter().map(|q| (q.0, q.3)).chain(p.iter().rev().map(|q| (q.0, q.2))).collect();
            chart.draw_series(std::iter::once(Polygon::new(outline, col.mix(BAND_ALPHA).filled())))?;
            continue;
        }
        if s.reference {
            chart.draw_series(DashedLineSeries::new(xy, 6, 4, col.stroke_width(2)))?;
        } else {
            if !s.scatter {
                chart.draw_series(LineSeries::new(xy.clone(), col.stroke_width(2)))?;
            }
            chart.draw_series(xy.map(|q| Circle::new(q, 3, col.filled())))?;
        }
        if s.y_se.is_some() {
            // A bar from y - se to y + se with caps of 1 % of the x range.
            let cap = 0.01 * (xh - xl + 2.0 * px);
            chart.draw_series(p.iter().filter(|q| q.3 > q.2).flat_map(|q| {
                [
                    PathElement::new(vec![(q.0, q.2), (q.0, q.3)], col.stroke_width(1)),
                    PathElement::new(vec![(q.0 - cap, q.2), (q.0 + cap, q.2)], col.stroke_width(1)),
                    PathElement::new(vec![(q.0 - cap, q.3), (q.0 + cap, q.3)], col.stroke_width(1)),
                ]
            }))?;
        }
    }
    if text {
        draw_legend(&legend_area, c)?;
    }
    Ok(())
}

/// The names of a chart's categories under its x axis (whose lowest y is `y_axis`), one
/// centred at each whole x, on two staggered rows so that neighbours never overlap.
fn draw_x_names<DB: Canvas>(
    plot_area: &DrawingArea<DB, Shift>,
    chart: &ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    c: &Chart,
    y_axis: f64,
) -> DrawResult {
    let (base_x, base_y) = plot_area.get_base_pixel();
    let font = TextStyle::from(("sans-serif", 12).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
    for (k, name) in c.x_names.iter().enumerate() {
        let (x, y) = chart.backend_coord(&(k as f64, y_axis));
        let row = 8 + 15 * (k % 2) as i32;
        plot_area.draw(&Text::new(name.as_str(), (x - base_x, y - base_y + row), font.clone()))?;
    }
    Ok(())
}

fn draw_figure<DB: Canvas>(root: &DrawingArea<DB, Shift>, f: &Figure, text: bool) -> DrawResult {
    page(root, || {
        let legend = legend_px(f);
        for (area, c) in root.split_evenly(f.grid).iter().zip(&f.panels) {
            draw_chart(area, c, legend, text)?;
        }
        Ok(())
    })
}

/// `f` drawn as PNG and SVG: `[("name.png", bytes), ("name.svg", bytes)]`.
pub fn render_figure(f: &Figure) -> Result<[(String, Vec<u8>); 2]> {
    let size = ((560 + legend_px(f)) * f.grid.1 as u32, 420 * f.grid.0 as u32);
    let text = crate::font_available();
    // No input of the user's is at fault when a plot fails: `what` names the plot.
    let plot = format!("plot {}", f.name);
    let fail = |e: Box<dyn std::error::Error>| Error::invalid(&plot, format!("{plot}: {e}"));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_figure(&root, f, text).map_err(fail)?;
    }
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw_figure(&root, f, text).map_err(fail)?;
    }
    let img = image::RgbImage::from_raw(size.0, size.1, buf)
        .ok_or_else(|| Error::invalid(&plot, format!("{plot}: bitmap size mismatch")))?;
    let mut png = std::io::Cursor::new(vec![]);
    img.write_to(&mut png, image::ImageFormat::Png)
        .map_err(|e| Error::invalid(&plot, format!("{plot}: PNG encoding: {e}")))?;
    Ok([(format!("{}.png", f.name), png.into_inner()), (format!("{}.svg", f.name), svg.into_bytes())])
}

/// Writes `f` as `dir/name.png` and `dir/name.svg` ([`render_figure`]; atomic writes);
/// returns the paths.
pub fn write_figure(dir: &Path, f: &Figure) -> Result<Vec<PathBuf>> {
    let mut paths = vec![];
    for (name, bytes) in render_figure(f)? {
        let path = dir.join(name);
        write_atomic(&path, &bytes)?;
        paths.push(path);
    }
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short_and_zero_is_zero() {
        assert_eq!(tick(80.0, 200.0), "80");
        assert_eq!(tick(2.5, 5.0), "2.5");
        assert_eq!(tick(-5.551115123125783e-17, 2.0), "0");
        assert_eq!(tick(0.30000000000000004, 1.0), "0.3");
        assert_eq!(tick(1e-5, 1e-4), "1e-5");
        assert_eq!(tick(2.5e6, 1e7), "2.5e6");
        assert_eq!(tick(1.2000000000000002e-4, 1e-3), "1.2e-4");
        assert_eq!(tick(-0.4, 2.0), "-0.4");
    }

    #[test]
    fn the_legend_column_fits_the_longest_name() {
        let chart = |names: &[&str]| Chart {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            log_y: false,
            series: names.iter().map(|n| Series::line(*n, 0, vec![(0.0, 1.0)])).collect(),
            x_names: vec![],
        };
        let figure = |names: &[&str]| Figure { name: "f".into(), grid: (1, 1), panels: vec![chart(names)] };
        assert_eq!(legend_px(&figure(&["a"])), 120);
        // 38 characters at about 7 px each, and the sample's 44 px.
        let long = "subsets: mean ± 1 s.e. (3 data sets) x";
        assert_eq!(legend_px(&figure(&["a", long])), 44 + 7 * long.chars().count() as u32);
        assert_eq!(legend_px(&figure(&[&"x".repeat(80)])), 360);
    }
}
