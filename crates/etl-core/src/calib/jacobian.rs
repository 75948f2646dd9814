//! The 25 numbers as one parameter vector (layout: [`super::params`]), and the
//! projection (Eq. 13-18) with its analytic Jacobian.

use super::params::{
    Span, DISTORTION_A, DISTORTION_TRIPLES, KF0X, KF0Y, KF_X, KF_Y, PARAMS, PRINCIPAL_POINT, REDUCED, ROTATION,
    R_DISTORTION, R_FX, R_FY, R_POSE, R_U0, R_V0, TRANSLATION, U0, V0,
};
use crate::error::{Error, Result};
use crate::model::camera::cubic;
use crate::model::rotation::{mat_vec, rodrigues_to_matrix, Mat3};
use crate::model::{CameraModel, Distortion};

/// The `N` entries of `x` in `span` (N = span.len; 0 past the end of `x`).
fn entries<const N: usize>(x: &[f64; PARAMS], span: Span) -> [f64; N] {
    core::array::from_fn(|k| x.get(span.at(k)).copied().unwrap_or(0.0))
}

/// The model as a parameter vector.
pub fn to_params(m: &CameraModel) -> [f64; PARAMS] {
    let mut x = [0.0; PARAMS];
    let parts: [(Span, &[f64]); 6] = [
        (ROTATION, &m.rotation_rodrigues),
        (TRANSLATION, &m.translation_mm),
        (KF_X, &m.kf_x),
        (KF_Y, &m.kf_y),
        (PRINCIPAL_POINT, &m.principal_point),
        (DISTORTION_A, &m.distortion_a),
    ];
    for (span, values) in parts {
        for (slot, &v) in x.iter_mut().skip(span.start).take(span.len).zip(values) {
            *slot = v;
        }
    }
    x
}

/// The parameter vector as a model.
pub fn from_params(x: &[f64; PARAMS]) -> CameraModel {
    CameraModel {
        rotation_rodrigues: entries(x, ROTATION),
        translation_mm: entries(x, TRANSLATION),
        kf_x: entries(x, KF_X),
        kf_y: entries(x, KF_Y),
        principal_point: entries(x, PRINCIPAL_POINT),
        distortion_a: entries(x, DISTORTION_A),
    }
}

fn skew(w: [f64; 3]) -> Mat3 {
    [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
}

fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

/// The right Jacobian of SO(3) at `om`:
/// J_r = I - (1 - cos t)/t^2 [om]x + (t - sin t)/t^3 [om]x^2 (series below t = 1e-6), so
/// that d(R(om) p)/d(om) = -R [p]x J_r = R [J_r e_k]x p column by column.
pub fn right_jacobian(om: [f64; 3]) -> Mat3 {
    let t2 = om[0] * om[0] + om[1] * om[1] + om[2] * om[2];
    let t = libm::sqrt(t2);
    let (b, c) = if t < 1e-6 {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        ((1.0 - libm::cos(t)) / t2, (t - libm::sin(t)) / (t2 * t))
    };
    let k = skew(om);
    let k2 = mat_mul(&k, &k);
    let mut jr = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            jr[i][j] = if i == j { 1.0 } else { 0.0 } - b * k[i][j] + c * k2[i][j];
        }
    }
    jr
}

/// d(R(om) p)/d(om) = -R [p]x J_r(om) (see [`right_jacobian`]).
pub fn rotate_point_jacobian(r: &Mat3, om: [f64; 3], p: [f64; 3]) -> Mat3 {
    let m = mat_mul(&mat_mul(r, &skew(p)), &right_jacobian(om));
    core::array::from_fn(|i| core::array::from_fn(|j| -m[i][j]))
}

/// The projection of one point with its derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Observed-frame pixel (u_d + u0, v_d + v0).
    pub pixel: [f64; 2],
    /// d pixel / d parameters (2 x 25).
    pub d_params: [[f64; PARAMS]; 2],
    /// d pixel / d Z_W (a shift of the point along the world Z axis, i.e. of the stage).
    pub d_z_w: [f64; 2],
    /// d pixel / d E (the current).
    pub d_e: [f64; 2],
}

/// The projection of one point with its derivatives with respect to the 13 per-view
/// variables ([`REDUCED`]). The full Jacobian is `d_reduced * chain`, with
/// [`Projector::chain`] the view's 13 x 25 matrix: this factorisation is what makes the
/// bundle adjustment's normal equations cheap (13 x 13 per point instead of 25 x 25).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReducedProjection {
    /// Observed-frame pixel (u_d + u0, v_d + v0).
    pub pixel: [f64; 2],
    /// d pixel / d (om, T, fx, fy, u0, v0, k1, p1, p2); fx and fy as total derivatives
    /// (directly, and through w = 2 / (fx + fy) in the distortion coefficients at fixed a).
    pub d_reduced: [[f64; REDUCED]; 2],
}

