//! [`ZhangRequest`]: the options of a monofocal (Zhang) calibration, their validation and
//! the run, for `etlcal zhang` and Python's `etlcal.zhang(...)`.

use etl_core::model::DistortionModel;
use etl_formats::Result;

use super::option::{RequestOption, Spelling};
use super::refusal::Refusal;
use crate::zhang::{zhang_with, PlanarView, ZhangOptions, ZhangResult};

/// The options of Zhang's method: the distortion family (default: the paper's) and, for
/// OpenCV's, its flags. The CLI's `--model`, `--fix-k3`, `--zero-tangent` and Python's
/// `model=`, `fix_k3=`, `zero_tangent=` parse into it.
///
/// ```
/// use etl_calib::request::{KeySpelling, RequestOption, ZhangRequest};
/// use etl_core::model::DistortionModel;
///
/// let opencv = ZhangRequest { model: DistortionModel::OpenCv, fix_k3: true, zero_tangent: false };
/// assert!(opencv.check().is_ok());
/// // OpenCV's flags mean nothing in the paper's family: refused, naming the flag.
/// let paper = ZhangRequest { model: DistortionModel::Paper, ..opencv };
/// let refusal = paper.check().unwrap_err();
/// assert_eq!(refusal.option(), RequestOption::FixK3);
/// assert!(refusal.message(&KeySpelling).contains("it needs model = opencv"));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ZhangRequest {
    /// The distortion family.
    pub model: DistortionModel,
    /// Hold k3 = 0 (OpenCV's `CALIB_FIX_K3`; the opencv family only).
    pub fix_k3: bool,
    /// Hold p1 = p2 = 0 (OpenCV's `CALIB_ZERO_TANGENT_DIST`; the opencv family only).
    pub zero_tangent: bool,
}

impl ZhangRequest {
    /// Refuses an OpenCV flag with the paper's family (it has no k3 and keeps its
    /// decentering terms).
    pub fn check(&self) -> std::result::Result<(), Refusal> {
        if self.model != DistortionModel::Paper {
            return Ok(());
        }
        let flags = [(RequestOption::FixK3, self.fix_k3), (RequestOption::ZeroTangent, self.zero_tangent)];
        match flags.iter().find(|(_, set)| *set) {
            Some(&(flag, _)) => {
                Err(Refusal::OpenCvFlagNeedsOpenCv { flag, family: RequestOption::Model, auto_allowed: false })
            }
            None => Ok(()),
        }
    }

    /// [`Self::check`], its refusal as bad input in `spelling`'s words.
    pub fn validate(&self, spelling: &dyn Spelling) -> Result<()> {
        self.check().map_err(|r| r.to_error(spelling))
    }

    /// The solver's options.
    pub fn options(&self) -> ZhangOptions {
        ZhangOptions {
            model: self.model,
            flags: etl_core::model::OpenCvFlags { fix_k3: self.fix_k3, zero_tangent: self.zero_tangent },
        }
    }

    /// Calibrates the camera from `views` of a planar board in images of `image_size`
    /// ([`zhang_with`]).
    ///
    /// Errors: the refusal of [`Self::check`] in `spelling`'s words; an `image_size` outside
    /// [1, 65536] px a side or above 2^28 px (`image_size`: the principal point's start and
    /// the normalisation depend on it, so (0, 0) would calibrate nonsense); a point or pixel
    /// that is not finite, naming its view; those of
    /// [`zhang_with`] (at least 3 views, 4 points each, not all parallel).
    pub fn run(&self, views: &[PlanarView], image_size: [u32; 2], spelling: &dyn Spelling) -> Result<ZhangResult> {
        self.validate(spelling)?;
        etl_formats::check_image_size(image_size, "image_size")?;
        // A NaN pixel would be dropped by nothing and poison the fit: refused, named.
        for (i, v) in views.iter().enumerate() {
            let bad = v.board_mm.iter().chain(&v.pixels).position(|p| !(p[0].is_finite() && p[1].is_finite()));
            if let Some(j) = bad {
                let (what, k) = if j < v.board_mm.len() { ("board_mm", j) } else { ("pixels", j - v.board_mm.len()) };
                return Err(etl_formats::Error::invalid(
                    format!("views[{i}].{what}"),
                    format!("view {i}: {what} point {k} is not finite"),
                ));
            }
        }
        zhang_with(views, image_size, &self.options())
    }
}
