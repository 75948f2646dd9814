//! The saddle response: where the smoothed image looks like the crossing of two edges.
//!
//! At an X-junction the Hessian of the (blurred) intensity has one positive and one negative
//! eigenvalue, so `R = I_xy^2 - I_xx I_yy = -det H` is large and positive; along a straight
//! edge `H` has rank one (`R = 0`), at a blob `R < 0`, and at the L-shaped corner of a single
//! square `R` is a quarter of an X-junction's of the same contrast.

use rayon::prelude::*;

use crate::grey::Plane;

/// A local maximum of the saddle response, at sub-pixel position (detection-level pixels).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Saddle {
    pub p: [f32; 2],
    pub strength: f32,
}

/// Absolute floor of the response, (grey levels / px^2)^2 on the 8-bit scale: noise of a few
/// grey levels after smoothing stays two orders of magnitude below.
const RESPONSE_FLOOR: f32 = 0.3;
/// Maxima weaker than this fraction of the strongest are not corners of the same board
/// (allows a 10-fold contrast drop across the image from uneven lighting).
const RESPONSE_RELATIVE: f32 = 0.01;

/// Local maxima (5 x 5) of the saddle response of the smoothed plane, strongest first.
pub(crate) fn saddles(s: &Plane) -> Vec<Saddle> {
    let (w, h) = (s.width, s.height);
    if w < 8 || h < 8 {
        return Vec::new();
    }
    // A reused buffer (the smoothing's intermediate plane, just dropped): every sample is
    // written, the border ones with zeros.
    let mut plane = Plane::scratch(w, h);
    plane.data.par_chunks_exact_mut(w).enumerate().for_each(|(y, out)| {
        if y == 0 || y == h - 1 {
            out.fill(0.0);
            return;
        }
        let up = &s.data[(y - 1) * w..y * w];
        let mid = &s.data[y * w..(y + 1) * w];
        let dn = &s.data[(y + 1) * w..(y + 2) * w];
        (out[0], out[w - 1]) = (0.0, 0.0);
        for x in 1..w - 1 {
            let c = mid[x];
            let ixx = mid[x + 1] - 2.0 * c + mid[x - 1];
            let iyy = dn[x] - 2.0 * c + up[x];
            let ixy = 0.25 * (dn[x + 1] - dn[x - 1] - up[x + 1] + up[x - 1]);
            out[x] = ixy * ixy - ixx * iyy;
        }
    });
    let r = &plane.data;
    let rmax = r.iter().fold(0.0f32, |a, &b| a.max(b));
    let thr = RESPONSE_FLOOR.max(RESPONSE_RELATIVE * rmax);
    let mut out = Vec::new();
    for y in 3..h - 3 {
        for x in 3..w - 3 {
            let v = r[y * w + x];
            if v <= thr {
                continue;
            }
            let mut is_max = true;
            'n: for dy in -2isize..=2 {
                for dx in -2isize..=2 {
                    if dx == 0 && dy == 0 {
                        continue;
                    }
                    let q = r[(y as isize + dy) as usize * w + (x as isize + dx) as usize];
                    // Ties go to the first in raster order.
                    if q > v || (q == v && (dy < 0 || (dy == 0 && dx < 0))) {
                        is_max = false;
                        break 'n;
                    }
                }
            }
            if !is_max {
                continue;
            }
            // Newton step to the stationary point of the intensity (the saddle).
            let g = |dx: isize, dy: isize| s.get((x as isize + dx) as usize, (y as isize + dy) as usize);
            let gx = 0.5 * (g(1, 0) - g(-1, 0));
            let gy = 0.5 * (g(0, 1) - g(0, -1));
            let ixx = g(1, 0) - 2.0 * g(0, 0) + g(-1, 0);
            let iyy = g(0, 1) - 2.0 * g(0, 0) + g(0, -1);
            let ixy = 0.25 * (g(1, 1) - g(-1, 1) - g(1, -1) + g(-1, -1));
            let det = ixx * iyy - ixy * ixy;
            let (mut ox, mut oy) = (0.0, 0.0);
            if det.abs() > 1e-12 {
                ox = -(iyy * gx - ixy * gy) / det;
                oy = -(-ixy * gx + ixx * gy) / det;
                if !(ox.abs() <= 1.0 && oy.abs() <= 1.0) {
                    ox = 0.0;
                    oy = 0.0;
                }
            }
            out.push(Saddle { p: [x as f32 + ox, y as f32 + oy], strength: v });
        }
    }
    out.sort_by(|a, b| b.strength.total_cmp(&a.strength));
    out
}
