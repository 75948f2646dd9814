//! Canny's non-maximum-suppressed, thresholded pixel classes exactly as
//! `skimage.feature.canny(image)` computes them with its defaults (scikit-image 0.26,
//! SciPy 1.17) on a float64 image of 0..255 grey levels, as CPBD's block classifier calls
//! it (SPEC.md A.3.1), for one rectangle of the image at a time. The hysteresis that
//! turns classes into edges is in `hysteresis.rs`.
//!
//! Every floating-point operation is done in the order SciPy's C filters and
//! scikit-image's Cython do it, so a class is identical, not merely close, and does not
//! depend on the rectangle it was computed in (each value is a function of the image
//! alone; a rectangle only adds a halo of recomputed values):
//!
//! 1. Gaussian, sigma 1, radius 4, `mode='constant'` (zeros outside): SciPy's
//!    `gaussian_filter` (axis 0, then axis 1; symmetric `correlate1d`:
//!    `x0 w0 + (x-4 + x+4) w4 + ... + (x-1 + x+1) w1`), divided by the same filter of an
//!    all-ones image plus machine epsilon (scikit-image's "bleed-over" correction,
//!    [`Bleed`]).
//! 2. `ndimage.sobel` with `mode='reflect'` along each axis: `[-1 0 1]` along it, then
//!    `[1 2 1]` across it; magnitude `sqrt(i^2 + j^2)`.
//! 3. Bilinear non-maximum suppression on the interior (the outer pixel ring is masked),
//!    keeping magnitudes `>= 0.1` (scikit-image passes the low threshold as a C `float`,
//!    so the test is against `0.1f32`); magnitudes `>= 0.2` are strong.

use std::ops::Range;

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
/// Gaussian radius, px.
const RADIUS: usize = 4;

/// scikit-image's default low threshold as the C `float` its Cython receives.
const LOW: f64 = 0.1f32 as f64;
/// scikit-image's default high threshold (compared in Python, as a double).
const HIGH: f64 = 0.2;

/// Not a local maximum above the low threshold (or on the masked outer ring).
pub const NONE: u8 = 0;
/// A local maximum with a magnitude in [0.1, 0.2): an edge only if the hysteresis links
/// it to a strong one.
pub const WEAK: u8 = 1;
/// A local maximum with a magnitude of at least 0.2: always an edge.
pub const STRONG: u8 = 2;

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

/// scikit-image's bleed-over denominators `gaussian(ones) + eps` for a `w x h` image.
///
/// They depend on the row only through its distance to the top or bottom edge when it is
/// within the Gaussian radius, so 9 rows of `w` values hold them all (rather than one
/// filtered line per image row). Needs `w, h >= 9` (CPBD's 64 x 64 minimum).
pub struct Bleed {
    rows: Vec<f64>,
    w: usize,
    h: usize,
}

impl Bleed {
    /// The denominators of a `w x h` image (`w, h >= 9`).
    pub fn new(w: usize, h: usize) -> Self {
        let mut column = vec![0.0f64; h];
        gauss_line(&vec![1.0f64; h], &mut column);
        let representative = [0, 1, 2, 3, RADIUS, h - 4, h - 3, h - 2, h - 1];
        let mut rows = vec![0.0f64; 9 * w];
        for (den, &r) in rows.chunks_exact_mut(w).zip(&representative) {
            gauss_line(&vec![column[r]; w], den);
            for d in den.iter_mut() {
                *d += f64::EPSILON;
            }
        }
        Bleed { rows, w, h }
    }

    /// The denominators of image row `r`.
    fn row(&self, r: usize) -> &[f64] {
        let class = if r < RADIUS {
            r
        } else if r + RADIUS >= self.h {
            9 - (self.h - r)
        } else {
            RADIUS
        };
        &self.rows[class * self.w..(class + 1) * self.w]
    }
}

/// Working memory of [`classify`], reused from one rectangle to the next.
#[derive(Default)]
pub struct Scratch {
    vertical: Vec<f64>,
    smoothed: Vec<f64>,
    di: Vec<f64>,
    dj: Vec<f64>,
    isobel: Vec<f64>,
    jsobel: Vec<f64>,
    magnitude: Vec<f64>,
}

