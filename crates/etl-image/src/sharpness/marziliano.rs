//! CPBD's edge widths (SPEC.md A.3.2 and A.4): the package's "vertical" Sobel edges
//! (octave.py L15-57) and the Marziliano width measured along image rows
//! (compute.py L53-146), counted per block as the pooling needs them.

use std::ops::Range;

use rayon::prelude::*;

/// SciPy's `reflect` index for a 3-tap filter: -1 -> 0, n -> n - 1.
#[inline(always)]
fn rf(i: isize, n: usize) -> usize {
    i.clamp(0, n as isize - 1) as usize
}

/// `64 x` the package's Sobel strength at columns `cols` of image row `r` (into `out`,
/// first column first), set to 0 where it is at most `keep_above`: `k^2` with
/// `k = conv(image, [1 0 -1; 2 0 -2; 1 0 -1])` (reflected borders), an exact integer,
/// so that comparisons of the package's floats `k^2 / 64` are those of `k^2`.
/// Needs `w >= 2`.
fn strength_row(image: &[u8], w: usize, h: usize, r: usize, cols: Range<usize>, keep_above: i32, out: &mut [i32]) {
    const CHUNK: usize = 128;
    let line = |rr: usize| &image[rr * w..rr * w + w];
    let (up, mid, down) = (line(rf(r as isize - 1, h)), line(r), line(rf(r as isize + 1, h)));
    // Column sums of the [1 2 1] smoothing (|sum| <= 1020: 16 bits), each used twice.
    let mut sums = [0i16; CHUNK + 2];
    for (start, out) in cols.clone().step_by(CHUNK).zip(out.chunks_mut(CHUNK)) {
        let n = CHUNK.min(cols.end - start).min(out.len());
        let sums = &mut sums[..n + 2];
        if start >= 1 && start + n < w {
            let span = start - 1..start + n + 1;
            let (u, m, d) = (&up[span.clone()], &mid[span.clone()], &down[span]);
            for (j, s) in sums.iter_mut().enumerate() {
                *s = u[j] as i16 + 2 * m[j] as i16 + d[j] as i16;
            }
        } else {
            for (j, s) in sums.iter_mut().enumerate() {
                let c = rf(start as isize + j as isize - 1, w);
                *s = up[c] as i16 + 2 * mid[c] as i16 + down[c] as i16;
            }
        }
        for (i, o) in out[..n].iter_mut().enumerate() {
            let k = (sums[i + 2] - sums[i]) as i32;
            let k2 = k * k;
            *o = if k2 <= keep_above { 0 } else { k2 };
        }
    }
}

/// The package's threshold `thresh2 = 2 sqrt(mean(strength2))` (octave.py L29) of a
/// `w x h` image (`w, h >= 2`).
pub fn strength_threshold(image: &[u8], w: usize, h: usize) -> f64 {
    // np.mean of the exact floats k^2/64: their sum is exact (< 2^53 / 64), then one
    // division by N, as NumPy does; an integer sum does not depend on the order.
    let sum: u64 = (0..h).into_par_iter().map(|r| strength_sum_row(image, w, h, r)).sum();
    let mean = (sum as f64 / 64.0) / (w * h) as f64;
    2.0 * mean.sqrt()
}

/// The sum of `64 x` the package's Sobel strength over image row `r` (see
/// [`strength_row`]).
fn strength_sum_row(image: &[u8], w: usize, h: usize, r: usize) -> u64 {
    let line = |rr: usize| &image[rr * w..rr * w + w];
    let (up, mid, down) = (line(rf(r as isize - 1, h)), line(r), line(rf(r as isize + 1, h)));
    let col = |c: usize| up[c] as i32 + 2 * mid[c] as i32 + down[c] as i32;
    let k2 = |c: usize| {
        let k = col(rf(c as isize + 1, w)) - col(rf(c as isize - 1, w));
        (k * k) as u64
    };
    // The two edge columns, then the interior in runs whose sum fits a u32
    // (k^2 <= 1020^2 < 2^32 / 4096).
    let mut sum = k2(0) + k2(w - 1);
    let interior = w - 2;
    for start in (0..interior).step_by(4096) {
        let n = 4096.min(interior - start);
        let (ul, ml, dl) = (&up[start..][..n], &mid[start..][..n], &down[start..][..n]);
        let (ur, mr, dr) = (&up[start + 2..][..n], &mid[start + 2..][..n], &down[start + 2..][..n]);
        let mut run = 0u32;
        for i in 0..n {
            let right = ur[i] as i16 + 2 * mr[i] as i16 + dr[i] as i16;
            let left = ul[i] as i16 + 2 * ml[i] as i16 + dl[i] as i16;
            let k = (right - left) as i32;
            run += (k * k) as u32;
        }
        sum += run as u64;
    }
    sum
}

