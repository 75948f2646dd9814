//! The simulated N-camera rig as images: every camera's record of every stage view, and
//! its lens-off views, rendered by the synthetic camera ([`crate::render`], the renderer
//! of the single-camera simulation, [`crate::simulate::images`]) and recorded as an
//! `etlcal.rig-dataset/1` of images, for `etlcal calibrate-rig` from images.
//!
//! Choices (those of the single-camera images, [`crate::simulate::images`], where they
//! apply):
//! - the stage board is the rig's board as a ChArUco board ([`RIG_CHARUCO`]: the squares
//!   of [`super::MULTI_CAMERA_BOARD`], 1.1 mm markers of DICT_5X5_1000), rendered whole:
//!   each verging camera sees the part that falls in its frame, and the detector tells
//!   which corners by their markers (the rig dataset holds no per-view hints). The
//!   dataset's world frame is the ChArUco board's, one square before the checkerboard's
//!   first inner corner ([`dataset_truths`]); the extrinsics, relative poses, are the same
//!   in either frame;
//! - a camera's view is rendered exactly where the points simulation records one (the
//!   same views, cameras and settings), at the *true* stage position and current (the
//!   recorded ones plus the simulated errors: dZ_j shared by the cameras, dE_kj each
//!   camera's own), and recorded with the noisy values;
//! - defocus: camera k's lens is in focus at the depth its own focus law gives at the
//!   true current ([`super::focus_depth_mm`], the inverse of the law the simulation
//!   focuses by), through an aperture of [`ImageOptions::aperture_mm`]; the board's tilt
//!   in a verging camera blurs its far side more, as the renderer computes per pixel;
//! - each camera's 10 lens-off views are the single-camera simulation's (the lens-off
//!   ChArUco board in the paper's tilted poses at E = 0, [`crate::rig::LENS_OFF_CHARUCO`]);
//! - the corner-position noise of the points simulation is not rendered (a printed board
//!   is one rigid object), nor is the pixel noise: the renderer's photon and read noise
//!   and the detector make the image's.

use std::path::{Path, PathBuf};

use etl_core::model::CameraModel;
use etl_core::progress::Progress;
use etl_formats::rig_dataset::{RigDataset, RigOffstateShot, RigOffstateView};
use etl_formats::{Error, Result};

use super::{focus_depth_mm, stage_position_mm, MultiCameraSimulation, MULTI_CAMERA_BOARD};
use crate::render::{Optics, Scene};
use crate::rig::{shifted_mm, CharucoSpec};
use crate::simulate::images::{lens_off_jobs, render_jobs, ImageOptions, Job, RigBoard};

/// The rig's stage board as a ChArUco board: the 42 x 34 squares of 1.5 mm around the
/// 41 x 33 inner corners of [`super::MULTI_CAMERA_BOARD`], 1.1 mm markers (cells of
/// 0.16 mm, as the paper rig's ChArUco board) from DICT_5X5_1000 (714 of its 1000).
pub const RIG_CHARUCO: CharucoSpec =
    CharucoSpec { squares: [42, 34], square_mm: 1.5, marker_mm: 1.1, dictionary: "DICT_5X5_1000" };

/// Each camera's true model in the world frame of the rendered rig dataset (the ChArUco
/// board's: ChArUco point (x, y) is the checkerboard frame's (x - s + X0, y - s + Y0), with
/// (X0, Y0) the checkerboard's first inner corner, s the square).
pub fn dataset_truths(sim: &MultiCameraSimulation) -> Vec<CameraModel> {
    let b = &MULTI_CAMERA_BOARD;
    let shift = [b.origin_mm[0] - b.square_mm, b.origin_mm[1] - b.square_mm];
    sim.truths.iter().map(|m| shifted_mm(m, shift)).collect()
}

/// The image of camera `k`'s stage view `i`, relative to the dataset's directory.
fn view_image(k: usize, i: usize) -> PathBuf {
    PathBuf::from(format!("images/cam{k}/view{i:02}.png"))
}

