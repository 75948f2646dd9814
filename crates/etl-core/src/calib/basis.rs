//! A well-conditioned internal parameterisation of the model's numbers for the bundle
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
//! With a moving centre (Eq. C1-C3) the per-view T_z(E) = T_z - dz1 E - dz2 E^2 and
//! u0(E) = u0 + u1 E (likewise v0) are polynomials in E too, and take the same map:
//! (T_z, -dz1, -dz2) and (u0, u1) as monomial coefficients, Chebyshev coefficients in t
//! inside (`CentreGroup`). Without it, T_z and dz would be as collinear as kf0 and kf1.
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
use super::params::Layout;
use crate::fit::basis::{BINOMIAL, CHEB_TO_MONO, MAX_BASIS_DEGREE, MONO_TO_CHEB};
use crate::model::{FocalPoly, MAX_FOCAL_DEGREE};

/// Most coefficients of one polynomial the maps handle (a focal polynomial of degree 5).
const MAXN: usize = MAX_FOCAL_DEGREE + 1;

// The conversions use the fit's tables (degree 6), of which the first MAXN rows and
// columns are those of degree MAX_FOCAL_DEGREE.
const _: () = assert!(MAXN <= MAX_BASIS_DEGREE + 1);

fn binomial(n: usize, k: usize) -> f64 {
    BINOMIAL.get(n).and_then(|r| r.get(k)).copied().unwrap_or(0.0)
}

/// Coefficients of a polynomial of degree < `n` (n <= 6) in x, as Chebyshev
/// coefficients in t = (x - mid) / half.
fn mono_to_cheb(a: [f64; MAXN], n: usize, mid: f64, half: f64) -> [f64; MAXN] {
    let n = n.min(MAXN);
    // In t: a'_j = sum_{k >= j} a_k C(k, j) mid^(k - j) half^j.
    let mut at = [0.0; MAXN];
    for j in 0..n {
        for k in j..n {
            at[j] += a[k] * binomial(k, j) * libm::pow(mid, (k - j) as f64) * libm::pow(half, j as f64);
        }
    }
    let mut c = [0.0; MAXN];
    for j in 0..n {
        for i in 0..n {
            c[i] += at[j] * MONO_TO_CHEB[j][i];
        }
    }
    c
}

/// The inverse of [`mono_to_cheb`].
fn cheb_to_mono(c: [f64; MAXN], n: usize, mid: f64, half: f64) -> [f64; MAXN] {
    let n = n.min(MAXN);
    let mut at = [0.0; MAXN];
    for i in 0..n {
        for j in 0..n {
            at[j] += c[i] * CHEB_TO_MONO[i][j];
        }
    }
    // In x: t^j = (x - mid)^j / half^j, so a_i = sum_{j >= i} a'_j C(j, i) (-mid)^(j - i) / half^j.
    let mut a = [0.0; MAXN];
    for i in 0..n {
        for j in i..n {
            a[i] += at[j] * binomial(j, i) * libm::pow(-mid, (j - i) as f64) / libm::pow(half, j as f64);
        }
    }
    a
}

/// The current range that defines the internal parameters (see the module documentation),
/// for one layout of the parameter vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Basis {
    layout: Layout,
    e_mid: f64,
    e_half: f64,
}

/// The w range (mid, half) under some focal-length coefficients, with its gradient with
/// respect to the Chebyshev coefficients of fx and fy (kf_x's slots, then kf_y's).
struct WRange {
    mid: f64,
    half: f64,
    d_mid: [f64; 2 * MAXN],
    d_half: [f64; 2 * MAXN],
}

/// `n` numbers of `v` from `at` (0 past the end of `v` or past `n`: the callers' ranges lie
/// inside).
fn read<const N: usize>(v: &[f64; N], at: usize, n: usize) -> [f64; MAXN] {
    core::array::from_fn(|k| if k < n { v.get(at + k).copied().unwrap_or(0.0) } else { 0.0 })
}

