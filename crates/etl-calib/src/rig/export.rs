//! [`RigAt::export_pair`]: a rectified pair of the rig at its settings as other tools read
//! it (`etl_formats::export::stereo`): OpenCV's stereo YAML (`stereo.yaml`), a ROS stereo
//! `camera_info` pair (`left.yaml`, `right.yaml`) and one mrcal `.cameramodel` per camera
//! of the rig (`NAME.cameramodel`), whose extrinsics are rt_cam_ref with camera 0 the
//! reference: the Rodrigues vector and T_k of X_k = R_k X_0 + T_k at the settings
//! (camera 0's zeros).

use std::path::{Path, PathBuf};

use etl_core::model::rotation::matrix_to_rodrigues;
use etl_formats::export::stereo::{opencv_camera, opencv_stereo_yaml, ros_stereo_pair, OpenCvStereo};
use etl_formats::export::{mrcal_cameramodel, ExportFormat};
use etl_formats::{Error, Result};

use super::{RigAt, StereoRectification};

/// One file of an export: its name in the output directory and its text.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportFile {
    /// The file's name (`stereo.yaml`, `left.yaml`, `NAME.cameramodel`, ...).
    pub name: String,
    /// Its text.
    pub text: String,
}

impl RigAt {
    /// The files of `formats` for the rectified pair `rect` (module docs), every text made
    /// before any is written. Errors: a camera's distortion the OpenCV fit cannot take.
    pub fn export_pair(&self, rect: &StereoRectification, formats: &[ExportFormat]) -> Result<Vec<ExportFile>> {
        let [l, r] = rect.pair;
        self.check_index(l, "pair")?;
        self.check_index(r, "pair")?;
        let (cl, _, hl) = opencv_camera(&self.cameras()[l], rect.image_size)?;
        let (cr, _, hr) = opencv_camera(&self.cameras()[r], rect.image_size)?;
        let pair = OpenCvStereo {
            image_size: rect.image_size,
            cameras: [cl, cr],
            rotation: rect.rotation,
            translation_mm: rect.translation_mm,
            rectification: rect.rectification,
            rms_px: None,
        };
        let mut files = vec![];
        for format in formats {
            match format {
                ExportFormat::OpenCv => {
                    let header = format!(
                        "# left: camera {l} ({})\n{hl}# right: camera {r} ({})\n{hr}",
                        self.name(l),
                        self.name(r)
                    );
                    files.push(ExportFile { name: "stereo.yaml".into(), text: opencv_stereo_yaml(&header, &pair) });
                }
                ExportFormat::Ros => {
                    let [a, b] = ros_stereo_pair(&pair, [self.name(l), self.name(r)], [&hl, &hr]);
                    files.push(ExportFile { name: "left.yaml".into(), text: a });
                    files.push(ExportFile { name: "right.yaml".into(), text: b });
                }
                ExportFormat::Mrcal => files.extend(self.mrcal_files()?),
            }
        }
        Ok(files)
    }

    /// One `.cameramodel` per camera, extrinsics relative to camera 0 at the settings.
    fn mrcal_files(&self) -> Result<Vec<ExportFile>> {
        (0..self.len())
            .map(|k| {
                let size = self.image_size(k).unwrap_or_default();
                let (c, _, header) = opencv_camera(&self.cameras()[k], size)?;
                let pose = &self.poses()[k];
                let om = matrix_to_rodrigues(&pose.rotation);
                let t = pose.translation_mm;
                let header = format!(
                    "# camera {k} ({}) of the rig; extrinsics relative to camera 0 at these settings\n{header}",
                    self.name(k)
                );
                let text = mrcal_cameramodel(
                    &header,
                    size,
                    (&c.camera_matrix, &c.dist_coeffs),
                    [om[0], om[1], om[2], t[0], t[1], t[2]],
                );
                let name = format!("{}.cameramodel", self.name(k));
                if Path::new(&name).file_name().and_then(|n| n.to_str()) != Some(name.as_str()) {
                    let message = format!(
                        "camera {k}'s name {:?} is not a file name: the mrcal export is named after it",
                        self.name(k)
                    );
                    return Err(Error::invalid("cameras.name", message));
                }
                Ok(ExportFile { name, text })
            })
            .collect()
    }
}

/// Writes `files` into `dir` (created if missing) as one set
/// ([`etl_formats::output::write_bytes_set`]: all of them or, on any error, none
/// replaced); returns their paths.
pub fn write_files(dir: &Path, files: Vec<(String, Vec<u8>)>) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|source| etl_formats::Error::Output { path: dir.to_owned(), source })?;
    let set: Vec<(PathBuf, Vec<u8>)> = files.into_iter().map(|(name, bytes)| (dir.join(name), bytes)).collect();
    etl_formats::output::write_bytes_set(&set)?;
    Ok(set.into_iter().map(|(p, _)| p).collect())
}

/// The maps of a pair as `.npy` files (float32, image-sized: `numpy.load` then
/// `cv2.remap(image, map_x, map_y, ...)`): `left_map_x.npy`, `left_map_y.npy`,
/// `right_map_x.npy`, `right_map_y.npy`.
pub fn maps_files(maps: &super::StereoRectifyMaps) -> Result<Vec<(String, Vec<u8>)>> {
    let mut out = vec![];
    for (side, m) in [("left", &maps.left), ("right", &maps.right)] {
        let (h, w) = (m.height_px(), m.width_px());
        out.push((format!("{side}_map_x.npy"), etl_formats::npy::npy_f32(h, w, m.map_x())?));
        out.push((format!("{side}_map_y.npy"), etl_formats::npy::npy_f32(h, w, m.map_y())?));
    }
    Ok(out)
}
