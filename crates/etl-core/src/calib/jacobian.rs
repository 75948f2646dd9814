//! A model's numbers as one parameter vector (layout: [`super::params::Layout`]), and the
//! projection (Eq. 13-18, either distortion family) with its analytic Jacobian.

use super::params::{Layout, Span, MAX_PARAMS, MAX_REDUCED, ROTATION, R_FX, R_FY, R_K1, R_POSE, R_U0, TRANSLATION};
use crate::error::{Error, Result};
use crate::model::distortion::{opencv_rows, paper_rows};
use crate::model::rotation::{mat_vec, rodrigues_to_matrix, Mat3};
use crate::model::{CameraModel, Distortion, DistortionA, DistortionModel, FocalPoly, MovingCentre, MAX_COEFFICIENTS};

/// Writes `values` into `x` from `span.start` (at most `span.len` of them).
fn put_span(x: &mut [f64], span: Span, values: &[f64]) {
    for (slot, &v) in x.iter_mut().skip(span.start).take(span.len).zip(values) {
        *slot = v;
    }
}

/// The entries of `x` in `span` (empty past the end of `x`).
fn span_of(x: &[f64], span: Span) -> &[f64] {
    x.get(span.start..span.end()).unwrap_or(&[])
}

/// The model as a parameter vector of its layout ([`CameraModel::layout`]), at capacity:
/// entries past the layout's length are zero.
pub fn to_params(m: &CameraModel) -> [f64; MAX_PARAMS] {
    let l = m.layout();
    let mut x = [0.0; MAX_PARAMS];
    put_span(&mut x, l.rotation(), &m.rotation_rodrigues);
    put_span(&mut x, l.translation(), &m.translation_mm);
    put_span(&mut x, l.kf_x(), m.kf_x.coefficients());
    put_span(&mut x, l.kf_y(), m.kf_y.coefficients());
    put_span(&mut x, l.principal_point(), &m.principal_point);
    put_span(&mut x, l.distortion_a(), m.distortion_a.as_slice());
    if let Some(c) = &m.centre {
        put_span(&mut x, l.centre_dz(), &c.dz_mm);
        put_span(&mut x, l.centre_principal_point(), &c.principal_point_slope_px);
    }
    x
}

/// The model's parameter vector of exactly `N` numbers. Errors: `N` is not the length of
/// the model's layout ([`Error::InvalidArgument`]).
pub fn to_params_n<const N: usize>(m: &CameraModel) -> Result<[f64; N]> {
    if m.layout().len() != N {
        return Err(Error::InvalidArgument { what: "parameter vector length differs from the model's layout" });
    }
    let x = to_params(m);
    Ok(core::array::from_fn(|i| x.get(i).copied().unwrap_or(0.0)))
}

/// The parameter vector `x` (at least `layout.len()` numbers; missing ones read as 0) as a
/// model of `layout`.
pub fn from_params(layout: &Layout, x: &[f64]) -> CameraModel {
    let mut kf_x = FocalPoly::zero(layout.focal_degree());
    let mut kf_y = kf_x;
    copy_into(kf_x.coefficients_mut(), span_of(x, layout.kf_x()));
    copy_into(kf_y.coefficients_mut(), span_of(x, layout.kf_y()));
    let mut distortion_a = DistortionA::zero(layout.model());
    copy_into(distortion_a.as_mut_slice(), span_of(x, layout.distortion_a()));
    let fixed = |span: Span| -> [f64; 3] { core::array::from_fn(|k| x.get(span.at(k)).copied().unwrap_or(0.0)) };
    let pp = layout.principal_point();
    let entry = |i: usize| x.get(i).copied().unwrap_or(0.0);
    let (dz, cp) = (layout.centre_dz(), layout.centre_principal_point());
    let centre = layout.moving_centre().then(|| MovingCentre {
        dz_mm: [entry(dz.at(0)), entry(dz.at(1))],
        principal_point_slope_px: [entry(cp.at(0)), entry(cp.at(1))],
    });
    CameraModel {
        rotation_rodrigues: fixed(layout.rotation()),
        translation_mm: fixed(layout.translation()),
        kf_x,
        kf_y,
        principal_point: [entry(pp.at(0)), entry(pp.at(1))],
        distortion_a,
        centre,
    }
}

