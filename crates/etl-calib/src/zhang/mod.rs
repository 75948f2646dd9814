//! Zhang's monofocal calibration (Zhang 2000): the lens-off intrinsics A0 (paper section
//! 4.2) from views of a planar board, the building block of the per-setting baseline, and
//! a fixed-focus camera in OpenCV's model (`etlcal zhang --model opencv`).
//!
//! 1. A homography per view ([`etl_core::pnp::homography`], normalised DLT), computed in
//!    a pixel frame centred on the image and scaled by its size, for conditioning.
//! 2. The closed form: each H gives two linear constraints v12^T b = 0,
//!    (v11 - v22)^T b = 0 on b = (B11, B12, B22, B13, B23, B33), B = K^-T K^-1; b is the
//!    right singular vector of the smallest singular value; K follows (Zhang's Appendix B),
//!    skew dropped. Each view's pose from K^-1 H, then the nearest rotation.
//! 3. Levenberg-Marquardt over the shared numbers (fx, fy, u0, v0 and the distortion
//!    coefficients of the chosen family, [`ZhangOptions`]) and the 6 pose numbers of every
//!    view, by the Schur-block solver of etl-core, from zero distortion. The projection and
//!    its Jacobian are the ETL model's at E = 0 with fx(E) = fx, fy(E) = fy and each
//!    distortion coefficient the constant term of its Eq. 18 quadratic: one camera model in
//!    the project. With the `opencv` family that is exactly OpenCV's camera
//!    (`cv2.projectPoints`): the same model and the same least-squares problem as
//!    `cv2.calibrateCamera` (no skew, aspect ratio free, `CALIB_FIX_K3` and
//!    `CALIB_ZERO_TANGENT_DIST` as [`OpenCvFlags`]).
//!
//! Needs at least 3 views of the board in distinct orientations (each view gives two
//! constraints on the 5 unknowns of B up to scale).

use etl_core::calib::jacobian::Projector;
use etl_core::calib::{Layout, A0};
use etl_core::linalg::svd::Svd;
use etl_core::lm::{solve_blocks, BlockNormal, BlockProblem, BlockRowSink, BlockScratch, Options, StopReason};
use etl_core::model::rotation::{matrix_to_rodrigues, rotation_from_two_columns};
use etl_core::model::{
    CameraModel, Distortion, DistortionA, DistortionModel, FocalPoly, OpenCvFlags, MAX_COEFFICIENTS,
};
use etl_core::pnp::{homography, zhang_constraints};

use etl_formats::calibration::Outlier;
use etl_formats::{Error, Result};

use crate::robust::{homography_inliers, outlier_limit_px};

mod uncertainty;
use uncertainty::invert_pose_block;
pub use uncertainty::ZhangUncertainty;

/// One view: board points (mm, on Z = 0) and their observed pixels.
#[derive(Debug, Clone, Default)]
pub struct PlanarView {
    /// Board (X, Y), mm.
    pub board_mm: Vec<[f64; 2]>,
    /// Observed pixels.
    pub pixels: Vec<[f64; 2]>,
}

/// What [`zhang_with`] fits: the distortion family and, for `opencv`, OpenCV's flags.
/// The default is the paper's family (k1, p1, p2 in centred pixels), as [`zhang`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ZhangOptions {
    /// The distortion family.
    pub model: DistortionModel,
    /// `CALIB_FIX_K3` (k3 held at 0) and `CALIB_ZERO_TANGENT_DIST` (p1 = p2 = 0); opencv only.
    pub flags: OpenCvFlags,
}

