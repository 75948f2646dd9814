//! `etlcal.rig-dataset/1`: what N cameras recorded of one board on one linear stage
//! (docs/FORMATS.md): per stage position, one entry per camera that saw the board, each
//! with its own lens setting and temperature, and per camera its lens-off views.
//!
//! ```json
//! {"format": "etlcal.rig-dataset/1",
//!  "board": {"inner_corners": [14, 12], "square_mm": 1.5},
//!  "cameras": [{"name": "left", "image_size": [1936, 1458]}, {"name": "right", "image_size": [1936, 1458]}],
//!  "views": [{"z_w_mm": 75.0, "cameras": [
//!      {"camera": 0, "image": "views/c0_v00.png", "e_in_ma": 80.0, "temperature_c": 27.0},
//!      {"camera": 1, "points": [[812.3, 402.1, 0.0, 0.0], [850.0, 402.5, 1.5, 0.0]],
//!       "e_in_ma": 91.5, "temperature_c": 27.4}]}],
//!  "offstate_views": [{"cameras": [{"camera": 0, "image": "offstate/c0_o00.png"}]}]}
//! ```
//!
//! Every view is a stage position `z_w_mm` (the board's corner (X, Y) at world (X, Y,
//! z_w_mm), as in `etlcal.dataset/1`): the stage's frame is the world frame all cameras
//! share, which is what ties them together.
//!
//! `"free_views"` (optional) are views of the same board without the stage: the board in a
//! free pose (e.g. held tilted in front of the cameras), seen at once by the cameras listed,
//! each at its own setting; points in the board's frame (`[u, v, X, Y]`, Z = 0). The board's
//! pose in the world is unknown (the rig's calibration estimates it, one pose per free view
//! shared by its cameras): they add tilted views, which the stage's nearly fronto-parallel
//! ones lack, to the extrinsics and intrinsics. The stage views stay required: they are
//! the world frame and the ETL model's depth.
//!
//! A camera entry gives exactly one of `"image"` (relative to the file, as in
//! `etlcal.dataset/1`) and `"points"`: the corners it saw as `[u, v, X, Y]` (the pixel, px,
//! and the board coordinates, mm; the world Z is the view's `z_w_mm`, 0 in a lens-off
//! view's board frame), the observations' shape without the repeated keys, so that a
//! simulation needs no images. A file gives images throughout or points throughout. The
//! lens setting is `e_in_ma` or `focal_power_dpt` ([`crate::lens_setting`]), with
//! `temperature_c` and optionally `e_com_ma`, per camera and view. A camera may be absent
//! from a view (it did not see the board there), but every camera must take part in at
//! least one stage view.
//!
//! `"offstate_board"` (optional, default `board`) is the board of the lens-off views, as in
//! `etlcal.dataset/1`: a file of images must name it for the detector when it differs.
//!
//! A camera may repeat the board (`"board"` in its entry of `"cameras"`); it must then be
//! the rig's board: one board on one stage is what the cameras share, and a camera that
//! saw another board could not be calibrated into the same world frame.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{read_json, write_json};
use crate::board::Board;
use crate::dataset::{Dataset, DatasetView, OffstateImage, SettingImage};
use crate::lens_setting::{self, SettingKind};
use crate::observations::{Observations, OffstateView, PointObs, ViewObs, PIXEL_MARGIN_IMAGES, WORLD_RANGE_MM};
use crate::{Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.rig-dataset/1";

/// One camera of the rig: a name, the image size, optionally the board it saw (which must
/// be the rig's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigDatasetCamera {
    /// A name, unique in the rig (e.g. `"left"`).
    pub name: String,
    /// Image width and height, px.
    pub image_size: [u32; 2],
    /// The board this camera saw, if the file repeats it: must equal the rig's `board`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub board: Option<Board>,
}

/// One camera's record of one stage view: its image or its points, and its lens setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigShot {
    /// The camera's index in `cameras`.
    pub camera: usize,
    /// The image, relative to the rig dataset file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<PathBuf>,
    /// The corners seen, `[u, v, X, Y]` (px, px, mm, mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<[f64; 4]>>,
    /// Commanded lens current, mA (absent, NaN here, in a focal-power view).
    #[serde(default = "lens_setting::absent", skip_serializing_if = "lens_setting::is_absent")]
    pub e_in_ma: f64,
    /// Commanded focal power, dpt (instead of `e_in_ma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_power_dpt: Option<f64>,
    /// Lens temperature, degC.
    pub temperature_c: f64,
    /// Compensated current, mA (optional; used as is when present).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e_com_ma: Option<f64>,
}

