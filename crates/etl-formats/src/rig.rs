//! `etlcal.rig/1`: a rig of N >= 2 cameras, each with its own calibration
//! (`etlcal.calibration/1`, inline or by a path relative to the rig file) and image size,
//! and the pose of every camera but the first relative to camera 0:
//!
//! ```text
//! X_k = R_k X_0 + T_k       (R_k = R(rotation_rodrigues), T_k = translation_mm)
//! ```
//!
//! takes a point from camera 0's frame to camera k's (`cv2.stereoCalibrate`'s R, T for the
//! pair (0, k)). Each pose may carry its 6 x 6 covariance over (rotation_rodrigues,
//! translation_mm) (rad, mm), and holds at a reference setting of both cameras
//! (`reference_setting`: camera 0's, camera k's, each in its calibration's own setting,
//! mA or dpt), required when either calibration has a moving centre (the pose then
//! follows the settings).
//!
//! ```json
//! {"format": "etlcal.rig/1",
//!  "cameras": [{"name": "left", "image_size": [1936, 1458], "calibration_path": "left.json"},
//!              {"name": "right", "image_size": [1936, 1458], "calibration": {"format": "etlcal.calibration/1", "...": "..."}}],
//!  "extrinsics": [{"camera": 1, "rotation_rodrigues": [0.01, -0.14, 0.0], "translation_mm": [-120.0, 1.5, 4.0],
//!                  "covariance": [[...6...], ...]}]}
//! ```
//!
//! A rig calibrated jointly (`etlcal calibrate-rig`) may carry `joint_covariance`:
//! `{"cameras": [0, 1, ...], "matrix": [[...]]}`, the covariance of every camera's model
//! numbers together, over the concatenation of each camera's numbers in its calibration's
//! layout order (`om1 om2 om3 tx ty tz kf.. u0 v0 a.. [dz1 dz2 u1 v1]`), camera 0 first.
//! Its meaning: the cameras' poses (om, t) in the calibrations are poses to one shared
//! world (the stage's), and the extrinsics follow from them, R_k = R(om_k) R(om_0)^T,
//! T_k = t_k - R_k t_0 ([`relative_pose`]). The reader and the writer check its size (the
//! sum of the layouts' sizes), that it is finite and symmetric with non-negative
//! variances, and that every extrinsic pose is the relative pose of the calibrations'
//! poses to 1e-9 rad and 1e-6 mm (otherwise the joint covariance does not describe this
//! rig and the file is refused, naming the key). Each calibration's own `covariance` and
//! each pose's 6 x 6 stay (a reader of one camera uses them); the cross-covariances
//! between the cameras (through the shared stage, and each camera's pose to it) are only
//! in the joint one.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{read_json, write_json};
use crate::calibration::Calibration;
use crate::{Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.rig/1";

/// One camera of a rig: its name, image size and calibration (exactly one of
/// `calibration`, inline, and `calibration_path`, relative to the rig file's directory).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigCamera {
    /// A name, unique in the rig (e.g. `"left"`).
    pub name: String,
    /// Image width and height, px (its calibration's).
    pub image_size: [u32; 2],
    /// The calibration, inline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<Box<Calibration>>,
    /// The calibration's file, relative to the rig file's directory (or absolute).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration_path: Option<PathBuf>,
}

/// The pose of camera `camera` relative to camera 0: X_k = R X_0 + T.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigExtrinsics {
    /// The camera's index in `cameras` (1..N).
    pub camera: usize,
    /// R as a Rodrigues vector, rad.
    pub rotation_rodrigues: [f64; 3],
    /// T, mm.
    pub translation_mm: [f64; 3],
    /// The covariance of (rotation_rodrigues, translation_mm), rad and mm, symmetric.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covariance: Option<[[f64; 6]; 6]>,
    /// The settings (camera 0's, this camera's) at which the pose holds, each in its
    /// calibration's setting (mA or dpt); required when either has a moving centre.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_setting: Option<[f64; 2]>,
}

