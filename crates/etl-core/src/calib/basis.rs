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
//! (likewise fy, p1, p2), an exactly invertible change of variables: the minimum, the model
//! and the covariance (mapped back by dx/dz) are those of the paper's parameters; only the
//! path of the iterations changes.
//!
//! The w range moves with the focal lengths: w_lo and w_hi are 2 / (fx + fy) at the ends
//! of the current range *under the parameters being evaluated*, not under the start. Why:
//! a view's distortion depends on kf only through w_j = 2 / (fx(E_j) + fy(E_j)), and on
//! the paper rig p1 is the small difference of a5 w and a6 (2.3e-5 against -1.9e-5), so a
//! 1 % change of kf at fixed a moves every view's p1 by about 6 % (0.6 px at the image
//! edge). At fixed Chebyshev coefficients d, s_j = (w_j - w_mid) / w_half barely moves
//! when kf does (w_j and the ends move together), so the views' distortion stays where the
//! data put it while kf moves: the bilinear coupling that made the LM crawl on six-view
//! subsets (10 iterations on average, 20 at worst, with a truth without distortion 4) is
//! gone from the parameterisation. The price: the map z -> x is nonlinear in the kf part,
//! so dx/dz is evaluated at z ([`Basis::params_jacobian`]).

use super::observations::View;
use super::params::{DISTORTION_TRIPLES, KF_X, KF_Y, PARAMS};
use crate::model::camera::cubic;

/// Where fx's and fy's coefficients start (kf0x, kf0y).
const KF_STARTS: [usize; 2] = [KF_X.start, KF_Y.start];
/// Where each distortion coefficient's a-triple starts (a1, a4, a7).
const A_STARTS: [usize; 3] = [DISTORTION_TRIPLES[0].start, DISTORTION_TRIPLES[1].start, DISTORTION_TRIPLES[2].start];

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

/// The current range that defines the internal parameters (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Basis {
    e_mid: f64,
    e_half: f64,
}

/// The w range (mid, half) under some focal-length coefficients, with its gradient with
/// respect to the Chebyshev coefficients of fx and fy (internal slots 6..14).
struct WRange {
    mid: f64,
    half: f64,
    d_mid: [f64; 8],
    d_half: [f64; 8],
}

/// `N` numbers of `v` from `at` (0 past the end: the callers' ranges lie inside).
fn read<const N: usize>(v: &[f64; PARAMS], at: usize) -> [f64; N] {
    core::array::from_fn(|k| v.get(at + k).copied().unwrap_or(0.0))
}

/// Writes `vals` into `v` from `at`.
fn write(v: &mut [f64; PARAMS], at: usize, vals: &[f64]) {
    for (slot, &val) in v.iter_mut().skip(at).zip(vals) {
        *slot = val;
    }
}

/// Sets entry (row, col) of a 25 x 25 matrix.
fn set(j: &mut [[f64; PARAMS]; PARAMS], row: usize, col: usize, val: f64) {
    if let Some(x) = j.get_mut(row).and_then(|r| r.get_mut(col)) {
        *x = val;
    }
}

impl Basis {
    /// The identity-like basis on E in [-1, 1] mA; used when the data give no range (a
    /// single current: the solvers refuse that anyway).
    const UNIT: Basis = Basis { e_mid: 0.0, e_half: 1.0 };

