//! The simulated rig as images: every view of a [`Simulation`] rendered by the synthetic
//! camera ([`crate::render`]) and recorded as an `etlcal.dataset/1` file, so that the
//! demo and `etlcal simulate` run the whole chain a user runs: images, detection,
//! calibration.
//!
//! Choices of this simulation (the paper gives no images):
//! - each ETL view is rendered at its *true* stage position and current (recorded value
//!   plus the simulated error) and recorded with the noisy values, as a user records them;
//! - the boards are ChArUco boards by default ([`RigBoard::Charuco`]:
//!   [`crate::rig::PAPER_CHARUCO`], [`crate::rig::LENS_OFF_CHARUCO`], the squares of the
//!   paper's boards with markers in the white squares), rendered whole: the ETL board
//!   overflows the frame at the near views, as the paper's does (docs/METHOD.md keeps the
//!   visible corners), and the detector tells which corners it sees by their markers, so
//!   the dataset holds no per-view hints. The dataset's world frame is then the ChArUco
//!   board's (OpenCV's), one square before the paper board's first inner corner
//!   ([`dataset_truth`] is the truth in it);
//! - with [`RigBoard::CheckerboardBlocks`] (the paper's checkerboards, as before ChArUco),
//!   a detector must not guess which part of a checkerboard it sees, so each image shows
//!   the largest block of the board's squares that lies fully inside the image with a
//!   margin (the part a user would cut, or mask, for that view), and the dataset says which
//!   corner of the board that block starts at (`first_corner`);
//! - the ETL views are focused by the simulated lens's smooth focus law
//!   ([`crate::render::Optics::paper_focus`], fitted to the paper's views; the views' whole-mm
//!   stage positions are off it by its residual, at most about 1 px of blur) through an aperture of
//!   [`ImageOptions::aperture_mm`]; the lens-off views are focused at 125 mm (the prime
//!   lens's own focus) through [`ImageOptions::lens_off_aperture_mm`];
//! - the 1 um corner-position noise of the noise model is not rendered (a printed board
//!   is one rigid object; it is below the renderer's resolution in any case).

use std::path::{Path, PathBuf};

use etl_core::model::CameraModel;
use etl_core::progress::Progress;
use rayon::prelude::*;

use super::{lens_off_poses, Simulation, LENS_OFF_BOARD, PAPER_BOARD};
use crate::render::{render, BitDepth, Optics, Photometry, RenderOptions, Scene};
use crate::rig::{charuco_frame, shifted_mm, LENS_OFF_CHARUCO, PAPER_CHARUCO};
use etl_formats::board::{Board, Checkerboard};
use etl_formats::dataset::{Dataset, DatasetView, OffstateImage};
use etl_formats::{Error, Result};

/// The boards the rig's images show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RigBoard {
    /// ChArUco boards ([`crate::rig::PAPER_CHARUCO`], [`crate::rig::LENS_OFF_CHARUCO`]),
    /// whole: each view shows what falls in the frame, the dataset holds no hints.
    #[default]
    Charuco,
    /// The paper's checkerboards, each view cut to the largest block of squares that fits
    /// the frame and recorded as a sub-board with its first corner (module docs).
    CheckerboardBlocks,
}

/// How the rig's images are made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageOptions {
    /// The boards.
    pub board: RigBoard,
    /// Aperture diameter of the ETL views, mm.
    pub aperture_mm: f64,
    /// Aperture diameter of the lens-off views, mm.
    pub lens_off_aperture_mm: f64,
    /// Camera depth the lens-off views are focused at, mm.
    pub lens_off_focus_mm: f64,
    /// Grey levels and noise.
    pub photometry: Photometry,
    /// Distance the rendered block of squares keeps from the image border, px.
    pub margin_px: f64,
}

impl Default for ImageOptions {
    fn default() -> Self {
        ImageOptions {
            board: RigBoard::Charuco,
            aperture_mm: 2.5,
            lens_off_aperture_mm: 1.0,
            lens_off_focus_mm: 125.0,
            photometry: Photometry::default(),
            margin_px: 12.0,
        }
    }
}

