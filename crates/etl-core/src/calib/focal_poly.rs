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
/// Unknowns of the largest system: kf0..kf5 of each axis and tz (kf0 solved, [`Kf0::Solved`]).
const MAX_UNKNOWNS: usize = 2 * MAX_FOCAL_DEGREE + 3;

/// Where the focal polynomials' constant term kf0 (fx, fy at setting 0) comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kf0 {
    /// Known: the lens-off focal lengths A0 (section 4.2), when the setting's zero is the
    /// lens off (a current: E = 0 mA is no current through the coil).
    Known([f64; 2]),
    /// Solved with the other coefficients, when the setting's zero is not the lens off (a
    /// focal power: the lens off is at the liquid lens's own power, 8.3 dpt for the paper's,
    /// not at 0 dpt). The setting is then scaled by its largest magnitude among the views
    /// inside, so the columns have comparable size. The perspective within each view
    /// (the board's tilt from RAC, the depth range of its points) is what separates kf0
    /// from tz, as it does in the bundle adjustment, which frees kf0 in either case.
    Solved,
}

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
    focal_poly_with(views, rac, Kf0::Known(kf0), principal_point, degree)
}

/// Solves Eq. 21-22 over all views for focal polynomials of degree `degree` (1..=5), kf0
/// known or solved ([`Kf0`]). With kf0 solved the rows gain the columns X_C and Y_C:
///
/// ```text
/// [X_C, X_C E, .., X_C E^d, -u] . [kf0x, kf1x, .., kf_dx, tz] = u w
/// ```
///
/// Preconditions: as [`focal_poly_of_degree`]; with kf0 solved, one more distinct setting
/// (d + 1 coefficients per axis) and a setting not all zero.
pub fn focal_poly_with(
    views: &[View<'_>],
    rac: &RacSolution,
    kf0: Kf0,
    principal_point: [f64; 2],
    degree: usize,
) -> Result<FocalPolySolution> {
    if !(1..=MAX_FOCAL_DEGREE).contains(&degree) {
        return Err(Error::OutOfRange { what: "focal_degree", value: degree as f64, min: 1.0, max: 5.0 });
    }
    validate(views)?;
    let nc = distinct_currents(views);
    let solved = matches!(kf0, Kf0::Solved);
    let needed = min_distinct_currents(degree) + usize::from(solved && degree >= 3);
    if nc < needed {
        let what = if degree <= 3 { "distinct currents (Appendix I)" } else { "distinct currents (focal degree)" };
        return Err(Error::TooFew { what, needed, got: nc });
    }
    let known = match kf0 {
        Kf0::Known(k) => Some(k),
        Kf0::Solved => None,
    };
    let finite = known.is_none_or(|k| k[0].is_finite() && k[1].is_finite());
    if !(finite && principal_point[0].is_finite() && principal_point[1].is_finite()) {
        return Err(Error::NotFinite { what: "A0 (kf0x, kf0y, u0, v0)" });
    }
    let scale = match known {
        Some(_) => E_SCALE_MA,
        None => views.iter().map(|v| v.e_com_ma.abs()).fold(0.0, f64::max),
    };
    if !(scale > 0.0) {
        return Err(Error::Degenerate { what: "focal polynomial with kf0 solved needs a setting other than 0" });
    }
    let system = System { rac, known, principal_point, degree, scale };
    let s = system.solve(views)?;
    system.solution(&s)
}

/// The linear system of [`focal_poly_with`]: the unknowns are kf1..kf_d of each axis
/// (kf0..kf_d when `known` is None), then tz; the setting is divided by `scale`.
struct System<'a> {
    rac: &'a RacSolution,
    known: Option<[f64; 2]>,
    principal_point: [f64; 2],
    degree: usize,
    scale: f64,
}

impl System<'_> {
    /// Coefficients per axis among the unknowns: d, or d + 1 with kf0 solved.
    fn per_axis(&self) -> usize {
        self.degree + usize::from(self.known.is_none())
    }

    /// The least-squares solution over every point of `views`.
    fn solve(&self, views: &[View<'_>]) -> Result<[f64; MAX_UNKNOWNS]> {
        let (r, n) = (&self.rac.rotation, self.per_axis());
        let first = usize::from(self.known.is_some());
        let kf0 = self.known.unwrap_or([0.0; 2]);
        let mut qr = GivensQr::<MAX_UNKNOWNS>::new(2 * n + 1)?;
        for view in views {
            let e = view.e_com_ma / self.scale;
            for p in view.points {
                let rw = mat_vec(r, p.world_mm);
                let (xc, yc, w) = (rw[0] + self.rac.tx_mm, rw[1] + self.rac.ty_mm, rw[2]);
                let (u, v) = (p.pixel[0] - self.principal_point[0], p.pixel[1] - self.principal_point[1]);
                let (mut rx, mut ry) = ([0.0; MAX_UNKNOWNS], [0.0; MAX_UNKNOWNS]);
                // X_C E^k as ((X_C E) E) ...: the products of the paper cubic's rows.
                let (mut tx, mut ty) = (xc, yc);
                if first == 1 {
                    tx *= e;
                    ty *= e;
                }
                for k in 0..n {
                    set(&mut rx, k, tx);
                    set(&mut ry, n + k, ty);
                    tx *= e;
                    ty *= e;
                }
                set(&mut rx, 2 * n, -u);
                set(&mut ry, 2 * n, -v);
                qr.add_row(&rx, u * w - kf0[0] * xc, 1.0)?;
                qr.add_row(&ry, v * w - kf0[1] * yc, 1.0)?;
            }
        }
        qr.solve().map_err(|_| Error::Degenerate {
            what: "focal polynomial system is rank deficient (currents or points too few or too alike)",
        })
    }

    /// The polynomials and tz of a solution, the scale undone.
    fn solution(&self, s: &[f64; MAX_UNKNOWNS]) -> Result<FocalPolySolution> {
        let (d, n) = (self.degree, self.per_axis());
        let first = usize::from(self.known.is_some());
        let (mut kx, mut ky) = ([0.0; MAX_FOCAL_DEGREE + 1], [0.0; MAX_FOCAL_DEGREE + 1]);
        if let Some(k) = self.known {
            kx[0] = k[0];
            ky[0] = k[1];
        }
        // scale^k as s s ... (left to right).
        let mut scale = if first == 1 { self.scale } else { 1.0 };
        let at = |i: usize| s.get(i).copied().unwrap_or(0.0);
        for k in 0..n {
            set(&mut kx, first + k, at(k) / scale);
            set(&mut ky, first + k, at(n + k) / scale);
            scale *= self.scale;
        }
        let (Some(cx), Some(cy)) = (kx.get(..=d), ky.get(..=d)) else {
            return Err(Error::OutOfRange { what: "focal_degree", value: d as f64, min: 1.0, max: 5.0 });
        };
        Ok(FocalPolySolution { kf_x: FocalPoly::new(cx)?, kf_y: FocalPoly::new(cy)?, tz_mm: at(2 * n) })
    }
}

/// `v[i] = x` where `i` lies in `v` (the callers' indices do, for degrees 1..=5).
fn set<const N: usize>(v: &mut [f64; N], i: usize, x: f64) {
    if let Some(slot) = v.get_mut(i) {
        *slot = x;
    }
}
