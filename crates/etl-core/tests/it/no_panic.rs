//! Issue 2: arbitrary f64 values (NaN, infinities, huge, subnormal, ordinary) fed to every
//! public function of etl-core's model, thermal, physics and fit modules: nothing panics,
//! and no `Ok` result holds a NaN (thermal, physics and fit results are also finite).

use etl_core::error::{all_finite, finite};
use etl_core::fit::basis::{chebyshev_to_monomial, chebyshev_values, horner, scaled_power_in_raw, scaled_to_raw};
use etl_core::fit::{GivensQr, PolyFit, Polynomial};
use etl_core::model::projection::project_camera_point;
use etl_core::model::rotation::{mat_t_vec, mat_vec, matrix_to_rodrigues, rodrigues_to_matrix};
use etl_core::model::{
    CameraModel, Distortion, DistortionA, DistortionModel, FocalPoly, Intrinsics, MovingCentre, Ray,
};
use etl_core::physics::LensPhysics;
use etl_core::thermal::{Compensation, ThermalCalibration, ThermalFit, ThermalSurface};
use etl_core::Result;
use proptest::prelude::*;

/// Any f64, with the special values over-represented and plausible values common.
fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => prop::sample::select(vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::MAX,
            f64::MIN,
            1e300,
            -1e300,
            1e-300,
            1.0,
        ]),
        3 => prop::num::f64::ANY,
        4 => -400.0f64..400.0,
    ]
}

fn arr<const N: usize>() -> impl Strategy<Value = [f64; N]> {
    prop::collection::vec(any_f64(), N).prop_map(|v| core::array::from_fn(|i| v[i]))
}

/// Values that must not hold a NaN.
trait NoNan {
    fn nan_free(&self) -> bool;
}
impl NoNan for f64 {
    fn nan_free(&self) -> bool {
        !self.is_nan()
    }
}
impl<T: NoNan, const N: usize> NoNan for [T; N] {
    fn nan_free(&self) -> bool {
        self.iter().all(NoNan::nan_free)
    }
}
impl NoNan for () {
    fn nan_free(&self) -> bool {
        true
    }
}
impl NoNan for Intrinsics {
    fn nan_free(&self) -> bool {
        [self.fx, self.fy, self.u0, self.v0].nan_free()
    }
}
impl NoNan for Distortion {
    fn nan_free(&self) -> bool {
        self.coefficients().iter().all(|v| !v.is_nan())
    }
}
impl NoNan for Ray {
    fn nan_free(&self) -> bool {
        self.origin_mm.nan_free() && self.direction.nan_free()
    }
}

fn ok_no_nan<T: NoNan + core::fmt::Debug>(r: Result<T>) {
    if let Ok(v) = r {
        assert!(v.nan_free(), "NaN in an Ok result: {v:?}");
    }
}

/// Values that must be finite.
trait Finite {
    fn all_finite(&self) -> bool;
}
impl Finite for f64 {
    fn all_finite(&self) -> bool {
        self.is_finite()
    }
}
impl<const N: usize> Finite for [f64; N] {
    fn all_finite(&self) -> bool {
        self.iter().all(|x| x.is_finite())
    }
}
impl Finite for () {
    fn all_finite(&self) -> bool {
        true
    }
}
impl Finite for Compensation {
    fn all_finite(&self) -> bool {
        [self.e_in_ma, self.e_t_ma, self.e_com_ma].all_finite()
    }
}
impl Finite for (ThermalSurface, f64) {
    fn all_finite(&self) -> bool {
        self.0.coefficients.all_finite() && self.1.is_finite()
    }
}
impl Finite for (ThermalCalibration, f64) {
    fn all_finite(&self) -> bool {
        self.0.surface.coefficients.all_finite() && self.1.is_finite()
    }
}
impl Finite for (Polynomial, f64) {
    fn all_finite(&self) -> bool {
        self.0.scaled.all_finite() && self.1.is_finite() && self.0.x_centre.is_finite()
    }
}

fn ok_finite<T: Finite + core::fmt::Debug>(r: Result<T>) {
    if let Ok(v) = r {
        assert!(v.all_finite(), "non-finite Ok result: {v:?}");
    }
}

fn camera() -> impl Strategy<Value = CameraModel> {
    let centre = (arr::<4>(), any::<bool>()).prop_map(|(c, moving)| {
        moving.then_some(MovingCentre { dz_mm: [c[0], c[1]], principal_point_slope_px: [c[2], c[3]] })
    });
    (arr::<3>(), arr::<3>(), arr::<6>(), arr::<6>(), arr::<2>(), arr::<15>(), 1usize..=5, any::<bool>(), centre)
        .prop_map(|(r, t, kx, ky, pp, a, degree, opencv, centre)| {
            let family = if opencv { DistortionModel::OpenCv } else { DistortionModel::Paper };
            CameraModel {
                rotation_rodrigues: r,
                translation_mm: t,
                kf_x: FocalPoly::new(&kx[..=degree]).unwrap(),
                kf_y: FocalPoly::new(&ky[..=degree]).unwrap(),
                principal_point: pp,
                distortion_a: DistortionA::new(family, &a[..family.a_len()]).unwrap(),
                centre,
            }
        })
}

