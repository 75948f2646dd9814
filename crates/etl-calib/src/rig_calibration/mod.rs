//! A multi-camera ETL rig calibrated jointly from an `etlcal.rig-dataset/1`: N cameras
//! looking at one board on one linear stage.
//!
//! The cameras share the stage's world frame. Camera k has its own numbers x_k: its pose
//! (om_k, t_k) to the world, its focal polynomials, principal point, distortion and
//! (optionally) moving centre, in its own layout (p_k <= 39 numbers). The extrinsics of
//! camera k relative to camera 0 follow from the poses, at E = 0 of each camera (where a
//! moving-centre model's pose holds; the rig file's `reference_setting` [0, 0]):
//!
//! ```text
//! R_k0 = R_k R_0',   T_k0 = t_k - R_k0 t_0       (X_k = R_k0 X_0 + T_k0)
//! ```
//!
//! **Start**: each camera calibrated alone by the single-camera pipeline, with the request
//! of `etlcal calibrate` ([`crate::request::CalibrationRequest`]: model, estimator, priors,
//! A0 from its lens-off views or given, its lens's temperature surface), the rig's or its
//! own ([`RigCalibrationOptions::per_camera`]), its outliers left out of the joint solve.
//! Cameras may so differ in layout (distortion family, focal degree, fixed or moving
//! centre, held numbers): each camera's numbers x_k keep their own layout in the joint
//! problem, p_k per camera. The estimator and the stage's prior are the rig's.
//!
//! **Joint solve** (errors-in-variables): view j's stage really stood at Z_j + dZ_j for
//! every camera that saw it (one physical stage), while each camera's lens ran at its own
//! E_kj + dE_kj. With each camera's rows normalised by its sigma_px (its own solve's):
//!
//! ```text
//! min sum_k sum_j in views(k) [ sum_i |q_k(P_ij + dZ_j e_z, E_kj + dE_kj) - u_kij|^2 / sigma_px,k^2
//!                               + dE_kj^2 / sigma_e^2 ] + sum_j dZ_j^2 / sigma_z^2
//! ```
//!
//! over all x_k, dZ_j, dE_kj: hand-written Levenberg-Marquardt with etl-core's pieces
//! (its projection Jacobians, its internal parameters, its damping logic), the per-view
//! corrections eliminated by the Schur complement into a reduced system over all cameras'
//! numbers ([`LinearSolver`]: dense, or sparse with the stage corrections kept). The
//! shared dZ_j is what couples the cameras: the stage error of a view moves every camera's
//! image of it at once, so the joint solve tells a stage error from a camera's focal error
//! better than any camera alone.
//!
//! **The paper's estimator** (no corrections) separates exactly: the cost is a sum over
//! cameras of each camera's own cost, each term depending on that camera's numbers only,
//! so the joint minimum is each camera's own (the joint result equals the per-camera
//! calibrations to solver precision; a test checks it). Its joint covariance still
//! couples the cameras through the shared stage errors (`covariance.rs`).
//!
//! **Covariance**: of all numbers jointly ([`RigCalibration::covariance`]), and of each
//! extrinsic pose (6 x 6, rad and mm) by the Jacobian of (R_k0, T_k0) with respect to
//! (om_0, t_0, om_k, t_k), written into `etlcal.rig/1`'s `covariance`.
//!
//! **Free views** (`etlcal.rig-dataset/1`'s `free_views`: the board in a free pose, no
//! stage) add one unknown board pose (om_b, t_b) per view, board to world, shared by the
//! cameras that saw it, without a prior; each camera keeps its own setting correction
//! there. Their corner (X, Y) stands at world R(om_b) (X, Y, 0) + t_b:
//!
//! ```text
//!   + sum_f sum_k in f [ sum_i |q_k(R_bf P_i + t_bf, E_kf + dE_kf) - u_kfi|^2 / sigma_px,k^2
//!                        + dE_kf^2 / sigma_e^2 ]
//! ```
//!
//! Each pose starts from relative PnP (`free.rs`) and is eliminated with the view's other
//! unknowns. They give the joint solve tilted views, which the stage's nearly
//! fronto-parallel ones lack; the cameras' own calibrations (the start) do not see them.
//! Errors-in-variables only: under the paper's estimator each camera is its own problem,
//! and a free pose would tie them (refused, one line).
//!
//! **Images**: a rig dataset of images is first turned into one of points by
//! [`detect_rig`] (each camera's images through the single-camera detection path, a view
//! whose board is not found dropped for that camera).
//!
//! Preconditions: every camera calibrates alone (at least 3 distinct settings, its
//! lens-off views or a given A0); points ([`detect_rig`] first for images); the proposed
//! method; no robust loss.

mod cameras;
mod covariance;
mod detect;
mod free;
mod lm;
mod normal;
mod options;
mod reduced;
mod result;
mod step;