/// The result of [`zhang`] and [`zhang_with`].
#[derive(Debug, Clone)]
pub struct ZhangResult {
    /// Focal length along u, px.
    pub fx: f64,
    /// Focal length along v, px.
    pub fy: f64,
    /// Principal point u0, px.
    pub u0: f64,
    /// Principal point v0, px.
    pub v0: f64,
    /// The distortion family fitted, with its flags.
    pub options: ZhangOptions,
    /// The distortion coefficients in the family's order, zero past its count: paper k1
    /// (1/px^2), p1, p2 (1/px); opencv k1, k2, p1, p2, k3 (OpenCV's `dist_coeffs`).
    pub coefficients: [f64; MAX_COEFFICIENTS],
    /// One standard deviation of fx, fy, u0, v0 and each coefficient (0 for one held by a
    /// flag), as OpenCV's `calibrateCameraExtended`: the shared block of (J^T J)^-1 with
    /// every pose free, times sigma^2 = cost / (2 points - shared numbers - 6 views).
    pub std: Vec<f64>,
    /// RMS reprojection error over the points used, px.
    pub rms_px: f64,
    /// Each view's RMS reprojection error over its points used, px (OpenCV's
    /// `perViewErrors`).
    pub per_view_rms_px: Vec<f64>,
    /// Each view's pose (Rodrigues, translation mm).
    pub poses: Vec<([f64; 3], [f64; 3])>,
    /// LM iterations.
    pub iterations: usize,
    /// Views used.
    pub views_used: usize,
    /// The points left out as gross outliers (view and point indices into the input),
    /// with their distances under the result; empty when there are none.
    pub outliers: Vec<Outlier>,
    /// The blocks of J^T J that [`Self::projection_std`] needs (intrinsics and every
    /// pose jointly; `None` only in a result built by hand).
    pub uncertainty: Option<ZhangUncertainty>,
}

impl ZhangResult {
    /// The shared numbers: fx, fy, u0, v0, the coefficients.
    pub(crate) fn shared(&self) -> Shared {
        let mut z = [0.0; SHARED_MAX];
        z[..4].copy_from_slice(&[self.fx, self.fy, self.u0, self.v0]);
        z[4..].copy_from_slice(&self.coefficients);
        z
    }

    /// The fitted camera as an ETL camera model at E = 0 (fx(E) = fx, fy(E) = fy, each
    /// coefficient the constant of its Eq. 18 quadratic), at the identity pose: its world
    /// frame is the camera frame, so `project` takes camera-frame points.
    pub fn camera(&self) -> CameraModel {
        model_at(self.options.model, &self.shared(), &[0.0; 6])
    }

    /// The mean distance of the views' boards from the camera, mm (of their poses'
    /// translations; 0 without views).
    pub fn views_distance_mm(&self) -> f64 {
        let n = self.poses.len().max(1) as f64;
        self.poses.iter().map(|(_, t)| (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt()).sum::<f64>() / n
    }

    /// The lens-off intrinsics A0.
    pub fn a0(&self) -> A0 {
        A0 { kf0x: self.fx, kf0y: self.fy, u0: self.u0, v0: self.v0 }
    }

    /// The family's coefficients (its count of [`Self::coefficients`]).
    pub fn distortion_coefficients(&self) -> &[f64] {
        self.coefficients.get(..self.options.model.coefficient_count()).unwrap_or(&self.coefficients)
    }

    /// The camera matrix [[fx, 0, u0], [0, fy, v0], [0, 0, 1]], px.
    pub fn camera_matrix(&self) -> [[f64; 3]; 3] {
        [[self.fx, 0.0, self.u0], [0.0, self.fy, self.v0], [0.0, 0.0, 1.0]]
    }

    /// OpenCV's `dist_coeffs` [k1, k2, p1, p2, k3] for the opencv family (exact: the
    /// model is OpenCV's); `None` for the paper family, whose coefficients act on
    /// centred pixels.
    pub fn dist_coeffs(&self) -> Option<[f64; 5]> {
        (self.options.model == DistortionModel::OpenCv).then_some(self.coefficients)
    }

    /// The distortion (the family's own evaluation of it).
    pub fn distortion(&self) -> Distortion {
        Distortion::from_coefficients(self.options.model, &self.coefficients, self.fx, self.fy)
    }
}

/// The most shared numbers: fx, fy, u0, v0 and OpenCV's five coefficients.
pub(crate) const SHARED_MAX: usize = 4 + MAX_COEFFICIENTS;

/// The shared numbers: fx, fy, u0, v0, then the coefficients in the family's order.
pub(crate) type Shared = [f64; SHARED_MAX];

/// The camera model the shared numbers `z` stand for at E = 0 in family `model`: focal
/// cubic focal polynomials with kf0 = fx, fy (E = 0 leaves only kf0; the paper's layout, so that the paper family solves exactly as before), each coefficient the
/// constant term a_(3c+3) of its Eq. 18 quadratic.
pub(crate) fn model_at(model: DistortionModel, z: &Shared, pose: &[f64; 6]) -> CameraModel {
    let mut a = DistortionA::zero(model);
    for (c, &v) in z.iter().skip(4).take(model.coefficient_count()).enumerate() {
        if let Some(slot) = a.as_mut_slice().get_mut(3 * c + 2) {
            *slot = v;
        }
    }
    CameraModel {
        rotation_rodrigues: [pose[0], pose[1], pose[2]],
        translation_mm: [pose[3], pose[4], pose[5]],
        kf_x: FocalPoly::cubic([z[0], 0.0, 0.0, 0.0]),
        kf_y: FocalPoly::cubic([z[1], 0.0, 0.0, 0.0]),
        principal_point: [z[2], z[3]],
        distortion_a: a,
        centre: None,
    }
}

/// Where shared number `k` lies in the parameter vector of [`model_at`]'s layout.
pub(crate) fn param_index(layout: &Layout, k: usize) -> usize {
    match k {
        0 => layout.kf0x(),
        1 => layout.kf0y(),
        2 => layout.u0(),
        3 => layout.v0(),
        c => layout.distortion_triple(c - 4).at(2),
    }
}

/// The refinement of the `N` free shared numbers (indices `free` into [`Shared`], the
/// others held at `base`) and every view's pose.
struct Refine<'a, const N: usize> {
    views: &'a [PlanarView],
    model: DistortionModel,
    free: [usize; N],
    base: Shared,
}