/// The largest block of inner corners of `board` (at Z = `z_mm` in `cam`'s world frame,
/// current `e_ma`) whose squares, including the outer ring of squares around the corners,
/// all project inside the image with `margin_px` to spare. Returns the block as a board
/// and the index of its corner (0, 0) on `board`; `None` if not even 3 x 3 corners fit.
pub fn visible_block(
    cam: &CameraModel,
    e_ma: f64,
    board: Checkerboard,
    z_mm: f64,
    image_size: [u32; 2],
    margin_px: f64,
) -> Option<(Board, [usize; 2])> {
    let [cols, rows] = board.inner_corners;
    let s = board.square_mm;
    // Square corners k = 0..=cols+1 (x = (k - 1) s), l = 0..=rows+1: inside or not.
    let (nk, nl) = (cols + 2, rows + 2);
    let inside = |k: usize, l: usize| -> bool {
        let w = [(k as f64 - 1.0) * s, (l as f64 - 1.0) * s, z_mm];
        cam.project(w, e_ma).is_ok_and(|p| {
            p[0] >= margin_px
                && p[1] >= margin_px
                && p[0] <= image_size[0] as f64 - 1.0 - margin_px
                && p[1] <= image_size[1] as f64 - 1.0 - margin_px
        })
    };
    let grid: Vec<Vec<bool>> = (0..nl).map(|l| (0..nk).map(|k| inside(k, l)).collect()).collect();
    // Prefix counts of "outside" to test a rectangle of square corners in O(1).
    let mut pre = vec![vec![0usize; nk + 1]; nl + 1];
    for l in 0..nl {
        for k in 0..nk {
            pre[l + 1][k + 1] = pre[l][k + 1] + pre[l + 1][k] - pre[l][k] + usize::from(!grid[l][k]);
        }
    }
    let outside = |k0: usize, l0: usize, k1: usize, l1: usize| {
        pre[l1 + 1][k1 + 1] + pre[l0][k0] - pre[l0][k1 + 1] - pre[l1 + 1][k0]
    };
    let mut best: Option<(usize, [usize; 4])> = None;
    // Inner corners i0..=i1 need square corners (i0 + 1 - 1)..=(i1 + 1 + 1) in k.
    for i0 in 0..cols {
        for i1 in (i0 + 2)..cols {
            for j0 in 0..rows {
                for j1 in (j0 + 2)..rows {
                    let n = (i1 - i0 + 1) * (j1 - j0 + 1);
                    if best.is_some_and(|(b, _)| b >= n) {
                        continue;
                    }
                    if outside(i0, j0, i1 + 2, j1 + 2) == 0 {
                        best = Some((n, [i0, i1, j0, j1]));
                    }
                }
            }
        }
    }
    best.map(|(_, [i0, i1, j0, j1])| {
        (Board::Checkerboard(Checkerboard { inner_corners: [i1 - i0 + 1, j1 - j0 + 1], square_mm: s }), [i0, j0])
    })
}

/// `cam` with its world frame moved so that the board's corner `first` is the origin:
/// the block then renders as a board of its own at the same place.
pub fn shifted(cam: &CameraModel, first: [usize; 2], square_mm: f64) -> CameraModel {
    shifted_mm(cam, first.map(|k| k as f64 * square_mm))
}

/// The true camera of `truth` (the simulation's, in the paper board's frame) in the world
/// frame of the dataset [`render_rig`] records with `options`: the ChArUco board's frame
/// for [`RigBoard::Charuco`], the paper board's for [`RigBoard::CheckerboardBlocks`].
pub fn dataset_truth(truth: &CameraModel, options: &ImageOptions) -> CameraModel {
    match options.board {
        RigBoard::Charuco => charuco_frame(truth, PAPER_CHARUCO.square_mm),
        RigBoard::CheckerboardBlocks => *truth,
    }
}

/// One image to make: the file, the scene, the lens's blur and the noise's seed.
pub(crate) struct Job {
    pub(crate) path: PathBuf,
    pub(crate) scene: Scene,
    pub(crate) optics: Optics,
    pub(crate) seed: u64,
}

/// Renders `jobs` in parallel (8-bit PNG, the photometry of `options`), `progress` showing
/// a bar.
pub(crate) fn render_jobs(jobs: &[Job], options: &ImageOptions, progress: &dyn Progress) -> Result<()> {
    progress.start(jobs.len(), "rendering");
    jobs.par_iter()
        .map(|job| {
            let opts = RenderOptions {
                optics: job.optics,
                photometry: options.photometry,
                bit_depth: BitDepth::Eight,
                seed: job.seed,
            };
            let r = render(&job.scene, &opts)?.image.save_png(&job.path);
            progress.advance(1);
            r
        })
        .collect::<Result<Vec<()>>>()?;
    progress.finish();
    Ok(())
}

