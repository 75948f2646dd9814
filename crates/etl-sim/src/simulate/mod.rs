//! The paper rig (docs/METHOD.md, "The paper rig"; section 5.1.2) as synthetic observations with
//! the paper's noise model.
//!
//! Per view j the stage really stands at Z_W,j + dZ_j and the lens runs at E_j + dE_j while
//! Z_W,j and E_j are recorded; each corner really sits 1 um off its nominal X, Y; the
//! observed pixel carries 0.2 px of noise; and the A0 that a lens-off calibration would
//! give is off by 0.3 % (kf0) and 1 px (u0, v0). Corners whose noise-free pixel leaves the
//! 1936 x 1458 image are dropped (2311 of 2520 remain).

pub mod focal_power;
pub mod images;
mod strong;

use etl_core::calib::{Point, A0};
use etl_core::model::CameraModel;
use etl_core::thermal::ThermalSurface;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use etl_formats::a0::A0File;
use etl_formats::observations::{Observations, OffstateView, PointObs, ViewObs};
use etl_formats::{write_json, Error, Result};
use serde_json::json;

mod config;
pub use crate::rig::{focus_depth_mm, focused_z_mm, PAPER_BOARD, PAPER_E_COM_MA, PAPER_TEMPERATURE_C, PAPER_Z_W_MM};
pub use config::{SimConfig, SimRig, CONFIG_FORMAT};
pub use strong::{strong_rig, STRONG_E_COM_MA, STRONG_LENS_OFF, STRONG_RIG_BOARD, STRONG_Z_W_MM};

/// Standard deviations of the noise model (docs/METHOD.md).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseModel {
    /// Corner X_W, Y_W, mm.
    pub xy_mm: f64,
    /// Stage position Z_W per view, mm.
    pub z_mm: f64,
    /// Current per view, mA.
    pub e_ma: f64,
    /// Observed pixels, px.
    pub px: f64,
    /// Relative error of kf0x, kf0y from A0.
    pub kf0_rel: f64,
    /// Error of u0, v0 from A0, px.
    pub pp_px: f64,
}

impl NoiseModel {
    /// The paper's noise model.
    pub const PAPER: NoiseModel =
        NoiseModel { xy_mm: 0.001, z_mm: 0.010, e_ma: 0.4, px: 0.2, kf0_rel: 0.003, pp_px: 1.0 };
    /// No noise at all.
    pub const NONE: NoiseModel = NoiseModel { xy_mm: 0.0, z_mm: 0.0, e_ma: 0.0, px: 0.0, kf0_rel: 0.0, pp_px: 0.0 };

    /// Checks every standard deviation against its documented range: at least 0 and at
    /// most xy_mm 10 mm, z_mm 10 mm, e_ma 50 mA, px 100 px, kf0_rel 1, pp_px 1000 px (far
    /// above any real rig's noise, far below what makes the synthetic corners leave the
    /// image or overflow; NaN is in none). `name` spells a key for the message (the
    /// simulation file's `noise.px`, Python's `noise["px"]`).
    ///
    /// ```
    /// use etl_sim::simulate::NoiseModel;
    /// let huge = NoiseModel { px: 1e308, ..NoiseModel::PAPER };
    /// let err = huge.validate(|k| format!("noise.{k}")).unwrap_err();
    /// assert_eq!(err.to_string(), "invalid input: noise.px 1e308 px is outside [0, 100] px");
    /// assert!(NoiseModel::PAPER.validate(|k| k.to_owned()).is_ok());
    /// ```
    pub fn validate(&self, name: impl Fn(&'static str) -> String) -> Result<()> {
        for (key, value, hi, unit) in [
            ("xy_mm", self.xy_mm, 10.0, "mm"),
            ("z_mm", self.z_mm, 10.0, "mm"),
            ("e_ma", self.e_ma, 50.0, "mA"),
            ("px", self.px, 100.0, "px"),
            ("kf0_rel", self.kf0_rel, 1.0, ""),
            ("pp_px", self.pp_px, 1000.0, "px"),
        ] {
            etl_formats::check_range(&name(key), value, [0.0, hi], unit)?;
        }
        Ok(())
    }
}

/// A simulated data set and the truth behind it.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The observations as a user would record them.
    pub observations: Observations,
    /// The A0 a lens-off calibration would give (with its error).
    pub a0: A0,
    /// The true camera.
    pub truth: CameraModel,
    /// The true stage error of each view, mm.
    pub true_dz_mm: Vec<f64>,
    /// The true current error of each view, mA.
    pub true_de_ma: Vec<f64>,
}

