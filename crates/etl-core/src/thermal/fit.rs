//! [`ThermalFit`]: the least-squares fit of the cubic surface E_T(T, E_in) from streamed
//! samples (section 4.1: refocusing experiments give E_T at a grid of T and E_in).

use super::check_domain;
use super::surface::{ThermalCalibration, ThermalSurface};
use crate::error::{finite, Error, Result};
use crate::fit::basis::{chebyshev_values, scaled_power_in_raw, MAX_BASIS_DEGREE};
use crate::fit::GivensQr;

/// (power of T, power of E) of each term, in the paper's order
/// 1, T, E, T^2, T E, E^2, T^3, T^2 E, T E^2, E^3.
const TERMS: [(usize, usize); 10] = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3)];

/// Monomial coefficients of the Chebyshev polynomials T_0..T_3 (row = index, column =
/// power).
const CHEB_MONO: [[f64; 4]; 4] =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [-1.0, 0.0, 2.0, 0.0], [0.0, -3.0, 0.0, 4.0]];

/// Distinct values needed per variable to determine a cubic in it.
const DISTINCT_NEEDED: usize = 4;

/// Up to [`DISTINCT_NEEDED`] distinct values seen, to name the missing ones in errors.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Distinct {
    values: [f64; DISTINCT_NEEDED],
    count: usize,
}

impl Distinct {
    fn note(&mut self, x: f64) {
        if self.count < DISTINCT_NEEDED && !self.values.iter().take(self.count).any(|&v| v == x) {
            self.values[self.count] = x;
            self.count += 1;
        }
    }
}

/// Streamed, allocation-free weighted least-squares fit of the 10-term cubic surface
/// E_T(T, E_in) of section 5.2.2.
///
/// T and E_in are centred and scaled (by the ranges given to [`ThermalFit::with_ranges`],
/// or by the paper procedure's 27..37 degC and 40..240 mA with [`ThermalFit::new`]; the
/// scaling only conditions the problem, any data is fitted), the rows are products of
/// Chebyshev polynomials T_i(t) T_j(e), i + j <= 3, folded into a 10 x 10 triangle by
/// Givens rotations ([`GivensQr`]), and the solution is converted exactly to the paper's
/// monomial coefficients. No normal equations on mA^3 powers.
///
/// ```
/// use etl_core::thermal::{ThermalFit, ThermalSurface};
/// let truth = ThermalSurface::PAPER;
/// let mut fit = ThermalFit::new();
/// for it in 0..=10 {
///     for ie in 0..=10 {
///         let (t, e) = (27.0 + it as f64, 40.0 + 20.0 * ie as f64);
///         fit.add(e, t, truth.e_t_ma(e, t).unwrap()).unwrap();
///     }
/// }
/// let (surface, rms_ma) = fit.solve().unwrap();
/// assert!(rms_ma < 1e-9);
/// assert!((surface.coefficients[9] - 2.761e-8).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalFit {
    t_centre_c: f64,
    t_half_c: f64,
    e_centre_ma: f64,
    e_half_ma: f64,
    qr: GivensQr<10>,
    t_seen: Distinct,
    e_seen: Distinct,
    t_range_c: [f64; 2],
    e_in_range_ma: [f64; 2],
}

impl Default for ThermalFit {
    fn default() -> Self {
        Self::new()
    }
}

impl ThermalFit {
    /// An empty fit scaled for the paper's procedure (27..37 degC, 40..240 mA).
    pub fn new() -> Self {
        Self::scaled(140.0, 100.0, 32.0, 5.0)
    }

    /// An empty fit scaled for samples expected over `e_in_range_ma` x `t_range_c`
    /// ([min, max] each). Samples outside these ranges are still accepted.
    ///
    /// Errors: a non-finite bound ([`Error::NotFinite`]); a bound outside the domain
    /// ([`Error::OutOfRange`]); min >= max ([`Error::InvalidArgument`]).
    pub fn with_ranges(e_in_range_ma: [f64; 2], t_range_c: [f64; 2]) -> Result<Self> {
        check_domain(e_in_range_ma[0], t_range_c[0])?;
        check_domain(e_in_range_ma[1], t_range_c[1])?;
        if !(t_range_c[0] < t_range_c[1] && e_in_range_ma[0] < e_in_range_ma[1]) {
            return Err(Error::InvalidArgument { what: "fit ranges must be [min, max] with min < max" });
        }
        Ok(Self::scaled(
            0.5 * (e_in_range_ma[0] + e_in_range_ma[1]),
            0.5 * (e_in_range_ma[1] - e_in_range_ma[0]),
            0.5 * (t_range_c[0] + t_range_c[1]),
            0.5 * (t_range_c[1] - t_range_c[0]),
        ))
    }

