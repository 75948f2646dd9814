//! A simulated N-camera ETL rig: N cameras around one linear stage that moves one board
//! along world Z, each with its own paper-model truth, as an `etlcal.rig-dataset/1` of
//! points and the truth as an `etlcal.rig/1`.
//!
//! Camera 0 is the paper rig's camera ([`CameraModel::paper_rig`]). Camera k >= 1 stands
//! `baseline_mm` from camera 0's centre, in camera 0's image plane at the angle
//! 2 pi (k - 1) / (N - 1) from its x axis, and verges on the board's centre at the
//! middle of the stage's travel (its z axis through that point, its x axis as near
//! camera 0's as that allows). Each camera's numbers are the paper rig's perturbed by a
//! per-camera factor s_k in [-1, 1] ([`camera_truth`]): kf (both polynomials) x (1 + 0.03
//! s_k), principal point + (25, -15) s_k px, distortion a_i x (1 + 0.2 s_k); optionally a
//! moving centre (dz1 = -0.01 (1 + 0.2 s_k) mm/mA, dz2 = 2e-5 mm/mA^2, u1 = 0.02,
//! v1 = -0.03 px/mA).
//!
//! Per stage view j (stage positions evenly over [`STAGE_TRAVEL_MM`]) the stage really
//! stands at Z_j + dZ_j (one physical stage: the same dZ_j for every camera); each camera
//! k focuses on the board: its compensated current E_kj is the paper lens's focus law
//! ([`crate::rig::focus_law_current_ma`]) at the camera depth of the board's centre,
//! recorded while the lens really runs at E_kj + dE_kj (its own current error). Each
//! camera's lens has its own focus law: the paper lens's at the depth mapped affinely
//! from the camera's depths of the board's centre at the ends of the travel onto camera
//! 0's ([`focus_current_ma`]), so that every camera sweeps the paper rig's currents. Each
//! physical corner sits off its nominal X, Y by the corner noise (the same for every
//! camera); each observed pixel carries the pixel noise. A camera takes part in a view
//! when at least [`MIN_POINTS`] corners fall in its image at a current inside the paper
//! rig's range of currents (within [`E_MARGIN_MA`]). Each camera has the 10 lens-off views of the paper rig
//! ([`crate::simulate::lens_off_views_of`]) for its A0.
//!
//! Every lens has the paper's temperature surface at 27 degC by default (each view's E_in
//! its E_com through it). With [`LensThermal`] each lens has its own: camera k's E_T is
//! the paper's with every coefficient times 1 + `spread` s_k
//! ([`lens_thermal_surface`]), and the lenses warm over the session, view j at the
//! temperature linear in j between `temperatures_c`; view j's E_in is then camera k's
//! E_com through its own surface at that temperature, so that a calibration that takes
//! one lens's surface for another's reads wrong currents.
//!
//! The extrinsics of camera k relative to camera 0 (X_k = R X_0 + T) are
//! R = R_k R_0^T, T = t_k - R t_0 with (R_k, t_k) each camera's pose to the stage's world
//! frame, at E = 0 (where a moving-centre model's pose holds).

