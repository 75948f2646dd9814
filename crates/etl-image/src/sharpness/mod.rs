//! Sharpness of an image: CPBD (exactly as the reference package `cpbd` 1.0.7) and the
//! four gradient/statistics measures of `etl_core::focus`.
//!
//! 16-bit images: the simple measures run on the 16-bit grey levels as they are (their
//! values scale with the square of the gain, see `etl_core::focus`). CPBD is defined on
//! the 0..255 scale (its just-noticeable-width contrast split at 50 grey levels, the
//! absolute Canny thresholds 0.1 and 0.2, the package's 256-entry width table that raises
//! `IndexError` on 16-bit data), so [`sharpness_u16`] converts to 8 bits first with
//! `round(v / 257)`, the exact inverse of the usual 8-to-16-bit scaling `v * 257`: an
//! 8-bit image widened that way gives the same CPBD.

use std::path::Path;
use std::str::FromStr;

use etl_core::focus::{brenner, laplacian_variance, normalised_variance, tenengrad, ImageView, Pixel};
use image::{DynamicImage, GrayImage, ImageBuffer, Luma};

use etl_formats::{Error, Result};

mod canny;
pub mod cpbd;
mod hysteresis;
mod marziliano;

/// A 16-bit grayscale image.
pub type Gray16Image = ImageBuffer<Luma<u16>, Vec<u16>>;

/// A sharpness measure (larger is sharper for every one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Metric {
    /// CPBD in [0, 1] ([`cpbd::cpbd`]); CLI name `cpbd`.
    Cpbd,
    /// Mean squared Sobel magnitude ([`etl_core::focus::tenengrad()`]); `tenengrad`.
    Tenengrad,
    /// Variance of the Laplacian ([`etl_core::focus::laplacian_variance`]); `laplacian`.
    Laplacian,
    /// Brenner gradient, both directions ([`etl_core::focus::brenner()`]); `brenner`.
    Brenner,
    /// Normalised variance ([`etl_core::focus::normalised_variance`]); `normvar`.
    Normvar,
}

impl Metric {
    /// Every measure, in the order of the CLI help.
    pub const ALL: [Metric; 5] = [Metric::Cpbd, Metric::Tenengrad, Metric::Laplacian, Metric::Brenner, Metric::Normvar];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Metric::Cpbd => "cpbd",
            Metric::Tenengrad => "tenengrad",
            Metric::Laplacian => "laplacian",
            Metric::Brenner => "brenner",
            Metric::Normvar => "normvar",
        }
    }
}

impl FromStr for Metric {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        Metric::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            Error::invalid_value(
                "metric",
                s,
                format!(
                    "unknown sharpness metric \"{s}\" (expected one of cpbd, tenengrad, laplacian, brenner, normvar)"
                ),
            )
        })
    }
}

impl std::fmt::Display for Metric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

fn simple<T: Pixel>(data: &[T], w: u32, h: u32, metric: Metric) -> Result<f64> {
    let view = ImageView::packed(data, w as usize, h as usize)?;
    Ok(match metric {
        Metric::Tenengrad => tenengrad(&view)?,
        Metric::Laplacian => laplacian_variance(&view)?,
        Metric::Brenner => brenner(&view)?,
        Metric::Normvar => normalised_variance(&view)?,
        Metric::Cpbd => return Err(Error::invalid_value("metric", "cpbd", "CPBD is not a simple measure")),
    })
}

/// The sharpness of an 8-bit grayscale image by `metric`.
///
/// Errors: an empty image or one too small for the measure (3 x 3 for the gradient
/// measures, one 64 x 64 block for CPBD), an all-black image for `normvar`
/// ([`Error::Core`] or [`Error::InvalidInput`], naming the precondition).
///
/// ```
/// use etl_image::sharpness::{sharpness, Metric};
/// let img = image::GrayImage::from_fn(96, 80, |x, y| image::Luma([if (x / 16 + y / 16) % 2 == 0 { 40 } else { 210 }]));
/// assert!(sharpness(&img, Metric::Tenengrad).unwrap() > 0.0);
/// let cpbd = sharpness(&img, Metric::Cpbd).unwrap();
/// assert!((0.0..=1.0).contains(&cpbd));
/// ```
pub fn sharpness(image: &GrayImage, metric: Metric) -> Result<f64> {
    let (w, h) = image.dimensions();
    match metric {
        Metric::Cpbd => cpbd::cpbd(image.as_raw(), w as usize, h as usize),
        m => simple(image.as_raw(), w, h, m),
    }
}

/// The sharpness of a 16-bit grayscale image by `metric`: the simple measures on the
/// 16-bit levels, CPBD on `round(v / 257)` (see the module documentation).
///
/// Errors: as [`sharpness`].
pub fn sharpness_u16(image: &Gray16Image, metric: Metric) -> Result<f64> {
    let (w, h) = image.dimensions();
    match metric {
        Metric::Cpbd => {
            let eight: Vec<u8> = image.as_raw().iter().map(|&v| to_8bit(v)).collect();
            cpbd::cpbd(&eight, w as usize, h as usize)
        }
        m => simple(image.as_raw(), w, h, m),
    }
}

/// `round(v / 257)` in integers (257 * 255 = 65535, so the result is at most 255).
fn to_8bit(v: u16) -> u8 {
    ((v as u32 + 128) / 257) as u8
}

/// The sharpness of the image file at `path` by `metric`: 8-bit grey as is, 16-bit grey
/// by [`sharpness_u16`], colour after conversion to luminance (the `image` crate's
/// `to_luma8`/`to_luma16`: the reference CPBD package does no colour conversion and must
/// be given the same grey image to agree). Errors name the file.
pub fn sharpness_file(path: &Path, metric: Metric) -> Result<f64> {
    let img = crate::read_image(path)?;
    let in_file = |e: Error| Error::Image { path: path.to_owned(), message: e.to_string() };
    match img {
        DynamicImage::ImageLuma8(g) => sharpness(&g, metric),
        DynamicImage::ImageLuma16(g) => sharpness_u16(&g, metric),
        other if other.color().bytes_per_pixel() / other.color().channel_count() > 1 => {
            sharpness_u16(&other.to_luma16(), metric)
        }
        other => sharpness(&other.to_luma8(), metric),
    }
    .map_err(in_file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eight_bit_conversion_inverts_the_widening() {
        for v in 0..=255u8 {
            assert_eq!(to_8bit(v as u16 * 257), v);
        }
        assert_eq!(to_8bit(128), 0);
        assert_eq!(to_8bit(129), 1);
        assert_eq!(to_8bit(65535), 255);
    }
}
