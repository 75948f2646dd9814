//! `v4l2:/dev/videoN`: a V4L2 camera (Linux, cargo feature `v4l2`; the `v4l` crate, whose
//! bindings are generated with libclang at build time: Debian's libclang-dev).
//!
//! Opening: the device is opened, its pixel format negotiated ([`super::v4l2_format`]:
//! `Y16 `, else `GREY`, else `YUYV` made grey) at the size it is set to, and
//! [`BUFFERS`] memory-mapped buffers queued; streaming starts at the first grab. Each grab
//! takes the next filled buffer (waiting at most [`FRAME_TIMEOUT_MS`]) and converts it.
//! Timestamps are the buffer's (the driver's, usually the monotonic clock at the frame's
//! start), ns.
//!
//! Exposure goes to the control `exposure_time_absolute` (V4L2_CID_EXPOSURE_ABSOLUTE, in
//! units of 100 us: the exposure is rounded to them), `auto_exposure` first set to manual
//! when the device has it; a device without it is refused in one line naming the
//! control. Gain is refused: V4L2's `gain` control (V4L2_CID_GAIN) has no unit, so a gain
//! in dB cannot be set through it (set it in the device's units with v4l2-ctl).

use v4l::buffer::Type;
use v4l::control::{Control, Value};
use v4l::io::traits::CaptureStream;
use v4l::prelude::*;
use v4l::v4l_sys;
use v4l::video::Capture;

use super::v4l2_format::{choose_layout, frame_pixels, PixelLayout};
use super::{Camera, CameraInfo, Frame};
use crate::error::{Error, ErrorKind, Result};

/// Buffers queued on the stream.
pub const BUFFERS: u32 = 4;

/// The longest wait for a frame, ms.
pub const FRAME_TIMEOUT_MS: u64 = 5000;

/// V4L2's manual exposure, the value of `auto_exposure` (V4L2_EXPOSURE_MANUAL).
const EXPOSURE_MANUAL: i64 = 1;

/// An open V4L2 camera.
pub struct V4l2Camera {
    path: std::path::PathBuf,
    // Dropped first: the stream's buffers before the device.
    stream: Option<MmapStream<'static>>,
    device: Device,
    layout: PixelLayout,
    size: [u32; 2],
    stride: usize,
    model: String,
}

impl V4l2Camera {
    /// Opens `path` and negotiates its format (module docs).
    ///
    /// Errors: the device cannot be opened (missing, busy, not a camera), or offers no
    /// format etlcal reads; each one line naming the device.
    pub fn open(path: &std::path::Path) -> Result<V4l2Camera> {
        let name = format!("camera v4l2:{}", path.display());
        let io = |kind: ErrorKind, what: &str| {
            let name = name.clone();
            let what = what.to_owned();
            move |e: std::io::Error| Error::device(&name, kind, format!("{what}: {e}"))
        };
        let device = Device::with_path(path).map_err(io(ErrorKind::LinkLost, "cannot open"))?;
        let caps = device.query_caps().map_err(io(ErrorKind::Protocol, "cannot query the device"))?;
        let offered: Vec<[u8; 4]> = device
            .enum_formats()
            .map_err(io(ErrorKind::Protocol, "cannot list its formats"))?
            .iter()
            .map(|f| f.fourcc.repr)
            .collect();
        let layout = choose_layout(&offered).map_err(|m| Error::device(&name, ErrorKind::Refused, m))?;
        let mut format = device.format().map_err(io(ErrorKind::Protocol, "cannot read its format"))?;
        format.fourcc = v4l::FourCC::new(&layout.fourcc());
        let set = device.set_format(&format).map_err(io(ErrorKind::Refused, "cannot set its format"))?;
        if set.fourcc.repr != layout.fourcc() {
            let message =
                format!("asked for {}, the driver set {}", fourcc_name(layout.fourcc()), fourcc_name(set.fourcc.repr));
            return Err(Error::device(&name, ErrorKind::Refused, message));
        }
        let model = format!("{} ({})", caps.card, caps.driver);
        Ok(V4l2Camera {
            path: path.to_owned(),
            stream: None,
            device,
            layout,
            size: [set.width, set.height],
            stride: set.stride as usize,
            model,
        })
    }

