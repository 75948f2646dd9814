//! `etlcal.calibration/1`: the result of a calibration (docs/FORMATS.md).
//!
//! The model's numbers under the names of [`etl_core::model::CameraModel`] (the paper's 25:
//! cubic `kf_x`, `kf_y` and `distortion_a` of 9; or focal polynomials of degree 1..=5 and,
//! with `"distortion_model": "opencv"`, `distortion_a` of 15), `std` with one standard
//! deviation of each, the calibrated current range, the RMS reprojection error, and what
//! produced it (estimator, iterations, per-view residuals and, for the errors-in-variables
//! estimator, each view's stage and current corrections). A file of the paper's model is
//! written exactly as before the families existed: no `"distortion_model"` field.
//!
//! A calibration made from views with a recorded E_com and no thermal calibration has no
//! temperature compensation and says so: `"temperature_compensation": "none"`
//! ([`TemperatureCompensation`]; the field is absent when there is a `"thermal"` part,
//! and in files written before it existed, which read and write byte for byte as before).
//! Such a calibration is used at a known E_com ([`Calibration::at_e_com`]); `at(E_in, T)`
//! is refused.

use std::path::Path;

use etl_core::calib::jacobian::{from_params, to_params};
use etl_core::calib::params::{Layout, MAX_PARAMS};
use etl_core::calib::{projection_uncertainty, PixelUncertainty};
use etl_core::focus::FocusLaw;
use etl_core::model::{CameraModel, DistortionA, DistortionModel, FocalPoly, MovingCentre};
use etl_core::runtime::{Camera, CameraAt, SettingKind, ThermalTrust, Trust};
use etl_core::thermal::{ThermalCalibration, ThermalSurface};
use serde::{Deserialize, Serialize};

use super::{parse_json, read_json, write_json};
use crate::thermal::ThermalFile;
use crate::{Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.calibration/1";

/// One standard deviation of every model number (same keys and lengths as the model).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelStd {
    /// Of the Rodrigues vector, rad.
    pub rotation_rodrigues: [f64; 3],
    /// Of T, mm.
    pub translation_mm: [f64; 3],
    /// Of kf_x.
    pub kf_x: Vec<f64>,
    /// Of kf_y.
    pub kf_y: Vec<f64>,
    /// Of (u0, v0), px.
    pub principal_point: [f64; 2],
    /// Of the a_i.
    pub distortion_a: Vec<f64>,
    /// Of the moving centre's coefficients, laid out as the file's `"centre"` (the
    /// constants: 0 for dz, `principal_point`'s for u0 and v0); absent for a fixed centre.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<CentreField>,
}

/// `"centre"`: a projection centre and principal point that move with E (Eq. C1-C3 of
/// `etl_core::model::centre`), each as its polynomial's ascending coefficients in E from
/// E^0. `dz_mm` is [0, dz1, dz2]: its constant is 0 because a constant move is the pose's
/// own T_z, so the calibration's pose (`translation_mm`) is the centre's at E = 0 and
/// T(E) = T - dz(E) e_z. `principal_point_px` is [[u0, u1], [v0, v1]], whose constants are
/// `principal_point`. Absent: the paper's fixed centre (files read and write as before).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CentreField {
    /// dz(E) = dz1 E + dz2 E^2 as [0, dz1, dz2]: mm, mm / mA, mm / mA^2.
    pub dz_mm: Vec<f64>,
    /// u0(E) = u0 + u1 E and v0(E) = v0 + v1 E as [[u0, u1], [v0, v1]]: px, px / mA.
    pub principal_point_px: Vec<Vec<f64>>,
}

impl CentreField {
    /// The field of `centre` with the principal point `principal_point`.
    pub fn of(centre: &MovingCentre, principal_point: [f64; 2]) -> Self {
        let [u1, v1] = centre.principal_point_slope_px;
        CentreField {
            dz_mm: vec![0.0, centre.dz_mm[0], centre.dz_mm[1]],
            principal_point_px: vec![vec![principal_point[0], u1], vec![principal_point[1], v1]],
        }
    }

    /// The centre, checked against the model's `principal_point`. `key` names the field in
    /// the messages (`centre` or `std.centre`).
    fn checked(&self, principal_point: [f64; 2], key: &str) -> std::result::Result<MovingCentre, String> {
        let n_dz = 1 + etl_core::model::CENTRE_DZ_LEN;
        if self.dz_mm.len() != n_dz {
            return Err(format!(
                "{key}.dz_mm has {} numbers: the moving centre's dz(E) has {n_dz} (E^0 .. E^{})",
                self.dz_mm.len(),
                n_dz - 1
            ));
        }
        if self.dz_mm[0] != 0.0 {
            return Err(format!(
                "{key}.dz_mm[0] = {} must be 0: a constant move of the centre is translation_mm's",
                crate::compact(self.dz_mm[0])
            ));
        }
        let n_pp = 1 + etl_core::model::CENTRE_PP_LEN;
        if self.principal_point_px.len() != 2 || self.principal_point_px.iter().any(|c| c.len() != n_pp) {
            return Err(format!("{key}.principal_point_px must be [[u0, u1], [v0, v1]]: 2 lists of {n_pp} numbers"));
        }
        for (k, axis) in ["u0", "v0"].into_iter().enumerate() {
            if self.principal_point_px[k][0] != principal_point[k] {
                return Err(format!(
                    "{key}.principal_point_px[{k}][0] = {} must equal principal_point[{k}] = {} ({axis} at E = 0)",
                    crate::compact(self.principal_point_px[k][0]),
                    crate::compact(principal_point[k])
                ));
            }
        }
        Ok(MovingCentre {
            dz_mm: [self.dz_mm[1], self.dz_mm[2]],
            principal_point_slope_px: [self.principal_point_px[0][1], self.principal_point_px[1][1]],
        })
    }
}

impl ModelStd {
    /// From the standard deviations in the parameter order of `layout` (at least its
    /// length of them; missing ones read as 0).
    pub fn from_params(layout: &Layout, s: &[f64]) -> Self {
        let m = from_params(layout, s);
        ModelStd {
            rotation_rodrigues: m.rotation_rodrigues,
            translation_mm: m.translation_mm,
            kf_x: m.kf_x.coefficients().to_vec(),
            kf_y: m.kf_y.coefficients().to_vec(),
            principal_point: m.principal_point,
            distortion_a: m.distortion_a.as_slice().to_vec(),
            centre: m.centre.as_ref().map(|c| CentreField::of(c, m.principal_point)),
        }
    }

    /// Zero standard deviations (an exact model) of `layout`.
    pub fn zero(layout: &Layout) -> Self {
        Self::from_params(layout, &[0.0; MAX_PARAMS])
    }

