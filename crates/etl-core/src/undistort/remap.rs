//! [`remap`]: bilinear resampling of an image at the source pixels the maps name.

use super::camera::check_side;
use crate::error::{Error, Result};

/// A sample type [`remap`] reads and writes: u8, u16 (grey levels) or f32.
pub trait Sample: Copy + private::Sealed {
    /// The value as f32 (exact for u8 and u16).
    fn to_f32(self) -> f32;
    /// An interpolated value back to the type: rounded to the nearest level and saturated
    /// for u8 and u16 (a bilinear mix of levels stays within them anyway), as is for f32.
    fn from_f32(v: f32) -> Self;
}

impl Sample for u8 {
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline(always)]
    fn from_f32(v: f32) -> Self {
        // `as` saturates (and maps NaN to 0): no panic on any value.
        (v + 0.5) as u8
    }
}

impl Sample for u16 {
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline(always)]
    fn from_f32(v: f32) -> Self {
        (v + 0.5) as u16
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
/// `dst[i * channels .. (i + 1) * channels]`. Computed in f32 (exact weights, not
/// OpenCV's 1/32 px table: the two agree to within the gradient times 1/64 px).
///
/// Errors: `map_x` and `map_y` of different lengths ([`Error::InvalidArgument`]); `dst`
/// shorter than `map_x.len() * channels` ([`Error::BufferTooSmall`]). On error nothing is
/// written.
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

/// [`remap`] with the channel count known at compile time (so the inner loop unrolls).
fn remap_channels<T: Sample, const C: usize>(
    src: &SourceImage<'_, T>,
    mx: &[f32],
    my: &[f32],
    border: T,
    dst: &mut [T],
) {
    let (w, h) = (src.width, src.height);
    // Bounds as f32 (exact: sides are at most 2^20). A map entry in [0, w - 1) x [0, h - 1)
    // has its four taps inside; one in (-1, w) x (-1, h) has at least one.
    let (wf, hf) = (w as f32, h as f32);
    let (w1, h1) = ((w - 1) as f32, (h - 1) as f32);
    let stride = w * C;
    let data = src.data;
    for ((&x, &y), out) in mx.iter().zip(my).zip(dst.chunks_exact_mut(C)) {
        if x >= 0.0 && y >= 0.0 && x < w1 && y < h1 {
            // Inside: 0 <= x, y < 2^20, so the i32 conversion is floor, exact.
            let (x0, y0) = (x as i32 as usize, y as i32 as usize);
            let (a, b) = (x - x0 as f32, y - y0 as f32);
            let i = y0 * stride + x0 * C;
            // The four taps are inside since x0 + 1 < w and y0 + 1 < h; `get` keeps that a
            // checked fact rather than a panic path (the branch is never taken).
            let tap = |j: usize| data.get(j).map_or(0.0, |s| s.to_f32());
            for (c, o) in out.iter_mut().enumerate() {
                let (s00, s01) = (tap(i + c), tap(i + C + c));
                let (s10, s11) = (tap(i + stride + c), tap(i + stride + C + c));
                let top = s00 + a * (s01 - s00);
                let bot = s10 + a * (s11 - s10);
                *o = T::from_f32(top + b * (bot - top));
            }
        } else if x > -1.0 && y > -1.0 && x < wf && y < hf {
            edge_pixel::<T, C>(data, w, h, x, y, border, out);
        } else {
            // Wholly outside, NaN or infinite.
            out.fill(border);
        }
    }
}

/// A pixel whose 2 x 2 neighbourhood straddles the image edge: taps outside read `border`.
/// Precondition: -1 < x < w, -1 < y < h.
#[inline(never)]
fn edge_pixel<T: Sample, const C: usize>(data: &[T], w: usize, h: usize, x: f32, y: f32, border: T, out: &mut [T]) {
    let (xf, yf) = (libm::floorf(x), libm::floorf(y));
    let (a, b) = (x - xf, y - yf);
    // xf, yf in [-1, w - 1], [-1, h - 1]: the casts are exact.
    let (x0, y0) = (xf as isize, yf as isize);
    let tap = |xi: isize, yi: isize, c: usize| -> f32 {
        if xi < 0 || yi < 0 || xi as usize >= w || yi as usize >= h {
            border.to_f32()
        } else {
            data.get((yi as usize * w + xi as usize) * C + c).map_or(border.to_f32(), |s| s.to_f32())
        }
    };
    for (c, o) in out.iter_mut().enumerate() {
        let top = tap(x0, y0, c) + a * (tap(x0 + 1, y0, c) - tap(x0, y0, c));
        let bot = tap(x0, y0 + 1, c) + a * (tap(x0 + 1, y0 + 1, c) - tap(x0, y0 + 1, c));
        *o = T::from_f32(top + b * (bot - top));
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