/// Whether any pixel's `atan2(gy, gx)` is non-zero under the package's rules (angle set
/// only where gx != 0), with NumPy's one-sided differences on the border: if not, the
/// package skips the whole width pass (compute.py L88) and CPBD is 0.
pub fn any_nonzero_angle(image: &[u8], w: usize, h: usize) -> bool {
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

/// Counts of the widths measured in one block: `total` of them, and `by_width[n]` of
/// those of width `n` for `n <= jnb` (the only ones the pooling tells apart).
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct BlockWidths {
    /// Widths measured in the block (every width is at least 2).
    pub total: u64,
    /// Widths of exactly `n` px, for `n` up to the block's just-noticeable width.
    pub by_width: [u64; 6],
}

/// The widths of the Sobel edge pixels in `rows x cols` of the `w x h` image
/// (`w, h >= 3`), as the package's `marziliano_method(sobel(image), image)` measures
/// them, counted up to `jnb <= 5` px: a width above `jnb` only adds to `total`, so each
/// side's walk stops after `jnb` pixels instead of the package's 101.
/// `strength` is working memory.
pub fn block_widths(
    image: &[u8],
    w: usize,
    h: usize,
    (rows, cols): (Range<usize>, Range<usize>),
    thresh2: f64,
    jnb: usize,
    strength: &mut Vec<i32>,
) -> BlockWidths {
    let mut counts = BlockWidths::default();
    // Thresholded strengths of the rows around the block (octave.py L29-31); thinning
    // looks one pixel to each side.
    let (r0, r1) = (rows.start.saturating_sub(1), (rows.end + 1).min(h));
    let (c0, c1) = (cols.start.saturating_sub(1), (cols.end + 1).min(w));
    let sw = c1 - c0;
    // `k^2 / 64 <= thresh2` exactly when `k^2 <= floor(64 thresh2)` (both sides scaled
    // by a power of two, then the integer side rounded down).
    let keep_above = (64.0 * thresh2).floor().min(i32::MAX as f64) as i32;
    strength.clear();
    strength.resize((r1 - r0) * sw, 0);
    for (r, out) in (r0..r1).zip(strength.chunks_exact_mut(sw)) {
        strength_row(image, w, h, r, c0..c1, keep_above, out);
    }
    let px = |r: usize, c: usize| image[r * w + c];
    let cap = jnb.min(5);
    let (ca, cb) = (cols.start.max(1), cols.end.min(w - 1));
    let n = cb.saturating_sub(ca);
    // Thinning flags, padded to whole 8-byte words.
    let mut thin = vec![0u8; n.div_ceil(8) * 8];
    for r in rows.start.max(1)..rows.end.min(h - 1) {
        let row = &image[r * w..r * w + w];
        // "Simple thinning" (octave.py L35-57): strictly above both horizontal or both
        // vertical neighbours; a branch-free pass over the row, then a scan of the
        // (sparse) survivors eight at a time.
        let line = |rr: usize, dc: isize| &strength[(rr - r0) * sw + (ca as isize + dc) as usize - c0..][..n];
        let (v, left, right, up, down) = (line(r, 0), line(r, -1), line(r, 1), line(r - 1, 0), line(r + 1, 0));
        for i in 0..n {
            thin[i] = ((v[i] > left[i]) & (v[i] > right[i]) | (v[i] > up[i]) & (v[i] > down[i])) as u8;
        }
        let survivors = thin.chunks_exact(8).enumerate().flat_map(|(k, word)| {
            let mut bits = u64::from_le_bytes([word[0], word[1], word[2], word[3], word[4], word[5], word[6], word[7]]);
            std::iter::from_fn(move || {
                (bits != 0).then(|| {
                    let i = bits.trailing_zeros() as usize / 8;
                    bits &= bits - 1;
                    ca + 8 * k + i
                })
            })
        });
        for c in survivors {
            let gx2 = px(r, c + 1) as i32 - px(r, c - 1) as i32;
            let gy2 = px(r + 1, c) as i32 - px(r - 1, c) as i32;
            let rising = match direction(gx2, gy2) {
                Direction::Rising => true,
                Direction::Falling => false,
                Direction::Other => continue,
            };
            counts.total += 1;
            let width = walk_left(row, c, rising, cap) + walk_right(row, c, rising, cap);
            if width <= cap {
                counts.by_width[width] += 1;
            }
        }
    }
    counts
}

/// The package's quantised gradient direction of an edge pixel (compute.py L69-91).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Direction {
    /// Quantised angle 0: intensity rising left to right (or `gx = 0`).
    Rising,
    /// Quantised angle +-180: falling left to right.
    Falling,
    /// +-45, +-90 or +-135: no width.
    Other,
}