    /// The standard deviations in parameter order (at capacity; the inverse of
    /// [`ModelStd::from_params`]), for a calibration of `layout`. Errors: lengths that do
    /// not match the layout (naming the field).
    pub fn to_params(&self, layout: &Layout) -> Result<[f64; MAX_PARAMS]> {
        self.checked_params(layout).map_err(|m| Error::invalid(leading_field(&m).to_owned(), m))
    }

    /// [`Self::to_params`] with the message alone (for the file's validator).
    fn checked_params(&self, layout: &Layout) -> std::result::Result<[f64; MAX_PARAMS], String> {
        let model = model_of(
            layout.model(),
            self.rotation_rodrigues,
            self.translation_mm,
            (&self.kf_x, &self.kf_y),
            self.principal_point,
            &self.distortion_a,
            self.centre.as_ref(),
        )
        .map_err(|e| format!("std.{e}"))?;
        if model.layout() != *layout {
            return Err("std: kf_x, kf_y, distortion_a and centre must have the lengths of the model's".into());
        }
        Ok(to_params(&model))
    }
}

/// The field a message of [`model_of`] or [`ModelStd::checked_params`] names first
/// (`"kf_x has 7 numbers: ..."` -> `kf_x`, `"std.kf_y has ..."` -> `std.kf_y`).
fn leading_field(message: &str) -> &str {
    message.split([' ', ':']).next().unwrap_or("calibration")
}

/// A model from the file's fields, with errors naming the field (without the file path).
fn model_of(
    family: DistortionModel,
    rotation_rodrigues: [f64; 3],
    translation_mm: [f64; 3],
    (kf_x, kf_y): (&[f64], &[f64]),
    principal_point: [f64; 2],
    distortion_a: &[f64],
    centre: Option<&CentreField>,
) -> std::result::Result<CameraModel, String> {
    let focal = |v: &[f64], name: &str| {
        FocalPoly::new(v)
            .map_err(|_| format!("{name} has {} numbers: a focal polynomial needs 2..=6 (degree 1..=5)", v.len()))
    };
    let (kf_x, kf_y) = (focal(kf_x, "kf_x")?, focal(kf_y, "kf_y")?);
    if kf_x.degree() != kf_y.degree() {
        return Err(format!(
            "kf_y has {} numbers and kf_x {}: both focal polynomials must have the same degree",
            kf_y.degree() + 1,
            kf_x.degree() + 1
        ));
    }
    let distortion_a = DistortionA::new(family, distortion_a).map_err(|_| {
        format!(
            "distortion_a has {} numbers: the {} distortion model has {}",
            distortion_a.len(),
            family.name(),
            family.a_len()
        )
    })?;
    let centre = centre.map(|c| c.checked(principal_point, "centre")).transpose()?;
    Ok(CameraModel { rotation_rodrigues, translation_mm, kf_x, kf_y, principal_point, distortion_a, centre })
}

/// The temperature compensation a calibration was made with and is used with: the whole
/// thermal calibration (surface, the ranges it was fitted over, its RMS) and where it came
/// from. Files written before the ranges were kept hold `coefficients` only; they stay
/// readable, and the run-time camera then treats every setting as outside the ranges
/// ([`etl_core::runtime::ThermalTrust`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalRef {
    /// The 10 coefficients of E_T(T, E_in) (docs/METHOD.md order).
    pub coefficients: [f64; 10],
    /// [min, max] temperature of the samples the surface was fitted to, degC.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_range_c: Option<[f64; 2]>,
    /// [min, max] driver current of those samples, mA.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e_in_range_ma: Option<[f64; 2]>,
    /// RMS of the surface fit, mA.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_ma: Option<f64>,
    /// Where it came from: `"paper"` (the paper's surface, chosen explicitly) or the
    /// `etlcal.thermal/1` file it was read from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// The word that chooses the paper's thermal surface where a thermal file is expected
/// (`--thermal paper`, `thermal="paper"`).
pub const PAPER_THERMAL: &str = "paper";

impl ThermalRef {
    /// The paper's surface over its procedure's ranges (27..37 degC, 40..240 mA, RMS
    /// 0.2106 mA), recorded as `"source": "paper"`.
    pub fn paper() -> Self {
        Self::from_file(&ThermalFile::paper(), PAPER_THERMAL)
    }

    /// The content of a thermal file, recorded with `source` (the file's path).
    pub fn from_file(file: &ThermalFile, source: &str) -> Self {
        ThermalRef {
            coefficients: file.coefficients,
            t_range_c: Some(file.t_range_c),
            e_in_range_ma: Some(file.e_in_range_ma),
            rms_ma: Some(file.rms_ma),
            source: Some(source.to_owned()),
        }
    }

    /// What the user chose: [`PAPER_THERMAL`] for the paper's surface, else the path of an
    /// `etlcal.thermal/1` file (read and checked; a file named `paper` is `./paper`).
    pub fn choose(choice: &Path) -> Result<Self> {
        if choice == Path::new(PAPER_THERMAL) {
            return Ok(Self::paper());
        }
        Ok(Self::from_file(&ThermalFile::load(choice)?, &choice.display().to_string()))
    }

    /// The surface with its ranges, as the run-time camera checks them.
    pub fn trust(&self) -> ThermalTrust {
        ThermalTrust {
            surface: ThermalSurface { coefficients: self.coefficients },
            t_range_c: self.t_range_c,
            e_in_range_ma: self.e_in_range_ma,
        }
    }

    /// The thermal calibration with its ranges. Errors: a file that does not keep them.
    pub fn calibration(&self) -> Result<ThermalCalibration> {
        match (self.t_range_c, self.e_in_range_ma) {
            (Some(t_range_c), Some(e_in_range_ma)) => Ok(ThermalCalibration {
                surface: ThermalSurface { coefficients: self.coefficients },
                t_range_c,
                e_in_range_ma,
            }),
            _ => Err(Error::invalid(
                if self.t_range_c.is_none() { "thermal.t_range_c" } else { "thermal.e_in_range_ma" },
                "the thermal part of this calibration has no calibrated ranges (an older file): re-run calibrate \
                 with --thermal FILE or --thermal paper",
            )),
        }
    }

    /// E_com of a view at (`e_in_ma`, `temperature_c`), refused outside the calibrated
    /// ranges (with their margins, [`etl_core::runtime`]): a calibration must not be built
    /// on extrapolated currents.
    pub fn e_com_ma(&self, e_in_ma: f64, temperature_c: f64) -> Result<f64> {
        let (e_t, _) = self.trust().e_t_ma(e_in_ma, temperature_c, Trust::Refuse)?;
        Ok(e_in_ma - e_t)
    }
}

