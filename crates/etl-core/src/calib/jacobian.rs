//! The 25 numbers as one parameter vector, and the projection (Eq. 13-18) with its
//! analytic Jacobian.
//!
//! Layout (also the names used in studies and reports):
//! `om1 om2 om3 tx ty tz kf0x kf1x kf2x kf3x kf0y kf1y kf2y kf3y u0 v0 a1 .. a9`.

#![allow(clippy::needless_range_loop)] // small fixed-size linear algebra reads best indexed

use crate::error::{Error, Result};
use crate::model::camera::cubic;
use crate::model::rotation::{mat_vec, rodrigues_to_matrix, Mat3};
use crate::model::{CameraModel, Distortion};

/// Number of model parameters.
pub const PARAMS: usize = 25;

/// Names of the 25 parameters, in vector order.
pub const PARAM_NAMES: [&str; PARAMS] = [
    "om1", "om2", "om3", "tx", "ty", "tz", "kf0x", "kf1x", "kf2x", "kf3x", "kf0y", "kf1y", "kf2y", "kf3y", "u0", "v0",
    "a1", "a2", "a3", "a4", "a5", "a6", "a7", "a8", "a9",
];

/// Index of kf0x; kf0y is at `KF0X + 4`, u0 and v0 at [`U0`], `U0 + 1`.
pub const KF0X: usize = 6;
/// Index of u0.
pub const U0: usize = 14;

/// The model as a parameter vector.
pub fn to_params(m: &CameraModel) -> [f64; PARAMS] {
    let mut x = [0.0; PARAMS];
    x[0..3].copy_from_slice(&m.rotation_rodrigues);
    x[3..6].copy_from_slice(&m.translation_mm);
    x[6..10].copy_from_slice(&m.kf_x);
    x[10..14].copy_from_slice(&m.kf_y);
    x[14..16].copy_from_slice(&m.principal_point);
    x[16..25].copy_from_slice(&m.distortion_a);
    x
}

