//! Defocus: thin-lens blur and the spatially varying Gaussian that applies it.
//!
//! A thin lens with aperture diameter A focused on the plane at depth Z_f images a point at
//! depth Z into a disc (the circle of confusion) of diameter, on the sensor,
//! c = A v |1/Z - 1/Z_f|, where v is the image distance. In pixels v is the focal length
//! f_px of the pinhole model (fx(E) of Eq. 16), so the blur grows with the dioptric
//! distance between the point and the plane in focus:
//!
//! ```text
//! c_px = A_mm * f_px * |1/Z_mm - 1/Z_f_mm|,   sigma_px = c_px / 4
//! ```
//!
//! The disc is replaced by the Gaussian of the same second moment (a uniform disc of
//! radius R has a standard deviation R / 2 along each axis, so sigma = c / 4).
//!
//! Known approximation: the Gaussian is sampled and applied to the area-coverage pixels,
//! whereas a camera integrates the blurred scene over each pixel. The two differ by the
//! aliasing of the sharp edges' high frequencies; on blurred boards (sigma 2 px) the image's
//! centre of point symmetry at a corner lies 0.005-0.009 px RMS (0.015 px at most) from the
//! true corner (tests/render.rs). Blurring a 2 x 2 supersampled coverage image would cut
//! that at four times the cost.

/// Largest blur the renderer applies, px; larger blurs are clamped (the image is a uniform
/// grey there anyway).
pub const MAX_SIGMA_PX: f64 = 64.0;
/// Blur below which a pixel is left as rendered, px (a sampled Gaussian narrower than this
/// is a delta).
pub const MIN_SIGMA_PX: f64 = 0.25;
/// Resolution of the blur field: sigma is quantised to multiples of this, px.
pub const SIGMA_STEP_PX: f64 = 0.01;
/// Kernel half-width in sigmas.
const KERNEL_SIGMAS: f64 = 4.0;

/// The defocus blur (Gaussian sigma, px) of a point at camera depth `z_mm` when the plane
/// in focus is at depth `focus_depth_mm`, for a lens of focal length `f_px` (the model's
/// fx(E), px) and aperture diameter `aperture_mm`: `aperture_mm * f_px * |1/z_mm -
/// 1/focus_depth_mm| / 4` (thin lens, module docs).
///
/// Returns infinity for a point at or behind the lens (z_mm <= 0) and NaN for NaN input.
///
/// ```
/// use etl_calib::render::defocus_sigma_px;
/// // 1 mm behind the plane in focus at 95 mm, f = 4850 px, A = 2.5 mm: about 0.33 px.
/// let s = defocus_sigma_px(4850.0, 2.5, 96.0, 95.0);
/// assert!((s - 2.5 * 4850.0 * (1.0 / 95.0 - 1.0 / 96.0) / 4.0).abs() < 1e-12);
/// assert_eq!(defocus_sigma_px(4850.0, 2.5, 95.0, 95.0), 0.0);
/// ```
pub fn defocus_sigma_px(f_px: f64, aperture_mm: f64, z_mm: f64, focus_depth_mm: f64) -> f64 {
    if z_mm <= 0.0 {
        return f64::INFINITY;
    }
    0.25 * aperture_mm * f_px * (1.0 / z_mm - 1.0 / focus_depth_mm).abs()
}

/// Total blur of a point: the defocus and a fixed optical blur `base_sigma_px` in quadrature,
/// clamped to [`MAX_SIGMA_PX`].
pub(crate) fn total_sigma_px(defocus_px: f64, base_sigma_px: f64) -> f64 {
    let s = (defocus_px * defocus_px + base_sigma_px * base_sigma_px).sqrt();
    if s.is_nan() {
        base_sigma_px
    } else {
        s.min(MAX_SIGMA_PX)
    }
}

/// Quantised blur level of sigma (0 = no blur).
#[inline]
pub(crate) fn sigma_level(sigma_px: f64) -> u16 {
    if !(sigma_px >= MIN_SIGMA_PX) {
        return 0;
    }
    (sigma_px.min(MAX_SIGMA_PX) / SIGMA_STEP_PX).round() as u16
}

/// Kernel half-width of a blur, px.
pub(crate) fn kernel_radius(sigma_px: f64) -> usize {
    (KERNEL_SIGMAS * sigma_px).ceil() as usize
}

/// Normalised sampled Gaussians for the levels `lo..=hi` (index level - lo); level 0 is
/// the delta.
struct Kernels {
    lo: u16,
    taps: Vec<Vec<f32>>,
}