/// Precomputed per-parameter-vector quantities (rotation), shared by all points.
#[derive(Debug, Clone, Copy)]
pub struct Projector {
    x: [f64; PARAMS],
    r: Mat3,
    /// M_l = R [e_l]x J_r(om): d(R p)/d om = -sum_l p_l M_l, so the rotation's Jacobian
    /// costs 27 multiplications per point and no trigonometry.
    r_skew_jr: [Mat3; 3],
}

impl Projector {
    /// Prepares the projection for parameter vector `x`.
    pub fn new(x: &[f64; PARAMS]) -> Self {
        let om = entries(x, ROTATION);
        let r = rodrigues_to_matrix(om);
        let jr = right_jacobian(om);
        // d(R p)/d om = -R [p]x J_r, linear in p: -R [p]x J_r = sum_l p_l (R [J_r]... ) is
        // precomputed as three matrices M_l = R [e_l]x J_r with d(R p)/d om = -sum_l p_l M_l.
        let r_skew_jr = core::array::from_fn(|l| {
            let mut e = [0.0; 3];
            e[l] = 1.0;
            mat_mul(&mat_mul(&r, &skew(e)), &jr)
        });
        Projector { x: *x, r, r_skew_jr }
    }

    fn focal(&self, e_ma: f64) -> Result<(f64, f64)> {
        let x = &self.x;
        let fx = cubic(&entries(x, KF_X), e_ma);
        let fy = cubic(&entries(x, KF_Y), e_ma);
        if !(fx > 0.0 && fy > 0.0) {
            return Err(Error::Degenerate { what: "focal length is not positive at a view's current" });
        }
        Ok((fx, fy))
    }

    /// The chain matrix C of a view at current `e_ma`: d(per-view variables)/d(25 numbers),
    /// with fx = sum kf_xi E^i (Eq. 16), k_c = a_3c+1 w^2 + a_3c+2 w + a_3c+3 (Eq. 18) at
    /// fixed w (w's own dependence on kf is already in the total derivatives of
    /// [`ReducedProjection::d_reduced`]).
    pub fn chain(&self, e_ma: f64) -> Result<[[f64; PARAMS]; REDUCED]> {
        let (fx, fy) = self.focal(e_ma)?;
        let w = 2.0 / (fx + fy);
        let powers = [1.0, e_ma, e_ma * e_ma, e_ma * e_ma * e_ma];
        let mut c = [[0.0; PARAMS]; REDUCED];
        // Entry (row, col) of C; the spans lie inside C by construction (params.rs tests).
        let mut put = |row: usize, col: usize, v: f64| {
            if let Some(slot) = c.get_mut(row).and_then(|r| r.get_mut(col)) {
                *slot = v;
            }
        };
        // The pose is the same entries in both vectors.
        for k in 0..R_POSE.len {
            put(R_POSE.at(k), R_POSE.at(k), 1.0);
        }
        for (i, &p) in powers.iter().enumerate() {
            put(R_FX, KF0X + i, p);
            put(R_FY, KF0Y + i, p);
        }
        put(R_U0, U0, 1.0);
        put(R_V0, V0, 1.0);
        let wp = [w * w, w, 1.0];
        for (k, triple) in DISTORTION_TRIPLES.iter().enumerate() {
            for (i, &wpi) in wp.iter().enumerate() {
                put(R_DISTORTION.at(k), triple.at(i), wpi);
            }
        }
        Ok(c)
    }

    /// The chain matrix of [`Projector::chain`] with respect to the bundle adjustment's
    /// internal parameters ([`super::basis::Basis`]): C dx/dz, with `dxdz` =
    /// [`super::basis::Basis::params_jacobian`]
    /// at the internal parameters of this projector.
    pub fn chain_in(&self, e_ma: f64, dxdz: &[[f64; PARAMS]; PARAMS]) -> Result<[[f64; PARAMS]; REDUCED]> {
        let c = self.chain(e_ma)?;
        let mut out = [[0.0; PARAMS]; REDUCED];
        for (orow, crow) in out.iter_mut().zip(c.iter()) {
            for (&cik, drow) in crow.iter().zip(dxdz.iter()) {
                if cik != 0.0 {
                    for (o, &d) in orow.iter_mut().zip(drow.iter()) {
                        *o += cik * d;
                    }
                }
            }
        }
        Ok(out)
    }