/// One of the observations' setting views as the bundle adjustment solved it
/// (`calibrate --setting-views joint`): its pose and current correction, and how well the
/// calibrated model reprojects it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingViewSummary {
    /// Its E_com, mA.
    pub e_com_ma: f64,
    /// Points used (all of the view's: setting views have no outlier screen).
    pub points: usize,
    /// RMS reprojection error of the view, px.
    pub rms_px: f64,
    /// Estimated current correction, mA (errors-in-variables; 0 otherwise).
    pub de_ma: f64,
    /// The board's pose, board to camera: Rodrigues vector, rad. With a moving centre a
    /// board point P is at R P + t - dz(E) e_z in the camera (docs/METHOD.md, Eq. 24b).
    pub rotation_rodrigues: [f64; 3],
    /// The board's pose, board to camera: translation, mm.
    pub translation_mm: [f64; 3],
}

/// Per-view summary.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewSummary {
    /// E_com of the view, mA (absent, NaN here, in a focal-power calibration).
    #[serde(default = "crate::lens_setting::absent", skip_serializing_if = "crate::lens_setting::is_absent")]
    pub e_com_ma: f64,
    /// The view's commanded focal power, dpt (a focal-power calibration, instead of
    /// `e_com_ma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_power_dpt: Option<f64>,
    /// Points used.
    pub points: usize,
    /// RMS reprojection error of the view, px.
    pub rms_px: f64,
    /// Estimated stage correction, mm (errors-in-variables; 0 otherwise).
    pub dz_mm: f64,
    /// Estimated current correction, mA (errors-in-variables; 0 otherwise; absent, NaN
    /// here, in a focal-power calibration).
    #[serde(default = "crate::lens_setting::absent", skip_serializing_if = "crate::lens_setting::is_absent")]
    pub de_ma: f64,
    /// Estimated focal-power correction, dpt (a focal-power calibration, instead of
    /// `de_ma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub de_dpt: Option<f64>,
    /// The view's own estimate of fx, px: fx refitted to this view alone with every other
    /// number of the calibration held (0 when not computed).
    #[serde(default)]
    pub fx_px: f64,
    /// The view's own estimate of fy, px (as `fx_px`).
    #[serde(default)]
    pub fy_px: f64,
}

impl ViewSummary {
    /// The view's setting in its calibration's unit: `focal_power_dpt`, or `e_com_ma`.
    pub fn setting(&self) -> f64 {
        self.focal_power_dpt.unwrap_or(self.e_com_ma)
    }

    /// The view's setting correction in its calibration's unit: `de_dpt`, or `de_ma`.
    pub fn setting_correction(&self) -> f64 {
        self.de_dpt.unwrap_or(self.de_ma)
    }
}

/// The file's `"distortion_model"` for a family: none for the paper's (files unchanged).
fn distortion_model_field(model: DistortionModel) -> Option<String> {
    match model {
        DistortionModel::Paper => None,
        DistortionModel::OpenCv => Some(model.name().to_owned()),
    }
}

/// What a calibration says about its temperature compensation when it has none
/// (`"temperature_compensation"`; a calibration with a thermal part has the field absent).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TemperatureCompensation {
    /// `"none"`: the views' recorded E_com were used as they are and no thermal
    /// calibration was given, so E_com cannot be had from (E_in, T): the camera is used at
    /// a known E_com only ([`Calibration::at_e_com`]).
    None,
}

impl TemperatureCompensation {
    /// What a calibration made with `thermal` records: [`TemperatureCompensation::None`]
    /// without one (its views carried E_com), nothing with one.
    pub fn of(thermal: Option<&ThermalRef>) -> Option<Self> {
        thermal.is_none().then_some(TemperatureCompensation::None)
    }
}

/// The warning a calibration recorded as `"temperature_compensation": "none"` gets, said
/// once by `calibrate` (the front ends name their own way to give E_com).
pub const NO_TEMPERATURE_COMPENSATION: &str = "no thermal calibration was given and the views carry E_com: the \
     calibration has no temperature compensation (recorded as \"temperature_compensation\": \"none\") and is used at \
     a known E_com only";

/// Which way [`Calibration::focus_thermal`] converts.
#[derive(Debug, Clone, Copy)]
enum Direction {
    EComForEIn,
    EInForECom,
}

/// The keys of the focus law in the file: a current calibration's `coefficients_ma`,
/// `e_com_range_ma`, `rms_ma` (the law's own), a focal-power calibration's
/// `coefficients_dpt`, `focal_power_range_dpt`, `rms_dpt` ([`FocusLaw::setting`]); either
/// with `distance_range_mm` and `views`. A law giving keys of both kinds, or not all of one,
/// is refused naming them.
mod focus_law_keys {
    use etl_core::focus::FocusLaw;
    use etl_core::runtime::SettingKind;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Either kind of law as read.
    #[derive(Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Keys {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        coefficients_ma: Option<[f64; 3]>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        coefficients_dpt: Option<[f64; 3]>,
        distance_range_mm: [f64; 2],
        #[serde(default, skip_serializing_if = "Option::is_none")]
        e_com_range_ma: Option<[f64; 2]>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        focal_power_range_dpt: Option<[f64; 2]>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rms_ma: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rms_dpt: Option<f64>,
        views: usize,
    }

    pub(super) fn write<S: Serializer>(law: &Option<FocusLaw>, s: S) -> Result<S::Ok, S::Error> {
        let Some(l) = law else { return s.serialize_none() };
        if l.setting == SettingKind::Current {
            return l.serialize(s);
        }
        let keys = Keys {
            coefficients_ma: None,
            coefficients_dpt: Some(l.coefficients_ma),
            distance_range_mm: l.distance_range_mm,
            e_com_range_ma: None,
            focal_power_range_dpt: Some(l.e_com_range_ma),
            rms_ma: None,
            rms_dpt: Some(l.rms_ma),
            views: l.views,
        };
        keys.serialize(s)
    }

    pub(super) fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Option<FocusLaw>, D::Error> {
        let Some(k) = Option::<Keys>::deserialize(d)? else { return Ok(None) };
        let (setting, c, r, rms) = match (k.coefficients_ma, k.e_com_range_ma, k.rms_ma) {
            (Some(c), Some(r), Some(rms)) if k.coefficients_dpt.is_none() && k.focal_power_range_dpt.is_none() => {
                (SettingKind::Current, c, r, rms)
            }
            (None, None, None) => match (k.coefficients_dpt, k.focal_power_range_dpt, k.rms_dpt) {
                (Some(c), Some(r), Some(rms)) => (SettingKind::FocalPower, c, r, rms),
                _ => return Err(serde::de::Error::custom(KINDS)),
            },
            _ => return Err(serde::de::Error::custom(KINDS)),
        };
        let law = FocusLaw {
            coefficients_ma: c,
            distance_range_mm: k.distance_range_mm,
            e_com_range_ma: r,
            rms_ma: rms,
            views: k.views,
            setting,
        };
        Ok(Some(law))
    }

    const KINDS: &str = "focus_law needs coefficients_ma, e_com_range_ma and rms_ma (a current's law) or \
                         coefficients_dpt, focal_power_range_dpt and rms_dpt (a focal power's), not a mix";
}