/// Writes the first `n` of `vals` into `v` from `at`.
fn write<const N: usize>(v: &mut [f64; N], at: usize, vals: &[f64], n: usize) {
    for (slot, &val) in v.iter_mut().skip(at).zip(vals.iter().take(n)) {
        *slot = val;
    }
}

/// Sets entry (row, col) of an N x N matrix.
fn set<const N: usize>(j: &mut [[f64; N]; N], row: usize, col: usize, val: f64) {
    if let Some(x) = j.get_mut(row).and_then(|r| r.get_mut(col)) {
        *x = val;
    }
}

/// One polynomial in E that a moving centre spreads over slots that are not contiguous
/// (T_z(E) over tz, dz1, dz2; u0(E) over u0, u1; v0(E) over v0, v1): its monomial
/// coefficient i is `sign[i] x[slot[i]]`.
#[derive(Clone, Copy)]
struct CentreGroup {
    slots: [usize; 3],
    sign: [f64; 3],
    n: usize,
}

impl CentreGroup {
    /// Slot `i` and its sign, for `i` below the group's length (else `None`).
    fn slot(&self, i: usize) -> Option<(usize, f64)> {
        if i < self.n {
            Some((*self.slots.get(i)?, *self.sign.get(i)?))
        } else {
            None
        }
    }

    /// The monomial coefficients of the group in `x` (signs applied).
    fn gather<const N: usize>(&self, x: &[f64; N]) -> [f64; MAXN] {
        core::array::from_fn(|i| self.slot(i).map_or(0.0, |(at, sign)| sign * x.get(at).copied().unwrap_or(0.0)))
    }

    /// The group's raw slots of `v` (no signs).
    fn read<const N: usize>(&self, v: &[f64; N]) -> [f64; MAXN] {
        core::array::from_fn(|i| self.slot(i).map_or(0.0, |(at, _)| v.get(at).copied().unwrap_or(0.0)))
    }

    /// Writes `vals` into the group's slots, times the signs when `signed`.
    fn write<const N: usize>(&self, v: &mut [f64; N], vals: [f64; MAXN], signed: bool) {
        for (i, &val) in vals.iter().enumerate() {
            if let Some((at, sign)) = self.slot(i) {
                if let Some(out) = v.get_mut(at) {
                    *out = if signed { sign * val } else { val };
                }
            }
        }
    }
}

/// The a-triple (w^2, w, 1) in slots [descending degree] as ascending coefficients.
fn triple_up(v: [f64; MAXN]) -> [f64; MAXN] {
    [v[2], v[1], v[0], 0.0, 0.0, 0.0]
}

impl Basis {
    /// The basis on the range of the views' currents (the w range follows the parameters,
    /// see [`Basis::params_jacobian`]) for parameter vectors laid out by `layout`; the
    /// identity-like range E in [-1, 1] mA when the data give no range (a single current:
    /// the solvers refuse that anyway).
    pub fn for_views(views: &[View<'_>], layout: Layout) -> Self {
        let (mut elo, mut ehi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in views {
            elo = elo.min(v.e_com_ma);
            ehi = ehi.max(v.e_com_ma);
        }
        if !(ehi > elo && (ehi - elo).is_finite()) {
            return Basis { layout, e_mid: 0.0, e_half: 1.0 };
        }
        Basis { layout, e_mid: 0.5 * (ehi + elo), e_half: 0.5 * (ehi - elo) }
    }

    /// The layout of the vectors this basis maps.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// Coefficients per focal polynomial (degree + 1).
    fn nk(&self) -> usize {
        self.layout.focal_degree() + 1
    }

    /// Where fx's and fy's coefficients start (kf0x, kf0y).
    fn kf_starts(&self) -> [usize; 2] {
        [self.layout.kf0x(), self.layout.kf0y()]
    }

    /// The moving centre's polynomials in E (none for a fixed centre).
    fn centre_groups(&self) -> impl Iterator<Item = CentreGroup> + '_ {
        let l = &self.layout;
        let (dz, cp) = (l.centre_dz(), l.centre_principal_point());
        let tz = l.translation().at(2);
        let groups = [
            CentreGroup { slots: [tz, dz.at(0), dz.at(1)], sign: [1.0, -1.0, -1.0], n: 3 },
            CentreGroup { slots: [l.u0(), cp.at(0), 0], sign: [1.0; 3], n: 2 },
            CentreGroup { slots: [l.v0(), cp.at(1), 0], sign: [1.0; 3], n: 2 },
        ];
        groups.into_iter().filter(|_| l.moving_centre())
    }

    /// Where each distortion coefficient's a-triple starts (a1, a4, ...).
    fn a_starts(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.layout.model().coefficient_count()).map(|c| self.layout.distortion_triple(c).start)
    }