    fn scaled(e_centre_ma: f64, e_half_ma: f64, t_centre_c: f64, t_half_c: f64) -> Self {
        let empty = Distinct { values: [0.0; DISTINCT_NEEDED], count: 0 };
        ThermalFit {
            t_centre_c,
            t_half_c,
            e_centre_ma,
            e_half_ma,
            qr: GivensQr::full(),
            t_seen: empty,
            e_seen: empty,
            t_range_c: [f64::INFINITY, f64::NEG_INFINITY],
            e_in_range_ma: [f64::INFINITY, f64::NEG_INFINITY],
        }
    }

    /// Samples added with a positive weight.
    pub fn samples(&self) -> usize {
        self.qr.rows()
    }

    /// [min, max] temperature of the samples so far (`None` before the first).
    pub fn t_range_c(&self) -> Option<[f64; 2]> {
        (self.samples() > 0).then_some(self.t_range_c)
    }

    /// [min, max] E_in of the samples so far (`None` before the first).
    pub fn e_in_range_ma(&self) -> Option<[f64; 2]> {
        (self.samples() > 0).then_some(self.e_in_range_ma)
    }

    /// Adds the measurement E_T = `e_t_ma` at (`e_in_ma`, `t_c`) with weight 1.
    pub fn add(&mut self, e_in_ma: f64, t_c: f64, e_t_ma: f64) -> Result<()> {
        self.add_weighted(e_in_ma, t_c, e_t_ma, 1.0)
    }

    /// Adds a measurement with weight `weight` (>= 0; e.g. 1 / variance; 0 ignores it).
    ///
    /// Errors (the fit is unchanged): a non-finite value ([`Error::NotFinite`]); T or E_in
    /// outside the domain of [`ThermalSurface`] ([`Error::OutOfRange`]); a negative weight
    /// ([`Error::InvalidArgument`]).
    pub fn add_weighted(&mut self, e_in_ma: f64, t_c: f64, e_t_ma: f64, weight: f64) -> Result<()> {
        check_domain(e_in_ma, t_c)?;
        finite(e_t_ma, "e_t_ma")?;
        let ct = chebyshev_values((t_c - self.t_centre_c) / self.t_half_c);
        let ce = chebyshev_values((e_in_ma - self.e_centre_ma) / self.e_half_ma);
        let mut row = [0.0; 10];
        // Powers are <= 3; the masks only let the compiler see that (no bounds checks).
        for (r, &(i, j)) in row.iter_mut().zip(TERMS.iter()) {
            *r = ct[i & 3] * ce[j & 3];
        }
        self.qr.add_row(&row, e_t_ma, weight)?;
        if weight > 0.0 {
            self.t_seen.note(t_c);
            self.e_seen.note(e_in_ma);
            self.t_range_c = [self.t_range_c[0].min(t_c), self.t_range_c[1].max(t_c)];
            self.e_in_range_ma = [self.e_in_range_ma[0].min(e_in_ma), self.e_in_range_ma[1].max(e_in_ma)];
        }
        Ok(())
    }

