//! A rig of N >= 2 ETL cameras at run time: the pose of each camera relative to camera 0
//! at the cameras' current settings ([`RigPose::at_settings`]), and the triangulation of a
//! point seen by K >= 2 of them, with its covariance ([`triangulate`]).
//!
//! Frames: camera k's frame at setting E_k has its origin at the projection centre where
//! the lens puts it at E_k (docs/METHOD.md, "The moving centre", Eq. C1-C3). A rig's pose
//! of camera k holds at a reference setting of both cameras (E_0,ref, E_k,ref):
//!
//! ```text
//! X_k(E_k,ref) = R_k X_0(E_0,ref) + T_k
//! ```
//!
//! Everything here is slices in, fixed-size arrays out: no allocation, no panic.
//!
//! ```
//! use etl_core::model::CameraModel;
//! use etl_core::runtime::rig::{triangulate, RigPose, TriangulationView};
//! use etl_core::runtime::Camera;
//! use etl_core::runtime::Trust;
//! let model = CameraModel::strong_distortion_rig();
//! let cam = Camera::new(model, None, [80.0, 225.0])?;
//! let (c0, c1) = (cam.at_e_com(120.0, Trust::Refuse)?, cam.at_e_com(150.0, Trust::Refuse)?);
//! // Camera 1 100 mm to the right of camera 0, turned 3 degrees towards it.
//! let pose = RigPose::from_rodrigues([0.0, -0.052, 0.0], [-100.0, 0.0, 0.0]);
//! let x0 = [20.0, -10.0, 800.0];
//! let p0 = c0.project_camera_point(x0)?;
//! let p1 = c1.project_camera_point(pose.apply(x0))?;
//! let views = [
//!     TriangulationView { camera: &c0, pose: RigPose::IDENTITY, pixel: p0 },
//!     TriangulationView { camera: &c1, pose, pixel: p1 },
//! ];
//! let t = triangulate(&views, 0.1)?;
//! assert!((0..3).all(|i| (t.point_mm[i] - x0[i]).abs() < 1e-6));
//! assert!(t.covariance_mm2[2][2].sqrt() > 0.1); // depth is the uncertain direction at 0.8 m
//! # Ok::<(), etl_core::Error>(())
//! ```

mod pose;
mod triangulate;

pub use pose::{centre_shift_mm, RigPose};
pub use triangulate::{triangulate, Triangulation, TriangulationView, MAX_ITERATIONS};
