//! [`FocusLaw`]: the in-focus distance of a calibrated camera as a function of the
//! compensated current, fitted to the calibration views (each of which is in focus at its
//! own current and board plane by the way the data are taken).
//!
//! The form, from the lens physics ([`crate::physics`], docs/METHOD.md "The focus law"):
//!
//! ```text
//! E_com = c0 + c1 V + c2 V^2,   V = 1000 / distance_mm   (dioptres, 1/m)
//! ```
//!
//! - Gaussian (thin-lens) imaging with the sensor fixed: 1/s_o + 1/s_i = P_com, so the
//!   object vergence V = 1/s_o of the plane in focus is affine in the group's power P_com.
//! - The compound power (Eq. 10) P_com = P_liq + P_pri - d_lens P_liq P_pri is affine in
//!   the liquid lens's power P_liq.
//! - P_liq (Eq. 1-4) is nearly affine in the current: the pressure is quadratic in E (Eq. 1)
//!   and the cap's curvature nearly proportional to the pressure. Inverted, E is a gently
//!   curved function of V. On the paper's lens ([`crate::physics::LensPhysics::paper`],
//!   80..225 mA, a sensor fixed for focus at 100 mm at 150 mA) an affine E(V) leaves 1.1 mA
//!   RMS (2.5 mA at worst), a quadratic 0.055 mA RMS: hence degree 2.
//! - The distance is measured from the camera's centre of projection (the pinhole of the
//!   calibrated model, which for a thin lens is its centre), so no offset between the
//!   camera's centre and the lens's principal plane is fitted: with 15 views and 0.4 mA of
//!   current noise an offset and a curvature are not both determined (the residual is flat
//!   over offsets of -30..+500 mm on the paper rig's views).
//!
//! The residual is taken in current because the current is what a caller asks the law for
//! and what is noisy in the calibration (0.4 mA per view against 10 um of stage).
//!
//! `distance_mm` is the depth Z_C of the plane in focus in the camera frame: its distance
//! along the optical axis from the camera's centre of projection (the plane in focus is
//! square to the axis).

use serde::{Deserialize, Serialize};

use crate::error::{finite, Error, Result};
use crate::fit::PolyFit;

/// Fewest views at distinct currents [`FocusLaw::fit`] accepts: the three coefficients
/// and one degree of freedom, so that the residual says something.
pub const FOCUS_LAW_MIN_CURRENTS: usize = 4;

/// Margin around each calibrated range (distance and current) inside which the law is
/// still evaluated, as a fraction of the range's width: 2 % (e.g. 1.5 mm on 50..125 mm and
/// 2.9 mA on 80..225 mA). Beyond it the quadratic is not trusted.
pub const FOCUS_LAW_RANGE_MARGIN: f64 = 0.02;

/// One calibration view as the fit sees it: the view is in focus at this current and
/// distance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FocusSample {
    /// Compensated current of the view, mA.
    pub e_com_ma: f64,
    /// Depth of the view's plane in focus in the camera frame, mm (> 0).
    pub distance_mm: f64,
}

/// The fitted focus law E_com = c0 + c1 V + c2 V^2 with V = 1000 / distance_mm (module
/// docs), with the ranges it was fitted over.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FocusLaw {
    /// c0 (mA), c1 (mA per dioptre), c2 (mA per dioptre^2).
    pub coefficients_ma: [f64; 3],
    /// [min, max] distance of the fitted views, mm.
    pub distance_range_mm: [f64; 2],
    /// [min, max] compensated current of the fitted views, mA.
    pub e_com_range_ma: [f64; 2],
    /// RMS of the current residuals of the fitted views, mA.
    pub rms_ma: f64,
    /// Views fitted.
    pub views: usize,
    /// What the law's setting is: E_com (mA; the default) or the focal power (dpt), whose
    /// calibration file names the law's keys in dpt (`coefficients_dpt`,
    /// `focal_power_range_dpt`, `rms_dpt`). Not a key of its own.
    #[serde(skip)]
    pub setting: crate::runtime::SettingKind,
}