use etl_core::model::rotation::{mat_vec, matrix_to_rodrigues, rodrigues_to_matrix, Mat3};
use etl_core::model::{CameraModel, DistortionA, FocalPoly, MovingCentre};
use etl_core::thermal::ThermalSurface;
use etl_formats::board::Board;
use etl_formats::calibration::Calibration;
use etl_formats::rig::{relative_pose, RigCamera, RigExtrinsics, RigFile};
use etl_formats::rig_dataset::{
    points_of, RigDataset, RigDatasetCamera, RigOffstateShot, RigOffstateView, RigShot, RigView,
};
use etl_formats::{Error, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::rig::{focus_law_current_ma, focus_law_depth_mm, PAPER_E_COM_MA, PAPER_TEMPERATURE_C};
use crate::simulate::{gauss, lens_off_views_of, LensOff, NoiseModel, StageBoard};

pub mod images;

/// The stage's travel, mm: the paper rig's (its views stand from 2 to 75 mm).
pub const STAGE_TRAVEL_MM: [f64; 2] = [2.0, 75.0];
/// The fewest corners a camera must see in a view to take part in it.
pub const MIN_POINTS: usize = 12;
/// The rig's board: 41 x 33 inner corners of 1.5 mm (the paper board's squares, 60 x 48
/// mm), centred where the paper board is, so that the verging cameras keep part of it in
/// view over the whole travel.
pub const MULTI_CAMERA_BOARD: StageBoard =
    StageBoard { inner_corners: [41, 33], square_mm: 1.5, origin_mm: [-20.25, -15.75] };
/// How far a camera's current may leave the paper rig's range of currents, mA (its lens's
/// offset, [`focus_current_ma`]).
pub const E_MARGIN_MA: f64 = 5.0;
/// The most cameras a simulated rig may have.
pub const MAX_CAMERAS: usize = 64;

/// How the rig is built (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiCameraDesign {
    /// Number of cameras, 2..=[`MAX_CAMERAS`].
    pub cameras: usize,
    /// Number of stage views (positions evenly over [`STAGE_TRAVEL_MM`]), >= 3.
    pub views: usize,
    /// Distance of cameras 1.. from camera 0, mm (60..=150).
    pub baseline_mm: f64,
    /// Whether each camera's centre moves with the setting.
    pub moving_centre: bool,
    /// Each lens's own temperature surface and the session's temperatures (module docs);
    /// `None`: the paper's surface for every lens, at 27 degC.
    pub lens_thermal: Option<LensThermal>,
}

/// Lenses whose temperature surfaces differ, warming over the session (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensThermal {
    /// How far camera k's surface is from the paper's: its coefficients times
    /// 1 + `spread` s_k (s_k the camera's factor: 0 for camera 0), in [0, 1].
    pub spread: f64,
    /// The lenses' temperature at the first and the last stage view, degC (linear in
    /// between), inside the paper surface's 27..37 degC.
    pub temperatures_c: [f64; 2],
}

/// Camera k's (of n) lens's temperature surface under `thermal` (module docs): the
/// paper's with every coefficient times 1 + spread s_k.
pub fn lens_thermal_surface(k: usize, n: usize, thermal: &LensThermal) -> ThermalSurface {
    let f = 1.0 + thermal.spread * spread(k, n);
    ThermalSurface { coefficients: ThermalSurface::PAPER.coefficients.map(|c| c * f) }
}

impl MultiCameraDesign {
    /// `cameras` cameras at a 60 mm baseline over the paper rig's 15 views, fixed centres.
    pub const fn new(cameras: usize) -> Self {
        MultiCameraDesign { cameras, views: 15, baseline_mm: 60.0, moving_centre: false, lens_thermal: None }
    }

    /// Refuses a design outside the documented ranges, naming the field.
    pub fn validate(&self) -> Result<()> {
        if !(2..=MAX_CAMERAS).contains(&self.cameras) {
            let message = format!("cameras: {} is outside 2..={MAX_CAMERAS}", self.cameras);
            return Err(Error::invalid_value("cameras", self.cameras as f64, message));
        }
        if !(3..=10_000).contains(&self.views) {
            let message = format!("views: {} is outside 3..=10000", self.views);
            return Err(Error::invalid_value("views", self.views as f64, message));
        }
        etl_formats::check_range("baseline_mm", self.baseline_mm, [60.0, 150.0], "mm")?;
        if let Some(t) = &self.lens_thermal {
            etl_formats::check_range("lens_thermal.spread", t.spread, [0.0, 1.0], "")?;
            for (i, &tc) in t.temperatures_c.iter().enumerate() {
                etl_formats::check_range(&format!("lens_thermal.temperatures_c[{i}]"), tc, [27.0, 37.0], "degC")?;
            }
        }
        Ok(())
    }
}

