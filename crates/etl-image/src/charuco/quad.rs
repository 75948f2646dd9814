//! Step 3: quadrilaterals. A contour is approximated by a polygon (Douglas-Peucker, as
//! OpenCV's `approxPolyDP` with 3 % of the perimeter); one of four convex vertices is a
//! marker candidate. Its sides are then located at full resolution: along each side, the
//! intensity profile across it (bilinear samples) has its steepest rise where the marker's
//! black border meets the white around it (the maximum of the derivative of a blurred step
//! is at the step, whatever the blur); a straight line through these points, fitted by total
//! least squares, is the side, and the corners are where consecutive sides cross.

use crate::grey::{GrayView, Sample};

/// The polygon tolerance as a fraction of the contour's length (OpenCV's default).
const POLY_RATE: f64 = 0.03;
/// Profiles across a side, per side.
const PROFILES: usize = 12;
/// Profile sample spacing, px.
const PROFILE_STEP: f64 = 0.5;

/// A quadrilateral at full resolution, corners clockwise in the image (u right, v down).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Quad {
    pub corners: [[f64; 2]; 4],
    /// Median over the profiles of the steepest rise across a side, grey levels per px.
    pub edge_slope: f64,
}

/// The four corners (detection-level px) of a contour that a convex quadrilateral
/// approximates, clockwise in the image; `None` otherwise or when a side is shorter than
/// `min_side` px.
pub(crate) fn approximate(points: &[[i32; 2]], min_side: f64) -> Option<[[f64; 2]; 4]> {
    let n = points.len();
    if n < 8 {
        return None;
    }
    let p = |i: usize| [points[i % n][0] as f64, points[i % n][1] as f64];
    let perimeter: f64 = (0..n).map(|i| dist(p(i), p(i + 1))).sum();
    let eps = POLY_RATE * perimeter;
    // Two vertices surely on the polygon: the point farthest from the first, and the one
    // farthest from it (the diameter of a convex outline joins two of its vertices).
    let far = |from: [f64; 2]| (0..n).max_by(|&a, &b| dist(p(a), from).total_cmp(&dist(p(b), from))).unwrap_or(0);
    let a = far(p(0));
    let b = far(p(a));
    let (a, b) = (a.min(b), a.max(b));
    if a == b {
        return None;
    }
    let mut keep = vec![a, b];
    simplify(&p, a, b, eps, &mut keep);
    simplify(&p, b, a + n, eps, &mut keep);
    if keep.len() != 4 {
        return None;
    }
    let mut idx: Vec<usize> = keep.iter().map(|&i| i % n).collect();
    idx.sort_unstable();
    let mut q = [[0.0; 2]; 4];
    for (k, &i) in idx.iter().enumerate() {
        q[k] = p(i);
    }
    orient_clockwise(&mut q);
    let convex = (0..4).all(|k| cross3(q[k], q[(k + 1) % 4], q[(k + 2) % 4]) > 0.0);
    let sides_ok = (0..4).all(|k| dist(q[k], q[(k + 1) % 4]) >= min_side);
    (convex && sides_ok).then_some(q)
}

/// Douglas-Peucker between indices `i < j` of the closed contour (indices modulo its length):
/// pushes the kept interior vertices.
fn simplify(p: &impl Fn(usize) -> [f64; 2], i: usize, j: usize, eps: f64, keep: &mut Vec<usize>) {
    let mut stack = vec![(i, j)];
    while let Some((i, j)) = stack.pop() {
        if keep.len() > 4 || j <= i + 1 {
            continue;
        }
        let (a, b) = (p(i), p(j));
        let (mut best, mut best_d) = (i, 0.0);
        for k in i + 1..j {
            let d = line_distance(p(k), a, b);
            if d > best_d {
                (best, best_d) = (k, d);
            }
        }
        if best_d > eps {
            keep.push(best);
            stack.push((i, best));
            stack.push((best, j));
        }
    }
}