/// An absent range (a focal-power calibration's `e_com_range_ma`): NaN.
fn absent_range() -> [f64; 2] {
    [f64::NAN; 2]
}

/// Whether a range is absent ([`absent_range`]): then it is not written.
fn is_absent_range(r: &[f64; 2]) -> bool {
    r[0].is_nan() && r[1].is_nan()
}

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// `"etlcal.calibration/1"`.
    pub format: String,
    /// Image width and height, px.
    pub image_size: [u32; 2],
    /// Rodrigues vector of R, rad.
    pub rotation_rodrigues: [f64; 3],
    /// T, mm.
    pub translation_mm: [f64; 3],
    /// kf0x..kf_dx (the paper: kf0x..kf3x; degree d = 1..=5).
    pub kf_x: Vec<f64>,
    /// kf0y..kf_dy (as many as kf_x).
    pub kf_y: Vec<f64>,
    /// (u0, v0), px.
    pub principal_point: [f64; 2],
    /// The distortion family: absent for the paper's (files of the paper model have no
    /// such field, as before the families existed), `"opencv"` for OpenCV's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distortion_model: Option<String>,
    /// The a_i: a1..a9 (paper) or a1..a15 (opencv: k1, k2, p1, p2, k3, each (w^2, w, 1)).
    pub distortion_a: Vec<f64>,
    /// The moving centre ([`CentreField`]); absent for the paper's fixed centre.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<CentreField>,
    /// The thermal surface (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<ThermalRef>,
    /// `"none"` when the calibration was made from views with a recorded E_com and no
    /// thermal calibration ([`TemperatureCompensation::None`]): it is used at a known
    /// E_com only. Absent in files with a thermal part and in files written before it
    /// existed (which read and write as before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature_compensation: Option<TemperatureCompensation>,
    /// What the calibration's setting is (`"setting"`): absent or `"current"` for E_com,
    /// `"focal_power"` for the commanded focal power ([`SettingKind`]); written only for a
    /// focal power, so that current calibrations read and write as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub setting: Option<SettingKind>,
    /// The range of E_com the calibration saw, mA (absent, NaN here, in a focal-power
    /// calibration).
    #[serde(default = "absent_range", skip_serializing_if = "is_absent_range")]
    pub e_com_range_ma: [f64; 2],
    /// The range of focal power the calibration saw, dpt (a focal-power calibration only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_power_range_dpt: Option<[f64; 2]>,
    /// The lens temperatures of a focal-power calibration's views, degC: where the
    /// driver's compensation was calibrated (a current calibration's are its thermal
    /// part's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_power_t_range_c: Option<[f64; 2]>,
    /// RMS reprojection error, px (sqrt of the mean squared point distance).
    pub rms_reprojection_px: f64,
    /// One standard deviation of each number.
    pub std: ModelStd,
    /// `"paper"` or `"eiv"`.
    #[serde(default)]
    pub estimator: String,
    /// Bundle-adjustment iterations.
    #[serde(default)]
    pub iterations: usize,
    /// RMS reprojection error before bundle adjustment, px.
    #[serde(default)]
    pub initial_rms_px: f64,
    /// Per-view summaries.
    #[serde(default)]
    pub views: Vec<ViewSummary>,
    /// Covariance of the model's numbers (optional: older files have none), p rows of p
    /// (25 for the paper's model) in the order of `etl_core::calib::params::Layout::names`
    /// (om1..om3, tx..tz, kf_x, kf_y, u0, v0, the a_i), each number in its own unit; its
    /// diagonal is `std` squared. For the errors-in-variables estimator it is that of the
    /// shared numbers with the per-view corrections marginalised out (the Schur
    /// complement).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covariance: Option<Vec<Vec<f64>>>,
    /// What `covariance` accounts for ([`CovarianceNoise`]); absent in files written
    /// before it was recorded, in which an `"estimator": "paper"` covariance holds the
    /// pixel noise only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covariance_noise: Option<CovarianceNoise>,
    /// The focus law: the distance in focus (mm, along the optical axis from the camera's
    /// centre) against E_com, fitted to the views (optional; absent when the views did not
    /// allow one, and in files written before it existed).
    /// A focal-power calibration's law is in dpt, and so are its keys
    /// (`coefficients_dpt`, `focal_power_range_dpt`, `rms_dpt`).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "focus_law_keys::write",
        deserialize_with = "focus_law_keys::read"
    )]
    pub focus_law: Option<FocusLaw>,
    /// The corners found to be gross outliers after the bundle adjustment and left out of
    /// the final solve (optional: absent when there are none, and in older files).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outliers: Vec<Outlier>,
    /// The corners Zhang's method left out as gross outliers at the settings of the
    /// per-setting baseline (`estimator` "per-setting"): `view` indexes the observations'
    /// `setting_views`, `point` that view's `points` (optional: absent when there are none,
    /// and in files of the other estimators).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub setting_outliers: Vec<Outlier>,
    /// The observations' setting views in the order of the observations, as the bundle
    /// adjustment solved them with the stage views (`calibrate --setting-views joint`:
    /// [`SettingViewSummary`]; optional: absent when they were not in the solve).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub setting_views: Vec<SettingViewSummary>,
    /// Why the result may be implausible (e.g. current corrections far beyond their prior,
    /// an RMS far above the detector's noise), one sentence each (optional: absent when
    /// there are none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// How the model was chosen (`calibrate --distortion auto` / `--focal-degree auto`):
    /// the comparison table ([`crate::model_selection`]); absent when the model was given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_selection: Option<crate::model_selection::ModelSelection>,
}

/// The noise a calibration's covariance accounts for: the corners' pixel noise, and the
/// spread of each view's recorded stage position and current. For the errors-in-variables
/// estimator the spreads are its priors; for the paper's (which takes the recorded values
/// as exact) they are the errors its covariance adds (docs/METHOD.md, "Uncertainty of the
/// paper estimator"), absent when it accounts for the pixel noise alone.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CovarianceNoise {
    /// Pixel noise standard deviation, px (given, or estimated from the residuals).
    pub sigma_px: f64,
    /// Standard deviation of a view's recorded stage position, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_z_mm: Option<f64>,
    /// Standard deviation of a view's recorded current, mA.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_e_ma: Option<f64>,
    /// Standard deviation of a view's focal power, dpt (a focal-power calibration, in place
    /// of `sigma_e_ma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_p_dpt: Option<f64>,
}

