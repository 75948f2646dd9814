//! Figures of the studies: line and scatter charts drawn with plotters into SVG and PNG.
//!
//! The legend of each panel is drawn beside its plot area (never over the data); every
//! series has its own colour from a palette of 12 (a figure with more series reuses them
//! in order); reference lines (bounds, the paper's values) are dashed; a series with
//! standard errors gets error bars of one standard error.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

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
}

impl Series {
    /// A line with markers.
    pub fn line(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: false, y_se: None }
    }
    /// A thin reference line (a bound, the paper's value).
    pub fn reference(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: true, scatter: false, y_se: None }
    }
    /// Markers only.
    pub fn scatter(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: true, y_se: None }
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

/// Twelve distinct colours (Tableau 10 and two dark ones).
const PALETTE: [RGBColor; 12] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(90, 90, 90),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 128),
    RGBColor(128, 0, 0),
];

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

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

/// Width of the legend column beside each plot, px.
const LEGEND_PX: u32 = 200;

/// The (x, y, y - se, y + se) of a series in plot coordinates (log10 when `log_y`), finite
/// points only; the bar ends are y itself where there is no standard error.
fn plotted(c: &Chart, s: &Series) -> Vec<(f64, f64, f64, f64)> {
    s.points
        .iter()
        .enumerate()
        .filter_map(|(k, &(x, y))| {
            let se =
                s.y_se.as_ref().and_then(|v| v.get(k)).copied().filter(|v| v.is_finite() && *v > 0.0).unwrap_or(0.0);
            let (lo, hi) = (y_of(c, y - se), y_of(c, y + se));
            let yy = y_of(c, y);
            // On a log axis a bar reaching zero or below ends at the point.
            let lo = if lo.is_finite() { lo } else { yy };
            (x.is_finite() && yy.is_finite()).then_some((x, yy, lo, if hi.is_finite() { hi } else { yy }))
        })
        .collect()
}

/// The legend in its own column: a sample of each series' line or marker and its name.
fn draw_legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, c: &Chart) -> DrawResult
where
    DB::ErrorType: 'static,
{
    for (k, s) in c.series.iter().enumerate() {
        let col = PALETTE[s.colour % PALETTE.len()];
        let y = 50 + 20 * k as i32;
        if s.reference {
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

fn draw_chart<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, c: &Chart, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (plot_area, legend_area) = area.split_horizontally(area.dim_in_pixel().0.saturating_sub(LEGEND_PX));
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
        b.caption(&c.title, ("sans-serif", 17)).x_label_area_size(40).y_label_area_size(65);
    }
    let mut chart = b.build_cartesian_2d(xl - px..xh + px, yl - py..yh + py)?;
    if text {
        let y_desc = if c.log_y { format!("log10 {}", c.y_label) } else { c.y_label.clone() };
        chart.configure_mesh().x_desc(c.x_label.as_str()).y_desc(y_desc).light_line_style(WHITE).draw()?;
    }
    for (s, p) in c.series.iter().zip(pts) {
        let col = PALETTE[s.colour % PALETTE.len()];
        let xy = p.iter().map(|q| (q.0, q.1));
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

fn draw_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &Figure, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let areas = root.split_evenly(f.grid);
    for (area, c) in areas.iter().zip(&f.panels) {
        draw_chart(area, c, text)?;
    }
    root.present()?;
    Ok(())
}

/// Writes `f` as `dir/name.svg` and `dir/name.png` (atomic writes); returns the paths.
pub fn write_figure(dir: &Path, f: &Figure) -> Result<Vec<PathBuf>> {
    let size = ((560 + LEGEND_PX) * f.grid.1 as u32, 420 * f.grid.0 as u32);
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
    let (p, s) = (dir.join(format!("{}.png", f.name)), dir.join(format!("{}.svg", f.name)));
    write_atomic(&p, png.get_ref())?;
    write_atomic(&s, svg.as_bytes())?;
    Ok(vec![p, s])
}