impl<const N: usize> Refine<'_, N> {
    fn shared(&self, x: &[f64; N]) -> Shared {
        let mut z = self.base;
        for (&i, &v) in self.free.iter().zip(x) {
            if let Some(slot) = z.get_mut(i) {
                *slot = v;
            }
        }
        z
    }
}

impl<const N: usize> BlockProblem<N, 6> for Refine<'_, N> {
    fn block_count(&self) -> usize {
        self.views.len()
    }

    fn eval_block(
        &mut self,
        b: usize,
        x: &[f64; N],
        y: &[f64; 6],
        jacobian: bool,
        sink: &mut dyn BlockRowSink<N, 6>,
    ) -> etl_core::Result<()> {
        let v = self.views.get(b).ok_or(etl_core::Error::InvalidArgument { what: "view index" })?;
        let m = model_at(self.model, &self.shared(x), y);
        let layout = m.layout();
        let cols: [usize; N] = core::array::from_fn(|k| param_index(&layout, self.free[k]));
        let proj = Projector::new(&m);
        for (w, px) in v.board_mm.iter().zip(&v.pixels) {
            let p = proj.project([w[0], w[1], 0.0], 0.0, jacobian)?;
            for row in 0..2 {
                let d = &p.d_params[row];
                let jx: [f64; N] = core::array::from_fn(|k| d.get(cols[k]).copied().unwrap_or(0.0));
                let jy: [f64; 6] = core::array::from_fn(|k| d[k]);
                sink.push(p.pixel[row] - px[row], &jx, &jy);
            }
        }
        Ok(())
    }
}