impl CovarianceNoise {
    /// A finite pixel noise >= 0 and finite spreads > 0, or the message naming the field.
    fn validate(&self) -> std::result::Result<(), String> {
        if !(self.sigma_px.is_finite() && self.sigma_px >= 0.0) {
            return Err(format!("covariance_noise.sigma_px = {} must be a finite number >= 0", self.sigma_px));
        }
        for (key, v) in
            [("sigma_z_mm", self.sigma_z_mm), ("sigma_e_ma", self.sigma_e_ma), ("sigma_p_dpt", self.sigma_p_dpt)]
        {
            if let Some(v) = v.filter(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(format!("covariance_noise.{key} = {v} must be a finite number > 0"));
            }
        }
        Ok(())
    }
}

/// A corner left out of a calibration as a gross outlier (`outliers`: of the observations'
/// `views`; `setting_outliers`: of their `setting_views`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Outlier {
    /// Index of the view in the observations' `views`.
    pub view: usize,
    /// Index of the point in that view's `points`.
    pub point: usize,
    /// Its reprojection error under the final model, px (the distance).
    pub residual_px: f64,
}

/// Relative tolerance of the covariance checks of [`Calibration::validate`]: symmetry
/// (|c_ij - c_ji| <= tol sqrt(c_ii c_jj)), Cauchy-Schwarz (|c_ij| <= (1 + tol)
/// sqrt(c_ii c_jj)) and the diagonal against `std` (|sqrt(c_ii) - std_i| <= tol std_i).
pub const COVARIANCE_TOLERANCE: f64 = 1e-9;

/// Where [`Calibration::pixel_projection_std`] evaluates a direction (a point at infinity)
/// along its ray, mm.
pub const AT_INFINITY_MM: f64 = 1e12;

impl Calibration {
    /// A calibration of `model` for images of `image_size` px over `e_com_range_ma`, with
    /// no thermal part, zero standard deviations, zero RMS and no views: an exact model,
    /// not an estimate. Estimators fill in the rest (`Calibration { .., ..from_model() }`).
    pub fn from_model(model: &CameraModel, image_size: [u32; 2], e_com_range_ma: [f64; 2]) -> Self {
        let layout = model.layout();
        Calibration {
            format: FORMAT.to_owned(),
            image_size,
            rotation_rodrigues: model.rotation_rodrigues,
            translation_mm: model.translation_mm,
            kf_x: model.kf_x.coefficients().to_vec(),
            kf_y: model.kf_y.coefficients().to_vec(),
            principal_point: model.principal_point,
            distortion_model: distortion_model_field(model.distortion_model()),
            distortion_a: model.distortion_a.as_slice().to_vec(),
            centre: model.centre.as_ref().map(|c| CentreField::of(c, model.principal_point)),
            thermal: None,
            temperature_compensation: None,
            setting: None,
            e_com_range_ma,
            focal_power_range_dpt: None,
            focal_power_t_range_c: None,
            rms_reprojection_px: 0.0,
            std: ModelStd::zero(&layout),
            estimator: String::new(),
            outliers: Vec::new(),
            setting_outliers: Vec::new(),
            setting_views: Vec::new(),
            warnings: Vec::new(),
            iterations: 0,
            initial_rms_px: 0.0,
            views: vec![],
            covariance: None,
            covariance_noise: None,
            focus_law: None,
            model_selection: None,
        }
    }

    /// This calibration made a focal-power one: `setting` says so, the range moves from
    /// `e_com_range_ma` to `focal_power_range_dpt`, `t_range_c` is that of the views, and
    /// each view summary's setting moves from `e_com_ma` to `focal_power_dpt`.
    pub fn into_focal_power(mut self, t_range_c: Option<[f64; 2]>) -> Self {
        self.setting = Some(SettingKind::FocalPower);
        self.focal_power_range_dpt = Some(self.e_com_range_ma);
        self.e_com_range_ma = absent_range();
        self.focal_power_t_range_c = t_range_c;
        self.temperature_compensation = None;
        for v in &mut self.views {
            v.focal_power_dpt = Some(v.e_com_ma);
            v.e_com_ma = f64::NAN;
            v.de_dpt = Some(v.de_ma);
            v.de_ma = f64::NAN;
        }
        if let Some(n) = &mut self.covariance_noise {
            n.sigma_p_dpt = n.sigma_e_ma.take();
        }
        if let Some(law) = &mut self.focus_law {
            law.setting = SettingKind::FocalPower;
        }
        self
    }

    /// What the calibration's setting is ([`SettingKind`]; absent means a current).
    pub fn setting_kind(&self) -> SettingKind {
        self.setting.unwrap_or_default()
    }

    /// The calibrated range of the setting, in its unit: `e_com_range_ma`, or
    /// `focal_power_range_dpt` (NaN when the file lacks it, which validation refuses).
    pub fn setting_range(&self) -> [f64; 2] {
        match self.setting_kind() {
            SettingKind::Current => self.e_com_range_ma,
            SettingKind::FocalPower => self.focal_power_range_dpt.unwrap_or_else(absent_range),
        }
    }

    /// The distortion family: `"distortion_model"`, the paper's when absent. Errors: a
    /// name that is no family (naming the field).
    pub fn distortion_model(&self) -> Result<DistortionModel> {
        match self.distortion_model.as_deref() {
            None => Ok(DistortionModel::Paper),
            Some(name) => DistortionModel::from_name(name).ok_or_else(|| {
                Error::invalid_value(
                    "distortion_model",
                    name,
                    format!("distortion_model = {name:?} is not a distortion model: use \"paper\" or \"opencv\""),
                )
            }),
        }
    }

    /// The layout of the model's numbers (family and focal degree; that of `std` and
    /// `covariance`). Errors: as [`Self::model`].
    pub fn layout(&self) -> Result<Layout> {
        Ok(self.model()?.layout())
    }

    /// Stores `covariance` (of the model's numbers, at capacity, as `etl_core`'s bundle
    /// adjustment reports it) as the file's `"covariance"` of the model's layout:
    /// symmetrised as (C + C^T) / 2, since the solver's products are symmetric only to
    /// rounding; a negative diagonal entry (rounding of a held number, whose `std` the
    /// solver reports as 0) is stored as 0 with its row and column, so that the diagonal
    /// stays `std` squared. Errors: a calibration whose model is invalid ([`Self::model`]).
    pub fn set_covariance(&mut self, covariance: &[[f64; MAX_PARAMS]; MAX_PARAMS]) -> Result<()> {
        let n = self.layout()?.len();
        let mut c: Vec<Vec<f64>> =
            (0..n).map(|i| (0..n).map(|j| 0.5 * (covariance[i][j] + covariance[j][i])).collect()).collect();
        for i in 0..n {
            if !(c[i][i] >= 0.0) {
                for j in 0..n {
                    c[i][j] = 0.0;
                    c[j][i] = 0.0;
                }
            }
        }
        self.covariance = Some(c);
        Ok(())
    }