/// Dioptres (1/m) of a distance in mm.
#[inline]
fn vergence_dpt(distance_mm: f64) -> f64 {
    1000.0 / distance_mm
}

/// `range` widened by [`FOCUS_LAW_RANGE_MARGIN`] of its width on each side.
#[inline]
fn widened(range: [f64; 2]) -> [f64; 2] {
    let m = FOCUS_LAW_RANGE_MARGIN * (range[1] - range[0]);
    [range[0] - m, range[1] + m]
}

impl FocusLaw {
    /// The least-squares law through `samples` (one per calibration view): c0..c2 minimise
    /// sum (c0 + c1 V_j + c2 V_j^2 - E_j)^2, V_j = 1000 / distance_j (module docs).
    ///
    /// Preconditions: every current and distance finite, every distance > 0; at least
    /// [`FOCUS_LAW_MIN_CURRENTS`] distinct currents and 3 distinct distances; the fitted
    /// E(V) strictly monotone over the widened distance range (one current per distance
    /// and back).
    ///
    /// Errors: a non-finite value ([`Error::NotFinite`]); a distance <= 0
    /// ([`Error::OutOfRange`]); too few distinct currents or distances ([`Error::TooFew`]);
    /// a law that is not monotone, or a degenerate system ([`Error::Degenerate`]).
    pub fn fit(samples: &[FocusSample]) -> Result<FocusLaw> {
        let mut d_range = [f64::INFINITY, f64::NEG_INFINITY];
        let mut e_range = [f64::INFINITY, f64::NEG_INFINITY];
        for s in samples {
            finite(s.e_com_ma, "e_com_ma of a focus sample")?;
            finite(s.distance_mm, "distance_mm of a focus sample")?;
            if !(s.distance_mm > 0.0) {
                return Err(Error::OutOfRange {
                    what: "distance_mm of a focus sample (the plane in focus must be in front of the camera)",
                    value: s.distance_mm,
                    min: 0.0,
                    max: f64::INFINITY,
                });
            }
            d_range = [d_range[0].min(s.distance_mm), d_range[1].max(s.distance_mm)];
            e_range = [e_range[0].min(s.e_com_ma), e_range[1].max(s.e_com_ma)];
        }
        let currents = distinct_currents(samples);
        if currents < FOCUS_LAW_MIN_CURRENTS {
            return Err(Error::TooFew {
                what: "calibration views at distinct currents for the focus law",
                needed: FOCUS_LAW_MIN_CURRENTS,
                got: currents,
            });
        }
        if !(d_range[0] < d_range[1]) {
            return Err(Error::TooFew { what: "distinct distances for the focus law", needed: 3, got: 1 });
        }
        let mut fit = PolyFit::new(2, [vergence_dpt(d_range[1]), vergence_dpt(d_range[0])])?;
        for s in samples {
            // Clamped: 1000 / d of the range's ends may round just outside the range.
            let v = vergence_dpt(s.distance_mm).clamp(vergence_dpt(d_range[1]), vergence_dpt(d_range[0]));
            fit.add(v, s.e_com_ma)?;
        }
        let (poly, rms_ma) = fit.solve()?;
        let c = poly.monomial_coefficients()?;
        let law = FocusLaw {
            coefficients_ma: [c[0], c[1], c[2]],
            distance_range_mm: d_range,
            e_com_range_ma: e_range,
            rms_ma,
            views: samples.len(),
            setting: crate::runtime::SettingKind::Current,
        };
        law.validate()?;
        Ok(law)
    }

