//! Links etl-core into a `#![no_std]` artefact without a global allocator (see Cargo.toml).
//! Each exported function calls one part of the core so the linker keeps it.
#![no_std]

use etl_core::fit::{GivensQr, PolyFit};
use etl_core::model::CameraModel;
use etl_core::physics::LensPhysics;
use etl_core::thermal::{ThermalCalibration, ThermalFit, ThermalSurface};

// The panic handler calls a function that exists nowhere. If any panic path in etl-core is
// reachable from the exported functions after optimisation, the final link (a cdylib
// linked with --no-undefined, see build.rs) fails naming `etl_core_can_panic`.
unsafe extern "C" {
    fn etl_core_can_panic() -> !;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never executed: the symbol is undefined, so a build in which this handler is
    // reachable does not link.
    unsafe { etl_core_can_panic() }
}

/// Projects a world point of the paper rig; returns u + v, or NaN on error.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_project(x: f64, y: f64, z: f64, e_ma: f64) -> f64 {
    match CameraModel::paper_rig().project([x, y, z], e_ma) {
        Ok([u, v]) => u + v,
        Err(_) => f64::NAN,
    }
}

/// Undistorts a pixel of the paper rig; returns u + v, or NaN on error.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_undistort(u: f64, v: f64, e_ma: f64) -> f64 {
    match CameraModel::paper_rig().undistort([u, v], e_ma) {
        Ok([a, b]) => a + b,
        Err(_) => f64::NAN,
    }
}

/// Temperature compensation with the paper's surface: E_com, or NaN on error.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_e_com(e_in_ma: f64, t_c: f64) -> f64 {
    ThermalSurface::PAPER.e_com_ma(e_in_ma, t_c).unwrap_or(f64::NAN)
}

/// The inverse of the compensation on a perturbed surface (exercises the root search).
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_e_in_for_e_com(e_com_ma: f64, t_c: f64, c9: f64) -> f64 {
    let mut s = ThermalSurface::PAPER;
    s.coefficients[9] = c9;
    s.e_in_for_e_com(e_com_ma, t_c).unwrap_or(f64::NAN)
}

/// Flagged compensation over a calibration with a caller-chosen lower temperature bound.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_compensate(e_in_ma: f64, t_c: f64, t_lo_c: f64) -> f64 {
    let mut c = ThermalCalibration::PAPER;
    c.t_range_c[0] = t_lo_c;
    match c.compensate(e_in_ma, t_c) {
        Ok(r) => r.e_com_ma + if r.extrapolated { 1.0 } else { 0.0 },
        Err(_) => f64::NAN,
    }
}

/// The streamed surface fit over `n` synthetic samples.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_thermal_fit(x0: f64, dx: f64, n: usize) -> f64 {
    let mut f = ThermalFit::new();
    for i in 0..n {
        let x = x0 + dx * i as f64;
        let _ = f.add_weighted(x * 2.0, x, x * 3.0, x);
    }
    match f.solve() {
        Ok((s, rms)) => s.coefficients[3] + rms,
        Err(_) => f64::NAN,
    }
}

/// The streamed polynomial fit of degree `d` over `n` samples.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_poly_fit(x0: f64, dx: f64, n: usize, d: usize, lo: f64, hi: f64) -> f64 {
    let Ok(mut f) = PolyFit::new(d, [lo, hi]) else { return f64::NAN };
    for i in 0..n {
        let x = x0 + dx * i as f64;
        let _ = f.add_weighted(x, x * 2.0, x);
    }
    match f.solve() {
        Ok((p, rms)) => {
            let c = p.monomial_coefficients().map(|c| c.get(d).copied().unwrap_or(0.0)).unwrap_or(0.0);
            p.eval(lo).unwrap_or(0.0) + rms + c
        }
        Err(_) => f64::NAN,
    }
}