/// The paper rig, or an arbitrary model.
fn some_camera() -> impl Strategy<Value = CameraModel> {
    prop_oneof![Just(CameraModel::paper_rig()), Just(CameraModel::strong_distortion_rig()), camera()]
}

fn lens() -> impl Strategy<Value = LensPhysics> {
    prop_oneof![
        Just(LensPhysics::paper()),
        (arr::<7>(), arr::<6>()).prop_map(|(a, b)| LensPhysics {
            young_modulus_pa: a[0],
            membrane_radius_mm: a[1],
            membrane_thickness_mm: a[2],
            poisson_ratio: a[3],
            prestrain: a[4],
            n_liq: a[5],
            n_0: a[6],
            p0_pa: b[0],
            k_e0_pa: b[1],
            k_e1_pa_per_ma: b[2],
            k_e2_pa_per_ma2: b[3],
            f_pri_mm: b[4],
            d_lens_mm: b[5],
        }),
    ]
}

fn surface() -> impl Strategy<Value = ThermalSurface> {
    prop_oneof![Just(ThermalSurface::PAPER), arr::<10>().prop_map(|coefficients| ThermalSurface { coefficients })]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 384, .. ProptestConfig::default() })]

    #[test]
    fn model_never_panics(
        cam in some_camera(),
        p in arr::<3>(),
        px in arr::<2>(),
        e in any_f64(),
        s in any_f64(),
        pts in prop::collection::vec(arr::<3>(), 0..6),
        out_len in 0usize..8,
        a in arr::<15>(),
        f in any_f64(),
        m in arr::<9>(),
    ) {
        ok_no_nan(cam.validate());
        let _ = cam.rotation_matrix();
        let _ = cam.focal_lengths(e);
        let _ = cam.world_to_camera(p);
        ok_no_nan(cam.intrinsics(e));
        ok_no_nan(cam.distortion(e));
        ok_no_nan(cam.project(p, e));
        let mut out = vec![[0.0; 2]; out_len];
        ok_no_nan(cam.project_many(&pts, e, &mut out));
        ok_no_nan(cam.undistort(px, e));
        if let Ok(ray) = cam.ray(px, e) {
            assert!(ray.nan_free(), "{ray:?}");
            let _ = ray.at(s);
        }
        let k = Intrinsics { fx: m[0], fy: m[1], u0: m[2], v0: m[3] };
        let _ = k.matrix();
        let a9: [f64; 9] = core::array::from_fn(|i| a[i]);
        let d = Distortion::from_a(&DistortionA::paper(a9), f, m[8]);
        let dd = Distortion::paper(m[4], m[5], m[6]);
        let dc = Distortion::from_a(&DistortionA::opencv(a), f, m[8]);
        let dcc = Distortion::opencv([m[4], m[5], m[6], m[7], m[8]], m[0], m[1]);
        for d in [d, dd, dc, dcc] {
            let _ = d.distort(px[0], px[1]);
            let _ = d.distort_jacobian(px[0], px[1]);
            let _ = d.coefficient_jacobian(px[0], px[1]);
            let _ = d.to_opencv(f);
            ok_no_nan(d.undistort(px[0], px[1]));
            ok_no_nan(project_camera_point(p, &k, &d));
        }
        if let Ok(poly) = FocalPoly::new(&m[..4]) {
            let _ = (poly.eval(e), poly.slope(e));
        }
        let r = rodrigues_to_matrix(p);
        let _ = matrix_to_rodrigues(&r);
        let mm = [[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]];
        let _ = matrix_to_rodrigues(&mm);
        let _ = mat_vec(&mm, p);
        let _ = mat_t_vec(&mm, p);
        ok_no_nan(finite(e, "e"));
        ok_no_nan(all_finite(&a, "a"));
    }

    #[test]
    fn thermal_never_panics(
        s in surface(),
        t in any_f64(),
        e in any_f64(),
        y in any_f64(),
        w in any_f64(),
        ranges in arr::<4>(),
        samples in prop::collection::vec(arr::<4>(), 0..24),
        paper_ranges in any::<bool>(),
    ) {
        ok_finite(s.validate());
        ok_finite(s.e_t_ma(e, t));
        ok_finite(s.e_com_ma(e, t));
        ok_finite(s.e_in_for_e_com(y, t));
        ok_finite(s.e_in_for_e_com(e, 30.0));
        let cal = if paper_ranges {
            ThermalCalibration { surface: s, ..ThermalCalibration::PAPER }
        } else {
            ThermalCalibration { surface: s, t_range_c: [ranges[0], ranges[1]], e_in_range_ma: [ranges[2], ranges[3]] }
        };
        ok_finite(cal.validate());
        let _ = cal.contains(e, t);
        ok_finite(cal.compensate(e, t));
        ok_finite(cal.e_in_for_e_com(y, t));

        let mut fit = ThermalFit::with_ranges([ranges[2], ranges[3]], [ranges[0], ranges[1]])
            .unwrap_or_default();
        ok_finite(fit.add(e, t, y));
        ok_finite(fit.add_weighted(e, t, y, w));
        for smp in &samples {
            ok_finite(fit.add_weighted(smp[1], smp[0], smp[2], smp[3]));
            // Plausible samples too, so that some solves succeed.
            ok_finite(fit.add((smp[1] % 290.0).abs(), 20.0 + (smp[0] % 20.0).abs(), smp[2]));
        }
        let _ = (fit.samples(), fit.t_range_c(), fit.e_in_range_ma());
        ok_finite(fit.solve());
        ok_finite(fit.solve_calibration());
    }

    #[test]
    fn physics_never_panics(lens in lens(), e in any_f64(), p in any_f64(), q in any_f64(), r in any_f64()) {
        ok_finite(lens.validate());
        ok_finite(lens.applied_pressure_pa(e));
        ok_finite(lens.membrane_pressure_pa(e));
        ok_finite(lens.hemisphere_pressure_pa());
        ok_finite(lens.peak_deflection_at_pressure_mm(p));
        ok_finite(lens.peak_deflection_mm(e));
        ok_finite(lens.radius_of_curvature_at_pressure_mm(p));
        ok_finite(lens.radius_of_curvature_mm(e));
        ok_finite(lens.f_liq_at_pressure_mm(p));
        ok_finite(lens.f_liq_mm(e));
        ok_finite(lens.gravity_error_mm(e, p));
        ok_finite(lens.gravity_coefficient(e, q, r));
        ok_finite(lens.f_com_for_f_liq_mm(q));
        ok_finite(lens.f_com_mm(e));
    }

    #[test]
    fn fit_never_panics(
        degree in 0usize..9,
        range in arr::<2>(),
        samples in prop::collection::vec(arr::<3>(), 0..16),
        row in arr::<6>(),
        n in 0usize..8,
        x in any_f64(),
        c in arr::<7>(),
        poly in (0usize..10, any_f64(), any_f64(), arr::<7>()),
    ) {
        if let Ok(mut fit) = PolyFit::new(degree, range) {
            let _ = (fit.degree(), fit.samples());
            for s in &samples {
                ok_finite(fit.add_weighted(s[0], s[1], s[2]));
                ok_finite(fit.add(s[0], s[1]));
            }
            let solved = fit.solve();
            if let Ok((p, rms)) = solved {
                assert!(rms.is_finite() && p.scaled.all_finite());
                ok_finite(p.eval(x));
                ok_finite(p.monomial_coefficients());
            }
        }
        let p = Polynomial { degree: poly.0, x_centre: poly.1, x_half_width: poly.2, scaled: poly.3 };
        ok_finite(p.eval(x));
        ok_finite(p.monomial_coefficients());

        if let Ok(mut qr) = GivensQr::<6>::new(n) {
            let _ = (qr.unknowns(), qr.rows(), qr.weight_sum(), qr.residual_sum_of_squares());
            for s in &samples {
                ok_finite(qr.add_row(&[s[0], s[1], s[2], row[0], row[1], row[2]], row[3], row[4]));
                ok_finite(qr.add_row(&row, s[0], 1.0));
            }
            ok_finite(qr.solve());
        }
        let mut full = GivensQr::<3>::full();
        ok_finite(full.add_row(&[row[0], row[1], row[2]], row[3], row[4]));
        ok_finite(full.solve());

        let _ = chebyshev_values(x);
        let _ = chebyshev_to_monomial(&c);
        let _ = scaled_power_in_raw(n, x, row[0]);
        let _ = scaled_to_raw(&c, x, row[0]);
        let _ = horner(&c, x);
    }
}

/// The fits must also reach `Ok` under the fuzzer's distributions, or the properties
/// above would prove nothing about their `Ok` paths: check one plausible case each.
#[test]
fn plausible_inputs_reach_ok() {
    let mut fit = ThermalFit::with_ranges([0.0, 290.0], [20.0, 40.0]).unwrap_or_default();
    for k in 0..30 {
        let kf = k as f64;
        fit.add((kf * 37.1) % 290.0, 20.0 + (kf * 7.3) % 20.0, kf.sin()).unwrap();
    }
    assert!(fit.solve().is_ok());
    assert!(CameraModel::paper_rig().ray([100.0, 200.0], 100.0).is_ok());
    assert!(LensPhysics::paper().f_com_mm(100.0).is_ok());
}