    /// Projects `world_mm` at current `e_ma`, with derivatives with respect to the 13
    /// per-view variables when `jacobian`.
    ///
    /// Errors: the point at or behind the camera; non-positive focal length; non-finite
    /// result.
    pub fn project_reduced(&self, world_mm: [f64; 3], e_ma: f64, jacobian: bool) -> Result<ReducedProjection> {
        let x = &self.x;
        let (fx, fy) = self.focal(e_ma)?;
        let rc = mat_vec(&self.r, world_mm);
        let t = entries::<3>(x, TRANSLATION);
        let pc = [rc[0] + t[0], rc[1] + t[1], rc[2] + t[2]];
        if !(pc[2] > 0.0) {
            return Err(Error::BehindCamera);
        }
        let iz = 1.0 / pc[2];
        let (xn, yn) = (pc[0] * iz, pc[1] * iz);
        let (u, v) = (fx * xn, fy * yn);
        let w = 2.0 / (fx + fy);
        let a: [f64; 9] = entries(x, DISTORTION_A);
        let d = Distortion::from_a(&a, 0.5 * (fx + fy));
        let [ud, vd] = d.distort(u, v);
        let pixel = [ud + x[U0], vd + x[V0]];
        if !(pixel[0].is_finite() && pixel[1].is_finite()) {
            return Err(Error::NotFinite { what: "projected pixel" });
        }
        let mut out = ReducedProjection { pixel, d_reduced: [[0.0; REDUCED]; 2] };
        if !jacobian {
            return Ok(out);
        }
        // Distortion: d(ud, vd)/d(u, v) and d(ud, vd)/d(k1, p1, p2).
        let jd = d.distort_jacobian(u, v);
        let r2 = u * u + v * v;
        let dk = [[u * r2, 3.0 * u * u + v * v, 2.0 * u * v], [v * r2, 2.0 * u * v, u * u + 3.0 * v * v]];
        // k = a_1 w^2 + a_2 w + a_3 (per coefficient): dk/dw, dw/dfx = dw/dfy = -w^2 / 2.
        let dkdw = [2.0 * a[0] * w + a[1], 2.0 * a[3] * w + a[4], 2.0 * a[6] * w + a[7]];
        let dwdf = -0.5 * w * w;
        // d(u, v)/d pc.
        let du_dpc = [fx * iz, 0.0, -u * iz];
        let dv_dpc = [0.0, fy * iz, -v * iz];
        let m = &self.r_skew_jr;
        let drot: Mat3 = core::array::from_fn(|i| {
            core::array::from_fn(|j| -(world_mm[0] * m[0][i][j] + world_mm[1] * m[1][i][j] + world_mm[2] * m[2][i][j]))
        });
        for row in 0..2 {
            let dp = &mut out.d_reduced[row];
            let mut dpix_dpc = [0.0; 3];
            for k in 0..3 {
                dpix_dpc[k] = jd[row][0] * du_dpc[k] + jd[row][1] * dv_dpc[k];
            }
            for j in 0..3 {
                dp[ROTATION.at(j)] = (0..3).map(|k| dpix_dpc[k] * drot[k][j]).sum();
                dp[TRANSLATION.at(j)] = dpix_dpc[j];
            }
            // fx enters u directly (u = fx xn) and the distortion through w.
            let via_w: f64 = (0..3).map(|k| dk[row][k] * dkdw[k]).sum::<f64>() * dwdf;
            dp[R_FX] = jd[row][0] * xn + via_w;
            dp[R_FY] = jd[row][1] * yn + via_w;
            dp[R_U0 + row] = 1.0;
            for (d, &v) in dp.iter_mut().skip(R_DISTORTION.start).zip(dk[row].iter()) {
                *d = v;
            }
        }
        Ok(out)
    }

    /// d(fx, fy)/dE at `e_ma` (Eq. 16 differentiated).
    pub fn focal_slope(&self, e_ma: f64) -> [f64; 2] {
        let (kx, ky) = (entries::<4>(&self.x, KF_X), entries::<4>(&self.x, KF_Y));
        [kx[1] + 2.0 * kx[2] * e_ma + 3.0 * kx[3] * e_ma * e_ma, ky[1] + 2.0 * ky[2] * e_ma + 3.0 * ky[3] * e_ma * e_ma]
    }