/// The focus law fitted to `n` views (E from `e0` by `de`, distance from `d0` by `dd`), then
/// evaluated both ways at `d`.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_focus_law(e0: f64, de: f64, d0: f64, dd: f64, n: usize, d: f64) -> f64 {
    use etl_core::focus::{FocusLaw, FocusSample};
    let mut samples = [FocusSample { e_com_ma: 0.0, distance_mm: 0.0 }; 16];
    for (i, s) in samples.iter_mut().enumerate() {
        *s = FocusSample { e_com_ma: e0 + de * i as f64, distance_mm: d0 + dd * i as f64 };
    }
    let Ok(law) = FocusLaw::fit(samples.get(..n).unwrap_or(&samples)) else { return f64::NAN };
    match law.e_com_ma(d) {
        Ok(e) => e + law.distance_mm(e).unwrap_or(f64::NAN),
        Err(_) => f64::NAN,
    }
}

/// A Givens QR accumulator of caller-chosen size.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_givens(n: usize, a: f64, b: f64) -> f64 {
    let Ok(mut q) = GivensQr::<5>::new(n) else { return f64::NAN };
    let _ = q.add_row(&[a, b, a, b, a], b, a);
    q.solve().map(|s| s[4]).unwrap_or(f64::NAN)
}

/// The lens physics (Eq. 1-10) with a caller-chosen Poisson ratio.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_physics(e_ma: f64, dp: f64, nu: f64) -> f64 {
    let mut l = LensPhysics::paper();
    l.poisson_ratio = nu;
    l.f_com_mm(e_ma).unwrap_or(0.0)
        + l.gravity_error_mm(e_ma, dp).unwrap_or(0.0)
        + l.gravity_coefficient(e_ma, dp, nu).unwrap_or(0.0)
}

/// The lens's dynamics: a caller's numbers validated, a shaped step and a plain one
/// advanced, the effective current returned (NaN when the numbers are refused).
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_dynamics(f_hz: f64, zeta: f64, step_ma: f64, t_s: f64) -> f64 {
    use etl_core::physics::dynamics::{LensDynamics, LensResponse};
    use etl_core::physics::shaping::ZvShaper;
    let d = LensDynamics { natural_frequency_hz: f_hz, damping: zeta, ..LensDynamics::PUBLISHED };
    if d.validate().is_err() {
        return f64::NAN;
    }
    let mut lens = LensResponse::at_rest(0.0);
    let shaper = ZvShaper::of(&d).unwrap_or(ZvShaper { first_fraction: 1.0, delay_s: 0.0 });
    lens.command(shaper.command_ma(0.0, step_ma, 0.0), &d);
    lens.advance(shaper.delay_s, &d);
    lens.command(step_ma, &d);
    lens.advance(t_s, &d);
    lens.effective_ma() + lens.rate_ma_per_s() + lens.resting_ma()
}

/// The whole calibration chain on a small synthetic rig: 3 views of 12 points, then the
/// linear initialisation, the bundle adjustment (plain or errors-in-variables) and PnP.
/// Returns the refined kf1x (or NaN on error).
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_calibrate(noise_px: f64, eiv: bool) -> f64 {
    use etl_core::calib::{bundle_adjust, initialise, BundleAdjustOptions, Estimator, Point, View, ViewScratch, A0};
    let cam = CameraModel::paper_rig();
    let mut pts = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 12]; 3];
    let setup = [(60.0, 90.0), (31.0, 130.0), (8.0, 200.0)];
    for (k, (z, e)) in setup.into_iter().enumerate() {
        for i in 0..12 {
            let w = [1.5 * (i % 4) as f64, 1.5 * (i / 4) as f64, z];
            let Ok(px) = cam.project(w, e) else { return f64::NAN };
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            pts[k][i] = Point { world_mm: w, pixel: [px[0] + sign * noise_px, px[1] - sign * noise_px] };
        }
    }
    let views = [
        View { e_com_ma: 90.0, points: &pts[0] },
        View { e_com_ma: 130.0, points: &pts[1] },
        View { e_com_ma: 200.0, points: &pts[2] },
    ];
    let a0 = A0 { kf0x: 5380.0, kf0y: 5430.0, u0: 900.0, v0: 550.0 };
    let Ok(init) = initialise(&views, &a0) else { return f64::NAN };
    let estimator = if eiv { Estimator::EIV_PAPER } else { Estimator::Paper };
    let opts = BundleAdjustOptions { estimator, ..BundleAdjustOptions::default() };
    let mut scratch = [ViewScratch::ZERO; 3];
    let Ok(r) = bundle_adjust(&views, &init, &opts, &mut scratch) else { return f64::NAN };
    let mut board = [[0.0; 3]; 12];
    let mut px = [[0.0; 2]; 12];
    for i in 0..12 {
        board[i] = [pts[1][i].world_mm[0], pts[1][i].world_mm[1], 0.0];
        px[i] = pts[1][i].pixel;
    }
    let Ok(p) = etl_core::pnp::solve_pnp(&r.model, 130.0, &board, &px) else { return f64::NAN };
    // The uncertainty of the pose, of a displacement and of a projected pixel.
    use etl_core::pnp::{displacement_covariance_mm2, pose_uncertainty, PixelNoise};
    let Ok(u) = pose_uncertainty(&r.model, 130.0, &board, &px, &p, PixelNoise::FromResidual) else { return f64::NAN };
    let Ok(d) = displacement_covariance_mm2(&u, &u, Some(&r.covariance)) else { return f64::NAN };
    let Ok(q) = etl_core::calib::projection_uncertainty(&r.model, &r.covariance, board[0], 130.0) else {
        return f64::NAN;
    };
    r.model.kf_x.padded()[1] + p.translation_mm[2] + d[2][2] + q.std_px[0]
}

