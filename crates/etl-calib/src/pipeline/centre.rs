//! Whether the data determine a moving centre's move (docs/METHOD.md, "The moving
//! centre"): one view per current fixes only fx(E) / distance unless the view has
//! perspective, so on fronto-parallel views fx(E) and dz(E) trade and the move's standard
//! deviation grows without bound.
//!
//! The rule, in the unit a user feels: the move over the calibrated range,
//! dz(E_hi) - dz(E_lo), has a standard deviation (from the covariance) that, relative to
//! the mean working distance of the views, is a scale uncertainty of every distance the
//! camera measures. Above [`MAX_CENTRE_SCALE_STD`] (0.1 %: 2 um on a 2 mm move) the move is
//! not determined: `calibrate --centre moving` says so in its warnings, and
//! `--centre auto` does not choose it.

use etl_core::calib::params::{Layout, MAX_PARAMS};
use etl_core::calib::uncertainty::sandwich;
use etl_core::calib::View;
use etl_core::model::CameraModel;

use super::focus_law::focus_samples;

/// The largest standard deviation of the centre's move over the range, relative to the
/// mean working distance, that counts as determined.
pub const MAX_CENTRE_SCALE_STD: f64 = 1e-3;

/// The standard deviation of dz(E_hi) - dz(E_lo), mm, from `covariance` of `layout`'s
/// numbers (None for a fixed centre): g C g^T with g = d(move)/d(dz1, dz2).
pub fn move_std_mm(layout: &Layout, covariance: &[[f64; MAX_PARAMS]; MAX_PARAMS], [lo, hi]: [f64; 2]) -> Option<f64> {
    if !layout.moving_centre() {
        return None;
    }
    let dz = layout.centre_dz();
    let mut g = [0.0; MAX_PARAMS];
    g[dz.at(0)] = hi - lo;
    g[dz.at(1)] = hi * hi - lo * lo;
    Some(sandwich(&[g], covariance)[0][0].max(0.0).sqrt())
}

/// Why `model`'s moving centre is not determined by `views` (one sentence, the range in
/// the unit of `setting`), or None (a fixed centre, or a move known to within
/// [`MAX_CENTRE_SCALE_STD`] of the distance).
pub fn undetermined_move(
    model: &CameraModel,
    covariance: &[[f64; MAX_PARAMS]; MAX_PARAMS],
    views: &[View<'_>],
    setting: etl_formats::SettingKind,
) -> Option<String> {
    let lo = views.iter().map(|v| v.e_com_ma).fold(f64::INFINITY, f64::min);
    let hi = views.iter().map(|v| v.e_com_ma).fold(f64::NEG_INFINITY, f64::max);
    let std_mm = move_std_mm(&model.layout(), covariance, [lo, hi])?;
    let samples = focus_samples(model, views);
    let distance_mm = samples.iter().map(|s| s.distance_mm).sum::<f64>() / samples.len().max(1) as f64;
    let relative = std_mm / distance_mm.abs();
    if relative <= MAX_CENTRE_SCALE_STD {
        return None;
    }
    let range = match setting {
        etl_formats::SettingKind::Current => format!("{lo:.0}..{hi:.0} mA"),
        etl_formats::SettingKind::FocalPower => format!("{lo:.2}..{hi:.2} dpt"),
    };
    Some(format!(
        "the data do not determine the centre's move: its standard deviation over {range} is {std_mm:.3} \
         mm, {:.2} % of the {distance_mm:.0} mm working distance (at most {:.1} %): only perspective in the views tells \
         fx(E) from dz(E); tilt the board on the stage further, add views, or keep the fixed centre (docs/RIG.md)",
        100.0 * relative,
        100.0 * MAX_CENTRE_SCALE_STD
    ))
}
