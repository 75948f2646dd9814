//! Grey-level image views (8- and 16-bit), the grey view of a decoded image, and the small
//! float planes the detectors work on (the checkerboard's, [`crate::checkerboard`], and
//! ChArUco's, [`crate::charuco`]).
//!
//! Grey levels are kept on the 8-bit scale (0..255) whatever the input depth, so that the
//! detector's absolute thresholds (a few grey levels of contrast) mean the same thing for
//! 8- and 16-bit images: a 16-bit value is divided by 257.

use image::{DynamicImage, ImageBuffer, Luma};
use rayon::prelude::*;

use etl_formats::{Error, Result};

/// A pixel type the detector reads.
pub trait Sample: Copy + Send + Sync + 'static {
    /// The grey level on the 8-bit scale (0..255).
    fn grey(self) -> f32;
}

impl Sample for u8 {
    #[inline(always)]
    fn grey(self) -> f32 {
        f32::from(self)
    }
}

impl Sample for f32 {
    #[inline(always)]
    fn grey(self) -> f32 {
        self
    }
}

impl Sample for u16 {
    #[inline(always)]
    fn grey(self) -> f32 {
        f32::from(self) * (1.0 / 257.0)
    }
}

/// A borrowed grey image, row-major, rows `stride` samples apart.
#[derive(Debug, Clone, Copy)]
pub struct GrayView<'a, T> {
    /// Width, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
    /// Samples between the starts of two rows (`>= width`).
    pub stride: usize,
    /// The samples; `data.len() >= (height - 1) * stride + width`.
    pub data: &'a [T],
}

impl<'a, T: Sample> GrayView<'a, T> {
    /// A view over a packed buffer (`stride == width`); `None` when `data` is too short.
    pub fn new(width: usize, height: usize, data: &'a [T]) -> Option<Self> {
        Self::with_stride(width, height, width, data)
    }

    /// A view with an explicit stride; `None` when `stride < width` or `data` is too short.
    pub fn with_stride(width: usize, height: usize, stride: usize, data: &'a [T]) -> Option<Self> {
        if stride < width {
            return None;
        }
        let need = if height == 0 || width == 0 { 0 } else { (height - 1).checked_mul(stride)?.checked_add(width)? };
        (data.len() >= need).then_some(Self { width, height, stride, data })
    }

    /// The grey level at (x, y) px ((0, 0) the centre of the top-left pixel), interpolated
    /// bilinearly; `None` outside `[0, width - 1] x [0, height - 1]`.
    #[inline]
    pub fn bilinear(&self, x: f64, y: f64) -> Option<f32> {
        if !(x >= 0.0 && y >= 0.0 && x <= (self.width - 1) as f64 && y <= (self.height - 1) as f64) {
            return None;
        }
        // The last row and column interpolate with themselves.
        let (x0, y0) =
            ((x as usize).min(self.width.saturating_sub(2)), (y as usize).min(self.height.saturating_sub(2)));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let i = y0 * self.stride + x0;
        let (dx, dy) = (usize::from(self.width > 1), if self.height > 1 { self.stride } else { 0 });
        let (a, b) = (self.data[i].grey(), self.data[i + dx].grey());
        let (c, d) = (self.data[i + dy].grey(), self.data[i + dy + dx].grey());
        let top = a + fx * (b - a);
        let bot = c + fx * (d - c);
        Some(top + fy * (bot - top))
    }
}

