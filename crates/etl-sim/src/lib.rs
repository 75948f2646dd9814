//! etl-sim: simulation. The synthetic camera ([`render`]: a board rendered through a camera
//! model with exact coverage, defocus and noise), the paper's rig and its noise model
//! ([`rig`], [`simulate`]) and the virtual rig of the temperature procedure
//! ([`virtual_rig`]); the printable board ([`mod@print`]: SVG at true size, exact raster).

pub mod lens_camera;
pub mod multi_camera;
pub mod optics;
pub mod print;
pub mod render;
pub mod rig;
pub mod simulate;
pub mod stereo_rig;
pub mod virtual_rig;

pub use etl_formats::{Error, Result};