/// Puts the corners in clockwise order in the image (positive shoelace with v down).
fn orient_clockwise(q: &mut [[f64; 2]; 4]) {
    let area: f64 = (0..4).map(|k| q[k][0] * q[(k + 1) % 4][1] - q[(k + 1) % 4][0] * q[k][1]).sum();
    if area < 0.0 {
        q.swap(1, 3);
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// (b - a) x (c - b): positive when a, b, c turn clockwise in the image.
fn cross3(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
}

fn line_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l = dx.hypot(dy);
    if l == 0.0 {
        return dist(p, a);
    }
    ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx).abs() / l
}

/// Locates the four sides of a dark quadrilateral on a light surround at full resolution,
/// from `coarse` corners (clockwise, within `reach` px of the true ones). `None` when a
/// side has too few clear edge points or the corners move farther than `2 reach`.
pub(crate) fn refine<T: Sample>(img: &GrayView<'_, T>, coarse: [[f64; 2]; 4], reach: f64) -> Option<Quad> {
    let mut lines = [([0.0; 2], [0.0; 2]); 4];
    let mut slopes = Vec::with_capacity(4 * PROFILES);
    for k in 0..4 {
        let (a, b) = (coarse[k], coarse[(k + 1) % 4]);
        let len = dist(a, b);
        let t = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
        // Outward normal of a clockwise outline (v down).
        let n = [t[1], -t[0]];
        let mut pts = Vec::with_capacity(PROFILES);
        for s in 0..PROFILES {
            // The middle of the side: near the corners the other sides bend the profile.
            let f = 0.15 + 0.7 * (s as f64 + 0.5) / PROFILES as f64;
            let base = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            if let Some((off, slope)) = steepest_rise(img, base, n, reach) {
                pts.push([base[0] + off * n[0], base[1] + off * n[1]]);
                slopes.push(slope);
            }
        }
        if pts.len() < PROFILES / 2 {
            return None;
        }
        lines[k] = fit_line(&pts)?;
    }
    let mut corners = [[0.0; 2]; 4];
    for k in 0..4 {
        corners[(k + 1) % 4] = intersect(lines[k], lines[(k + 1) % 4])?;
        if dist(corners[(k + 1) % 4], coarse[(k + 1) % 4]) > 2.0 * reach + 1.0 {
            return None;
        }
    }
    slopes.sort_by(f64::total_cmp);
    Some(Quad { corners, edge_slope: slopes[slopes.len() / 2] })
}

/// Along `base + o n`, o in [-reach, reach]: where the intensity crosses half-way between
/// its dark and light levels next to its steepest rise (linear interpolation; for a blurred
/// step the crossing is the step, and less noisy than the derivative's peak), and the rise
/// per px there. `None` when the profile leaves the image or does not rise.
fn steepest_rise<T: Sample>(img: &GrayView<'_, T>, base: [f64; 2], n: [f64; 2], reach: f64) -> Option<(f64, f64)> {
    let m = (reach / PROFILE_STEP).ceil() as i32 + 1;
    let mut v = [0.0f64; 64];
    let count = (2 * m + 1) as usize;
    if count > v.len() {
        return None;
    }
    for (i, o) in (-m..=m).enumerate() {
        let s = o as f64 * PROFILE_STEP;
        v[i] = f64::from(img.bilinear(base[0] + s * n[0], base[1] + s * n[1])?);
    }
    // Central differences, per px.
    let d = |i: usize| (v[i + 1] - v[i - 1]) / (2.0 * PROFILE_STEP);
    let (best, slope) = (1..count - 1).map(|i| (i, d(i))).max_by(|a, b| a.1.total_cmp(&b.1))?;
    if !(slope > 0.0) {
        return None;
    }
    let lo = v[..=best].iter().copied().fold(f64::MAX, f64::min);
    let hi = v[best..count].iter().copied().fold(f64::MIN, f64::max);
    let mid = 0.5 * (lo + hi);
    // The crossing nearest the steepest sample: i with v[i] <= mid < v[i + 1].
    let crossing = (0..count - 1)
        .filter(|&i| v[i] <= mid && v[i + 1] > mid)
        .min_by_key(|&i| (i as i64 - best as i64).abs().min((i as i64 + 1 - best as i64).abs()))?;
    let t = (mid - v[crossing]) / (v[crossing + 1] - v[crossing]);
    Some(((crossing as f64 + t - m as f64) * PROFILE_STEP, slope))
}