/// The closed form (steps 1 and 2): (fx, fy, u0, v0) and each view's pose
/// (Rodrigues, translation) from the views' homographies.
fn closed_form(views: &[PlanarView], image_size: [u32; 2]) -> Result<([f64; 4], Vec<[f64; 6]>)> {
    let (cx, cy) = (image_size[0] as f64 / 2.0, image_size[1] as f64 / 2.0);
    let s = cx.max(cy).max(1.0);
    let mut hs = vec![];
    let mut vtv = [[0.0; 6]; 6];
    for v in views {
        let img: Vec<[f64; 2]> = v.pixels.iter().map(|p| [(p[0] - cx) / s, (p[1] - cy) / s]).collect();
        let h = homography(&v.board_mm, &img)?;
        for row in zhang_constraints(&h) {
            for i in 0..6 {
                for j in 0..6 {
                    vtv[i][j] += row[i] * row[j];
                }
            }
        }
        hs.push(h);
    }
    // etl-core's Jacobi SVD of V^T V, not faer's SVD of V: the latter moves A0 in the last
    // bits and the golden outputs of `calibrate` and `demo` beyond 1e-12 (docs/PERFORMANCE-HISTORY.md).
    let svd = Svd::of_rows(&vtv);
    let kmin = (0..6).min_by(|&a, &b| svd.s[a].total_cmp(&svd.s[b])).unwrap_or(0);
    let b = svd.v[kmin];
    let (b11, b12, b22, b13, b23, b33) = (b[0], b[1], b[2], b[3], b[4], b[5]);
    let den = b11 * b22 - b12 * b12;
    let degenerate = || {
        Error::Core(etl_core::Error::Degenerate {
            what: "Zhang's closed form failed: board views too alike (tilt the board between views)",
        })
    };
    if den.abs() < 1e-300 || b11.abs() < 1e-300 {
        return Err(degenerate());
    }
    let v0n = (b12 * b13 - b11 * b23) / den;
    let lambda = b33 - (b13 * b13 + v0n * (b12 * b13 - b11 * b23)) / b11;
    let alpha2 = lambda / b11;
    let beta2 = lambda * b11 / den;
    if !(alpha2 > 0.0 && beta2 > 0.0) {
        return Err(degenerate());
    }
    let (alpha, beta) = (alpha2.sqrt(), beta2.sqrt());
    let u0n = -b13 * alpha2 / lambda; // skew dropped
                                      // Poses from K^-1 H (H in the normalised frame, K likewise).
    let kinv = |p: [f64; 3]| [(p[0] - u0n * p[2]) / alpha, (p[1] - v0n * p[2]) / beta, p[2]];
    let mut poses: Vec<[f64; 6]> = vec![];
    for h in &hs {
        let r1 = kinv([h[0][0], h[1][0], h[2][0]]);
        let r2 = kinv([h[0][1], h[1][1], h[2][1]]);
        let t = kinv([h[0][2], h[1][2], h[2][2]]);
        let n1 = (r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2]).sqrt();
        let n2 = (r2[0] * r2[0] + r2[1] * r2[1] + r2[2] * r2[2]).sqrt();
        let mut l = 2.0 / (n1 + n2);
        if t[2] * l < 0.0 {
            l = -l;
        }
        let (r1, r2, t) = (r1.map(|v| v * l), r2.map(|v| v * l), t.map(|v| v * l));
        let om = matrix_to_rodrigues(&rotation_from_two_columns(r1, r2));
        poses.push([om[0], om[1], om[2], t[0], t[1], t[2]]);
    }
    // Back to pixels: the normalised frame is (p - c) / s.
    Ok(([alpha * s, beta * s, u0n * s + cx, v0n * s + cy], poses))
}

/// What one refinement gives: the shared numbers (held ones at their start), their
/// covariance (OpenCV's scaling, rows and columns of held numbers zero), the poses.
struct Refined {
    z: Shared,
    cov: [[f64; SHARED_MAX]; SHARED_MAX],
    iterations: usize,
    poses: Vec<[f64; 6]>,
    uncertainty: ZhangUncertainty,
}

