//! Whole-image undistortion, parallel over bands of rows (rayon): the undistortion maps of
//! the model at one current in `cv2.remap`'s convention ([`undistort_maps`]), bilinear
//! resampling through them ([`remap`]), both at once without storing the maps
//! ([`undistort_image`]), and the maps at any current of a calibrated range, exact, within
//! the 5 ms a focus change may cost ([`FocusMaps`]).
//!
//! The work per band is etl-core's ([`etl_core::undistort`]), compiled for the widest
//! vector instructions of the CPU and chosen at run time (the `simd` module): the same
//! numbers as a single-threaded embedded caller gets, whatever the number of threads and
//! the instruction set.
//!
//! ```
//! use etl_core::model::CameraModel;
//! use etl_image::undistort::{undistort_image, undistort_maps, remap, OutputCamera, SourceImage};
//! let cam = CameraModel::paper_rig();
//! let (k, d) = (cam.intrinsics(150.0)?, cam.distortion(150.0)?);
//! let out = OutputCamera::of_intrinsics(&k, 320, 240)?;
//! let maps = undistort_maps(&k, &d, &out)?;
//! let image = vec![77u8; 320 * 240];
//! let src = SourceImage::new(&image, 320, 240, 1)?;
//! let a = remap(&src, &maps, 0)?;
//! assert_eq!(a, undistort_image(&k, &d, &out, &src, 0)?);
//! # Ok::<(), etl_image::Error>(())
//! ```

mod focus_maps;
mod rectify;
mod simd;

use etl_core::model::{Distortion, Intrinsics};
use pulp::Arch;
use rayon::prelude::*;
use simd::{FusedBand, MapsBand, RemapBand};

pub use etl_core::undistort::{OutputCamera, Sample, SourceImage};
pub use focus_maps::{FocusMaps, OutputChoice};
pub use rectify::rectify_maps;

use crate::Result;

/// Output rows per parallel task: 1458 rows make 183 tasks, enough to balance any thread
/// count, and a band's maps (16 rows of 1936 px, 248 KB) stay in the L2 cache for
/// [`undistort_image`].
pub const BAND_ROWS: usize = 16;

/// The undistortion maps of one output camera: `map_x`, `map_y` of `width_px * height_px`
/// f32 each, row-major, in `cv2.remap`'s convention (see [`etl_core::undistort`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UndistortMaps {
    width_px: usize,
    height_px: usize,
    map_x: Vec<f32>,
    map_y: Vec<f32>,
}

impl UndistortMaps {
    /// Width of the output image, px.
    pub fn width_px(&self) -> usize {
        self.width_px
    }
    /// Height of the output image, px.
    pub fn height_px(&self) -> usize {
        self.height_px
    }
    /// Source x of every output pixel, px (row-major).
    pub fn map_x(&self) -> &[f32] {
        &self.map_x
    }
    /// Source y of every output pixel, px (row-major).
    pub fn map_y(&self) -> &[f32] {
        &self.map_y
    }
    /// (map_x, map_y), moved out.
    pub fn into_parts(self) -> (Vec<f32>, Vec<f32>) {
        (self.map_x, self.map_y)
    }
}

/// The undistortion maps of the model (intrinsics `k`, distortion `d` at one current) for
/// the output camera `out`: [`etl_core::undistort::undistort_maps`] over bands of
/// [`BAND_ROWS`] rows in parallel. Exact for the model (f32 rounding: 1.2e-4 px at most
/// over a 1936 x 1458 image). Errors as the core's.
pub fn undistort_maps(k: &Intrinsics, d: &Distortion, out: &OutputCamera) -> Result<UndistortMaps> {
    let mut maps = UndistortMaps::default();
    undistort_maps_into(k, d, out, &mut maps)?;
    Ok(maps)
}