    /// w = 2 / (fx + fy) at the ends of the current range under the monomial kf of `x`,
    /// as (mid, half), with d(mid, half)/d(Chebyshev kf coefficients): with
    /// fx(E_lo) = sum c_xm T_m(-1) = sum c_xm (-1)^m and fx(E_hi) = sum c_xm,
    /// dw/dc = -w^2 / 2 dfx/dc. A degenerate range (w_lo = w_hi, or a non-positive focal
    /// length) falls back to mid 0, half 1 (the solver's trial step is then rejected by the
    /// projection's own checks).
    fn w_range<const N: usize>(&self, x: &[f64; N]) -> WRange {
        let nk = self.nk();
        let (lo, hi) = (self.e_mid - self.e_half, self.e_mid + self.e_half);
        let [sx, sy] = self.kf_starts();
        let (cx, cy) = (read(x, sx, nk), read(x, sy, nk));
        let poly = |c: &[f64; MAXN]| c.get(..nk).map(FocalPoly::new);
        let (Some(Ok(kx)), Some(Ok(ky))) = (poly(&cx), poly(&cy)) else {
            return WRange { mid: 0.0, half: 1.0, d_mid: [0.0; 2 * MAXN], d_half: [0.0; 2 * MAXN] };
        };
        let f = |e: f64| 0.5 * (kx.eval(e) + ky.eval(e));
        let (flo, fhi) = (f(lo), f(hi));
        let (wlo, whi) = (1.0 / flo, 1.0 / fhi);
        let half = 0.5 * (whi - wlo);
        if !(flo > 0.0 && fhi > 0.0 && half != 0.0 && half.is_finite()) {
            return WRange { mid: 0.0, half: 1.0, d_mid: [0.0; 2 * MAXN], d_half: [0.0; 2 * MAXN] };
        }
        // w = 2 / (fx + fy): dw/dfx = dw/dfy = -w^2 / 2.
        let (glo, ghi) = (-0.5 * wlo * wlo, -0.5 * whi * whi);
        // Slot c: coefficient m = c % nk of fx (c < nk) or fy; T_m(-1) = (-1)^m, T_m(1) = 1.
        let dlo = |c: usize| if c.checked_rem(nk).unwrap_or(0) % 2 == 0 { glo } else { -glo };
        let live = |c: usize| c < 2 * nk;
        let d_mid: [f64; 2 * MAXN] = core::array::from_fn(|c| if live(c) { 0.5 * (ghi + dlo(c)) } else { 0.0 });
        let d_half: [f64; 2 * MAXN] = core::array::from_fn(|c| if live(c) { 0.5 * (ghi - dlo(c)) } else { 0.0 });
        WRange { mid: 0.5 * (whi + wlo), half, d_mid, d_half }
    }