    /// The least-squares surface and the weighted RMS of its residuals in mA,
    /// sqrt(sum w_i r_i^2 / sum w_i) (the plain RMS, as the paper's 0.2106 mA, for unit
    /// weights).
    ///
    /// Errors: fewer than 10 samples ([`Error::TooFew`]); all samples at one temperature
    /// or at one current ([`Error::Degenerate`]); fewer than 4 distinct temperatures or
    /// currents ([`Error::TooFew`]: a cubic needs 4); samples that do not determine the
    /// surface otherwise, e.g. all on one line in (T, E_in) ([`Error::Degenerate`]).
    pub fn solve(&self) -> Result<(ThermalSurface, f64)> {
        let n = self.samples();
        if n < 10 {
            return Err(Error::TooFew { what: "thermal samples", needed: 10, got: n });
        }
        if self.t_seen.count == 1 {
            return Err(Error::Degenerate { what: "all samples at one temperature" });
        }
        if self.e_seen.count == 1 {
            return Err(Error::Degenerate { what: "all samples at one current" });
        }
        if self.t_seen.count < DISTINCT_NEEDED {
            return Err(Error::TooFew {
                what: "distinct temperatures",
                needed: DISTINCT_NEEDED,
                got: self.t_seen.count,
            });
        }
        if self.e_seen.count < DISTINCT_NEEDED {
            return Err(Error::TooFew { what: "distinct currents", needed: DISTINCT_NEEDED, got: self.e_seen.count });
        }
        let cheb = self.qr.solve()?;
        // sum c_ij T_i(t) T_j(e) -> sum a_kl t^k e^l -> sum raw_kl T^k E^l. Entries with
        // k + l > 3 stay exactly zero (T_i has no power above i).
        let mut scaled = [[0.0; 4]; 4];
        for (&c, &(i, j)) in cheb.iter().zip(TERMS.iter()) {
            for (row, &mk) in scaled.iter_mut().zip(CHEB_MONO[i & 3].iter()) {
                for (a, &ml) in row.iter_mut().zip(CHEB_MONO[j & 3].iter()) {
                    *a += c * mk * ml;
                }
            }
        }
        let pt: [[f64; MAX_BASIS_DEGREE + 1]; 4] =
            core::array::from_fn(|i| scaled_power_in_raw(i, self.t_centre_c, self.t_half_c));
        let pe: [[f64; MAX_BASIS_DEGREE + 1]; 4] =
            core::array::from_fn(|j| scaled_power_in_raw(j, self.e_centre_ma, self.e_half_ma));
        let mut raw = [[0.0; 4]; 4];
        for (srow, pti) in scaled.iter().zip(pt.iter()) {
            for (&a, pej) in srow.iter().zip(pe.iter()) {
                if a == 0.0 {
                    continue;
                }
                for (rrow, &tk) in raw.iter_mut().zip(pti.iter()) {
                    for (r, &el) in rrow.iter_mut().zip(pej.iter()) {
                        *r += a * tk * el;
                    }
                }
            }
        }
        let coefficients = TERMS.map(|(k, l)| raw[k & 3][l & 3]);
        let rms = libm::sqrt(self.qr.residual_sum_of_squares() / self.qr.weight_sum());
        if !(rms.is_finite() && coefficients.iter().all(|c| c.is_finite())) {
            return Err(Error::Degenerate { what: "thermal fit is not finite" });
        }
        Ok((ThermalSurface { coefficients }, rms))
    }

    /// [`Self::solve`] packed with the ranges of the samples (what `etlcal.thermal/1` holds).
    pub fn solve_calibration(&self) -> Result<(ThermalCalibration, f64)> {
        let (surface, rms) = self.solve()?;
        Ok((ThermalCalibration { surface, t_range_c: self.t_range_c, e_in_range_ma: self.e_in_range_ma }, rms))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// The paper's procedure grid: T = 27..37 by 1, E_in = 40..240 by 20.
    fn paper_grid() -> impl Iterator<Item = (f64, f64)> {
        (0..=10).flat_map(|it| (0..=10).map(move |ie| (27.0 + it as f64, 40.0 + 20.0 * ie as f64)))
    }

    fn assert_recovers(fit: &ThermalFit, truth: &ThermalSurface) {
        let (s, rms) = fit.solve().unwrap();
        for k in 0..10 {
            let rel = (s.coefficients[k] - truth.coefficients[k]).abs() / truth.coefficients[k].abs();
            assert!(rel < 1e-9, "c{k}: {} vs {} (rel {rel:e})", s.coefficients[k], truth.coefficients[k]);
        }
        assert!(rms < 1e-10, "{rms}");
    }

    /// Issue 2: noise-free samples give back the coefficients to 1e-9 relative.
    #[test]
    fn noise_free_fit_recovers_the_paper_coefficients() {
        let truth = ThermalSurface::PAPER;
        let mut fit = ThermalFit::new();
        let mut ranged = ThermalFit::with_ranges([40.0, 240.0], [27.0, 37.0]).unwrap();
        // A wider, off-centre grid through the default scaling.
        let mut wide = ThermalFit::new();
        for (t, e) in paper_grid() {
            let y = truth.e_t_ma(e, t).unwrap();
            fit.add(e, t, y).unwrap();
            ranged.add(e, t, y).unwrap();
            let (t2, e2) = (2.0 * t - 30.0, 1.2 * e - 40.0);
            wide.add(e2, t2, truth.e_t_ma(e2, t2).unwrap()).unwrap();
        }
        assert_recovers(&fit, &truth);
        assert_recovers(&ranged, &truth);
        assert_recovers(&wide, &truth);
        assert_eq!(fit.samples(), 121);
        assert_eq!(fit.t_range_c(), Some([27.0, 37.0]));
        assert_eq!(fit.e_in_range_ma(), Some([40.0, 240.0]));
        let (cal, _) = fit.solve_calibration().unwrap();
        assert_eq!(cal.t_range_c, [27.0, 37.0]);
    }

    /// Issue 2: with 0.2 mA Gaussian noise the reported RMS is 0.2 +- 0.03 mA.
    #[test]
    fn noisy_fit_reports_the_noise_rms() {
        let truth = ThermalSurface::PAPER;
        let noise = Normal::new(0.0, 0.2).unwrap();
        for seed in 0..5 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut fit = ThermalFit::new();
            for (t, e) in paper_grid() {
                fit.add(e, t, truth.e_t_ma(e, t).unwrap() + noise.sample(&mut rng)).unwrap();
            }
            let (s, rms) = fit.solve().unwrap();
            assert!((rms - 0.2).abs() < 0.03, "seed {seed}: rms {rms}");
            // The fitted surface follows the truth to ~ sqrt(10 / 121) * 0.2 = 0.06 mA RMS.
            let mut sq = 0.0;
            for (t, e) in paper_grid() {
                sq += (s.e_t_ma(e, t).unwrap() - truth.e_t_ma(e, t).unwrap()).powi(2);
            }
            let rms_err = (sq / 121.0).sqrt();
            assert!(rms_err < 0.1, "seed {seed}: surface RMS error {rms_err}");
        }
    }

