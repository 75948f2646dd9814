//! A well-conditioned internal parameterisation of the 25 numbers for the bundle
//! adjustment.
//!
//! The model writes fx(E) = sum kf_xi E^i (Eq. 16) and each distortion coefficient as
//! a w^2 + b w + c in w = 1/f (Eq. 18). Over the currents of a calibration (e.g. 80..225
//! mA) the monomials 1, E, E^2, E^3 are nearly collinear, and so are w^2, w, 1 over the
//! narrow range of w: MINPACK's column scaling equalises their norms but not their angles,
//! and Levenberg-Marquardt then crawls along the resulting valleys (tens of iterations on
//! six-view subsets). The solver therefore works in Chebyshev coefficients on the data's
//! own ranges, t = (E - E_mid) / E_half and s = (w - w_mid) / w_half:
//!
//! ```text
//! fx(E) = sum_k c_xk T_k(t),  k = 0..3        k1(w) = d_2 T_2(s) + d_1 T_1(s) + d_0
//! ```
//!
//! (likewise fy, p1, p2), a linear and exactly invertible change of variables: the minimum,
//! the model and the covariance (mapped back by dx/dz) are those of the paper's
//! parameters; only the path of the iterations changes.

#![allow(clippy::needless_range_loop)] // small fixed-size linear algebra reads best indexed

use super::jacobian::{PARAMS, U0};
use super::observations::View;
use crate::model::camera::cubic;
use crate::model::CameraModel;

/// Monomial coefficients (t^0..t^3) of T_0..T_3.
const MONO_OF_CHEB: [[f64; 4]; 4] =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [-1.0, 0.0, 2.0, 0.0], [0.0, -3.0, 0.0, 4.0]];
/// Chebyshev coefficients (T_0..T_3) of t^0..t^3.
const CHEB_OF_MONO: [[f64; 4]; 4] =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.5, 0.0, 0.5, 0.0], [0.0, 0.75, 0.0, 0.25]];

fn binomial(n: usize, k: usize) -> f64 {
    const ROWS: [[f64; 4]; 4] =
        [[1.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0], [1.0, 2.0, 1.0, 0.0], [1.0, 3.0, 3.0, 1.0]];
    ROWS.get(n).and_then(|r| r.get(k)).copied().unwrap_or(0.0)
}

/// Coefficients of a polynomial of degree < `n` (n <= 4) in x, as Chebyshev
/// coefficients in t = (x - mid) / half.
fn mono_to_cheb(a: [f64; 4], n: usize, mid: f64, half: f64) -> [f64; 4] {
    // In t: a'_j = sum_{k >= j} a_k C(k, j) mid^(k - j) half^j.
    let mut at = [0.0; 4];
    for j in 0..n.min(4) {
        for k in j..n.min(4) {
            at[j] += a[k] * binomial(k, j) * libm::pow(mid, (k - j) as f64) * libm::pow(half, j as f64);
        }
    }
    let mut c = [0.0; 4];
    for j in 0..n.min(4) {
        for i in 0..4 {
            c[i] += at[j] * CHEB_OF_MONO[j][i];
        }
    }
    c
}

/// The inverse of [`mono_to_cheb`].
fn cheb_to_mono(c: [f64; 4], n: usize, mid: f64, half: f64) -> [f64; 4] {
    let mut at = [0.0; 4];
    for i in 0..n.min(4) {
        for j in 0..4 {
            at[j] += c[i] * MONO_OF_CHEB[i][j];
        }
    }
    // In x: t^j = (x - mid)^j / half^j, so a_i = sum_{j >= i} a'_j C(j, i) (-mid)^(j - i) / half^j.
    let mut a = [0.0; 4];
    for i in 0..n.min(4) {
        for j in i..n.min(4) {
            a[i] += at[j] * binomial(j, i) * libm::pow(-mid, (j - i) as f64) / libm::pow(half, j as f64);
        }
    }
    a
}

/// The ranges that define the internal parameters (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Basis {
    e_mid: f64,
    e_half: f64,
    w_mid: f64,
    w_half: f64,
}

impl Basis {
    /// The identity-like basis on E in [-1, 1] mA and w in [-1, 1]; used when the data give
    /// no range (a single current: the solvers refuse that anyway).
    const UNIT: Basis = Basis { e_mid: 0.0, e_half: 1.0, w_mid: 0.0, w_half: 1.0 };

