//! The [`Camera`] trait and its backends: [`files`] (a folder replayed in order), [`sim`]
//! (the synthetic camera on the virtual lens and the simulated stage), and, behind cargo
//! features, aravis (GenICam) and V4L2 (`v4l2`, Linux; its formats in [`v4l2_format`]).
//!
//! Frames are mono, 8 or 16 bits ([`Pixels`]). A colour frame is converted to grey with
//! the image crate's luma weights, those of ITU-R BT.709 (0.2126 R + 0.7152 G + 0.0722 B),
//! as `etlcal detect` reads a colour file.

#[cfg(feature = "aravis")]
pub mod aravis;
pub mod files;
pub mod sim;
#[cfg(all(feature = "v4l2", target_os = "linux"))]
pub mod v4l2;
pub mod v4l2_format;

use image::{DynamicImage, GrayImage, ImageBuffer, Luma};

use crate::error::{Error, ErrorKind, Result};

/// A 16-bit grey image.
pub type Gray16Image = ImageBuffer<Luma<u16>, Vec<u16>>;

/// The pixels of a mono frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Pixels {
    /// 8-bit grey.
    Mono8(GrayImage),
    /// 16-bit grey (a 10-, 12- or 14-bit sensor's samples as they come).
    Mono16(Gray16Image),
}

impl Pixels {
    /// Grey pixels of any decoded image: 16-bit images stay 16-bit, everything else is
    /// 8-bit grey (colour by the BT.709 weights of the module docs).
    pub fn from_dynamic(image: DynamicImage) -> Pixels {
        match image {
            DynamicImage::ImageLuma16(g) => Pixels::Mono16(g),
            DynamicImage::ImageLumaA16(_) | DynamicImage::ImageRgb16(_) | DynamicImage::ImageRgba16(_) => {
                Pixels::Mono16(image.to_luma16())
            }
            DynamicImage::ImageLuma8(g) => Pixels::Mono8(g),
            other => Pixels::Mono8(other.to_luma8()),
        }
    }

    /// Width and height, px.
    pub fn size(&self) -> [u32; 2] {
        match self {
            Pixels::Mono8(g) => [g.width(), g.height()],
            Pixels::Mono16(g) => [g.width(), g.height()],
        }
    }

    /// The image as the image crate's (for detection and encoding).
    pub fn to_dynamic(&self) -> DynamicImage {
        match self {
            Pixels::Mono8(g) => DynamicImage::ImageLuma8(g.clone()),
            Pixels::Mono16(g) => DynamicImage::ImageLuma16(g.clone()),
        }
    }

    /// The image encoded as PNG (8 or 16 bits as it is).
    pub fn to_png(&self) -> Result<Vec<u8>> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        self.to_dynamic().write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| {
            Error::Formats(etl_formats::Error::invalid("image", format!("cannot encode the frame as PNG: {e}")))
        })?;
        Ok(bytes.into_inner())
    }
}

/// A grabbed frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// The pixels.
    pub pixels: Pixels,
    /// When it was exposed, ns, on the camera's own clock (monotonic within a session;
    /// each backend says what its clock is).
    pub timestamp_ns: u64,
}

/// What a camera says about itself.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraInfo {
    /// The spec it was opened with, e.g. `aravis:Fake_1`.
    pub spec: String,
    /// Vendor and model as the device reports them.
    pub model: String,
    /// Image width and height, px.
    pub image_size: [u32; 2],
}

/// A camera: grab mono frames, set exposure and gain.
pub trait Camera {
    /// The device's name in errors: `camera SPEC`.
    fn name(&self) -> String;

    /// Grabs one frame.
    fn grab(&mut self) -> Result<Frame>;

    /// Sets the exposure time, us.
    fn set_exposure_us(&mut self, exposure_us: f64) -> Result<()>;

    /// Sets the analogue gain, dB.
    fn set_gain_db(&mut self, gain_db: f64) -> Result<()>;

    /// Vendor, model and image size.
    fn info(&mut self) -> Result<CameraInfo>;
}

impl<C: Camera + ?Sized> Camera for Box<C> {
    fn name(&self) -> String {
        (**self).name()
    }
    fn grab(&mut self) -> Result<Frame> {
        (**self).grab()
    }
    fn set_exposure_us(&mut self, exposure_us: f64) -> Result<()> {
        (**self).set_exposure_us(exposure_us)
    }
    fn set_gain_db(&mut self, gain_db: f64) -> Result<()> {
        (**self).set_gain_db(gain_db)
    }
    fn info(&mut self) -> Result<CameraInfo> {
        (**self).info()
    }
}

/// The mean of `frames`, rounded to the nearest sample (all of one size and depth).
///
/// Errors: no frames, or frames of different sizes or depths (named by `camera`).
pub fn average(frames: &[Frame], camera: &str) -> Result<Pixels> {
    let first = frames.first().ok_or_else(|| Error::device(camera, ErrorKind::Other, "no frame to average"))?;
    let size = first.pixels.size();
    let n = frames.len() as f64;
    let mut sum = vec![0.0f64; size[0] as usize * size[1] as usize];
    for f in frames {
        if f.pixels.size() != size || std::mem::discriminant(&f.pixels) != std::mem::discriminant(&first.pixels) {
            let message =
                format!("frames changed size or depth during a view ({size:?} px, then {:?} px)", f.pixels.size());
            return Err(Error::device(camera, ErrorKind::Protocol, message));
        }
        match &f.pixels {
            Pixels::Mono8(g) => sum.iter_mut().zip(g.as_raw()).for_each(|(s, &v)| *s += f64::from(v)),
            Pixels::Mono16(g) => sum.iter_mut().zip(g.as_raw()).for_each(|(s, &v)| *s += f64::from(v)),
        }
    }
    let [w, h] = size;
    Ok(match first.pixels {
        Pixels::Mono8(_) => {
            let raw = sum.iter().map(|s| (s / n).round().clamp(0.0, 255.0) as u8).collect();
            Pixels::Mono8(GrayImage::from_raw(w, h, raw).unwrap_or_default())
        }
        Pixels::Mono16(_) => {
            let raw = sum.iter().map(|s| (s / n).round().clamp(0.0, 65535.0) as u16).collect();
            Pixels::Mono16(Gray16Image::from_raw(w, h, raw).unwrap_or_default())
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_average_to_the_rounded_mean() {
        let f = |v: u8| Frame { pixels: Pixels::Mono8(GrayImage::from_pixel(2, 1, Luma([v]))), timestamp_ns: 0 };
        let Pixels::Mono8(g) = average(&[f(10), f(11), f(13)], "camera t").unwrap() else { panic!() };
        assert_eq!(g.get_pixel(1, 0).0, [11]);
        let big = Frame { pixels: Pixels::Mono8(GrayImage::new(3, 1)), timestamp_ns: 0 };
        assert!(average(&[f(1), big], "camera t").unwrap_err().to_string().starts_with("camera t: "));
    }
}