/// Renders every camera's stage and lens-off views of `sim` into `dir` (`images/camK/`,
/// 8-bit PNG) and returns the rig dataset of images that records them (paths relative to
/// `dir`, where the caller writes it; its world frame that of [`dataset_truths`]).
/// Rendering runs in parallel; `progress` shows a bar.
///
/// Errors: [`RigBoard::CheckerboardBlocks`] (the rig dataset has no per-view sub-boards;
/// named); a view the simulation did not place on its stage; rendering or writing failures.
pub fn render_multi_camera(
    sim: &MultiCameraSimulation,
    dir: &Path,
    options: &ImageOptions,
    seed: u64,
    progress: &dyn Progress,
) -> Result<RigDataset> {
    if options.board != RigBoard::Charuco {
        return Err(Error::invalid(
            "board",
            "board: a rig's images show the ChArUco board (a rig dataset holds no per-view sub-boards)",
        ));
    }
    let truths = dataset_truths(sim);
    let mut dataset = sim.dataset.clone();
    dataset.board = RIG_CHARUCO.board()?;
    let mut jobs = stage_jobs(sim, &truths, &mut dataset, dir, (options, seed))?;
    let n = truths.len();
    dataset.offstate_views.clear();
    for (k, truth) in truths.iter().enumerate() {
        let name = |i: usize| PathBuf::from(format!("images/cam{k}/off{i:02}.png"));
        let (board, views) =
            lens_off_jobs(truth, dataset.cameras[k].image_size, (dir, &name), options, camera_seed(seed, k))?;
        dataset.offstate_board = Some(board);
        for (i, (image, job)) in views.into_iter().enumerate() {
            if dataset.offstate_views.len() <= i {
                dataset.offstate_views.push(RigOffstateView { cameras: Vec::with_capacity(n) });
            }
            dataset.offstate_views[i].cameras.push(RigOffstateShot {
                camera: k,
                image: Some(image.image),
                points: None,
            });
            jobs.push(job);
        }
    }
    for k in 0..n {
        let d = dir.join(format!("images/cam{k}"));
        std::fs::create_dir_all(&d).map_err(|source| Error::Io { path: d, source })?;
    }
    render_jobs(&jobs, options, progress)?;
    Ok(dataset)
}

/// Camera `k`'s seed of the rig's `seed`: its images' noise independent of the others'.
fn camera_seed(seed: u64, k: usize) -> u64 {
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(k as u64)
}

/// The render jobs of every camera's stage views, each entry of `dataset` turned from
/// points into its image: at the true stage position and current (module docs).
fn stage_jobs(
    sim: &MultiCameraSimulation,
    truths: &[CameraModel],
    dataset: &mut RigDataset,
    dir: &Path,
    (options, seed): (&ImageOptions, u64),
) -> Result<Vec<Job>> {
    let designed = sim.true_dz_mm.len();
    let n = truths.len();
    let mut jobs = vec![];
    for (i, view) in dataset.views.iter_mut().enumerate() {
        let j = (0..designed).find(|&j| stage_position_mm(j, designed) == view.z_w_mm).ok_or_else(|| {
            let message = format!("views[{i}]: stage position {} mm is not one of the simulation's", view.z_w_mm);
            Error::invalid(format!("views[{i}].z_w_mm"), message)
        })?;
        let z = view.z_w_mm + sim.true_dz_mm[j];
        for shot in &mut view.cameras {
            let k = shot.camera;
            let e_rec = shot.e_com_ma.unwrap_or(shot.e_in_ma);
            let e = e_rec + sim.true_de_ma[k][j].unwrap_or(0.0);
            let size = dataset.cameras[k].image_size;
            let image = view_image(k, i);
            let focus = focus_depth_mm(&sim.truths[k], &sim.truths[0], (k, n), e);
            jobs.push(Job {
                path: dir.join(&image),
                scene: Scene::new(truths[k], e, dataset.board, z, size),
                optics: Optics { focus_depth_mm: Some(focus), aperture_mm: options.aperture_mm, base_sigma_px: 0.0 },
                seed: camera_seed(seed, k).wrapping_mul(1_000_003).wrapping_add(i as u64),
            });
            shot.image = Some(image);
            shot.points = None;
        }
    }
    Ok(jobs)
}