/// The pose (om, T) of camera k relative to camera 0 from each camera's pose (om, t) to a
/// shared world frame (X_c = R X_w + t): R = R_k R_0', T = t_k - R t_0, so that
/// X_k = R X_0 + T (module docs).
pub fn relative_pose(zero: ([f64; 3], [f64; 3]), k: ([f64; 3], [f64; 3])) -> ([f64; 3], [f64; 3]) {
    use etl_core::model::rotation::{mat_vec, matrix_to_rodrigues, rodrigues_to_matrix, Mat3};
    let (r0, rk) = (rodrigues_to_matrix(zero.0), rodrigues_to_matrix(k.0));
    let r: Mat3 = core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|m| rk[i][m] * r0[j][m]).sum()));
    let q = mat_vec(&r, zero.1);
    (matrix_to_rodrigues(&r), [k.1[0] - q[0], k.1[1] - q[1], k.1[2] - q[2]])
}

/// `etlcal.rig/1` (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigFile {
    /// `"etlcal.rig/1"`.
    pub format: String,
    /// The cameras; camera 0 is the reference.
    pub cameras: Vec<RigCamera>,
    /// One pose per camera but camera 0.
    pub extrinsics: Vec<RigExtrinsics>,
    /// The covariance of every camera's numbers jointly, when the rig was calibrated
    /// jointly (module docs); absent, each calibration and each pose stands alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_covariance: Option<JointCovariance>,
}

/// The joint covariance of the cameras' numbers (`joint_covariance`, module docs): the
/// concatenation of each camera's model numbers in its calibration's layout order
/// (`om1 om2 om3 tx ty tz kf.. u0 v0 a.. [dz1 dz2 u1 v1]`), camera 0 first; the cameras'
/// poses (om, t) in the calibrations are poses to one shared world, and the extrinsics
/// their [`relative_pose`]s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointCovariance {
    /// The cameras whose numbers it covers, in order: every camera of the rig, 0..N.
    pub cameras: Vec<usize>,
    /// The matrix, symmetric, square of side the sum of the layouts' sizes.
    pub matrix: Vec<Vec<f64>>,
}

/// How far an extrinsic pose may be from the relative pose of the calibrations' poses
/// for the joint covariance to describe the rig: rad, mm.
pub const JOINT_POSE_TOLERANCE: (f64, f64) = (1e-9, 1e-6);

/// A rig file with every camera's calibration loaded, in the cameras' order.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    /// The file.
    pub file: RigFile,
    /// Each camera's calibration.
    pub calibrations: Vec<Calibration>,
}

/// The covariance's problem, if any: not finite, not symmetric, a negative variance.
fn covariance_problem(c: &[[f64; 6]; 6]) -> Option<&'static str> {
    let scale = (0..6).map(|i| c[i][i].abs()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    if !c.iter().flatten().all(|v| v.is_finite()) {
        return Some("is not finite");
    }
    if (0..6).any(|i| c[i][i] < 0.0) {
        return Some("has a negative variance");
    }
    if (0..6).any(|i| (0..6).any(|j| (c[i][j] - c[j][i]).abs() > 1e-9 * scale)) {
        return Some("is not symmetric");
    }
    None
}

impl RigFile {
    /// A rig of `cameras` and `extrinsics`.
    pub fn new(cameras: Vec<RigCamera>, extrinsics: Vec<RigExtrinsics>) -> Self {
        RigFile { format: FORMAT.into(), cameras, extrinsics, joint_covariance: None }
    }

    /// The pose of camera `k` relative to camera 0 (`None` for camera 0 and past the end).
    pub fn extrinsics_of(&self, k: usize) -> Option<&RigExtrinsics> {
        self.extrinsics.iter().find(|e| e.camera == k)
    }