    /// The internal parameters z of the model's parameters x.
    pub fn to_internal<const N: usize>(&self, x: &[f64; N]) -> [f64; N] {
        let nk = self.nk();
        let mut z = *x;
        for start in self.kf_starts() {
            write(&mut z, start, &mono_to_cheb(read(x, start, nk), nk, self.e_mid, self.e_half), nk);
        }
        for g in self.centre_groups() {
            g.write(&mut z, mono_to_cheb(g.gather(x), g.n, self.e_mid, self.e_half), false);
        }
        let w = self.w_range(x);
        for s in self.a_starts() {
            // Slots (w^2, w, 1) hold degrees (2, 1, 0): reversed to ascending order.
            let m = mono_to_cheb(triple_up(read(x, s, 3)), 3, w.mid, w.half);
            write(&mut z, s, &[m[2], m[1], m[0]], 3);
        }
        z
    }

    /// The model's parameters x of the internal parameters z.
    pub fn to_params<const N: usize>(&self, z: &[f64; N]) -> [f64; N] {
        let nk = self.nk();
        let mut x = *z;
        for start in self.kf_starts() {
            write(&mut x, start, &cheb_to_mono(read(z, start, nk), nk, self.e_mid, self.e_half), nk);
        }
        for g in self.centre_groups() {
            g.write(&mut x, cheb_to_mono(g.read(z), g.n, self.e_mid, self.e_half), true);
        }
        let w = self.w_range(&x);
        for s in self.a_starts() {
            let m = cheb_to_mono(triple_up(read(z, s, 3)), 3, w.mid, w.half);
            write(&mut x, s, &[m[2], m[1], m[0]], 3);
        }
        x
    }

    /// dx/dz (N x N) at internal parameters `z`: row i is the gradient of the model's
    /// parameter i with respect to the internal ones.
    ///
    /// Linear parts: the identity (om, T, u0, v0), the Chebyshev-to-monomial maps of kf
    /// and of each distortion coefficient's d at the current w range. The nonlinear part:
    /// a distortion coefficient k(w) = sum_i d_i T_i(s), s = (w - mid) / half, at fixed w
    /// changes with the range as dk/dmid = -k'(s) / half and dk/dhalf = -s k'(s) / half,
    /// whose Chebyshev coefficients are -(d_1, 4 d_2, 0) / half and
    /// -(2 d_2, d_1, 2 d_2) / half (k' = d_1 + 4 d_2 s, s k' = 2 d_2 T_0 + d_1 T_1 +
    /// 2 d_2 T_2); the range moves with the kf coefficients (`Basis::w_range`).
    pub fn params_jacobian<const N: usize>(&self, z: &[f64; N]) -> [[f64; N]; N] {
        let nk = self.nk();
        let mut j = [[0.0; N]; N];
        for i in 0..N {
            set(&mut j, i, i, 1.0);
        }
        for start in self.kf_starts() {
            for col in 0..nk {
                let unit: [f64; MAXN] = core::array::from_fn(|k| if k == col { 1.0 } else { 0.0 });
                for (row, a) in cheb_to_mono(unit, nk, self.e_mid, self.e_half).into_iter().take(nk).enumerate() {
                    set(&mut j, start + row, start + col, a);
                }
            }
        }
        for g in self.centre_groups() {
            for col in 0..g.n {
                let unit: [f64; MAXN] = core::array::from_fn(|k| if k == col { 1.0 } else { 0.0 });
                for (row, a) in cheb_to_mono(unit, g.n, self.e_mid, self.e_half).into_iter().enumerate() {
                    if let (Some((r, sign)), Some((c, _))) = (g.slot(row), g.slot(col)) {
                        set(&mut j, r, c, sign * a);
                    }
                }
            }
        }
        let x = self.to_params(z);
        let w = self.w_range(&x);
        let kf0x = self.layout.kf0x();
        for s in self.a_starts() {
            // The slots hold z (T_2, T_1, T_0) and x (w^2, w, 1): descending degree.
            let [d2, d1, ..] = read(z, s, 3);
            let to_slots = |m: [f64; MAXN]| [m[2], m[1], m[0]];
            for (k, unit) in [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]].into_iter().enumerate() {
                let up = [unit[0], unit[1], unit[2], 0.0, 0.0, 0.0];
                for (row, a) in to_slots(cheb_to_mono(up, 3, w.mid, w.half)).into_iter().enumerate() {
                    set(&mut j, s + row, s + k, a);
                }
            }
            let ih = 1.0 / w.half;
            let da_dmid = to_slots(cheb_to_mono([-d1 * ih, -4.0 * d2 * ih, 0.0, 0.0, 0.0, 0.0], 3, w.mid, w.half));
            let da_dhalf =
                to_slots(cheb_to_mono([-2.0 * d2 * ih, -d1 * ih, -2.0 * d2 * ih, 0.0, 0.0, 0.0], 3, w.mid, w.half));
            for (row, (dm, dh)) in da_dmid.into_iter().zip(da_dhalf).enumerate() {
                for (c, (&gm, &gh)) in w.d_mid.iter().zip(w.d_half.iter()).enumerate().take(2 * nk) {
                    // Slot c < 2 nk runs over kf_x then kf_y (contiguous).
                    set(&mut j, s + row, kf0x + c, dm * gm + dh * gh);
                }
            }
        }
        j
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::jacobian::to_params_n;
    use crate::model::{CameraModel, DistortionA, DistortionModel, MovingCentre};

