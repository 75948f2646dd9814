//! A physical ETL camera: a sequential ray tracer with real refraction, an electrically
//! tunable lens (a liquid-filled membrane lens) in front of a prime lens of a published
//! prescription, an aperture stop, ray aiming through it, and the image of a point as the
//! centroid of a ray fan over the pupil (what a corner detector sees), read out on a pixel
//! grid; the paper's calibration procedure traced through it (`etlcal simulate --optics`).
//!
//! The rig is described by an `etlcal.optics/1` file ([`etl_formats::optics`], which
//! defines the geometry: the ETL's power law and its membrane's sag, the surfaces, the
//! stop, the sensor, the tolerances and the procedure). Here it is traced:
//! - [`ray`], [`surface`], [`trace`]: rays, surfaces in their own frames (intersection
//!   without cancellation, vector Snell's law), the sequential trace with typed errors
//!   naming the surface ([`OpticsError`]);
//! - [`etl`]: the ETL's closed forms (lensmaker's power, the thin-lens pupil shift);
//! - [`prime`]: the published prime lenses, scaled to a focal length;
//! - [`paraxial`]: focal length, back focus and entrance pupil from the y-nu trace;
//! - [`aim`]: ray aiming through the stop (Newton's method on the stop coordinates);
//! - [`spot`]: the fan over the stop, its centroid and RMS radius, the chief ray;
//! - [`tolerance`]: the toleranced system (decentred, tilted ETL and sensor);
//! - [`rig`]: the camera on its stage: world points to pixels, the distance in focus per
//!   current;
//! - [`procedure`]: the paper's procedure traced, as `etlcal.observations/1`;
//! - [`truth`]: what the rig is at each current (focal length, entrance pupil, focus);
//! - [`multi_camera`]: N traced cameras on one stage, as an `etlcal.rig-dataset/1`.
//!
//! All numbers are f64, lengths in mm.

pub mod aim;
pub mod etl;
pub mod multi_camera;
pub mod paraxial;
pub mod prime;
pub mod procedure;
pub mod ray;
pub mod rig;
pub mod spot;
pub mod surface;
pub mod tolerance;
pub mod trace;
pub mod truth;

pub use rig::OpticalRig;

/// Why a ray could not be traced, or the optics not be built; each names the surface.
#[derive(Debug, Clone, PartialEq)]
pub enum OpticsError {
    /// The ray does not meet the surface (it passes beside a sphere, or runs parallel to a
    /// plane).
    Missed {
        /// The surface's name in the optics file.
        surface: String,
    },
    /// The ray meets the surface outside its clear aperture.
    Blocked {
        /// The surface's name.
        surface: String,
        /// The ray's height there, mm.
        height_mm: f64,
        /// The surface's semi-diameter, mm.
        semi_diameter_mm: f64,
    },
    /// Total internal reflection at the surface.
    TotalInternalReflection {
        /// The surface's name.
        surface: String,
    },
    /// Ray aiming did not bring the ray to its target on the stop.
    StopMissed {
        /// The stop's name.
        surface: String,
        /// The distance left between the ray and its target, mm.
        residual_mm: f64,
    },
    /// The optics are singular: afocal, or no object plane in focus.
    Singular {
        /// What is singular.
        what: String,
    },
}

impl std::fmt::Display for OpticsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OpticsError::Missed { surface } => write!(f, "the ray misses {surface}"),
            OpticsError::Blocked { surface, height_mm, semi_diameter_mm } => write!(
                f,
                "the ray meets {surface} at {height_mm:.4} mm from its axis, outside its semi-diameter {semi_diameter_mm} mm"
            ),
            OpticsError::TotalInternalReflection { surface } => write!(f, "total internal reflection at {surface}"),
            OpticsError::StopMissed { surface, residual_mm } => {
                write!(f, "ray aiming does not reach its point on {surface} (left {residual_mm:.3e} mm off)")
            }
            OpticsError::Singular { what } => write!(f, "singular optics: {what}"),
        }
    }
}

impl std::error::Error for OpticsError {}

impl From<OpticsError> for etl_formats::Error {
    fn from(e: OpticsError) -> Self {
        let what = match &e {
            OpticsError::Missed { surface }
            | OpticsError::Blocked { surface, .. }
            | OpticsError::TotalInternalReflection { surface }
            | OpticsError::StopMissed { surface, .. } => surface.clone(),
            OpticsError::Singular { .. } => "optics".to_owned(),
        };
        etl_formats::Error::invalid(what, e.to_string())
    }
}
