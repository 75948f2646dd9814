//! `aravis:NAME`: a GenICam camera (GigE Vision, USB3 Vision) through libaravis 0.8
//! (cargo feature `aravis`; Debian: libaravis-dev). NAME is aravis's device id, as
//! `etlcal camera list` and `arv-tool-0.8` print it. `aravis:Fake_N` opens aravis's
//! in-process fake camera with serial N (no network, no interface to enable): the
//! GenICam stack and the stream path of a real camera, frames of a test pattern.
//!
//! Frames come through an aravis stream with [`BUFFERS`] buffers, acquisition running
//! from the first grab on; each grab takes the next complete buffer and gives it back.
//! Mono8 frames are 8-bit; Mono10, Mono12, Mono14 and Mono16 (unpacked, little-endian)
//! 16-bit with their samples as they come; any other pixel format is refused (set a mono
//! format in the camera). Timestamps are the camera's (`timestamp`, ns), or the host's
//! arrival time when the camera gives none.
//!
//! The fake camera renders its own pattern. Filling its frames with rendered boards (so
//! that a whole capture would run through aravis) needs `arv_fake_camera_set_fill_pattern`,
//! a C callback writing into the buffer: the safe bindings (`aravis` 0.11) do not bind it,
//! only the raw `aravis-sys` does, and this crate keeps no `unsafe` code; `sim` renders
//! the board instead.

use aravis::prelude::*;
use aravis::{Buffer, BufferStatus, Camera as ArvCamera, FakeDevice, PixelFormat, Stream};

use super::{Camera, CameraInfo, Frame, Gray16Image, Pixels};
use crate::error::{Error, ErrorKind, Result};

/// Buffers queued on the stream.
pub const BUFFERS: usize = 4;

/// The longest wait for a frame, us.
pub const FRAME_TIMEOUT_US: u64 = 5_000_000;

/// An open GenICam camera.
pub struct AravisCamera {
    id: String,
    acquiring: bool,
    // Dropped in this order: the stream before the camera, the camera before its device.
    stream: Stream,
    camera: ArvCamera,
    _device: Option<FakeDevice>,
}

fn glib_err(name: &str, kind: ErrorKind) -> impl Fn(aravis::glib::Error) -> Error + '_ {
    move |e| Error::device(name, kind, e.to_string())
}

/// One camera opened at a time in the process: aravis builds each camera's GenICam tree
/// with GLib's lazily registered types, and two threads opening cameras at once corrupt it
/// (seen as "self is not a ArvDomNode" and a SIGFPE with two fake cameras opened by
/// parallel tests).
static OPENING: std::sync::Mutex<()> = std::sync::Mutex::new(());

impl AravisCamera {
    /// Opens the camera `id` and queues its stream's buffers (one opening at a time in the
    /// process, `OPENING`).
    pub fn open(id: &str) -> Result<AravisCamera> {
        let _one_at_a_time = OPENING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let name = format!("camera aravis:{id}");
        let (camera, device) = match id.strip_prefix("Fake_") {
            Some(serial) => {
                let device = FakeDevice::new(serial).map_err(glib_err(&name, ErrorKind::LinkLost))?;
                (ArvCamera::with_device(&device).map_err(glib_err(&name, ErrorKind::LinkLost))?, Some(device))
            }
            None => (ArvCamera::new(Some(id)).map_err(glib_err(&name, ErrorKind::LinkLost))?, None),
        };
        let payload = camera.payload().map_err(glib_err(&name, ErrorKind::Protocol))?;
        let stream = camera.create_stream().map_err(glib_err(&name, ErrorKind::LinkLost))?;
        for _ in 0..BUFFERS {
            stream.push_buffer(Buffer::new_allocate(payload as usize));
        }
        Ok(AravisCamera { id: id.to_owned(), acquiring: false, stream, camera, _device: device })
    }

