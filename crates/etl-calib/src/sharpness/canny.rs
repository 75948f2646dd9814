//! Canny edges exactly as `skimage.feature.canny(image)` computes them with its defaults
//! (scikit-image 0.26, SciPy 1.17) on a float64 image of 0..255 grey levels, as CPBD's
//! block classifier calls it (SPEC.md A.3.1). Every floating-point operation is done in
//! the order SciPy's C filters and scikit-image's Cython do it, so the edge map is
//! identical, not merely close:
//!
//! 1. Gaussian, sigma 1, radius 4, `mode='constant'` (zeros outside): SciPy's
//!    `gaussian_filter` (axis 0, then axis 1; symmetric `correlate1d`:
//!    `x0 w0 + (x-4 + x+4) w4 + ... + (x-1 + x+1) w1`), divided by the same filter of an
//!    all-ones image plus machine epsilon (scikit-image's "bleed-over" correction).
//! 2. `ndimage.sobel` with `mode='reflect'` along each axis: `[-1 0 1]` along it, then
//!    `[1 2 1]` across it; magnitude `sqrt(i^2 + j^2)`.
//! 3. Bilinear non-maximum suppression on the interior (the outer pixel ring is masked),
//!    keeping magnitudes `>= 0.1` (scikit-image passes the low threshold as a C `float`,
//!    so the test is against `0.1f32`).
//! 4. Hysteresis: 8-connected groups of kept pixels that contain a magnitude `>= 0.2`.

use rayon::prelude::*;

/// SciPy's sigma-1 Gaussian taps at distances 0..=4
/// (`scipy.ndimage._filters._gaussian_kernel1d(1.0, 0, 4)`, NumPy 2.4 on x86-64; the
/// values are the correctly rounded normalised `exp(-x^2/2)`).
const GAUSS: [f64; 5] = [
    0.398_943_469_357_097_76,
    0.241_971_445_656_600_73,
    0.053_991_127_420_704_41,
    0.004_431_861_620_031_265_5,
    0.000_133_830_624_614_741_75,
];

/// scikit-image's default low threshold as the C `float` its Cython receives.
const LOW: f64 = 0.1f32 as f64;
/// scikit-image's default high threshold (compared in Python, as a double).
const HIGH: f64 = 0.2;

/// Pixel classes of the non-maximum-suppressed magnitude.
const NONE: u8 = 0;
const LOW_ONLY: u8 = 1;
const STRONG: u8 = 2;
/// A weak pixel reached from a strong one by the hysteresis.
const LINKED: u8 = 3;

/// One SciPy symmetric 9-tap correlation output from the centre and the four pairs.
#[inline(always)]
fn gauss_tap(x0: f64, pairs: [f64; 4]) -> f64 {
    // pairs[k] = x[-(4-k)] + x[4-k], k = 0..4 (distances 4, 3, 2, 1): SciPy's jj order.
    let mut acc = x0 * GAUSS[0];
    acc += pairs[0] * GAUSS[4];
    acc += pairs[1] * GAUSS[3];
    acc += pairs[2] * GAUSS[2];
    acc += pairs[3] * GAUSS[1];
    acc
}

/// The 1-D Gaussian of a line with zeros outside, into `out` (same length).
fn gauss_line(line: &[f64], out: &mut [f64]) {
    let n = line.len();
    let at = |i: isize| if i >= 0 && (i as usize) < n { line[i as usize] } else { 0.0 };
    for (i, o) in out.iter_mut().enumerate() {
        let i = i as isize;
        *o = gauss_tap(
            at(i),
            [at(i - 4) + at(i + 4), at(i - 3) + at(i + 3), at(i - 2) + at(i + 2), at(i - 1) + at(i + 1)],
        );
    }
}

