//! A board as the user prints it (`etlcal board`, Python `Board.to_svg`): an SVG at true
//! size and a raster at a given resolution, both drawn from the board's own geometry
//! ([`etl_formats::board::Board`], OpenCV's layout for ChArUco boards), so that the board
//! printed is the one calibrated with.
//!
//! The page is the board's pattern (all its squares; a checkerboard's outer ring of
//! squares included) with a white margin of `margin_mm` around it; page coordinates are
//! mm from the page's top-left corner, x right, y down, as printed:
//! page (x, y) = board (x + x_min - margin_mm, y + y_min - margin_mm), with
//! [x_min, y_min] the start of the pattern ([`Board::pattern_mm`]).
//!
//! - [`svg`]: `width`/`height` in mm and a `viewBox` in mm, so it prints at true size at
//!   100 % scale; black squares and each marker's black cells (its border ring and its 0
//!   bits) as filled paths, adjacent cells of a row merged into one rectangle and all
//!   rectangles of a path of the same orientation (no seams between them under the
//!   non-zero fill rule).
//! - [`raster`]: pixel (x, y) covers page [x p, (x + 1) p] x [y p, (y + 1) p] with
//!   p = 25.4 / dpi mm, its grey level the exact mean of the board over it (the renderer's
//!   coverage, [`crate::render`]), 0 black and 255 white; [`encode_png`] records the dpi
//!   (the PNG `pHYs` chunk) so that printing tools know its size.

use std::fmt::Write as _;

use etl_formats::board::Board;
use etl_formats::{compact, Error, Result};
use rayon::prelude::*;

use crate::render::board::{BoardLayout, Levels};
use crate::render::{BitDepth, Image, MAX_IMAGE_SIDE_PX};

/// Largest margin accepted, mm.
pub const MAX_MARGIN_MM: f64 = 1000.0;
/// Resolutions accepted for a raster, dots per inch.
pub const DPI_RANGE: [f64; 2] = [1.0, 100_000.0];

/// Page width and height, mm: the pattern and the margin on both sides.
pub fn page_mm(board: &Board, margin_mm: f64) -> [f64; 2] {
    let [x0, y0, x1, y1] = board.pattern_mm();
    [x1 - x0 + 2.0 * margin_mm, y1 - y0 + 2.0 * margin_mm]
}

/// `margin_mm` if it is in [0, [`MAX_MARGIN_MM`]], else an error naming it.
fn check_margin(margin_mm: f64) -> Result<f64> {
    etl_formats::check_range("margin_mm", margin_mm, [0.0, MAX_MARGIN_MM], "mm")
}

/// Shortest decimal of `x` rounded to 1e-6 mm (a nanometre: far below any printer), so
/// that sums such as 3 x 1.1 print as 3.3.
fn num(x: f64) -> String {
    let r = (x * 1e6).round() / 1e6;
    format!("{}", if r == 0.0 { 0.0 } else { r })
}

/// `M x y h w v h h -w z`: a rectangle as a subpath, clockwise on the page (y down).
fn rect_path(out: &mut String, x: f64, y: f64, w: f64, h: f64) {
    let _ = write!(out, "M{} {}h{}v{}h{}z", num(x), num(y), num(w), num(h), num(-w));
}

