//! A ray-traced N-camera ETL rig on one linear stage: every camera a physical ETL camera
//! ([`OpticalRig`]), every corner the centroid of its traced spot, recorded as an
//! `etlcal.rig-dataset/1` of points ([`etl_formats::rig_dataset`]) for
//! `etl_calib::rig_calibration::calibrate_rig`.
//!
//! **Geometry.** The world frame is the stage's, as in [`crate::optics::rig`]: the board
//! (camera 0's procedure board, first inner corner at the origin) at stage position Z lies
//! in the plane Z_W = Z. Camera 0 stands where its optics file puts it
//! ([`OpticalRig::stage_pose`]). Camera k >= 1 (its own optics file, or the same) stands
//! `baseline_mm` from camera 0's origin and verges on the board's centre at the middle of
//! camera 0's travel in focus, as [`crate::multi_camera`] places its cameras
//! ([`crate::multi_camera::verging_poses`]); a camera's pose maps the world to its tracer's
//! camera frame (OpenCV axes, origin at the centre of the ETL's rim plane, in front of the
//! entrance pupil).
//!
//! **Focus.** At stage position Z each camera runs at the current that puts its distance
//! in focus at the camera depth d_k(Z) of the board's centre ([`focus::FocusTable`]:
//! the traced distance in focus on a grid, inverted by interpolation within
//! [`focus::FOCUS_TOLERANCE_MM`]). d_k(Z) is affine in Z, so each camera focuses over an
//! interval of the stage; the rig's travel is the interval where every camera can focus
//! within its procedure's currents ([`TracedMultiCamera::stage_travel_mm`]).
//!
//! **Views.** `views` stage positions evenly over the travel (the far end first); at each,
//! every camera's noise-free traced centroids of the corners it sees ([`board_view_as`]:
//! the centroid inside its image; the chief rays' hits instead with [`CornerAs::Chief`],
//! to compare), recorded with its E_com, the E_in the traced procedure
//! commands for it ([`commanded_e_in_ma`]) and its procedure's temperature; a camera that
//! sees fewer than [`MIN_POINTS`] corners takes no part in a view. Each camera's lens-off
//! views are its procedure's ([`lens_off_views`]). The pixel noise comes after the trace,
//! seeded on its own ([`TracedMultiCamera::with_pixel_noise`]): one trace serves every
//! noise seed. The stage and the currents are exact (no stage or current error).
//!
//! **Truth** ([`TracedMultiCamera::truths`]): each camera's pose and, per current of its
//! procedure, [`crate::optics::truth`]'s focal length, entrance pupil and distance in
//! focus, with the rig's stage position at which that camera is in focus there.

pub mod focus;

use etl_core::model::rotation::{mat_t_vec, mat_vec, rodrigues_to_matrix};
use etl_formats::observations::PointObs;
use etl_formats::optics::BoardSpec;
use etl_formats::rig_dataset::{
    points_of, RigDataset, RigDatasetCamera, RigFreeView, RigOffstateShot, RigOffstateView, RigShot, RigView,
};
use etl_formats::{Error, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use self::focus::FocusTable;
use super::procedure::{board_view_as, commanded_e_in_ma, lens_off_views, CornerAs, Pose};
use super::ray::V3;
use super::rig::{board_centre_mm, Setting};
use super::truth::{setting_truths, SettingTruth};
use super::OpticalRig;
use crate::multi_camera::{position_in_travel_mm, verging_poses, MAX_CAMERAS, MIN_POINTS};
use crate::simulate::gauss;

/// The format key of the traced rig's truth file (`etlcal simulate --rig N --optics`).
pub const RIG_TRUTH_FORMAT: &str = "etlcal.optics-rig-truth/1";

/// The shortest travel the cameras must share in focus, mm (a 2 mm move and room about it).
pub const MIN_TRAVEL_MM: f64 = 4.0;
/// The range of `baseline_mm`, mm.
pub const BASELINE_RANGE_MM: [f64; 2] = [5.0, 150.0];

/// How the traced rig is built (module docs); the cameras' optics are given beside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TracedRigDesign {
    /// Stage views, 3..=1000.
    pub views: usize,
    /// Distance of cameras 1.. from camera 0's origin, mm ([`BASELINE_RANGE_MM`]).
    pub baseline_mm: f64,
    /// The focus table's grid step, mA (0 < step <= 5: the step
    /// [`focus::FOCUS_TOLERANCE_MM`] holds for).
    pub focus_step_ma: f64,
    /// Which point of a traced spot stands for a corner (stage and lens-off views):
    /// the centroid (what a detector sees) or, to compare, the chief ray's hit.
    pub corner: CornerAs,
    /// Free views (the board tilted, no stage: `etlcal.rig-dataset/1`'s `free_views`),
    /// 0..=100 ([`free_pose`]).
    pub free_views: usize,
}