    /// Checks a law (as read from a file): finite coefficients; finite ordered ranges with
    /// positive distances; a finite RMS >= 0; E(V) strictly monotone over the widened
    /// distance range.
    ///
    /// Errors: [`Error::NotFinite`], [`Error::InvalidArgument`] or [`Error::Degenerate`]
    /// naming the field.
    pub fn validate(&self) -> Result<()> {
        crate::error::all_finite(&self.coefficients_ma, "focus_law coefficients_ma")?;
        crate::error::all_finite(&self.distance_range_mm, "focus_law distance_range_mm")?;
        crate::error::all_finite(&self.e_com_range_ma, "focus_law e_com_range_ma")?;
        let [d0, d1] = self.distance_range_mm;
        if !(d0 > 0.0 && d0 < d1) {
            return Err(Error::InvalidArgument {
                what: "focus_law distance_range_mm must be [min, max] with 0 < min < max",
            });
        }
        if !(self.e_com_range_ma[0] <= self.e_com_range_ma[1]) {
            return Err(Error::InvalidArgument { what: "focus_law e_com_range_ma must be [min, max]" });
        }
        if !(self.rms_ma.is_finite() && self.rms_ma >= 0.0) {
            return Err(Error::InvalidArgument { what: "focus_law rms_ma must be a finite number >= 0" });
        }
        // dE/dV = c1 + 2 c2 V is affine in V: the same strict sign at both ends of the
        // widened range is the same sign all over it.
        let [dw0, dw1] = widened(self.distance_range_mm);
        let near = if dw0 > 0.0 { vergence_dpt(dw0) } else { f64::INFINITY };
        let [_, c1, c2] = self.coefficients_ma;
        let (s_far, s_near) = (c1 + 2.0 * c2 * vergence_dpt(dw1), c1 + 2.0 * c2 * near);
        if !(s_far.is_finite() && s_near.is_finite() && s_far * s_near > 0.0) {
            return Err(Error::Degenerate {
                what: "the focus law is not monotone over its distance range (one distance would need two currents)",
            });
        }
        Ok(())
    }

    /// E_com (mA) in focus at `distance_mm`: c0 + c1 V + c2 V^2, V = 1000 / distance_mm.
    ///
    /// Errors: a non-finite distance ([`Error::NotFinite`]); a distance outside the fitted
    /// range widened by [`FOCUS_LAW_RANGE_MARGIN`] ([`Error::OutOfRange`] "distance_mm").
    pub fn e_com_ma(&self, distance_mm: f64) -> Result<f64> {
        finite(distance_mm, "distance_mm")?;
        let [lo, hi] = widened(self.distance_range_mm);
        if !(distance_mm >= lo && distance_mm <= hi && distance_mm > 0.0) {
            return Err(Error::OutOfRange {
                what: "distance_mm (outside the focus law's calibrated distances)",
                value: distance_mm,
                min: lo,
                max: hi,
            });
        }
        let v = vergence_dpt(distance_mm);
        let [c0, c1, c2] = self.coefficients_ma;
        finite(c0 + v * (c1 + v * c2), "E_com of the focus law")
    }

    /// The distance (mm) in focus at `e_com_ma`: the root V of c0 + c1 V + c2 V^2 = E_com
    /// inside the widened distance range, then 1000 / V.
    ///
    /// Errors: a non-finite current ([`Error::NotFinite`]); a current outside the fitted
    /// range widened by [`FOCUS_LAW_RANGE_MARGIN`] ([`Error::OutOfRange`] "e_com_ma"), or
    /// one whose distance falls outside the widened distance range.
    pub fn distance_mm(&self, e_com_ma: f64) -> Result<f64> {
        finite(e_com_ma, "e_com_ma")?;
        let [lo, hi] = widened(self.e_com_range_ma);
        if !(e_com_ma >= lo && e_com_ma <= hi) {
            return Err(Error::OutOfRange {
                what: "e_com_ma (outside the focus law's calibrated currents)",
                value: e_com_ma,
                min: lo,
                max: hi,
            });
        }
        let [d_lo, d_hi] = widened(self.distance_range_mm);
        let v_lo = vergence_dpt(d_hi);
        let v_hi = if d_lo > 0.0 { vergence_dpt(d_lo) } else { f64::INFINITY };
        let v = self.vergence_for(e_com_ma, [v_lo, v_hi]).ok_or(Error::OutOfRange {
            what: "e_com_ma (its distance in focus is outside the focus law's calibrated distances)",
            value: e_com_ma,
            min: lo,
            max: hi,
        })?;
        finite(vergence_dpt(v), "distance of the focus law")
    }