/// The calibration chain in any layout on a small synthetic rig of the strong-distortion
/// camera: focal degree `degree` (1..=5), the opencv family (with OpenCV's flags) or the
/// paper's, plain or errors-in-variables, with the Cramer-Rao bound at the result.
/// Returns kf0x + the bound of u0 (or NaN on error).
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_calibrate_family(noise_px: f64, degree: usize, opencv: bool, flags: u8, eiv: bool) -> f64 {
    use etl_core::calib::crlb::crlb_covariance_eiv;
    use etl_core::calib::{bundle_adjust, initialise_model, BundleAdjustOptions, Estimator, Layout, Point, View, ViewScratch, A0};
    use etl_core::model::{DistortionModel, OpenCvFlags};
    let cam = CameraModel::strong_distortion_rig();
    let mut pts = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 30]; 6];
    let currents = [80.0, 110.0, 140.0, 170.0, 200.0, 225.0];
    for (k, view) in pts.iter_mut().enumerate() {
        for (i, p) in view.iter_mut().enumerate() {
            let w = [20.0 * (i % 6) as f64, 20.0 * (i / 6) as f64, -40.0 + 16.0 * k as f64];
            let Ok(px) = cam.project(w, currents[k]) else { return f64::NAN };
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            *p = Point { world_mm: w, pixel: [px[0] + sign * noise_px, px[1] - sign * noise_px] };
        }
    }
    let views: [View; 6] = core::array::from_fn(|k| View { e_com_ma: currents[k], points: &pts[k] });
    let family = if opencv { DistortionModel::OpenCv } else { DistortionModel::Paper };
    let Ok(layout) = Layout::new(family, degree) else { return f64::NAN };
    let flags = OpenCvFlags { fix_k3: flags & 1 != 0, zero_tangent: flags & 2 != 0 };
    let a0 = A0 { kf0x: 1500.0, kf0y: 1510.0, u0: 980.0, v0: 720.0 };
    let Ok(init) = initialise_model(&views, &a0, layout, flags) else { return f64::NAN };
    let Ok(hold) = layout.opencv_mask(flags) else { return f64::NAN };
    let estimator = if eiv { Estimator::EIV_PAPER } else { Estimator::Paper };
    let opts = BundleAdjustOptions { estimator, hold: hold | layout.a0_mask(), ..BundleAdjustOptions::default() };
    let mut scratch = [ViewScratch::ZERO; 6];
    let Ok(r) = bundle_adjust(&views, &init, &opts, &mut scratch) else { return f64::NAN };
    let Ok(c) = crlb_covariance_eiv(&views, &r.model, 0.2, Some((0.01, 0.4))) else { return f64::NAN };
    r.model.kf_x.padded()[0] + c[layout.u0()][layout.u0()]
}