    /// The basis on the range of the views' currents (the w range follows the parameters,
    /// see [`Basis::params_jacobian`]).
    pub fn for_views(views: &[View<'_>]) -> Self {
        let (mut elo, mut ehi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in views {
            elo = elo.min(v.e_com_ma);
            ehi = ehi.max(v.e_com_ma);
        }
        if !(ehi > elo && (ehi - elo).is_finite()) {
            return Basis::UNIT;
        }
        Basis { e_mid: 0.5 * (ehi + elo), e_half: 0.5 * (ehi - elo) }
    }

    /// w = 2 / (fx + fy) at the ends of the current range under the monomial kf of `x`,
    /// as (mid, half), with d(mid, half)/d(Chebyshev kf coefficients): with
    /// fx(E_lo) = sum c_xm T_m(-1) = sum c_xm (-1)^m and fx(E_hi) = sum c_xm,
    /// dw/dc = -w^2 / 2 dfx/dc. A degenerate range (w_lo = w_hi, or a non-positive focal
    /// length) falls back to mid 0, half 1 (the solver's trial step is then rejected by the
    /// projection's own checks).
    fn w_range(&self, x: &[f64; PARAMS]) -> WRange {
        let (lo, hi) = (self.e_mid - self.e_half, self.e_mid + self.e_half);
        let (kx, ky) = (read::<4>(x, KF_X.start), read::<4>(x, KF_Y.start));
        let f = |e: f64| 0.5 * (cubic(&kx, e) + cubic(&ky, e));
        let (flo, fhi) = (f(lo), f(hi));
        let (wlo, whi) = (1.0 / flo, 1.0 / fhi);
        let half = 0.5 * (whi - wlo);
        if !(flo > 0.0 && fhi > 0.0 && half != 0.0 && half.is_finite()) {
            return WRange { mid: 0.0, half: 1.0, d_mid: [0.0; 8], d_half: [0.0; 8] };
        }
        // w = 2 / (fx + fy): dw/dfx = dw/dfy = -w^2 / 2.
        let (glo, ghi) = (-0.5 * wlo * wlo, -0.5 * whi * whi);
        // Slot c: coefficient m = c % 4 of fx (c < 4) or fy; T_m(-1) = (-1)^m, T_m(1) = 1.
        let dlo = |c: usize| if c % 2 == 0 { glo } else { -glo };
        let d_mid: [f64; 8] = core::array::from_fn(|c| 0.5 * (ghi + dlo(c)));
        let d_half: [f64; 8] = core::array::from_fn(|c| 0.5 * (ghi - dlo(c)));
        WRange { mid: 0.5 * (whi + wlo), half, d_mid, d_half }
    }

    /// The internal parameters z of the model's parameters x.
    pub fn to_internal(&self, x: &[f64; PARAMS]) -> [f64; PARAMS] {
        let mut z = *x;
        for start in KF_STARTS {
            write(&mut z, start, &mono_to_cheb(read(x, start), 4, self.e_mid, self.e_half));
        }
        let w = self.w_range(x);
        for s in A_STARTS {
            // Slots (w^2, w, 1) hold degrees (2, 1, 0): reversed to ascending order.
            let [q2, q1, q0] = read::<3>(x, s);
            let m = mono_to_cheb([q0, q1, q2, 0.0], 3, w.mid, w.half);
            write(&mut z, s, &[m[2], m[1], m[0]]);
        }
        z
    }

    /// The model's parameters x of the internal parameters z.
    pub fn to_params(&self, z: &[f64; PARAMS]) -> [f64; PARAMS] {
        let mut x = *z;
        for start in KF_STARTS {
            write(&mut x, start, &cheb_to_mono(read(z, start), 4, self.e_mid, self.e_half));
        }
        let w = self.w_range(&x);
        for s in A_STARTS {
            let [d2, d1, d0] = read::<3>(z, s);
            let m = cheb_to_mono([d0, d1, d2, 0.0], 3, w.mid, w.half);
            write(&mut x, s, &[m[2], m[1], m[0]]);
        }
        x
    }

    /// dx/dz (25 x 25) at internal parameters `z`: row i is the gradient of the model's
    /// parameter i with respect to the internal ones.
    ///
    /// Linear parts: the identity (om, T, u0, v0), the Chebyshev-to-monomial maps of kf
    /// and of each distortion coefficient's d at the current w range. The nonlinear part:
    /// a distortion coefficient k(w) = sum_i d_i T_i(s), s = (w - mid) / half, at fixed w
    /// changes with the range as dk/dmid = -k'(s) / half and dk/dhalf = -s k'(s) / half,
    /// whose Chebyshev coefficients are -(d_1, 4 d_2, 0) / half and
    /// -(2 d_2, d_1, 2 d_2) / half (k' = d_1 + 4 d_2 s, s k' = 2 d_2 T_0 + d_1 T_1 +
    /// 2 d_2 T_2); the range moves with the kf coefficients ([`Basis::w_range`]).
    pub fn params_jacobian(&self, z: &[f64; PARAMS]) -> [[f64; PARAMS]; PARAMS] {
        let mut j = [[0.0; PARAMS]; PARAMS];
        for i in 0..PARAMS {
            set(&mut j, i, i, 1.0);
        }
        for start in KF_STARTS {
            for col in 0..4 {
                let unit: [f64; 4] = core::array::from_fn(|k| if k == col { 1.0 } else { 0.0 });
                for (row, a) in cheb_to_mono(unit, 4, self.e_mid, self.e_half).into_iter().enumerate() {
                    set(&mut j, start + row, start + col, a);
                }
            }
        }
        let x = self.to_params(z);
        let w = self.w_range(&x);
        for s in A_STARTS {
            // The slots hold z (T_2, T_1, T_0) and x (w^2, w, 1): descending degree.
            let [d2, d1, _] = read::<3>(z, s);
            let to_slots = |m: [f64; 4]| [m[2], m[1], m[0]];
            for (k, unit) in [[0.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]].into_iter().enumerate()
            {
                for (row, a) in to_slots(cheb_to_mono(unit, 3, w.mid, w.half)).into_iter().enumerate() {
                    set(&mut j, s + row, s + k, a);
                }
            }
            let ih = 1.0 / w.half;
            let da_dmid = to_slots(cheb_to_mono([-d1 * ih, -4.0 * d2 * ih, 0.0, 0.0], 3, w.mid, w.half));
            let da_dhalf = to_slots(cheb_to_mono([-2.0 * d2 * ih, -d1 * ih, -2.0 * d2 * ih, 0.0], 3, w.mid, w.half));
            for (row, (dm, dh)) in da_dmid.into_iter().zip(da_dhalf).enumerate() {
                for (c, (&gm, &gh)) in w.d_mid.iter().zip(w.d_half.iter()).enumerate() {
                    // Slot c < 8 runs over kf_x then kf_y (contiguous).
                    set(&mut j, s + row, KF_X.at(c), dm * gm + dh * gh);
                }
            }
        }
        j
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::jacobian::to_params;
    use crate::model::CameraModel;

    #[test]
    fn round_trip_and_the_same_curves() {
        let m = CameraModel::paper_rig();
        let pts = [];
        let views = [View { e_com_ma: 80.0, points: &pts }, View { e_com_ma: 225.0, points: &pts }];
        let b = Basis::for_views(&views);
        let x = to_params(&m);
        let z = b.to_internal(&x);
        let back = b.to_params(&z);
        for i in 0..PARAMS {
            assert!((back[i] - x[i]).abs() <= 1e-9 * x[i].abs().max(1e-12), "{i}: {} vs {}", back[i], x[i]);
        }
        // fx(E) from the Chebyshev coefficients equals the cubic; k1(w) from its Chebyshev
        // coefficients on the w range at the ends of 80..225 mA equals the quadratic.
        let f = |e: f64| 0.5 * (cubic(&m.kf_x, e) + cubic(&m.kf_y, e));
        let (wlo, whi) = (1.0 / f(80.0), 1.0 / f(225.0));
        for e in [80.0, 131.0, 225.0] {
            let t = (e - 152.5) / 72.5;
            let col = [1.0, t, 2.0 * t * t - 1.0, 4.0 * t * t * t - 3.0 * t];
            let fx: f64 = (0..4).map(|k| z[KF_X.at(k)] * col[k]).sum();
            assert!((fx / cubic(&m.kf_x, e) - 1.0).abs() < 1e-12);
            let w = 1.0 / f(e);
            let s = (w - 0.5 * (whi + wlo)) / (0.5 * (whi - wlo));
            let k1 = z[16] * (2.0 * s * s - 1.0) + z[17] * s + z[18];
            let want = x[16] * w * w + x[17] * w + x[18];
            assert!((k1 - want).abs() <= 1e-9 * want.abs().max(1e-12), "{k1} vs {want}");
        }
    }

    /// dx/dz against central differences of `to_params`, at a point where every part of
    /// the map (kf, the moving w range, d) is exercised.
    #[test]
    fn params_jacobian_matches_finite_differences() {
        let m = CameraModel::paper_rig();
        let pts = [];
        let views = [View { e_com_ma: 80.0, points: &pts }, View { e_com_ma: 225.0, points: &pts }];
        let b = Basis::for_views(&views);
        let mut x = to_params(&m);
        x[7] *= 1.03;
        x[12] *= 0.97;
        let z = b.to_internal(&x);
        let j = b.params_jacobian(&z);
        for col in 0..PARAMS {
            let h = 1e-6 * z[col].abs().max(1e-12);
            let (mut zp, mut zm) = (z, z);
            zp[col] += h;
            zm[col] -= h;
            let (xp, xm) = (b.to_params(&zp), b.to_params(&zm));
            for row in 0..PARAMS {
                let fd = (xp[row] - xm[row]) / (2.0 * h);
                let scale = (j[row][col].abs() + fd.abs()).max(1e-300);
                let ok =
                    (fd - j[row][col]).abs() <= 1e-5 * scale || (fd - j[row][col]).abs() * h <= 1e-12 * x[row].abs();
                assert!(ok, "dx{row}/dz{col}: analytic {} vs {fd}", j[row][col]);
            }
        }
    }
}