    /// The checks that need no calibration: at least 2 cameras with unique non-empty
    /// names, one calibration source each, one pose per camera 1..N with finite numbers
    /// and a valid covariance. The message names the key.
    fn check_structure(&self) -> std::result::Result<(), String> {
        if self.cameras.len() < 2 {
            return Err(format!("cameras: a rig needs at least 2 cameras, got {}", self.cameras.len()));
        }
        for (k, c) in self.cameras.iter().enumerate() {
            if c.name.is_empty() || self.cameras[..k].iter().any(|o| o.name == c.name) {
                return Err(format!("cameras[{k}].name: {:?} is empty or not unique", c.name));
            }
            if c.calibration.is_some() == c.calibration_path.is_some() {
                return Err(format!("cameras[{k}]: give exactly one of calibration and calibration_path"));
            }
            crate::check_image_size(c.image_size, &format!("cameras[{k}].image_size")).map_err(|e| e.to_string())?;
        }
        for (i, e) in self.extrinsics.iter().enumerate() {
            if e.camera == 0 || e.camera >= self.cameras.len() {
                return Err(format!(
                    "extrinsics[{i}].camera: {} is not a camera 1..{}",
                    e.camera,
                    self.cameras.len() - 1
                ));
            }
            if self.extrinsics[..i].iter().any(|o| o.camera == e.camera) {
                return Err(format!("extrinsics[{i}].camera: camera {} has two poses", e.camera));
            }
            if !e.rotation_rodrigues.iter().chain(&e.translation_mm).all(|v| v.is_finite()) {
                return Err(format!("extrinsics[{i}]: rotation_rodrigues and translation_mm must be finite"));
            }
            if let Some(p) = e.covariance.as_ref().and_then(covariance_problem) {
                return Err(format!("extrinsics[{i}].covariance {p}"));
            }
        }
        match (1..self.cameras.len()).find(|&k| self.extrinsics_of(k).is_none()) {
            Some(k) => Err(format!("extrinsics: camera {k} ({}) has no pose", self.cameras[k].name)),
            None => Ok(()),
        }
    }

    /// Each camera's calibration, inline or read from its path (relative to the
    /// directory of `path`, the rig file), checked against its camera's image size and,
    /// with a moving centre, the pose's reference setting. The message names the key.
    fn resolve(&self, path: &Path) -> std::result::Result<Vec<Calibration>, String> {
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut out = vec![];
        for (k, c) in self.cameras.iter().enumerate() {
            let cal = match (&c.calibration, &c.calibration_path) {
                (Some(cal), _) => {
                    cal.validate(path).map_err(|e| match e {
                        Error::Parse { message, .. } => format!("cameras[{k}].calibration: {message}"),
                        e => format!("cameras[{k}].calibration: {e}"),
                    })?;
                    (**cal).clone()
                }
                (None, Some(p)) => {
                    Calibration::load(&dir.join(p)).map_err(|e| format!("cameras[{k}].calibration_path: {e}"))?
                }
                (None, None) => return Err(format!("cameras[{k}]: no calibration")),
            };
            if cal.image_size != c.image_size {
                return Err(format!(
                    "cameras[{k}].image_size: {:?} but its calibration's is {:?}",
                    c.image_size, cal.image_size
                ));
            }
            out.push(cal);
        }
        for (i, e) in self.extrinsics.iter().enumerate() {
            let moving = out[0].centre.is_some() || out[e.camera].centre.is_some();
            if moving && e.reference_setting.is_none() {
                return Err(format!(
                    "extrinsics[{i}].reference_setting: required, a camera of the pair has a moving centre"
                ));
            }
        }
        Ok(out)
    }

    /// The one check of the format, made by the reader and the writer (module docs):
    /// returns the calibrations. `path` is the rig file (its directory resolves
    /// `calibration_path`, and it names the file in the message).
    pub fn validate(&self, path: &Path) -> Result<Vec<Calibration>> {
        let bad = |message: String| Error::Parse { path: path.to_owned(), message };
        if self.format != FORMAT {
            return Err(Error::Format { path: path.to_owned(), found: self.format.clone(), expected: FORMAT.into() });
        }
        self.check_structure().map_err(bad)?;
        let calibrations = self.resolve(path).map_err(bad)?;
        self.check_joint(&calibrations).map_err(bad)?;
        Ok(calibrations)
    }