/// The direction of twice the `np.gradient` central differences, `gx2 = 2 gx` and
/// `gy2 = 2 gy`. The package computes `angle = degrees(atan2(gy, gx))` (0 where
/// `gx == 0`) and `45 round(angle / 45)` with half-to-even rounding: quantised angle 0
/// exactly when `|angle| <= 22.5`, +-180 when `|angle| >= 157.5`. For integers the true
/// angle is never within 1e-6 of those bounds, far more than the rounding of the
/// floating-point expression, so the integer test `|gy2| < (sqrt 2 - 1) |gx2|`, i.e.
/// `(|gy2| + |gx2|)^2 < 2 gx2^2`, decides the same (checked over every pair of 8-bit
/// differences in the tests).
fn direction(gx2: i32, gy2: i32) -> Direction {
    if gx2 == 0 {
        return Direction::Rising;
    }
    let s = gy2.abs() + gx2.abs();
    if s * s >= 2 * gx2 * gx2 {
        Direction::Other
    } else if gx2 > 0 {
        Direction::Rising
    } else {
        Direction::Falling
    }
}

/// `1 +` the number of further steps left of `c - 1` over which the intensity keeps
/// falling (rising edge) or rising (falling edge) towards the left (compute.py L98-144),
/// or `cap + 1` if that is more.
fn walk_left(row: &[u8], c: usize, rising: bool, cap: usize) -> usize {
    let mut m = 0;
    while m < cap {
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
fn walk_right(row: &[u8], c: usize, rising: bool, cap: usize) -> usize {
    let mut m = 0;
    while m < cap {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The package's expression in floating point, as compute.py L78-91 evaluates it.
    fn direction_by_angle(gx2: i32, gy2: i32) -> Direction {
        let (gx, gy) = (gx2 as f64 / 2.0, gy2 as f64 / 2.0);
        let angle = if gx != 0.0 { gy.atan2(gx) * (180.0 / std::f64::consts::PI) } else { 0.0 };
        let q = (angle / 45.0).round_ties_even();
        if q == 0.0 {
            Direction::Rising
        } else if q == 4.0 || q == -4.0 {
            Direction::Falling
        } else {
            Direction::Other
        }
    }

    #[test]
    fn integer_direction_equals_the_quantised_angle_for_every_8bit_gradient() {
        let mut seen = [0usize; 3];
        for gx2 in -255..=255 {
            for gy2 in -255..=255 {
                let d = direction(gx2, gy2);
                assert_eq!(d, direction_by_angle(gx2, gy2), "gx2 {gx2} gy2 {gy2}");
                seen[d as usize] += 1;
            }
        }
        // Every class occurs (the test is not vacuous).
        assert!(seen.iter().all(|&n| n > 10_000), "{seen:?}");
    }

    /// The widths of a block with the package's full walks (each side up to 101 px).
    fn full_widths(image: &[u8], w: usize, h: usize, (bi, bj): (usize, usize), thresh2: f64) -> Vec<usize> {
        let mut strength = vec![0i32; w * h];
        for (r, out) in strength.chunks_exact_mut(w).enumerate() {
            strength_row(image, w, h, r, 0..w, 0, out);
        }
        let s = |r: usize, c: usize| if strength[r * w + c] as f64 / 64.0 <= thresh2 { 0 } else { strength[r * w + c] };
        let mut widths = Vec::new();
        for r in (bi * 64..bi * 64 + 64).filter(|&r| r >= 1 && r + 1 < h) {
            for c in (bj * 64..bj * 64 + 64).filter(|&c| c >= 1 && c + 1 < w) {
                let v = s(r, c);
                if !((v > s(r, c - 1) && v > s(r, c + 1)) || (v > s(r - 1, c) && v > s(r + 1, c))) {
                    continue;
                }
                let gx2 = image[r * w + c + 1] as i32 - image[r * w + c - 1] as i32;
                let gy2 = image[(r + 1) * w + c] as i32 - image[(r - 1) * w + c] as i32;
                let rising = match direction_by_angle(gx2, gy2) {
                    Direction::Rising => true,
                    Direction::Falling => false,
                    Direction::Other => continue,
                };
                let row = &image[r * w..r * w + w];
                widths.push(walk_left(row, c, rising, 100) + walk_right(row, c, rising, 100));
            }
        }
        widths
    }

    #[test]
    fn widths_counted_up_to_the_jnb_equal_the_full_walks() {
        for name in ["camera.png", "board_s1.5_n2.png"] {
            let (img, w, h) = crate::sharpness::canny::tests::fixture(name);
            let thresh2 = strength_threshold(&img, w, h);
            let mut long = 0;
            for bi in 0..h / 64 {
                for bj in 0..w / 64 {
                    let full = full_widths(&img, w, h, (bi, bj), thresh2);
                    long += full.iter().filter(|&&n| n > 10).count();
                    for jnb in [3, 5] {
                        let span = (bi * 64..bi * 64 + 64, bj * 64..bj * 64 + 64);
                        let got = block_widths(&img, w, h, span, thresh2, jnb, &mut Vec::new());
                        assert_eq!(got.total, full.len() as u64);
                        for n in 0..6 {
                            let want = if n <= jnb { full.iter().filter(|&&x| x == n).count() } else { 0 };
                            assert_eq!(got.by_width[n], want as u64, "{name} block {bi}, {bj}, jnb {jnb}, width {n}");
                        }
                    }
                }
            }
            // Walks longer than the cap occur (the test is not vacuous).
            assert!(long > 0, "{name}");
        }
    }
}