/// The board as an SVG document at true size (module docs) with a white margin of
/// `margin_mm` around the pattern.
///
/// Errors: a margin outside [0, [`MAX_MARGIN_MM`]] mm; an invalid board.
///
/// ```
/// use etl_formats::board::Board;
/// let b = Board::charuco([5, 4], 10.0, 6.0, "DICT_4X4_50").unwrap();
/// let svg = etl_sim::print::svg(&b, 5.0).unwrap();
/// assert!(svg.contains(r#"width="60mm" height="50mm" viewBox="0 0 60 50""#));
/// assert_eq!(svg.matches("<path id=\"marker-").count(), 10);
/// ```
pub fn svg(board: &Board, margin_mm: f64) -> Result<String> {
    board.validate()?;
    let margin = check_margin(margin_mm)?;
    let [w, h] = page_mm(board, margin);
    let [x_min, y_min, ..] = board.pattern_mm();
    // Page coordinates of a board point.
    let page = |x: f64, y: f64| (x - x_min + margin, y - y_min + margin);
    let s = board.square_mm();
    let [cols, rows] = board.corner_grid().map(|n| n + 1);
    let mut out = String::new();
    let _ = writeln!(out, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        out,
        "<!-- etlcal board: {}; page {} x {} mm, margin {} mm; print at 100 % (no scaling) -->",
        board.describe(),
        num(w),
        num(h),
        compact(margin)
    );
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{0}mm" height="{1}mm" viewBox="0 0 {0} {1}">"#,
        num(w),
        num(h)
    );
    let _ = writeln!(out, r##"<rect x="0" y="0" width="{}" height="{}" fill="#ffffff"/>"##, num(w), num(h));
    // Square (c, r) of the pattern is black when c + r is even, for both kinds of board.
    let mut squares = String::new();
    for r in 0..rows {
        for c in (r % 2..cols).step_by(2) {
            let (x, y) = page(x_min + c as f64 * s, y_min + r as f64 * s);
            rect_path(&mut squares, x, y, s, s);
        }
    }
    let _ = writeln!(out, r##"<path id="squares" fill="#000000" d="{squares}"/>"##);
    if let Some(b) = board.as_charuco() {
        let n = b.dictionary().marker_bits();
        let cells = n + 2;
        let cell = b.marker_mm() / cells as f64;
        for id in 0..b.markers() as u32 {
            let Some([tl, ..]) = b.marker_corners_mm(id) else { continue };
            let dark = |row: usize, col: usize| {
                let border = row == 0 || col == 0 || row == cells - 1 || col == cells - 1;
                border || b.dictionary().is_white(id, row - 1, col - 1) == Some(false)
            };
            let mut d = String::new();
            for row in 0..cells {
                let mut col = 0;
                while col < cells {
                    if !dark(row, col) {
                        col += 1;
                        continue;
                    }
                    let start = col;
                    while col < cells && dark(row, col) {
                        col += 1;
                    }
                    let (x, y) = page(tl[0] + start as f64 * cell, tl[1] + row as f64 * cell);
                    rect_path(&mut d, x, y, (col - start) as f64 * cell, cell);
                }
            }
            let _ = writeln!(out, r##"<path id="marker-{id}" fill="#000000" d="{d}"/>"##);
        }
    }
    out.push_str("</svg>\n");
    Ok(out)
}

/// The board rasterised at `dpi` with a white margin of `margin_mm` (module docs): 8-bit,
/// round(page size x dpi / 25.4) pixels each way, every pixel the exact area mean of the
/// board over it (0 black, 255 white; beyond the page, white paper).
///
/// Errors: a dpi outside [`DPI_RANGE`], a margin outside [0, [`MAX_MARGIN_MM`]] mm, or a
/// page of more than [`MAX_IMAGE_SIDE_PX`] pixels a side; an invalid board.
///
/// ```
/// use etl_formats::board::Board;
/// // 10 px per mm: squares of 100 px, marker cells of 10 px, exactly on the pixel grid.
/// let b = Board::charuco([5, 4], 10.0, 6.0, "DICT_4X4_50").unwrap();
/// let img = etl_sim::print::raster(&b, 254.0, 5.0).unwrap();
/// assert_eq!((img.width, img.height), (600, 500));
/// assert_eq!(img.get(60, 60), Some(0)); // square (0, 0), black
/// assert_eq!(img.get(2, 2), Some(255)); // margin
/// assert!(img.data.iter().all(|&v| v == 0 || v == 255));
/// ```
pub fn raster(board: &Board, dpi: f64, margin_mm: f64) -> Result<Image> {
    board.validate()?;
    let margin = check_margin(margin_mm)?;
    let dpi = etl_formats::check_range("dpi", dpi, DPI_RANGE, "dpi")?;
    let pixel_mm = 25.4 / dpi;
    let [w_mm, h_mm] = page_mm(board, margin);
    let [w, h] = [w_mm, h_mm].map(|v| (v / pixel_mm).round());
    if !(1.0..=f64::from(MAX_IMAGE_SIDE_PX)).contains(&w) || !(1.0..=f64::from(MAX_IMAGE_SIDE_PX)).contains(&h) {
        let message = format!(
            "a page of {} x {} mm at {} dpi is {w} x {h} px: at most {MAX_IMAGE_SIDE_PX} px a side",
            num(w_mm),
            num(h_mm),
            compact(dpi)
        );
        return Err(Error::invalid_value("dpi", dpi, message));
    }
    let (w, h) = (w as usize, h as usize);
    // White paper beyond the margin too (the page may end inside the last pixel).
    let layout = BoardLayout::of(board, margin, Levels { dark: 0.0, light: 255.0, background: 255.0 });
    let [x_min, y_min, ..] = board.pattern_mm();
    let (x0, y0) = (x_min - margin, y_min - margin);
    let mut data = vec![0u16; w * h];
    data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let (ya, yb) = (y0 + y as f64 * pixel_mm, y0 + (y + 1) as f64 * pixel_mm);
        for (x, out) in row.iter_mut().enumerate() {
            let (xa, xb) = (x0 + x as f64 * pixel_mm, x0 + (x + 1) as f64 * pixel_mm);
            let level = layout
                .level_over([xa, ya], [xb, yb])
                .unwrap_or_else(|| layout.mean_over(&[[xa, ya], [xb, ya], [xb, yb], [xa, yb]]));
            *out = level.round().clamp(0.0, 255.0) as u16;
        }
    });
    Ok(Image { width: w as u32, height: h as u32, bit_depth: BitDepth::Eight, data })
}