/// scikit-image's smoothed image: SciPy's Gaussian (constant mode) divided by the
/// bleed-over of an all-ones image plus epsilon. `image` is row-major `h x w`.
fn smooth(image: &[f64], w: usize, h: usize) -> Vec<f64> {
    // Axis 0 (down the columns), done row by row so that each output row is a
    // vectorisable combination of nine input rows.
    let mut vertical = vec![0.0f64; w * h];
    let zero = vec![0.0f64; w];
    let row = |r: isize| -> &[f64] {
        if r >= 0 && (r as usize) < h {
            &image[r as usize * w..r as usize * w + w]
        } else {
            &zero
        }
    };
    vertical.par_chunks_mut(w).enumerate().for_each(|(r, out)| {
        let r = r as isize;
        let (c0, m4, p4, m3, p3) = (row(r), row(r - 4), row(r + 4), row(r - 3), row(r + 3));
        let (m2, p2, m1, p1) = (row(r - 2), row(r + 2), row(r - 1), row(r + 1));
        for c in 0..w {
            out[c] = gauss_tap(c0[c], [m4[c] + p4[c], m3[c] + p3[c], m2[c] + p2[c], m1[c] + p1[c]]);
        }
    });

    // The bleed-over of an all-ones image: the vertical pass is a function of the row
    // alone, the horizontal pass of that constant row a function of the column near the
    // left and right ends only.
    let ones = vec![1.0f64; h];
    let mut bleed_rows = vec![0.0f64; h];
    gauss_line(&ones, &mut bleed_rows);

    let mut smoothed = vec![0.0f64; w * h];
    smoothed.par_chunks_mut(w).zip(vertical.par_chunks(w)).zip(bleed_rows.par_iter()).for_each(|((out, line), &b)| {
        let mut bleed = vec![0.0f64; w];
        gauss_line(&vec![b; w], &mut bleed);
        gauss_line(line, out);
        for (o, b) in out.iter_mut().zip(&bleed) {
            *o /= b + f64::EPSILON;
        }
    });
    smoothed
}

/// Edge map of `image` (row-major `h x w`, values 0..255 as f64): `true` where
/// `skimage.feature.canny(image)` is `True`. Needs `w, h >= 1`.
pub fn canny(image: &[f64], w: usize, h: usize) -> Vec<bool> {
    let smoothed = smooth(image, w, h);
    let (isobel, jsobel) = sobel_pair(&smoothed, w, h);
    let class = suppress(&isobel, &jsobel, w, h);
    hysteresis(class, w, h)
}

/// `ndimage.sobel(s, axis=0)` and `ndimage.sobel(s, axis=1)` (reflect mode).
fn sobel_pair(s: &[f64], w: usize, h: usize) -> (Vec<f64>, Vec<f64>) {
    let rf = |i: isize, n: usize| -> usize {
        if i < 0 {
            0
        } else if i as usize >= n {
            n - 1
        } else {
            i as usize
        }
    };
    // Derivative passes: along axis 0 for isobel, axis 1 for jsobel.
    // SciPy's antisymmetric branch: x*0 + (x[-1] - x[+1]) * (-1).
    let mut di = vec![0.0f64; w * h];
    let mut dj = vec![0.0f64; w * h];
    di.par_chunks_mut(w).zip(dj.par_chunks_mut(w)).enumerate().for_each(|(r, (oi, oj))| {
        let up = &s[rf(r as isize - 1, h) * w..][..w];
        let down = &s[rf(r as isize + 1, h) * w..][..w];
        let mid = &s[r * w..][..w];
        for c in 0..w {
            oi[c] = mid[c] * 0.0 + (up[c] - down[c]) * -1.0;
            let (l, rr) = (mid[rf(c as isize - 1, w)], mid[rf(c as isize + 1, w)]);
            oj[c] = mid[c] * 0.0 + (l - rr) * -1.0;
        }
    });
    // Smoothing passes across: [1 2 1] symmetric branch: x*2 + (x[-1] + x[+1]) * 1.
    let mut isobel = vec![0.0f64; w * h];
    let mut jsobel = vec![0.0f64; w * h];
    isobel.par_chunks_mut(w).zip(jsobel.par_chunks_mut(w)).enumerate().for_each(|(r, (oi, oj))| {
        let line = &di[r * w..][..w];
        for c in 0..w {
            let (l, rr) = (line[rf(c as isize - 1, w)], line[rf(c as isize + 1, w)]);
            oi[c] = line[c] * 2.0 + (l + rr) * 1.0;
        }
        let up = &dj[rf(r as isize - 1, h) * w..][..w];
        let down = &dj[rf(r as isize + 1, h) * w..][..w];
        let mid = &dj[r * w..][..w];
        for c in 0..w {
            oj[c] = mid[c] * 2.0 + (up[c] + down[c]) * 1.0;
        }
    });
    (isobel, jsobel)
}