/// Step 3 for `N` free numbers (see [`refine`]).
fn refine_n<const N: usize>(
    views: &[PlanarView],
    model: DistortionModel,
    free: &[usize],
    z0: &Shared,
    poses: &[[f64; 6]],
) -> Result<Refined> {
    let free: [usize; N] = core::array::from_fn(|k| free.get(k).copied().unwrap_or(0));
    let mut problem = Refine { views, model, free, base: *z0 };
    let x0: [f64; N] = core::array::from_fn(|k| z0[free[k]]);
    let mut scratch: Vec<BlockScratch<N, 6>> = poses.iter().map(|&p| BlockScratch::starting_at(p)).collect();
    let opts = Options { max_iterations: 100, ftol: 1e-12, xtol: 1e-12, gtol: 1e-12, ..Options::default() };
    let r = solve_blocks(&mut problem, x0, &opts, &mut scratch)?;
    if r.stop == StopReason::RankDeficient {
        return Err(Error::Core(etl_core::Error::Degenerate {
            what: "Zhang's refinement is rank deficient (too few or too similar views)",
        }));
    }
    // OpenCV's degrees of freedom: every pose number is a parameter too.
    let dof = r.residuals.saturating_sub(N + 6 * views.len()).max(1) as f64;
    let scale = if r.sigma2 > 0.0 { r.cost / dof / r.sigma2 } else { 0.0 };
    let mut cov = [[0.0; SHARED_MAX]; SHARED_MAX];
    for (a, &i) in free.iter().enumerate() {
        for (b, &j) in free.iter().enumerate() {
            cov[i][j] = r.covariance[a][b] * scale;
        }
    }
    let (z, poses): (Shared, Vec<[f64; 6]>) = (problem.shared(&r.x), scratch.iter().map(|b| *b.y()).collect());
    let uncertainty = joint_blocks(&mut problem, &r, &scratch, r.cost / dof, (z, poses.clone()))?;
    Ok(Refined { z, cov, iterations: r.iterations, poses, uncertainty })
}

/// The blocks of J^T J at the solution `r` (poses in `scratch`) for
/// [`ZhangResult::projection_std`], with the pixel noise variance `sigma2_px` and the
/// solution's shared numbers and poses.
fn joint_blocks<const N: usize>(
    problem: &mut Refine<'_, N>,
    r: &etl_core::lm::BlockReport<N>,
    scratch: &[BlockScratch<N, 6>],
    sigma2_px: f64,
    (shared, poses): (Shared, Vec<[f64; 6]>),
) -> Result<ZhangUncertainty> {
    let free = problem.free;
    let unscale = if r.sigma2 > 0.0 { 1.0 / r.sigma2 } else { 0.0 };
    let mut s_inv = [[0.0; SHARED_MAX]; SHARED_MAX];
    for (a, &i) in free.iter().enumerate() {
        for (b, &j) in free.iter().enumerate() {
            s_inv[i][j] = r.covariance[a][b] * unscale;
        }
    }
    let (mut w, mut v_inv) = (vec![], vec![]);
    for (b, block) in scratch.iter().enumerate() {
        let (mut u, mut gx, mut wb, mut v, mut gy) = ([[0.0; N]; N], [0.0; N], [[0.0; 6]; N], [[0.0; 6]; 6], [0.0; 6]);
        let mut sink = BlockNormal { u: &mut u, gx: &mut gx, w: &mut wb, v: &mut v, gy: &mut gy, cost: 0.0, rows: 0 };
        problem.eval_block(b, &r.x, block.y(), true, &mut sink).map_err(Error::Core)?;
        v_inv.push(invert_pose_block(&v)?);
        // W_i's rows of the free numbers, at their places among the shared ones.
        let mut at_shared = [[0.0; 6]; SHARED_MAX];
        for (&i, row) in free.iter().zip(wb) {
            at_shared[i] = row;
        }
        w.push(at_shared);
    }
    Ok(ZhangUncertainty { model: problem.model, shared, poses, s_inv, w, v_inv, sigma2_px })
}

/// The indices into [`Shared`] of the numbers `options` leaves free: fx, fy, u0, v0 and
/// every coefficient of the family that no OpenCV flag holds.
pub(crate) fn free_numbers(options: &ZhangOptions) -> Vec<usize> {
    let model = options.model;
    (0..4 + model.coefficient_count()).filter(|&k| k < 4 || !options.flags.holds(model, k - 4)).collect()
}

/// Step 3: the LM refinement of the free shared numbers and every view's pose from `z0`
/// and `poses`; the numbers `options` holds stay at `z0`.
fn refine(views: &[PlanarView], options: &ZhangOptions, z0: &Shared, poses: &[[f64; 6]]) -> Result<Refined> {
    let model = options.model;
    let free = free_numbers(options);
    match free.len() {
        6 => refine_n::<6>(views, model, &free, z0, poses),
        7 => refine_n::<7>(views, model, &free, z0, poses),
        8 => refine_n::<8>(views, model, &free, z0, poses),
        9 => refine_n::<9>(views, model, &free, z0, poses),
        _ => Err(Error::invalid("options", format!("Zhang's refinement: {} free numbers", free.len()))),
    }
}

