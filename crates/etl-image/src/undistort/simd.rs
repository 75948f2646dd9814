//! The bands of rows of [`super`], each run by etl-core compiled for the widest vector
//! instructions the CPU has, chosen at run time ([`pulp::Arch::dispatch`]: AVX-512, else
//! AVX2 with FMA, else the x86-64 baseline SSE2; elsewhere the target's baseline).
//!
//! Why: etl-core's maps and remap loops are written to vectorise, but a library is
//! compiled for the baseline, where a vector holds two f64 or four f32. The same loops
//! compiled for AVX-512 take the maps of a 1936 x 1458 image from 3.1 to 0.7 ms and the
//! remap from 7.5 to 5.3 ms on one core of the project's machine (docs/PERFORMANCE-HISTORY.md,
//! "Undistortion"). The numbers do not change: the loops are IEEE f32/f64 additions and
//! multiplications in a fixed order (Rust never fuses them into FMAs), whatever the width.
//!
//! Each band is an operation struct rather than a closure: pulp compiles `with_simd` for
//! each instruction set, and only what is inlined into it is compiled for that set. A
//! closure's body is not inlined there; `with_simd` is `#[inline(always)]`, and so are
//! the etl-core entry points it calls.

use core::ops::Range;

use etl_core::model::{Distortion, Intrinsics};
use etl_core::undistort::{remap, undistort_maps, OutputCamera, Sample, SourceImage};
use pulp::{Simd, WithSimd};

/// Implements [`WithSimd`] for a band (its generic parameters in brackets): `with_simd` runs the body on the band (`$band`) with
/// the instruction set's token (`$simd`), `#[inline(always)]` so that the body is compiled
/// for each instruction set (see the module docs); one band's failure is etl-core's error.
macro_rules! band {
    ([$($generics:tt)*] $band_type:ty, |$band:ident, $simd:ident| $body:expr) => {
        impl<$($generics)*> WithSimd for $band_type {
            type Output = etl_core::Result<()>;
            #[inline(always)]
            fn with_simd<S: Simd>(self, $simd: S) -> Self::Output {
                let $band = self;
                $body
            }
        }
    };
}

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

band!([] MapsBand<'_>, |b, _simd| undistort_maps(b.k, b.d, b.out, b.rows, b.map_x, b.map_y));

/// A band of output pixels resampled through stored maps ([`etl_core::undistort::remap`]).
pub(super) struct RemapBand<'a, T: Sample> {
    pub src: &'a SourceImage<'a, T>,
    pub map_x: &'a [f32],
    pub map_y: &'a [f32],
    pub border: T,
    pub dst: &'a mut [T],
}

band!([T: Sample] RemapBand<'_, T>, |b, _simd| remap(b.src, b.map_x, b.map_y, b.border, b.dst));

/// The maps of the band's rows into scratch buffers (each thread's own), then the band's
/// pixels through them ([`super::undistort_image`]).
pub(super) struct FusedBand<'a, T: Sample> {
    /// The band's rows, with the scratch buffers as its maps (longer than the band needs
    /// for the last, shorter band).
    pub maps: MapsBand<'a>,
    pub src: &'a SourceImage<'a, T>,
    pub border: T,
    pub dst: &'a mut [T],
}

band!([T: Sample] FusedBand<'_, T>, |band, simd| {
    let MapsBand { k, d, out, rows, map_x: scratch_x, map_y: scratch_y } = band.maps;
    let n = rows.len() * out.width_px;
    let got = scratch_x.len().min(scratch_y.len());
    let (Some(map_x), Some(map_y)) = (scratch_x.get_mut(..n), scratch_y.get_mut(..n)) else {
        return Err(etl_core::Error::BufferTooSmall { what: "band scratch maps", needed: n, got });
    };
    MapsBand { k, d, out, rows, map_x: &mut *map_x, map_y: &mut *map_y }.with_simd(simd)?;
    RemapBand { src: band.src, map_x, map_y, border: band.border, dst: band.dst }.with_simd(simd)
});