/// An owned single-precision image (row-major, packed).
#[derive(Debug, Clone)]
pub(crate) struct Plane {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Plane {
    #[inline(always)]
    pub fn get(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// Bilinear interpolation with the coordinates clamped into the image.
    pub fn bilinear(&self, x: f32, y: f32) -> f32 {
        let xm = (self.width - 1) as f32;
        let ym = (self.height - 1) as f32;
        let x = x.clamp(0.0, xm);
        let y = y.clamp(0.0, ym);
        let x0 = (x.floor() as usize).min(self.width.saturating_sub(2));
        let y0 = (y.floor() as usize).min(self.height.saturating_sub(2));
        let fx = x - x0 as f32;
        let fy = y - y0 as f32;
        let i = y0 * self.width + x0;
        let w = self.width;
        let a = self.data[i];
        let b = self.data[i + 1];
        let c = self.data[i + w];
        let d = self.data[i + w + 1];
        let top = a + fx * (b - a);
        let bot = c + fx * (d - c);
        top + fy * (bot - top)
    }

    /// Bilinear interpolation at a point known to be inside `[0, w-2] x [0, h-2]`.
    #[inline(always)]
    pub fn bilinear_inside(&self, x: f32, y: f32) -> f32 {
        let (x0, y0) = (x as usize, y as usize);
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let i = y0 * self.width + x0;
        let w = self.width;
        let (a, b, c, d) = (self.data[i], self.data[i + 1], self.data[i + w], self.data[i + w + 1]);
        let top = a + fx * (b - a);
        let bot = c + fx * (d - c);
        top + fy * (bot - top)
    }

    pub fn contains(&self, p: [f32; 2], margin: f32) -> bool {
        p[0] >= margin
            && p[1] >= margin
            && p[0] <= self.width as f32 - 1.0 - margin
            && p[1] <= self.height as f32 - 1.0 - margin
    }
}

/// Box-averages `factor x factor` blocks (the last partial blocks are dropped). Pixel `x`
/// of the result is centred on full-resolution `factor * x + (factor - 1) / 2`. Rows in
/// parallel (rayon).
pub(crate) fn downsample<T: Sample>(img: GrayView<'_, T>, factor: usize) -> Plane {
    let width = img.width / factor;
    let height = img.height / factor;
    let mut data = vec![0.0f32; width * height];
    if width == 0 || height == 0 {
        return Plane { width, height, data };
    }
    let norm = 1.0 / (factor * factor) as f32;
    data.par_chunks_exact_mut(width).enumerate().for_each(|(y, out)| {
        if factor == 2 {
            // The usual case (1280 x 800 to 2560 x 1600 images): one pass over two rows.
            let r0 = &img.data[2 * y * img.stride..][..2 * width];
            let r1 = &img.data[(2 * y + 1) * img.stride..][..2 * width];
            for ((o, a), b) in out.iter_mut().zip(r0.chunks_exact(2)).zip(r1.chunks_exact(2)) {
                *o = norm * ((a[0].grey() + a[1].grey()) + (b[0].grey() + b[1].grey()));
            }
            return;
        }
        for dy in 0..factor {
            let row = &img.data[(y * factor + dy) * img.stride..][..width * factor];
            if factor == 1 {
                for (o, s) in out.iter_mut().zip(row) {
                    *o += s.grey();
                }
            } else {
                for (o, block) in out.iter_mut().zip(row.chunks_exact(factor)) {
                    *o += block.iter().map(|s| s.grey()).sum::<f32>();
                }
            }
        }
        if factor > 1 {
            out.iter_mut().for_each(|o| *o *= norm);
        }
    });
    Plane { width, height, data }
}

/// Separable Gaussian smoothing (kernel radius `ceil(3 sigma)`, edges clamped). Both passes
/// are sums of shifted rows (vectorisable), rows in parallel (rayon).
pub(crate) fn gaussian(p: &Plane, sigma: f32) -> Plane {
    let r = (3.0 * sigma).ceil() as usize;
    let mut k: Vec<f32> = (0..=2 * r)
        .map(|i| {
            let x = i as f32 - r as f32;
            (-0.5 * x * x / (sigma * sigma)).exp()
        })
        .collect();
    let s: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    let (w, h) = (p.width, p.height);
    let mut tmp = vec![0.0f32; w * h];
    if w == 0 || h == 0 {
        return Plane { width: w, height: h, data: tmp };
    }
    // The padded row is a per-thread buffer: clamped ends copied, the middle memcpy'd.
    tmp.par_chunks_exact_mut(w).enumerate().for_each_init(Vec::new, |pad: &mut Vec<f32>, (y, out)| {
        let row = &p.data[y * w..(y + 1) * w];
        pad.clear();
        pad.resize(r, row[0]);
        pad.extend_from_slice(row);
        pad.resize(w + 2 * r, row[w - 1]);
        for (t, kv) in k.iter().enumerate() {
            for (o, s) in out.iter_mut().zip(&pad[t..t + w]) {
                *o += kv * s;
            }
        }
    });
    let mut data = vec![0.0f32; w * h];
    data.par_chunks_exact_mut(w).enumerate().for_each(|(y, out)| {
        for (t, kv) in k.iter().enumerate() {
            let sy = (y as isize + t as isize - r as isize).clamp(0, h as isize - 1) as usize;
            let src = &tmp[sy * w..(sy + 1) * w];
            for (o, s) in out.iter_mut().zip(src) {
                *o += kv * s;
            }
        }
    });
    Plane { width: w, height: h, data }
}

/// The grey view of an image buffer; `InvalidInput` when the buffer is shorter than its size.
pub(crate) fn view_of<T: Sample + image::Primitive>(image: &ImageBuffer<Luma<T>, Vec<T>>) -> Result<GrayView<'_, T>> {
    GrayView::new(image.width() as usize, image.height() as usize, image.as_raw())
        .ok_or_else(|| Error::invalid("image", "image buffer shorter than its size"))
}

/// Calls `at8` on the 8-bit grey view of a decoded image, or `at16` on its 16-bit one when
/// the image has 16-bit samples (converting colour to grey first).
pub(crate) fn with_grey_view<R>(
    image: &DynamicImage,
    at8: impl FnOnce(GrayView<'_, u8>) -> Result<R>,
    at16: impl FnOnce(GrayView<'_, u16>) -> Result<R>,
) -> Result<R> {
    match image {
        DynamicImage::ImageLuma8(g) => at8(view_of(g)?),
        DynamicImage::ImageLuma16(g) => at16(view_of(g)?),
        DynamicImage::ImageLumaA16(_) | DynamicImage::ImageRgb16(_) | DynamicImage::ImageRgba16(_) => {
            at16(view_of(&image.to_luma16())?)
        }
        _ => at8(view_of(&image.to_luma8())?),
    }
}