/// `[a, b)` of `a`, `b` given as signed values clipped to `[0, n)`.
fn clip(a: isize, b: isize, n: usize) -> Range<usize> {
    a.clamp(0, n as isize) as usize..b.clamp(0, n as isize) as usize
}

/// SciPy's `reflect` index for a 3-tap filter: -1 -> 0, n -> n - 1.
#[inline(always)]
fn rf(i: isize, n: usize) -> usize {
    i.clamp(0, n as isize - 1) as usize
}

/// Pixel classes ([`NONE`], [`WEAK`], [`STRONG`]) of `rows x cols` of the `w x h` 8-bit
/// `image`, written to `out` (row-major, row stride `stride >= cols.len()`, row
/// `rows.start` first); returns the numbers of strong and weak pixels.
///
/// Preconditions (checked by the caller): `w, h >= 9`, `image.len() == w * h`,
/// `rows.end <= h`, `cols.end <= w`, `bleed` made for `w x h`, `out` long enough.
#[allow(clippy::too_many_arguments)]
pub fn classify(
    image: &[u8],
    w: usize,
    h: usize,
    bleed: &Bleed,
    rows: Range<usize>,
    cols: Range<usize>,
    out: &mut [u8],
    stride: usize,
    s: &mut Scratch,
) -> (usize, usize) {
    for o in out.chunks_mut(stride).take(rows.len()) {
        o[..cols.len()].fill(NONE);
    }
    if rows.is_empty() || cols.is_empty() {
        return (0, 0);
    }
    let Some((busy_r, busy_c)) = busy_box(image, w, bleed, rows.clone(), cols.clone()) else {
        return (0, 0);
    };
    let (ra, rb, ca, cb) = (busy_r.start as isize, busy_r.end as isize, busy_c.start as isize, busy_c.end as isize);
    // The halo each stage needs: magnitudes around the suppressed pixels, smoothed
    // values around the Sobel outputs, Gaussian radius around the smoothed values.
    let (rm, cm) = (clip(ra - 1, rb + 1, h), clip(ca - 1, cb + 1, w));
    let (rs, cs) = (clip(ra - 2, rb + 2, h), clip(ca - 2, cb + 2, w));
    smooth(image, w, h, bleed, rs.clone(), cs.clone(), s);
    sobel(s, w, h, [rs, cs, rm.clone(), cm.clone()]);
    suppress(s, w, h, [ra, rb, ca, cb], [rm, cm], [rows.start, cols.start], out, stride)
}