    /// The pixel layout negotiated.
    pub fn layout(&self) -> PixelLayout {
        self.layout
    }

    /// Whether the device has the control `id`.
    fn has_control(&self, id: u32) -> Result<bool> {
        let controls = self
            .device
            .query_controls()
            .map_err(|e| Error::device(self.name(), ErrorKind::Protocol, format!("cannot list its controls: {e}")))?;
        Ok(controls.iter().any(|c| c.id == id))
    }

    fn set_control(&self, id: u32, value: i64, control: &str) -> Result<()> {
        self.device
            .set_control(Control { id, value: Value::Integer(value) })
            .map_err(|e| Error::device(self.name(), ErrorKind::Refused, format!("{control} = {value} refused: {e}")))
    }
}

fn fourcc_name(c: [u8; 4]) -> String {
    String::from_utf8_lossy(&c).trim_end().to_owned()
}

impl Camera for V4l2Camera {
    fn name(&self) -> String {
        format!("camera v4l2:{}", self.path.display())
    }

    fn grab(&mut self) -> Result<Frame> {
        let name = self.name();
        if self.stream.is_none() {
            let mut stream = MmapStream::with_buffers(&self.device, Type::VideoCapture, BUFFERS)
                .map_err(|e| Error::device(&name, ErrorKind::LinkLost, format!("cannot map its buffers: {e}")))?;
            stream.set_timeout(std::time::Duration::from_millis(FRAME_TIMEOUT_MS));
            self.stream = Some(stream);
        }
        let Some(stream) = self.stream.as_mut() else {
            return Err(Error::device(&name, ErrorKind::LinkLost, "no stream"));
        };
        let (data, meta) = stream.next().map_err(|e| {
            let kind = if e.kind() == std::io::ErrorKind::TimedOut { ErrorKind::Timeout } else { ErrorKind::LinkLost };
            Error::device(&name, kind, format!("no frame within {} s ({e})", FRAME_TIMEOUT_MS as f64 / 1000.0))
        })?;
        let used = &data[..(meta.bytesused as usize).min(data.len())];
        let pixels = frame_pixels(self.layout, used, self.size, self.stride)
            .map_err(|m| Error::device(&name, ErrorKind::Protocol, m))?;
        let (sec, usec) = (meta.timestamp.sec.max(0) as u64, meta.timestamp.usec.max(0) as u64);
        Ok(Frame { pixels, timestamp_ns: sec * 1_000_000_000 + usec * 1000 })
    }

    fn set_exposure_us(&mut self, exposure_us: f64) -> Result<()> {
        if !(exposure_us.is_finite() && exposure_us > 0.0) {
            let message = format!("exposure {exposure_us} us must be > 0");
            return Err(Error::device(self.name(), ErrorKind::InvalidInput, message));
        }
        let id = v4l_sys::V4L2_CID_EXPOSURE_ABSOLUTE;
        if !self.has_control(id)? {
            let message = "the device has no control exposure_time_absolute (V4L2_CID_EXPOSURE_ABSOLUTE): set its exposure with v4l2-ctl";
            return Err(Error::device(self.name(), ErrorKind::Refused, message));
        }
        if self.has_control(v4l_sys::V4L2_CID_EXPOSURE_AUTO)? {
            self.set_control(v4l_sys::V4L2_CID_EXPOSURE_AUTO, EXPOSURE_MANUAL, "auto_exposure")?;
        }
        // The control counts 100 us.
        self.set_control(id, (exposure_us / 100.0).round().max(1.0) as i64, "exposure_time_absolute")
    }

    fn set_gain_db(&mut self, _gain_db: f64) -> Result<()> {
        let message = "V4L2's gain control (V4L2_CID_GAIN) has no unit, a gain in dB cannot be set: set it in the device's units with v4l2-ctl";
        Err(Error::device(self.name(), ErrorKind::Refused, message))
    }

    fn info(&mut self) -> Result<CameraInfo> {
        Ok(CameraInfo {
            spec: format!("v4l2:{}", self.path.display()),
            model: self.model.clone(),
            image_size: self.size,
        })
    }
}
