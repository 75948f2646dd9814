//! [`remap`]: bilinear resampling of an image at the source pixels the maps name.

mod bilinear;

use super::pinhole::check_side;
use crate::error::{Error, Result};
use bilinear::{remap_block, remap_block_grey_u8, remap_pixel, Geometry, Positions, Taps, BLOCK, ROUNDER};

/// A sample type [`remap`] reads and writes: u8, u16 (grey levels) or f32.
pub trait Sample: Copy + private::Sealed {
    /// The value as f32 (exact for u8 and u16).
    fn to_f32(self) -> f32;
    /// An interpolated value back to the type: rounded to the nearest level and saturated
    /// for u8 and u16 (a bilinear mix of levels stays within them anyway), as is for f32.
    fn from_f32(v: f32) -> Self;
    /// One block of [`remap`] (etl-core's kernel; a sample type may have a faster one).
    #[doc(hidden)]
    #[inline(always)]
    fn remap_block<const C: usize>(
        src: &SourceImage<'_, Self>,
        pos: &Positions,
        maps: (&[f32], &[f32]),
        border: Self,
        taps: &mut Taps<Self, C>,
        dst: &mut [Self],
    ) {
        remap_block(src, pos, maps, border, taps, dst);
    }
}

impl Sample for u8 {
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline(always)]
    fn from_f32(v: f32) -> Self {
        // What `(v + 0.5) as u8` gives for every v (NaN to 0, saturated), in arithmetic
        // that vectorises (the saturating cast does not).
        floor_clamped(v + 0.5, 255.0) as u8
    }
    #[inline(always)]
    fn remap_block<const C: usize>(
        src: &SourceImage<'_, u8>,
        pos: &Positions,
        maps: (&[f32], &[f32]),
        border: u8,
        taps: &mut Taps<u8, C>,
        dst: &mut [u8],
    ) {
        // One channel of u8, the common case, has its own gather and blend.
        if C == 1 {
            remap_block_grey_u8(src, pos, maps, border, dst);
        } else {
            remap_block(src, pos, maps, border, taps, dst);
        }
    }
}

impl Sample for u16 {
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline(always)]
    fn from_f32(v: f32) -> Self {
        // As `(v + 0.5) as u16`, vectorisable (see u8's).
        floor_clamped(v + 0.5, 65535.0) as u16
    }
}

impl Sample for f32 {
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline(always)]
    fn from_f32(v: f32) -> Self {
        v
    }
}

/// floor(v) clamped to [0, max] (NaN to 0) for max < 2^22, branch-free: the clamped value
/// rounded to an integer by [`bilinear::ROUNDER`], less one where that rounded up.
#[inline(always)]
fn floor_clamped(v: f32, max: f32) -> i32 {
    // `max` returns the other operand when one is NaN: NaN becomes 0.
    let c = v.max(0.0).min(max);
    let r = (c + ROUNDER).to_bits() as i32 - ROUNDER.to_bits() as i32;
    r - i32::from(r as f32 > c)
}

mod private {
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
    impl Sealed for f32 {}
}

/// A read-only image: `height` rows of `width` pixels of `channels` interleaved samples
/// (1: grey; 3: e.g. RGB), packed (row `y` starts at `data[y * width * channels]`).
#[derive(Debug, Clone, Copy)]
pub struct SourceImage<'a, T: Sample> {
    data: &'a [T],
    width: usize,
    height: usize,
    channels: usize,
}

impl<'a, T: Sample> SourceImage<'a, T> {
    /// A view of `data` as `height` rows of `width` pixels of `channels` samples.
    ///
    /// Errors: a zero or too large side ([`Error::OutOfRange`] naming it), `channels` not 1
    /// or 3 ([`Error::InvalidArgument`]), `data` shorter than `width * height * channels`
    /// ([`Error::BufferTooSmall`]).
    pub fn new(data: &'a [T], width: usize, height: usize, channels: usize) -> Result<Self> {
        check_side("source image width_px", width)?;
        check_side("source image height_px", height)?;
        if channels != 1 && channels != 3 {
            return Err(Error::InvalidArgument { what: "image channels must be 1 or 3" });
        }
        // At most 2^20 * 2^20 * 3 < 2^42: no overflow.
        let needed = width * height * channels;
        if data.len() < needed {
            return Err(Error::BufferTooSmall { what: "source image", needed, got: data.len() });
        }
        Ok(SourceImage { data: &data[..needed], width, height, channels })
    }