/// scikit-image's `_nonmaximum_suppression_bilinear` followed by the two thresholds.
fn suppress(isobel: &[f64], jsobel: &[f64], w: usize, h: usize) -> Vec<u8> {
    let mut magnitude = vec![0.0f64; w * h];
    magnitude.par_iter_mut().zip(isobel.par_iter().zip(jsobel.par_iter())).for_each(|(m, (&i, &j))| {
        let mut v = i * i;
        v += j * j;
        *m = v.sqrt();
    });
    let mut class = vec![NONE; w * h];
    if w < 3 || h < 3 {
        return class;
    }
    let mag = &magnitude;
    class.par_chunks_mut(w).enumerate().skip(1).take(h - 2).for_each(|(x, out)| {
        let at = |r: usize, c: usize| mag[r * w + c];
        for y in 1..w - 1 {
            let k = x * w + y;
            let m = mag[k];
            if !(m >= LOW) {
                continue;
            }
            let (iv, jv) = (isobel[k], jsobel[k]);
            let is_down = iv <= 0.0;
            let is_left = jv <= 0.0;
            let (is_up, is_right) = (!is_down, !is_left);
            let cond1 = (is_up && is_right) || (is_down && is_left);
            let (ai, aj) = (iv.abs(), jv.abs());
            let (wgt, n11, n12, n21, n22);
            if cond1 {
                if ai > aj {
                    wgt = aj / ai;
                    (n11, n12, n21, n22) = (at(x + 1, y), at(x + 1, y + 1), at(x - 1, y), at(x - 1, y - 1));
                } else {
                    wgt = ai / aj;
                    (n11, n12, n21, n22) = (at(x, y + 1), at(x + 1, y + 1), at(x, y - 1), at(x - 1, y - 1));
                }
            } else if ai < aj {
                wgt = ai / aj;
                (n11, n12, n21, n22) = (at(x, y + 1), at(x - 1, y + 1), at(x, y - 1), at(x + 1, y - 1));
            } else {
                wgt = aj / ai;
                (n11, n12, n21, n22) = (at(x - 1, y), at(x - 1, y + 1), at(x + 1, y), at(x + 1, y - 1));
            }
            if n12 * wgt + n11 * (1.0 - wgt) <= m && n22 * wgt + n21 * (1.0 - wgt) <= m {
                out[y] = if m >= HIGH { STRONG } else { LOW_ONLY };
            }
        }
    });
    class
}

/// Keeps the 8-connected groups of suppressed-and-thresholded pixels that contain a
/// strong one (equivalent to scikit-image's labelling of the low mask).
fn hysteresis(mut class: Vec<u8>, w: usize, h: usize) -> Vec<bool> {
    let mut stack: Vec<usize> = Vec::new();
    for start in 0..class.len() {
        if class[start] != STRONG {
            continue;
        }
        stack.push(start);
        while let Some(k) = stack.pop() {
            let (r, c) = (k / w, k % w);
            for r2 in r.saturating_sub(1)..(r + 2).min(h) {
                for c2 in c.saturating_sub(1)..(c + 2).min(w) {
                    let k2 = r2 * w + c2;
                    if class[k2] == LOW_ONLY {
                        class[k2] = LINKED;
                        stack.push(k2);
                    }
                }
            }
        }
    }
    class.into_iter().map(|c| c == STRONG || c == LINKED).collect()
}
