//! The traced camera on its stage: world points to pixels through the optics, the
//! distance in focus per current, and the paper's procedure as observations.
//!
//! Frames: the camera frame is OpenCV's (x right, y down, z towards the object) with its
//! origin at the centre of the ETL's rim plane; the lens frame of the tracer is the same
//! turned by 180 degrees about x (x, -y, -z: light travels towards +z). The sensor is read
//! out upright: sensor-local (x, y) mm is pixel (c_u - x / pitch, c_v + y / pitch), with
//! (c_u, c_v) = ((W - 1) / 2, (H - 1) / 2) the sensor's centre. The world frame is the
//! stage's: the board at stage position Z lies in the plane Z_W = Z, its first inner
//! corner at (0, 0, Z); the stage axis is the optical axis turned by the procedure's
//! `stage_rotation_rodrigues`, and the board's centre at Z = 0 stands `stage_origin_mm` in
//! front of the rim plane on the axis.

use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
use etl_formats::optics::{BoardSpec, OpticsFile};
use etl_formats::Result;

use super::paraxial::{entrance_pupil, EntrancePupil};
use super::ray::V3;
use super::spot::{spot, Spot};
use super::tolerance::system_at;
use super::trace::System;
use super::OpticsError;

/// A traced rig.
#[derive(Debug, Clone, PartialEq)]
pub struct OpticalRig {
    /// Its optics file (valid).
    pub file: OpticsFile,
}

/// The rig at one current: its toleranced system and the centred system's paraxial
/// entrance pupil (which starts ray aiming).
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// The current, mA.
    pub e_ma: f64,
    /// The toleranced system.
    pub system: System,
    /// The centred system's entrance pupil.
    pub pupil: EntrancePupil,
    rings: usize,
    pitch_mm: f64,
    centre_px: [f64; 2],
}

impl Setting {
    /// The spot of a camera-frame point (mm), sensor-local.
    pub fn spot(&self, camera_mm: V3) -> std::result::Result<Spot, OpticsError> {
        spot(&self.system, lens_frame(camera_mm), self.rings, &self.pupil)
    }

    /// The pixel a corner detector sees for a camera-frame point: its spot's centroid.
    pub fn pixel(&self, camera_mm: V3) -> std::result::Result<[f64; 2], OpticsError> {
        Ok(self.to_pixel(self.spot(camera_mm)?.centroid_mm))
    }

    /// The pixel of a camera-frame point's chief ray (through the stop's centre).
    pub fn chief_pixel(&self, camera_mm: V3) -> std::result::Result<[f64; 2], OpticsError> {
        Ok(self.to_pixel(self.spot(camera_mm)?.chief_mm))
    }

    /// Sensor-local mm to pixels (see the module docs).
    pub fn to_pixel(&self, sensor_mm: [f64; 2]) -> [f64; 2] {
        [self.centre_px[0] - sensor_mm[0] / self.pitch_mm, self.centre_px[1] + sensor_mm[1] / self.pitch_mm]
    }
}

/// A camera-frame point in the lens frame: (x, -y, -z).
pub fn lens_frame(camera_mm: V3) -> V3 {
    [camera_mm[0], -camera_mm[1], -camera_mm[2]]
}

/// Golden-section steps of the focus search (the bracket shrinks 0.618 a step).
const FOCUS_STEPS: usize = 60;

impl OpticalRig {
    /// The rig of a file: checks it ([`OpticsFile::validate`]).
    pub fn new(file: OpticsFile) -> Result<Self> {
        file.validate()?;
        Ok(OpticalRig { file })
    }

    /// The rig at current `e_ma`. Errors: a singular stop image.
    pub fn at(&self, e_ma: f64) -> std::result::Result<Setting, OpticsError> {
        let f = &self.file;
        let pupil = entrance_pupil(&f.centred_surfaces(e_ma), f.stop_surface())?;
        let [w, h] = f.sensor.size_px;
        Ok(Setting {
            e_ma,
            system: system_at(f, e_ma),
            pupil,
            rings: f.procedure.fan_rings,
            pitch_mm: f.sensor.pixel_pitch_mm,
            centre_px: [(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0],
        })
    }

    /// The distance (camera z, mm) of the on-axis point whose spot on the fixed sensor is
    /// smallest (RMS radius) at `e_ma`: a golden-section search over [0.7 s, 1.4 s] about
    /// the paraxial distance s. Errors: the paraxial focus's, or a trace's.
    pub fn focus_distance_mm(&self, e_ma: f64) -> Result<f64> {
        let s = self.file.paraxial_focus_distance_mm(e_ma)?;
        let at = self.at(e_ma)?;
        let rms = |d: f64| at.spot([0.0, 0.0, d]).map(|p| p.rms_mm);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        let (mut a, mut b) = (0.7 * s, 1.4 * s);
        let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
        let (mut fc, mut fd) = (rms(c)?, rms(d)?);
        for _ in 0..FOCUS_STEPS {
            if fc < fd {
                (b, d, fd) = (d, c, fc);
                c = b - g * (b - a);
                fc = rms(c)?;
            } else {
                (a, c, fc) = (c, d, fd);
                d = a + g * (b - a);
                fd = rms(d)?;
            }
        }
        Ok(0.5 * (a + b))
    }

    /// The stage position at which the board's plane is in focus at `e_ma`: the distance
    /// in focus less `stage_origin_mm`, along the stage axis.
    pub fn stage_z_mm(&self, e_ma: f64) -> Result<f64> {
        Ok(self.stage_z_at_distance_mm(self.focus_distance_mm(e_ma)?))
    }

    /// The stage position at which the board's plane stands `distance_mm` (camera z) in
    /// front, along the stage axis: for a distance in focus already found.
    pub fn stage_z_at_distance_mm(&self, distance_mm: f64) -> f64 {
        let axis = mat_vec(&rodrigues_to_matrix(self.file.procedure.stage_rotation_rodrigues), [0.0, 0.0, 1.0]);
        (distance_mm - self.file.procedure.stage_origin_mm) / axis[2]
    }

    /// The stage's pose, world to camera: (Rodrigues, translation mm); a world point is
    /// R p + t.
    pub fn stage_pose(&self) -> ([f64; 3], [f64; 3]) {
        let p = &self.file.procedure;
        let r = rodrigues_to_matrix(p.stage_rotation_rodrigues);
        let c = mat_vec(&r, board_centre_mm(&p.board));
        (p.stage_rotation_rodrigues, [-c[0], -c[1], p.stage_origin_mm - c[2]])
    }

    /// A world point in the camera frame.
    pub fn world_to_camera(&self, world_mm: V3) -> V3 {
        let (om, t) = self.stage_pose();
        let p = mat_vec(&rodrigues_to_matrix(om), world_mm);
        [p[0] + t[0], p[1] + t[1], p[2] + t[2]]
    }
}

/// The board's centre in its frame (first inner corner at the origin), mm.
pub fn board_centre_mm(b: &BoardSpec) -> V3 {
    let [c, r] = b.inner_corners;
    [b.square_mm * (c - 1) as f64 / 2.0, b.square_mm * (r - 1) as f64 / 2.0, 0.0]
}
