//! The paper's procedure traced through a rig ([`super::OpticalRig`]): the ETL views (one
//! per current, the board on the stage at the position in focus), the lens-off views for
//! A0 (the ETL left in at 0 mA, at its zero-current power: the model's A0 is the camera at
//! E = 0), tilted views per current for a monofocal calibration at each current
//! (`setting_views`); pixels are traced spot centroids plus Gaussian pixel noise of the
//! procedure's `pixel_noise_px`, seeded.

use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
use etl_core::model::CameraModel;
use etl_core::thermal::ThermalSurface;
use etl_formats::observations::{Observations, OffstateView, PointObs, ViewObs};
use etl_formats::optics::BoardSpec;
use etl_formats::Result;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::ray::V3;
use super::rig::{board_centre_mm, OpticalRig, Setting};
use crate::simulate::{gauss, lens_off_poses_of, LensOff};

/// A board pose, board frame to camera frame: (Rodrigues, translation mm).
pub type Pose = ([f64; 3], [f64; 3]);

/// Which point of a traced spot stands for the corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CornerAs {
    /// The spot's centroid ([`Setting::pixel`]): what the procedure records.
    Centroid,
    /// The chief ray's hit ([`Setting::chief_pixel`]): the ray through the stop's centre,
    /// a central projection but for the pupil's own aberration; to compare what the fan
    /// (defocus, coma, vignetting) adds.
    Chief,
}

/// The corners of `board` (its frame: first inner corner at the origin, Z = `z_mm`) seen
/// at `setting` through `pose`: every corner whose traced centroid lies inside the image
/// (a corner whose chief ray a surface's aperture stops is not seen), noise-free.
/// `world_mm` of each point is the board-frame (X, Y, `z_mm`).
pub fn board_view(rig: &OpticalRig, setting: &Setting, board: &BoardSpec, pose: &Pose, z_mm: f64) -> Vec<PointObs> {
    board_view_as(rig, setting, board, pose, z_mm, CornerAs::Centroid)
}

/// [`board_view`] with each corner's pixel taken as `corner` says; which corners are seen
/// does not depend on it (the centroid inside the image decides).
pub fn board_view_as(
    rig: &OpticalRig,
    setting: &Setting,
    board: &BoardSpec,
    pose: &Pose,
    z_mm: f64,
    corner: CornerAs,
) -> Vec<PointObs> {
    let [cols, rows] = board.inner_corners;
    let r = rodrigues_to_matrix(pose.0);
    let [w, h] = rig.file.sensor.size_px.map(|n| n as f64 - 1.0);
    let corners: Vec<V3> = (0..rows)
        .flat_map(|j| (0..cols).map(move |i| [i as f64 * board.square_mm, j as f64 * board.square_mm, z_mm]))
        .collect();
    let pixels: Vec<Option<[f64; 2]>> = corners
        .par_iter()
        .map(|&p| {
            let c = mat_vec(&r, p);
            let spot = setting.spot([c[0] + pose.1[0], c[1] + pose.1[1], c[2] + pose.1[2]]).ok()?;
            let px = setting.to_pixel(spot.centroid_mm);
            let inside = (0.0..=w).contains(&px[0]) && (0.0..=h).contains(&px[1]);
            inside.then_some(match corner {
                CornerAs::Centroid => px,
                CornerAs::Chief => setting.to_pixel(spot.chief_mm),
            })
        })
        .collect();
    corners.iter().zip(pixels).filter_map(|(&world_mm, px)| Some(PointObs { world_mm, pixel: px? })).collect()
}

/// `obs` with Gaussian noise of `sigma_px` on every pixel, seeded (views, lens-off views,
/// setting views in turn): the traced pixels do not depend on the seed, so one trace
/// serves every noise seed.
pub fn with_pixel_noise(obs: &Observations, sigma_px: f64, seed: u64) -> Observations {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = obs.clone();
    let views = out.views.iter_mut().chain(out.setting_views.iter_mut()).map(|v| &mut v.points);
    for points in out.offstate_views.iter_mut().map(|v| &mut v.points).chain(views) {
        for p in points.iter_mut() {
            p.pixel = [p.pixel[0] + gauss(sigma_px, &mut rng), p.pixel[1] + gauss(sigma_px, &mut rng)];
        }
    }
    out
}

/// The view record of current `e_ma` at the procedure's temperature: E_com recorded, the
/// E_in that gives it through the paper's thermal surface commanded (as the simulated
/// paper rig does).
fn view_obs(e_ma: f64, temperature_c: f64, points: Vec<PointObs>) -> ViewObs {
    ViewObs {
        e_in_ma: commanded_e_in_ma(e_ma, temperature_c),
        focal_power_dpt: None,
        temperature_c,
        e_com_ma: Some(e_ma),
        points,
    }
}