/// A Gaussian draw of standard deviation `s` (0 when `s` is 0 or not a valid sigma).
pub fn gauss(s: f64, rng: &mut ChaCha8Rng) -> f64 {
    match Normal::new(0.0, s) {
        Ok(n) if s > 0.0 => n.sample(rng),
        _ => 0.0,
    }
}

/// The visible corners of the paper board at stage position `z_mm` and current `e_ma`
/// (board frame: X, Y in mm, Z = 0) with their noise-free pixels.
pub fn visible_board(cam: &CameraModel, z_mm: f64, e_ma: f64) -> Vec<([f64; 2], [f64; 2])> {
    visible_stage_board(cam, &PAPER_RIG_BOARD, CameraModel::PAPER_IMAGE_SIZE, z_mm, e_ma)
}

/// A rig's stage board: inner corners (columns, rows), square, and the world (X, Y) of
/// corner (0, 0), mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageBoard {
    /// Inner corners, columns x rows.
    pub inner_corners: [usize; 2],
    /// Side of a square, mm.
    pub square_mm: f64,
    /// World (X, Y) of inner corner (0, 0), mm.
    pub origin_mm: [f64; 2],
}

/// The paper rig's board ([`PAPER_BOARD`]) at the world origin.
pub const PAPER_RIG_BOARD: StageBoard =
    StageBoard { inner_corners: PAPER_BOARD.0, square_mm: PAPER_BOARD.1, origin_mm: [0.0, 0.0] };

/// The corners of `board` at stage position `z_mm` whose noise-free pixel at current
/// `e_ma` lies inside an image of `image_size`, with that pixel.
pub fn visible_stage_board(
    cam: &CameraModel,
    board: &StageBoard,
    image_size: [u32; 2],
    z_mm: f64,
    e_ma: f64,
) -> Vec<([f64; 2], [f64; 2])> {
    let [cols, rows] = board.inner_corners;
    let (sq, [x0, y0]) = (board.square_mm, board.origin_mm);
    let (w_max, h_max) = (image_size[0] as f64 - 1.0, image_size[1] as f64 - 1.0);
    let mut out = vec![];
    for j in 0..rows {
        for i in 0..cols {
            let w = [x0 + sq * i as f64, y0 + sq * j as f64];
            if let Ok(p) = cam.project([w[0], w[1], z_mm], e_ma) {
                if (0.0..=w_max).contains(&p[0]) && (0.0..=h_max).contains(&p[1]) {
                    out.push((w, p));
                }
            }
        }
    }
    out
}

/// Observed pixels of the visible board corners at the true stage position `z_mm` and
/// true current `e_ma`, with corner and pixel noise. Returns (board X, Y; pixel).
pub fn observe_board(
    cam: &CameraModel,
    z_mm: f64,
    e_ma: f64,
    noise: &NoiseModel,
    rng: &mut ChaCha8Rng,
) -> Vec<([f64; 2], [f64; 2])> {
    visible_board(cam, z_mm, e_ma)
        .into_iter()
        .filter_map(|(w, _)| {
            let truth = [w[0] + gauss(noise.xy_mm, rng), w[1] + gauss(noise.xy_mm, rng), z_mm];
            let p = cam.project(truth, e_ma).ok()?;
            Some((w, [p[0] + gauss(noise.px, rng), p[1] + gauss(noise.px, rng)]))
        })
        .collect()
}

/// Tilts (about X, about Y, degrees) of the 10 lens-off views: up to about 25 degrees.
const LENS_OFF_TILTS_DEG: [(f64, f64); 10] = [
    (0.0, 0.0),
    (20.0, 0.0),
    (-20.0, 0.0),
    (0.0, 20.0),
    (0.0, -20.0),
    (15.0, 15.0),
    (-15.0, 15.0),
    (15.0, -15.0),
    (-15.0, -15.0),
    (25.0, 5.0),
];

