//! `files:DIR`: the images of a folder (PNG, TIFF, JPEG), replayed in name order, one per
//! grab: a capture rehearsed on images taken before, or a camera whose own software saves
//! files. Exposure and gain are the files' own: setting them is refused. Timestamps are
//! the files' modification times, ns since the Unix epoch. After the last image the camera
//! reports its link lost (no more frames).

use std::path::{Path, PathBuf};

use super::{Camera, CameraInfo, Frame, Pixels};
use crate::error::{Error, ErrorKind, Result};

/// A folder replayed as a camera.
pub struct FilesCamera {
    dir: PathBuf,
    files: Vec<PathBuf>,
    next: usize,
}

impl FilesCamera {
    /// The images of `dir` in name order.
    ///
    /// Errors: the folder cannot be read or holds no image.
    pub fn open(dir: &Path) -> Result<FilesCamera> {
        let name = format!("camera files:{}", dir.display());
        let entries = std::fs::read_dir(dir).map_err(|e| Error::device(&name, ErrorKind::LinkLost, e.to_string()))?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                let ext = p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
                matches!(ext.as_deref(), Some("png" | "tif" | "tiff" | "jpg" | "jpeg"))
            })
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(Error::device(&name, ErrorKind::LinkLost, "the folder holds no image (png, tif, jpg)"));
        }
        Ok(FilesCamera { dir: dir.to_owned(), files, next: 0 })
    }
}

impl Camera for FilesCamera {
    fn name(&self) -> String {
        format!("camera files:{}", self.dir.display())
    }

    fn grab(&mut self) -> Result<Frame> {
        let Some(path) = self.files.get(self.next) else {
            let message = format!("no more images: all {} of the folder were replayed", self.files.len());
            return Err(Error::device(self.name(), ErrorKind::LinkLost, message));
        };
        self.next += 1;
        let image =
            etl_image::read_image(path).map_err(|e| Error::device(self.name(), ErrorKind::Protocol, e.to_string()))?;
        let timestamp_ns = std::fs::metadata(path)
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos() as u64);
        Ok(Frame { pixels: Pixels::from_dynamic(image), timestamp_ns })
    }

    fn set_exposure_us(&mut self, _exposure_us: f64) -> Result<()> {
        Err(Error::device(self.name(), ErrorKind::Refused, "replayed files have their own exposure"))
    }

    fn set_gain_db(&mut self, _gain_db: f64) -> Result<()> {
        Err(Error::device(self.name(), ErrorKind::Refused, "replayed files have their own gain"))
    }

    fn info(&mut self) -> Result<CameraInfo> {
        let first = self.files.first().cloned().unwrap_or_default();
        let (w, h) = image::image_dimensions(&first)
            .map_err(|e| Error::device(self.name(), ErrorKind::Protocol, e.to_string()))?;
        Ok(CameraInfo {
            spec: format!("files:{}", self.dir.display()),
            model: "image files".into(),
            image_size: [w, h],
        })
    }
}