    /// The joint covariance's checks (module docs), if the file has one: every camera
    /// in order, the size the sum of the layouts', finite, symmetric, non-negative
    /// variances, and each extrinsic pose the relative pose of the calibrations' poses
    /// (to [`JOINT_POSE_TOLERANCE`]). The message names the key.
    fn check_joint(&self, calibrations: &[Calibration]) -> std::result::Result<(), String> {
        let Some(j) = &self.joint_covariance else { return Ok(()) };
        let key = "joint_covariance";
        if j.cameras != (0..calibrations.len()).collect::<Vec<_>>() {
            return Err(format!(
                "{key}.cameras: {:?}, expected every camera in order 0..{}",
                j.cameras,
                calibrations.len() - 1
            ));
        }
        let mut n = 0;
        for c in calibrations {
            n += c.layout().map_err(|e| format!("{key}: {e}"))?.len();
        }
        let m = &j.matrix;
        if m.len() != n || m.iter().any(|row| row.len() != n) {
            return Err(format!(
                "{key}.matrix: expected {n} x {n} (the sum of the cameras' layouts), got {} rows",
                m.len()
            ));
        }
        if !m.iter().flatten().all(|v| v.is_finite()) {
            return Err(format!("{key}.matrix is not finite"));
        }
        if (0..n).any(|i| m[i][i] < 0.0) {
            return Err(format!("{key}.matrix has a negative variance"));
        }
        let scale = (0..n).map(|i| m[i][i]).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        if (0..n).any(|i| (0..i).any(|k| (m[i][k] - m[k][i]).abs() > 1e-9 * scale)) {
            return Err(format!("{key}.matrix is not symmetric"));
        }
        let pose = |c: &Calibration| (c.rotation_rodrigues, c.translation_mm);
        for e in &self.extrinsics {
            let (om, t) = relative_pose(pose(&calibrations[0]), pose(&calibrations[e.camera]));
            let d_rad = (0..3).map(|i| (om[i] - e.rotation_rodrigues[i]).abs()).fold(0.0, f64::max);
            let d_mm = (0..3).map(|i| (t[i] - e.translation_mm[i]).abs()).fold(0.0, f64::max);
            if d_rad > JOINT_POSE_TOLERANCE.0 || d_mm > JOINT_POSE_TOLERANCE.1 {
                return Err(format!(
                    "{key}: camera {}'s extrinsic pose is not the relative pose of the calibrations' poses ({d_rad:.1e} rad, {d_mm:.1e} mm off): the joint covariance does not describe this rig",
                    e.camera
                ));
            }
        }
        Ok(())
    }

    /// Reads and checks a rig file, its calibrations loaded.
    pub fn load(path: &Path) -> Result<Rig> {
        let file: RigFile = read_json(path, FORMAT)?;
        let calibrations = file.validate(path)?;
        Ok(Rig { file, calibrations })
    }

    /// Checks (the calibrations it names included) and writes the file atomically: a rig
    /// whose calibration is missing is refused and nothing written.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate(path)?;
        write_json(path, self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn service() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/service/calibration.json")
    }