impl TracedRigDesign {
    /// 15 views (the paper's), a 30 mm baseline, the focus table every 5 mA, centroids, no
    /// free views.
    pub const fn new() -> Self {
        TracedRigDesign { views: 15, baseline_mm: 30.0, focus_step_ma: 5.0, corner: CornerAs::Centroid, free_views: 0 }
    }

    /// Refuses a design outside its ranges, or `cameras` optics outside 2..=[`MAX_CAMERAS`],
    /// naming the field.
    pub fn validate(&self, cameras: usize) -> Result<()> {
        if !(2..=MAX_CAMERAS).contains(&cameras) {
            let message = format!("cameras: {cameras} optics given, outside 2..={MAX_CAMERAS}");
            return Err(Error::invalid_value("cameras", cameras as f64, message));
        }
        if !(3..=1000).contains(&self.views) {
            let message = format!("views: {} is outside 3..=1000", self.views);
            return Err(Error::invalid_value("views", self.views as f64, message));
        }
        etl_formats::check_range("baseline_mm", self.baseline_mm, BASELINE_RANGE_MM, "mm")?;
        etl_formats::check_range("focus_step_ma", self.focus_step_ma, [1e-3, 5.0], "mA")?;
        if self.free_views > 100 {
            let message = format!("free_views: {} is outside 0..=100", self.free_views);
            return Err(Error::invalid_value("free_views", self.free_views as f64, message));
        }
        Ok(())
    }
}

impl Default for TracedRigDesign {
    fn default() -> Self {
        Self::new()
    }
}

/// One traced camera of the rig.
#[derive(Debug, Clone, PartialEq)]
pub struct TracedCamera {
    /// Its optics.
    pub optics: OpticalRig,
    /// Its pose, world to its tracer's camera frame: (Rodrigues, translation mm).
    pub pose: Pose,
    /// Its distance in focus per current.
    pub focus: FocusTable,
}

impl TracedCamera {
    /// A world point in this camera's frame: R X + t.
    pub fn world_to_camera(&self, world_mm: V3) -> V3 {
        let p = mat_vec(&rodrigues_to_matrix(self.pose.0), world_mm);
        [p[0] + self.pose.1[0], p[1] + self.pose.1[1], p[2] + self.pose.1[2]]
    }

    /// A camera-frame point in the world: R' (X_c - t).
    pub fn camera_to_world(&self, camera_mm: V3) -> V3 {
        let t = self.pose.1;
        mat_t_vec(&rodrigues_to_matrix(self.pose.0), [camera_mm[0] - t[0], camera_mm[1] - t[1], camera_mm[2] - t[2]])
    }

    /// The camera depth (z, mm) of `board`'s centre at stage position `z_mm`.
    pub fn board_centre_depth_mm(&self, board: &BoardSpec, z_mm: f64) -> f64 {
        let c = board_centre_mm(board);
        self.world_to_camera([c[0], c[1], z_mm])[2]
    }

    /// The current (mA) that focuses this camera on `board`'s centre at stage position
    /// `z_mm` (module docs); None where its procedure's currents cannot.
    pub fn focus_current_ma(&self, board: &BoardSpec, z_mm: f64) -> Option<f64> {
        self.focus.current_ma(self.board_centre_depth_mm(board, z_mm))
    }

    /// The stage positions [lo, hi] at which this camera can focus on `board`'s centre.
    /// Precondition: the stage moves the board along the camera's depth (R_22 != 0).
    pub fn travel_mm(&self, board: &BoardSpec) -> [f64; 2] {
        let (d0, slope) = (self.board_centre_depth_mm(board, 0.0), rodrigues_to_matrix(self.pose.0)[2][2]);
        let [near, far] = self.focus.range_mm();
        let (a, b) = ((near - d0) / slope, (far - d0) / slope);
        [a.min(b), a.max(b)]
    }

    /// The corners of `board` at stage position `z_mm` this camera sees at `setting`
    /// (world points, noise-free traced pixels as `corner` says: [`board_view_as`]).
    pub fn stage_view(&self, setting: &Setting, board: &BoardSpec, z_mm: f64, corner: CornerAs) -> Vec<PointObs> {
        board_view_as(&self.optics, setting, board, &self.pose, z_mm, corner)
    }

