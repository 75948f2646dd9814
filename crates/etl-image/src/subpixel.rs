//! Sub-pixel refinement of a corner by point symmetry, for every board's corners (the
//! checkerboard's and ChArUco's, as OpenCV's `cornerSubPix` serves both).
//!
//! Two straight edges crossing at `c` make an image that is point-symmetric about `c`:
//! `I(c + d) = I(c - d)`. This holds after any isotropic blur (Gaussian defocus, the pixel's
//! own area integration) and under perspective (lines stay lines), so the minimiser of
//!
//! `C(c) = sum_d w(d) (I(c + d) - I(c - d))^2`
//!
//! over a disc of integer offsets `d` is unbiased whatever the blur. With `I` interpolated
//! bilinearly, `c + d` and `c - d` share their fractional part `c - floor(c)`; the
//! interpolation error (second order, point-symmetric) then cancels between the two sides,
//! and inside one pixel cell `C` is a biquadratic polynomial of the fractional part: one pass
//! over the window accumulates its 4 x 4 moment matrix, and minimising it is a few scalar
//! steps. The window must not reach the next edges: its radius is a fraction of the local
//! square size.

use crate::grey::{GrayView, Sample};

/// The offsets (half disc: `d` and `-d` are the same pair) and weights of a window.
pub(crate) struct Window {
    pub radius: usize,
    offsets: Vec<(isize, isize, f64)>,
}

impl Window {
    /// A disc of radius `radius` px with weights tapering to zero at the rim (so that the
    /// cost is smooth as the rim crosses pixels), `step` = 1 or 2 (every other offset: 4x
    /// fewer samples for large windows; offsets stay integers).
    pub fn new(radius: usize, step: usize) -> Self {
        let r = radius as isize;
        let step = step.max(1) as isize;
        let mut offsets = Vec::new();
        let rr = (radius * radius) as f64;
        let mut dy = 0;
        while dy <= r {
            let mut dx = -r + (r % step);
            while dx <= r {
                if dy > 0 || dx > 0 {
                    let d2 = (dx * dx + dy * dy) as f64;
                    if d2 <= rr {
                        let t = 1.0 - d2 / (rr + 1.0);
                        offsets.push((dx, dy, t));
                    }
                }
                dx += step;
            }
            dy += step;
        }
        Self { radius, offsets }
    }

    /// [`Window::new`] (step 1) keeping only the offsets `d` for which `keep(dx, dy)` holds;
    /// `keep` must be point-symmetric (`keep(d) == keep(-d)`), as the cost pairs `d` with
    /// `-d`. For a corner where only part of the neighbourhood is point-symmetric (a ChArUco
    /// corner: the markers' data differ between its two white squares).
    pub fn masked(radius: usize, keep: impl Fn(isize, isize) -> bool) -> Self {
        let mut w = Self::new(radius, 1);
        w.offsets.retain(|&(dx, dy, _)| keep(dx, dy));
        w
    }
}

/// The cost as a quadratic form in m = (1, x, y, xy), x, y the fractional position.
#[derive(Default, Clone, Copy)]
struct Quartic {
    m: [[f64; 4]; 4],
}

impl Quartic {
    fn eval(&self, x: f64, y: f64) -> f64 {
        let v = [1.0, x, y, x * y];
        let mut s = 0.0;
        for a in 0..4 {
            for b in 0..4 {
                s += v[a] * self.m[a][b] * v[b];
            }
        }
        s
    }

    /// Minimum over [0, 1]^2 by alternating exact line minimisations (the cost is
    /// quadratic in x for fixed y and vice versa).
    fn minimise(&self, mut x: f64, mut y: f64) -> (f64, f64) {
        let m = &self.m;
        for _ in 0..60 {
            let (ox, oy) = (x, y);
            // m = a + x b with a = (1, 0, y, 0), b = (0, 1, 0, y).
            let a = [1.0, 0.0, y, 0.0];
            let b = [0.0, 1.0, 0.0, y];
            let (ab, bb) = (quad(m, &a, &b), quad(m, &b, &b));
            if bb > 0.0 {
                x = (-ab / bb).clamp(0.0, 1.0);
            }
            let a = [1.0, x, 0.0, 0.0];
            let b = [0.0, 0.0, 1.0, x];
            let (ab, bb) = (quad(m, &a, &b), quad(m, &b, &b));
            if bb > 0.0 {
                y = (-ab / bb).clamp(0.0, 1.0);
            }
            if (x - ox).abs() < 1e-9 && (y - oy).abs() < 1e-9 {
                break;
            }
        }
        (x, y)
    }
}

fn quad(m: &[[f64; 4]; 4], a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let mut s = 0.0;
    for i in 0..4 {
        for j in 0..4 {
            s += a[i] * m[i][j] * b[j];
        }
    }
    s
}

