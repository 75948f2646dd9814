//! [`rectify_maps`]: a stereo pair's rectification maps of one camera, over bands of rows
//! in parallel.

use etl_core::model::rotation::Mat3;
use etl_core::model::{Distortion, Intrinsics};
use rayon::prelude::*;

use super::{OutputCamera, UndistortMaps, BAND_ROWS};
use crate::Result;

/// The maps of the rectified camera `out` turned by `rotation` (R1 or R2) from the camera
/// of intrinsics `k` and distortion `d` at one setting, in `cv2.remap`'s convention
/// ([`etl_core::undistort::rectify_maps`]: exactly the model's projection of each rectified
/// ray, f32-rounded; NaN where the ray is behind the camera), bands of [`BAND_ROWS`] rows
/// in parallel. Errors as the core's; maps above the memory budget
/// ([`etl_formats::memory`]) are refused before they are allocated.
pub fn rectify_maps(k: &Intrinsics, d: &Distortion, rotation: &Mat3, out: &OutputCamera) -> Result<UndistortMaps> {
    // The whole image as one band first checks every argument, without writing.
    etl_core::undistort::rectify_maps(k, d, rotation, out, 0..0, &mut [], &mut [])?;
    let (w, h) = (out.width_px, out.height_px);
    etl_formats::memory::check_memory("size", 8 * (w * h) as u64)?;
    let (mut map_x, mut map_y) = (vec![0.0f32; w * h], vec![0.0f32; w * h]);
    let band = BAND_ROWS * w.max(1);
    map_x.par_chunks_mut(band).zip(map_y.par_chunks_mut(band)).enumerate().try_for_each(|(i, (mx, my))| {
        let rows = i * BAND_ROWS..((i + 1) * BAND_ROWS).min(h);
        etl_core::undistort::rectify_maps(k, d, rotation, out, rows, mx, my)
    })?;
    Ok(UndistortMaps { width_px: w, height_px: h, map_x, map_y })
}