    /// The traced pixel of world point `world_mm` at `setting` as `corner` says, None
    /// where the trace fails or its centroid falls outside the image (as [`board_view_as`]
    /// decides which corners are seen).
    pub fn pixel(&self, setting: &Setting, world_mm: V3, corner: CornerAs) -> Option<[f64; 2]> {
        let spot = setting.spot(self.world_to_camera(world_mm)).ok()?;
        let px = setting.to_pixel(spot.centroid_mm);
        let [w, h] = self.optics.file.sensor.size_px.map(|n| n as f64 - 1.0);
        let inside = (0.0..=w).contains(&px[0]) && (0.0..=h).contains(&px[1]);
        inside.then(|| match corner {
            CornerAs::Centroid => px,
            CornerAs::Chief => setting.to_pixel(spot.chief_mm),
        })
    }

    /// The entrance pupil's centre at `e_ma` in the world, mm: the centred system's
    /// paraxial pupil on the axis (camera z = -pupil z of the tracer's lens frame).
    pub fn entrance_pupil_world_mm(&self, e_ma: f64) -> Result<V3> {
        Ok(self.camera_to_world([0.0, 0.0, -self.optics.at(e_ma)?.pupil.z_mm]))
    }
}

/// One camera's truth (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct TracedCameraTruth {
    /// Its pose, world to camera frame.
    pub pose: Pose,
    /// Per current of its procedure ([`setting_truths`]); `stage_z_mm` the rig's stage
    /// position at which this camera is in focus on the board's centre at that current
    /// (outside the rig's travel where other cameras cannot follow).
    pub settings: Vec<SettingTruth>,
}

/// The traced rig and its noise-free record.
#[derive(Debug, Clone, PartialEq)]
pub struct TracedMultiCamera {
    /// The cameras, camera 0 first.
    pub cameras: Vec<TracedCamera>,
    /// The stage board (camera 0's procedure board).
    pub board: BoardSpec,
    /// The stage positions at which every camera can focus, [lo, hi], mm.
    pub stage_travel_mm: [f64; 2],
    /// The noise-free record (points are traced centroids, or chief rays' hits as the
    /// design said).
    pub dataset: RigDataset,
    /// Which point of a spot the record's corners are.
    pub corner: CornerAs,
}

/// Places the cameras of `optics` (module docs): camera 0 at its file's stage pose, the
/// others verging on the board's centre at the middle of camera 0's travel in focus.
fn place(optics: &[OpticalRig], design: &TracedRigDesign) -> Result<Vec<TracedCamera>> {
    let board = &optics[0].file.procedure.board;
    let tables =
        optics.iter().map(|o| FocusTable::new(o, design.focus_step_ma)).collect::<Result<Vec<FocusTable>>>()?;
    let pose0 = optics[0].stage_pose();
    let first = TracedCamera { optics: optics[0].clone(), pose: pose0, focus: tables[0].clone() };
    let [lo, hi] = first.travel_mm(board);
    let c = board_centre_mm(board);
    let target = [c[0], c[1], 0.5 * (lo + hi)];
    Ok(verging_poses(pose0, target, design.baseline_mm, optics.len())
        .into_iter()
        .zip(optics.iter().zip(tables))
        .map(|(pose, (o, focus))| TracedCamera { optics: o.clone(), pose, focus })
        .collect())
}

/// The interval every camera can focus over, refused (naming `baseline_mm`) when shorter
/// than [`MIN_TRAVEL_MM`].
fn shared_travel(cameras: &[TracedCamera], board: &BoardSpec, baseline_mm: f64) -> Result<[f64; 2]> {
    let [lo, hi] = cameras
        .iter()
        .map(|c| c.travel_mm(board))
        .fold([f64::NEG_INFINITY, f64::INFINITY], |a, t| [a[0].max(t[0]), a[1].min(t[1])]);
    if !(hi - lo >= MIN_TRAVEL_MM) {
        return Err(Error::invalid_value(
            "baseline_mm",
            baseline_mm,
            format!(
                "baseline_mm: at {baseline_mm} mm the cameras share {:.2} mm of stage travel in focus, less than {MIN_TRAVEL_MM} mm",
                (hi - lo).max(0.0)
            ),
        ));
    }
    Ok([lo, hi])
}