    /// The covariance as a matrix at capacity (zero past the layout's numbers), or `None`
    /// when the file has none (or, in a file not validated, one of the wrong shape).
    pub fn covariance_matrix(&self) -> Option<[[f64; MAX_PARAMS]; MAX_PARAMS]> {
        let rows = self.covariance.as_ref()?;
        let n = self.layout().ok()?.len();
        if rows.len() != n || rows.iter().any(|r| r.len() != n) {
            return None;
        }
        let mut c = [[0.0; MAX_PARAMS]; MAX_PARAMS];
        for (out, row) in c.iter_mut().zip(rows) {
            for (o, &v) in out.iter_mut().zip(row) {
                *o = v;
            }
        }
        Some(c)
    }

    /// The standard deviation of the pixel the calibrated model projects `world_mm` to
    /// at `e_com_ma`, due to the calibration's uncertainty: Sigma_p = J_p C J_p^T
    /// (`etl_core::calib::projection_uncertainty`), per axis and as the 2 x 2 covariance.
    ///
    /// Errors: a calibration without a covariance (older files); `e_com_ma` outside the
    /// calibrated range (margin 5 mA) unless `trust` is [`Trust::Extrapolate`]; a NaN;
    /// the point at or behind the camera.
    pub fn projection_std(&self, world_mm: [f64; 3], e_com_ma: f64, trust: Trust) -> Result<PixelUncertainty> {
        let c = self.require_covariance()?;
        self.camera()?.at_e_com(e_com_ma, trust)?;
        Ok(projection_uncertainty(&self.model()?, &c, world_mm, e_com_ma)?)
    }

    /// The standard deviation, in mrcal's sense, of the re-projection of the point seen at
    /// `pixel` at `e_com_ma`: the point at `distance_mm` from the projection centre along
    /// that pixel's ray, or for `None` in that direction (a point at infinity), held fixed in
    /// the stage frame while the calibration varies within its covariance. The same
    /// Sigma_p = J_p C J_p^T as [`Self::projection_std`], whose world point this is.
    ///
    /// A direction is evaluated at [`AT_INFINITY_MM`] along the ray: there the translation
    /// moves the pixel by f |T| / 1e12 (under 1e-6 px for |T| < 100 mm and f < 10^4 px) and
    /// its derivatives scale with 1 / distance, so the result is the direction's to far
    /// below any calibration's standard deviation (tested against 1e9 mm).
    ///
    /// Errors: those of [`Self::projection_std`]; a distance that is not a finite number
    /// > 0; a pixel that does not unproject (outside the distortion's domain).
    pub fn pixel_projection_std(
        &self,
        pixel: [f64; 2],
        e_com_ma: f64,
        distance_mm: Option<f64>,
        trust: Trust,
    ) -> Result<PixelUncertainty> {
        if let Some(d) = distance_mm.filter(|d| !(d.is_finite() && *d > 0.0)) {
            let message = format!("distance_mm = {d} must be a finite number > 0 (None: a direction)");
            return Err(Error::invalid_value("distance_mm", d, message));
        }
        self.require_covariance()?;
        self.camera()?.at_e_com(e_com_ma, trust)?;
        let ray = self.model()?.ray(pixel, e_com_ma)?;
        self.projection_std(ray.at(distance_mm.unwrap_or(AT_INFINITY_MM)), e_com_ma, trust)
    }

    /// The covariance, or an error saying that the file has none.
    pub fn require_covariance(&self) -> Result<[[f64; MAX_PARAMS]; MAX_PARAMS]> {
        self.covariance_matrix().ok_or_else(|| {
            Error::invalid(
                "covariance",
                "this calibration has no covariance (files written before it was recorded): calibrate again to get one",
            )
        })
    }