/// The bundle adjustment with free-pose views (a moving centre, plain or
/// errors-in-variables): three stage views and two tilted boards started by PnP. Returns
/// the refined dz1 + the first board's tz (or NaN on error).
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_calibrate_free_views(noise_px: f64, eiv: bool) -> f64 {
    use etl_core::calib::{bundle_adjust_free_views, BundleAdjustOptions, Estimator, FreeView, JointScratch, Point, View};
    use etl_core::model::MovingCentre;
    let mut cam = CameraModel::paper_rig();
    cam.centre = Some(MovingCentre { dz_mm: [0.01, -2e-5], principal_point_slope_px: [0.02, -0.01] });
    let currents = [90.0, 130.0, 200.0];
    let mut pts = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 12]; 5];
    for (k, view) in pts.iter_mut().enumerate() {
        let mut m = cam;
        if k >= 3 {
            m.rotation_rodrigues = [0.2 * (k as f64 - 3.5), 0.1, 0.0];
            m.translation_mm = [-2.0, -2.0, 70.0];
        }
        for (i, p) in view.iter_mut().enumerate() {
            let w = if k < 3 { [1.5 * (i % 4) as f64, 1.5 * (i / 4) as f64, 60.0 - 25.0 * k as f64] } else { [1.5 * (i % 4) as f64, 1.5 * (i / 4) as f64, 0.0] };
            let Ok(px) = m.project(w, currents[k % 3]) else { return f64::NAN };
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            *p = Point { world_mm: w, pixel: [px[0] + sign * noise_px, px[1] - sign * noise_px] };
        }
    }
    let stage: [View; 3] = core::array::from_fn(|k| View { e_com_ma: currents[k], points: &pts[k] });
    let mut board = [[0.0; 3]; 12];
    let mut px = [[0.0; 2]; 12];
    let mut free = [FreeView { e_com_ma: 0.0, points: &pts[3], rotation_rodrigues: [0.0; 3], translation_mm: [0.0; 3] }; 2];
    for (f, fv) in free.iter_mut().enumerate() {
        for i in 0..12 {
            board[i] = pts[3 + f][i].world_mm;
            px[i] = pts[3 + f][i].pixel;
        }
        let Ok(pose) = etl_core::pnp::solve_pnp(&cam, currents[f], &board, &px) else { return f64::NAN };
        *fv = FreeView { e_com_ma: currents[f], points: &pts[3 + f], rotation_rodrigues: pose.rotation_rodrigues, translation_mm: pose.translation_mm };
    }
    let estimator = if eiv { Estimator::EIV_PAPER } else { Estimator::Paper };
    let opts = BundleAdjustOptions { estimator, ..BundleAdjustOptions::default() };
    let mut scratch = [JointScratch::ZERO; 5];
    let Ok(r) = bundle_adjust_free_views(&stage, &free, &cam, &opts, &mut scratch) else { return f64::NAN };
    let dz1 = r.model.centre.map_or(f64::NAN, |c| c.dz_mm[0]);
    dz1 + scratch[3].board_pose().1[2]
}

/// The strong-distortion camera (opencv family): a projection, its undistortion, the
/// exact OpenCV export and a band of undistortion maps; their sum, or NaN on error.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_opencv_family(x: f64, y: f64, z: f64, e_ma: f64, maps: &mut [f32; 128]) -> f64 {
    use etl_core::undistort::{undistort_maps, OutputCamera};
    let cam = CameraModel::strong_distortion_rig();
    let Ok([u, v]) = cam.project([x, y, z], e_ma) else { return f64::NAN };
    let Ok([a, b]) = cam.undistort([u, v], e_ma) else { return f64::NAN };
    let (Ok(k), Ok(d)) = (cam.intrinsics(e_ma), cam.distortion(e_ma)) else { return f64::NAN };
    let Ok(fit) = etl_core::model::fit_opencv5(&k, &d, [1936, 1458]) else { return f64::NAN };
    let Ok(out) = OutputCamera::of_intrinsics(&k, 8, 8) else { return f64::NAN };
    let (mx, my) = maps.split_at_mut(64);
    if undistort_maps(&k, &d, &out, 0..8, mx, my).is_err() {
        return f64::NAN;
    }
    a + b + fit.dist_coeffs[0] + mx[9] as f64
}