    /// A two-camera rig: camera 0 by path, camera 1 inline.
    fn rig(dir: &Path) -> RigFile {
        let cal = Calibration::load(&service()).unwrap();
        std::fs::copy(service(), dir.join("left.json")).unwrap();
        let size = cal.image_size;
        let mut cov = [[0.0; 6]; 6];
        for (i, row) in cov.iter_mut().enumerate() {
            row[i] = 1e-6 * (i + 1) as f64;
        }
        RigFile::new(
            vec![
                RigCamera {
                    name: "left".into(),
                    image_size: size,
                    calibration: None,
                    calibration_path: Some("left.json".into()),
                },
                RigCamera {
                    name: "right".into(),
                    image_size: size,
                    calibration: Some(Box::new(cal)),
                    calibration_path: None,
                },
            ],
            vec![RigExtrinsics {
                camera: 1,
                rotation_rodrigues: [0.01, -0.14, 0.005],
                translation_mm: [-120.0, 1.5, 4.0],
                covariance: Some(cov),
                reference_setting: None,
            }],
        )
    }

    #[test]
    fn rig_round_trips_with_calibrations_by_path_and_inline() {
        let dir = tempfile::tempdir().unwrap();
        let r = rig(dir.path());
        let path = dir.path().join("rig.json");
        r.save(&path).unwrap();
        let back = RigFile::load(&path).unwrap();
        assert_eq!(back.file, r);
        assert_eq!(back.calibrations.len(), 2);
        assert_eq!(back.calibrations[0], back.calibrations[1]);
        assert_eq!(back.file.extrinsics_of(1).unwrap().translation_mm, [-120.0, 1.5, 4.0]);
        assert!(back.file.extrinsics_of(0).is_none());
    }

    /// Each bad rig gets one line naming the key, and nothing is written.
    #[test]
    fn rig_refuses_bad_rigs_naming_the_key() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rig.json");
        type Edit = Box<dyn Fn(&mut RigFile)>;
        let cases: Vec<(Edit, &str)> = vec![
            (
                Box::new(|r| r.cameras[0].calibration_path = Some("missing.json".into())),
                "cameras[0].calibration_path: ",
            ),
            (Box::new(|r| r.cameras.truncate(1)), "cameras: a rig needs at least 2 cameras, got 1"),
            (Box::new(|r| r.cameras[1].name = "left".into()), "cameras[1].name"),
            (Box::new(|r| r.cameras[1].calibration_path = Some("left.json".into())), "cameras[1]: give exactly one"),
            (
                Box::new(|r| r.cameras[1].image_size = [640, 480]),
                "cameras[1].image_size: [640, 480] but its calibration's",
            ),
            (Box::new(|r| r.extrinsics.clear()), "extrinsics: camera 1 (right) has no pose"),
            (Box::new(|r| r.extrinsics[0].camera = 2), "extrinsics[0].camera: 2 is not a camera 1..1"),
            (Box::new(|r| r.extrinsics[0].translation_mm[0] = f64::NAN), "extrinsics[0]: rotation_rodrigues and"),
            (
                Box::new(|r| r.extrinsics[0].covariance.as_mut().unwrap()[0][1] = 1.0),
                "extrinsics[0].covariance is not symmetric",
            ),
            (
                Box::new(|r| r.extrinsics[0].covariance.as_mut().unwrap()[2][2] = -1.0),
                "covariance has a negative variance",
            ),
        ];
        for (edit, expected) in cases {
            let mut r = rig(dir.path());
            edit(&mut r);
            let e = r.save(&path).unwrap_err().to_string();
            assert!(e.contains(expected), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
            assert!(!path.exists(), "{expected}: written");
        }
    }