/// C dx/dz for a chain matrix C (per-view variables x N).
fn chain_times<const N: usize>(c: &[[f64; N]; MAX_REDUCED], dxdz: &[[f64; N]; N]) -> [[f64; N]; MAX_REDUCED] {
    let mut out = [[0.0; N]; MAX_REDUCED];
    for (orow, crow) in out.iter_mut().zip(c.iter()) {
        for (&cik, drow) in crow.iter().zip(dxdz.iter()) {
            if cik != 0.0 {
                for (o, &d) in orow.iter_mut().zip(drow.iter()) {
                    *o += cik * d;
                }
            }
        }
    }
    out
}

fn copy_into(dst: &mut [f64], src: &[f64]) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = s;
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
/// `J_r = I - (1 - cos t)/t^2 [om]x + (t - sin t)/t^3 [om]x^2` (series below t = 1e-6), so
/// that `d(R(om) p)/d(om) = -R [p]x J_r = R [J_r e_k]x p` column by column.
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

/// `d(R(om) p)/d(om) = -R [p]x J_r(om)` (see [`right_jacobian`]).
pub fn rotate_point_jacobian(r: &Mat3, om: [f64; 3], p: [f64; 3]) -> Mat3 {
    let m = mat_mul(&mat_mul(r, &skew(p)), &right_jacobian(om));
    core::array::from_fn(|i| core::array::from_fn(|j| -m[i][j]))
}

/// The projection of one point with its derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Observed-frame pixel (u_d + u0, v_d + v0).
    pub pixel: [f64; 2],
    /// d pixel / d parameters (2 x the layout's length, at capacity: zero past it).
    pub d_params: [[f64; MAX_PARAMS]; 2],
    /// d pixel / d Z_W (a shift of the point along the world Z axis, i.e. of the stage).
    pub d_z_w: [f64; 2],
    /// d pixel / d E (the current).
    pub d_e: [f64; 2],
}

/// The projection of one point with its derivatives with respect to the per-view
/// variables ([`Layout::reduced_len`]: 13 or 15). The full Jacobian is `d_reduced *
/// chain`, with [`Projector::chain`] the view's matrix: this factorisation is what makes
/// the bundle adjustment's normal equations cheap (13 x 13 per point instead of 25 x 25).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReducedProjection {
    /// Observed-frame pixel (u_d + u0, v_d + v0).
    pub pixel: [f64; 2],
    /// d pixel / d (om, T, fx, fy, u0, v0, the distortion coefficients) at capacity (zero
    /// past the layout's per-view variables); fx and fy as total derivatives (directly, and
    /// through w = 2 / (fx + fy) in the distortion coefficients at fixed a).
    pub d_reduced: [[f64; MAX_REDUCED]; 2],
}

/// Precomputed per-model quantities (rotation), shared by all points.
#[derive(Debug, Clone, Copy)]
pub struct Projector {
    model: CameraModel,
    layout: Layout,
    r: Mat3,
    /// M_l = R [e_l]x J_r(om): d(R p)/d om = -sum_l p_l M_l, so the rotation's Jacobian
    /// costs 27 multiplications per point and no trigonometry.
    r_skew_jr: [Mat3; 3],
}

impl Projector {
    /// Prepares the projection for `model` (whose layout fixes the parameter vector).
    pub fn new(model: &CameraModel) -> Self {
        let om = model.rotation_rodrigues;
        let r = rodrigues_to_matrix(om);
        let jr = right_jacobian(om);
        // d(R p)/d om = -R [p]x J_r, linear in p: -R [p]x J_r = sum_l p_l (R [J_r]... ) is
        // precomputed as three matrices M_l = R [e_l]x J_r with d(R p)/d om = -sum_l p_l M_l.
        let r_skew_jr = core::array::from_fn(|l| {
            let mut e = [0.0; 3];
            e[l] = 1.0;
            mat_mul(&mat_mul(&r, &skew(e)), &jr)
        });
        Projector { model: *model, layout: model.layout(), r, r_skew_jr }
    }