    /// The paper rig, and the strong rig with quintic focal polynomials (every slot of the
    /// largest layout in play).
    fn models() -> [CameraModel; 2] {
        let mut strong = CameraModel::strong_distortion_rig();
        strong.kf_x = FocalPoly::new(&[1500.0, -1.96, 0.0056, -8.4e-6, 2e-9, -1e-12]).unwrap();
        strong.kf_y = FocalPoly::new(&[1510.0, -1.96, 0.0056, -8.4e-6, 2e-9, -1e-12]).unwrap();
        [CameraModel::paper_rig(), strong]
    }

    fn round_trip<const N: usize>(m: &CameraModel) {
        let pts = [];
        let views = [View { e_com_ma: 80.0, points: &pts }, View { e_com_ma: 225.0, points: &pts }];
        let layout = m.layout();
        let b = Basis::for_views(&views, layout);
        let x = to_params_n::<N>(m).unwrap();
        let z = b.to_internal(&x);
        let back = b.to_params(&z);
        for i in 0..N {
            assert!((back[i] - x[i]).abs() <= 1e-9 * x[i].abs().max(1e-12), "{i}: {} vs {}", back[i], x[i]);
        }
        // fx(E) from the Chebyshev coefficients equals the polynomial; k1(w) from its
        // Chebyshev coefficients on the w range at the ends of 80..225 mA equals the
        // quadratic.
        let f = |e: f64| 0.5 * (m.kf_x.eval(e) + m.kf_y.eval(e));
        let (wlo, whi) = (1.0 / f(80.0), 1.0 / f(225.0));
        let nk = layout.focal_degree() + 1;
        for e in [80.0, 131.0, 225.0] {
            let t: f64 = (e - 152.5) / 72.5;
            // T_k(t) = cos(k acos t).
            let fx: f64 = (0..nk).map(|k| z[layout.kf_x().at(k)] * libm::cos(k as f64 * libm::acos(t))).sum();
            assert!((fx / m.kf_x.eval(e) - 1.0).abs() < 1e-12);
            let w = 1.0 / f(e);
            let s = (w - 0.5 * (whi + wlo)) / (0.5 * (whi - wlo));
            let a1 = layout.distortion_a().start;
            let k1 = z[a1] * (2.0 * s * s - 1.0) + z[a1 + 1] * s + z[a1 + 2];
            let want = x[a1] * w * w + x[a1 + 1] * w + x[a1 + 2];
            assert!((k1 - want).abs() <= 1e-9 * want.abs().max(1e-12), "{k1} vs {want}");
        }
    }

