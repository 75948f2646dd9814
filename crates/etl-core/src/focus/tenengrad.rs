//! Tenengrad: the mean squared Sobel gradient magnitude (Tenenbaum 1970; Krotkov 1987).

use super::image::{ImageView, Pixel};
use crate::error::Result;

/// Tenengrad of `image`: the mean over the interior pixels (one-pixel border excluded)
/// of `Gx^2 + Gy^2`, with the unnormalised 3 x 3 Sobel kernels
/// `Gx = [1 0 -1; 2 0 -2; 1 0 -1]` (sign irrelevant) and its transpose, in squared grey
/// levels of the image's own scale (a 16-bit image gives 65 536 times the value of the
/// same scene at 8 bits). No threshold is applied, so the measure is smooth in the focus.
///
/// Sums are exact integers; only the final division rounds.
///
/// Errors: fewer than 3 rows or columns ([`Error::TooFew`](crate::Error::TooFew)).
///
/// ```
/// use etl_core::focus::{tenengrad, ImageView};
/// // A vertical step of 100 grey levels: |Gx| = 400 on the two columns next to it.
/// let px: [u8; 16] = [0, 0, 100, 100, 0, 0, 100, 100, 0, 0, 100, 100, 0, 0, 100, 100];
/// let t = tenengrad(&ImageView::packed(&px, 4, 4).unwrap()).unwrap();
/// assert_eq!(t, 160_000.0);
/// ```
pub fn tenengrad<T: Pixel>(image: &ImageView<'_, T>) -> Result<f64> {
    image.require_side(3, "image rows and columns for Tenengrad")?;
    let mut total: u128 = 0;
    for y in 1..image.height() - 1 {
        let (r0, r1, r2) = (image.row(y - 1), image.row(y), image.row(y + 1));
        let mut row_sum: u64 = 0;
        for ((a, b), c) in r0.windows(3).zip(r1.windows(3)).zip(r2.windows(3)) {
            let (&[a0, a1, a2], &[b0, _, b2], &[c0, c1, c2]) = (a, b, c) else { continue };
            let (a0, a1, a2) = (a0.level(), a1.level(), a2.level());
            let (b0, b2) = (b0.level(), b2.level());
            let (c0, c1, c2) = (c0.level(), c1.level(), c2.level());
            let gx = (a2 + 2 * b2 + c2) - (a0 + 2 * b0 + c0);
            let gy = (c0 + 2 * c1 + c2) - (a0 + 2 * a1 + a2);
            row_sum += (gx * gx + gy * gy) as u64;
        }
        total += row_sum as u128;
    }
    let n = (image.width() - 2) * (image.height() - 2);
    Ok(total as f64 / n as f64)
}
