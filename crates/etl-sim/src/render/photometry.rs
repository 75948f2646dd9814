//! Photometry: grey levels, shading (vignetting, illumination gradient), photon and read
//! noise, quantisation.

use rand::{Rng, RngCore};
use rand_distr::{Distribution, Poisson, StandardNormal};

use super::image::BitDepth;
use etl_formats::{Error, Result};

/// Grey levels and noise of the synthetic camera, all on the 8-bit scale (a 16-bit image
/// multiplies them by 257).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Photometry {
    /// Grey level of the black squares (before shading).
    pub dark: f64,
    /// Grey level of the white squares and the margin.
    pub light: f64,
    /// Grey level of the surface around the board (in the board's plane).
    pub background: f64,
    /// Vignetting: the relative loss of light at the image corners; the shading is
    /// 1 - vignetting * r^2 with r the distance from the image centre over the half
    /// diagonal. 0 = none; below 1.
    pub vignetting: f64,
    /// Illumination gradient (`g` below): the shading is multiplied by
    /// `1 + g[0] (x - cx) / width + g[1] (y - cy) / height`, (cx, cy) the image centre; so
    /// `g[0] = 0.2` is 20 % more light at the right edge than at the left one.
    pub gradient: [f64; 2],
    /// Gaussian read noise, standard deviation in grey levels.
    pub read_noise: f64,
    /// Photon (shot) noise: electrons per grey level; the signal S becomes
    /// Poisson(S * photon_gain) / photon_gain. 0 = no photon noise.
    pub photon_gain: f64,
}

impl Default for Photometry {
    /// Dark 40, light 210, background 120, no shading, read noise 2 grey levels, no photon
    /// noise (the test images).
    fn default() -> Self {
        Photometry {
            dark: 40.0,
            light: 210.0,
            background: 120.0,
            vignetting: 0.0,
            gradient: [0.0, 0.0],
            read_noise: 2.0,
            photon_gain: 0.0,
        }
    }
}

impl Photometry {
    /// No noise (the grey levels and shading of `self`).
    pub fn noise_free(self) -> Self {
        Photometry { read_noise: 0.0, photon_gain: 0.0, ..self }
    }

    /// Checks every field (levels within 0..=255, vignetting in [0, 1), noise not negative).
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("dark", self.dark), ("light", self.light), ("background", self.background)] {
            if !(0.0..=255.0).contains(&v) {
                return Err(Error::invalid_value(
                    name,
                    v,
                    format!("{name} grey level must be within 0..=255, got {v}"),
                ));
            }
        }
        if !(0.0..1.0).contains(&self.vignetting) {
            return Err(Error::invalid_value(
                "vignetting",
                self.vignetting,
                format!("vignetting must be in [0, 1), got {}", self.vignetting),
            ));
        }
        if !self.gradient.iter().all(|g| g.is_finite() && g.abs() < 2.0) {
            return Err(Error::invalid_value(
                "gradient",
                self.gradient,
                format!("illumination gradient must be finite and below 2 in magnitude, got {:?}", self.gradient),
            ));
        }
        if !(self.read_noise.is_finite() && self.read_noise >= 0.0) {
            return Err(Error::invalid_value(
                "read_noise",
                self.read_noise,
                format!("read noise must be finite and not negative, got {}", self.read_noise),
            ));
        }
        if !(self.photon_gain.is_finite() && self.photon_gain >= 0.0) {
            return Err(Error::invalid_value(
                "photon_gain",
                self.photon_gain,
                format!("photon gain must be finite and not negative, got {}", self.photon_gain),
            ));
        }
        Ok(())
    }

    /// Shading factor at pixel (x, y) of a `width` x `height` image.
    #[inline]
    pub fn shading(&self, x: f64, y: f64, width: f64, height: f64) -> f64 {
        let (cx, cy) = (0.5 * (width - 1.0), 0.5 * (height - 1.0));
        let (dx, dy) = (x - cx, y - cy);
        let half_diag2 = (cx * cx + cy * cy).max(1e-12);
        let v = 1.0 - self.vignetting * (dx * dx + dy * dy) / half_diag2;
        let g = 1.0 + self.gradient[0] * dx / width + self.gradient[1] * dy / height;
        (v * g).max(0.0)
    }

    /// Shades, adds noise to and quantises row `y` of radiances `radiance` (8-bit scale)
    /// into `out`. The noise stream of a row depends only on (`seed`, y) ([`RowNoise`]), so
    /// a render is the same whatever the thread count.
    pub(crate) fn finish_row(
        &self,
        radiance: &[f32],
        y: usize,
        (width, height): (usize, usize),
        bit_depth: BitDepth,
        seed: u64,
        out: &mut [u16],
    ) {
        let mut rng = RowNoise::new(seed, y as u64);
        let scale = bit_depth.scale_from_8bit();
        let max = bit_depth.max_value();
        let (wf, hf) = (width as f64, height as f64);
        let yf = y as f64;
        let flat = self.vignetting == 0.0 && self.gradient == [0.0, 0.0];
        for (x, (r, o)) in radiance.iter().zip(out.iter_mut()).enumerate() {
            let mut s = f64::from(*r);
            if !flat {
                s *= self.shading(x as f64, yf, wf, hf);
            }
            if self.photon_gain > 0.0 {
                let lambda = s * self.photon_gain;
                s = match Poisson::new(lambda) {
                    Ok(p) if lambda > 0.0 => p.sample(&mut rng) / self.photon_gain,
                    _ => s,
                };
            }
            if self.read_noise > 0.0 {
                let n: f64 = rng.sample(StandardNormal);
                s += self.read_noise * n;
            }
            // Round half up; the float-to-int cast saturates (negative and NaN to 0).
            *o = ((s * scale + 0.5) as u16).min(max);
        }
    }
}