    /// The model projected.
    pub fn model(&self) -> &CameraModel {
        &self.model
    }

    /// The layout of the model's parameter vector.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    #[inline(always)]
    fn focal(&self, e_ma: f64) -> Result<(f64, f64)> {
        let fx = self.model.kf_x.eval(e_ma);
        let fy = self.model.kf_y.eval(e_ma);
        if !(fx > 0.0 && fy > 0.0) {
            return Err(Error::Degenerate { what: "focal length is not positive at a view's current" });
        }
        Ok((fx, fy))
    }

    /// The chain matrix C of a view at current `e_ma`: d(per-view variables)/d(the
    /// layout's numbers), at capacity, with fx = sum kf_xi E^i (Eq. 16) and each coefficient
    /// k_c = a_3c+1 w^2 + a_3c+2 w + a_3c+3 (Eq. 18) at fixed w (w's own dependence on kf is
    /// already in the total derivatives of [`ReducedProjection::d_reduced`]).
    /// `N` columns: the layout's length, or [`MAX_PARAMS`] for the matrix at capacity.
    pub fn chain<const N: usize>(&self, e_ma: f64) -> Result<[[f64; N]; MAX_REDUCED]> {
        let (fx, fy) = self.focal(e_ma)?;
        let l = &self.layout;
        let w = 2.0 / (fx + fy);
        let mut c = [[0.0; N]; MAX_REDUCED];
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
        // E^i as 1, E, E E, (E E) E, ...: the paper cubic's own products.
        let mut power = 1.0;
        for i in 0..l.kf_x().len {
            put(R_FX, l.kf_x().at(i), power);
            put(R_FY, l.kf_y().at(i), power);
            power *= e_ma;
        }
        put(R_U0, l.u0(), 1.0);
        put(R_U0 + 1, l.v0(), 1.0);
        // Eq. C2-C3: T_z(E) = T_z - dz1 E - dz2 E^2, u0(E) = u0 + u1 E, v0(E) = v0 + v1 E.
        if l.moving_centre() {
            let (dz, cp) = (l.centre_dz(), l.centre_principal_point());
            put(TRANSLATION.at(2), dz.at(0), -e_ma);
            put(TRANSLATION.at(2), dz.at(1), -e_ma * e_ma);
            put(R_U0, cp.at(0), e_ma);
            put(R_U0 + 1, cp.at(1), e_ma);
        }
        let wp = [w * w, w, 1.0];
        for k in 0..l.model().coefficient_count() {
            let triple = l.distortion_triple(k);
            for (i, &wpi) in wp.iter().enumerate() {
                put(R_K1 + k, triple.at(i), wpi);
            }
        }
        Ok(c)
    }

    /// The chain matrix of [`Projector::chain`] with respect to the bundle adjustment's
    /// `N` internal parameters ([`super::basis::Basis`]): C dx/dz, with `dxdz` =
    /// [`super::basis::Basis::params_jacobian`] at the internal parameters of this
    /// projector.
    pub fn chain_in<const N: usize>(&self, e_ma: f64, dxdz: &[[f64; N]; N]) -> Result<[[f64; N]; MAX_REDUCED]> {
        Ok(chain_times(&self.chain::<N>(e_ma)?, dxdz))
    }

    /// The chain matrix of a board in its own pose (a free-pose view of the bundle
    /// adjustment, whose projector holds that pose as its R, T): [`Projector::chain_in`]
    /// without the pose's identity entries, since the pose is not among the model's
    /// numbers. What stays of the pose rows is the moving centre's T_z(E) = T_z - dz1 E -
    /// dz2 E^2 (Eq. C2): its -E, -E^2 on dz1, dz2.
    pub fn board_chain_in<const N: usize>(&self, e_ma: f64, dxdz: &[[f64; N]; N]) -> Result<[[f64; N]; MAX_REDUCED]> {
        let mut c = self.chain::<N>(e_ma)?;
        for k in 0..R_POSE.len {
            if let Some(slot) = c.get_mut(R_POSE.at(k)).and_then(|r| r.get_mut(R_POSE.at(k))) {
                *slot = 0.0;
            }
        }
        Ok(chain_times(&c, dxdz))
    }