    fn pixels(&self, buffer: &Buffer) -> Result<Pixels> {
        let (w, h) = (buffer.image_width().max(0) as u32, buffer.image_height().max(0) as u32);
        let data = buffer.image_data();
        let format = buffer.image_pixel_format();
        let n = w as usize * h as usize;
        let short = |bytes: usize| {
            Error::device(self.name(), ErrorKind::Protocol, format!("a {w} x {h} frame came with {bytes} bytes"))
        };
        if format == PixelFormat::MONO_8 {
            let raw = data.get(..n).ok_or_else(|| short(data.len()))?.to_vec();
            return Ok(Pixels::Mono8(image::GrayImage::from_raw(w, h, raw).ok_or_else(|| short(data.len()))?));
        }
        let wide = [PixelFormat::MONO_10, PixelFormat::MONO_12, PixelFormat::MONO_14, PixelFormat::MONO_16];
        if wide.contains(&format) {
            let bytes = data.get(..2 * n).ok_or_else(|| short(data.len()))?;
            let raw = bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect();
            return Ok(Pixels::Mono16(Gray16Image::from_raw(w, h, raw).ok_or_else(|| short(data.len()))?));
        }
        let message = format!("pixel format 0x{:08x} is not mono: set Mono8 or Mono16 in the camera", format.raw());
        Err(Error::device(self.name(), ErrorKind::Refused, message))
    }
}

impl Camera for AravisCamera {
    fn name(&self) -> String {
        format!("camera aravis:{}", self.id)
    }

    fn grab(&mut self) -> Result<Frame> {
        let name = self.name();
        if !self.acquiring {
            self.camera.start_acquisition().map_err(glib_err(&name, ErrorKind::LinkLost))?;
            self.acquiring = true;
        }
        let buffer = self.stream.timeout_pop_buffer(FRAME_TIMEOUT_US).ok_or_else(|| {
            let message = format!("no frame within {} s (disconnected?)", FRAME_TIMEOUT_US as f64 / 1e6);
            Error::device(&name, ErrorKind::Timeout, message)
        })?;
        let status = buffer.status();
        let result = if status == BufferStatus::Success {
            let ts = buffer.timestamp();
            let timestamp_ns = if ts == 0 { buffer.system_timestamp() } else { ts };
            self.pixels(&buffer).map(|pixels| Frame { pixels, timestamp_ns })
        } else {
            Err(Error::device(&name, ErrorKind::Protocol, format!("incomplete frame (buffer status {status:?})")))
        };
        self.stream.push_buffer(buffer);
        result
    }

    fn set_exposure_us(&mut self, exposure_us: f64) -> Result<()> {
        let name = self.name();
        self.camera.set_exposure_time(exposure_us).map_err(glib_err(&name, ErrorKind::Refused))
    }

    fn set_gain_db(&mut self, gain_db: f64) -> Result<()> {
        let name = self.name();
        self.camera.set_gain(gain_db).map_err(glib_err(&name, ErrorKind::Refused))
    }

    fn info(&mut self) -> Result<CameraInfo> {
        let name = self.name();
        let vendor = self.camera.vendor_name().map_err(glib_err(&name, ErrorKind::Protocol))?;
        let model = self.camera.model_name().map_err(glib_err(&name, ErrorKind::Protocol))?;
        let (_, _, w, h) = self.camera.region().map_err(glib_err(&name, ErrorKind::Protocol))?;
        Ok(CameraInfo {
            spec: format!("aravis:{}", self.id),
            model: format!("{vendor} {model}"),
            image_size: [w.max(0) as u32, h.max(0) as u32],
        })
    }
}

impl AravisCamera {
    /// The aravis camera (a handle to the same connection: the lens of
    /// [`crate::lens::genicam`] shares it).
    pub fn arv_camera(&self) -> ArvCamera {
        self.camera.clone()
    }

    /// The exposure time the camera reports, us.
    pub fn exposure_us(&self) -> Result<f64> {
        self.camera.exposure_time().map_err(glib_err(&self.name(), ErrorKind::Protocol))
    }
}

impl Drop for AravisCamera {
    fn drop(&mut self) {
        if self.acquiring {
            let _ = self.camera.stop_acquisition();
        }
    }
}

/// Opens the aravis camera `id` alone (no stream; one opening at a time, `OPENING`):
/// for a GenICam lens on a camera that grabs no frames here.
pub fn open_arv_camera(id: &str) -> Result<ArvCamera> {
    let _one_at_a_time = OPENING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    ArvCamera::new(Some(id)).map_err(glib_err(&format!("camera aravis:{id}"), ErrorKind::LinkLost))
}

/// The ids of the GenICam cameras aravis finds on the GigE Vision and USB3 Vision
/// interfaces.
pub fn list() -> Result<Vec<String>> {
    let mut ids = vec![];
    for iface in [aravis::GvInterface::instance(), aravis::UvInterface::instance()].into_iter().flatten() {
        iface.update_device_list();
        ids.extend((0..iface.n_devices()).filter_map(|i| iface.device_id(i)).map(|s| s.to_string()));
    }
    Ok(ids)
}
