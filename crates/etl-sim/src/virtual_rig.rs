//! The procedure's virtual rig: the synthetic camera looking at a board through the
//! virtual lens ([`etl_hw::virtual_lens::VirtualLens`]), and the virtual lens's heated
//! mount as the [`Climate`].
//!
//! The camera (this simulation's choices): a board of 5 x 4 inner corners, 1.5 mm squares,
//! fronto-parallel on the optical axis, an 800 x 600 crop of a sensor with 5.86 um pixels at
//! a fixed image distance of 26 mm behind the ETL group; the group's focal length is the
//! paper's physics, f_com(E_com) (Eq. 8, 10), at the lens's *true* E_com = E_in - E_T(T,
//! E_in) (the virtual lens's surface), so the plane in focus lies at the thin-lens distance
//! s_o = 1 / (1/f_com - 1/26 mm): about 236 mm at 40 mA and 81 mm at 240 mA. The board's
//! image size is held fixed (a pinhole of focal length 26 mm / 5.86 um); only the focus
//! moves with the current, so a sharpness peak is where the board is in focus.

use etl_core::model::{CameraModel, DistortionA, FocalPoly};
use etl_core::physics::LensPhysics;
use etl_core::thermal::ThermalSurface;
use etl_hw::virtual_lens::VirtualLens;
use image::GrayImage;

use crate::render::{render, Optics, RenderOptions, Scene};
use etl_calib::thermal_calibration::{run_procedure, Camera, Climate, ProcedureOptions, ProcedureResult};
use etl_core::progress::Progress;
use etl_formats::board::{Board, Checkerboard};
use etl_formats::{Error, Result};
use etl_hw::client::{LensClient, OpenOptions};

/// Image distance of the virtual camera, mm.
pub const IMAGE_DISTANCE_MM: f64 = 26.0;
/// Pixel pitch, mm.
pub const PIXEL_MM: f64 = 0.005_86;

/// The synthetic camera looking through a virtual lens.
pub struct VirtualCamera<'a> {
    lens: &'a VirtualLens,
    physics: LensPhysics,
    /// Aperture diameter, mm.
    pub aperture_mm: f64,
    /// Image width and height, px.
    pub image_size: [u32; 2],
    board: Checkerboard,
    board_depth_mm: f64,
    frames: u64,
    /// How long the camera waits for the lens to settle before each frame, model s (the
    /// model's clock jumps ahead by it: no wall time is spent). 0: the frame is taken at
    /// once, which a lens with dynamics punishes.
    pub settle_s: f64,
}

impl<'a> VirtualCamera<'a> {
    /// The camera of the module documentation on `lens`, aperture 10 mm (the EL-10-30's
    /// clear aperture: the paper placed the board close, at high magnification, for the
    /// same reason, a sharpness that changes fast with the current).
    pub fn new(lens: &'a VirtualLens) -> Self {
        VirtualCamera {
            lens,
            physics: LensPhysics::paper(),
            aperture_mm: 10.0,
            image_size: [800, 600],
            board: Checkerboard { inner_corners: [5, 4], square_mm: 1.5 },
            board_depth_mm: 150.0,
            frames: 0,
            settle_s: 0.0,
        }
    }

    /// The distance in focus at E_com, mm (thin lens at the fixed image distance).
    pub fn focus_distance_mm(&self, e_com_ma: f64) -> Result<f64> {
        let f = self.physics.f_com_mm(e_com_ma)?;
        let inv = 1.0 / f - 1.0 / IMAGE_DISTANCE_MM;
        if !(inv > 0.0) {
            return Err(Error::invalid_value(
                "e_com_ma",
                e_com_ma,
                format!(
                    "at E_com {e_com_ma} mA the lens (f = {f} mm) cannot focus with the sensor at {IMAGE_DISTANCE_MM} mm"
                ),
            ));
        }
        Ok(1.0 / inv)
    }
}

impl Camera for VirtualCamera<'_> {
    fn capture(&mut self) -> Result<GrayImage> {
        self.lens.device().advance_s(self.settle_s);
        let focus = self.focus_distance_mm(self.lens.state().e_com_ma)?;
        let f_px = IMAGE_DISTANCE_MM / PIXEL_MM;
        let [w, h] = self.image_size;
        let s = self.board.square_mm;
        let [cols, rows] = self.board.inner_corners;
        let centre = [0.5 * s * (cols - 1) as f64, 0.5 * s * (rows - 1) as f64];
        let model = CameraModel {
            rotation_rodrigues: [0.0; 3],
            translation_mm: [-centre[0], -centre[1], self.board_depth_mm],
            kf_x: FocalPoly::cubic([f_px, 0.0, 0.0, 0.0]),
            kf_y: FocalPoly::cubic([f_px, 0.0, 0.0, 0.0]),
            principal_point: [0.5 * (w as f64 - 1.0), 0.5 * (h as f64 - 1.0)],
            distortion_a: DistortionA::paper([0.0; 9]),
            centre: None,
        };
        self.frames += 1;
        let scene = Scene::new(model, 0.0, Board::Checkerboard(self.board), 0.0, self.image_size);
        let opts = RenderOptions {
            optics: Optics { focus_depth_mm: Some(focus), aperture_mm: self.aperture_mm, base_sigma_px: 0.0 },
            seed: self.frames,
            ..RenderOptions::default()
        };
        Ok(render(&scene, &opts)?.image.to_dynamic().to_luma8())
    }

    fn place_board_in_focus(&mut self) -> Result<()> {
        // The board is placed for the lens at rest, after the same wait as a frame.
        self.lens.device().advance_s(self.settle_s);
        self.board_depth_mm = self.focus_distance_mm(self.lens.state().e_com_ma)?;
        Ok(())
    }
}

