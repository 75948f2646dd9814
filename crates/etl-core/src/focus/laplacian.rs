//! Variance of the Laplacian (Pech-Pacheco et al. 2000).

use super::image::{ImageView, Pixel};
use crate::error::Result;

/// Variance of the Laplacian of `image`: the population variance, over the interior
/// pixels (one-pixel border excluded), of the 4-neighbour Laplacian
/// `L = I(x-1,y) + I(x+1,y) + I(x,y-1) + I(x,y+1) - 4 I(x,y)`, in squared grey levels.
///
/// This is OpenCV's `cv2.Laplacian(img, cv2.CV_64F).var()` except at the border, which
/// OpenCV fills by reflection and this function leaves out. Sums are exact integers.
///
/// Errors: fewer than 3 rows or columns ([`Error::TooFew`](crate::Error::TooFew)).
///
/// ```
/// use etl_core::focus::{laplacian_variance, ImageView};
/// // One bright pixel in the middle of a 3 x 3 image: a single Laplacian value.
/// let px: [u8; 9] = [0, 0, 0, 0, 10, 0, 0, 0, 0];
/// let v = laplacian_variance(&ImageView::packed(&px, 3, 3).unwrap()).unwrap();
/// assert_eq!(v, 0.0);
/// ```
pub fn laplacian_variance<T: Pixel>(image: &ImageView<'_, T>) -> Result<f64> {
    image.require_side(3, "image rows and columns for the variance of the Laplacian")?;
    let (mut s1, mut s2): (i128, u128) = (0, 0);
    for y in 1..image.height() - 1 {
        let (r0, r1, r2) = (image.row(y - 1), image.row(y), image.row(y + 1));
        let (mut row_s1, mut row_s2): (i64, u64) = (0, 0);
        let up = r0.get(1..).unwrap_or(&[]);
        let down = r2.get(1..).unwrap_or(&[]);
        for ((m, &u), &d) in r1.windows(3).zip(up).zip(down) {
            let &[l, c, r] = m else { continue };
            let lap = l.level() + r.level() + u.level() + d.level() - 4 * c.level();
            row_s1 += lap;
            row_s2 += (lap * lap) as u64;
        }
        s1 += row_s1 as i128;
        s2 += row_s2 as u128;
    }
    let n = ((image.width() - 2) * (image.height() - 2)) as u128;
    // n * S2 - S1^2 >= 0 exactly (Cauchy-Schwarz), so the subtraction is safe in u128.
    let num = n * s2 - (s1 * s1) as u128;
    let nf = n as f64;
    Ok(num as f64 / nf / nf)
}
