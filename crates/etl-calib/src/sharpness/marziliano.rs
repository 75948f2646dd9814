//! CPBD's edge widths (SPEC.md A.3.2 and A.4): the package's "vertical" Sobel edges and
//! the Marziliano width measured along image rows.

use rayon::prelude::*;

/// Each side of a width is capped at this many pixels (the package's `margin` runs 0..100).
const MAX_SIDE: usize = 101;

/// The width map of `image` (row-major `h x w` 8-bit grey levels): 0 where there is no
/// width, else the Marziliano width (2..=202) of the edge pixel, exactly as the package's
/// `marziliano_method(sobel(image), image)` computes it. Needs `w, h >= 2`.
pub fn edge_widths(image: &[u8], w: usize, h: usize) -> Vec<u8> {
    let mut widths = vec![0u8; w * h];
    if !any_nonzero_angle(image, w, h) {
        // The package skips the whole width pass when every gradient angle is 0.
        return widths;
    }
    let strength = thresholded_strength(image, w, h);
    let px = |r: usize, c: usize| image[r * w + c];
    let s = |r: usize, c: usize| strength[r * w + c];
    widths.par_chunks_mut(w).enumerate().skip(1).take(h.saturating_sub(2)).for_each(|(r, out)| {
        for c in 1..w.saturating_sub(1) {
            let v = s(r, c);
            // "Simple thinning": strictly above both horizontal or both vertical neighbours.
            if !((v > s(r, c - 1) && v > s(r, c + 1)) || (v > s(r - 1, c) && v > s(r + 1, c))) {
                continue;
            }
            // np.gradient: central differences; the package's angle, quantised to 45 deg.
            let gx = (px(r, c + 1) as f64 - px(r, c - 1) as f64) / 2.0;
            let gy = (px(r + 1, c) as f64 - px(r - 1, c) as f64) / 2.0;
            let angle = if gx != 0.0 { gy.atan2(gx) * (180.0 / std::f64::consts::PI) } else { 0.0 };
            let q = (angle / 45.0).round_ties_even();
            let rising = if q == 0.0 {
                true
            } else if q == 4.0 || q == -4.0 {
                false
            } else {
                continue;
            };
            let row = &image[r * w..r * w + w];
            out[c] = (walk_left(row, c, rising) + walk_right(row, c, rising)) as u8;
        }
    });
    widths
}

/// `1 +` the number of further steps left of `c - 1` over which the intensity keeps
/// falling (rising edge) or rising (falling edge) towards the left, capped at 101.
fn walk_left(row: &[u8], c: usize, rising: bool) -> usize {
    let mut m = 0;
    while m < MAX_SIDE - 1 {
        let (Some(inner), Some(outer)) = (c.checked_sub(1 + m), c.checked_sub(2 + m)) else { break };
        let (i, o) = (row[inner], row[outer]);
        if if rising { o >= i } else { o <= i } {
            break;
        }
        m += 1;
    }
    m + 1
}

/// The mirror of [`walk_left`] to the right of `c + 1`.
fn walk_right(row: &[u8], c: usize, rising: bool) -> usize {
    let mut m = 0;
    while m < MAX_SIDE - 1 {
        let (inner, outer) = (c + 1 + m, c + 2 + m);
        if outer >= row.len() {
            break;
        }
        let (i, o) = (row[inner], row[outer]);
        if if rising { o <= i } else { o >= i } {
            break;
        }
        m += 1;
    }
    m + 1
}

/// Whether any pixel's `atan2(gy, gx)` is non-zero under the package's rules (angle set
/// only where gx != 0), with NumPy's one-sided differences on the border.
fn any_nonzero_angle(image: &[u8], w: usize, h: usize) -> bool {
    let px = |r: usize, c: usize| image[r * w + c] as i32;
    // Twice the gradients: exact integers, same signs and zeros.
    let grad2 = |r: usize, c: usize| -> (i32, i32) {
        let gx = if c == 0 {
            2 * (px(r, 1) - px(r, 0))
        } else if c == w - 1 {
            2 * (px(r, c) - px(r, c - 1))
        } else {
            px(r, c + 1) - px(r, c - 1)
        };
        let gy = if r == 0 {
            2 * (px(1, c) - px(0, c))
        } else if r == h - 1 {
            2 * (px(r, c) - px(r - 1, c))
        } else {
            px(r + 1, c) - px(r - 1, c)
        };
        (gx, gy)
    };
    (0..h).into_par_iter().any(|r| {
        (0..w).any(|c| {
            let (gx, gy) = grad2(r, c);
            gx != 0 && (gy != 0 || gx < 0)
        })
    })
}

/// The package's Sobel strength `(conv(image, [1 0 -1; 2 0 -2; 1 0 -1] / 8))^2` with
/// reflected borders, set to 0 where it is `<= 2 sqrt(mean)`. Returned as the exact
/// integers `64 x strength` (so comparisons are those of the floats).
fn thresholded_strength(image: &[u8], w: usize, h: usize) -> Vec<u32> {
    let rf = |i: isize, n: usize| -> usize {
        if i < 0 {
            0
        } else if i as usize >= n {
            n - 1
        } else {
            i as usize
        }
    };
    let mut k2 = vec![0u32; w * h];
    k2.par_chunks_mut(w).enumerate().for_each(|(r, out)| {
        let up = &image[rf(r as isize - 1, h) * w..][..w];
        let mid = &image[r * w..][..w];
        let down = &image[rf(r as isize + 1, h) * w..][..w];
        let col = |c: usize| up[c] as i32 + 2 * mid[c] as i32 + down[c] as i32;
        for (c, o) in out.iter_mut().enumerate() {
            let k = col(rf(c as isize + 1, w)) - col(rf(c as isize - 1, w));
            *o = (k * k) as u32;
        }
    });
    // np.mean of the exact floats k^2/64: their sum is exact (< 2^53 / 64), then one
    // division by N, as NumPy does.
    let sum: u64 = k2.par_iter().map(|&v| v as u64).sum();
    let mean = (sum as f64 / 64.0) / (w * h) as f64;
    let thresh2 = 2.0 * mean.sqrt();
    k2.par_iter_mut().for_each(|v| {
        if (*v as f64 / 64.0) <= thresh2 {
            *v = 0;
        }
    });
    k2
}