    /// Width, px.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Height, px.
    pub fn height(&self) -> usize {
        self.height
    }
    /// Samples per pixel (1 or 3).
    pub fn channels(&self) -> usize {
        self.channels
    }
    /// The samples, exactly `width * height * channels` of them.
    pub(crate) fn data(&self) -> &'a [T] {
        self.data
    }
}

/// Resamples `src` at the maps' source pixels into `dst` (a band of output pixels): output
/// pixel i, channel c is the bilinear interpolation of `src` at `(map_x[i], map_y[i])`,
///
/// ```text
/// x0 = floor(mx), y0 = floor(my), a = mx - x0, b = my - y0,
/// dst = (1-b) ((1-a) s(x0, y0) + a s(x0+1, y0)) + b ((1-a) s(x0, y0+1) + a s(x0+1, y0+1))
/// ```
///
/// with pixel centres at integer coordinates. Border (OpenCV's default
/// `BORDER_CONSTANT`): each of the four taps outside the image reads `border` (so a pixel
/// whose source is wholly outside is `border`, and one near the edge blends into it); a
/// NaN or infinite map entry gives `border`. `dst` pixel i is
/// `dst[i * channels .. (i + 1) * channels]`. Computed in f32 (exact weights; OpenCV 5's
/// `cv2.remap` with float maps does the same, its fixed-point maps quantise the position
/// to 1/32 px).
///
/// Vectorised by blocks of 64 pixels (etl-core's `bilinear` module; at most 6 KB of stack,
/// for three f32 channels); images wider or taller than 32767 px go one pixel at a time,
/// with the same numbers.
///
/// Errors: `map_x` and `map_y` of different lengths ([`Error::InvalidArgument`]); `dst`
/// shorter than `map_x.len() * channels` ([`Error::BufferTooSmall`]). On error nothing is
/// written.
// Inlined into its callers (as `undistort_maps`), so that one running it under a wider
// instruction set compiles the kernel's vector loops for it.
#[inline(always)]
pub fn remap<T: Sample>(
    src: &SourceImage<'_, T>,
    map_x: &[f32],
    map_y: &[f32],
    border: T,
    dst: &mut [T],
) -> Result<()> {
    if map_x.len() != map_y.len() {
        return Err(Error::InvalidArgument { what: "map_x and map_y must have the same length" });
    }
    let needed = map_x.len().saturating_mul(src.channels);
    if dst.len() < needed {
        return Err(Error::BufferTooSmall { what: "dst", needed, got: dst.len() });
    }
    match src.channels {
        1 => remap_channels::<T, 1>(src, map_x, map_y, border, dst),
        _ => remap_channels::<T, 3>(src, map_x, map_y, border, dst),
    }
    Ok(())
}