pub use cameras::JointCamera;
pub use detect::{detect_rig, RigDetectionSummary};
pub use options::{CameraRequest, LinearSolver, RigCalibrationOptions, DEFAULT_MAX_ITERATIONS, SPARSE_FROM_CAMERAS};
pub use result::{RigCalibration, RigCameraResult};
pub use step::JointSystem;

use etl_core::calib::Estimator;
use etl_formats::rig::{relative_pose, RigExtrinsics};
use etl_formats::rig_dataset::RigDataset;
use etl_formats::Result;

use self::cameras::calibrate_cameras;
use self::covariance::pose_pair;
use self::normal::JointProblem;
use self::result::{joint_calibration, pose_of};
use crate::request::{KeySpelling, Spelling};

/// Calibrates the rig of `dataset` (module docs), refusals spelt by the request's own
/// keys ([`KeySpelling`]); [`calibrate_rig_spelled`] for a front end's words.
pub fn calibrate_rig(dataset: &RigDataset, options: &RigCalibrationOptions) -> Result<RigCalibration> {
    calibrate_rig_spelled(dataset, options, &KeySpelling)
}

/// [`calibrate_rig`] with the front end's `spelling` of the request's options.
///
/// Errors (one line, naming the input): the dataset's own ([`RigDataset::validate`]);
/// images instead of points; a per-camera request naming no camera of the dataset, or one
/// camera twice; the per-setting method or a robust loss (a camera's own request: naming
/// the camera); a camera's own estimator or stage prior other than the rig's (named); a
/// camera whose views record E_in without E_com and which has no temperature surface
/// (named); a camera's own calibration failing (naming the camera); a joint system that is
/// not positive definite.
pub fn calibrate_rig_spelled(
    dataset: &RigDataset,
    options: &RigCalibrationOptions,
    spelling: &(dyn Spelling + Sync),
) -> Result<RigCalibration> {
    let parts = calibrate_cameras(dataset, options, spelling)?;
    let joint: Vec<JointCamera> = parts.iter().map(|p| p.joint.clone()).collect();
    let (sigma_z, estimator) = match options.request.estimator() {
        Estimator::Eiv { sigma_z_mm, .. } => (Some(sigma_z_mm), "eiv"),
        Estimator::Paper => (None, "paper"),
    };
    let free_start = free::free_view_starts(&joint, dataset.views.len(), dataset.free_views.len())?;
    let problem = JointProblem::new(&joint, dataset.views.len(), free_start, sigma_z);
    let sparse = options.solver.sparse_for(joint.len());
    let max_iterations = if options.max_iterations == 0 { DEFAULT_MAX_ITERATIONS } else { options.max_iterations };
    let solved = lm::solve(&problem, sparse, max_iterations)?;
    let input_sigma_z = options.request.input_noise().sigma_z_mm;
    let cov = covariance::joint_covariance(&problem, &solved.state, Some(input_sigma_z))?;
    let sizes = problem.sizes();
    let offsets: Vec<usize> = sizes.iter().scan(0, |a, p| Some(std::mem::replace(a, *a + p))).collect();
    let mut cameras = vec![];
    for (k, part) in parts.iter().enumerate() {
        let m = problem.model(k, &solved.state);
        let block = cov.view((offsets[k], offsets[k]), (sizes[k], sizes[k])).into_owned();
        let (rms_px, corrections) = problem.camera_rms(k, &solved.state)?;
        let calibration =
            joint_calibration(&part.own.calibration, &m, &block, (rms_px, &corrections), solved.iterations)?;
        let c = &dataset.cameras[k];
        cameras.push(RigCameraResult {
            name: c.name.clone(),
            image_size: c.image_size,
            calibration,
            own: part.own.calibration.clone(),
            rms_px,
            request: part.request.clone(),
        });
    }
    let (p0, i0) = pose_of(&problem.model(0, &solved.state));
    let extrinsics = (1..joint.len())
        .map(|k| {
            let (pk, ik) = pose_of(&problem.model(k, &solved.state));
            let (om, t) = relative_pose(pose_pair(p0), pose_pair(pk));
            let shift = |i: [usize; 6], o: usize| i.map(|x| x + o);
            let c = covariance::extrinsics_covariance(&cov, (&shift(i0, offsets[0]), &shift(ik, offsets[k])), (p0, pk));
            RigExtrinsics {
                camera: k,
                rotation_rodrigues: om,
                translation_mm: t,
                covariance: Some(c),
                reference_setting: Some([0.0, 0.0]),
            }
        })
        .collect();
    Ok(RigCalibration {
        cameras,
        extrinsics,
        covariance: cov,
        offsets,
        dz_mm: solved.state.y.iter().take(dataset.views.len()).map(|y| y.get(0).copied().unwrap_or(0.0)).collect(),
        free_view_poses: problem.free_poses(&solved.state).iter().map(|p| pose_pair(*p)).collect(),
        estimator: estimator.into(),
        iterations: solved.iterations,
        cost: [solved.initial_cost, solved.cost],
        sparse,
    })
}
