//! `sim`: the synthetic camera of the simulated paper rig ([`crate::sim`]), looking through
//! the virtual lens. Each frame renders (etl-sim's renderer) the board where the simulated
//! world has it, at the lens's *true* compensated current at that moment (the virtual
//! lens's thermal surface and, with dynamics, its response), defocus included: in focus at
//! the paper rig's focus law through a 2.5 mm aperture for the ETL views, at 125 mm
//! through 1 mm for the lens-off views (as `etlcal demo` renders them), with the renderer's
//! default grey levels and noise (a new noise draw per frame). At 0 mA the lens is off and
//! renders at E = 0 (the model's lens-off state). Exposure and gain are accepted and change
//! nothing. Timestamps are the virtual lens's model clock, ns.
//!
//! A region of interest ([`SimCamera::set_roi`], `--sim-roi X Y W H`) renders only that
//! window of the sensor (the principal point moved by its offset, as a camera's
//! OffsetX/OffsetY do): the same pixels, `W x H` of them; a temperature capture, which
//! needs sharpness and not the whole board, runs many times faster on a small window.
//!
//! A frame-level test double as well: [`SimCamera::disconnect_after`] makes it lose its
//! link after a number of frames, as an unplugged camera does.

use etl_core::model::CameraModel;
use etl_hw::virtual_lens::VirtualDevice;
use etl_sim::render::{render, Optics, RenderOptions, Scene};
use etl_sim::rig::charuco_frame;

use super::{Camera, CameraInfo, Frame, Pixels};
use crate::error::{Error, ErrorKind, Result};
use crate::sim::{SimWorld, SIM_OFFSTATE_POSES};

/// Aperture of the ETL views, mm (the demo's).
const APERTURE_MM: f64 = 2.5;
/// Aperture and focus distance of the lens-off views, mm (the demo's).
const LENS_OFF_APERTURE_MM: f64 = 1.0;
const LENS_OFF_FOCUS_MM: f64 = 125.0;

/// The synthetic camera.
pub struct SimCamera {
    world: SimWorld,
    lens: VirtualDevice,
    truth: CameraModel,
    frames: u64,
    seed: u64,
    disconnect_after: Option<u64>,
    roi: Option<[u32; 4]>,
}

/// The smallest region of interest, px (a side).
pub const MIN_ROI_PX: u32 = 16;

impl SimCamera {
    /// The camera of the module docs on `world` through the virtual lens `lens`; `seed`
    /// seeds the noise of each frame (with the frame's number).
    pub fn new(world: SimWorld, lens: VirtualDevice, seed: u64) -> SimCamera {
        SimCamera { world, lens, truth: CameraModel::paper_rig(), frames: 0, seed, disconnect_after: None, roi: None }
    }

    /// The true camera of the simulated rig (the paper rig's, in its own world frame).
    pub fn truth(&self) -> CameraModel {
        self.truth
    }

    /// Test double: after `frames` more frames every grab fails with a lost link.
    pub fn disconnect_after(&mut self, frames: u64) {
        self.disconnect_after = Some(self.frames + frames);
    }

    /// Renders only the window `[x, y, width, height]` of the sensor, px (module docs).
    ///
    /// Errors: a window not inside the 1936 x 1458 sensor or under [`MIN_ROI_PX`] a side.
    pub fn set_roi(&mut self, roi: [u32; 4]) -> Result<()> {
        let [x, y, w, h] = roi;
        let [sw, sh] = CameraModel::PAPER_IMAGE_SIZE;
        let inside = u64::from(x) + u64::from(w) <= u64::from(sw) && u64::from(y) + u64::from(h) <= u64::from(sh);
        if !(inside && w >= MIN_ROI_PX && h >= MIN_ROI_PX) {
            let message = format!(
                "region of interest x {x}, y {y}, {w} x {h} px is not inside the {sw} x {sh} px sensor with sides of at least {MIN_ROI_PX} px"
            );
            return Err(Error::device(self.name(), ErrorKind::InvalidInput, message));
        }
        self.roi = Some(roi);
        Ok(())
    }

    /// The rendered image's size, px (the region of interest's, or the sensor's).
    fn image_size(&self) -> [u32; 2] {
        self.roi.map_or(CameraModel::PAPER_IMAGE_SIZE, |[_, _, w, h]| [w, h])
    }

