//! The ETL group: the compound focal length of the ETL and the prime lens (Eq. 10).

use super::lens::LensPhysics;
use crate::error::{finite, Error, Result};

impl LensPhysics {
    /// f_com = f_liq f_pri / (f_liq + f_pri - d_lens) (Eq. 10), mm, for a liquid-lens
    /// focal length `f_liq_mm`.
    ///
    /// Errors: invalid parameters; a non-finite input; f_liq + f_pri - d_lens = 0 (the group
    /// is afocal, [`Error::Degenerate`]).
    pub fn f_com_for_f_liq_mm(&self, f_liq_mm: f64) -> Result<f64> {
        self.validate()?;
        finite(f_liq_mm, "f_liq_mm")?;
        let denom = f_liq_mm + self.f_pri_mm - self.d_lens_mm;
        if denom == 0.0 {
            return Err(Error::Degenerate { what: "f_liq + f_pri - d_lens = 0 (afocal lens group)" });
        }
        finite(f_liq_mm * self.f_pri_mm / denom, "f_com")
    }

    /// Compound focal length of the ETL group at (compensated) current `e_ma` (Eq. 8, 10),
    /// mm: the ground truth of Fig. 5. Errors as [`Self::f_liq_mm`] and
    /// [`Self::f_com_for_f_liq_mm`].
    pub fn f_com_mm(&self, e_ma: f64) -> Result<f64> {
        self.f_com_for_f_liq_mm(self.f_liq_mm(e_ma)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::PolyFit;

    #[test]
    fn compound_by_hand() {
        let lens = LensPhysics::paper();
        let fl = lens.f_liq_mm(0.0).unwrap();
        assert!((lens.f_com_mm(0.0).unwrap() - fl * 30.0 / (fl + 27.0)).abs() < 1e-12);
        // f_com decreases with current like f_liq (section 2.3.1).
        assert!(lens.f_com_mm(250.0).unwrap() < lens.f_com_mm(0.0).unwrap());
        let afocal = LensPhysics { d_lens_mm: 30.0 + fl, ..lens };
        assert!(matches!(afocal.f_com_mm(0.0), Err(Error::Degenerate { .. })));
    }

    /// Fig. 5 / section 5.1.1: polynomials of degree 1..6 fitted to f_com over 0..260 mA
    /// (sampled every 0.1 mA); the cubic's RMSE is the paper's 1.09e-3 mm within 10 %, and
    /// the RMSE falls with the degree.
    #[test]
    fn fig5_rmse_falls_with_degree_and_cubic_matches_the_paper() {
        let lens = LensPhysics::paper();
        let mut rmse = [0.0; 6];
        for (d, r) in rmse.iter_mut().enumerate() {
            let mut fit = PolyFit::new(d + 1, [0.0, 260.0]).unwrap();
            for i in 0..=2600 {
                let e = 0.1 * i as f64;
                fit.add(e, lens.f_com_mm(e).unwrap()).unwrap();
            }
            *r = fit.solve().unwrap().1;
        }
        assert!((rmse[2] - 1.10e-3).abs() < 0.1 * 1.10e-3, "cubic RMSE {:e}", rmse[2]);
        for d in 1..6 {
            assert!(rmse[d] < 0.5 * rmse[d - 1], "{rmse:?}");
        }
    }
}
