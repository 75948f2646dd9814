//! One synthetic image of a board on the paper rig's stage, as a front end asks for it
//! (`etlcal render`, Python's `etlcal.render`): the options, their documented ranges and
//! their checks in one place, so that both front ends refuse the same values with the same
//! words, each naming its own spelling of the option.

use etl_core::model::CameraModel;
use etl_formats::{check_range, Result};

use super::{BitDepth, Optics, Photometry, RenderOptions, MAX_SIGMA_PX};
use crate::simulate::focused_z_mm;

/// A render of the paper rig's camera at a compensated current.
///
/// The documented ranges, checked by [`PaperRender::validate`] before anything is drawn (NaN
/// is in none of them):
///
/// | option | key | range |
/// |---|---|---|
/// | compensated current | `e_com_ma` | [`etl_core::thermal::E_IN_DOMAIN_MA`] |
/// | stage position | `z_mm` | [-10000, 10000] mm, or `None`: the rig's focus position at the current |
/// | aperture diameter | `aperture_mm` | [0, 50] mm (0: no defocus) |
/// | uniform blur | `blur_px` | [0, [`MAX_SIGMA_PX`]] px (the renderer's largest blur) |
/// | read noise | `noise` | [0, 255] grey levels (8-bit scale) |
///
/// ```
/// use etl_sim::render::{BitDepth, PaperRender};
/// let r = PaperRender { e_com_ma: 150.0, z_mm: None, aperture_mm: f64::NAN, blur_px: 0.0,
///     noise: 2.0, bit_depth: BitDepth::Eight, seed: 1 };
/// let err = r.validate(|key| key.to_owned()).unwrap_err();
/// assert_eq!(err.to_string(), "invalid input: aperture_mm NaN mm is outside [0, 50] mm");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperRender {
    /// The compensated lens current, mA.
    pub e_com_ma: f64,
    /// The stage position Z_W, mm; `None`: the paper rig's focus position at the current.
    pub z_mm: Option<f64>,
    /// The aperture diameter for the defocus, mm (0: no defocus).
    pub aperture_mm: f64,
    /// A uniform Gaussian blur added in quadrature, px.
    pub blur_px: f64,
    /// The read noise, grey levels (8-bit scale).
    pub noise: f64,
    /// Bits per pixel.
    pub bit_depth: BitDepth,
    /// The noise seed.
    pub seed: u64,
}

impl PaperRender {
    /// Checks every option against the documented range (the table above); `name` gives
    /// the front end's spelling of a key (`--aperture-mm`, `aperture_mm`) for the message.
    pub fn validate(&self, name: impl Fn(&'static str) -> String) -> Result<()> {
        check_range(&name("e_com_ma"), self.e_com_ma, etl_core::thermal::E_IN_DOMAIN_MA, "mA")?;
        if let Some(z) = self.z_mm {
            check_range(&name("z_mm"), z, [-10_000.0, 10_000.0], "mm")?;
        }
        check_range(&name("aperture_mm"), self.aperture_mm, [0.0, 50.0], "mm")?;
        check_range(&name("blur_px"), self.blur_px, [0.0, MAX_SIGMA_PX], "px")?;
        check_range(&name("noise"), self.noise, [0.0, 255.0], "grey levels")?;
        Ok(())
    }

    /// The stage position: the one given, or the rig's focus position at the current.
    pub fn stage_z_mm(&self) -> f64 {
        self.z_mm.unwrap_or_else(|| focused_z_mm(self.e_com_ma))
    }

    /// The renderer's options: the paper rig's focus at the current when the aperture is
    /// positive (else a sharp lens), the blur, the noise, the depth and the seed.
    pub fn options(&self, truth: &CameraModel) -> RenderOptions {
        let focus = if self.aperture_mm > 0.0 {
            Optics::paper_focus(truth, self.e_com_ma, self.aperture_mm)
        } else {
            Optics::sharp()
        };
        RenderOptions {
            optics: Optics { base_sigma_px: self.blur_px, ..focus },
            photometry: Photometry { read_noise: self.noise, ..Photometry::default() },
            bit_depth: self.bit_depth,
            seed: self.seed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> PaperRender {
        PaperRender {
            e_com_ma: 150.0,
            z_mm: None,
            aperture_mm: 2.5,
            blur_px: 0.0,
            noise: 2.0,
            bit_depth: BitDepth::Eight,
            seed: 1,
        }
    }

    #[test]
    fn every_option_out_of_its_range_is_refused_by_its_front_ends_name() {
        let cli = |key: &'static str| format!("--{}", key.replace('_', "-"));
        assert!(request().validate(cli).is_ok());
        // A change to the request and the start of the message that refuses it.
        type Case = (fn(&mut PaperRender), &'static str);
        let cases: [Case; 7] = [
            (|r| r.e_com_ma = f64::NAN, "--e-com-ma NaN mA"),
            (|r| r.z_mm = Some(f64::INFINITY), "--z-mm inf mm"),
            (|r| r.aperture_mm = f64::NAN, "--aperture-mm NaN mm"),
            (|r| r.aperture_mm = -1.0, "--aperture-mm -1 mm"),
            (|r| r.blur_px = 100.0, "--blur-px 100 px is outside [0, 64] px"),
            (|r| r.noise = 1e308, "--noise 1e308 grey levels"),
            (|r| r.noise = -0.5, "--noise -0.5 grey levels"),
        ];
        for (spoil, message) in cases {
            let mut r = request();
            spoil(&mut r);
            let err = r.validate(cli).unwrap_err().to_string();
            assert!(err.contains(message), "{err}");
        }
    }

    #[test]
    fn the_largest_blur_accepted_is_the_renderers_largest() {
        let mut r = request();
        r.blur_px = MAX_SIGMA_PX;
        assert!(r.validate(str::to_owned).is_ok());
        assert!(r.options(&CameraModel::paper_rig()).optics.validate().is_ok());
    }

    #[test]
    fn no_aperture_is_a_sharp_lens_and_a_stage_position_defaults_to_focus() {
        let mut r = request();
        r.aperture_mm = 0.0;
        assert_eq!(r.options(&CameraModel::paper_rig()).optics.focus_depth_mm, None);
        assert_eq!(r.stage_z_mm(), focused_z_mm(150.0));
        r.z_mm = Some(3.0);
        assert_eq!(r.stage_z_mm(), 3.0);
    }
}