/// The noise generator of one image row: SplitMix64 (Steele, Lea and Flood 2014), started
/// at a state that mixes the seed and the row index. A few instructions per 64 bits, it
/// passes BigCrush; ChaCha's cryptographic strength buys nothing for sensor noise and cost
/// a fifth of the render. The rows' streams start at unrelated points of the generator's
/// 2^64 cycle, so they do not overlap in practice (a row uses about two draws per pixel).
#[derive(Debug, Clone)]
pub(crate) struct RowNoise {
    state: u64,
}

const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64's output function (a bijection of u64).
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl RowNoise {
    /// The stream of row `row` of the image with noise seed `seed`.
    pub fn new(seed: u64, row: u64) -> Self {
        RowNoise { state: mix64(seed ^ mix64(row.wrapping_add(1).wrapping_mul(GOLDEN_GAMMA))) }
    }
}

impl RngCore for RowNoise {
    #[inline]
    fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix64(self.state)
    }

    fn fill_bytes(&mut self, dst: &mut [u8]) {
        rand::rand_core::impls::fill_bytes_via_next(self, dst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shading_and_noise_statistics() {
        let p = Photometry { vignetting: 0.3, gradient: [0.2, 0.0], ..Photometry::default() };
        assert!((p.shading(49.5, 29.5, 100.0, 60.0) - 1.0).abs() < 1e-12);
        assert!((p.shading(0.0, 0.0, 100.0, 60.0) - 0.7 * (1.0 - 0.2 * 49.5 / 100.0)).abs() < 1e-12);
        // Read noise 2: sample standard deviation over a flat row of 100.5.
        let flat = Photometry::default();
        let row = vec![100.5f32; 20000];
        let mut out = vec![0u16; row.len()];
        flat.finish_row(&row, 3, (row.len(), 1), BitDepth::Sixteen, 7, &mut out);
        let vals: Vec<f64> = out.iter().map(|&v| f64::from(v) / 257.0).collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vals.len() as f64).sqrt();
        assert!((mean - 100.5).abs() < 0.05 && (sd - 2.0).abs() < 0.05, "{mean} {sd}");
        // Photon noise alone: variance S / gain.
        let shot = Photometry { read_noise: 0.0, photon_gain: 4.0, ..Photometry::default() };
        shot.finish_row(&row, 3, (row.len(), 1), BitDepth::Sixteen, 7, &mut out);
        let vals: Vec<f64> = out.iter().map(|&v| f64::from(v) / 257.0).collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vals.len() as f64;
        assert!((mean - 100.5).abs() < 0.1 && (var - 100.5 / 4.0).abs() < 1.0, "{mean} {var}");
        // Same seed and row, same noise; another row, other noise.
        let mut a = vec![0u16; 50];
        let mut b = vec![0u16; 50];
        flat.finish_row(&row[..50], 5, (50, 9), BitDepth::Eight, 1, &mut a);
        flat.finish_row(&row[..50], 5, (50, 9), BitDepth::Eight, 1, &mut b);
        assert_eq!(a, b);
        flat.finish_row(&row[..50], 6, (50, 9), BitDepth::Eight, 1, &mut b);
        assert_ne!(a, b);
        // Neighbouring rows' and seeds' streams are uncorrelated (|r| < 4 / sqrt(n)).
        let normals = |seed: u64, row: u64| -> Vec<f64> {
            let mut rng = RowNoise::new(seed, row);
            (0..20000).map(|_| rng.sample(StandardNormal)).collect()
        };
        let base = normals(7, 3);
        for other in [normals(7, 4), normals(8, 3), normals(7, 3 + (1 << 32))] {
            let r = base.iter().zip(&other).map(|(x, y)| x * y).sum::<f64>() / 20000.0;
            assert!(r.abs() < 4.0 / 20000f64.sqrt(), "{r}");
        }
    }

    #[test]
    fn bad_photometry_is_refused() {
        let d = Photometry::default();
        for (p, what) in [
            (Photometry { dark: -1.0, ..d }, "dark"),
            (Photometry { light: 256.0, ..d }, "light"),
            (Photometry { background: f64::NAN, ..d }, "background"),
            (Photometry { vignetting: 1.0, ..d }, "vignetting"),
            (Photometry { gradient: [f64::INFINITY, 0.0], ..d }, "gradient"),
            (Photometry { read_noise: -0.1, ..d }, "read noise"),
            (Photometry { photon_gain: f64::NAN, ..d }, "photon gain"),
        ] {
            let e = p.validate().unwrap_err().to_string();
            assert!(e.contains(what), "{e}");
        }
        assert!(d.validate().is_ok());
    }
}