    /// The basis on the range of the views' currents and of w = 2 / (fx + fy) under
    /// `model` at those currents.
    pub fn for_views(views: &[View<'_>], model: &CameraModel) -> Self {
        let (mut elo, mut ehi) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut wlo, mut whi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in views {
            let e = v.e_com_ma;
            elo = elo.min(e);
            ehi = ehi.max(e);
            let f = 0.5 * (cubic(&model.kf_x, e) + cubic(&model.kf_y, e));
            if f > 0.0 {
                wlo = wlo.min(1.0 / f);
                whi = whi.max(1.0 / f);
            }
        }
        if !(ehi > elo && whi > wlo && (ehi - elo).is_finite() && (whi - wlo).is_finite()) {
            return Basis::UNIT;
        }
        Basis {
            e_mid: 0.5 * (ehi + elo),
            e_half: 0.5 * (ehi - elo),
            w_mid: 0.5 * (whi + wlo),
            w_half: 0.5 * (whi - wlo),
        }
    }

    /// The internal parameters z of the model's parameters x.
    pub fn to_internal(&self, x: &[f64; PARAMS]) -> [f64; PARAMS] {
        self.map(x, true)
    }

    /// The model's parameters x of the internal parameters z.
    pub fn to_params(&self, z: &[f64; PARAMS]) -> [f64; PARAMS] {
        self.map(z, false)
    }

    fn map(&self, v: &[f64; PARAMS], forward: bool) -> [f64; PARAMS] {
        let mut out = *v;
        let (ex, ey) = (v.get(6..10), v.get(10..14));
        for (start, part) in [(6, ex), (10, ey)] {
            let Some(&[a0, a1, a2, a3]) = part else { continue };
            let a = [a0, a1, a2, a3];
            let m = if forward {
                mono_to_cheb(a, 4, self.e_mid, self.e_half)
            } else {
                cheb_to_mono(a, 4, self.e_mid, self.e_half)
            };
            if let Some(slot) = out.get_mut(start..start + 4) {
                slot.copy_from_slice(&m);
            }
        }
        for s in [16, 19, 22] {
            // Slots (w^2, w, 1) hold degrees (2, 1, 0): reversed to ascending order.
            let Some(&[q2, q1, q0]) = v.get(s..s + 3) else { continue };
            let m = if forward {
                mono_to_cheb([q0, q1, q2, 0.0], 3, self.w_mid, self.w_half)
            } else {
                cheb_to_mono([q0, q1, q2, 0.0], 3, self.w_mid, self.w_half)
            };
            if let Some(slot) = out.get_mut(s..s + 3) {
                slot.copy_from_slice(&[m[2], m[1], m[0]]);
            }
        }
        out
    }

    /// dx/dz (25 x 25): row i is the gradient of the model's parameter i with respect to
    /// the internal ones (constant: the map is linear).
    pub fn params_jacobian(&self) -> [[f64; PARAMS]; PARAMS] {
        let mut j = [[0.0; PARAMS]; PARAMS];
        for col in 0..PARAMS {
            let mut e = [0.0; PARAMS];
            e[col] = 1.0;
            let x = self.to_params(&e);
            for row in 0..PARAMS {
                j[row][col] = x[row];
            }
        }
        j
    }

    /// d fx / d c_xk at current `e_ma`: T_0..T_3 of t.
    pub fn kf_column(&self, e_ma: f64) -> [f64; 4] {
        let t = (e_ma - self.e_mid) / self.e_half;
        [1.0, t, 2.0 * t * t - 1.0, 4.0 * t * t * t - 3.0 * t]
    }

    /// d k / d (d_2, d_1, d_0) at w, in the slots' order: T_2(s), T_1(s), T_0.
    pub fn a_column(&self, w: f64) -> [f64; 3] {
        let s = (w - self.w_mid) / self.w_half;
        [2.0 * s * s - 1.0, s, 1.0]
    }
}

/// Indices of the four numbers the hold-A0 option pins (kf0x, kf0y, u0, v0).
pub(crate) const A0_INDICES: [usize; 4] = [6, 10, U0, U0 + 1];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::jacobian::to_params;

    #[test]
    fn round_trip_and_the_same_curves() {
        let m = CameraModel::paper_rig();
        let pts = [];
        let views = [View { e_com_ma: 80.0, points: &pts }, View { e_com_ma: 225.0, points: &pts }];
        let b = Basis::for_views(&views, &m);
        let x = to_params(&m);
        let z = b.to_internal(&x);
        let back = b.to_params(&z);
        for i in 0..PARAMS {
            assert!((back[i] - x[i]).abs() <= 1e-9 * x[i].abs().max(1e-12), "{i}: {} vs {}", back[i], x[i]);
        }
        // fx(E) from the Chebyshev coefficients equals the cubic.
        for e in [80.0, 131.0, 225.0] {
            let col = b.kf_column(e);
            let fx: f64 = (0..4).map(|k| z[6 + k] * col[k]).sum();
            assert!((fx / cubic(&m.kf_x, e) - 1.0).abs() < 1e-12);
            let w = 1.0 / 7000.0;
            let aw = b.a_column(w);
            let k1: f64 = (0..3).map(|k| z[16 + k] * aw[k]).sum();
            let want = x[16] * w * w + x[17] * w + x[18];
            assert!((k1 - want).abs() <= 1e-9 * want.abs().max(1e-12), "{k1} vs {want}");
        }
        // dx/dz maps z back to x.
        let j = b.params_jacobian();
        for i in 0..PARAMS {
            let xi: f64 = (0..PARAMS).map(|k| j[i][k] * z[k]).sum();
            assert!((xi - x[i]).abs() <= 1e-9 * x[i].abs().max(1e-12));
        }
    }
}
