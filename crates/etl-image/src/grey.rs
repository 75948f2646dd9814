//! Grey-level image views (8- and 16-bit), the grey view of a decoded image, and the small
//! float planes the detectors work on (the checkerboard's, [`crate::checkerboard`], and
//! ChArUco's, [`crate::charuco`]).
//!
//! Grey levels are kept on the 8-bit scale (0..255) whatever the input depth, so that the
//! detector's absolute thresholds (a few grey levels of contrast) mean the same thing for
//! 8- and 16-bit images: a 16-bit value is divided by 257.

use std::sync::{Mutex, MutexGuard, TryLockError};

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

/// An owned single-precision image (row-major, packed). Its buffer goes back to the spare
/// buffers ([`take_buffer`]) when it is dropped.
#[derive(Debug, Clone)]
pub(crate) struct Plane {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Drop for Plane {
    fn drop(&mut self) {
        give_back(std::mem::take(&mut self.data));
    }
}

/// The float buffers of dropped planes, kept for the next detection. Without them every
/// detection allocated its planes (a few hundred KB to a few MB each) afresh, from the
/// arena of whichever rayon worker ran it, and glibc trimmed that arena's top when they
/// were freed: the second detection of a 640 x 480 image in a fresh process page-faulted
/// 374 times (1.6 ms against 0.9 ms warm), the third ~120 times. Shared by all threads,
/// so the buffers follow the work to whichever worker runs it.
static SPARE: Mutex<Vec<Vec<f32>>> = Mutex::new(Vec::new());
/// At most this many spare buffers (a detection holds two or three planes at a time)...
const SPARE_BUFFERS: usize = 4;
/// ...of at most this many bytes in all (a 1936 x 1458 image's planes are 2.8 MB each).
const SPARE_BYTES: usize = 32 << 20;

/// The spare buffers, or `None` while another thread holds them: the caller then
/// allocates (or frees) as if there were none rather than wait, and a process forked
/// while one of its threads held them (a thread the child does not have) never blocks.
fn spare() -> Option<MutexGuard<'static, Vec<Vec<f32>>>> {
    match SPARE.try_lock() {
        Ok(g) => Some(g),
        Err(TryLockError::Poisoned(p)) => Some(p.into_inner()),
        Err(TryLockError::WouldBlock) => None,
    }
}

/// A buffer of `n` samples whose values are unspecified (zeros, or a dropped plane's):
/// the caller writes every one. The smallest spare buffer that holds `n`, else a new
/// zeroed one (`calloc`: its pages are not touched until written).
fn take_buffer(n: usize) -> Vec<f32> {
    let Some(mut spare) = spare().filter(|_| n > 0) else { return vec![0.0; n] };
    let fits = spare.iter().enumerate().filter(|(_, b)| b.capacity() >= n).min_by_key(|(_, b)| b.capacity());
    let Some((i, _)) = fits else {
        drop(spare);
        return vec![0.0; n];
    };
    let mut b = spare.swap_remove(i);
    drop(spare);
    b.truncate(n);
    b.resize(n, 0.0);
    b
}

/// Keeps a dropped plane's buffer for [`take_buffer`]; the smallest go when there are
/// too many (a larger image's planes replace a smaller one's).
fn give_back(b: Vec<f32>) {
    let bytes = |b: &Vec<f32>| b.capacity() * std::mem::size_of::<f32>();
    if b.capacity() == 0 || bytes(&b) > SPARE_BYTES {
        return;
    }
    let Some(mut spare) = spare() else { return };
    spare.push(b);
    let mut evicted = Vec::new();
    while spare.len() > SPARE_BUFFERS || spare.iter().map(bytes).sum::<usize>() > SPARE_BYTES {
        let smallest = (0..spare.len()).min_by_key(|&i| spare[i].capacity()).unwrap_or(0);
        evicted.push(spare.swap_remove(smallest));
    }
    // Freed after the lock is released.
    drop(spare);
    drop(evicted);
}

/// Adds `count` spare buffers of `n` samples, their pages touched now: the first
/// detection of a process whose planes fit them then faults on no fresh page (a fault
/// costs ~1 us on the 2-core VM of the benchmarks: 150 of them were a third of the first
/// 640 x 480 detection's extra cost).
pub(crate) fn reserve(n: usize, count: usize) {
    for _ in 0..count.min(SPARE_BUFFERS) {
        // Hidden from the optimiser, which would drop the writes of zeros to memory
        // allocated zeroed: the writes are the point.
        let mut b = std::hint::black_box(vec![0.0f32; n]);
        b.fill(0.0);
        give_back(b);
    }
}

impl Plane {
    /// A plane of zeros.
    pub fn zeros(width: usize, height: usize) -> Self {
        let mut data = take_buffer(width * height);
        data.fill(0.0);
        Self { width, height, data }
    }

    /// A plane whose values are unspecified (zeros or a dropped plane's values): for a
    /// caller that writes every pixel, as it saves clearing a reused buffer.
    pub fn scratch(width: usize, height: usize) -> Self {
        Self { width, height, data: take_buffer(width * height) }
    }

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
    let mut p = Plane::zeros(img.width / factor, img.height / factor);
    let width = p.width;
    if width == 0 || p.height == 0 {
        return p;
    }
    p.data.par_chunks_exact_mut(width).enumerate().for_each(|(y, out)| downsample_row(img, factor, y, out));
    p
}

/// Row `y` of [`downsample`] into `out` (`width / factor` samples, zeros on entry).
#[inline]
fn downsample_row<T: Sample>(img: GrayView<'_, T>, factor: usize, y: usize, out: &mut [f32]) {
    let width = out.len();
    let norm = 1.0 / (factor * factor) as f32;
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
}

