//! The bands of rows of [`super`], each run by etl-core compiled for the widest vector
//! instructions the CPU has, chosen at run time ([`pulp::Arch::dispatch`]: AVX-512, else
//! AVX2 with FMA, else the x86-64 baseline SSE2; elsewhere the target's baseline).
//!
//! Why: etl-core's maps and remap loops are written to vectorise, but a library is
//! compiled for the baseline, where a vector holds two f64 or four f32. The same loops
//! compiled for AVX-512 take the maps of a 1936 x 1458 image from 3.1 to 0.7 ms and the
//! remap from 7.5 to 5.3 ms on one core of the project's machine (docs/BENCHMARKS.md,
//! "Undistortion"). The numbers do not change: the loops are IEEE f32/f64 additions and
//! multiplications in a fixed order (Rust never fuses them into FMAs), whatever the width.
//!
//! Each band is an operation struct rather than a closure: pulp compiles `with_simd` for
//! each instruction set, and only what is inlined into it is compiled for that set. A
//! closure's body is not inlined there; `with_simd` is `#[inline(always)]`, and so are
//! the etl-core entry points it calls.

use core::ops::Range;

use etl_core::model::{Distortion, Intrinsics};
use etl_core::undistort::{OutputCamera, Sample, SourceImage};
use pulp::{Simd, WithSimd};

/// The maps of rows `rows` into a band of the caller's buffers
/// ([`etl_core::undistort::undistort_maps`]).
pub(super) struct MapsBand<'a> {
    pub k: &'a Intrinsics,
    pub d: &'a Distortion,
    pub out: &'a OutputCamera,
    pub rows: Range<usize>,
    pub map_x: &'a mut [f32],
    pub map_y: &'a mut [f32],
}

impl WithSimd for MapsBand<'_> {
    type Output = etl_core::Result<()>;
    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> Self::Output {
        etl_core::undistort::undistort_maps(self.k, self.d, self.out, self.rows, self.map_x, self.map_y)
    }
}

/// A band of output pixels resampled through stored maps ([`etl_core::undistort::remap`]).
pub(super) struct RemapBand<'a, T: Sample> {
    pub src: &'a SourceImage<'a, T>,
    pub map_x: &'a [f32],
    pub map_y: &'a [f32],
    pub border: T,
    pub dst: &'a mut [T],
}

impl<T: Sample> WithSimd for RemapBand<'_, T> {
    type Output = etl_core::Result<()>;
    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> Self::Output {
        etl_core::undistort::remap(self.src, self.map_x, self.map_y, self.border, self.dst)
    }
}

/// The maps of the band's rows into scratch buffers (each thread's own), then the band's
/// pixels through them ([`super::undistort_image`]).
pub(super) struct FusedBand<'a, T: Sample> {
    pub k: &'a Intrinsics,
    pub d: &'a Distortion,
    pub out: &'a OutputCamera,
    pub rows: Range<usize>,
    pub scratch_x: &'a mut [f32],
    pub scratch_y: &'a mut [f32],
    pub src: &'a SourceImage<'a, T>,
    pub border: T,
    pub dst: &'a mut [T],
}

impl<T: Sample> WithSimd for FusedBand<'_, T> {
    type Output = etl_core::Result<()>;
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> Self::Output {
        let n = self.rows.len() * self.out.width_px;
        let got = self.scratch_x.len().min(self.scratch_y.len());
        let (Some(map_x), Some(map_y)) = (self.scratch_x.get_mut(..n), self.scratch_y.get_mut(..n)) else {
            return Err(etl_core::Error::BufferTooSmall { what: "band scratch maps", needed: n, got });
        };
        let (k, d, out, rows) = (self.k, self.d, self.out, self.rows);
        MapsBand { k, d, out, rows, map_x: &mut *map_x, map_y: &mut *map_y }.with_simd(simd)?;
        RemapBand { src: self.src, map_x, map_y, border: self.border, dst: self.dst }.with_simd(simd)
    }
}
