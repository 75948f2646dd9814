//! Calibrations that mean nothing: a solution the data do not determine, refused unless
//! the caller accepts it ([`super::CalibrationRequest::accept_ill_conditioned`]).
//!
//! Two symptoms, each checked on the calibration as it would be written:
//! - **A focal length that is not positive** somewhere over the calibrated E_com range
//!   (fx(E) or fy(E), Eq. 16, at 65 evenly spaced currents and the ends): no camera has
//!   one, so the polynomials were fitted to too few currents or too little signal.
//! - **A principal point the data leave loose** (with a moving centre: u0(E), v0(E) at the
//!   ends of the range): a standard deviation of u0 above
//!   [`MAX_PRINCIPAL_POINT_STD_FRACTION`] of the image width (v0: of its height). At 5 %
//!   (97 px on a 1936 px sensor) the point is not known to within a tenth of the image; a
//!   calibration of the paper's 15 views has 0.3 px. Three views of six corners gave
//!   35,844 px.
//!
//! A standard deviation that is not finite is a singular normal matrix, the same verdict.
//! Why not the condition number of the normal matrix: its scale depends on the units of
//! the numbers (mm, px, px/mA^3), so any threshold on it would be arbitrary, where these
//! two are in the units a user judges a camera by.

use etl_core::calib::params::MAX_PARAMS;
use etl_core::calib::uncertainty::sandwich;
use etl_formats::calibration::Calibration;

/// The largest standard deviation of the principal point a calibration may have, as a
/// fraction of the image side (u0: width, v0: height): 0.05.
pub const MAX_PRINCIPAL_POINT_STD_FRACTION: f64 = 0.05;

/// Why a calibration means nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IllCondition {
    /// fx(E) (`axis` "fx") or fy(E) is <= 0 (or not finite) at `e_com_ma`.
    FocalNotPositive {
        /// "fx" or "fy".
        axis: &'static str,
        /// Where, mA.
        e_com_ma: f64,
        /// Its value there, px.
        value_px: f64,
    },
    /// The principal point's standard deviation beyond the limit (or not finite).
    PrincipalPointLoose {
        /// Of (u0, v0), px.
        std_px: [f64; 2],
        /// The image (width, height), px.
        image_size_px: [u32; 2],
    },
}

impl IllCondition {
    /// The cause and the data that would cure it, one clause.
    pub fn describe(&self) -> String {
        match *self {
            IllCondition::FocalNotPositive { axis, e_com_ma, value_px } => format!(
                "{axis}(E) is {} px at E_com {} mA (a focal length must be positive over the calibrated range); \
                 it needs views at more currents, each with more corners",
                shown(value_px),
                shown(e_com_ma)
            ),
            IllCondition::PrincipalPointLoose { std_px, image_size_px } => format!(
                "the principal point's standard deviation is ({}, {}) px, more than {} % of the {} x {} px image; \
                 it needs more views, tilted in several directions, with corners over the whole image",
                shown(std_px[0]),
                shown(std_px[1]),
                MAX_PRINCIPAL_POINT_STD_FRACTION * 100.0,
                image_size_px[0],
                image_size_px[1]
            ),
        }
    }
}

/// A number for people: two decimals from 0.01 to 1e5, else three significant digits in
/// scientific notation (never 309 digits for 1e308).
fn shown(v: f64) -> String {
    if v == 0.0 || (0.01..1e5).contains(&v.abs()) {
        format!("{v:.2}")
    } else {
        format!("{v:.2e}")
    }
}

/// Horner's rule for sum c_i x^i.
/// The standard deviation of (u0, v0) as the check judges it: `std.principal_point`, or
/// with a moving centre the larger of u0(E)'s (v0(E)'s) at the ends of the range, from the
/// covariance (the file's u0 is the line's value at E = 0, mostly outside the range, whose
/// spread says nothing of the point where the camera is used).
fn principal_point_std_px(cal: &Calibration) -> [f64; 2] {
    let fixed = cal.std.principal_point;
    let (Some(cov), Ok(layout)) = (cal.covariance_matrix(), cal.layout()) else { return fixed };
    if !layout.moving_centre() {
        return fixed;
    }
    let slope = layout.centre_principal_point();
    core::array::from_fn(|k| {
        let at = |e: f64| {
            // d u0(E) / d (u0, u1) = (1, E).
            let mut g = [0.0; MAX_PARAMS];
            g[[layout.u0(), layout.v0()][k]] = 1.0;
            g[slope.at(k)] = e;
            sandwich(&[g], &cov)[0][0].max(0.0).sqrt()
        };
        cal.setting_range().iter().map(|&e| at(e)).fold(f64::NEG_INFINITY, f64::max)
    })
}

fn poly(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * x + k)
}

/// The first symptom of `cal` (module doc), `None` when it has none.
pub fn ill_condition(cal: &Calibration) -> Option<IllCondition> {
    const SAMPLES: usize = 64;
    let [lo, hi] = cal.setting_range();
    for k in 0..=SAMPLES {
        let e_com_ma = lo + (hi - lo) * k as f64 / SAMPLES as f64;
        for (axis, c) in [("fx", &cal.kf_x), ("fy", &cal.kf_y)] {
            let value_px = poly(c, e_com_ma);
            if !(value_px > 0.0 && value_px.is_finite()) {
                return Some(IllCondition::FocalNotPositive { axis, e_com_ma, value_px });
            }
        }
    }
    let std_px = principal_point_std_px(cal);
    let [w, h] = cal.image_size;
    let limits = [f64::from(w), f64::from(h)].map(|side| MAX_PRINCIPAL_POINT_STD_FRACTION * side);
    let loose = std_px.iter().zip(limits).any(|(&s, limit)| !(s <= limit));
    loose.then_some(IllCondition::PrincipalPointLoose { std_px, image_size_px: cal.image_size })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn calibration() -> Calibration {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/service/calibration.json"))
                .unwrap();
        Calibration::parse(&text, std::path::Path::new("calibration.json")).unwrap()
    }

    #[test]
    fn a_sound_calibration_has_no_symptom_and_each_symptom_is_named() {
        let good = calibration();
        assert_eq!(ill_condition(&good), None);
        let mut bad = good.clone();
        bad.kf_y = vec![-100.0, 1.0];
        let hi = bad.setting_range()[1];
        match ill_condition(&bad) {
            Some(IllCondition::FocalNotPositive { axis: "fy", e_com_ma, value_px }) => {
                assert!(e_com_ma <= hi && value_px <= 0.0, "{e_com_ma} {value_px}");
            }
            other => panic!("{other:?}"),
        }
        let mut loose = good.clone();
        let limit = MAX_PRINCIPAL_POINT_STD_FRACTION * f64::from(loose.image_size[1]);
        loose.std.principal_point[1] = limit * 1.01;
        let c = ill_condition(&loose).unwrap();
        assert!(matches!(c, IllCondition::PrincipalPointLoose { .. }), "{c:?}");
        assert!(c.describe().contains("more than 5 % of the 1936 x 1458 px image"), "{}", c.describe());
        loose.std.principal_point[1] = limit * 0.99;
        assert_eq!(ill_condition(&loose), None);
        assert_eq!(
            (shown(430.22777), shown(1e308), shown(-0.001), shown(0.0)),
            ("430.23".into(), "1.00e308".into(), "-1.00e-3".into(), "0.00".into())
        );
        loose.std.principal_point[0] = f64::NAN;
        assert!(ill_condition(&loose).is_some());
    }
}
