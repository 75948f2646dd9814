//! Step 1: the dark pixels, by an adaptive mean threshold.
//!
//! A pixel is dark when it is darker than the mean of the `(2 r + 1)^2` square around it
//! (clipped to the image) by more than an offset: a marker's black border is dark wherever
//! the white margin around it is within `r`, whatever the lighting across the image, while
//! the middle of a large black square (its neighbourhood as dark as itself) is not. The
//! box mean is a vertical then a horizontal running sum, bands of rows in parallel (rayon).

use rayon::prelude::*;

use crate::grey::Plane;

/// A binary image: `data[y * width + x]` is true for a dark pixel.
pub(crate) struct Mask {
    pub width: usize,
    pub height: usize,
    pub data: Vec<bool>,
}

impl Mask {
    /// Whether (x, y) is inside the image and dark.
    #[inline(always)]
    pub fn dark(&self, x: isize, y: isize) -> bool {
        x >= 0
            && y >= 0
            && (x as usize) < self.width
            && (y as usize) < self.height
            && self.data[y as usize * self.width + x as usize]
    }
}

/// Rows per band of the parallel pass.
const BAND_ROWS: usize = 32;

/// The dark pixels of `p`: `p < mean - offset` over the `(2 radius + 1)^2` square (grey
/// levels on the 8-bit scale).
pub(crate) fn dark_mask(p: &Plane, radius: usize, offset: f32) -> Mask {
    let (w, h) = (p.width, p.height);
    let mut data = vec![false; w * h];
    if w == 0 || h == 0 {
        return Mask { width: w, height: h, data };
    }
    data.par_chunks_mut(BAND_ROWS * w).enumerate().for_each(|(band, out)| {
        let y_start = band * BAND_ROWS;
        // Column sums over rows [lo, hi) of the window of the current row.
        let mut col = vec![0.0f32; w];
        let (mut lo, mut hi) = (y_start.saturating_sub(radius), y_start.saturating_sub(radius));
        let mut row_sum = vec![0.0f32; w + 1];
        for (dy, out_row) in out.chunks_exact_mut(w).enumerate() {
            let y = y_start + dy;
            let (want_lo, want_hi) = (y.saturating_sub(radius), (y + radius + 1).min(h));
            while hi < want_hi {
                col.iter_mut().zip(&p.data[hi * w..(hi + 1) * w]).for_each(|(c, v)| *c += v);
                hi += 1;
            }
            while lo < want_lo {
                col.iter_mut().zip(&p.data[lo * w..(lo + 1) * w]).for_each(|(c, v)| *c -= v);
                lo += 1;
            }
            // Prefix sums along the row: the window's sum is a difference of two.
            for x in 0..w {
                row_sum[x + 1] = row_sum[x] + col[x];
            }
            let rows = (hi - lo) as f32;
            let src = &p.data[y * w..(y + 1) * w];
            for (x, (o, &v)) in out_row.iter_mut().zip(src).enumerate() {
                let (x0, x1) = (x.saturating_sub(radius), (x + radius + 1).min(w));
                let mean = (row_sum[x1] - row_sum[x0]) / (rows * (x1 - x0) as f32);
                *o = v < mean - offset;
            }
        }
    });
    Mask { width: w, height: h, data }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A black square on white: its rim is dark, its middle (farther than the radius from
    /// the white) is not, the white is not.
    #[test]
    fn rim_of_a_large_dark_square_is_dark_its_middle_not() {
        let (w, h) = (40, 40);
        let data = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (10..30).contains(&x) && (10..30).contains(&y) {
                    40.0
                } else {
                    210.0
                }
            })
            .collect();
        let m = dark_mask(&Plane { width: w, height: h, data }, 3, 7.0);
        assert!(m.dark(10, 10) && m.dark(29, 20) && m.dark(12, 20));
        assert!(!m.dark(20, 20), "the middle is as dark as its neighbourhood");
        assert!(!m.dark(9, 20) && !m.dark(0, 0) && !m.dark(-1, 5));
    }
}