/// The image box-downsampled by `factor` ([`downsample`]) and smoothed by a separable
/// Gaussian (kernel radius `ceil(3 sigma)`, edges clamped): bit for bit the smoothing of
/// [`downsample`]'s plane, without that plane. Each row of the horizontal pass is
/// downsampled into its padded buffer, so that the first detection of a process touches
/// two fresh planes (this one and the horizontal pass's, which the saddle response then
/// reuses), not four: page faults were most of that first call's extra cost.
/// Both passes are sums of shifted rows (vectorisable), rows in parallel (rayon).
pub(crate) fn smoothed_level<T: Sample>(img: GrayView<'_, T>, factor: usize, sigma: f32) -> Plane {
    let r = (3.0 * sigma).ceil() as usize;
    let mut k: Vec<f32> = (0..=2 * r)
        .map(|i| {
            let x = i as f32 - r as f32;
            (-0.5 * x * x / (sigma * sigma)).exp()
        })
        .collect();
    let s: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    let (w, h) = (img.width / factor, img.height / factor);
    let mut tmp = Plane::scratch(w, h);
    if w == 0 || h == 0 {
        return tmp;
    }
    // The padded row is a per-thread buffer: the downsampled row, its ends repeated.
    tmp.data.par_chunks_exact_mut(w).enumerate().for_each_init(Vec::new, |pad: &mut Vec<f32>, (y, out)| {
        pad.clear();
        pad.resize(w + 2 * r, 0.0);
        downsample_row(img, factor, y, &mut pad[r..r + w]);
        let (first, last) = (pad[r], pad[r + w - 1]);
        pad[..r].fill(first);
        pad[r + w..].fill(last);
        convolve(&k, |t| &pad[t..t + w], out);
    });
    let mut smooth = Plane::scratch(w, h);
    smooth.data.par_chunks_exact_mut(w).enumerate().for_each(|(y, out)| {
        convolve(
            &k,
            |t| {
                let sy = (y as isize + t as isize - r as isize).clamp(0, h as isize - 1) as usize;
                &tmp.data[sy * w..(sy + 1) * w]
            },
            out,
        );
    });
    smooth
}

/// `out = sum_t k[t] * src(t)`, summed in the order of `t` starting from `0.0` (the sums a
/// cleared `out` accumulated before, to the bit). Every sample of `out` is written and
/// none read, so `out` need not be cleared, and its fresh pages fault once (a write), not
/// twice (a read of the shared zero page, then a write) as they did when accumulated
/// into a freshly `calloc`ed plane.
#[inline]
fn convolve<'a>(k: &[f32], src: impl Fn(usize) -> &'a [f32], out: &mut [f32]) {
    for (o, s) in out.iter_mut().zip(src(0)) {
        *o = 0.0 + k[0] * s;
    }
    for (t, kv) in k.iter().enumerate().skip(1) {
        for (o, s) in out.iter_mut().zip(src(t)) {
            *o += kv * s;
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A pseudo-random `w x h` 8-bit image.
    fn noise(w: usize, h: usize, seed: u32) -> Vec<u8> {
        let mut x = seed;
        (0..w * h)
            .map(|_| {
                x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (x >> 24) as u8
            })
            .collect()
    }

    /// The smoothing as it was computed before [`smoothed_level`]: [`downsample`]'s plane,
    /// then each pass accumulated into cleared rows, one row at a time.
    fn reference(img: GrayView<'_, u8>, factor: usize, sigma: f32) -> Vec<f32> {
        let p = downsample(img, factor);
        let (w, h) = (p.width, p.height);
        let r = (3.0 * sigma).ceil() as usize;
        let mut k: Vec<f32> = (0..=2 * r)
            .map(|i| (i as f32 - r as f32, sigma * sigma))
            .map(|(x, s2)| (-0.5 * x * x / s2).exp())
            .collect();
        let s: f32 = k.iter().sum();
        k.iter_mut().for_each(|v| *v /= s);
        let mut tmp = vec![0.0f32; w * h];
        for y in 0..h {
            let row = &p.data[y * w..(y + 1) * w];
            let pad: Vec<f32> = std::iter::repeat_n(row[0], r)
                .chain(row.iter().copied())
                .chain(std::iter::repeat_n(row[w - 1], r))
                .collect();
            for (t, kv) in k.iter().enumerate() {
                for (o, s) in tmp[y * w..(y + 1) * w].iter_mut().zip(&pad[t..t + w]) {
                    *o += kv * s;
                }
            }
        }
        let mut out = vec![0.0f32; w * h];
        for y in 0..h {
            for (t, kv) in k.iter().enumerate() {
                let sy = (y as isize + t as isize - r as isize).clamp(0, h as isize - 1) as usize;
                for (o, s) in out[y * w..(y + 1) * w].iter_mut().zip(&tmp[sy * w..(sy + 1) * w]) {
                    *o += kv * s;
                }
            }
        }
        out
    }

    #[test]
    fn smoothed_level_is_the_smoothing_of_the_downsampled_plane_bit_for_bit() {
        let (w, h) = (83, 61);
        let (a, b) = (noise(w, h, 1), noise(w, h, 2));
        let (a, b) = (GrayView::new(w, h, &a).unwrap(), GrayView::new(w, h, &b).unwrap());
        for factor in [1, 2, 3, 4] {
            let want: Vec<u32> = reference(a, factor, 1.5).iter().map(|v| v.to_bits()).collect();
            // Again after another image's planes were dropped: reused buffers hold its values.
            for _ in 0..2 {
                let got = smoothed_level(a, factor, 1.5);
                assert_eq!((got.width, got.height), (w / factor, h / factor));
                assert_eq!(got.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want, "factor {factor}");
                drop(smoothed_level(b, factor, 1.5));
            }
        }
    }
}