/// Stage 1 of [`classify`]: the Gaussian (sigma 1, radius 4, zeros outside the image) of
/// `image` on `rs x cs`, divided by the bleed-over correction, into `s.smoothed`
/// (row-major, width `cs.len()`).
fn smooth(image: &[u8], w: usize, h: usize, bleed: &Bleed, rs: Range<usize>, cs: Range<usize>, s: &mut Scratch) {
    // 1a. Axis 0 Gaussian over the smoothed rows, on columns cs +- radius with zeros
    // outside the image, so that axis 1 needs no bounds tests.
    let vw = cs.len() + 2 * RADIUS;
    let v0 = cs.start as isize - RADIUS as isize;
    let vcols = clip(v0, v0 + vw as isize, w);
    s.vertical.clear();
    s.vertical.resize(rs.len() * vw, 0.0);
    let zero_row: &[u8] = &[];
    for (r, out_v) in rs.clone().zip(s.vertical.chunks_exact_mut(vw)) {
        let row = |d: isize| -> &[u8] {
            let rr = r as isize + d;
            if rr >= 0 && (rr as usize) < h {
                &image[rr as usize * w..rr as usize * w + w]
            } else {
                zero_row
            }
        };
        let px = |line: &[u8], c: usize| line.get(c).map_or(0.0, |&v| v as f64);
        let (c0, m4, p4, m3, p3) = (row(0), row(-4), row(4), row(-3), row(3));
        let (m2, p2, m1, p1) = (row(-2), row(2), row(-1), row(1));
        let dst = &mut out_v[(vcols.start as isize - v0) as usize..][..vcols.len()];
        if m4.is_empty() || p4.is_empty() {
            for (o, c) in dst.iter_mut().zip(vcols.clone()) {
                *o = gauss_tap(
                    px(c0, c),
                    [px(m4, c) + px(p4, c), px(m3, c) + px(p3, c), px(m2, c) + px(p2, c), px(m1, c) + px(p1, c)],
                );
            }
        } else {
            let cr = vcols.clone();
            let (c0, m4, p4, m3, p3) =
                (&c0[cr.clone()], &m4[cr.clone()], &p4[cr.clone()], &m3[cr.clone()], &p3[cr.clone()]);
            let (m2, p2, m1, p1) = (&m2[cr.clone()], &p2[cr.clone()], &m1[cr.clone()], &p1[cr]);
            for k in 0..dst.len() {
                // Sums of two grey levels are exact in integers as in floats.
                let pair = |a: &[u8], b: &[u8]| (a[k] as u16 + b[k] as u16) as f64;
                dst[k] = gauss_tap(c0[k] as f64, [pair(m4, p4), pair(m3, p3), pair(m2, p2), pair(m1, p1)]);
            }
        }
    }

    // 1b. Axis 1 Gaussian and the bleed-over correction, over nine shifted views of the
    // row so that the loop has no bounds tests and vectorises.
    let sw = cs.len();
    s.smoothed.clear();
    s.smoothed.resize(rs.len() * sw, 0.0);
    for ((r, v), out_s) in rs.clone().zip(s.vertical.chunks_exact(vw)).zip(s.smoothed.chunks_exact_mut(sw)) {
        let den = &bleed.row(r)[cs.clone()];
        let t = |d: usize| &v[d..d + sw];
        let (x0, x1, x2, x3, x4, x5, x6, x7, x8) = (t(0), t(1), t(2), t(3), t(4), t(5), t(6), t(7), t(8));
        for k in 0..sw {
            out_s[k] = gauss_tap(x4[k], [x0[k] + x8[k], x1[k] + x7[k], x2[k] + x6[k], x3[k] + x5[k]]) / den[k];
        }
    }
}

/// Stage 2 of [`classify`]: the Sobel derivatives of `s.smoothed` (on `rs x cs`) into
/// `s.isobel`, `s.jsobel` and their magnitude into `s.magnitude`, on `rm x cm`
/// (`[rs, cs, rm, cm]`).
fn sobel(s: &mut Scratch, w: usize, h: usize, [rs, cs, rm, cm]: [Range<usize>; 4]) {
    let sw = cs.len();
    // 2. Sobel. Derivative passes (SciPy's antisymmetric branch x*0 + (x[-1] - x[+1]) * -1,
    // the product by -1 being an exact negation),
    // di along axis 0 on rm x cs, dj along axis 1 on rs x cm; then the [1 2 1] passes
    // (x*2 + (x[-1] + x[+1]) * 1) across, both on rm x cm; then the magnitude.
    let mw = cm.len();
    let srow = |r: usize| &s.smoothed[(r - rs.start) * sw..][..sw];
    s.di.clear();
    s.di.resize(rm.len() * sw, 0.0);
    for (r, o) in rm.clone().zip(s.di.chunks_exact_mut(sw)) {
        let (up, mid, down) = (srow(rf(r as isize - 1, h)), srow(r), srow(rf(r as isize + 1, h)));
        for k in 0..sw {
            o[k] = mid[k] * 0.0 + -(up[k] - down[k]);
        }
    }
    s.dj.clear();
    s.dj.resize(rs.len() * mw, 0.0);
    for (r, o) in rs.clone().zip(s.dj.chunks_exact_mut(mw)) {
        across(srow(r), cs.start, o, cm.clone(), w, |mid, l, r| mid * 0.0 + -(l - r));
    }
    s.isobel.clear();
    s.isobel.resize(rm.len() * mw, 0.0);
    s.jsobel.clear();
    s.jsobel.resize(rm.len() * mw, 0.0);
    s.magnitude.clear();
    s.magnitude.resize(rm.len() * mw, 0.0);
    let rows_m = s.isobel.chunks_exact_mut(mw).zip(s.jsobel.chunks_exact_mut(mw)).zip(s.magnitude.chunks_exact_mut(mw));
    for (r, ((oi, oj), om)) in rm.clone().zip(rows_m) {
        across(&s.di[(r - rm.start) * sw..][..sw], cs.start, oi, cm.clone(), w, |mid, l, r| mid * 2.0 + (l + r) * 1.0);
        let djrow = |rr: usize| &s.dj[(rr - rs.start) * mw..][..mw];
        let (up, mid, down) = (djrow(rf(r as isize - 1, h)), djrow(r), djrow(rf(r as isize + 1, h)));
        for k in 0..mw {
            oj[k] = mid[k] * 2.0 + (up[k] + down[k]) * 1.0;
        }
        for k in 0..mw {
            let mut m = oi[k] * oi[k];
            m += oj[k] * oj[k];
            om[k] = m.sqrt();
        }
    }
}