/// [`undistort_maps`] into `maps`, reusing its buffers (no allocation when the size is
/// unchanged: the per-frame path of a focus change). On error `maps` is left as it was.
/// Maps of a new size whose 8 bytes a pixel are above the memory budget
/// ([`etl_formats::memory`]) are refused before they are allocated.
pub fn undistort_maps_into(k: &Intrinsics, d: &Distortion, out: &OutputCamera, maps: &mut UndistortMaps) -> Result<()> {
    // The whole image as one band first checks every argument, without writing.
    etl_core::undistort::undistort_maps(k, d, out, 0..0, &mut [], &mut [])?;
    let (w, h) = (out.width_px, out.height_px);
    if maps.map_x.len() != w * h || maps.map_y.len() != w * h {
        // Two f32 maps: costed against the memory budget before the allocation.
        etl_formats::memory::check_memory("size", 8 * (w * h) as u64)?;
        // Fresh zeroed pages (calloc) are written once below; `resize` would fill them
        // first, touching 22 MB twice for 1936 x 1458.
        (maps.map_x, maps.map_y) = (vec![0.0; w * h], vec![0.0; w * h]);
    }
    (maps.width_px, maps.height_px) = (w, h);
    let (band, arch) = (BAND_ROWS * w, Arch::new());
    maps.map_x.par_chunks_mut(band).zip(maps.map_y.par_chunks_mut(band)).enumerate().try_for_each(
        |(i, (map_x, map_y))| {
            let rows = i * BAND_ROWS..((i + 1) * BAND_ROWS).min(h);
            arch.dispatch(MapsBand { k, d, out, rows, map_x, map_y })
        },
    )?;
    Ok(())
}

/// Resamples `src` through `maps` (bilinear, border constant `border`, NaN map entries give
/// `border`; see [`etl_core::undistort::remap()`]) over bands of rows in parallel: the
/// `maps.width_px() x maps.height_px()` output image, `src.channels()` interleaved samples
/// per pixel.
pub fn remap<T: Sample + Send + Sync>(src: &SourceImage<'_, T>, maps: &UndistortMaps, border: T) -> Result<Vec<T>> {
    let c = src.channels();
    let mut dst = vec![border; maps.map_x.len() * c];
    let (band, arch) = (BAND_ROWS * maps.width_px.max(1), Arch::new());
    dst.par_chunks_mut(band * c)
        .zip(maps.map_x.par_chunks(band).zip(maps.map_y.par_chunks(band)))
        .try_for_each(|(dst, (map_x, map_y))| arch.dispatch(RemapBand { src, map_x, map_y, border, dst }))?;
    Ok(dst)
}

/// The undistorted image of `src` (taken by the model `k`, `d` at one current) as the
/// camera `out` sees it: [`undistort_maps`] then [`remap`], band by band, without storing
/// the maps of the whole image (each thread keeps one band's maps). The same numbers as
/// the two steps.
///
/// Errors as [`undistort_maps`] and [`remap`].
pub fn undistort_image<T: Sample + Send + Sync>(
    k: &Intrinsics,
    d: &Distortion,
    out: &OutputCamera,
    src: &SourceImage<'_, T>,
    border: T,
) -> Result<Vec<T>> {
    etl_core::undistort::undistort_maps(k, d, out, 0..0, &mut [], &mut [])?;
    let (w, h, c) = (out.width_px, out.height_px, src.channels());
    let mut dst = vec![border; w * h * c];
    let arch = Arch::new();
    dst.par_chunks_mut(BAND_ROWS * w * c).enumerate().try_for_each_init(
        || (vec![0.0f32; BAND_ROWS * w], vec![0.0f32; BAND_ROWS * w]),
        |(scratch_x, scratch_y), (i, dst)| {
            let rows = i * BAND_ROWS..((i + 1) * BAND_ROWS).min(h);
            let maps = MapsBand { k, d, out, rows, map_x: scratch_x, map_y: scratch_y };
            arch.dispatch(FusedBand { maps, src, border, dst })
        },
    )?;
    Ok(dst)
}

#[cfg(test)]
mod tests;