/// Traces the rig of `optics` (camera 0 first; at least 2) built by `design` (module
/// docs). Errors: a design outside its ranges or too few optics (named); lens-off boards
/// that differ between the cameras (`optics[k].procedure.lens_off_board`: the dataset has
/// one); cameras that share less than [`MIN_TRAVEL_MM`] of travel in focus
/// (`baseline_mm`); a failed focus search or trace.
pub fn trace_multi_camera(optics: &[OpticalRig], design: &TracedRigDesign) -> Result<TracedMultiCamera> {
    design.validate(optics.len())?;
    let off_board = &optics[0].file.procedure.lens_off_board;
    if let Some(k) = optics.iter().position(|o| o.file.procedure.lens_off_board != *off_board) {
        let what = format!("optics[{k}].procedure.lens_off_board");
        return Err(Error::invalid(what.clone(), format!("{what}: differs from camera 0's (the rig dataset has one)")));
    }
    let board = optics[0].file.procedure.board;
    let cameras = place(optics, design)?;
    let travel = shared_travel(&cameras, &board, design.baseline_mm)?;
    let names = cameras.iter().enumerate().map(|(k, c)| RigDatasetCamera {
        name: format!("cam{k}"),
        image_size: c.optics.file.sensor.size_px,
        board: None,
    });
    let mut dataset = RigDataset::new(
        etl_formats::board::Board::checkerboard(board.inner_corners, board.square_mm)?,
        names.collect(),
    );
    dataset.offstate_board =
        Some(etl_formats::board::Board::checkerboard(off_board.inner_corners, off_board.square_mm)?);
    for j in 0..design.views {
        let z = position_in_travel_mm(travel, j, design.views);
        let mut view = RigView { z_w_mm: z, cameras: vec![] };
        for (k, cam) in cameras.iter().enumerate() {
            if let Some(shot) = shoot(k, cam, (&board, z), design.corner)? {
                view.cameras.push(shot);
            }
        }
        if !view.cameras.is_empty() {
            dataset.views.push(view);
        }
    }
    for (k, cam) in cameras.iter().enumerate() {
        for (i, points) in lens_off_views(&cam.optics, design.corner)?.iter().enumerate() {
            if dataset.offstate_views.len() <= i {
                dataset.offstate_views.push(RigOffstateView { cameras: vec![] });
            }
            let shot = RigOffstateShot { camera: k, image: None, points: Some(points_of(points)) };
            dataset.offstate_views[i].cameras.push(shot);
        }
    }
    for f in 0..design.free_views {
        let (pose, z) = free_pose(&board, travel, f, design.free_views);
        let mut view = RigFreeView { cameras: vec![] };
        for (k, cam) in cameras.iter().enumerate() {
            if let Some(shot) = shoot_free(k, cam, (&board, z), &pose, design.corner)? {
                view.cameras.push(shot);
            }
        }
        if !view.cameras.is_empty() {
            dataset.free_views.push(view);
        }
    }
    dataset.validate()?;
    Ok(TracedMultiCamera { cameras, board, stage_travel_mm: travel, dataset, corner: design.corner })
}

/// Free view `f` of `n`: the board turned about its centre by 10 to 25 degrees (about axes
/// spread around the stage axis, alternately 10 and 25), its centre where the stage would
/// put it at a position spread over `travel`; the pose board to world, and that position.
pub fn free_pose(board: &BoardSpec, travel: [f64; 2], f: usize, n: usize) -> (Pose, f64) {
    let z = position_in_travel_mm(travel, f, n.max(2));
    let phi = 2.0 * std::f64::consts::PI * f as f64 / n.max(1) as f64;
    let tilt = if f % 2 == 0 { 10f64 } else { 25.0 }.to_radians();
    let om = [tilt * phi.cos(), tilt * phi.sin(), 0.05];
    let c = board_centre_mm(board);
    let rc = mat_vec(&rodrigues_to_matrix(om), c);
    ((om, [c[0] - rc[0], c[1] - rc[1], z + c[2] - rc[2]]), z)
}