/// Stage 3 of [`classify`]: non-maximum suppression and the two thresholds on the interior
/// pixels of the busy box `[ra, rb, ca, cb]`, classes written to `out` (whose row 0, column
/// 0 is pixel `[rows_start, cols_start]`); the magnitudes are on `rm x cm`. Returns the
/// numbers of strong and weak pixels.
#[allow(clippy::too_many_arguments)]
fn suppress(
    s: &Scratch,
    w: usize,
    h: usize,
    [ra, rb, ca, cb]: [isize; 4],
    [rm, cm]: [Range<usize>; 2],
    [rows_start, cols_start]: [usize; 2],
    out: &mut [u8],
    stride: usize,
) -> (usize, usize) {
    let mw = cm.len();
    // 3. scikit-image's `_nonmaximum_suppression_bilinear` and the two thresholds, on
    // the interior only. Its four cases differ in which ratio is the weight and which
    // neighbours are interpolated; choosing both by index rather than by branch keeps
    // the loop free of unpredictable jumps on noisy images.
    let (mut strong, mut weak) = (0usize, 0usize);
    let mag = &s.magnitude[..];
    let mwi = mw as isize;
    // Offsets of (n11, n12, n21, n22) per case, in the order of the Cython source:
    // cond1 and |i| > |j|, cond1 otherwise, not cond1 and |i| < |j|, not cond1 otherwise.
    let neighbours: [[isize; 4]; 4] = [
        [mwi, mwi + 1, -mwi, -mwi - 1],
        [1, mwi + 1, -1, -mwi - 1],
        [1, -mwi + 1, -1, mwi - 1],
        [-mwi, -mwi + 1, mwi, mwi - 1],
    ];
    let nr = clip(ra.max(1), rb.min(h as isize - 1), h);
    let nc = clip(ca.max(1), cb.min(w as isize - 1), w);
    for x in nr {
        let o = &mut out[(x - rows_start) * stride..];
        for y in nc.clone() {
            let k = (x - rm.start) * mw + (y - cm.start);
            let m = mag[k];
            if m < LOW || m.is_nan() {
                continue;
            }
            let (iv, jv) = (s.isobel[k], s.jsobel[k]);
            let is_down = iv <= 0.0;
            let is_left = jv <= 0.0;
            let cond1 = is_down == is_left;
            let (ai, aj) = (iv.abs(), jv.abs());
            let case = if cond1 { (ai <= aj) as usize } else { 2 + (ai >= aj) as usize };
            // Cases 0 and 3 weigh by |j| / |i|, cases 1 and 2 by |i| / |j|.
            let j_over_i = case == 0 || case == 3;
            let wgt = if j_over_i { aj } else { ai } / if j_over_i { ai } else { aj };
            let at = |d: isize| mag[(k as isize + d) as usize];
            let [d11, d12, d21, d22] = neighbours[case];
            let (n11, n12, n21, n22) = (at(d11), at(d12), at(d21), at(d22));
            let keep = (n12 * wgt + n11 * (1.0 - wgt) <= m) & (n22 * wgt + n21 * (1.0 - wgt) <= m);
            let is_strong = m >= HIGH;
            strong += (keep & is_strong) as usize;
            weak += (keep & !is_strong) as usize;
            o[y - cols_start] = keep as u8 * if is_strong { STRONG } else { WEAK };
        }
    }
    (strong, weak)
}