/// The four sharpness measures on a caller's 8-bit frame with stride; their sum, or NaN.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_sharpness_u8(data: &[u8; 64], width: usize, height: usize, stride: usize) -> f64 {
    use etl_core::focus::{brenner, laplacian_variance, normalised_variance, tenengrad, ImageView};
    let Ok(v) = ImageView::new(data, width, height, stride) else { return f64::NAN };
    let mut s = 0.0;
    for m in [tenengrad(&v), laplacian_variance(&v), brenner(&v), normalised_variance(&v)] {
        s += m.unwrap_or(f64::NAN);
    }
    s
}

/// The same on a 16-bit frame.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_sharpness_u16(data: &[u16; 64], width: usize, height: usize, stride: usize) -> f64 {
    use etl_core::focus::{brenner, laplacian_variance, normalised_variance, tenengrad, ImageView};
    let Ok(v) = ImageView::new(data, width, height, stride) else { return f64::NAN };
    let mut s = 0.0;
    for m in [tenengrad(&v), laplacian_variance(&v), brenner(&v), normalised_variance(&v)] {
        s += m.unwrap_or(f64::NAN);
    }
    s
}

/// Autofocus on a caller-positioned peak with caller-chosen options; best current or NaN.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_autofocus(centre_ma: f64, lo: f64, hi: f64, coarse: usize, budget: usize, tol: f64) -> f64 {
    use etl_core::focus::{autofocus, AutofocusOptions};
    let opts = AutofocusOptions { range_ma: [lo, hi], coarse_points: coarse, max_evaluations: budget, tolerance_ma: tol };
    let f = |e: f64| if e > 1e6 { Err(etl_core::Error::Degenerate { what: "gate" }) } else { Ok(-(e - centre_ma) * (e - centre_ma)) };
    autofocus(f, &opts).map(|r| r.best_ma + r.evaluations as f64).unwrap_or(f64::NAN)
}

/// The run-time camera at (E_in, T) with a caller's policy, then a projection and a ray
/// through it, and the OpenCV fit of its distortion; u + v + fit RMS, or NaN on error.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_camera_at(e_in_ma: f64, t_c: f64, extrapolate: bool, w: u32, h: u32) -> f64 {
    use etl_core::runtime::{Camera, ThermalTrust, Trust};
    let thermal = ThermalTrust::from_calibration(&ThermalCalibration::PAPER);
    let Ok(cam) = Camera::new(CameraModel::paper_rig(), Some(thermal), [80.0, 225.0]) else { return f64::NAN };
    let trust = if extrapolate { Trust::Extrapolate } else { Trust::Refuse };
    let Ok(at) = cam.at_with(e_in_ma, t_c, trust) else { return f64::NAN };
    let Ok([u, v]) = at.project([3.0, 4.5, 22.0]) else { return f64::NAN };
    let Ok(ray) = at.ray([u, v]) else { return f64::NAN };
    let Ok(fit) = etl_core::model::fit_opencv5(at.intrinsics(), at.distortion(), [w, h]) else { return f64::NAN };
    u + v + ray.direction[2] + fit.rms_px
}

/// Undistortion maps of a caller's band of rows at a current, then a remap of a 1- or
/// 3-channel image of each sample type through them; the sum of the outputs, or NaN.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_undistort_remap(
    e_com_ma: f64,
    width: usize,
    height: usize,
    first_row: usize,
    end_row: usize,
    channels: usize,
    maps: &mut [f32; 128],
    image: &[u8; 192],
) -> f64 {
    use etl_core::undistort::{remap, undistort_maps, OutputCamera, SourceImage};
    let cam = CameraModel::paper_rig();
    let (Ok(k), Ok(d)) = (cam.intrinsics(e_com_ma), cam.distortion(e_com_ma)) else { return f64::NAN };
    let Ok(out) = OutputCamera::of_intrinsics(&k, width, height) else { return f64::NAN };
    let (mx, my) = maps.split_at_mut(64);
    if undistort_maps(&k, &d, &out, first_row..end_row, mx, my).is_err() {
        return f64::NAN;
    }
    let mut s = 0.0;
    let Ok(src) = SourceImage::new(image, width, height, channels) else { return f64::NAN };
    let mut d8 = [0u8; 192];
    s += remap(&src, mx, my, 3, &mut d8).map_or(f64::NAN, |()| d8.iter().map(|&v| v as f64).sum());
    let i16: [u16; 192] = core::array::from_fn(|i| image[i] as u16 * 257);
    let Ok(src) = SourceImage::new(&i16, width, height, channels) else { return f64::NAN };
    let mut d16 = [0u16; 192];
    s += remap(&src, mx, my, 3, &mut d16).map_or(f64::NAN, |()| d16.iter().map(|&v| v as f64).sum());
    let f: [f32; 192] = core::array::from_fn(|i| image[i] as f32);
    let Ok(src) = SourceImage::new(&f, width, height, channels) else { return f64::NAN };
    let mut df = [0f32; 192];
    s += remap(&src, mx, my, f32::NAN, &mut df).map_or(f64::NAN, |()| df.iter().map(|&v| v as f64).sum());
    s
}