/// [`remap`] with the channel count known at compile time, block by block.
#[inline(always)]
fn remap_channels<T: Sample, const C: usize>(
    src: &SourceImage<'_, T>,
    map_x: &[f32],
    map_y: &[f32],
    border: T,
    dst: &mut [T],
) {
    let Some(g) = Geometry::of(src) else {
        for ((&x, &y), out) in map_x.iter().zip(map_y).zip(dst.chunks_exact_mut(C)) {
            remap_pixel::<T, C>(src, x, y, border, out);
        }
        return;
    };
    let (mut pos, mut taps) = (Positions::new(g), Taps::<T, C>::new(border));
    // Block starts by hand: zipped `chunks` divide by their (constant) size in code that the
    // no-panic gate's size-optimised build does not inline, a division-by-zero panic path.
    for start in (0..map_x.len()).step_by(BLOCK) {
        let end = (start + BLOCK).min(map_x.len());
        let (Some(mx), Some(my), Some(out)) = (map_x.get(start..end), map_y.get(start..end), dst.get_mut(start * C..))
        else {
            return;
        };
        pos.locate(mx, my);
        T::remap_block::<C>(src, &pos, (mx, my), border, &mut taps, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth known image: s(x, y) = 3 x + 5 y + 7 (bilinear interpolation of an affine
    /// function is exact).
    fn affine(w: usize, h: usize, c: usize) -> [f32; 600] {
        let mut img = [0.0f32; 600];
        for y in 0..h {
            for x in 0..w {
                for k in 0..c {
                    img[(y * w + x) * c + k] = 3.0 * x as f32 + 5.0 * y as f32 + 7.0 + 100.0 * k as f32;
                }
            }
        }
        img
    }

    #[test]
    fn bilinear_is_exact_on_an_affine_image_one_and_three_channels() {
        let (w, h) = (20, 10);
        for c in [1, 3] {
            let img = affine(w, h, c);
            let src = SourceImage::new(&img[..w * h * c], w, h, c).unwrap();
            let mx = [0.0f32, 0.25, 18.999, 3.5, 7.125, 19.0];
            let my = [0.0f32, 0.75, 8.5, 9.0, 2.0625, 0.0];
            let mut dst = [0.0f32; 18];
            remap(&src, &mx, &my, -1.0, &mut dst).unwrap();
            for i in 0..mx.len() {
                for k in 0..c {
                    let truth = 3.0 * mx[i] + 5.0 * my[i] + 7.0 + 100.0 * k as f32;
                    assert!((dst[i * c + k] - truth).abs() < 1e-4, "{i} {k}: {} vs {truth}", dst[i * c + k]);
                }
            }
        }
    }

    #[test]
    fn border_constant_nan_and_far_outside_without_panics() {
        let img: [u8; 12] = [10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120];
        let src = SourceImage::new(&img, 4, 3, 1).unwrap();
        let mx = [f32::NAN, 0.0, -0.5, 3.5, 1e30, -1e30, f32::INFINITY, -1.0, 4.0, 1.0];
        let my = [0.0, f32::NAN, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let mut dst = [9u8; 10];
        remap(&src, &mx, &my, 0, &mut dst).unwrap();
        // Half a pixel left of (0, 0): half of 10 and half of the border 0; at x = 3.5 on
        // the last row, half of 120.
        assert_eq!(dst, [0, 0, 5, 60, 0, 0, 0, 0, 0, 60]);
        let mut dst16 = [9u16; 10];
        let img16 = img.map(|v| v as u16 * 100);
        remap(&SourceImage::new(&img16, 4, 3, 1).unwrap(), &mx, &my, 7, &mut dst16).unwrap();
        assert_eq!(dst16, [7, 7, 504, 6004, 7, 7, 7, 7, 7, 6000]);
    }

    #[test]
    fn u8_rounds_to_the_nearest_level() {
        let img: [u8; 4] = [0, 1, 0, 1];
        let src = SourceImage::new(&img, 2, 2, 1).unwrap();
        let mut dst = [0u8; 3];
        remap(&src, &[0.49, 0.51, 0.25], &[0.0, 0.0, 0.5], 0, &mut dst).unwrap();
        assert_eq!(dst, [0, 1, 0]);
    }

    #[test]
    fn bad_inputs_are_named_errors_and_write_nothing() {
        let img = [1u8; 12];
        assert!(matches!(
            SourceImage::new(&img, 0, 3, 1),
            Err(Error::OutOfRange { what: "source image width_px", .. })
        ));
        assert!(matches!(
            SourceImage::new(&img, 4, 0, 1),
            Err(Error::OutOfRange { what: "source image height_px", .. })
        ));
        assert!(matches!(SourceImage::new(&img, 2, 2, 2), Err(Error::InvalidArgument { .. })));
        assert_eq!(
            SourceImage::new(&img, 4, 2, 3).unwrap_err(),
            Error::BufferTooSmall { what: "source image", needed: 24, got: 12 }
        );
        let src = SourceImage::new(&img, 4, 3, 1).unwrap();
        let mut dst = [9u8; 2];
        assert!(matches!(remap(&src, &[0.0; 2], &[0.0; 1], 0, &mut dst), Err(Error::InvalidArgument { .. })));
        assert_eq!(
            remap(&src, &[0.0; 3], &[0.0; 3], 0, &mut dst),
            Err(Error::BufferTooSmall { what: "dst", needed: 3, got: 2 })
        );
        assert_eq!(dst, [9, 9]);
    }
}