/// The lens-off views of docs/METHOD.md (this project's choice; the paper gives none): 10 views
/// at E = 0 of a planar board of 11 x 8 inner corners with 4 mm squares, about 125 mm from the
/// camera, tilted up to about 25 degrees, with corner and pixel noise. Points are in the
/// board frame (Z = 0).
pub fn lens_off_views(truth: &CameraModel, noise: &NoiseModel, rng: &mut ChaCha8Rng) -> Vec<OffstateView> {
    lens_off_views_of(truth, &LensOff::PAPER, CameraModel::PAPER_IMAGE_SIZE, noise, rng)
}

/// How a rig's lens-off views are taken: the board (inner corners, square, mm) and the
/// distance of its centre from the camera, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensOff {
    /// Inner corners (columns, rows) and square, mm.
    pub board: ([usize; 2], f64),
    /// Distance of the board's centre, mm (the views spread a few percent about it).
    pub distance_mm: f64,
}

impl LensOff {
    /// The paper rig's ([`LENS_OFF_BOARD`] at 125 mm).
    pub const PAPER: LensOff = LensOff { board: LENS_OFF_BOARD, distance_mm: 125.0 };
}

/// The 10 lens-off views of `design` at E = 0 (the tilts of [`lens_off_poses`]), with
/// corner and pixel noise; only corners inside an image of `image_size`.
pub fn lens_off_views_of(
    truth: &CameraModel,
    design: &LensOff,
    image_size: [u32; 2],
    noise: &NoiseModel,
    rng: &mut ChaCha8Rng,
) -> Vec<OffstateView> {
    let ([cols, rows], sq) = design.board;
    let (w_max, h_max) = (image_size[0] as f64 - 1.0, image_size[1] as f64 - 1.0);
    let mut views = vec![];
    for cam in lens_off_poses_of(truth, design) {
        let mut points = vec![];
        for j in 0..rows {
            for i in 0..cols {
                let w = [sq * i as f64, sq * j as f64];
                let real = [w[0] + gauss(noise.xy_mm, rng), w[1] + gauss(noise.xy_mm, rng), 0.0];
                if let Ok(p) = cam.project(real, 0.0) {
                    if (0.0..=w_max).contains(&p[0]) && (0.0..=h_max).contains(&p[1]) {
                        let pixel = [p[0] + gauss(noise.px, rng), p[1] + gauss(noise.px, rng)];
                        points.push(PointObs { world_mm: [w[0], w[1], 0.0], pixel });
                    }
                }
            }
        }
        views.push(OffstateView { points });
    }
    views
}

/// The lens-off board: inner corners (columns, rows) and square size, mm (docs/METHOD.md).
pub const LENS_OFF_BOARD: ([usize; 2], f64) = ([11, 8], 4.0);

/// The camera of each lens-off view with the board frame as its world frame (board at
/// Z = 0): the truth's intrinsics and distortion, the view's pose.
pub fn lens_off_poses(truth: &CameraModel) -> Vec<CameraModel> {
    lens_off_poses_of(truth, &LensOff::PAPER)
}

/// The camera of each lens-off view of `design` (the paper's: [`lens_off_poses`]): the
/// tilts of `LENS_OFF_TILTS_DEG`, the board's centre about `distance_mm` away, the
/// sideways spread scaled with the distance.
pub fn lens_off_poses_of(truth: &CameraModel, design: &LensOff) -> Vec<CameraModel> {
    let ([cols, rows], sq) = design.board;
    let centre_mm = [sq * (cols - 1) as f64 / 2.0, sq * (rows - 1) as f64 / 2.0, 0.0];
    // The paper's spread (3 mm, 2 mm, 4 mm steps at 125 mm), scaled.
    let s = design.distance_mm / 125.0;
    LENS_OFF_TILTS_DEG
        .iter()
        .enumerate()
        .map(|(k, &(ax, ay))| {
            let om = [ax.to_radians(), ay.to_radians(), 0.05 * (k as f64 - 4.5) / 4.5];
            let r = etl_core::model::rotation::rodrigues_to_matrix(om);
            let centre = etl_core::model::rotation::mat_vec(&r, centre_mm);
            let shift = [
                s * 3.0 * ((k % 3) as f64 - 1.0),
                s * 2.0 * ((k % 2) as f64 - 0.5),
                design.distance_mm + s * 4.0 * (k % 4) as f64,
            ];
            CameraModel {
                rotation_rodrigues: om,
                translation_mm: [shift[0] - centre[0], shift[1] - centre[1], shift[2] - centre[2]],
                ..*truth
            }
        })
        .collect()
}