    /// Projects `world_mm` at current `e_ma`, with derivatives with respect to the
    /// per-view variables when `jacobian`.
    ///
    /// Errors: the point at or behind the camera; non-positive focal length; non-finite
    /// result.
    pub fn project_reduced(&self, world_mm: [f64; 3], e_ma: f64, jacobian: bool) -> Result<ReducedProjection> {
        // One compiled body per family (its coefficient count a constant): this runs once
        // per point of every bundle-adjustment evaluation.
        match self.layout.model() {
            DistortionModel::Paper => self.reduced::<3>(world_mm, e_ma, jacobian),
            DistortionModel::OpenCv => self.reduced::<5>(world_mm, e_ma, jacobian),
        }
    }

    /// [`Self::project_reduced`] for the family of `C` coefficients (3: paper, 5: opencv).
    #[inline(always)]
    fn reduced<const C: usize>(&self, world_mm: [f64; 3], e_ma: f64, jacobian: bool) -> Result<ReducedProjection> {
        let (fx, fy) = self.focal(e_ma)?;
        let rc = mat_vec(&self.r, world_mm);
        let t = self.model.translation_at(e_ma);
        let pc = [rc[0] + t[0], rc[1] + t[1], rc[2] + t[2]];
        if !(pc[2] > 0.0) {
            return Err(Error::BehindCamera);
        }
        let iz = 1.0 / pc[2];
        let (xn, yn) = (pc[0] * iz, pc[1] * iz);
        let w = 2.0 / (fx + fy);
        let a = self.model.distortion_a.padded();
        let coefficients = self.model.distortion_a.coefficients_at(0.5 * (fx + fy));
        let [u0, v0] = self.model.principal_point_at(e_ma);
        // Per family: the pixel, d pixel / d pc, d pixel / d(fx, fy) at fixed coefficients,
        // and d pixel / d coefficients.
        let local = if C == 3 {
            let [k1, p1, p2, ..] = coefficients;
            paper_local(&Distortion::paper(k1, p1, p2), fx, fy, xn, yn, iz, jacobian)
        } else {
            opencv_local(&Distortion::opencv(coefficients, fx, fy), fx, fy, xn, yn, iz, jacobian)
        };
        let pixel = [local.pixel[0] + u0, local.pixel[1] + v0];
        if !(pixel[0].is_finite() && pixel[1].is_finite()) {
            return Err(Error::NotFinite { what: "projected pixel" });
        }
        let mut out = ReducedProjection { pixel, d_reduced: [[0.0; MAX_REDUCED]; 2] };
        if !jacobian {
            return Ok(out);
        }
        // k = a_1 w^2 + a_2 w + a_3 (per coefficient): dk/dw, dw/dfx = dw/dfy = -w^2 / 2.
        let dkdw: [f64; MAX_COEFFICIENTS] = core::array::from_fn(|c| {
            let (q2, q1) = (a.get(3 * c).copied().unwrap_or(0.0), a.get(3 * c + 1).copied().unwrap_or(0.0));
            2.0 * q2 * w + q1
        });
        let dwdf = -0.5 * w * w;
        let m = &self.r_skew_jr;
        let drot: Mat3 = core::array::from_fn(|i| {
            core::array::from_fn(|j| -(world_mm[0] * m[0][i][j] + world_mm[1] * m[1][i][j] + world_mm[2] * m[2][i][j]))
        });
        for row in 0..2 {
            let dp = &mut out.d_reduced[row];
            let dpix_dpc = &local.d_pc[row];
            for j in 0..3 {
                dp[ROTATION.at(j)] = (0..3).map(|k| dpix_dpc[k] * drot[k][j]).sum();
                dp[TRANSLATION.at(j)] = dpix_dpc[j];
            }
            // fx enters the projection directly and the distortion through w.
            let dk = &local.d_coefficients[row];
            let via_w: f64 = dk.iter().zip(dkdw.iter()).take(C).map(|(d, k)| d * k).sum::<f64>() * dwdf;
            dp[R_FX] = local.d_focal[row][0] + via_w;
            dp[R_FY] = local.d_focal[row][1] + via_w;
            dp[R_U0 + row] = 1.0;
            for (d, &v) in dp.iter_mut().skip(R_K1).zip(dk.iter().take(C)) {
                *d = v;
            }
        }
        Ok(out)
    }