/// The 8-bit `image` as a PNG whose `pHYs` chunk says `dpi` (in pixels per metre, as PNG
/// records it, rounded), so that it prints at its true size.
pub fn encode_png(image: &Image, dpi: f64) -> Result<Vec<u8>> {
    let dpi = etl_formats::check_range("dpi", dpi, DPI_RANGE, "dpi")?;
    let bytes: Vec<u8> = image.data.iter().map(|&v| v.min(255) as u8).collect();
    let mut out = Vec::new();
    let fail = |e: png::EncodingError| Error::invalid("image", format!("cannot encode PNG: {e}"));
    let mut enc = png::Encoder::new(&mut out, image.width, image.height);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let ppm = (dpi / 0.0254).round() as u32;
    enc.set_pixel_dims(Some(png::PixelDimensions { xppu: ppm, yppu: ppm, unit: png::Unit::Meter }));
    let mut writer = enc.write_header().map_err(fail)?;
    writer.write_image_data(&bytes).map_err(fail)?;
    writer.finish().map_err(fail)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rectangles of the SVG's black paths, page mm: (x, y, w, h).
    fn black_rects(svg: &str) -> Vec<[f64; 4]> {
        let mut rects = vec![];
        for path in svg.split("<path ").skip(1) {
            let d = path.split(" d=\"").nth(1).unwrap().split('"').next().unwrap();
            for sub in d.split('M').filter(|t| !t.is_empty()) {
                let nums: Vec<f64> = sub
                    .trim_end_matches('z')
                    .split(['h', 'v', ' '])
                    .filter(|t| !t.is_empty())
                    .map(|t| t.parse().unwrap())
                    .collect();
                assert_eq!(nums.len(), 5, "{sub}");
                assert_eq!(nums[4], -nums[2], "{sub}");
                rects.push([nums[0], nums[1], nums[2], nums[3]]);
            }
        }
        rects
    }

    /// The SVG and the raster draw the same board: point-sampling the SVG's rectangles at
    /// a pixel's centre gives the raster's level wherever the raster's pixel is uniform
    /// (whole pixels at 10 px/mm with mm-aligned cells: every pixel).
    #[test]
    fn the_svg_and_the_raster_agree_pixel_for_pixel() {
        for board in [
            Board::charuco([5, 4], 10.0, 6.0, "DICT_4X4_50").unwrap(),
            Board::charuco([4, 5], 10.0, 7.0, "DICT_5X5_100").unwrap(),
            Board::charuco([6, 5], 9.0, 8.0, "DICT_7X7_250").unwrap(),
            Board::checkerboard([4, 3], 5.0).unwrap(),
        ] {
            let svg = svg(&board, 3.0).unwrap();
            let rects = black_rects(&svg);
            let img = raster(&board, 254.0, 3.0).unwrap();
            let [w, h] = page_mm(&board, 3.0);
            assert_eq!((img.width, img.height), ((w * 10.0).round() as u32, (h * 10.0).round() as u32));
            assert!(svg.contains(&format!(r#"width="{}mm" height="{}mm""#, num(w), num(h))), "{svg}");
            let mut mixed = 0;
            for y in 0..img.height {
                for x in 0..img.width {
                    let (px, py) = ((x as f64 + 0.5) / 10.0, (y as f64 + 0.5) / 10.0);
                    let black = rects.iter().any(|r| px >= r[0] && px < r[0] + r[2] && py >= r[1] && py < r[1] + r[3]);
                    let v = img.get(x, y).unwrap();
                    if v != 0 && v != 255 {
                        mixed += 1; // a cell edge inside the pixel (7 / 9 mm cells)
                        continue;
                    }
                    assert_eq!(v == 0, black, "{} ({x}, {y})", board.describe());
                }
            }
            assert!(mixed < (img.width * img.height / 10) as usize, "{mixed}");
        }
    }

    #[test]
    fn a_pixel_across_edges_is_its_exact_area_mean() {
        // 1 px = 2.54 mm at 10 dpi: the first pixel inside the margin of 1.27 mm is half
        // margin (white), half square (0, 0) (black).
        let board = Board::checkerboard([3, 3], 2.54).unwrap();
        let img = raster(&board, 10.0, 1.27).unwrap();
        assert_eq!(img.get(0, 0), Some(191)); // a quarter black: 255 * 3 / 4 = 191.25
        assert_eq!((img.width, img.height), (5, 5));
    }

    #[test]
    fn bad_sizes_are_named() {
        let b = Board::charuco([5, 4], 10.0, 6.0, "DICT_4X4_50").unwrap();
        for (r, needle) in [
            (raster(&b, 0.0, 1.0), "dpi 0 dpi is outside"),
            (raster(&b, f64::NAN, 1.0), "dpi NaN"),
            (raster(&b, 300.0, -1.0), "margin_mm -1 mm is outside"),
            (raster(&b, 100_000.0, 1.0), "at most 32768 px a side"),
        ] {
            let e = r.unwrap_err().to_string();
            assert!(e.contains(needle), "{e}");
        }
        assert!(svg(&b, f64::INFINITY).unwrap_err().to_string().contains("margin_mm inf"));
    }

    #[test]
    fn the_png_says_its_resolution() {
        let b = Board::checkerboard([3, 3], 2.0).unwrap();
        let png = encode_png(&raster(&b, 254.0, 0.0).unwrap(), 254.0).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let reader = decoder.read_info().unwrap();
        let dims = reader.info().pixel_dims.unwrap();
        assert_eq!((dims.xppu, dims.yppu, dims.unit), (10_000, 10_000, png::Unit::Meter));
    }
}