/// The E_in (mA) the traced procedure records for compensated current `e_com_ma` at
/// `temperature_c`: the one that gives it through the paper's thermal surface (E_com
/// itself where the surface has none).
pub fn commanded_e_in_ma(e_com_ma: f64, temperature_c: f64) -> f64 {
    ThermalSurface::PAPER.e_in_for_e_com(e_com_ma, temperature_c).unwrap_or(e_com_ma)
}

/// The stage board at stage position `z_mm` (world frame) at `setting`, noise-free.
pub fn stage_view(rig: &OpticalRig, setting: &Setting, z_mm: f64) -> Vec<PointObs> {
    board_view(rig, setting, &rig.file.procedure.board, &rig.stage_pose(), z_mm)
}

/// The poses of the tilted views at one current: the board's centre `distance_mm` in
/// front on the axis, tilted about axes spread evenly around it by the full, two thirds
/// and one third of `tilt_deg` in turn, turned a little in its plane, shifted a little.
pub fn setting_poses(board: &BoardSpec, distance_mm: f64, views: usize, tilt_deg: f64) -> Vec<Pose> {
    let centre = board_centre_mm(board);
    (0..views)
        .map(|k| {
            let phi = 2.0 * std::f64::consts::PI * k as f64 / views as f64;
            let amount = tilt_deg.to_radians() * [1.0, 2.0 / 3.0, 1.0 / 3.0][k % 3];
            let om = [amount * phi.cos(), amount * phi.sin(), 0.1 * ((k % 5) as f64 - 2.0) / 2.0];
            let c = mat_vec(&rodrigues_to_matrix(om), centre);
            let shift = [0.5 * ((k % 3) as f64 - 1.0), 0.4 * ((k % 2) as f64 - 0.5), distance_mm];
            (om, [shift[0] - c[0], shift[1] - c[1], shift[2] - c[2]])
        })
        .collect()
}

/// The observations of the procedure with the procedure's pixel noise, seeded
/// ([`traced`], then [`with_pixel_noise`]).
pub fn observations(rig: &OpticalRig, seed: u64) -> Result<Observations> {
    Ok(with_pixel_noise(&traced(rig)?, rig.file.procedure.pixel_noise_px, seed))
}

/// The procedure's 10 lens-off views traced, noise-free: the ETL at 0 mA, the lens-off
/// board in the poses of [`lens_off_poses_of`] about the distance in focus at 0 mA (board
/// frame to camera frame), each view's corners as [`board_view_as`] sees them with the
/// corners as `corner` says. Errors: no focus at 0 mA.
pub fn lens_off_views(rig: &OpticalRig, corner: CornerAs) -> Result<Vec<Vec<PointObs>>> {
    let p = &rig.file.procedure;
    let off = rig.at(0.0)?;
    let design = LensOff {
        board: (p.lens_off_board.inner_corners, p.lens_off_board.square_mm),
        distance_mm: rig.focus_distance_mm(0.0)?,
    };
    // Only the poses of the lens-off cameras are used (the traced optics are the camera).
    Ok(lens_off_poses_of(&CameraModel::paper_rig(), &design)
        .iter()
        .map(|cam| {
            let pose = (cam.rotation_rodrigues, cam.translation_mm);
            board_view_as(rig, &off, &p.lens_off_board, &pose, 0.0, corner)
        })
        .collect())
}

/// The procedure's views traced, noise-free: the ETL views, the lens-off views (the 10
/// poses of [`lens_off_poses_of`] about the distance in focus at 0 mA) and the tilted
/// views per current. Errors: a current at which the focus cannot be found.
pub fn traced(rig: &OpticalRig) -> Result<Observations> {
    let p = &rig.file.procedure;
    let mut obs = Observations::new(rig.file.sensor.size_px);
    // The focus search is the costly part of a setting: once per current.
    let mut settings = Vec::with_capacity(p.e_com_ma.len());
    for &e in &p.e_com_ma {
        settings.push((e, rig.at(e)?, rig.focus_distance_mm(e)?));
    }
    for (e, setting, d) in &settings {
        obs.views.push(view_obs(*e, p.temperature_c, stage_view(rig, setting, rig.stage_z_at_distance_mm(*d))));
    }
    obs.offstate_views =
        lens_off_views(rig, CornerAs::Centroid)?.into_iter().map(|points| OffstateView { points }).collect();
    for (e, setting, d) in &settings {
        for pose in setting_poses(&p.board, *d, p.setting_views_per_current, p.setting_tilt_deg) {
            let points = board_view(rig, setting, &p.board, &pose, 0.0);
            obs.setting_views.push(view_obs(*e, p.temperature_c, points));
        }
    }
    Ok(obs)
}