/// The total-least-squares line through `pts`: (a point on it, its unit direction).
fn fit_line(pts: &[[f64; 2]]) -> Option<([f64; 2], [f64; 2])> {
    let n = pts.len() as f64;
    let c = [pts.iter().map(|p| p[0]).sum::<f64>() / n, pts.iter().map(|p| p[1]).sum::<f64>() / n];
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (x, y) = (p[0] - c[0], p[1] - c[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
    }
    // Direction of the largest eigenvector of the scatter matrix.
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    (sxx + syy > 0.0).then_some((c, [theta.cos(), theta.sin()]))
}

fn intersect(l1: ([f64; 2], [f64; 2]), l2: ([f64; 2], [f64; 2])) -> Option<[f64; 2]> {
    let ((p, d), (q, e)) = (l1, l2);
    let den = d[0] * e[1] - d[1] * e[0];
    if den.abs() < 1e-6 {
        return None;
    }
    let t = ((q[0] - p[0]) * e[1] - (q[1] - p[1]) * e[0]) / den;
    Some([p[0] + t * d[0], p[1] + t * d[1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The outline of a tilted square (pixel staircase): four corners, clockwise.
    #[test]
    fn a_tilted_square_outline_gives_its_four_corners() {
        let c = [[30.0, 10.0], [50.0, 30.0], [30.0, 50.0], [10.0, 30.0]];
        let mut pts = Vec::new();
        for k in 0..4 {
            let (a, b): ([f64; 2], [f64; 2]) = (c[k], c[(k + 1) % 4]);
            for s in 0..20 {
                let f = s as f64 / 20.0;
                let p = [(a[0] + f * (b[0] - a[0])).round() as i32, (a[1] + f * (b[1] - a[1])).round() as i32];
                pts.push(p);
            }
        }
        let q = approximate(&pts, 5.0).expect("a quad");
        let first = q.iter().position(|p| p == &[30.0, 10.0]).expect("the top corner");
        for k in 0..4 {
            assert_eq!(q[(first + k) % 4], c[k]);
        }
        // A triangle is not a quad.
        let tri: Vec<[i32; 2]> = pts.iter().copied().filter(|p| p[1] <= 30).collect();
        assert!(approximate(&tri, 5.0).is_none());
    }

    /// A sharp dark square on white: the sides are found to a few hundredths of a pixel
    /// from coarse corners 1.5 px off.
    #[test]
    fn sides_of_a_dark_square_at_sub_pixel() {
        let (w, h) = (80usize, 80usize);
        // Square [20.3, 60.3] x [19.6, 59.6] in continuous px (pixel centres at integers):
        // area coverage of each pixel.
        let cover = |a: f64, b: f64, x: f64| ((x + 0.5).min(b) - (x - 0.5).max(a)).clamp(0.0, 1.0);
        let data: Vec<u8> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                let c = cover(20.3, 60.3, x) * cover(19.6, 59.6, y);
                (210.0 - 170.0 * c).round() as u8
            })
            .collect();
        let img = GrayView::new(w, h, &data[..]).unwrap();
        let coarse = [[21.5, 18.5], [59.0, 21.0], [61.5, 58.0], [19.0, 61.0]];
        let q = refine(&img, coarse, 4.0).expect("refined");
        let truth = [[20.3, 19.6], [60.3, 19.6], [60.3, 59.6], [20.3, 59.6]];
        // A sharp edge crosses half-way within 0.1 px of the step (the bilinear profile of
        // area-sampled pixels is piecewise linear, not a ramp of the step's width).
        for (c, t) in q.corners.iter().zip(truth) {
            assert!(dist(*c, t) < 0.12, "{c:?} vs {t:?}");
        }
        assert!(q.edge_slope > 100.0, "{}", q.edge_slope);
    }
}