/// The points of each view that `used` keeps.
fn kept(views: &[PlanarView], used: &[Vec<bool>]) -> Vec<PlanarView> {
    views
        .iter()
        .zip(used)
        .map(|(v, u)| {
            let (board_mm, pixels) =
                v.board_mm.iter().zip(&v.pixels).zip(u).filter(|&(_, &k)| k).map(|((b, p), _)| (*b, *p)).unzip();
            PlanarView { board_mm, pixels }
        })
        .collect()
}

/// Every point's reprojection distance, px, under the shared numbers `z` and `poses`
/// (infinite where it does not project).
fn distances(views: &[PlanarView], model: DistortionModel, z: &Shared, poses: &[[f64; 6]]) -> Vec<Vec<f64>> {
    views
        .iter()
        .zip(poses)
        .map(|(v, pose)| {
            let m = model_at(model, z, pose);
            v.board_mm
                .iter()
                .zip(&v.pixels)
                .map(|(b, px)| match m.project([b[0], b[1], 0.0], 0.0) {
                    Ok(q) => (q[0] - px[0]).hypot(q[1] - px[1]),
                    Err(_) => f64::INFINITY,
                })
                .collect()
        })
        .collect()
}

/// Calibrates a fixed-focus camera from planar views with the paper's distortion family
/// ([`zhang_with`] with the default [`ZhangOptions`]).
pub fn zhang(views: &[PlanarView], image_size: [u32; 2]) -> Result<ZhangResult> {
    zhang_with(views, image_size, &ZhangOptions::default())
}

/// Calibrates a fixed-focus camera from planar views (see the module docs) with the
/// distortion family and flags of `options`, robustly: each view's points are first
/// screened against a robust homography
/// ([`crate::robust::homography_inliers`]); after the refinement a point whose
/// distance exceeds [`outlier_limit_px`] is an outlier, and the refinement is
/// repeated without the outliers until their set no longer changes (at most 4 times).
///
/// `image_size` sets the conditioning frame. Errors: fewer than 3 views or a view with
/// fewer than 4 points ([`Error::InvalidInput`] about `"views"` or `"views[k].pixels"`,
/// which a caller holding the views under another key renames, [`in_list`]); an OpenCV
/// flag with the paper family
/// ([`Error::Core`] naming it); degenerate geometry (all views parallel) or a failed
/// solve ([`Error::Core`]).
///
/// ```
/// use etl_calib::zhang::{zhang_with, PlanarView, ZhangOptions};
/// use etl_core::model::{CameraModel, DistortionModel, OpenCvFlags};
///
/// // Lens-off views of the paper rig, noise-free, fitted with OpenCV's model.
/// let sim = etl_sim::simulate::paper_rig(&etl_sim::simulate::NoiseModel::NONE, 1);
/// let views: Vec<PlanarView> = sim.observations.offstate_views.iter().map(|v| PlanarView {
///     board_mm: v.points.iter().map(|p| [p.world_mm[0], p.world_mm[1]]).collect(),
///     pixels: v.points.iter().map(|p| p.pixel).collect(),
/// }).collect();
/// let opts = ZhangOptions { model: DistortionModel::OpenCv, flags: OpenCvFlags::NONE };
/// let z = zhang_with(&views, CameraModel::PAPER_IMAGE_SIZE, &opts)?;
/// let [k1, k2, p1, p2, k3] = z.dist_coeffs().unwrap();
/// assert!((z.u0 - 900.0).abs() < 0.5 && k1 < 0.0);
/// # let _ = (k2, p1, p2, k3);
/// # Ok::<(), etl_calib::Error>(())
/// ```
pub fn zhang_with(views: &[PlanarView], image_size: [u32; 2], options: &ZhangOptions) -> Result<ZhangResult> {
    options.flags.check(options.model).map_err(Error::Core)?;
    if views.len() < 3 {
        return Err(Error::invalid(
            "views",
            format!("Zhang's method needs at least 3 views of the board, got {}", views.len()),
        ));
    }
    for (k, v) in views.iter().enumerate() {
        if v.board_mm.len() != v.pixels.len() || v.board_mm.len() < 4 {
            return Err(Error::invalid(
                format!("views[{k}].pixels"),
                format!("view {k}: needs at least 4 points with their pixels"),
            ));
        }
    }
    let model = options.model;
    let mut used: Vec<Vec<bool>> = views.iter().map(|v| homography_inliers(&v.board_mm, &v.pixels)).collect();
    let screened = kept(views, &used);
    let (k, poses) = closed_form(&screened, image_size)?;
    let mut z0 = [0.0; SHARED_MAX];
    z0[..4].copy_from_slice(&k);
    let mut r = refine(&screened, options, &z0, &poses)?;
    let mut d = distances(views, model, &r.z, &r.poses);
    for _ in 0..4 {
        let all: Vec<f64> = d.iter().flatten().copied().collect();
        let limit = outlier_limit_px(&all);
        let inliers: Vec<Vec<bool>> = d.iter().map(|v| v.iter().map(|&x| x <= limit).collect()).collect();
        if inliers == used {
            break;
        }
        used = inliers;
        // From the last solution: it is already near, and the closed form is only needed
        // to start.
        r = refine(&kept(views, &used), options, &r.z, &r.poses)?;
        d = distances(views, model, &r.z, &r.poses);
    }
    Ok(summarise(views, options, r, &used, &d))
}