    #[test]
    fn round_trip_and_the_same_curves() {
        let [paper, strong] = models();
        round_trip::<25>(&paper);
        round_trip::<35>(&strong);
        let [moving_paper, moving_strong] = moving_models();
        round_trip::<29>(&moving_paper);
        round_trip::<39>(&moving_strong);
        // Every degree of the paper family: a linear fx(E) round-trips too.
        let mut linear = paper;
        linear.kf_x = FocalPoly::new(&[5380.0, -3.0]).unwrap();
        linear.kf_y = FocalPoly::new(&[5430.0, -3.0]).unwrap();
        round_trip::<21>(&linear);
        assert_eq!(DistortionA::zero(DistortionModel::Paper).as_slice().len(), 9);
    }

    /// dx/dz against central differences of `to_params`, at a point where every part of
    /// the map (kf, the moving w range, d) is exercised.
    fn jacobian_check<const N: usize>(m: &CameraModel) {
        let pts = [];
        let views = [View { e_com_ma: 80.0, points: &pts }, View { e_com_ma: 225.0, points: &pts }];
        let layout = m.layout();
        let b = Basis::for_views(&views, layout);
        let mut x = to_params_n::<N>(m).unwrap();
        x[layout.kf0x() + 1] *= 1.03;
        x[layout.kf0y() + 2] *= 0.97;
        let z = b.to_internal(&x);
        let j = b.params_jacobian(&z);
        for col in 0..N {
            let h = 1e-6 * z[col].abs().max(1e-12);
            let (mut zp, mut zm) = (z, z);
            zp[col] += h;
            zm[col] -= h;
            let (xp, xm) = (b.to_params(&zp), b.to_params(&zm));
            for row in 0..N {
                let fd = (xp[row] - xm[row]) / (2.0 * h);
                let scale = (j[row][col].abs() + fd.abs()).max(1e-300);
                let ok =
                    (fd - j[row][col]).abs() <= 1e-5 * scale || (fd - j[row][col]).abs() * h <= 1e-12 * x[row].abs();
                assert!(ok, "dx{row}/dz{col}: analytic {} vs {fd}", j[row][col]);
            }
        }
    }

    #[test]
    fn params_jacobian_matches_finite_differences() {
        let [paper, strong] = models();
        jacobian_check::<25>(&paper);
        jacobian_check::<35>(&strong);
        let [moving_paper, moving_strong] = moving_models();
        jacobian_check::<29>(&moving_paper);
        jacobian_check::<39>(&moving_strong);
    }

    /// [`models`] with a moving centre.
    fn moving_models() -> [CameraModel; 2] {
        let centre = Some(MovingCentre { dz_mm: [-6e-3, 1.2e-5], principal_point_slope_px: [0.03, -0.02] });
        models().map(|m| CameraModel { centre, ..m })
    }

    /// T_z(E) and u0(E) from the internal coefficients equal the model's (Eq. C2-C3).
    #[test]
    fn the_centre_polynomials_are_chebyshev_inside() {
        let [m, _] = moving_models();
        let pts = [];
        let views = [View { e_com_ma: 80.0, points: &pts }, View { e_com_ma: 225.0, points: &pts }];
        let l = m.layout();
        let b = Basis::for_views(&views, l);
        let z = b.to_internal(&to_params_n::<29>(&m).unwrap());
        for e in [80.0, 120.0, 225.0] {
            let t: f64 = (e - 152.5) / 72.5;
            let tz =
                z[l.translation().at(2)] + z[l.centre_dz().at(0)] * t + z[l.centre_dz().at(1)] * (2.0 * t * t - 1.0);
            assert!((tz - m.translation_at(e)[2]).abs() < 1e-9, "{tz} vs {:?}", m.translation_at(e));
            let u0 = z[l.u0()] + z[l.centre_principal_point().at(0)] * t;
            assert!((u0 - m.principal_point_at(e)[0]).abs() < 1e-9);
        }
    }
}