impl Kernels {
    fn new(lo: u16, hi: u16) -> Self {
        let taps = (lo..=hi)
            .map(|l| {
                if l == 0 {
                    return vec![1.0];
                }
                let s = l as f64 * SIGMA_STEP_PX;
                let r = kernel_radius(s) as i64;
                let w: Vec<f64> = (-r..=r).map(|k| (-0.5 * (k * k) as f64 / (s * s)).exp()).collect();
                let sum: f64 = w.iter().sum();
                w.iter().map(|x| (x / sum) as f32).collect()
            })
            .collect();
        Kernels { lo, taps }
    }

    #[inline]
    fn get(&self, level: u16) -> &[f32] {
        &self.taps[usize::from(level - self.lo)]
    }
}

/// Blurs the padded image `src` (`pw` x `ph`, row-major) with the per-pixel Gaussian of
/// blur level `levels` (same layout) and writes the central `w` x `h` window (offset `pad`
/// in both axes) into `dst`. Separable: a horizontal then a vertical pass, each pixel with
/// its own kernel; `pad` must be at least the largest kernel radius.
pub(crate) fn blur_varying(
    src: &[f32],
    levels: &[u16],
    (pw, ph): (usize, usize),
    pad: usize,
    (w, _h): (usize, usize),
    dst: &mut [f32],
) {
    use rayon::prelude::*;
    let (lo, hi) = levels
        .par_chunks(pw.max(1))
        .map(|r| r.iter().fold((u16::MAX, 0u16), |(a, b), &l| (a.min(l), b.max(l))))
        .reduce(|| (u16::MAX, 0), |a, b| (a.0.min(b.0), a.1.max(b.1)));
    if hi == 0 || lo > hi {
        dst.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            let s = (y + pad) * pw + pad;
            row.copy_from_slice(&src[s..s + w]);
        });
        return;
    }
    let kernels = Kernels::new(lo, hi);
    // Horizontal pass over all padded rows, central columns only.
    let mut tmp = vec![0.0f32; w * ph];
    tmp.par_chunks_mut(w).enumerate().for_each(|(py, row)| {
        let srow = &src[py * pw..(py + 1) * pw];
        let lrow = &levels[py * pw..(py + 1) * pw];
        for (x, o) in row.iter_mut().enumerate() {
            let k = kernels.get(lrow[x + pad]);
            let r = k.len() / 2;
            let start = x + pad - r;
            *o = k.iter().zip(&srow[start..start + k.len()]).map(|(a, b)| a * b).sum();
        }
    });
    // Vertical pass.
    dst.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let lrow = &levels[(y + pad) * pw..(y + pad + 1) * pw];
        for (x, o) in row.iter_mut().enumerate() {
            let k = kernels.get(lrow[x + pad]);
            let r = k.len() / 2;
            let start = y + pad - r;
            let mut acc = 0.0f32;
            for (t, kv) in k.iter().enumerate() {
                acc += kv * tmp[(start + t) * w + x];
            }
            *o = acc;
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_lens_blur() {
        assert_eq!(defocus_sigma_px(5000.0, 2.0, 100.0, 100.0), 0.0);
        // Symmetric in dioptres, not in millimetres.
        let near = defocus_sigma_px(5000.0, 2.0, 50.0, 100.0);
        assert!((near - 0.25 * 2.0 * 5000.0 * 0.01).abs() < 1e-12);
        assert!(defocus_sigma_px(5000.0, 2.0, -1.0, 100.0).is_infinite());
        assert_eq!(total_sigma_px(3.0, 4.0), 5.0);
        assert_eq!(total_sigma_px(1e9, 0.0), MAX_SIGMA_PX);
        assert_eq!(sigma_level(0.1), 0);
        assert_eq!(sigma_level(1.234), 123);
    }

    #[test]
    fn uniform_blur_keeps_the_mean_and_spreads_a_point() {
        // The window holds the point's blur to 5 sigma on every side.
        let (w, h, pad) = (21usize, 21usize, 9usize);
        let (pw, ph) = (w + 2 * pad, h + 2 * pad);
        let mut src = vec![0.0f32; pw * ph];
        src[(pad + 10) * pw + pad + 10] = 1.0;
        let levels = vec![sigma_level(2.0); pw * ph];
        let mut dst = vec![0.0f32; w * h];
        blur_varying(&src, &levels, (pw, ph), pad, (w, h), &mut dst);
        let sum: f32 = dst.iter().sum();
        assert!((sum - 1.0).abs() < 1e-4, "{sum}");
        // Second moment along x is sigma^2 = 4 (a sampled, truncated Gaussian: to 0.05 %).
        let m2: f32 = dst.iter().enumerate().map(|(i, v)| v * ((i % w) as f32 - 10.0).powi(2)).sum();
        assert!((m2 - 4.0).abs() < 2e-3, "{m2}");
    }
}