    /// A file on disk whose calibration went missing is refused on reading.
    #[test]
    fn rig_refuses_a_missing_calibration_on_reading() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rig.json");
        rig(dir.path()).save(&path).unwrap();
        std::fs::remove_file(dir.path().join("left.json")).unwrap();
        let e = RigFile::load(&path).unwrap_err().to_string();
        assert!(e.contains("rig.json: cameras[0].calibration_path: ") && e.contains("left.json"), "{e}");
    }

    /// With a moving centre the pose holds at one pair of settings, which the file must
    /// name.
    #[test]
    fn rig_with_a_moving_centre_needs_the_reference_setting() {
        use crate::calibration::{CentreField, ModelStd};
        use etl_core::model::MovingCentre;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rig.json");
        let mut r = rig(dir.path());
        let cal = r.cameras[1].calibration.as_mut().unwrap();
        let centre = MovingCentre { dz_mm: [1e-3, 0.0], principal_point_slope_px: [0.0, 0.0] };
        cal.centre = Some(CentreField::of(&centre, cal.principal_point));
        // Its standard deviations and covariance cover the centre's numbers too.
        cal.std = ModelStd::zero(&cal.layout().unwrap());
        cal.covariance = None;
        let e = r.save(&path).unwrap_err().to_string();
        assert!(e.contains("extrinsics[0].reference_setting: required"), "{e}");
        r.extrinsics[0].reference_setting = Some([150.0, 150.0]);
        r.save(&path).unwrap();
        assert_eq!(RigFile::load(&path).unwrap().file, r);
    }

    /// `rig` with a made-up joint covariance (diagonal plus one cross term between the
    /// cameras) and the extrinsic pose the calibrations' poses imply.
    fn joint_rig(dir: &Path) -> RigFile {
        let mut r = rig(dir);
        let cals = r.validate(&dir.join("rig.json")).unwrap();
        let pose = |c: &Calibration| (c.rotation_rodrigues, c.translation_mm);
        let (om, t) = relative_pose(pose(&cals[0]), pose(&cals[1]));
        r.extrinsics[0].rotation_rodrigues = om;
        r.extrinsics[0].translation_mm = t;
        let n = cals.iter().map(|c| c.layout().unwrap().len()).sum::<usize>();
        let mut m = vec![vec![0.0; n]; n];
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = 1e-4 * (i + 1) as f64;
        }
        m[0][n - 1] = 1e-5;
        m[n - 1][0] = 1e-5;
        r.joint_covariance = Some(JointCovariance { cameras: vec![0, 1], matrix: m });
        r
    }

    #[test]
    fn rig_round_trips_with_the_joint_covariance() {
        let dir = tempfile::tempdir().unwrap();
        let r = joint_rig(dir.path());
        let path = dir.path().join("rig.json");
        r.save(&path).unwrap();
        let back = RigFile::load(&path).unwrap();
        assert_eq!(back.file, r);
        assert!(std::fs::read_to_string(&path).unwrap().contains("\"joint_covariance\""));
    }

    /// Each bad joint covariance gets one line naming the key, and nothing is written.
    #[test]
    fn rig_refuses_a_bad_joint_covariance_naming_the_key() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rig.json");
        type Edit = Box<dyn Fn(&mut JointCovariance, &mut RigExtrinsics)>;
        let cases: Vec<(Edit, &str)> = vec![
            (Box::new(|j, _| j.matrix.truncate(3)), "joint_covariance.matrix: expected"),
            (Box::new(|j, _| j.matrix[0][1] = 1.0), "joint_covariance.matrix is not symmetric"),
            (Box::new(|j, _| j.matrix[2][2] = -1.0), "joint_covariance.matrix has a negative variance"),
            (Box::new(|j, _| j.matrix[3][3] = f64::INFINITY), "joint_covariance.matrix is not finite"),
            (Box::new(|j, _| j.cameras = vec![1, 0]), "joint_covariance.cameras: [1, 0]"),
            (Box::new(|_, e| e.translation_mm[0] += 1e-3), "joint_covariance: camera 1's extrinsic pose is not"),
            (Box::new(|_, e| e.rotation_rodrigues[2] += 1e-6), "the joint covariance does not describe this rig"),
        ];
        for (edit, expected) in cases {
            let mut r = joint_rig(dir.path());
            let mut j = r.joint_covariance.take().unwrap();
            edit(&mut j, &mut r.extrinsics[0]);
            r.joint_covariance = Some(j);
            let e = r.save(&path).unwrap_err().to_string();
            assert!(e.contains(expected), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
            assert!(!path.exists(), "{expected}: written");
        }
    }
}