    /// The checks of `"covariance"` (see [`COVARIANCE_TOLERANCE`]): p x p for the model's
    /// p numbers, finite, symmetric, a non-negative diagonal equal to `std` squared,
    /// |c_ij| <= sqrt(c_ii c_jj).
    fn validate_covariance(&self, layout: &Layout) -> std::result::Result<(), String> {
        let Some(rows) = &self.covariance else { return Ok(()) };
        let n = layout.len();
        if rows.len() != n {
            return Err(format!("covariance must be {n} x {n}: it has {} rows", rows.len()));
        }
        if let Some((i, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != n) {
            return Err(format!("covariance must be {n} x {n}: row {i} has {} numbers", r.len()));
        }
        let std = self.std.checked_params(layout)?;
        let name = |i: usize| layout.name(i);
        let tol = COVARIANCE_TOLERANCE;
        for i in 0..n {
            let cii = rows[i][i];
            if !(cii.is_finite() && cii >= 0.0) {
                return Err(format!("covariance[{i}][{i}] = {cii} (variance of {}) must be finite and >= 0", name(i)));
            }
            if (cii.sqrt() - std[i]).abs() > tol * std[i].max(cii.sqrt()) {
                return Err(format!(
                    "covariance[{i}][{i}] = {cii} (variance of {}) is not std squared (std {})",
                    name(i),
                    std[i]
                ));
            }
        }
        for i in 0..n {
            for j in 0..n {
                let (cij, cji) = (rows[i][j], rows[j][i]);
                let scale = (rows[i][i] * rows[j][j]).sqrt();
                if !cij.is_finite() {
                    return Err(format!("covariance[{i}][{j}] = {cij} must be finite"));
                }
                if (cij - cji).abs() > tol * scale {
                    return Err(format!(
                        "covariance is not symmetric: [{i}][{j}] = {}, [{j}][{i}] = {}",
                        crate::compact(cij),
                        crate::compact(cji)
                    ));
                }
                if cij.abs() > (1.0 + tol) * scale {
                    return Err(format!(
                        "covariance[{i}][{j}] = {} exceeds sqrt(c_ii c_jj) = {} ({}, {}): not a covariance",
                        crate::compact(cij),
                        crate::compact(scale),
                        name(i),
                        name(j)
                    ));
                }
            }
        }
        Ok(())
    }

    /// The camera model. Errors (naming the field): an unknown `distortion_model`; `kf_x`,
    /// `kf_y` not of 2..=6 numbers or of different lengths; `distortion_a` not of the
    /// family's length.
    pub fn model(&self) -> Result<CameraModel> {
        model_of(
            self.distortion_model()?,
            self.rotation_rodrigues,
            self.translation_mm,
            (&self.kf_x, &self.kf_y),
            self.principal_point,
            &self.distortion_a,
            self.centre.as_ref(),
        )
        .map_err(|m| Error::invalid(leading_field(&m).to_owned(), m))
    }

    /// The thermal surface the calibration was made with. A file without one is refused
    /// here rather than given a default: a surface assumed silently changes every E_com.
    pub fn thermal_surface(&self) -> Result<ThermalSurface> {
        Ok(self.thermal_ref()?.trust().surface)
    }

    /// The thermal part, refused when absent (as [`Self::thermal_surface`]).
    pub fn thermal_ref(&self) -> Result<&ThermalRef> {
        self.thermal.as_ref().ok_or_else(|| {
            Error::invalid(
                "thermal",
                "this calibration has no temperature compensation (thermal); pass E_com directly or add one",
            )
        })
    }

    /// The run-time camera of this calibration (etl-core, no allocation): model, thermal
    /// part with its ranges, calibrated E_com range.
    pub fn camera(&self) -> Result<Camera> {
        Ok(match self.setting_kind() {
            SettingKind::Current => {
                Camera::new(self.model()?, self.thermal.as_ref().map(ThermalRef::trust), self.e_com_range_ma)?
            }
            SettingKind::FocalPower => {
                Camera::new_focal_power(self.model()?, self.setting_range(), self.focal_power_t_range_c)?
            }
        })
    }

    /// The camera of a focal-power calibration at commanded focal power
    /// `focal_power_dpt` and lens temperature `temperature_c`, refused outside the
    /// calibrated power and temperature ranges unless `trust` is [`Trust::Extrapolate`]
    /// ([`Camera::at_focal_power_with`]). A current calibration refuses it.
    pub fn at_focal_power(&self, focal_power_dpt: f64, temperature_c: f64, trust: Trust) -> Result<CameraAt> {
        Ok(self.camera()?.at_focal_power_with(focal_power_dpt, temperature_c, trust)?)
    }

    /// The camera at driver current `e_in_ma` and temperature `temperature_c`, refused
    /// outside the calibrated ranges unless `trust` is [`Trust::Extrapolate`]
    /// ([`Camera::at_with`]).
    pub fn at(&self, e_in_ma: f64, temperature_c: f64, trust: Trust) -> Result<CameraAt> {
        Ok(self.camera()?.at_with(e_in_ma, temperature_c, trust)?)
    }

    /// The camera at a known compensated current `e_com_ma` (a calibration without a
    /// thermal part, or E_com compensated elsewhere), refused outside the calibrated E_com
    /// range (margin [`etl_core::runtime::E_COM_MARGIN_MA`]) unless `trust` is
    /// [`Trust::Extrapolate`] ([`Camera::at_e_com`]); E_in and T of the result are NaN.
    pub fn at_e_com(&self, e_com_ma: f64, trust: Trust) -> Result<CameraAt> {
        Ok(self.camera()?.at_e_com(e_com_ma, trust)?)
    }

    /// The warning of a calibration that has no temperature compensation
    /// ([`NO_TEMPERATURE_COMPENSATION`]), or None.
    pub fn temperature_compensation_warning(&self) -> Option<&'static str> {
        self.temperature_compensation.map(|TemperatureCompensation::None| NO_TEMPERATURE_COMPENSATION)
    }

    /// The one check of a calibration, made by every reader and writer (CLI and Python):
    /// a valid camera model, an image size within `check_image_size`, an ordered current
    /// range within the driver's `E_IN_DOMAIN_MA`, a
    /// valid thermal surface when there is one, and a finite RMS >= 0. `path` names the
    /// file in the message.
    pub fn validate(&self, path: &Path) -> Result<()> {
        let bad = |message: String| Err(Error::Parse { path: path.to_owned(), message });
        let model = match self.model() {
            Ok(m) => m,
            Err(Error::InvalidInput { message, .. }) => return bad(message),
            Err(e) => return bad(e.to_string()),
        };
        if let Err(e) = model.validate() {
            return bad(e.to_string());
        }
        if let Err(e) = crate::check_image_size(self.image_size, "image_size") {
            return bad(e.to_string());
        }
        self.validate_setting().or_else(bad)?;
        if let Some(t) = &self.thermal {
            if let Err(e) = t.trust().validate() {
                return bad(format!("thermal: {e}"));
            }
            if !t.rms_ma.is_none_or(|r| r.is_finite() && r >= 0.0) {
                return bad(format!("thermal.rms_ma = {:?} must be a finite number >= 0", t.rms_ma));
            }
        }
        if self.thermal.is_some() && self.temperature_compensation.is_some() {
            return bad("temperature_compensation = \"none\" but the calibration has a thermal part: remove one".into());
        }
        if !(self.rms_reprojection_px.is_finite() && self.rms_reprojection_px >= 0.0) {
            return bad(format!("rms_reprojection_px = {} must be a finite number >= 0", self.rms_reprojection_px));
        }
        if let Some(law) = &self.focus_law {
            if let Err(e) = law.validate() {
                return bad(e.to_string());
            }
        }
        if let Some(sel) = &self.model_selection {
            if let Err(e) = sel.validate() {
                return bad(e.to_string());
            }
        }
        for (key, list) in [("outliers", &self.outliers), ("setting_outliers", &self.setting_outliers)] {
            if let Some((i, o)) = list.iter().enumerate().find(|(_, o)| !(o.residual_px >= 0.0)) {
                return bad(format!("{key}[{i}].residual_px = {} must be a number >= 0", o.residual_px));
            }
        }
        if let Some((i, o)) = self.outliers.iter().enumerate().find(|(_, o)| o.view >= self.views.len()) {
            return bad(format!("outliers[{i}].view = {} must name one of the {} views", o.view, self.views.len()));
        }
        if let Err(e) = self.std.checked_params(&model.layout()) {
            return bad(e);
        }
        if let Some(n) = &self.covariance_noise {
            n.validate().or_else(bad)?;
        }
        self.validate_covariance(&model.layout()).or_else(bad)
    }

