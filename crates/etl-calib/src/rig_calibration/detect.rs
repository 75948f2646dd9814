//! A rig dataset of images turned into one of points: each camera's images detected by the
//! single-camera detection path ([`crate::pipeline::dataset::observations_from_dataset`],
//! the one `etlcal calibrate --dataset` runs), each camera's board corners written back
//! as its `[u, v, X, Y]` rows.
//!
//! A view whose board is not found in one camera's image is dropped for that camera (a
//! missing detection is normal: the board may leave a verging camera's frame) and listed
//! in the summary; a stage view no camera kept is dropped. A camera whose views left span
//! fewer than 3 distinct settings (its board found nowhere, in particular) is refused,
//! naming the camera. Every image of every camera is checked up front: a missing one
//! fails the run, named, before any detection.

use std::path::Path;

use etl_core::progress::Progress;
use etl_formats::dataset::Dataset;
use etl_formats::observations::ViewObs;
use etl_formats::rig_dataset::{
    points_of, RigDataset, RigFreeView, RigOffstateShot, RigOffstateView, RigShot, RigView, ShotKind,
};
use etl_formats::{Error, Result};

use crate::pipeline::dataset::{observations_from_dataset, CornerDetector, DetectionSummary};

/// What detection did, per camera (in the dataset's order).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RigDetectionSummary {
    /// Each camera's name and its detection summary (images looked at, found, skipped).
    pub cameras: Vec<(String, DetectionSummary)>,
}

/// The points rig dataset of the images of `dataset` (read from `dataset_path`, against
/// which image paths resolve), with what was skipped (module docs). A points dataset is
/// returned as it is, with an empty summary.
///
/// Errors (one line): an image missing or unreadable, or of another size than its
/// camera's `image_size` (named); a camera whose detected views span fewer than 3 distinct
/// settings (named, with the images whose board was not found).
pub fn detect_rig(
    dataset: &RigDataset,
    dataset_path: &Path,
    detector: &dyn CornerDetector,
    progress: &dyn Progress,
) -> Result<(RigDataset, RigDetectionSummary)> {
    dataset.validate()?;
    if dataset.shot_kind() == ShotKind::Points {
        return Ok((dataset.clone(), RigDetectionSummary { cameras: vec![] }));
    }
    // Missing files fail the run before any camera's detection work.
    for image in dataset.images() {
        let path = Dataset::resolve(dataset_path, image);
        std::fs::metadata(&path).map_err(|source| Error::Io { path: path.clone(), source })?;
    }
    let mut points = RigDataset { views: vec![], offstate_views: vec![], offstate_board: None, ..dataset.clone() };
    points.views = dataset.views.iter().map(|v| RigView { z_w_mm: v.z_w_mm, cameras: vec![] }).collect();
    points.free_views = dataset.free_views.iter().map(|_| RigFreeView { cameras: vec![] }).collect();
    let mut summaries = vec![];
    for (k, camera) in dataset.cameras.iter().enumerate() {
        let (single, view_index) = dataset.camera_dataset(k);
        let in_camera = |e: Error| e.within(format!("camera {k} ({})", camera.name), Some(&format!("cameras[{k}]")));
        let (obs, summary) = observations_from_dataset(&single, dataset_path, detector, progress).map_err(in_camera)?;
        let detected = detected_views(&single, dataset_path, &summary);
        put_free_views(dataset, k, (&single, dataset_path, &summary), &obs.setting_views, &mut points);
        for (i, v) in detected.into_iter().zip(&obs.views) {
            let Some(shot) = dataset.views[view_index[i]].cameras.iter().find(|s| s.camera == k) else { continue };
            let rows = points_of(&v.points);
            points.views[view_index[i]].cameras.push(RigShot { image: None, points: Some(rows), ..(*shot).clone() });
        }
        for (i, v) in obs.offstate_views.iter().enumerate() {
            if points.offstate_views.len() <= i {
                points.offstate_views.push(RigOffstateView { cameras: vec![] });
            }
            let shot = RigOffstateShot { camera: k, image: None, points: Some(points_of(&v.points)) };
            points.offstate_views[i].cameras.push(shot);
        }
        summaries.push((camera.name.clone(), summary));
    }
    points.views.retain(|v| !v.cameras.is_empty());
    points.free_views.retain(|v| !v.cameras.is_empty());
    points.validate()?;
    Ok((points, RigDetectionSummary { cameras: summaries }))
}

/// Camera `k`'s detected free views (its single-camera dataset's setting views, in the
/// order of the rig's free views where it has an image) written back into `points`.
fn put_free_views(
    dataset: &RigDataset,
    k: usize,
    (single, dataset_path, summary): (&Dataset, &Path, &DetectionSummary),
    detected: &[ViewObs],
    points: &mut RigDataset,
) {
    let with_image: Vec<(usize, &RigShot)> = dataset
        .free_views
        .iter()
        .enumerate()
        .filter_map(|(f, v)| v.cameras.iter().find(|s| s.camera == k && s.image.is_some()).map(|s| (f, s)))
        .collect();
    let mut skipped = summary.skipped.iter().filter(|s| s.kind == "setting").peekable();
    let mut found = detected.iter();
    for ((f, shot), image) in with_image.into_iter().zip(&single.setting_views) {
        if skipped.peek().is_some_and(|s| s.image == Dataset::resolve(dataset_path, &image.image)) {
            skipped.next();
            continue;
        }
        let Some(v) = found.next() else { return };
        let rows = points_of(&v.points);
        points.free_views[f].cameras.push(RigShot { image: None, points: Some(rows), ..shot.clone() });
    }
}

/// The index in `single.views` of each view whose board was found, in order: the views
/// whose image is not the next skipped view image ([`observations_from_dataset`] keeps its
/// jobs' order in both the observations and the skipped list).
fn detected_views(single: &Dataset, dataset_path: &Path, summary: &DetectionSummary) -> Vec<usize> {
    let mut skipped = summary.skipped.iter().filter(|s| s.kind == "view").peekable();
    let mut detected = vec![];
    for (i, v) in single.views.iter().enumerate() {
        let path = Dataset::resolve(dataset_path, &v.image);
        if skipped.peek().is_some_and(|s| s.image == path) {
            skipped.next();
        } else {
            detected.push(i);
        }
    }
    detected
}