/// `dst[c] = f(src[c], src[c - 1], src[c + 1])` for the columns `dst_cols`, with SciPy's
/// `reflect` index at the image edges; `src` holds columns from `src_start` and must cover
/// `dst_cols` widened by one inside the image.
#[inline(always)]
fn across(
    src: &[f64],
    src_start: usize,
    dst: &mut [f64],
    dst_cols: Range<usize>,
    w: usize,
    f: impl Fn(f64, f64, f64) -> f64,
) {
    let at = |c: usize| src[c - src_start];
    for c in [dst_cols.start, dst_cols.end - 1] {
        if c == 0 || c == w - 1 {
            dst[c - dst_cols.start] = f(at(c), at(rf(c as isize - 1, w)), at(rf(c as isize + 1, w)));
        }
    }
    let (a, b) = (dst_cols.start.max(1), dst_cols.end.min(w - 1));
    if a < b {
        let n = b - a;
        let (mid, l, r) = (&src[a - src_start..][..n], &src[a - 1 - src_start..][..n], &src[a + 1 - src_start..][..n]);
        let o = &mut dst[a - dst_cols.start..][..n];
        for k in 0..n {
            o[k] = f(mid[k], l[k], r[k]);
        }
    }
}

/// The smallest rectangle within `rows x cols` outside which every class is [`NONE`]
/// for a reason that needs no arithmetic, or `None` if that is all of it.
///
/// Pixel `(x, y)` is [`NONE`] when the image holds one value over rows `x - 5 ..= x + 5`
/// and columns `y - 5 ..= y + 5` and the pixel is at least 5 px from the image edges
/// (where the bleed-over correction varies): the smoothed values around it are then
/// exactly constant, its Sobel responses exactly 0, and so is its magnitude. So only
/// pixels near two differing neighbouring grey levels, or near the edges, can be
/// anything else. Flat areas (a board's squares, its margin) are skipped this way.
fn busy_box(
    image: &[u8],
    w: usize,
    bleed: &Bleed,
    rows: Range<usize>,
    cols: Range<usize>,
) -> Option<(Range<usize>, Range<usize>)> {
    const REACH: usize = 5;
    let h = bleed.h;
    // Inclusive bounds of the busy pixels found so far.
    let (mut r0, mut r1, mut c0, mut c1) = (usize::MAX, 0usize, usize::MAX, 0usize);
    let mut add = |ra: usize, rb: usize, ca: usize, cb: usize| {
        // Clip [ra, rb] x [ca, cb] to the rectangle asked for; skip if disjoint.
        let (ra, rb, ca, cb) = (ra.max(rows.start), rb.min(rows.end - 1), ca.max(cols.start), cb.min(cols.end - 1));
        if ra <= rb && ca <= cb {
            (r0, r1, c0, c1) = (r0.min(ra), r1.max(rb), c0.min(ca), c1.max(cb));
        }
    };
    // The bands along the image edges.
    add(0, REACH - 1, 0, w - 1);
    add(h - REACH, h - 1, 0, w - 1);
    add(0, h - 1, 0, REACH - 1);
    add(0, h - 1, w - REACH, w - 1);
    // Pairs of differing neighbours within reach of the rectangle.
    let rr = rows.start.saturating_sub(REACH)..(rows.end + REACH).min(h);
    let cc = cols.start.saturating_sub(REACH)..(cols.end + REACH).min(w);
    let line = |r: usize| &image[r * w..][cc.clone()];
    for r in rr.clone() {
        let here = line(r);
        // Across: (r, c) and (r, c + 1) differ; windows holding both have
        // x in r - 5 ..= r + 5 and y in c - 4 ..= c + 5.
        let (a, b) = (&here[..here.len() - 1], &here[1..]);
        if a != b {
            let first = a.iter().zip(b).position(|(p, q)| p != q).map_or(0, |i| i);
            let last = a.iter().zip(b).rposition(|(p, q)| p != q).map_or(0, |i| i);
            let (cf, cl) = (cc.start + first, cc.start + last);
            add(r.saturating_sub(REACH), r + REACH, cf.saturating_sub(REACH - 1), cl + REACH);
        }
        // Down: (r, c) and (r + 1, c) differ.
        if r + 1 < rr.end {
            let below = line(r + 1);
            if here != below {
                let first = here.iter().zip(below).position(|(p, q)| p != q).map_or(0, |i| i);
                let last = here.iter().zip(below).rposition(|(p, q)| p != q).map_or(0, |i| i);
                let (cf, cl) = (cc.start + first, cc.start + last);
                add(r.saturating_sub(REACH - 1), r + REACH, cf.saturating_sub(REACH), cl + REACH);
            }
        }
    }
    (r0 <= r1).then(|| (r0..r1 + 1, c0..c1 + 1))
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A fixture of the CPBD tests as grey levels.
    pub(crate) fn fixture(name: &str) -> (Vec<u8>, usize, usize) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cpbd").join(name);
        let img = image::open(path).unwrap().to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        (img.into_raw(), w, h)
    }

    /// The classes of the whole image computed in rectangles of `rh x rw`.
    fn in_rectangles(image: &[u8], w: usize, h: usize, rh: usize, rw: usize) -> (Vec<u8>, usize, usize) {
        let bleed = Bleed::new(w, h);
        let mut s = Scratch::default();
        let mut all = vec![9u8; w * h];
        let (mut strong, mut weak) = (0, 0);
        for r0 in (0..h).step_by(rh) {
            for c0 in (0..w).step_by(rw) {
                let (rows, cols) = (r0..(r0 + rh).min(h), c0..(c0 + rw).min(w));
                let mut out = vec![9u8; rh * rw];
                let (a, b) = classify(image, w, h, &bleed, rows.clone(), cols.clone(), &mut out, rw, &mut s);
                strong += a;
                weak += b;
                for r in rows {
                    for c in cols.clone() {
                        all[r * w + c] = out[(r - r0) * rw + c - c0];
                    }
                }
            }
        }
        (all, strong, weak)
    }

    /// The whole image as one rectangle is computed in full (`busy_box` always keeps the
    /// bands along the image edges, hence everything between), smaller rectangles skip
    /// flat areas: equal classes check the shortcut too (the noise-free board has them).
    #[test]
    fn classes_do_not_depend_on_the_rectangle_they_are_computed_in() {
        for name in ["camera.png", "board_s0.5_n0.png", "board_s0.3_n3.png"] {
            let (img, w, h) = fixture(name);
            let (whole, strong, weak) = in_rectangles(&img, w, h, h, w);
            assert_eq!(strong, whole.iter().filter(|&&c| c == STRONG).count());
            assert_eq!(weak, whole.iter().filter(|&&c| c == WEAK).count());
            assert!(strong > 1000 && whole.iter().filter(|&&c| c == NONE).count() > 1000, "{name}");
            // The outer ring is masked.
            assert!((0..w).all(|c| whole[c] == NONE && whole[(h - 1) * w + c] == NONE));
            assert!((0..h).all(|r| whole[r * w] == NONE && whole[r * w + w - 1] == NONE));
            for (rh, rw) in [(64, 64), (4, 64), (7, 13), (1, 1)] {
                let (parts, s2, k2) = in_rectangles(&img, w, h, rh, rw);
                assert!(parts == whole && (s2, k2) == (strong, weak), "{name} in {rh} x {rw} rectangles");
            }
        }
    }

    #[test]
    fn bleed_rows_equal_the_filtered_ones_image() {
        let (w, h) = (70, 81);
        let bleed = Bleed::new(w, h);
        let mut column = vec![0.0; h];
        gauss_line(&vec![1.0; h], &mut column);
        for (r, &b) in column.iter().enumerate() {
            let mut row = vec![0.0; w];
            gauss_line(&vec![b; w], &mut row);
            let want: Vec<f64> = row.iter().map(|v| v + f64::EPSILON).collect();
            assert_eq!(bleed.row(r), &want[..], "row {r}");
        }
    }

    #[test]
    fn a_constant_image_has_no_canny_pixel() {
        // The interior takes the flat-area shortcut (`busy_box`), the border the full
        // computation (with the bleed-over correction).
        let (w, h) = (150, 100);
        let img = vec![217u8; w * h];
        let (classes, strong, weak) = in_rectangles(&img, w, h, 64, 64);
        assert_eq!((strong, weak), (0, 0));
        assert!(classes.iter().all(|&c| c == NONE));
        // One different pixel makes its neighbourhood classify in full.
        let mut dot = img;
        dot[50 * w + 75] = 218;
        let (_, strong, _) = in_rectangles(&dot, w, h, 64, 64);
        assert!(strong > 0);
    }
}