/// Renders every ETL and lens-off view of `sim` into `dir` (`views/`, `offstate/`, 8-bit
/// PNG) and returns the dataset that records them (image paths relative to `dir`, where the
/// caller writes it; its world frame is that of [`dataset_truth`]). Rendering runs in
/// parallel; `progress` shows a bar.
///
/// Errors: with [`RigBoard::CheckerboardBlocks`], a view in which not even 3 x 3 corners
/// fit the image (named); rendering or writing failures.
pub fn render_rig(
    sim: &Simulation,
    dir: &Path,
    options: &ImageOptions,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Dataset> {
    let (mut dataset, mut jobs) = etl_views(sim, dir, options, seed)?;
    lens_off_views(sim, dir, options, seed, &mut dataset, &mut jobs)?;
    for sub in ["views", "offstate"] {
        let d = dir.join(sub);
        std::fs::create_dir_all(&d).map_err(|source| Error::Io { path: d, source })?;
    }
    render_jobs(&jobs, options, progress)?;
    Ok(dataset)
}

/// The dataset with its ETL views, and their render jobs: each view at its true stage
/// position and current, recorded with the noisy ones.
fn etl_views(sim: &Simulation, dir: &Path, options: &ImageOptions, seed: u64) -> Result<(Dataset, Vec<Job>)> {
    let truth = &sim.truth;
    let size = sim.observations.image_size;
    let (paper_inner, paper_square) = PAPER_BOARD;
    let paper_board = Checkerboard { inner_corners: paper_inner, square_mm: paper_square };
    let mut dataset = match options.board {
        RigBoard::Charuco => Dataset::new(size, PAPER_CHARUCO.board()?),
        RigBoard::CheckerboardBlocks => Dataset::new(size, Board::Checkerboard(paper_board)),
    };
    let mut jobs = vec![];
    for (k, view) in sim.observations.views.iter().enumerate() {
        let z_rec = view.points.first().map(|p| p.world_mm[2]).ok_or_else(|| {
            Error::invalid(
                format!("views[{k}].points"),
                format!("simulated view {k} has no points, so no stage position"),
            )
        })?;
        let e_rec = view.e_com_ma.unwrap_or(view.e_in_ma);
        let z = z_rec + sim.true_dz_mm.get(k).copied().unwrap_or(0.0);
        let e = e_rec + sim.true_de_ma.get(k).copied().unwrap_or(0.0);
        let (scene, board, first_corner) = match options.board {
            RigBoard::Charuco => (Scene::new(dataset_truth(truth, options), e, dataset.board, z, size), None, None),
            RigBoard::CheckerboardBlocks => {
                let (block, first) =
                    visible_block(truth, e, paper_board, z, size, options.margin_px).ok_or_else(|| {
                        let message = format!("view {k}: not even 3 x 3 corners of the board fit the image");
                        Error::invalid(format!("views[{k}]"), message)
                    })?;
                (Scene::new(shifted(truth, first, paper_square), e, block, z, size), Some(block), Some(first))
            }
        };
        let image = PathBuf::from(format!("views/view{k:02}.png"));
        jobs.push(Job {
            path: dir.join(&image),
            scene,
            optics: Optics::paper_focus(truth, e, options.aperture_mm),
            seed: seed.wrapping_mul(1_000_003).wrapping_add(k as u64),
        });
        dataset.views.push(DatasetView {
            image,
            e_in_ma: view.e_in_ma,
            focal_power_dpt: None,
            temperature_c: view.temperature_c,
            e_com_ma: view.e_com_ma,
            z_w_mm: z_rec,
            board,
            first_corner,
        });
    }
    Ok((dataset, jobs))
}

/// The lens-off views (E = 0, focused at [`ImageOptions::lens_off_focus_mm`]) into
/// `dataset` and their render jobs into `jobs`.
fn lens_off_views(
    sim: &Simulation,
    dir: &Path,
    options: &ImageOptions,
    seed: u64,
    dataset: &mut Dataset,
    jobs: &mut Vec<Job>,
) -> Result<()> {
    let size = sim.observations.image_size;
    let name = |k: usize| PathBuf::from(format!("offstate/off{k:02}.png"));
    let (board, views) = lens_off_jobs(&sim.truth, size, (dir, &name), options, seed)?;
    dataset.offstate_board = Some(board);
    for (image, job) in views {
        dataset.offstate_views.push(image);
        jobs.push(job);
    }
    Ok(())
}

/// The lens-off views of `truth` (the paper's 10 tilted poses of the lens-off board,
/// E = 0, focused at [`ImageOptions::lens_off_focus_mm`] through
/// [`ImageOptions::lens_off_aperture_mm`]) on an image of `size`: the lens-off board and,
/// per view, its dataset entry (image `name(k)`, relative to `dir`) with its render job.
/// Seeds `seed * 1000003 + 500 + k`.
pub(crate) fn lens_off_jobs(
    truth: &CameraModel,
    size: [u32; 2],
    (dir, name): (&Path, &dyn Fn(usize) -> PathBuf),
    options: &ImageOptions,
    seed: u64,
) -> Result<(Board, Vec<(OffstateImage, Job)>)> {
    let (off_inner, off_square) = LENS_OFF_BOARD;
    let off_board = Checkerboard { inner_corners: off_inner, square_mm: off_square };
    let charuco = LENS_OFF_CHARUCO.board()?;
    let dataset_board = match options.board {
        RigBoard::Charuco => charuco,
        RigBoard::CheckerboardBlocks => Board::Checkerboard(off_board),
    };
    let mut views = vec![];
    for (k, pose) in lens_off_poses(truth).iter().enumerate() {
        let (scene, board, first_corner) = match options.board {
            RigBoard::Charuco => (Scene::new(charuco_frame(pose, off_square), 0.0, charuco, 0.0, size), None, None),
            RigBoard::CheckerboardBlocks => {
                let Some((block, first)) = visible_block(pose, 0.0, off_board, 0.0, size, options.margin_px) else {
                    return Err(Error::invalid(
                        format!("offstate_views[{k}]"),
                        format!("lens-off view {k}: not even 3 x 3 corners fit the image"),
                    ));
                };
                (Scene::new(shifted(pose, first, off_square), 0.0, block, 0.0, size), Some(block), Some(first))
            }
        };
        let image = name(k);
        let job = Job {
            path: dir.join(&image),
            scene,
            optics: Optics {
                focus_depth_mm: Some(options.lens_off_focus_mm),
                aperture_mm: options.lens_off_aperture_mm,
                base_sigma_px: 0.0,
            },
            seed: seed.wrapping_mul(1_000_003).wrapping_add(500 + k as u64),
        };
        views.push((OffstateImage { image, board, first_corner }, job));
    }
    Ok((dataset_board, views))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_block_is_the_largest_that_fits_and_shrinks_near_the_camera() {
        let truth = CameraModel::paper_rig();
        let (inner, sq) = PAPER_BOARD;
        let board = Checkerboard { inner_corners: inner, square_mm: sq };
        let far = visible_block(&truth, 150.0, board, super::super::focused_z_mm(150.0), [1936, 1458], 12.0).unwrap();
        let near = visible_block(&truth, 225.0, board, super::super::focused_z_mm(225.0), [1936, 1458], 12.0).unwrap();
        let n = |b: &(Board, [usize; 2])| b.0.corner_count();
        assert!(n(&near) < n(&far) && n(&far) <= 168, "{near:?} {far:?}");
        // Every square corner of the block (outer ring included) is inside the margin.
        let (b, [i0, j0]) = near;
        for l in 0..b.corner_grid()[1] + 2 {
            for k in 0..b.corner_grid()[0] + 2 {
                let w = [(i0 + k) as f64 * sq - sq, (j0 + l) as f64 * sq - sq, super::super::focused_z_mm(225.0)];
                let p = truth.project(w, 225.0).unwrap();
                assert!(p[0] >= 12.0 && p[1] >= 12.0 && p[0] <= 1923.0 && p[1] <= 1445.0, "{p:?}");
            }
        }
        // A board far outside the image has no block.
        assert!(visible_block(&truth, 150.0, board, -500.0, [1936, 1458], 12.0).is_none());
    }
}