    /// d pixel / d Z_W and d pixel / d E of a point from its per-view derivatives: a stage
    /// shift moves the point along world Z (d pc / d Z_W = R e_z, as a change of T would),
    /// and the current acts through fx and fy only.
    pub fn view_shift_derivatives(&self, d_reduced: &[[f64; REDUCED]; 2], e_ma: f64) -> ([f64; 2], [f64; 2]) {
        let c = self.shift_chain(e_ma);
        let mut d = [[0.0; 2]; 2];
        for row in 0..2 {
            for (k, ck) in c.iter().enumerate() {
                d[0][row] += d_reduced[row][k] * ck[0];
                d[1][row] += d_reduced[row][k] * ck[1];
            }
        }
        (d[0], d[1])
    }

    /// d(per-view variables)/d(Z_W, E) (13 x 2): a stage shift moves the point along
    /// world Z, which acts as the change R e_z of T; the current acts through fx and fy.
    pub fn shift_chain(&self, e_ma: f64) -> [[f64; 2]; REDUCED] {
        let slope = self.focal_slope(e_ma);
        let mut c = [[0.0; 2]; REDUCED];
        for k in 0..3 {
            c[TRANSLATION.at(k)][0] = self.r[k][2];
        }
        c[R_FX][1] = slope[0];
        c[R_FY][1] = slope[1];
        c
    }

    /// Projects `world_mm` at current `e_ma`, with derivatives with respect to the 25
    /// numbers, Z_W and E when `jacobian`.
    ///
    /// Errors: the point at or behind the camera; non-positive focal length; non-finite
    /// result.
    pub fn project(&self, world_mm: [f64; 3], e_ma: f64, jacobian: bool) -> Result<Projection> {
        let red = self.project_reduced(world_mm, e_ma, jacobian)?;
        let mut out = Projection { pixel: red.pixel, d_params: [[0.0; PARAMS]; 2], d_z_w: [0.0; 2], d_e: [0.0; 2] };
        if !jacobian {
            return Ok(out);
        }
        let c = self.chain(e_ma)?;
        for row in 0..2 {
            for (k, ck) in c.iter().enumerate() {
                let g = red.d_reduced[row][k];
                for (dp, &ckp) in out.d_params[row].iter_mut().zip(ck.iter()) {
                    *dp += g * ckp;
                }
            }
        }
        (out.d_z_w, out.d_e) = self.view_shift_derivatives(&red.d_reduced, e_ma);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::params::PARAM_NAMES;

    #[test]
    fn jacobian_matches_central_differences() {
        let x0 = to_params(&CameraModel::paper_rig());
        for &(pw, e) in &[([3.0, 4.5, 48.0], 100.0), ([19.5, 16.5, 2.0], 225.0), ([0.0, 0.0, 75.0], 80.0)] {
            let p = Projector::new(&x0).project(pw, e, true).unwrap();
            for j in 0..PARAMS {
                // The pixel is linear in a_i, so a large step is exact there and beats roundoff.
                let h = if j >= DISTORTION_A.start { 1e-2 } else { 1e-6 } * x0[j].abs().max(1e-3);
                let (mut xp, mut xm) = (x0, x0);
                xp[j] += h;
                xm[j] -= h;
                let fp = Projector::new(&xp).project(pw, e, false).unwrap().pixel;
                let fm = Projector::new(&xm).project(pw, e, false).unwrap().pixel;
                for row in 0..2 {
                    let fd = (fp[row] - fm[row]) / (2.0 * h);
                    let an = p.d_params[row][j];
                    assert!(
                        (fd - an).abs() <= 1e-5 * an.abs().max(1e-3),
                        "{} row {row}: fd {fd} an {an}",
                        PARAM_NAMES[j]
                    );
                }
            }
            for row in 0..2 {
                let h = 1e-4;
                let fz =
                    |dz: f64| Projector::new(&x0).project([pw[0], pw[1], pw[2] + dz], e, false).unwrap().pixel[row];
                let fe = |de: f64| Projector::new(&x0).project(pw, e + de, false).unwrap().pixel[row];
                let (dz, de) = ((fz(h) - fz(-h)) / (2.0 * h), (fe(h) - fe(-h)) / (2.0 * h));
                assert!((dz - p.d_z_w[row]).abs() < 1e-5 * dz.abs().max(1.0), "dZ {dz} {}", p.d_z_w[row]);
                assert!((de - p.d_e[row]).abs() < 1e-5 * de.abs().max(1.0), "dE {de} {}", p.d_e[row]);
            }
            // And the value agrees with the model's own projection.
            let q = CameraModel::paper_rig().project(pw, e).unwrap();
            assert!((q[0] - p.pixel[0]).abs() < 1e-12 && (q[1] - p.pixel[1]).abs() < 1e-12);
        }
    }
}
