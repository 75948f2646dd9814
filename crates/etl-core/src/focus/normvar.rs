//! Normalised variance (Groen, Young and Ligthart 1985).

use super::image::{ImageView, Pixel};
use crate::error::{Error, Result};

/// Normalised variance of `image`: the population variance of the grey levels divided by
/// their mean, `sum((I - mu)^2) / (N mu)`, in grey levels. Dividing by the mean makes it
/// insensitive to a change of illumination (to first order), unlike the plain variance.
/// Sums are exact integers.
///
/// Errors: an all-black image, whose mean is 0 ([`Error::Degenerate`]).
///
/// ```
/// use etl_core::focus::{normalised_variance, ImageView};
/// let px: [u8; 4] = [10, 30, 10, 30]; // mean 20, variance 100
/// let v = normalised_variance(&ImageView::packed(&px, 2, 2).unwrap()).unwrap();
/// assert_eq!(v, 5.0);
/// ```
pub fn normalised_variance<T: Pixel>(image: &ImageView<'_, T>) -> Result<f64> {
    let (mut s1, mut s2): (u128, u128) = (0, 0);
    for y in 0..image.height() {
        let (mut row_s1, mut row_s2): (u64, u64) = (0, 0);
        for &p in image.row(y) {
            let v = p.level() as u64;
            row_s1 += v;
            row_s2 += v * v;
        }
        s1 += row_s1 as u128;
        s2 += row_s2 as u128;
    }
    if s1 == 0 {
        return Err(Error::Degenerate { what: "image is black (mean 0): normalised variance is undefined" });
    }
    let n = (image.width() * image.height()) as u128;
    // N * var * N = N * S2 - S1^2 and N * mu = S1, so var / mu = (N S2 - S1^2) / (N S1).
    let num = n * s2 - s1 * s1;
    Ok(num as f64 / (n as f64 * s1 as f64))
}