    /// d(fx, fy)/dE at `e_ma` (Eq. 16 differentiated).
    pub fn focal_slope(&self, e_ma: f64) -> [f64; 2] {
        [self.model.kf_x.slope(e_ma), self.model.kf_y.slope(e_ma)]
    }

    /// d pixel / d Z_W and d pixel / d E of a point from its per-view derivatives: a stage
    /// shift moves the point along world Z (d pc / d Z_W = R e_z, as a change of T would),
    /// and the current acts through fx and fy only.
    pub fn view_shift_derivatives(&self, d_reduced: &[[f64; MAX_REDUCED]; 2], e_ma: f64) -> ([f64; 2], [f64; 2]) {
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

    /// d(per-view variables)/d(Z_W, E) (at capacity x 2): a stage shift moves the point
    /// along world Z, which acts as the change R e_z of T; the current acts through fx
    /// and fy, and with a moving centre through T_z(E) and (u0(E), v0(E)) (Eq. C2-C3).
    pub fn shift_chain(&self, e_ma: f64) -> [[f64; 2]; MAX_REDUCED] {
        let slope = self.focal_slope(e_ma);
        let mut c = [[0.0; 2]; MAX_REDUCED];
        for k in 0..3 {
            c[TRANSLATION.at(k)][0] = self.r[k][2];
        }
        c[R_FX][1] = slope[0];
        c[R_FY][1] = slope[1];
        if let Some(centre) = &self.model.centre {
            c[TRANSLATION.at(2)][1] = -centre.dz_slope(e_ma);
            c[R_U0][1] = centre.principal_point_slope_px[0];
            c[R_U0 + 1][1] = centre.principal_point_slope_px[1];
        }
        c
    }

    /// Projects `world_mm` at current `e_ma`, with derivatives with respect to the
    /// layout's numbers, Z_W and E when `jacobian`.
    ///
    /// Errors: the point at or behind the camera; non-positive focal length; non-finite
    /// result.
    pub fn project(&self, world_mm: [f64; 3], e_ma: f64, jacobian: bool) -> Result<Projection> {
        let red = self.project_reduced(world_mm, e_ma, jacobian)?;
        let mut out = Projection { pixel: red.pixel, d_params: [[0.0; MAX_PARAMS]; 2], d_z_w: [0.0; 2], d_e: [0.0; 2] };
        if !jacobian {
            return Ok(out);
        }
        let c = self.chain::<MAX_PARAMS>(e_ma)?;
        let (nr, np) = (self.layout.reduced_len(), self.layout.len());
        for row in 0..2 {
            for (k, ck) in c.iter().enumerate().take(nr) {
                let g = red.d_reduced[row][k];
                for (dp, &ckp) in out.d_params[row].iter_mut().zip(ck.iter()).take(np) {
                    *dp += g * ckp;
                }
            }
        }
        (out.d_z_w, out.d_e) = self.view_shift_derivatives(&red.d_reduced, e_ma);
        Ok(out)
    }
}

/// A camera point `pc` (mm, the camera's frame) projected under intrinsics `k` and
/// distortion `d` ([`crate::model::projection::project_camera_point`], either family),
/// with d pixel / d pc (2 x 3), analytic: the derivatives the bundle adjustment uses.
///
/// Errors: the point at or behind the camera; a non-finite pixel.
pub fn project_camera_point_jacobian(
    pc: [f64; 3],
    k: &crate::model::Intrinsics,
    d: &Distortion,
) -> Result<([f64; 2], [[f64; 3]; 2])> {
    if !(pc[2] > 0.0) {
        return Err(Error::BehindCamera);
    }
    let iz = 1.0 / pc[2];
    let (xn, yn) = (pc[0] * iz, pc[1] * iz);
    let local = match d.model() {
        DistortionModel::Paper => paper_local(d, k.fx, k.fy, xn, yn, iz, true),
        DistortionModel::OpenCv => opencv_local(d, k.fx, k.fy, xn, yn, iz, true),
    };
    let pixel = [local.pixel[0] + k.u0, local.pixel[1] + k.v0];
    if !(pixel[0].is_finite() && pixel[1].is_finite()) {
        return Err(Error::NotFinite { what: "projected pixel" });
    }
    Ok((pixel, local.d_pc))
}

/// One family's part of a projection: the pixel relative to the principal point and its
/// derivatives with respect to the camera point, to (fx, fy) at fixed coefficients, and to
/// the coefficients.
struct Local {
    pixel: [f64; 2],
    d_pc: [[f64; 3]; 2],
    d_focal: [[f64; 2]; 2],
    d_coefficients: [[f64; MAX_COEFFICIENTS]; 2],
}

/// The paper family (Eq. 15, 17): u = fx x, v = fy y, then Eq. 17 in centred pixels.
#[inline]
fn paper_local(d: &Distortion, fx: f64, fy: f64, xn: f64, yn: f64, iz: f64, jacobian: bool) -> Local {
    let (u, v) = (fx * xn, fy * yn);
    let pixel = d.distort(u, v);
    let mut out = Local { pixel, d_pc: [[0.0; 3]; 2], d_focal: [[0.0; 2]; 2], d_coefficients: [[0.0; 5]; 2] };
    if !jacobian {
        return out;
    }
    let jd = d.distort_jacobian(u, v);
    // d(u, v)/d pc.
    let du_dpc = [fx * iz, 0.0, -u * iz];
    let dv_dpc = [0.0, fy * iz, -v * iz];
    for row in 0..2 {
        for k in 0..3 {
            out.d_pc[row][k] = jd[row][0] * du_dpc[k] + jd[row][1] * dv_dpc[k];
        }
        out.d_focal[row] = [jd[row][0] * xn, jd[row][1] * yn];
    }
    out.d_coefficients = paper_rows(u, v);
    out
}

/// OpenCV's family: x_d, y_d of the normalised point, then u_d = fx x_d, v_d = fy y_d.
#[inline]
fn opencv_local(d: &Distortion, fx: f64, fy: f64, xn: f64, yn: f64, iz: f64, jacobian: bool) -> Local {
    let [xd, yd] = d.distort_normalised(xn, yn);
    let pixel = [fx * xd, fy * yd];
    let mut out = Local { pixel, d_pc: [[0.0; 3]; 2], d_focal: [[0.0; 2]; 2], d_coefficients: [[0.0; 5]; 2] };
    if !jacobian {
        return out;
    }
    let jn = d.normalised_jacobian(xn, yn);
    let dx_dpc = [iz, 0.0, -xn * iz];
    let dy_dpc = [0.0, iz, -yn * iz];
    let f = [fx, fy];
    for row in 0..2 {
        for k in 0..3 {
            out.d_pc[row][k] = f[row] * (jn[row][0] * dx_dpc[k] + jn[row][1] * dy_dpc[k]);
        }
    }
    out.d_focal = [[xd, 0.0], [0.0, yd]];
    let rows = opencv_rows(xn, yn);
    out.d_coefficients = [rows[0].map(|c| fx * c), rows[1].map(|c| fy * c)];
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::FocalPoly;

    /// d pixel / d(numbers, Z_W, E) against central differences, for a model of `layout`.
    fn check(model: &CameraModel, points: &[([f64; 3], f64)]) {
        let l = model.layout();
        let x0 = to_params(model);
        let at = |x: &[f64; MAX_PARAMS]| Projector::new(&from_params(&l, x));
        for &(pw, e) in points {
            let p = Projector::new(model).project(pw, e, true).unwrap();
            for j in 0..l.len() {
                // The pixel is linear in a_i, so a large step is exact there and beats roundoff.
                // (A zero a_i gets a step of 1: its pixel change is still small and linear.)
                // A focal coefficient kf_i steps so that f(E) moves by 1e-6 of itself.
                let kf_power = [l.kf_x(), l.kf_y()].iter().find(|s| s.contains(j)).map(|s| j - s.start);
                let h = match (l.distortion_a().contains(j), x0[j] == 0.0, kf_power) {
                    (true, true, _) => 1.0,
                    (true, false, _) => 1e-2 * x0[j].abs(),
                    (false, _, Some(i)) => 1e-6 * x0[l.kf0x()] / libm::pow(e, i as f64),
                    (false, _, None) => 1e-6 * x0[j].abs().max(1e-3),
                };
                let (mut xp, mut xm) = (x0, x0);
                xp[j] += h;
                xm[j] -= h;
                let fp = at(&xp).project(pw, e, false).unwrap().pixel;
                let fm = at(&xm).project(pw, e, false).unwrap().pixel;
                for row in 0..2 {
                    let fd = (fp[row] - fm[row]) / (2.0 * h);
                    let an = p.d_params[row][j];
                    assert!((fd - an).abs() <= 1e-5 * an.abs().max(1e-3), "{} row {row}: fd {fd} an {an}", l.name(j));
                }
            }
            assert!(p.d_params.iter().all(|r| r[l.len()..].iter().all(|&v| v == 0.0)));
            for row in 0..2 {
                let h = 1e-4;
                let proj = Projector::new(model);
                let fz = |dz: f64| proj.project([pw[0], pw[1], pw[2] + dz], e, false).unwrap().pixel[row];
                let fe = |de: f64| proj.project(pw, e + de, false).unwrap().pixel[row];
                let (dz, de) = ((fz(h) - fz(-h)) / (2.0 * h), (fe(h) - fe(-h)) / (2.0 * h));
                assert!((dz - p.d_z_w[row]).abs() < 1e-5 * dz.abs().max(1.0), "dZ {dz} {}", p.d_z_w[row]);
                assert!((de - p.d_e[row]).abs() < 1e-5 * de.abs().max(1.0), "dE {de} {}", p.d_e[row]);
            }
            // And the value agrees with the model's own projection.
            let q = model.project(pw, e).unwrap();
            assert!((q[0] - p.pixel[0]).abs() < 1e-9 && (q[1] - p.pixel[1]).abs() < 1e-9, "{q:?} {:?}", p.pixel);
        }
    }

    /// The camera point's projection and its Jacobian against the model's own projection
    /// and central differences, both families.
    #[test]
    fn camera_point_jacobian_matches_central_differences() {
        use crate::model::projection::project_camera_point;
        for model in [CameraModel::paper_rig(), CameraModel::strong_distortion_rig()] {
            let (k, d) = (model.intrinsics(150.0).unwrap(), model.distortion(150.0).unwrap());
            for pc in [[30.0, -20.0, 400.0], [-150.0, 90.0, 300.0], [0.0, 0.0, 50.0]] {
                let (px, j) = project_camera_point_jacobian(pc, &k, &d).unwrap();
                let q = project_camera_point(pc, &k, &d).unwrap();
                assert!((px[0] - q[0]).abs() < 1e-9 && (px[1] - q[1]).abs() < 1e-9, "{px:?} {q:?}");
                for c in 0..3 {
                    let h = 1e-4;
                    let (mut a, mut b) = (pc, pc);
                    a[c] += h;
                    b[c] -= h;
                    let (pa, pb) = (project_camera_point(a, &k, &d).unwrap(), project_camera_point(b, &k, &d).unwrap());
                    for row in 0..2 {
                        let fd = (pa[row] - pb[row]) / (2.0 * h);
                        assert!(
                            (fd - j[row][c]).abs() < 1e-6 * fd.abs().max(1.0),
                            "{pc:?} {row} {c}: {fd} {}",
                            j[row][c]
                        );
                    }
                }
            }
            assert_eq!(project_camera_point_jacobian([0.0, 0.0, -1.0], &k, &d), Err(Error::BehindCamera));
        }
    }

    #[test]
    fn jacobian_matches_central_differences() {
        check(
            &CameraModel::paper_rig(),
            &[([3.0, 4.5, 48.0], 100.0), ([19.5, 16.5, 2.0], 225.0), ([0.0, 0.0, 75.0], 80.0)],
        );
        let strong = CameraModel::strong_distortion_rig();
        let pts = [([0.0, 0.0, 0.0], 100.0), ([120.0, 90.0, -40.0], 225.0), ([60.0, -30.0, 50.0], 80.0)];
        check(&strong, &pts);
        // Other focal degrees: linear and quintic.
        let mut lin = strong;
        lin.kf_x = FocalPoly::new(&[1400.0, -0.9]).unwrap();
        lin.kf_y = FocalPoly::new(&[1410.0, -0.9]).unwrap();
        check(&lin, &pts);
        let mut quintic = CameraModel::paper_rig();
        quintic.kf_x = FocalPoly::new(&[5380.0, -7.0, 0.02, -3e-5, 1e-9, -2e-12]).unwrap();
        quintic.kf_y = FocalPoly::new(&[5430.0, -7.0, 0.02, -3e-5, 1e-9, -2e-12]).unwrap();
        check(&quintic, &[([3.0, 4.5, 48.0], 100.0), ([19.5, 16.5, 2.0], 225.0)]);
        // A moving centre (Eq. C1-C3), both families.
        let centre = Some(MovingCentre { dz_mm: [-6e-3, 1.2e-5], principal_point_slope_px: [0.03, -0.02] });
        check(
            &CameraModel { centre, ..CameraModel::paper_rig() },
            &[([3.0, 4.5, 48.0], 100.0), ([19.5, 16.5, 2.0], 225.0)],
        );
        check(&CameraModel { centre, ..strong }, &pts);
    }

    /// A moving centre's T_z(E) and principal point (Eq. C2-C3) in the projection: the
    /// model at E projects as the fixed-centre model with T_z - dz(E) and (u0, v0)(E).
    #[test]
    fn a_moving_centre_is_the_fixed_model_moved() {
        let centre = MovingCentre { dz_mm: [-6e-3, 1.2e-5], principal_point_slope_px: [0.03, -0.02] };
        let moving = CameraModel { centre: Some(centre), ..CameraModel::paper_rig() };
        let e = 150.0;
        let mut fixed = CameraModel::paper_rig();
        fixed.translation_mm[2] -= e * (-6e-3 + 1.2e-5 * e);
        fixed.principal_point = [900.0 + 0.03 * e, 550.0 - 0.02 * e];
        let p = [3.0, 4.5, 48.0];
        let (a, b) = (moving.project(p, e).unwrap(), fixed.project(p, e).unwrap());
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
        let r = Projector::new(&moving).project(p, e, false).unwrap().pixel;
        assert!((r[0] - b[0]).abs() < 1e-9 && (r[1] - b[1]).abs() < 1e-9);
        let back = from_params(&moving.layout(), &to_params(&moving));
        assert_eq!(back, moving);
    }

    #[test]
    fn vectors_round_trip_for_every_layout() {
        let m = CameraModel::strong_distortion_rig();
        let back = from_params(&m.layout(), &to_params(&m));
        assert_eq!(back, m);
        assert!(to_params_n::<25>(&m).is_err() && to_params_n::<31>(&m).is_ok());
        assert_eq!(from_params(&Layout::PAPER, &to_params(&CameraModel::paper_rig())), CameraModel::paper_rig());
    }
}