/// Camera `k`'s record of the board in free pose `pose` (board to world), focused on its
/// centre (the stage board's at `z_mm`); None when it cannot focus there or sees fewer
/// than [`MIN_POINTS`] corners.
fn shoot_free(
    k: usize,
    cam: &TracedCamera,
    (board, z_mm): (&BoardSpec, f64),
    pose: &Pose,
    corner: CornerAs,
) -> Result<Option<RigShot>> {
    let Some(e) = cam.focus_current_ma(board, z_mm) else {
        return Ok(None);
    };
    let setting = cam.optics.at(e)?;
    let r = rodrigues_to_matrix(pose.0);
    let [cols, rows] = board.inner_corners;
    let mut points = vec![];
    for (i, j) in (0..rows).flat_map(|j| (0..cols).map(move |i| (i, j))) {
        let b = [i as f64 * board.square_mm, j as f64 * board.square_mm, 0.0];
        let w = mat_vec(&r, b);
        if let Some(px) = cam.pixel(&setting, [w[0] + pose.1[0], w[1] + pose.1[1], w[2] + pose.1[2]], corner) {
            points.push([px[0], px[1], b[0], b[1]]);
        }
    }
    Ok(shot_of(k, cam, e, points))
}

/// Camera `k`'s entry at current `e_ma` with `points` (`[u, v, X, Y]` rows): E_com, the
/// commanded E_in and the procedure's temperature, as the traced procedure records them;
/// None with fewer than [`MIN_POINTS`] points.
fn shot_of(k: usize, cam: &TracedCamera, e_ma: f64, points: Vec<[f64; 4]>) -> Option<RigShot> {
    if points.len() < MIN_POINTS {
        return None;
    }
    let t = cam.optics.file.procedure.temperature_c;
    Some(RigShot {
        camera: k,
        image: None,
        points: Some(points),
        e_in_ma: commanded_e_in_ma(e_ma, t),
        focal_power_dpt: None,
        temperature_c: t,
        e_com_ma: Some(e_ma),
    })
}

/// Camera `k`'s record of the board at stage position `z_mm`, in focus; None when it
/// cannot focus there or sees fewer than [`MIN_POINTS`] corners.
fn shoot(k: usize, cam: &TracedCamera, (board, z_mm): (&BoardSpec, f64), corner: CornerAs) -> Result<Option<RigShot>> {
    let Some(e) = cam.focus_current_ma(board, z_mm) else {
        return Ok(None);
    };
    let points = cam.stage_view(&cam.optics.at(e)?, board, z_mm, corner);
    Ok(shot_of(k, cam, e, points_of(&points)))
}

/// `dataset` with Gaussian noise of `sigma_px` on every pixel (stage views camera by
/// camera, then lens-off views, then free views), seeded: the traced pixels do not depend on the seed.
pub fn rig_with_pixel_noise(dataset: &RigDataset, sigma_px: f64, seed: u64) -> RigDataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = dataset.clone();
    let stage = out.views.iter_mut().flat_map(|v| v.cameras.iter_mut().map(|s| &mut s.points));
    let off = out.offstate_views.iter_mut().flat_map(|v| v.cameras.iter_mut().map(|s| &mut s.points));
    let free = out.free_views.iter_mut().flat_map(|v| v.cameras.iter_mut().map(|s| &mut s.points));
    for points in stage.chain(off).chain(free).flatten() {
        for p in points.iter_mut() {
            p[0] += gauss(sigma_px, &mut rng);
            p[1] += gauss(sigma_px, &mut rng);
        }
    }
    out
}

impl TracedMultiCamera {
    /// The record with the seed's pixel noise ([`rig_with_pixel_noise`]).
    pub fn with_pixel_noise(&self, sigma_px: f64, seed: u64) -> RigDataset {
        rig_with_pixel_noise(&self.dataset, sigma_px, seed)
    }

    /// Each camera's focus current (mA) at stage position `z_mm`. Errors: a position
    /// where some camera cannot focus (`z_mm`).
    pub fn focus_currents_ma(&self, z_mm: f64) -> Result<Vec<f64>> {
        self.cameras
            .iter()
            .enumerate()
            .map(|(k, c)| {
                c.focus_current_ma(&self.board, z_mm).ok_or_else(|| {
                    Error::invalid_value("z_mm", z_mm, format!("z_mm: camera {k} cannot focus at {z_mm} mm"))
                })
            })
            .collect()
    }

    /// The truth (module docs). Errors: a failed focus search or trace.
    pub fn truths(&self) -> Result<Vec<TracedCameraTruth>> {
        self.cameras
            .iter()
            .map(|c| {
                let slope = rodrigues_to_matrix(c.pose.0)[2][2];
                let d0 = c.board_centre_depth_mm(&self.board, 0.0);
                let settings = setting_truths(&c.optics)?
                    .into_iter()
                    .map(|s| SettingTruth { stage_z_mm: (s.focus_distance_mm - d0) / slope, ..s })
                    .collect();
                Ok(TracedCameraTruth { pose: c.pose, settings })
            })
            .collect()
    }
}