    #[test]
    fn weights_scale_out() {
        // Uniform weights of 4 give the same surface and the same (weighted) RMS.
        let truth = ThermalSurface::PAPER;
        let mut a = ThermalFit::new();
        let mut b = ThermalFit::new();
        for (k, (t, e)) in paper_grid().enumerate() {
            let y = truth.e_t_ma(e, t).unwrap() + 0.1 * ((k % 7) as f64 - 3.0);
            a.add(e, t, y).unwrap();
            b.add_weighted(e, t, y, 4.0).unwrap();
        }
        let (sa, ra) = a.solve().unwrap();
        let (sb, rb) = b.solve().unwrap();
        assert!((ra - rb).abs() < 1e-12);
        for k in 0..10 {
            assert!((sa.coefficients[k] - sb.coefficients[k]).abs() <= 1e-9 * sa.coefficients[k].abs().max(1e-6));
        }
    }

    #[test]
    fn degenerate_samples_are_typed_errors() {
        let truth = ThermalSurface::PAPER;
        let mut fit = ThermalFit::new();
        assert_eq!(fit.solve().unwrap_err(), Error::TooFew { what: "thermal samples", needed: 10, got: 0 });
        assert_eq!(fit.t_range_c(), None);
        // All at one temperature.
        for ie in 0..20 {
            let e = 10.0 * ie as f64;
            fit.add(e, 30.0, truth.e_t_ma(e, 30.0).unwrap()).unwrap();
        }
        assert_eq!(fit.solve().unwrap_err(), Error::Degenerate { what: "all samples at one temperature" });
        // Three temperatures are not enough for a cubic in T.
        for &t in &[31.0, 32.0] {
            fit.add(100.0, t, 0.0).unwrap();
        }
        assert_eq!(fit.solve().unwrap_err(), Error::TooFew { what: "distinct temperatures", needed: 4, got: 3 });
        // All at one current.
        let mut one_e = ThermalFit::new();
        for it in 0..12 {
            one_e.add(100.0, 27.0 + it as f64, 0.0).unwrap();
        }
        assert_eq!(one_e.solve().unwrap_err(), Error::Degenerate { what: "all samples at one current" });
        // Enough distinct values, but all on the line E = 10 T: rank-deficient.
        let mut line = ThermalFit::new();
        for k in 0..20 {
            let t = 20.0 + k as f64;
            line.add(10.0 * t - 100.0, t, 1.0).unwrap();
        }
        assert!(matches!(line.solve(), Err(Error::Degenerate { .. })));
    }

    #[test]
    fn bad_samples_are_refused_and_leave_the_fit_unchanged() {
        let mut fit = ThermalFit::new();
        fit.add(100.0, 30.0, 0.5).unwrap();
        let before = fit;
        assert_eq!(fit.add(100.0, f64::NAN, 0.0), Err(Error::NotFinite { what: "t_c" }));
        assert_eq!(fit.add(f64::NAN, 30.0, 0.0), Err(Error::NotFinite { what: "e_in_ma" }));
        assert_eq!(fit.add(100.0, 30.0, f64::NAN), Err(Error::NotFinite { what: "e_t_ma" }));
        assert!(matches!(fit.add(100.0, 303.15, 0.0), Err(Error::OutOfRange { what: "t_c", .. })));
        assert!(matches!(fit.add(0.1e6, 30.0, 0.0), Err(Error::OutOfRange { what: "e_in_ma", .. })));
        assert!(matches!(fit.add_weighted(100.0, 30.0, 0.0, -1.0), Err(Error::InvalidArgument { .. })));
        assert_eq!(fit, before);
        assert!(matches!(ThermalFit::with_ranges([0.0, 1.0], [37.0, 27.0]), Err(Error::InvalidArgument { .. })));
        assert!(matches!(ThermalFit::with_ranges([0.0, f64::NAN], [27.0, 37.0]), Err(Error::NotFinite { .. })));
    }
}