/// The paper rig's 15 views under `noise`, seeded.
pub fn paper_rig(noise: &NoiseModel, seed: u64) -> Simulation {
    simulate_rig(&RigDesign::paper(), noise, seed)
}

/// A simulated ETL rig: its true camera and image, the board on its stage, the views
/// (stage position and compensated current of each) and the lens-off views.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigDesign {
    /// The true camera.
    pub truth: CameraModel,
    /// Image size, px.
    pub image_size: [u32; 2],
    /// The board on the stage.
    pub board: StageBoard,
    /// Stage position of each view, mm.
    pub z_w_mm: &'static [f64],
    /// Compensated current of each view, mA.
    pub e_com_ma: &'static [f64],
    /// The lens-off views (for A0).
    pub lens_off: LensOff,
}

impl RigDesign {
    /// The paper rig (docs/METHOD.md, "The paper rig").
    pub const fn paper() -> Self {
        RigDesign {
            truth: CameraModel::paper_rig(),
            image_size: CameraModel::PAPER_IMAGE_SIZE,
            board: PAPER_RIG_BOARD,
            z_w_mm: &PAPER_Z_W_MM,
            e_com_ma: &PAPER_E_COM_MA,
            lens_off: LensOff::PAPER,
        }
    }
}

/// The views of `design` under `noise`, seeded: per view j the stage really stands at
/// Z_W,j + dZ_j and the lens runs at E_j + dE_j while Z_W,j and E_j are recorded; each
/// corner sits off its nominal X, Y by the corner noise; the observed pixel carries the
/// pixel noise; corners whose noise-free pixel leaves the image are dropped; the A0 a
/// lens-off calibration would give is off by the noise model's kf0 and principal-point
/// errors.
pub fn simulate_rig(design: &RigDesign, noise: &NoiseModel, seed: u64) -> Simulation {
    let truth = design.truth;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut obs = Observations::new(design.image_size);
    let (mut dzs, mut des) = (vec![], vec![]);
    for (&z, &e) in design.z_w_mm.iter().zip(design.e_com_ma) {
        let (dz, de) = (gauss(noise.z_mm, &mut rng), gauss(noise.e_ma, &mut rng));
        let mut points = vec![];
        for (w, _) in visible_stage_board(&truth, &design.board, design.image_size, z, e) {
            let real = [w[0] + gauss(noise.xy_mm, &mut rng), w[1] + gauss(noise.xy_mm, &mut rng), z + dz];
            if let Ok(p) = truth.project(real, e + de) {
                let pixel = [p[0] + gauss(noise.px, &mut rng), p[1] + gauss(noise.px, &mut rng)];
                points.push(PointObs { world_mm: [w[0], w[1], z], pixel });
            }
        }
        // The recorded current is E_com; the driver was commanded the E_in that gives it at
        // the lens temperature.
        let e_in = ThermalSurface::PAPER.e_in_for_e_com(e, PAPER_TEMPERATURE_C).unwrap_or(e);
        obs.views.push(ViewObs {
            e_in_ma: e_in,
            focal_power_dpt: None,
            temperature_c: PAPER_TEMPERATURE_C,
            e_com_ma: Some(e),
            points,
        });
        dzs.push(dz);
        des.push(de);
    }
    obs.offstate_views = lens_off_views_of(&truth, &design.lens_off, design.image_size, noise, &mut rng);
    let a0 = lens_off_a0(&truth, noise, &mut rng);
    Simulation { observations: obs, a0, truth, true_dz_mm: dzs, true_de_ma: des }
}

/// The A0 a lens-off calibration of `truth` would give: kf0 off by the noise model's
/// relative error, the principal point by its error in px.
pub(super) fn lens_off_a0(truth: &CameraModel, noise: &NoiseModel, rng: &mut ChaCha8Rng) -> A0 {
    A0 {
        kf0x: truth.kf_x.coefficients()[0] * (1.0 + gauss(noise.kf0_rel, rng)),
        kf0y: truth.kf_y.coefficients()[0] * (1.0 + gauss(noise.kf0_rel, rng)),
        u0: truth.principal_point[0] + gauss(noise.pp_px, rng),
        v0: truth.principal_point[1] + gauss(noise.pp_px, rng),
    }
}

