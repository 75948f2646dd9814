//! Figures of the studies: line and scatter charts drawn with plotters into SVG and PNG.

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
}

impl Series {
    /// A line with markers.
    pub fn line(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: false }
    }
    /// A thin reference line (a bound, the paper's value).
    pub fn reference(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: true, scatter: false }
    }
    /// Markers only.
    pub fn scatter(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: true }
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

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(90, 90, 90),
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

fn draw_chart<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, c: &Chart, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let pts: Vec<Vec<(f64, f64)>> = c
        .series
        .iter()
        .map(|s| {
            s.points.iter().map(|&(x, y)| (x, y_of(c, y))).filter(|p| p.0.is_finite() && p.1.is_finite()).collect()
        })
        .collect();
    let (mut xl, mut xh, mut yl, mut yh) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in pts.iter().flatten() {
        xl = xl.min(p.0);
        xh = xh.max(p.0);
        yl = yl.min(p.1);
        yh = yh.max(p.1);
    }
    if !(xl.is_finite() && yl.is_finite()) {
        (xl, xh, yl, yh) = (0.0, 1.0, 0.0, 1.0);
    }
    let (px, py) = (((xh - xl) * 0.05).max(1e-9), ((yh - yl) * 0.08).max(1e-9 * yh.abs().max(1e-12)));
    let mut b = ChartBuilder::on(area);
    b.margin(10);
    if text {
        b.caption(&c.title, ("sans-serif", 18)).x_label_area_size(40).y_label_area_size(65);
    }
    let mut chart = b.build_cartesian_2d(xl - px..xh + px, yl - py..yh + py)?;
    if text {
        let y_desc = if c.log_y { format!("log10 {}", c.y_label) } else { c.y_label.clone() };
        chart.configure_mesh().x_desc(c.x_label.as_str()).y_desc(y_desc).light_line_style(WHITE).draw()?;
    }
    for (s, p) in c.series.iter().zip(pts) {
        let col = PALETTE[s.colour % PALETTE.len()];
        let legend = move |(x, y): (i32, i32)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2));
        if s.scatter {
            chart
                .draw_series(p.iter().map(|q| Circle::new(*q, 3, col.filled())))?
                .label(s.name.as_str())
                .legend(legend);
        } else if s.reference {
            chart.draw_series(LineSeries::new(p, col.mix(0.7).stroke_width(1)))?.label(s.name.as_str()).legend(legend);
        } else {
            chart.draw_series(LineSeries::new(p.clone(), col.stroke_width(2)))?.label(s.name.as_str()).legend(legend);
            chart.draw_series(p.iter().map(|q| Circle::new(*q, 3, col.filled())))?;
        }
    }
    if text {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 12))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
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
    let size = (560 * f.grid.1 as u32, 400 * f.grid.0 as u32);
    let text = crate::font_available();
    let fail = |e: Box<dyn std::error::Error>| Error::InvalidInput(format!("plot {}: {e}", f.name));
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
        .ok_or_else(|| Error::InvalidInput(format!("plot {}: bitmap size mismatch", f.name)))?;
    let mut png = std::io::Cursor::new(vec![]);
    img.write_to(&mut png, image::ImageFormat::Png)
        .map_err(|e| Error::InvalidInput(format!("plot {}: PNG encoding: {e}", f.name)))?;
    let (p, s) = (dir.join(format!("{}.png", f.name)), dir.join(format!("{}.svg", f.name)));
    write_atomic(&p, png.get_ref())?;
    write_atomic(&s, svg.as_bytes())?;
    Ok(vec![p, s])
}
