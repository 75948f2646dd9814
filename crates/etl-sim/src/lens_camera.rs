//! A camera that frames the virtual lens at a frame rate, for characterising its dynamics
//! ([`etl_calib::lens_dynamics`]): each frame renders a board at the optics' state at that
//! frame's model time, so a frame taken during a step sees the lens part way.
//!
//! The camera (this simulation's choices): a board of 5 x 4 inner corners, 1.2 mm
//! squares, fronto-parallel on the optical axis 60 mm away, a 384 x 320 image whose focal
//! length follows the lens's compensated current, fx = 1500 + 3 E_com px (mA): 0.17 % of
//! scale per mA at 100 mA, a magnification that changes with the power as an ETL in front
//! of a prime lens changes it. No defocus: the scale carries the state, not the sharpness.
//! The model's clock is the device's: a frame advances it by one frame period, and
//! waiting advances it without rendering (no wall time is spent; give the device a small
//! time scale so that wall time does not move it either).

use etl_calib::lens_dynamics::{Pattern, TimedCamera};
use etl_core::model::{CameraModel, DistortionA, FocalPoly};
use etl_formats::board::{Board, Checkerboard};
use etl_formats::{Error, Result};
use etl_hw::virtual_lens::VirtualDevice;
use image::GrayImage;

use crate::render::{render, RenderOptions, Scene};

/// The board's distance, mm.
const DISTANCE_MM: f64 = 60.0;
/// fx = FX0 + FX1 E_com, px.
const FX: [f64; 2] = [1500.0, 3.0];

/// The camera on a virtual lens.
pub struct SimLensCamera {
    device: VirtualDevice,
    frame_period_s: f64,
    board: Checkerboard,
    image_size: [u32; 2],
    frames: u64,
}

impl SimLensCamera {
    /// The camera of the module docs on `device`, framing at `frame_rate_hz` (1..=100000).
    pub fn new(device: VirtualDevice, frame_rate_hz: f64) -> Result<Self> {
        if !(frame_rate_hz.is_finite() && (1.0..=1e5).contains(&frame_rate_hz)) {
            let message = format!("frame_rate_hz {frame_rate_hz} Hz must lie in 1..=100000 Hz");
            return Err(Error::invalid_value("frame_rate_hz", frame_rate_hz, message));
        }
        Ok(SimLensCamera {
            device,
            frame_period_s: 1.0 / frame_rate_hz,
            board: Checkerboard { inner_corners: [5, 4], square_mm: 1.2 },
            image_size: [384, 320],
            frames: 0,
        })
    }

    /// The camera model at compensated current `e_com_ma`, the board centred on the axis.
    fn model(&self) -> CameraModel {
        let s = self.board.square_mm;
        let [cols, rows] = self.board.inner_corners;
        let centre = [0.5 * s * (cols - 1) as f64, 0.5 * s * (rows - 1) as f64];
        let [w, h] = self.image_size;
        CameraModel {
            rotation_rodrigues: [0.0; 3],
            translation_mm: [-centre[0], -centre[1], DISTANCE_MM],
            kf_x: FocalPoly::cubic([FX[0], FX[1], 0.0, 0.0]),
            kf_y: FocalPoly::cubic([FX[0], FX[1], 0.0, 0.0]),
            principal_point: [0.5 * (w as f64 - 1.0), 0.5 * (h as f64 - 1.0)],
            distortion_a: DistortionA::paper([0.0; 9]),
            centre: None,
        }
    }
}

impl TimedCamera for SimLensCamera {
    fn grab(&mut self) -> Result<(f64, GrayImage)> {
        self.device.advance_s(self.frame_period_s);
        let state = self.device.state();
        self.frames += 1;
        let scene = Scene::new(self.model(), state.e_com_ma, Board::Checkerboard(self.board), 0.0, self.image_size);
        let options = RenderOptions { seed: self.frames, ..RenderOptions::default() };
        let image = render(&scene, &options)?.image.to_dynamic().to_luma8();
        Ok((state.model_time_s, image))
    }

    fn wait_s(&mut self, s: f64) -> Result<()> {
        self.device.advance_s(s);
        Ok(())
    }

    fn now_s(&self) -> f64 {
        self.device.state().model_time_s
    }

    fn pattern(&self) -> Pattern {
        let [cols, rows] = self.board.inner_corners;
        Pattern { cols, rows }
    }
}