/// The per-setting baseline's rig (the paper's "existing method", section 5.2.3): at each
/// current, `views_per_setting` views of the paper board near the plane in focus, each
/// tilted as far as the depth of field allows.
///
/// Depth of field: a point `dz` mm off the plane in focus at depth Zc blurs to about
/// fx * A * dz / Zc^2 px through an aperture of `aperture_mm`; keeping that below
/// `blur_px` limits the board's depth extent to 2 dz and its tilt to
/// asin(2 dz / board width), capped at `max_tilt_deg`. At high current (short distance,
/// high magnification) the tilt falls to a few degrees, which is what makes the
/// baseline's focal length scatter (paper Fig. 12(a)).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingRig {
    /// The currents, mA.
    pub e_com_ma: Vec<f64>,
    /// Views per current.
    pub views_per_setting: usize,
    /// Blur accepted at the board's edges, px.
    pub blur_px: f64,
    /// Effective aperture diameter, mm.
    pub aperture_mm: f64,
    /// Largest tilt whatever the depth of field, degrees.
    pub max_tilt_deg: f64,
}

impl Default for SettingRig {
    fn default() -> Self {
        SettingRig {
            e_com_ma: vec![80.0, 100.0, 125.0, 150.0, 175.0, 200.0, 225.0],
            views_per_setting: 15,
            blur_px: 2.0,
            aperture_mm: 2.5,
            max_tilt_deg: 25.0,
        }
    }
}

impl SettingRig {
    /// The largest tilt the depth of field allows at `e_ma`, degrees.
    pub fn tilt_limit_deg(&self, truth: &CameraModel, e_ma: f64) -> f64 {
        let zc = focus_depth_mm(truth, e_ma);
        let (fx, _) = truth.focal_lengths(e_ma);
        let dz = self.blur_px * zc * zc / (fx * self.aperture_mm);
        let ([cols, _], sq) = PAPER_BOARD;
        let width = sq * (cols - 1) as f64;
        ((2.0 * dz / width).min(1.0)).asin().to_degrees().min(self.max_tilt_deg)
    }
}

/// Simulates [`SettingRig`] into `obs.setting_views` (pixel noise, corner noise and one
/// current error per setting from `noise`; no stage). Board points are in the board's
/// frame (Z = 0); only corners inside the image are kept.
pub fn add_setting_views(obs: &mut Observations, rig: &SettingRig, noise: &NoiseModel, seed: u64) {
    add_setting_views_of(obs, &CameraModel::paper_rig(), rig, noise, seed);
}

/// [`add_setting_views`] through the camera `truth` (e.g. one with a moving centre: each
/// board's camera point then shifts by -dz(E) along the axis, Eq. C2).
pub fn add_setting_views_of(
    obs: &mut Observations,
    truth: &CameraModel,
    rig: &SettingRig,
    noise: &NoiseModel,
    seed: u64,
) {
    let truth = *truth;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xba5e_11fe);
    let ([cols, rows], sq) = PAPER_BOARD;
    let centre = [sq * (cols - 1) as f64 / 2.0, sq * (rows - 1) as f64 / 2.0, 0.0];
    for &e in &rig.e_com_ma {
        let de = gauss(noise.e_ma, &mut rng);
        let zc = focus_depth_mm(&truth, e);
        let tilt = rig.tilt_limit_deg(&truth, e).to_radians();
        for k in 0..rig.views_per_setting {
            // Tilt axes spread evenly around the optical axis, the amount cycling through
            // full, two thirds and one third of the limit; a little in-plane rotation.
            let phi = 2.0 * std::f64::consts::PI * k as f64 / rig.views_per_setting as f64;
            let amount = tilt * [1.0, 2.0 / 3.0, 1.0 / 3.0][k % 3];
            let om = [amount * phi.cos(), amount * phi.sin(), 0.1 * ((k % 5) as f64 - 2.0) / 2.0];
            let r = etl_core::model::rotation::rodrigues_to_matrix(om);
            let c = etl_core::model::rotation::mat_vec(&r, centre);
            let shift = [0.5 * ((k % 3) as f64 - 1.0), 0.4 * ((k % 2) as f64 - 0.5), zc];
            let cam = CameraModel {
                rotation_rodrigues: om,
                translation_mm: [shift[0] - c[0], shift[1] - c[1], shift[2] - c[2]],
                ..truth
            };
            let mut points = vec![];
            for j in 0..rows {
                for i in 0..cols {
                    let w = [sq * i as f64, sq * j as f64];
                    let real = [w[0] + gauss(noise.xy_mm, &mut rng), w[1] + gauss(noise.xy_mm, &mut rng), 0.0];
                    if let Ok(p) = cam.project(real, e + de) {
                        if (0.0..=1935.0).contains(&p[0]) && (0.0..=1457.0).contains(&p[1]) {
                            let pixel = [p[0] + gauss(noise.px, &mut rng), p[1] + gauss(noise.px, &mut rng)];
                            points.push(PointObs { world_mm: [w[0], w[1], 0.0], pixel });
                        }
                    }
                }
            }
            let e_in = ThermalSurface::PAPER.e_in_for_e_com(e, PAPER_TEMPERATURE_C).unwrap_or(e);
            obs.setting_views.push(ViewObs {
                e_in_ma: e_in,
                focal_power_dpt: None,
                temperature_c: PAPER_TEMPERATURE_C,
                e_com_ma: Some(e),
                points,
            });
        }
    }
}

