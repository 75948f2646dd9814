//! The Brenner gradient (Brenner et al. 1976), in both directions.

use super::image::{ImageView, Pixel};
use crate::error::Result;

/// Brenner gradient of `image`: the mean of `(I(x+2,y) - I(x,y))^2` over all
/// `height * (width - 2)` horizontal pairs plus the mean of `(I(x,y+2) - I(x,y))^2` over
/// all `(height - 2) * width` vertical pairs, in squared grey levels. The classic measure
/// is the horizontal term alone; adding the vertical one makes it see horizontal edges
/// too and leaves it unchanged under a 90 degree rotation. No threshold is applied.
///
/// Errors: fewer than 3 rows or columns ([`Error::TooFew`](crate::Error::TooFew)).
///
/// ```
/// use etl_core::focus::{brenner, ImageView};
/// // A bright right-hand column: each row's pair (0, 10) gives 100, each column's 0.
/// let px: [u8; 9] = [0, 0, 10, 0, 0, 10, 0, 0, 10];
/// assert_eq!(brenner(&ImageView::packed(&px, 3, 3).unwrap()).unwrap(), 100.0);
/// ```
pub fn brenner<T: Pixel>(image: &ImageView<'_, T>) -> Result<f64> {
    image.require_side(3, "image rows and columns for the Brenner gradient")?;
    let (w, h) = (image.width(), image.height());
    let (mut horizontal, mut vertical): (u128, u128) = (0, 0);
    for y in 0..h {
        let row = image.row(y);
        let mut row_h: u64 = 0;
        for (&a, &b) in row.iter().zip(row.get(2..).unwrap_or(&[])) {
            let d = b.level() - a.level();
            row_h += (d * d) as u64;
        }
        horizontal += row_h as u128;
        if y + 2 < h {
            let mut row_v: u64 = 0;
            for (&a, &b) in row.iter().zip(image.row(y + 2)) {
                let d = b.level() - a.level();
                row_v += (d * d) as u64;
            }
            vertical += row_v as u128;
        }
    }
    let n_h = (h * (w - 2)) as f64;
    let n_v = ((h - 2) * w) as f64;
    Ok(horizontal as f64 / n_h + vertical as f64 / n_v)
}
