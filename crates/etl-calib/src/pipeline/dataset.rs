//! From a dataset's images to observations: every image is checked up front (a missing or
//! unreadable image fails the run before any work), boards are detected in parallel
//! (rayon, with a progress bar on request), views whose board is not found are reported
//! and skipped, and the run fails only if what remains breaks a precondition of the
//! method, which the error names.

use std::path::{Path, PathBuf};

use etl_core::progress::Progress;
use rayon::prelude::*;

use etl_formats::dataset::{Board, Dataset};
use etl_formats::observations::{Observations, OffstateView, PointObs, ViewObs};
use etl_formats::{Error, Result};

/// Corners found in one image.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    /// Width and height of the image, px.
    pub image_size: [u32; 2],
    /// Each corner found: its id on the board asked for (row by row over its corner grid,
    /// [`Board::corner_grid`]; a ChArUco board's own ids) and its pixel.
    pub corners: Vec<(u32, [f64; 2])>,
}

impl Detection {
    /// The board-frame (X, Y) of every corner, mm: [`Board::corner_mm`] of its id, moved by
    /// `first_corner` squares (the index on the physical checkerboard of the corner (0, 0)
    /// of the sub-board `board` that was detected; [0, 0] for a whole board).
    pub fn board_mm(&self, board: &Board, first_corner: [usize; 2]) -> Vec<[f64; 2]> {
        let s = board.square_mm();
        let [dx, dy] = first_corner.map(|k| k as f64 * s);
        // Detectors return only ids of the board asked for; an id beyond it is a bug of
        // the detector, kept visible as a NaN point that every solver refuses.
        self.corners
            .iter()
            .map(|&(id, _)| board.corner_mm(id).map_or([f64::NAN; 2], |[x, y]| [x + dx, y + dy]))
            .collect()
    }

    /// The pixel of every corner, in the order of [`Detection::board_mm`].
    pub fn pixels(&self) -> Vec<[f64; 2]> {
        self.corners.iter().map(|c| c.1).collect()
    }
}

/// Finds the corners of a board (ChArUco or checkerboard) in an image file.
///
/// Implementations return [`Error::BoardNotFound`] when the board is not in the image
/// (the view is then skipped) and [`Error::Image`] / [`Error::Io`] when the file cannot be
/// read (the run fails).
pub trait CornerDetector: Sync {
    /// Detects `board` in the image at `path`: a checkerboard whole, a ChArUco board in
    /// part (the corners it can tell by their markers).
    fn detect(&self, path: &Path, board: &Board) -> Result<Detection>;
}

/// A view of the dataset that was skipped, and why.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SkippedView {
    /// The image.
    pub image: PathBuf,
    /// `"view"`, `"offstate"` or `"setting"`.
    pub kind: &'static str,
    /// Why (the detector's message).
    pub reason: String,
}

/// What detection did.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct DetectionSummary {
    /// Images looked at.
    pub images: usize,
    /// Images in which the board was found.
    pub detected: usize,
    /// ETL views in which the board was found.
    pub views_detected: usize,
    /// Views skipped.
    pub skipped: Vec<SkippedView>,
}

#[derive(Clone, Copy)]
enum Kind {
    View(usize),
    Offstate,
    Setting(usize),
}

/// Detects every image of `dataset` (read from `dataset_path`, against which image paths
/// resolve) and returns the observations with a summary of what was skipped.
///
/// Errors: an image missing or unreadable (named); an image of another size than the
/// dataset's `image_size`; no ETL view left while the dataset had some, or the ETL views
/// left spanning fewer than 3 distinct currents (named with the images skipped).
pub fn observations_from_dataset(
    dataset: &Dataset,
    dataset_path: &Path,
    detector: &dyn CornerDetector,
    progress: &dyn Progress,
) -> Result<(Observations, DetectionSummary)> {
    dataset.validate()?;
    let jobs = detection_jobs(dataset, dataset_path);
    // Missing files fail the run before any detection work.
    for (_, path, _, _) in &jobs {
        std::fs::metadata(path).map_err(|source| Error::Io { path: path.clone(), source })?;
    }
    progress.start(jobs.len(), "detecting");
    let results: Vec<Result<Detection>> = jobs
        .par_iter()
        .map(|(_, path, board, _)| {
            let r = detector.detect(path, board);
            progress.advance(1);
            r
        })
        .collect();
    progress.finish();

    let mut obs = Observations::new(dataset.image_size);
    let mut summary = DetectionSummary { images: jobs.len(), ..DetectionSummary::default() };
    for ((kind, path, board, first_corner), result) in jobs.iter().zip(results) {
        let det = match result {
            Ok(d) => d,
            Err(Error::BoardNotFound(reason)) => {
                let kind = match kind {
                    Kind::View(_) => "view",
                    Kind::Offstate => "offstate",
                    Kind::Setting(_) => "setting",
                };
                summary.skipped.push(SkippedView { image: path.clone(), kind, reason });
                continue;
            }
            Err(e) => return Err(e),
        };
        super::check_image_size(path, det.image_size, dataset.image_size, "the dataset says")?;
        summary.detected += 1;
        let z = match kind {
            Kind::View(i) => dataset.views[*i].z_w_mm,
            _ => 0.0,
        };
        let points: Vec<PointObs> = det
            .board_mm(board, *first_corner)
            .into_iter()
            .zip(det.pixels())
            .map(|([x, y], pixel)| PointObs { world_mm: [x, y, z], pixel })
            .collect();
        match *kind {
            Kind::View(i) => {
                let v = &dataset.views[i];
                summary.views_detected += 1;
                obs.views.push(ViewObs {
                    e_in_ma: v.e_in_ma,
                    focal_power_dpt: v.focal_power_dpt,
                    temperature_c: v.temperature_c,
                    e_com_ma: v.e_com_ma,
                    points,
                });
            }
            Kind::Offstate => obs.offstate_views.push(OffstateView { points }),
            Kind::Setting(i) => {
                let v = &dataset.setting_views[i];
                obs.setting_views.push(ViewObs {
                    e_in_ma: v.e_in_ma,
                    focal_power_dpt: v.focal_power_dpt,
                    temperature_c: v.temperature_c,
                    e_com_ma: v.e_com_ma,
                    points,
                });
            }
        }
    }
    if !dataset.views.is_empty() {
        check_distinct_settings(&obs, &summary, dataset.views.len())?;
    }
    Ok((obs, summary))
}