/// The result of the last refinement `r`: RMS over the points `used`, per view and in all,
/// the outliers, the standard deviations.
fn summarise(
    views: &[PlanarView],
    options: &ZhangOptions,
    r: Refined,
    used: &[Vec<bool>],
    d: &[Vec<f64>],
) -> ZhangResult {
    let mut outliers = vec![];
    let mut per_view_rms_px = vec![];
    let (mut ss, mut n) = (0.0, 0usize);
    for (j, (u, dv)) in used.iter().zip(d).enumerate() {
        let (mut sv, mut nv) = (0.0, 0usize);
        for (i, (&k, &x)) in u.iter().zip(dv).enumerate() {
            if k {
                sv += x * x;
                nv += 1;
            } else {
                outliers.push(Outlier { view: j, point: i, residual_px: if x.is_finite() { x } else { f64::MAX } });
            }
        }
        per_view_rms_px.push((sv / nv.max(1) as f64).sqrt());
        ss += sv;
        n += nv;
    }
    let count = 4 + options.model.coefficient_count();
    let std = (0..count).map(|i| r.cov[i][i].max(0.0).sqrt()).collect();
    let mut coefficients = [0.0; MAX_COEFFICIENTS];
    coefficients.copy_from_slice(&r.z[4..]);
    ZhangResult {
        fx: r.z[0],
        fy: r.z[1],
        u0: r.z[2],
        v0: r.z[3],
        options: *options,
        coefficients,
        std,
        rms_px: (ss / n.max(1) as f64).sqrt(),
        per_view_rms_px,
        poses: r.poses.iter().map(|p| ([p[0], p[1], p[2]], [p[3], p[4], p[5]])).collect(),
        iterations: r.iterations,
        views_used: views.len(),
        outliers,
        uncertainty: Some(r.uncertainty),
    }
}

/// A [`zhang`] error about its `views` argument as the bad input of the list the views
/// came from: `"views"` and `"views[k]..."` become `"{key}"` and `"{key}[indices[k]]..."`
/// (`indices[k]`: the list's index of the k-th view given to Zhang, `None` for the same
/// index), e.g. `offstate_views[2].pixels`; message and value unchanged.
pub fn in_list(err: Error, key: &str, indices: Option<&[usize]>) -> Error {
    err.map_what(|what| {
        let Some(rest) = what.strip_prefix("views") else { return what };
        let index = rest.strip_prefix('[').and_then(|r| r.split_once(']'));
        match index.and_then(|(k, tail)| Some((k.parse::<usize>().ok()?, tail))) {
            Some((k, tail)) => {
                let i = indices.and_then(|ix| ix.get(k).copied()).unwrap_or(k);
                format!("{key}[{i}]{tail}")
            }
            None => format!("{key}{rest}"),
        }
    })
}