/// One stage position and what each camera that saw the board there recorded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigView {
    /// The stage position, mm.
    pub z_w_mm: f64,
    /// One entry per camera that saw the board.
    pub cameras: Vec<RigShot>,
}

/// A view of the board without the stage (module docs): one entry per camera that saw it,
/// each with its own setting; points in the board's frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigFreeView {
    /// One entry per camera that saw the board.
    pub cameras: Vec<RigShot>,
}

/// One camera's lens-off view (E = 0, the board in a free pose): its image or points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigOffstateShot {
    /// The camera's index in `cameras`.
    pub camera: usize,
    /// The image, relative to the rig dataset file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<PathBuf>,
    /// The corners seen, `[u, v, X, Y]` in the board's frame (Z = 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<[f64; 4]>>,
}

/// A set of lens-off views taken together (one per camera that took one).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigOffstateView {
    /// One entry per camera.
    pub cameras: Vec<RigOffstateShot>,
}

/// `etlcal.rig-dataset/1` (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigDataset {
    /// `"etlcal.rig-dataset/1"`.
    pub format: String,
    /// The board on the stage (and of the lens-off views).
    pub board: Board,
    /// The cameras; camera 0 is the rig's reference.
    pub cameras: Vec<RigDatasetCamera>,
    /// The stage views.
    pub views: Vec<RigView>,
    /// The board of the lens-off views when it differs from `board` (images: the detector
    /// must be told which board to look for; points carry their board coordinates).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offstate_board: Option<Board>,
    /// The lens-off views (optional: A0 may be given instead).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub offstate_views: Vec<RigOffstateView>,
    /// Views of the board in free poses, without the stage (optional; module docs).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub free_views: Vec<RigFreeView>,
}

/// What a file's camera entries carry: images or points (one kind throughout).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShotKind {
    /// Every entry gives an image.
    Images,
    /// Every entry gives points.
    Points,
}

/// One camera's part of a rig dataset as single-camera observations, with the rig's view
/// index of each of its views (its `views[i]` is the rig's `views[view_index[i]]`).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraObservations {
    /// The camera's observations (`etlcal.observations/1`).
    pub observations: Observations,
    /// The rig view of each of its ETL views.
    pub view_index: Vec<usize>,
}

/// The kind of an entry giving `image` and `points`, or the message if it gives both or
/// neither.
fn shot_kind(image: bool, points: bool) -> std::result::Result<ShotKind, &'static str> {
    match (image, points) {
        (true, false) => Ok(ShotKind::Images),
        (false, true) => Ok(ShotKind::Points),
        _ => Err("give exactly one of image and points"),
    }
}

/// Checks an entry's points: at least one, finite, pixels within
/// [`PIXEL_MARGIN_IMAGES`] of the image, board coordinates within [`WORLD_RANGE_MM`].
fn check_points(points: &[[f64; 4]], key: &str, image_size: [u32; 2]) -> Result<()> {
    if points.is_empty() {
        return Err(Error::invalid(format!("{key}.points"), format!("{key}: no points")));
    }
    let [w0, w1] = WORLD_RANGE_MM;
    for (j, p) in points.iter().enumerate() {
        let what = format!("{key}.points[{j}]");
        if let Some(&x) = p.iter().find(|x| !x.is_finite()) {
            return Err(Error::invalid_value(what, x, format!("{key} point {j} is not finite")));
        }
        for (&x, side) in p[..2].iter().zip(image_size) {
            let margin = PIXEL_MARGIN_IMAGES * f64::from(side);
            if !(-margin..=f64::from(side) + margin).contains(&x) {
                let message = format!(
                    "{key} point {j}: pixel {} px is outside the image and one image size around it",
                    crate::compact(x)
                );
                return Err(Error::invalid_value(what, x, message));
            }
        }
        if let Some(&x) = p[2..].iter().find(|x| !(w0..=w1).contains(*x)) {
            let message =
                format!("{key} point {j}: board coordinate {} mm is outside [{w0}, {w1}] mm", crate::compact(x));
            return Err(Error::invalid_value(what, x, message));
        }
    }
    Ok(())
}

impl RigDataset {
    /// An empty rig dataset of `cameras` (name, image size) on `board`.
    pub fn new(board: Board, cameras: Vec<RigDatasetCamera>) -> Self {
        RigDataset {
            format: FORMAT.into(),
            board,
            cameras,
            views: vec![],
            offstate_board: None,
            offstate_views: vec![],
            free_views: vec![],
        }
    }