/// The parameter vector as a model.
pub fn from_params(x: &[f64; PARAMS]) -> CameraModel {
    CameraModel {
        rotation_rodrigues: [x[0], x[1], x[2]],
        translation_mm: [x[3], x[4], x[5]],
        kf_x: [x[6], x[7], x[8], x[9]],
        kf_y: [x[10], x[11], x[12], x[13]],
        principal_point: [x[14], x[15]],
        distortion_a: [x[16], x[17], x[18], x[19], x[20], x[21], x[22], x[23], x[24]],
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

/// d(R(om) p)/d(om) = -R [p]x J_r(om), with the right Jacobian of SO(3)
/// J_r = I - (1 - cos t)/t^2 [om]x + (t - sin t)/t^3 [om]x^2 (series below t = 1e-6).
pub fn rotate_point_jacobian(r: &Mat3, om: [f64; 3], p: [f64; 3]) -> Mat3 {
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
    let rp = mat_mul(r, &skew(p));
    let m = mat_mul(&rp, &jr);
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = -m[i][j];
        }
    }
    out
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

/// Precomputed per-parameter-vector quantities (rotation), shared by all points.
#[derive(Debug, Clone, Copy)]
pub struct Projector {
    x: [f64; PARAMS],
    r: Mat3,
}

impl Projector {
    /// Prepares the projection for parameter vector `x`.
    pub fn new(x: &[f64; PARAMS]) -> Self {
        Projector { x: *x, r: rodrigues_to_matrix([x[0], x[1], x[2]]) }
    }

    /// Projects `world_mm` at current `e_ma`, with derivatives when `jacobian`.
    ///
    /// Errors: the point at or behind the camera; non-positive focal length; non-finite
    /// result.
    pub fn project(&self, world_mm: [f64; 3], e_ma: f64, jacobian: bool) -> Result<Projection> {
        let x = &self.x;
        let kfx = [x[6], x[7], x[8], x[9]];
        let kfy = [x[10], x[11], x[12], x[13]];
        let fx = cubic(&kfx, e_ma);
        let fy = cubic(&kfy, e_ma);
        if !(fx > 0.0 && fy > 0.0) {
            return Err(Error::Degenerate { what: "focal length is not positive at a view's current" });
        }
        let rc = mat_vec(&self.r, world_mm);
        let pc = [rc[0] + x[3], rc[1] + x[4], rc[2] + x[5]];
        if !(pc[2] > 0.0) {
            return Err(Error::BehindCamera);
        }
        let iz = 1.0 / pc[2];
        let (xn, yn) = (pc[0] * iz, pc[1] * iz);
        let (u, v) = (fx * xn, fy * yn);
        let w = 2.0 / (fx + fy);
        let a = [x[16], x[17], x[18], x[19], x[20], x[21], x[22], x[23], x[24]];
        let d = Distortion::from_a(&a, 0.5 * (fx + fy));
        let [ud, vd] = d.distort(u, v);
        let pixel = [ud + x[14], vd + x[15]];
        if !(pixel[0].is_finite() && pixel[1].is_finite()) {
            return Err(Error::NotFinite { what: "projected pixel" });
        }
        let mut out = Projection { pixel, d_params: [[0.0; PARAMS]; 2], d_z_w: [0.0; 2], d_e: [0.0; 2] };
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
        // Total derivative of the pixel w.r.t. (u, v, fx, fy) of the pinhole stage.
        let mut g = [[0.0; 4]; 2]; // columns: u, v, fx (through w only), fy (through w only)
        for row in 0..2 {
            g[row][0] = jd[row][0];
            g[row][1] = jd[row][1];
            let via_w: f64 = (0..3).map(|k| dk[row][k] * dkdw[k]).sum::<f64>() * dwdf;
            g[row][2] = via_w;
            g[row][3] = via_w;
        }
        // d(u, v)/d pc.
        let du_dpc = [fx * iz, 0.0, -u * iz];
        let dv_dpc = [0.0, fy * iz, -v * iz];
        let mut dpix_dpc = [[0.0; 3]; 2];
        for row in 0..2 {
            for k in 0..3 {
                dpix_dpc[row][k] = g[row][0] * du_dpc[k] + g[row][1] * dv_dpc[k];
            }
        }
        let drot = rotate_point_jacobian(&self.r, [x[0], x[1], x[2]], world_mm);
        let e2 = e_ma * e_ma;
        let powers = [1.0, e_ma, e2, e2 * e_ma];
        for row in 0..2 {
            let dp = &mut out.d_params[row];
            for j in 0..3 {
                dp[j] = (0..3).map(|k| dpix_dpc[row][k] * drot[k][j]).sum();
                dp[3 + j] = dpix_dpc[row][j];
            }
            // fx enters u directly (u = fx xn) and the distortion through w.
            let dfx = g[row][0] * xn + g[row][2];
            let dfy = g[row][1] * yn + g[row][3];
            for i in 0..4 {
                dp[6 + i] = dfx * powers[i];
                dp[10 + i] = dfy * powers[i];
            }
            dp[14] = if row == 0 { 1.0 } else { 0.0 };
            dp[15] = if row == 1 { 1.0 } else { 0.0 };
            let wp = [w * w, w, 1.0];
            for c in 0..3 {
                for i in 0..3 {
                    dp[16 + 3 * c + i] = dk[row][c] * wp[i];
                }
            }
            // A stage shift moves the point along world Z: d pc / d Z_W = R e_z.
            out.d_z_w[row] = (0..3).map(|k| dpix_dpc[row][k] * self.r[k][2]).sum();
            let dfx_de = x[7] + 2.0 * x[8] * e_ma + 3.0 * x[9] * e2;
            let dfy_de = x[11] + 2.0 * x[12] * e_ma + 3.0 * x[13] * e2;
            out.d_e[row] = dfx * dfx_de + dfy * dfy_de;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_matches_central_differences() {
        let x0 = to_params(&CameraModel::paper_rig());
        for &(pw, e) in &[([3.0, 4.5, 48.0], 100.0), ([19.5, 16.5, 2.0], 225.0), ([0.0, 0.0, 75.0], 80.0)] {
            let p = Projector::new(&x0).project(pw, e, true).unwrap();
            for j in 0..PARAMS {
                // The pixel is linear in a_i, so a large step is exact there and beats roundoff.
                let h = if j >= 16 { 1e-2 } else { 1e-6 } * x0[j].abs().max(1e-3);
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