/// A simulated rig and the truth behind it.
#[derive(Debug, Clone)]
pub struct MultiCameraSimulation {
    /// What the cameras recorded (points).
    pub dataset: RigDataset,
    /// Each camera's true model (pose to the stage's world frame).
    pub truths: Vec<CameraModel>,
    /// The true stage error of each view, mm.
    pub true_dz_mm: Vec<f64>,
    /// The true current error of each camera in each view, mA (`None` where it took no
    /// part).
    pub true_de_ma: Vec<Vec<Option<f64>>>,
}

/// The per-camera factor s_k of camera k of n: 0 for camera 0, then alternating signs
/// within [-1, 1].
fn spread(k: usize, n: usize) -> f64 {
    if k == 0 {
        return 0.0;
    }
    let m = k as f64 / (n.max(2) - 1) as f64;
    if k % 2 == 1 {
        m
    } else {
        -m
    }
}

/// Camera k's intrinsic truth (module docs), at the pose `om`, `t`.
pub fn camera_truth(k: usize, n: usize, moving_centre: bool, (om, t): ([f64; 3], [f64; 3])) -> CameraModel {
    let paper = CameraModel::paper_rig();
    let s = spread(k, n);
    let scaled = |p: &FocalPoly| {
        let c: Vec<f64> = p.coefficients().iter().map(|c| c * (1.0 + 0.03 * s)).collect();
        FocalPoly::new(&c).unwrap_or(*p)
    };
    let a = paper.distortion_a.as_slice().iter().map(|a| a * (1.0 + 0.2 * s)).collect::<Vec<_>>();
    let distortion_a = DistortionA::paper(core::array::from_fn(|i| a.get(i).copied().unwrap_or(0.0)));
    let centre = moving_centre
        .then_some(MovingCentre { dz_mm: [-0.01 * (1.0 + 0.2 * s), 2e-5], principal_point_slope_px: [0.02, -0.03] });
    CameraModel {
        rotation_rodrigues: om,
        translation_mm: t,
        kf_x: scaled(&paper.kf_x),
        kf_y: scaled(&paper.kf_y),
        principal_point: [paper.principal_point[0] + 25.0 * s, paper.principal_point[1] - 15.0 * s],
        distortion_a,
        centre,
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Each camera's pose to the stage's world frame (om, t), camera 0's the paper rig's
/// ([`verging_poses`] about the board's centre at the middle of [`STAGE_TRAVEL_MM`]).
pub fn camera_poses(design: &MultiCameraDesign) -> Vec<([f64; 3], [f64; 3])> {
    let paper = CameraModel::paper_rig();
    let z_mid = 0.5 * (STAGE_TRAVEL_MM[0] + STAGE_TRAVEL_MM[1]);
    verging_poses(
        (paper.rotation_rodrigues, paper.translation_mm),
        [0.0, 0.0, z_mid],
        design.baseline_mm,
        design.cameras,
    )
}

/// The poses (world to camera: X_c = R X_w + t, Rodrigues and mm) of `cameras` cameras
/// around camera 0's `pose0`: camera k >= 1 stands `baseline_mm` from camera 0's centre
/// C_0 = -R_0' t_0, in camera 0's image plane at the angle phi_k = 2 pi (k - 1) / (N - 1)
/// from its x axis (C_k = C_0 + b (cos phi_k x_0 + sin phi_k y_0), x_0, y_0 the rows of
/// R_0), and verges on `target_world_mm`: its z axis z_k = (target - C_k) / |.|, its y
/// axis y_k = z_k x x_0 / |.|, x_k = y_k x z_k (its x axis as near camera 0's as that
/// allows); t_k = -R_k C_k. Camera 0's pose is the first. Precondition: the target is not
/// on camera 0's x axis line through C_k.
pub fn verging_poses(
    pose0: ([f64; 3], [f64; 3]),
    target_world_mm: [f64; 3],
    baseline_mm: f64,
    cameras: usize,
) -> Vec<([f64; 3], [f64; 3])> {
    let r0 = rodrigues_to_matrix(pose0.0);
    let t0 = pose0.1;
    // Camera 0's centre, and its x and y axes, in the world: C = -R^T t, axes the rows of R.
    let c0: [f64; 3] = core::array::from_fn(|i| -(0..3).map(|k| r0[k][i] * t0[k]).sum::<f64>());
    let mut poses = vec![pose0];
    for k in 1..cameras {
        let phi = 2.0 * std::f64::consts::PI * (k - 1) as f64 / (cameras - 1) as f64;
        let b = baseline_mm;
        let c: [f64; 3] = core::array::from_fn(|i| c0[i] + b * (phi.cos() * r0[0][i] + phi.sin() * r0[1][i]));
        let z = unit(sub(target_world_mm, c));
        let y = unit(cross(z, r0[0]));
        let x = cross(y, z);
        let r: Mat3 = [x, y, z];
        let rc = mat_vec(&r, c);
        poses.push((matrix_to_rodrigues(&r), [-rc[0], -rc[1], -rc[2]]));
    }
    poses
}

/// The visible corners of the rig's board at stage position `z_mm` for `cam` at current
/// `e_ma` (the noise-free pixel in the image), as indices into the board's corners.
fn visible(cam: &CameraModel, image_size: [u32; 2], z_mm: f64, e_ma: f64) -> Vec<usize> {
    let b = &MULTI_CAMERA_BOARD;
    let [cols, rows] = b.inner_corners;
    let (w_max, h_max) = (f64::from(image_size[0]) - 1.0, f64::from(image_size[1]) - 1.0);
    (0..cols * rows)
        .filter(|&i| {
            let w =
                [b.origin_mm[0] + b.square_mm * (i % cols) as f64, b.origin_mm[1] + b.square_mm * (i / cols) as f64];
            cam.project([w[0], w[1], z_mm], e_ma)
                .is_ok_and(|p| (0.0..=w_max).contains(&p[0]) && (0.0..=h_max).contains(&p[1]))
        })
        .collect()
}

/// The board's corner `i` in mm (row-major, X along the rows).
pub fn corner_mm(i: usize) -> [f64; 2] {
    let b = &MULTI_CAMERA_BOARD;
    let cols = b.inner_corners[0];
    [b.origin_mm[0] + b.square_mm * (i % cols) as f64, b.origin_mm[1] + b.square_mm * (i / cols) as f64]
}

/// The rig's `etlcal.board/1` board.
pub fn multi_camera_board() -> Result<Board> {
    Board::checkerboard(MULTI_CAMERA_BOARD.inner_corners, MULTI_CAMERA_BOARD.square_mm)
}

/// The current (mA) at which camera `cam` (the rig's camera k of n) focuses the board's
/// centre at stage position `z_mm`: the paper lens's focus law ([`focus_law_current_ma`])
/// at the depth d' = d0(z0) + (d - d(z0)) (d0(z1) - d0(z0)) / (d(z1) - d(z0)), d the
/// camera's depth of the board's centre, d0 camera 0's (`zero`), z0, z1 the ends of
/// [`STAGE_TRAVEL_MM`], plus 4 s_k mA (its lens's own offset, s_k the camera's factor).
pub fn focus_current_ma(cam: &CameraModel, zero: &CameraModel, (k, n): (usize, usize), z_mm: f64) -> f64 {
    let depth = |m: &CameraModel, z: f64| m.world_to_camera([0.0, 0.0, z])[2];
    let [z0, z1] = STAGE_TRAVEL_MM;
    let (a0, a1) = (depth(zero, z0), depth(zero, z1));
    let (b0, b1) = (depth(cam, z0), depth(cam, z1));
    focus_law_current_ma(a0 + (depth(cam, z_mm) - b0) * (a1 - a0) / (b1 - b0)) + 4.0 * spread(k, n)
}

/// The camera depth (mm) camera `cam` (the rig's camera k of n) is in focus at when its
/// lens runs at `e_ma`: the inverse of [`focus_current_ma`], d = d(z0) + (d' - d0(z0))
/// (d(z1) - d(z0)) / (d0(z1) - d0(z0)) with d' = [`focus_law_depth_mm`]`(e_ma - 4 s_k)`.
pub fn focus_depth_mm(cam: &CameraModel, zero: &CameraModel, (k, n): (usize, usize), e_ma: f64) -> f64 {
    let depth = |m: &CameraModel, z: f64| m.world_to_camera([0.0, 0.0, z])[2];
    let [z0, z1] = STAGE_TRAVEL_MM;
    let (a0, a1) = (depth(zero, z0), depth(zero, z1));
    let (b0, b1) = (depth(cam, z0), depth(cam, z1));
    b0 + (focus_law_depth_mm(e_ma - 4.0 * spread(k, n)) - a0) * (b1 - b0) / (a1 - a0)
}

/// The stage position of view j of `views` (evenly over [`STAGE_TRAVEL_MM`], the far end
/// first), mm.
pub fn stage_position_mm(j: usize, views: usize) -> f64 {
    position_in_travel_mm(STAGE_TRAVEL_MM, j, views)
}

/// The stage position of view j of `views` evenly over `travel_mm` [z0, z1], the far end
/// first: z1 - (z1 - z0) j / (views - 1), mm.
pub fn position_in_travel_mm(travel_mm: [f64; 2], j: usize, views: usize) -> f64 {
    let [z0, z1] = travel_mm;
    z1 - (z1 - z0) * j as f64 / (views.max(2) - 1) as f64
}

/// Camera `cam`'s record of the stage at `z` (really at `z + dz`), focused on the board's
/// centre: its entry (or `None` when it sees too little of the board or the current
/// leaves the paper rig's range) and its current error.
fn shoot(
    (k, n, cam, zero): (usize, usize, &CameraModel, &CameraModel),
    (z, dz): (f64, f64),
    (surface, t_c): (&ThermalSurface, f64),
    corner_noise: &[[f64; 2]],
    noise: &NoiseModel,
    rng: &mut ChaCha8Rng,
) -> Option<(RigShot, f64)> {
    let size = CameraModel::PAPER_IMAGE_SIZE;
    let e = focus_current_ma(cam, zero, (k, n), z);
    let (lo, hi) = (PAPER_E_COM_MA[0] - E_MARGIN_MA, PAPER_E_COM_MA[PAPER_E_COM_MA.len() - 1] + E_MARGIN_MA);
    if !(lo..=hi).contains(&e) {
        return None;
    }
    let de = gauss(noise.e_ma, rng);
    let seen = visible(cam, size, z, e);
    let mut points = vec![];
    for i in seen {
        let (w, n) = (corner_mm(i), corner_noise[i]);
        if let Ok(p) = cam.project([w[0] + n[0], w[1] + n[1], z + dz], e + de) {
            points.push([p[0] + gauss(noise.px, rng), p[1] + gauss(noise.px, rng), w[0], w[1]]);
        }
    }
    if points.len() < MIN_POINTS {
        return None;
    }
    let e_in = surface.e_in_for_e_com(e, t_c).unwrap_or(e);
    let shot = RigShot {
        camera: k,
        image: None,
        points: Some(points),
        e_in_ma: e_in,
        focal_power_dpt: None,
        temperature_c: t_c,
        e_com_ma: Some(e),
    };
    Some((shot, de))
}

/// Simulates the rig of `design` under `noise` (its `z_mm`, `e_ma`, `px`, `xy_mm`; A0
/// comes from the lens-off views), seeded. Errors: a design outside its ranges, a noise
/// model outside its own.
pub fn simulate_multi_camera(
    design: &MultiCameraDesign,
    noise: &NoiseModel,
    seed: u64,
) -> Result<MultiCameraSimulation> {
    design.validate()?;
    noise.validate(|k| format!("noise.{k}"))?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = design.cameras;
    let truths: Vec<CameraModel> = camera_poses(design)
        .into_iter()
        .enumerate()
        .map(|(k, pose)| camera_truth(k, n, design.moving_centre, pose))
        .collect();
    let size = CameraModel::PAPER_IMAGE_SIZE;
    let cameras = (0..n).map(|k| RigDatasetCamera { name: format!("cam{k}"), image_size: size, board: None }).collect();
    let mut dataset = RigDataset::new(multi_camera_board()?, cameras);
    let (mut true_dz_mm, mut true_de_ma) = (vec![], vec![vec![None; design.views]; n]);
    let corners = MULTI_CAMERA_BOARD.inner_corners[0] * MULTI_CAMERA_BOARD.inner_corners[1];
    let surfaces: Vec<ThermalSurface> =
        (0..n).map(|k| design.lens_thermal.map_or(ThermalSurface::PAPER, |t| lens_thermal_surface(k, n, &t))).collect();
    for j in 0..design.views {
        let z = stage_position_mm(j, design.views);
        let t_c = design.lens_thermal.map_or(PAPER_TEMPERATURE_C, |t| {
            let [t0, t1] = t.temperatures_c;
            t0 + (t1 - t0) * j as f64 / (design.views - 1) as f64
        });
        let dz = gauss(noise.z_mm, &mut rng);
        let corner_noise: Vec<[f64; 2]> =
            (0..corners).map(|_| [gauss(noise.xy_mm, &mut rng), gauss(noise.xy_mm, &mut rng)]).collect();
        let mut view = RigView { z_w_mm: z, cameras: vec![] };
        for (k, cam) in truths.iter().enumerate() {
            let lens = (&surfaces[k], t_c);
            if let Some((shot, de)) = shoot((k, n, cam, &truths[0]), (z, dz), lens, &corner_noise, noise, &mut rng) {
                view.cameras.push(shot);
                true_de_ma[k][j] = Some(de);
            }
        }
        true_dz_mm.push(dz);
        dataset.views.push(view);
    }
    for k in 0..n {
        let views = lens_off_views_of(&truths[k], &LensOff::PAPER, size, noise, &mut rng);
        for (i, v) in views.iter().enumerate() {
            if dataset.offstate_views.len() <= i {
                dataset.offstate_views.push(RigOffstateView { cameras: vec![] });
            }
            let shot = RigOffstateShot { camera: k, image: None, points: Some(points_of(&v.points)) };
            dataset.offstate_views[i].cameras.push(shot);
        }
    }
    dataset.views.retain(|v| !v.cameras.is_empty());
    Ok(MultiCameraSimulation { dataset, truths, true_dz_mm, true_de_ma })
}

/// The truth as an `etlcal.rig/1`: each camera's true model as an exact calibration
/// (inline) over the currents of its views, and the true extrinsics at E = 0
/// (`reference_setting` [0, 0]), without covariance.
pub fn truth_rig(sim: &MultiCameraSimulation) -> RigFile {
    let cameras = sim
        .truths
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let e =
                sim.dataset.views.iter().flat_map(|v| &v.cameras).filter(|s| s.camera == k).filter_map(|s| s.e_com_ma);
            let (lo, hi) = e.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| (lo.min(e), hi.max(e)));
            let c = &sim.dataset.cameras[k];
            let calibration = Calibration::from_model(m, c.image_size, [lo, hi]);
            RigCamera {
                name: c.name.clone(),
                image_size: c.image_size,
                calibration: Some(Box::new(calibration)),
                calibration_path: None,
            }
        })
        .collect();
    let pose = |m: &CameraModel| (m.rotation_rodrigues, m.translation_mm);
    let extrinsics = (1..sim.truths.len())
        .map(|k| {
            let (om, t) = relative_pose(pose(&sim.truths[0]), pose(&sim.truths[k]));
            RigExtrinsics {
                camera: k,
                rotation_rodrigues: om,
                translation_mm: t,
                covariance: None,
                reference_setting: Some([0.0, 0.0]),
            }
        })
        .collect();
    RigFile::new(cameras, extrinsics)
}
