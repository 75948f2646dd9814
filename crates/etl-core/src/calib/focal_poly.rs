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
//! (7 unknowns for the cubic, 2 d + 1 for degree d), which uses every observation for tz;
//! E is scaled by 100 mA inside so the columns have comparable size. Needs at least
//! max(3, d) distinct currents (Appendix I for the cubic; d coefficients past kf0 in
//! general).

use super::observations::{distinct_currents, validate, View};
use super::rac::RacSolution;
use crate::error::{Error, Result};
use crate::fit::GivensQr;
use crate::model::rotation::mat_vec;
use crate::model::{FocalPoly, MAX_FOCAL_DEGREE, PAPER_FOCAL_DEGREE};

/// The focal-length coefficients of both axes and tz.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocalPolySolution {
    /// kf0x..kf_dx (kf0x as given).
    pub kf_x: FocalPoly,
    /// kf0y..kf_dy (kf0y as given).
    pub kf_y: FocalPoly,
    /// tz, mm.
    pub tz_mm: f64,
}

const E_SCALE_MA: f64 = 100.0;
/// Unknowns of the largest system: kf1..kf5 of each axis and tz.
const MAX_UNKNOWNS: usize = 2 * MAX_FOCAL_DEGREE + 1;

/// The fewest distinct currents that determine a focal polynomial of degree `degree`:
/// max(3, d) (Appendix I asks 3 for the paper's cubic).
pub const fn min_distinct_currents(degree: usize) -> usize {
    if degree > 3 {
        degree
    } else {
        3
    }
}

/// Solves Eq. 21-22 over all views for the paper's cubic.
///
/// Preconditions: at least 3 distinct currents ([`Error::TooFew`]); finite input; the
/// system of full column rank ([`Error::Degenerate`]).
pub fn focal_poly(
    views: &[View<'_>],
    rac: &RacSolution,
    kf0: [f64; 2],
    principal_point: [f64; 2],
) -> Result<FocalPolySolution> {
    focal_poly_of_degree(views, rac, kf0, principal_point, PAPER_FOCAL_DEGREE)
}

/// Solves Eq. 21-22 over all views for focal polynomials of degree `degree` (1..=5).
///
/// Preconditions: a degree in 1..=5 ([`Error::OutOfRange`]); at least
/// [`min_distinct_currents`] distinct currents ([`Error::TooFew`]); finite input; the
/// system of full column rank ([`Error::Degenerate`]).
pub fn focal_poly_of_degree(
    views: &[View<'_>],
    rac: &RacSolution,
    kf0: [f64; 2],
    principal_point: [f64; 2],
    degree: usize,
) -> Result<FocalPolySolution> {
    if !(1..=MAX_FOCAL_DEGREE).contains(&degree) {
        return Err(Error::OutOfRange { what: "focal_degree", value: degree as f64, min: 1.0, max: 5.0 });
    }
    validate(views)?;
    let nc = distinct_currents(views);
    let needed = min_distinct_currents(degree);
    if nc < needed {
        let what = if degree <= 3 { "distinct currents (Appendix I)" } else { "distinct currents (focal degree)" };
        return Err(Error::TooFew { what, needed, got: nc });
    }
    if !(kf0[0].is_finite() && kf0[1].is_finite() && principal_point[0].is_finite() && principal_point[1].is_finite()) {
        return Err(Error::NotFinite { what: "A0 (kf0x, kf0y, u0, v0)" });
    }
    let r = &rac.rotation;
    let d = degree;
    // Unknowns: kf1x..kfdx at 0..d, kf1y..kfdy at d..2d, tz at 2d.
    let mut qr = GivensQr::<MAX_UNKNOWNS>::new(2 * d + 1)?;
    for view in views {
        let e = view.e_com_ma / E_SCALE_MA;
        for p in view.points {
            let rw = mat_vec(r, p.world_mm);
            let (xc, yc, w) = (rw[0] + rac.tx_mm, rw[1] + rac.ty_mm, rw[2]);
            let (u, v) = (p.pixel[0] - principal_point[0], p.pixel[1] - principal_point[1]);
            let (mut rx, mut ry) = ([0.0; MAX_UNKNOWNS], [0.0; MAX_UNKNOWNS]);
            // X_C E^k as ((X_C E) E) ...: the products of the paper cubic's rows.
            let (mut tx, mut ty) = (xc, yc);
            for k in 0..d {
                tx *= e;
                ty *= e;
                set(&mut rx, k, tx);
                set(&mut ry, d + k, ty);
            }
            set(&mut rx, 2 * d, -u);
            set(&mut ry, 2 * d, -v);
            qr.add_row(&rx, u * w - kf0[0] * xc, 1.0)?;
            qr.add_row(&ry, v * w - kf0[1] * yc, 1.0)?;
        }
    }
    let s = qr.solve().map_err(|_| Error::Degenerate {
        what: "focal polynomial system is rank deficient (currents or points too few or too alike)",
    })?;
    let (mut kx, mut ky) = ([0.0; MAX_FOCAL_DEGREE + 1], [0.0; MAX_FOCAL_DEGREE + 1]);
    kx[0] = kf0[0];
    ky[0] = kf0[1];
    // E_SCALE^k as E E ... (left to right).
    let mut scale = 1.0;
    let at = |i: usize| s.get(i).copied().unwrap_or(0.0);
    for k in 0..d {
        scale *= E_SCALE_MA;
        set(&mut kx, k + 1, at(k) / scale);
        set(&mut ky, k + 1, at(d + k) / scale);
    }
    let (Some(cx), Some(cy)) = (kx.get(..=d), ky.get(..=d)) else {
        return Err(Error::OutOfRange { what: "focal_degree", value: d as f64, min: 1.0, max: 5.0 });
    };
    Ok(FocalPolySolution { kf_x: FocalPoly::new(cx)?, kf_y: FocalPoly::new(cy)?, tz_mm: at(2 * d) })
}

/// `v[i] = x` where `i` lies in `v` (the callers' indices do, for degrees 1..=5).
fn set<const N: usize>(v: &mut [f64; N], i: usize, x: f64) {
    if let Some(slot) = v.get_mut(i) {
        *slot = x;
    }
}