/// Convenience: the observations' points as core points, for tests.
pub fn core_points(sim: &Simulation) -> Vec<Vec<Point>> {
    sim.observations.core_points()
}

/// The noise model of the simulation flags.
pub fn noise_from(stage_um: f64, current_ma: f64, pixel_px: f64) -> Result<NoiseModel> {
    let levels = [("stage_noise_um", stage_um), ("current_noise_ma", current_ma), ("pixel_noise_px", pixel_px)];
    if let Some((what, x)) = levels.into_iter().find(|(_, x)| !(x.is_finite() && *x >= 0.0)) {
        return Err(Error::invalid_value(what, x, "noise levels must be finite and not negative"));
    }
    Ok(NoiseModel { z_mm: stage_um / 1000.0, e_ma: current_ma, px: pixel_px, ..NoiseModel::PAPER })
}

/// Writes a simulation's files into `dir`: observations.json, a0.json, truth.json
/// ([`write_truth`] without a dataset).
pub fn write_simulation(sim: &Simulation, dir: &std::path::Path) -> Result<()> {
    sim.observations.save(&dir.join("observations.json"))?;
    A0File::new(&sim.a0).save(&dir.join("a0.json"))?;
    write_truth(sim, None, dir)
}

/// Writes `dir/truth.json`: `{"format": "etlcal.truth/1", "model", "dz_mm", "de_ma"}`, the
/// true model in the simulated observations' world frame (the paper board's) and each
/// view's true stage and current errors, and with rendered images `"dataset_model"`, the
/// true model in the world frame of dataset.json (its ETL board's, e.g. the ChArUco
/// board's: [`images::dataset_truth`]).
pub fn write_truth(sim: &Simulation, dataset_model: Option<&CameraModel>, dir: &std::path::Path) -> Result<()> {
    let mut truth =
        json!({"format": "etlcal.truth/1", "model": sim.truth, "dz_mm": sim.true_dz_mm, "de_ma": sim.true_de_ma});
    if let Some(m) = dataset_model {
        truth["dataset_model"] = json!(m);
    }
    write_json(&dir.join("truth.json"), &truth)
}

/// Simulates `config`.
pub fn simulate(config: &SimConfig) -> Simulation {
    if config.rig == SimRig::Strong {
        return strong_rig(&config.noise, config.seed);
    }
    let mut sim = paper_rig(&config.noise, config.seed);
    if let Some(rig) = &config.setting_rig {
        add_setting_views(&mut sim.observations, rig, &config.noise, config.seed);
    }
    sim
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_rig_has_2311_points_and_compensates_back() {
        let s = paper_rig(&NoiseModel::NONE, 0);
        assert_eq!(s.observations.views.iter().map(|v| v.points.len()).sum::<usize>(), 2311);
        for v in &s.observations.views {
            let e = ThermalSurface::PAPER.e_com_ma(v.e_in_ma, v.temperature_c).unwrap();
            assert!((e - v.e_com_ma.unwrap()).abs() < 1e-8);
        }
        assert_eq!(focused_z_mm(225.0), 2.0);
        assert!((focused_z_mm(85.0) - 67.5).abs() < 1e-12);
    }
}