    /// The setting's fields (`validate`): a current calibration's `e_com_range_ma` within
    /// the driver's `E_IN_DOMAIN_MA`, and no focal-power field; a focal-power calibration's
    /// `focal_power_range_dpt` within `FOCAL_POWER_DOMAIN_DPT`, its temperature range
    /// ordered, and neither `e_com_range_ma` nor a thermal part.
    fn validate_setting(&self) -> std::result::Result<(), String> {
        let (key, [lo, hi], [d0, d1], unit) = match self.setting_kind() {
            SettingKind::Current => {
                if self.focal_power_range_dpt.is_some() || self.focal_power_t_range_c.is_some() {
                    return Err("focal_power_range_dpt or focal_power_t_range_c in a current calibration: \
                                give \"setting\": \"focal_power\" or remove them"
                        .into());
                }
                let absent = |v: &ViewSummary| v.e_com_ma.is_nan() || v.de_ma.is_nan() || v.focal_power_dpt.is_some();
                if let Some(i) = self.views.iter().position(absent) {
                    return Err(format!(
                        "views[{i}] needs e_com_ma and de_ma (and no focal_power_dpt) in a current calibration"
                    ));
                }
                ("e_com_range_ma", self.e_com_range_ma, etl_core::thermal::E_IN_DOMAIN_MA, "mA")
            }
            SettingKind::FocalPower => {
                if !is_absent_range(&self.e_com_range_ma) || self.thermal.is_some() {
                    return Err("a focal-power calibration has neither e_com_range_ma nor a thermal part (the \
                                driver compensates the temperature): remove them"
                        .into());
                }
                let present =
                    |v: &ViewSummary| !v.e_com_ma.is_nan() || !v.de_ma.is_nan() || v.focal_power_dpt.is_none();
                if let Some(i) = self.views.iter().position(present) {
                    return Err(format!(
                        "views[{i}] needs focal_power_dpt and de_dpt (and neither e_com_ma nor de_ma) in a focal-power calibration"
                    ));
                }
                let t = self.focal_power_t_range_c.unwrap_or([0.0; 2]);
                if !(t[0].is_finite() && t[1].is_finite() && t[0] <= t[1]) {
                    return Err("focal_power_t_range_c must be a finite [min, max] degC".into());
                }
                let range = self.focal_power_range_dpt.unwrap_or_else(absent_range);
                ("focal_power_range_dpt", range, crate::lens_setting::FOCAL_POWER_DOMAIN_DPT, "dpt")
            }
        };
        // Within the driver's range: a range of 1e308 would also hang a plot's axis.
        if !(lo.is_finite() && hi.is_finite() && lo <= hi && d0 <= lo && hi <= d1) {
            return Err(format!(
                "{key} [{}, {}] must be a [min, max] within the lens driver's [{d0}, {d1}] {unit}",
                crate::compact(lo),
                crate::compact(hi)
            ));
        }
        Ok(())
    }

    /// The focus law, or an error saying that this calibration has none.
    pub fn focus_law(&self) -> Result<&FocusLaw> {
        self.focus_law.as_ref().ok_or_else(|| {
            Error::invalid(
                "focus_law",
                "this calibration has no focus law (focus_law); recalibrate with views at >= 4 distinct currents",
            )
        })
    }

    /// The driver current E_in (mA) that focuses the camera at `distance_mm` (the depth of
    /// the plane in focus, i.e. its distance along the optical axis from the camera's
    /// centre) at lens temperature `temperature_c`: E_com = law(distance), then E_in such
    /// that E_in - E_T(T, E_in) = E_com.
    ///
    /// Errors: no focus law; a distance outside the law's calibrated distances (+- 2 %,
    /// [`etl_core::focus::FOCUS_LAW_RANGE_MARGIN`]); no thermal part; a setting outside
    /// the calibrated ranges unless `trust` is [`Trust::Extrapolate`] ([`Self::at`]).
    pub fn focus_e_in(&self, distance_mm: f64, temperature_c: f64, trust: Trust) -> Result<f64> {
        let e_com_ma = self.focus_law()?.e_com_ma(distance_mm)?;
        self.focus_thermal(e_com_ma, temperature_c, Direction::EInForECom, trust)
    }

    /// The focal power (dpt) that focuses a focal-power calibration's camera at
    /// `distance_mm` (as [`Self::focus_e_in`]) at lens temperature `temperature_c`: the
    /// law's power there, the driver compensating the temperature. The law is in dioptres:
    /// P = c0 + c1 V + c2 V^2 with the vergence V = 1000 / distance (docs/METHOD.md, "The
    /// focus law in dioptres": thin lenses add their powers, so the power that brings a
    /// plane at vergence V into focus on a fixed sensor is V plus a constant, to first
    /// order, and c2 takes the ETL's distance from the pupil).
    ///
    /// Errors: not a focal-power calibration; no focus law; a distance outside the law's
    /// calibrated distances (+- 2 %); a power or temperature outside the calibrated ranges
    /// unless `trust` is [`Trust::Extrapolate`] ([`Self::at_focal_power`]).
    pub fn focus_focal_power_dpt(&self, distance_mm: f64, temperature_c: f64, trust: Trust) -> Result<f64> {
        let dpt = self.focus_law()?.e_com_ma(distance_mm)?;
        self.at_focal_power(dpt, temperature_c, trust)?;
        Ok(dpt)
    }

    /// The distance in focus (mm, as [`Self::focus_e_in`]) at driver current `e_in_ma` and
    /// lens temperature `temperature_c`: E_com through the thermal surface, then the law.
    ///
    /// Errors: no focus law; no thermal part; a setting outside the calibrated ranges
    /// unless `trust` is [`Trust::Extrapolate`]; an E_com outside the law's calibrated
    /// currents (+- 2 %).
    pub fn focus_distance_mm(&self, e_in_ma: f64, temperature_c: f64, trust: Trust) -> Result<f64> {
        let law = self.focus_law()?;
        let e_com_ma = self.focus_thermal(e_in_ma, temperature_c, Direction::EComForEIn, trust)?;
        Ok(law.distance_mm(e_com_ma)?)
    }

    /// The one use of the thermal conversion by the focus functions (so that the range
    /// policy of the temperature compensation applies to them in one place): E_com of
    /// (E_in, T), or the E_in of (E_com, T).
    /// The setting is checked by [`Self::at`], the one range policy.
    fn focus_thermal(&self, current_ma: f64, temperature_c: f64, direction: Direction, trust: Trust) -> Result<f64> {
        Ok(match direction {
            Direction::EComForEIn => self.at(current_ma, temperature_c, trust)?.e_com_ma(),
            Direction::EInForECom => {
                // The temperature is judged before the inverse, whose own message would
                // otherwise blame the current.
                let thermal = self.thermal_ref()?.trust();
                thermal.check_temperature(temperature_c, trust)?;
                let e_in_ma = thermal.surface.e_in_for_e_com(current_ma, temperature_c)?;
                self.at(e_in_ma, temperature_c, trust)?;
                e_in_ma
            }
        })
    }

    /// Reads and checks a file.
    pub fn load(path: &Path) -> Result<Self> {
        let c: Calibration = read_json(path, FORMAT)?;
        c.validate(path)?;
        Ok(c)
    }

    /// Parses and checks `etlcal.calibration/1` text; `path` names it in messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let c: Calibration = parse_json(text, path, FORMAT)?;
        c.validate(path)?;
        Ok(c)
    }

    /// Checks and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate(path)?;
        write_json(path, self)
    }
}