    /// The root of c2 V^2 + c1 V + (c0 - E) = 0 inside `[v_lo, v_hi]`, if any, by the
    /// cancellation-free quadratic formula (linear when c2 = 0).
    fn vergence_for(&self, e_com_ma: f64, [v_lo, v_hi]: [f64; 2]) -> Option<f64> {
        let [c0, c1, c2] = self.coefficients_ma;
        let c = c0 - e_com_ma;
        let inside = |v: f64| v.is_finite() && v >= v_lo && v <= v_hi && v > 0.0;
        if c2 == 0.0 {
            let v = -c / c1;
            return inside(v).then_some(v);
        }
        let disc = c1 * c1 - 4.0 * c2 * c;
        if !(disc >= 0.0) {
            return None;
        }
        let q = -0.5 * (c1 + libm::copysign(libm::sqrt(disc), c1));
        // Roots q / c2 and c / q (the latter undefined when q = 0, i.e. c1 = c = 0).
        let r1 = q / c2;
        let r2 = if q != 0.0 { c / q } else { f64::NAN };
        // The law is monotone over the widened range (validate), so at most one is inside.
        [r1, r2].into_iter().find(|&v| inside(v))
    }
}

/// Number of distinct currents among `samples`, counted up to [`FOCUS_LAW_MIN_CURRENTS`].
fn distinct_currents(samples: &[FocusSample]) -> usize {
    let mut seen = [0.0; FOCUS_LAW_MIN_CURRENTS];
    let mut n = 0;
    for s in samples {
        if seen.iter().take(n).any(|&v| v == s.e_com_ma) {
            continue;
        }
        if let Some(slot) = seen.get_mut(n) {
            *slot = s.e_com_ma;
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::LensPhysics;

    /// A law with known coefficients, sampled at 15 currents.
    fn samples_of(c: [f64; 3], noise: &[f64]) -> [FocusSample; 15] {
        let mut s = [FocusSample { e_com_ma: 0.0, distance_mm: 0.0 }; 15];
        for (k, x) in s.iter_mut().enumerate() {
            let d = 50.0 + 5.0 * k as f64;
            let v = 1000.0 / d;
            x.distance_mm = d;
            x.e_com_ma = c[0] + c[1] * v + c[2] * v * v + noise.get(k).copied().unwrap_or(0.0);
        }
        s
    }

    #[test]
    fn recovers_known_coefficients_and_inverts() {
        let c = [-40.0, 14.0, -0.05];
        let s = samples_of(c, &[]);
        let law = FocusLaw::fit(&s).unwrap();
        for k in 0..3 {
            assert!((law.coefficients_ma[k] - c[k]).abs() < 1e-9 * (1.0 + c[k].abs()), "{law:?}");
        }
        assert!(law.rms_ma < 1e-9 && law.views == 15);
        assert_eq!(law.distance_range_mm, [50.0, 120.0]);
        for d in [50.0, 61.3, 88.0, 120.0, 121.0] {
            let e = law.e_com_ma(d).unwrap();
            let v = 1000.0 / d;
            assert!((e - (c[0] + c[1] * v + c[2] * v * v)).abs() < 1e-9);
            assert!((law.distance_mm(e).unwrap() - d).abs() < 1e-9, "{d}");
        }
    }

    #[test]
    fn noisy_currents_give_their_rms() {
        let noise = [0.4, -0.4, 0.4, -0.4, 0.4, -0.4, 0.4, -0.4, 0.4, -0.4, 0.4, -0.4, 0.4, -0.4, 0.4];
        let s = samples_of([-40.0, 14.0, -0.05], &noise);
        let law = FocusLaw::fit(&s).unwrap();
        // Alternating +-0.4 mA is nearly orthogonal to a quadratic in V: RMS just under 0.4.
        assert!(law.rms_ma > 0.35 && law.rms_ma < 0.4, "{}", law.rms_ma);
    }

    /// Why degree 2 (module docs): on the paper's lens, with the sensor fixed so that
    /// 150 mA focuses at 100 mm, the current in focus as a function of the object vergence
    /// is fitted by the quadratic to 0.06 mA RMS; an affine law would leave 1.1 mA.
    #[test]
    fn the_paper_lens_physics_is_quadratic_in_vergence() {
        let lens = LensPhysics::paper();
        let p = |e: f64| 1.0 / lens.f_com_mm(e).unwrap();
        let inv_si = p(150.0) - 1.0 / 100.0;
        let mut s = [FocusSample { e_com_ma: 0.0, distance_mm: 0.0 }; 146];
        for (k, x) in s.iter_mut().enumerate() {
            let e = 80.0 + k as f64;
            *x = FocusSample { e_com_ma: e, distance_mm: 1.0 / (p(e) - inv_si) };
        }
        let law = FocusLaw::fit(&s).unwrap();
        assert!(law.rms_ma < 0.06, "{}", law.rms_ma);
        assert!(law.distance_range_mm[0] > 75.0 && law.distance_range_mm[1] < 145.0, "{law:?}");
    }

    #[test]
    fn out_of_range_and_bad_input_are_named() {
        let s = samples_of([-40.0, 14.0, -0.05], &[]);
        let law = FocusLaw::fit(&s).unwrap();
        // 2 % of 70 mm = 1.4 mm of margin.
        assert!(law.e_com_ma(121.0).is_ok() && law.e_com_ma(48.8).is_ok());
        let e = law.e_com_ma(122.0).unwrap_err();
        assert!(matches!(e, Error::OutOfRange { what, .. } if what.starts_with("distance_mm")), "{e}");
        assert!(matches!(law.e_com_ma(f64::NAN), Err(Error::NotFinite { what: "distance_mm" })));
        let [e_lo, e_hi] = law.e_com_range_ma;
        let e = law.distance_mm(e_hi + 0.1 * (e_hi - e_lo)).unwrap_err();
        assert!(matches!(e, Error::OutOfRange { what, .. } if what.starts_with("e_com_ma")), "{e}");
        assert!(matches!(law.distance_mm(f64::INFINITY), Err(Error::NotFinite { what: "e_com_ma" })));
        // Fit preconditions.
        assert!(matches!(FocusLaw::fit(&s[..3]), Err(Error::TooFew { needed: 4, got: 3, .. })));
        let mut same = s;
        for x in same.iter_mut() {
            x.e_com_ma = 100.0 + (x.distance_mm as usize % 3) as f64;
        }
        assert!(matches!(FocusLaw::fit(&same), Err(Error::TooFew { got: 3, .. })));
        let mut bad = s;
        bad[2].distance_mm = -1.0;
        assert!(matches!(FocusLaw::fit(&bad), Err(Error::OutOfRange { .. })));
        bad[2].distance_mm = f64::NAN;
        assert!(matches!(FocusLaw::fit(&bad), Err(Error::NotFinite { .. })));
        let mut flat = s;
        for x in flat.iter_mut() {
            x.distance_mm = 70.0;
        }
        assert!(matches!(FocusLaw::fit(&flat), Err(Error::TooFew { .. })));
        // A law that turns back inside its range is refused.
        let turning = FocusLaw { coefficients_ma: [0.0, 10.0, -0.5], ..law };
        assert!(matches!(turning.validate(), Err(Error::Degenerate { .. })));
        let unordered = FocusLaw { distance_range_mm: [90.0, 80.0], ..law };
        assert!(matches!(unordered.validate(), Err(Error::InvalidArgument { .. })));
        let nan = FocusLaw { rms_ma: f64::NAN, ..law };
        assert!(nan.validate().is_err());
    }
}
