//! A heat map of values on a grid as a PNG: `etlcal diff --heatmap`.

use crate::{Error, Result};

/// The colour of `t` in 0..=1 on a ramp from dark blue through teal and green to yellow
/// (the ends and middle of matplotlib's viridis), linear between them.
fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] =
        [[68.0, 1.0, 84.0], [59.0, 82.0, 139.0], [33.0, 145.0, 140.0], [94.0, 201.0, 98.0], [253.0, 231.0, 37.0]];
    let x = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    core::array::from_fn(|c| (STOPS[i][c] + f * (STOPS[i + 1][c] - STOPS[i][c])).round() as u8)
}

/// `values` (row-major, `cols` x `rows`) as a PNG of `cell_px` pixels a cell, 0 dark blue
/// and `max` (or more) yellow; a value that is not finite is grey. Errors: `values` not
/// `cols * rows` long, an empty grid, `max` not finite and > 0, an image above 2^26 px.
pub fn heat_map_png(values: &[f64], cols: usize, rows: usize, max: f64, cell_px: u32) -> Result<Vec<u8>> {
    let (w, h) = (cols as u64 * u64::from(cell_px), rows as u64 * u64::from(cell_px));
    if values.len() != cols * rows || w == 0 || h == 0 || w * h > 1 << 26 {
        return Err(Error::invalid("heat map", format!("heat map of {cols} x {rows} cells of {cell_px} px: bad size")));
    }
    if !(max > 0.0 && max.is_finite()) {
        return Err(Error::invalid("heat map", format!("heat map scale {max} must be finite and > 0")));
    }
    let img = image::RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let v = values[(y / cell_px) as usize * cols + (x / cell_px) as usize];
        image::Rgb(if v.is_finite() { ramp(v / max) } else { [128, 128, 128] })
    });
    let mut png = std::io::Cursor::new(vec![]);
    img.write_to(&mut png, image::ImageFormat::Png)
        .map_err(|e| Error::invalid("heat map", format!("heat map PNG encoding: {e}")))?;
    Ok(png.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_take_their_colour_and_bad_sizes_are_refused() {
        let png = heat_map_png(&[0.0, 1.0, f64::NAN, 2.0], 2, 2, 1.0, 3).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (6, 6));
        assert_eq!(img.get_pixel(0, 0).0, [68, 1, 84]);
        assert_eq!(img.get_pixel(5, 0).0, [253, 231, 37]);
        assert_eq!(img.get_pixel(0, 5).0, [128, 128, 128]);
        assert_eq!(img.get_pixel(5, 5).0, [253, 231, 37], "clamped at max");
        assert_eq!(ramp(0.5), [33, 145, 140]);
        assert!(heat_map_png(&[1.0], 2, 2, 1.0, 3).is_err());
        assert!(heat_map_png(&[1.0], 1, 1, 0.0, 3).is_err());
    }
}