    /// Reads and checks a file.
    pub fn load(path: &Path) -> Result<Self> {
        let d: RigDataset = read_json(path, FORMAT)?;
        d.validate().map_err(|e| e.within(path.display(), None))?;
        Ok(d)
    }

    /// Checks and writes the file atomically (nothing written if it fails its checks).
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate().map_err(|e| e.within(path.display(), None))?;
        write_json(path, self)
    }

    /// The checks of the cameras list: at least 2, unique non-empty names, valid image
    /// sizes, a repeated board equal to the rig's.
    fn check_cameras(&self) -> Result<()> {
        self.board.validate().map_err(|e| e.under("board"))?;
        if let Some(b) = self.offstate_board {
            b.validate().map_err(|e| e.under("offstate_board"))?;
        }
        if self.cameras.len() < 2 {
            let message = format!("cameras: a rig needs at least 2 cameras, got {}", self.cameras.len());
            return Err(Error::invalid("cameras", message));
        }
        for (k, c) in self.cameras.iter().enumerate() {
            if c.name.is_empty() || self.cameras[..k].iter().any(|o| o.name == c.name) {
                return Err(Error::invalid(
                    format!("cameras[{k}].name"),
                    format!("cameras[{k}].name: {:?} is empty or not unique", c.name),
                ));
            }
            crate::check_image_size(c.image_size, &format!("cameras[{k}].image_size"))?;
            if c.board.is_some_and(|b| b != self.board) {
                return Err(Error::invalid(
                    format!("cameras[{k}].board"),
                    format!(
                        "cameras[{k}].board: camera {:?} names another board than the rig's ({}): the cameras of a rig \
                         see one board on one stage",
                        c.name,
                        self.board.describe()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Checks an entry's camera index (`key` its path) against the cameras and the entries
    /// before it in the same view (`seen`).
    fn check_camera_index(&self, camera: usize, key: &str, seen: &mut Vec<usize>) -> Result<()> {
        let n = self.cameras.len();
        if camera >= n {
            let message = format!("{key}.camera: {camera} is not a camera of the rig (cameras 0..{})", n - 1);
            return Err(Error::invalid_value(format!("{key}.camera"), camera as f64, message));
        }
        if seen.contains(&camera) {
            let message = format!("{key}.camera: camera {camera} has two entries in one view");
            return Err(Error::invalid_value(format!("{key}.camera"), camera as f64, message));
        }
        seen.push(camera);
        Ok(())
    }

    /// Checks one stage view's entry: index, image or points, the setting.
    fn check_shot(&self, s: &RigShot, key: &str, seen: &mut Vec<usize>) -> Result<ShotKind> {
        self.check_camera_index(s.camera, key, seen)?;
        let kind = shot_kind(s.image.is_some(), s.points.is_some())
            .map_err(|m| Error::invalid(key.to_owned(), format!("{key}: {m}")))?;
        lens_setting::view_setting_kind(s.e_in_ma, s.focal_power_dpt, s.e_com_ma, |f| format!("{key}.{f}"), key)?;
        let e_in = s.focal_power_dpt.is_none().then_some(s.e_in_ma);
        let numbers = [("e_in_ma", e_in), ("temperature_c", Some(s.temperature_c)), ("e_com_ma", s.e_com_ma)];
        if let Some((field, x)) = crate::first_not_finite(numbers) {
            return Err(Error::invalid_value(format!("{key}.{field}"), x, format!("{key}.{field} is not finite")));
        }
        if let Some(p) = &s.points {
            check_points(p, key, self.cameras[s.camera].image_size)?;
        }
        Ok(kind)
    }

    /// The one check of the format, made by the reader and the writer (module docs); the
    /// message names the key.
    pub fn validate(&self) -> Result<()> {
        if self.format != FORMAT {
            return Err(Error::invalid("format", format!("format: {:?}, expected {FORMAT:?}", self.format)));
        }
        self.check_cameras()?;
        if self.views.is_empty() {
            return Err(Error::invalid("views", "views: the rig dataset holds no stage views"));
        }
        let mut kinds: Vec<(ShotKind, String)> = vec![];
        for (i, v) in self.views.iter().enumerate() {
            if !v.z_w_mm.is_finite() {
                return Err(Error::invalid_value(
                    format!("views[{i}].z_w_mm"),
                    v.z_w_mm,
                    format!("views[{i}].z_w_mm is not finite"),
                ));
            }
            if v.cameras.is_empty() {
                return Err(Error::invalid(
                    format!("views[{i}].cameras"),
                    format!("views[{i}].cameras: no camera saw view {i}"),
                ));
            }
            let mut seen = vec![];
            for (c, s) in v.cameras.iter().enumerate() {
                let key = format!("views[{i}].cameras[{c}]");
                kinds.push((self.check_shot(s, &key, &mut seen)?, key));
            }
        }
        for (i, v) in self.free_views.iter().enumerate() {
            if v.cameras.is_empty() {
                return Err(Error::invalid(
                    format!("free_views[{i}].cameras"),
                    format!("free_views[{i}].cameras: no camera saw free view {i}"),
                ));
            }
            let mut seen = vec![];
            for (c, s) in v.cameras.iter().enumerate() {
                let key = format!("free_views[{i}].cameras[{c}]");
                kinds.push((self.check_shot(s, &key, &mut seen)?, key));
            }
        }
        for (i, v) in self.offstate_views.iter().enumerate() {
            let mut seen = vec![];
            for (c, s) in v.cameras.iter().enumerate() {
                let key = format!("offstate_views[{i}].cameras[{c}]");
                self.check_camera_index(s.camera, &key, &mut seen)?;
                let kind = shot_kind(s.image.is_some(), s.points.is_some())
                    .map_err(|m| Error::invalid(key.clone(), format!("{key}: {m}")))?;
                if let Some(p) = &s.points {
                    check_points(p, &key, self.cameras[s.camera].image_size)?;
                }
                kinds.push((kind, key));
            }
        }
        if let Some((kind, key)) = kinds.iter().find(|(k, _)| *k != kinds[0].0) {
            let word = |k: ShotKind| if k == ShotKind::Images { "an image" } else { "points" };
            let message = format!(
                "{key} gives {} but {} gives {}: a rig dataset gives images throughout or points throughout",
                word(*kind),
                kinds[0].1,
                word(kinds[0].0)
            );
            return Err(Error::invalid(key.clone(), message));
        }
        for k in 0..self.cameras.len() {
            let views = self
                .views
                .iter()
                .enumerate()
                .filter_map(|(i, v)| v.cameras.iter().position(|s| s.camera == k).map(|c| (i, c, &v.cameras[c])));
            let kind_of =
                |s: &RigShot| if s.focal_power_dpt.is_some() { SettingKind::FocalPower } else { SettingKind::Current };
            let mut settings: Vec<(SettingKind, String)> =
                views.map(|(i, c, s)| (kind_of(s), format!("views[{i}].cameras[{c}]"))).collect();
            let stage_settings = settings.len();
            for (i, v) in self.free_views.iter().enumerate() {
                if let Some(c) = v.cameras.iter().position(|s| s.camera == k) {
                    settings.push((kind_of(&v.cameras[c]), format!("free_views[{i}].cameras[{c}]")));
                }
            }
            if stage_settings == 0 {
                let message = format!(
                    "cameras[{k}]: camera {:?} sees the board in none of the {} stage views: every camera must see it \
                     on the stage",
                    self.cameras[k].name,
                    self.views.len()
                );
                return Err(Error::invalid(format!("cameras[{k}]"), message));
            }
            lens_setting::common_kind(settings)?;
        }
        Ok(())
    }

    /// The board of the lens-off views: `offstate_board`, or `board` when absent.
    pub fn offstate_board(&self) -> Board {
        self.offstate_board.unwrap_or(self.board)
    }

    /// Camera `k`'s images as a single-camera `etlcal.dataset/1` (its stage views with
    /// their settings and stage positions, its lens-off views; no setting views), with the
    /// rig view of each of its views, for the single-camera detection path. Image paths
    /// stay relative to the rig dataset file (resolve them against it). Entries that give
    /// points contribute no view.
    pub fn camera_dataset(&self, k: usize) -> (Dataset, Vec<usize>) {
        let size = self.cameras.get(k).map_or([1, 1], |c| c.image_size);
        let mut d = Dataset::new(size, self.board);
        d.offstate_board = self.offstate_board;
        let mut view_index = vec![];
        for (i, v) in self.views.iter().enumerate() {
            let Some(s) = v.cameras.iter().find(|s| s.camera == k) else { continue };
            let Some(image) = &s.image else { continue };
            d.views.push(DatasetView {
                image: image.clone(),
                e_in_ma: s.e_in_ma,
                focal_power_dpt: s.focal_power_dpt,
                temperature_c: s.temperature_c,
                e_com_ma: s.e_com_ma,
                z_w_mm: v.z_w_mm,
                board: None,
                first_corner: None,
            });
            view_index.push(i);
        }
        let off = self.offstate_views.iter().filter_map(|v| v.cameras.iter().find(|s| s.camera == k));
        for image in off.filter_map(|s| s.image.clone()) {
            d.offstate_views.push(OffstateImage { image, board: None, first_corner: None });
        }
        for s in self.free_views.iter().filter_map(|v| v.cameras.iter().find(|s| s.camera == k)) {
            let Some(image) = &s.image else { continue };
            d.setting_views.push(SettingImage {
                image: image.clone(),
                e_in_ma: s.e_in_ma,
                focal_power_dpt: s.focal_power_dpt,
                temperature_c: s.temperature_c,
                e_com_ma: s.e_com_ma,
                board: None,
                first_corner: None,
            });
        }
        (d, view_index)
    }

    /// Camera `k`'s free views (module docs) as single-camera views (points with world
    /// (X, Y, 0) in the board's frame, its settings), with the index in `free_views` of
    /// each. Entries that give images contribute none.
    pub fn camera_free_views(&self, k: usize) -> (Vec<ViewObs>, Vec<usize>) {
        let mut views = vec![];
        let mut index = vec![];
        for (i, v) in self.free_views.iter().enumerate() {
            let Some(s) = v.cameras.iter().find(|s| s.camera == k) else { continue };
            let Some(points) = &s.points else { continue };
            views.push(ViewObs {
                e_in_ma: s.e_in_ma,
                focal_power_dpt: s.focal_power_dpt,
                temperature_c: s.temperature_c,
                e_com_ma: s.e_com_ma,
                points: points.iter().map(|p| PointObs { world_mm: [p[2], p[3], 0.0], pixel: [p[0], p[1]] }).collect(),
            });
            index.push(i);
        }
        (views, index)
    }

    /// Every image the file names, in the file's order (stage views, lens-off views, free
    /// views).
    pub fn images(&self) -> impl Iterator<Item = &Path> + '_ {
        let views = self.views.iter().flat_map(|v| &v.cameras).filter_map(|s| s.image.as_deref());
        let free = self.free_views.iter().flat_map(|v| &v.cameras).filter_map(|s| s.image.as_deref());
        views.chain(self.offstate_views.iter().flat_map(|v| &v.cameras).filter_map(|s| s.image.as_deref())).chain(free)
    }

    /// Whether the camera entries give images or points (the file's one kind; points for a
    /// file without entries, which [`Self::validate`] refuses).
    pub fn shot_kind(&self) -> ShotKind {
        let image = self.views.iter().flat_map(|v| &v.cameras).next().is_some_and(|s| s.image.is_some());
        if image {
            ShotKind::Images
        } else {
            ShotKind::Points
        }
    }

    /// Camera `k`'s part of a points file as single-camera observations: each view it
    /// took part in (world (X, Y, z_w_mm)) with its setting, and its lens-off views.
    /// Entries that give images (not points) contribute no view.
    pub fn camera_observations(&self, k: usize) -> CameraObservations {
        let size = self.cameras.get(k).map_or([1, 1], |c| c.image_size);
        let mut observations = Observations::new(size);
        let mut view_index = vec![];
        for (i, v) in self.views.iter().enumerate() {
            let Some(s) = v.cameras.iter().find(|s| s.camera == k) else { continue };
            let Some(points) = &s.points else { continue };
            let points = points.iter().map(|p| PointObs { world_mm: [p[2], p[3], v.z_w_mm], pixel: [p[0], p[1]] });
            observations.views.push(ViewObs {
                e_in_ma: s.e_in_ma,
                focal_power_dpt: s.focal_power_dpt,
                temperature_c: s.temperature_c,
                e_com_ma: s.e_com_ma,
                points: points.collect(),
            });
            view_index.push(i);
        }
        for v in &self.offstate_views {
            let Some(points) = v.cameras.iter().find(|s| s.camera == k).and_then(|s| s.points.as_ref()) else {
                continue;
            };
            let points = points.iter().map(|p| PointObs { world_mm: [p[2], p[3], 0.0], pixel: [p[0], p[1]] });
            observations.offstate_views.push(OffstateView { points: points.collect() });
        }
        CameraObservations { observations, view_index }
    }
}

/// `[u, v, X, Y]` rows of points whose world Z is dropped (the view's stage position or
/// the lens-off board's 0): the inverse of [`RigDataset::camera_observations`]'s mapping.
pub fn points_of(points: &[PointObs]) -> Vec<[f64; 4]> {
    points.iter().map(|p| [p.pixel[0], p.pixel[1], p.world_mm[0], p.world_mm[1]]).collect()
}

#[cfg(test)]
mod tests;