    /// `cam` seen through the region of interest: the principal point moved by its offset.
    fn windowed(&self, mut cam: CameraModel) -> CameraModel {
        if let Some([x, y, _, _]) = self.roi {
            cam.principal_point[0] -= f64::from(x);
            cam.principal_point[1] -= f64::from(y);
        }
        cam
    }

    /// The camera in the frame of a ChArUco `board` (OpenCV's origin, one square before
    /// the paper board's first inner corner), or as it is for a checkerboard.
    fn in_board_frame(cam: &CameraModel, board: &etl_formats::Board) -> CameraModel {
        match board {
            etl_formats::Board::Charuco(_) => charuco_frame(cam, board.square_mm()),
            etl_formats::Board::Checkerboard(_) => *cam,
        }
    }

    fn scene(&self, e_com_ma: f64) -> Result<(Scene, Optics)> {
        let size = self.image_size();
        match self.world.view() {
            (Some((k, board)), _, _) => {
                let poses = etl_sim::simulate::lens_off_poses(&self.truth);
                let pose = poses.get(k % SIM_OFFSTATE_POSES).copied().unwrap_or(self.truth);
                let optics = Optics {
                    focus_depth_mm: Some(LENS_OFF_FOCUS_MM),
                    aperture_mm: LENS_OFF_APERTURE_MM,
                    base_sigma_px: 0.0,
                };
                let cam = self.windowed(Self::in_board_frame(&pose, &board));
                Ok((Scene::new(cam, e_com_ma, board, 0.0, size), optics))
            }
            (None, board, z_mm) => {
                let optics = Optics::paper_focus(&self.truth, e_com_ma, APERTURE_MM);
                let cam = self.windowed(Self::in_board_frame(&self.truth, &board));
                Ok((Scene::new(cam, e_com_ma, board, z_mm, size), optics))
            }
        }
    }
}

impl Camera for SimCamera {
    fn name(&self) -> String {
        "camera sim".into()
    }

    fn grab(&mut self) -> Result<Frame> {
        if self.disconnect_after.is_some_and(|n| self.frames >= n) {
            return Err(Error::device(self.name(), ErrorKind::LinkLost, "disconnected: no frame (the link is gone)"));
        }
        let state = self.lens.state();
        self.frames += 1;
        // No current, no power change: the lens-off state of the model, E = 0 (the virtual
        // lens's thermal surface is not defined there).
        let e_com_ma = if state.e_in_ma == 0.0 { 0.0 } else { state.e_com_ma };
        if !e_com_ma.is_finite() {
            let message = format!(
                "the virtual lens has no compensated current at {} mA (outside its thermal surface)",
                state.e_in_ma
            );
            return Err(Error::device(self.name(), ErrorKind::InvalidInput, message));
        }
        let (scene, optics) = self.scene(e_com_ma)?;
        let options = RenderOptions {
            optics,
            seed: self.seed.wrapping_mul(1_000_003).wrapping_add(self.frames),
            ..RenderOptions::default()
        };
        let rendered =
            render(&scene, &options).map_err(|e| Error::device(self.name(), ErrorKind::Other, e.to_string()))?;
        let pixels = Pixels::from_dynamic(rendered.image.to_dynamic());
        Ok(Frame { pixels, timestamp_ns: (state.model_time_s.max(0.0) * 1e9) as u64 })
    }

    fn set_exposure_us(&mut self, exposure_us: f64) -> Result<()> {
        if !(exposure_us.is_finite() && exposure_us > 0.0) {
            return Err(Error::device(
                self.name(),
                ErrorKind::InvalidInput,
                format!("exposure {exposure_us} us must be > 0"),
            ));
        }
        Ok(())
    }

    fn set_gain_db(&mut self, gain_db: f64) -> Result<()> {
        if !gain_db.is_finite() {
            return Err(Error::device(
                self.name(),
                ErrorKind::InvalidInput,
                format!("gain {gain_db} dB is not finite"),
            ));
        }
        Ok(())
    }

    fn info(&mut self) -> Result<CameraInfo> {
        Ok(CameraInfo {
            spec: "sim".into(),
            model: "etlcal synthetic camera (paper rig)".into(),
            image_size: self.image_size(),
        })
    }
}
