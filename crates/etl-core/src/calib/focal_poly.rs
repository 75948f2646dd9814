//! The focal polynomial and tz (Eq. 21-22), given R, tx, ty from RAC and A0.
//!
//! With Z_C = w + tz, w = r7 X + r8 Y + r9 Z, and centred u = fx(E) X_C / Z_C, the row of
//! the x equation for [kf1x, kf2x, kf3x, tz] is (docs/METHOD.md: the paper prints +u, a sign typo)
//!
//! ```text
//! [X_C E, X_C E^2, X_C E^3, -u] . [kf1x, kf2x, kf3x, tz] = u w - kf0x X_C
//! ```
//!
//! and likewise for y with v, Y_C, kf0y. etlcal solves both sets *together*, sharing tz
//! (7 unknowns), which uses every observation for tz; E is scaled by 100 mA inside so
//! the columns have comparable size. Needs at least 3 distinct currents (Appendix I).

use super::observations::{distinct_currents, validate, View};
use super::rac::RacSolution;
use crate::error::{Error, Result};
use crate::fit::GivensQr;
use crate::model::rotation::mat_vec;

/// The focal-length coefficients of both axes and tz.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocalPolySolution {
    /// kf0x..kf3x (kf0x as given).
    pub kf_x: [f64; 4],
    /// kf0y..kf3y (kf0y as given).
    pub kf_y: [f64; 4],
    /// tz, mm.
    pub tz_mm: f64,
}

const E_SCALE_MA: f64 = 100.0;

/// Solves Eq. 21-22 over all views.
///
/// Preconditions: at least 3 distinct currents ([`Error::TooFew`]); finite input; the
/// system of full column rank ([`Error::Degenerate`]).
pub fn focal_poly(
    views: &[View<'_>],
    rac: &RacSolution,
    kf0: [f64; 2],
    principal_point: [f64; 2],
) -> Result<FocalPolySolution> {
    validate(views)?;
    let nc = distinct_currents(views);
    if nc < 3 {
        return Err(Error::TooFew { what: "distinct currents (Appendix I)", needed: 3, got: nc });
    }
    if !(kf0[0].is_finite() && kf0[1].is_finite() && principal_point[0].is_finite() && principal_point[1].is_finite()) {
        return Err(Error::NotFinite { what: "A0 (kf0x, kf0y, u0, v0)" });
    }
    let r = &rac.rotation;
    let mut qr = GivensQr::<7>::full();
    for view in views {
        let e = view.e_com_ma / E_SCALE_MA;
        for p in view.points {
            let rw = mat_vec(r, p.world_mm);
            let (xc, yc, w) = (rw[0] + rac.tx_mm, rw[1] + rac.ty_mm, rw[2]);
            let (u, v) = (p.pixel[0] - principal_point[0], p.pixel[1] - principal_point[1]);
            qr.add_row(&[xc * e, xc * e * e, xc * e * e * e, 0.0, 0.0, 0.0, -u], u * w - kf0[0] * xc, 1.0)?;
            qr.add_row(&[0.0, 0.0, 0.0, yc * e, yc * e * e, yc * e * e * e, -v], v * w - kf0[1] * yc, 1.0)?;
        }
    }
    let s = qr.solve().map_err(|_| Error::Degenerate {
        what: "focal polynomial system is rank deficient (currents or points too few or too alike)",
    })?;
    let (e1, e2, e3) = (E_SCALE_MA, E_SCALE_MA * E_SCALE_MA, E_SCALE_MA * E_SCALE_MA * E_SCALE_MA);
    Ok(FocalPolySolution {
        kf_x: [kf0[0], s[0] / e1, s[1] / e2, s[2] / e3],
        kf_y: [kf0[1], s[3] / e1, s[4] / e2, s[5] / e3],
        tz_mm: s[6],
    })
}