/// Looks up a dictionary by a name given as bytes, decodes `observed` with it and builds a
/// ChArUco board from it; returns a checksum of what it found, or NaN on error.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_board(name: &[u8; 16], len: usize, observed: u64, cols: u32, rows: u32, id: u32) -> f64 {
    use etl_core::board::{CharucoBoard, Dictionary};
    let Some(bytes) = name.get(..len) else { return f64::NAN };
    let Ok(name) = core::str::from_utf8(bytes) else { return f64::NAN };
    let Some(dict) = Dictionary::by_name(name) else { return f64::NAN };
    let decoded = dict.identify(observed, dict.max_correction_bits()).map_or(-1.0, |m| m.id as f64);
    let Ok(board) = CharucoBoard::new([cols, rows], 1.5, 1.1, dict) else { return f64::NAN };
    let corner = board.corner_mm(id).map_or(0.0, |p| p[0] + p[1]);
    let marker = board.marker_corners_mm(id).map_or(0.0, |m| m[2][0]);
    let touching = board.corner_markers(id).map_or(0.0, |m| (m[0] + m[1]) as f64);
    decoded + corner + marker + touching
}

/// A two-camera rig: the pose at caller settings of a moving centre (Eq. R2), a point
/// triangulated from its two pixels with its covariance, and a band of rectification maps
/// through the rotation; their sum, or NaN on error.
#[unsafe(no_mangle)]
pub extern "C" fn etl_gate_rig(e0_ma: f64, e1_ma: f64, z_mm: f64, sigma_px: f64, maps: &mut [f32; 128]) -> f64 {
    use etl_core::model::MovingCentre;
    use etl_core::runtime::rig::{centre_shift_mm, triangulate, RigPose, TriangulationView};
    use etl_core::runtime::{Camera, Trust};
    use etl_core::undistort::{rectify_maps, OutputCamera};
    let mut model = CameraModel::strong_distortion_rig();
    model.centre = Some(MovingCentre { dz_mm: [-5e-3, 1e-5], principal_point_slope_px: [0.01, 0.0] });
    let Ok(cam) = Camera::new(model, None, [80.0, 225.0]) else { return f64::NAN };
    let (Ok(c0), Ok(c1)) = (cam.at_e_com(e0_ma, Trust::Refuse), cam.at_e_com(e1_ma, Trust::Refuse)) else {
        return f64::NAN;
    };
    let reference = RigPose::from_rodrigues([0.0, -0.05, 0.0], [-100.0, 0.0, 0.0]);
    let pose = reference.at_settings(centre_shift_mm(&model, e0_ma, 150.0), centre_shift_mm(&model, e1_ma, 150.0));
    let x = [10.0, -5.0, z_mm];
    let (Ok(p0), Ok(p1)) = (c0.project_camera_point(x), c1.project_camera_point(pose.apply(x))) else {
        return f64::NAN;
    };
    let views = [
        TriangulationView { camera: &c0, pose: RigPose::IDENTITY, pixel: p0 },
        TriangulationView { camera: &c1, pose, pixel: p1 },
    ];
    let Ok(t) = triangulate(&views, sigma_px) else { return f64::NAN };
    let Ok(out) = OutputCamera::of_intrinsics(c1.intrinsics(), 8, 8) else { return f64::NAN };
    let (mx, my) = maps.split_at_mut(64);
    if rectify_maps(c1.intrinsics(), c1.distortion(), &pose.rotation, &out, 0..8, mx, my).is_err() {
        return f64::NAN;
    }
    t.point_mm[2] + t.covariance_mm2[2][2] + mx[9] as f64
}