/// A detection job: (kind, image, board asked of the detector, index of its corner (0, 0)
/// on the board).
type Job = (Kind, PathBuf, Board, [usize; 2]);

/// The jobs of every image of `dataset` (views, lens-off views, setting views, in this
/// order), image paths resolved against `dataset_path`.
fn detection_jobs(dataset: &Dataset, dataset_path: &Path) -> Vec<Job> {
    let mut jobs: Vec<Job> = vec![];
    for (i, v) in dataset.views.iter().enumerate() {
        let board = v.board.unwrap_or(dataset.board);
        jobs.push((Kind::View(i), Dataset::resolve(dataset_path, &v.image), board, v.first_corner.unwrap_or([0, 0])));
    }
    for v in &dataset.offstate_views {
        let board = v.board.unwrap_or(dataset.offstate_board());
        jobs.push((Kind::Offstate, Dataset::resolve(dataset_path, &v.image), board, v.first_corner.unwrap_or([0, 0])));
    }
    for (i, v) in dataset.setting_views.iter().enumerate() {
        let board = v.board.unwrap_or(dataset.board);
        jobs.push((
            Kind::Setting(i),
            Dataset::resolve(dataset_path, &v.image),
            board,
            v.first_corner.unwrap_or([0, 0]),
        ));
    }
    jobs
}

/// Refuses observations whose views span fewer than 3 distinct settings (a setting is its
/// recorded E_com, or its (E_in, T) pair), naming the views whose board was not found.
fn check_distinct_settings(obs: &Observations, summary: &DetectionSummary, views: usize) -> Result<()> {
    // A setting is its recorded E_com, or its (E_in, T) pair.
    let mut currents: Vec<(f64, f64)> = obs
        .views
        .iter()
        .map(|v| match (v.focal_power_dpt, v.e_com_ma) {
            (Some(p), _) => (p, f64::NAN),
            (None, Some(e)) => (e, f64::NAN),
            (None, None) => (v.e_in_ma, v.temperature_c),
        })
        .collect();
    currents.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    currents.dedup_by(|a, b| a.0 == b.0 && (a.1 == b.1 || (a.1.is_nan() && b.1.is_nan())));
    if currents.len() < 3 {
        let names: Vec<String> = summary
            .skipped
            .iter()
            .filter(|s| s.kind == "view")
            .map(|s| s.image.file_name().map_or_else(|| s.image.display().to_string(), |n| n.to_string_lossy().into()))
            .collect();
        return Err(Error::BoardNotFound(format!(
            "the board was found in {} of {} views (not in: {}); the views left span {} distinct currents, \
             the method needs at least 3",
            summary.views_detected,
            views,
            names.join(", "),
            currents.len()
        )));
    }
    Ok(())
}

/// The detector of the `etlcal` command line: reads the image file and finds the board
/// with [`etl_image::board::detect_board_dynamic`].
#[derive(Debug, Clone, Copy, Default)]
pub struct ImageDetector;

/// The detector the command line uses.
pub fn default_detector() -> ImageDetector {
    ImageDetector
}

impl CornerDetector for ImageDetector {
    fn detect(&self, path: &Path, board: &Board) -> Result<Detection> {
        // The one image reader: it refuses what is not a regular file before opening it
        // and images above its pixel-count limit before decoding them. The board-generic
        // detector: a ChArUco board's corners that its markers identify, a whole
        // checkerboard's (row-major ids); 16-bit images read at 16 bits.
        let img = etl_image::read_image(path)?;
        let d = etl_image::board::detect_board_dynamic(&img, board).map_err(|e| match e {
            Error::BoardNotFound(m) => Error::BoardNotFound(format!("{}: {m}", path.display())),
            other => other,
        })?;
        Ok(Detection { image_size: d.image_size, corners: d.ids.into_iter().zip(d.corners_px).collect() })
    }
}