/// The virtual lens's heated mount: sets the heater for the temperature and jumps to
/// thermal equilibrium.
pub struct VirtualClimate<'a>(pub &'a VirtualLens);

impl Climate for VirtualClimate<'_> {
    fn set_temperature_c(&mut self, t_c: f64) -> Result<()> {
        if !t_c.is_finite() {
            return Err(Error::invalid_value("temperature_c", t_c, format!("temperature {t_c} degC is not finite")));
        }
        self.0.set_target_temperature_c(t_c);
        self.0.settle();
        Ok(())
    }
}

/// How far a fitted surface is from the virtual lens's true one over `t_range_c` x
/// `e_in_range_ma` (a 21 x 21 grid), mA: (RMS against the truth referenced like the
/// procedure, i.e. E_T(T, E) - E_T(T_ref, E_ref) with E_ref the current in focus at
/// T_ref for the same E_com; RMS against the truth as it is).
pub fn surface_error_ma(
    result: &ProcedureResult,
    truth: &ThermalSurface,
    e_in_range_ma: [f64; 2],
    t_range_c: [f64; 2],
    t_ref_c: f64,
) -> Result<(f64, f64)> {
    let fitted = &result.calibration.surface;
    let (mut referenced, mut absolute, mut n) = (0.0, 0.0, 0usize);
    for a in 0..=20 {
        for b in 0..=20 {
            let t = t_range_c[0] + (t_range_c[1] - t_range_c[0]) * a as f64 / 20.0;
            let e = e_in_range_ma[0] + (e_in_range_ma[1] - e_in_range_ma[0]) * b as f64 / 20.0;
            let got = fitted.e_t_ma(e, t)?;
            let want = truth.e_t_ma(e, t)?;
            let e_com = e - want;
            let e_ref = truth.e_in_for_e_com(e_com, t_ref_c)?;
            let want_ref = want - truth.e_t_ma(e_ref, t_ref_c)?;
            referenced += (got - want_ref) * (got - want_ref);
            absolute += (got - want) * (got - want);
            n += 1;
        }
    }
    Ok(((referenced / n as f64).sqrt(), (absolute / n as f64).sqrt()))
}
/// The longest wait before a frame, s.
pub const MAX_SETTLE_S: f64 = 10.0;

/// How the virtual rig's lens behaves and how long its camera waits for it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VirtualRigLens {
    /// The lens's dynamics (None: the optics follow the current at once).
    pub dynamics: Option<etl_core::physics::dynamics::LensDynamics>,
    /// The camera's wait before each frame, s, in 0..=[`MAX_SETTLE_S`]
    /// ([`VirtualCamera::settle_s`]).
    pub settle_s: f64,
}

/// The temperature procedure run on the virtual rig, and how far its surface is from the
/// virtual lens's true one.
#[derive(Debug, Clone)]
pub struct VirtualProcedure {
    /// What the procedure measured and fitted.
    pub result: ProcedureResult,
    /// The temperature the procedure references its E_T to (its first), degC.
    pub t_ref_c: f64,
    /// RMS error of the fitted surface against the truth, referenced to `t_ref_c` as the
    /// procedure is, mA.
    pub surface_error_ma: f64,
    /// The same without the reference, mA.
    pub surface_error_absolute_ma: f64,
}

/// Runs the section 4.1 procedure with `options` on a virtual lens (the paper's physics
/// and thermal surface, and `dynamics` if given: the camera then sees the lens where its
/// response has got to at each frame) served on a pseudo-terminal and driven through the
/// real serial client, the synthetic camera looking through it and its climate; compares
/// the fitted surface with the truth over the procedure's ranges.
pub fn run_virtual_procedure(
    options: &ProcedureOptions,
    lens: &VirtualRigLens,
    progress: &dyn Progress,
) -> Result<VirtualProcedure> {
    if !(lens.settle_s.is_finite() && (0.0..=MAX_SETTLE_S).contains(&lens.settle_s)) {
        let message = format!("settle_s {} s must lie in 0..={MAX_SETTLE_S} s", lens.settle_s);
        return Err(Error::invalid_value("settle_s", lens.settle_s, message));
    }
    let config = etl_hw::virtual_lens::VirtualLensConfig { dynamics: lens.dynamics, ..Default::default() };
    let truth = config.surface;
    let device = VirtualLens::spawn(config).map_err(Error::lens)?;
    let mut client = LensClient::open(device.path(), OpenOptions::default()).map_err(Error::lens)?;
    let mut camera = VirtualCamera::new(&device);
    camera.settle_s = lens.settle_s;
    let mut climate = VirtualClimate(&device);
    let result = run_procedure(&mut client, &mut camera, &mut climate, options, progress)?;
    let t_ref_c = options.temperatures_c.first().copied().unwrap_or(27.0);
    let c = &result.calibration;
    let (surface_error_ma, surface_error_absolute_ma) =
        surface_error_ma(&result, &truth, c.e_in_range_ma, c.t_range_c, t_ref_c)?;
    Ok(VirtualProcedure { result, t_ref_c, surface_error_ma, surface_error_absolute_ma })
}