/// The cost's quadratic form in the cell with top-left pixel (x0, y0); `None` when the
/// window leaves the image.
fn accumulate<T: Sample>(img: &GrayView<'_, T>, win: &Window, x0: isize, y0: isize) -> Option<Quartic> {
    let r = win.radius as isize;
    if x0 - r < 0 || y0 - r < 0 || x0 + r + 1 >= img.width as isize || y0 + r + 1 >= img.height as isize {
        return None;
    }
    let s = img.stride as isize;
    let d = img.data;
    let base = y0 * s + x0;
    let mut acc = [0.0f64; 10];
    for &(dx, dy, w) in &win.offsets {
        let ia = (base + dy * s + dx) as usize;
        let ib = (base - dy * s - dx) as usize;
        let d00 = d[ia].grey() - d[ib].grey();
        let d10 = d[ia + 1].grey() - d[ib + 1].grey();
        let d01 = d[ia + s as usize].grey() - d[ib + s as usize].grey();
        let d11 = d[ia + s as usize + 1].grey() - d[ib + s as usize + 1].grey();
        let e0 = d00 as f64;
        let e1 = (d10 - d00) as f64;
        let e2 = (d01 - d00) as f64;
        let e3 = (d11 - d10 - d01 + d00) as f64;
        let (w0, w1, w2, w3) = (w * e0, w * e1, w * e2, w * e3);
        acc[0] += w0 * e0;
        acc[1] += w0 * e1;
        acc[2] += w0 * e2;
        acc[3] += w0 * e3;
        acc[4] += w1 * e1;
        acc[5] += w1 * e2;
        acc[6] += w1 * e3;
        acc[7] += w2 * e2;
        acc[8] += w2 * e3;
        acc[9] += w3 * e3;
    }
    let m = [
        [acc[0], acc[1], acc[2], acc[3]],
        [acc[1], acc[4], acc[5], acc[6]],
        [acc[2], acc[5], acc[7], acc[8]],
        [acc[3], acc[6], acc[8], acc[9]],
    ];
    Some(Quartic { m })
}

/// Refines a corner from `start` (full-resolution px). Walks from pixel cell to pixel cell
/// while the minimum lies on a cell's edge. `None` when the window leaves the image or the
/// minimum runs more than `max_move` px from `start`.
pub(crate) fn refine<T: Sample>(
    img: &GrayView<'_, T>,
    win: &Window,
    start: [f64; 2],
    max_move: f64,
) -> Option<[f64; 2]> {
    let mut cell = (start[0].floor() as isize, start[1].floor() as isize);
    let (mut x, mut y) = (start[0] - cell.0 as f64, start[1] - cell.1 as f64);
    let mut best: Option<([f64; 2], f64)> = None;
    let mut visited: Vec<(isize, isize)> = Vec::with_capacity(8);
    for _ in 0..8 {
        if visited.contains(&cell) {
            break;
        }
        visited.push(cell);
        let q = accumulate(img, win, cell.0, cell.1)?;
        let (mx, my) = q.minimise(x, y);
        let cost = q.eval(mx, my);
        let p = [cell.0 as f64 + mx, cell.1 as f64 + my];
        if best.is_none_or(|b| cost < b.1) {
            best = Some((p, cost));
        } else {
            break;
        }
        let step_x = if mx <= 1e-9 {
            -1
        } else if mx >= 1.0 - 1e-9 {
            1
        } else {
            0
        };
        let step_y = if my <= 1e-9 {
            -1
        } else if my >= 1.0 - 1e-9 {
            1
        } else {
            0
        };
        if step_x == 0 && step_y == 0 {
            break;
        }
        cell = (cell.0 + step_x, cell.1 + step_y);
        x = if step_x < 0 {
            1.0
        } else if step_x > 0 {
            0.0
        } else {
            mx
        };
        y = if step_y < 0 {
            1.0
        } else if step_y > 0 {
            0.0
        } else {
            my
        };
    }
    let (p, _) = best?;
    let moved = (p[0] - start[0]).hypot(p[1] - start[1]);
    (moved <= max_move).then_some(p)
}

/// [`refine`] on a copy of the neighbourhood smoothed by the binomial kernel [1 2 1] / 4 in
/// each direction (sigma 0.7 px). The kernel is symmetric, so the symmetry centre does not
/// move; the smoother signal makes the bilinear interpolation nearly exact on sharp images
/// (at blur sigma 0.5 px it halves the error). Falls back to the raw image near the border.
pub(crate) fn refine_smoothed<T: Sample>(
    img: &GrayView<'_, T>,
    win: &Window,
    start: [f64; 2],
    max_move: f64,
) -> Option<[f64; 2]> {
    // Room for the window, the walk over a few cells and the interpolation.
    let r = win.radius as isize + 5;
    let (x0, y0) = (start[0].floor() as isize - r, start[1].floor() as isize - r);
    let n = (2 * r + 2) as usize;
    if x0 < 1 || y0 < 1 || x0 + n as isize + 1 > img.width as isize || y0 + n as isize + 1 > img.height as isize {
        return refine(img, win, start, max_move);
    }
    let s = img.stride;
    let d = img.data;
    // Horizontal pass over n + 2 rows, then vertical.
    let mut tmp = vec![0.0f32; n * (n + 2)];
    for (ty, row) in tmp.chunks_exact_mut(n).enumerate() {
        let base = (y0 as usize + ty - 1) * s + x0 as usize;
        for (tx, o) in row.iter_mut().enumerate() {
            let i = base + tx;
            *o = 0.25 * (d[i - 1].grey() + d[i + 1].grey()) + 0.5 * d[i].grey();
        }
    }
    let mut patch = vec![0.0f32; n * n];
    for (y, row) in patch.chunks_exact_mut(n).enumerate() {
        for (x, o) in row.iter_mut().enumerate() {
            *o = 0.25 * (tmp[y * n + x] + tmp[(y + 2) * n + x]) + 0.5 * tmp[(y + 1) * n + x];
        }
    }
    let view = GrayView { width: n, height: n, stride: n, data: &patch[..] };
    let local = [start[0] - x0 as f64, start[1] - y0 as f64];
    refine(&view, win, local, max_move).map(|p| [p[0] + x0 as f64, p[1] + y0 as f64])
}
