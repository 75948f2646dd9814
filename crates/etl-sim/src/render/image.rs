//! The rendered image: 8- or 16-bit grayscale, row-major, and its PNG encoding.

use std::path::Path;

use image::{ImageBuffer, Luma};

use etl_formats::write_atomic;
use etl_formats::{Error, Result};

/// Bits per pixel of a rendered image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum BitDepth {
    /// 0..=255.
    #[default]
    Eight,
    /// 0..=65535 (the 8-bit scale times 257, so 255 maps to 65535).
    Sixteen,
}

impl BitDepth {
    /// The largest grey level.
    pub fn max_value(self) -> u16 {
        match self {
            BitDepth::Eight => 255,
            BitDepth::Sixteen => 65535,
        }
    }

    /// Grey levels of this depth per grey level of the 8-bit scale (1 or 257).
    pub fn scale_from_8bit(self) -> f64 {
        match self {
            BitDepth::Eight => 1.0,
            BitDepth::Sixteen => 257.0,
        }
    }
}

/// A grayscale image: `data[y * width + x]` is the grey level of pixel (x, y), whose centre
/// is at pixel coordinates (x, y) (it covers [x - 0.5, x + 0.5] x [y - 0.5, y + 0.5]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Range of the values.
    pub bit_depth: BitDepth,
    /// Grey levels, row by row (at most `bit_depth.max_value()`).
    pub data: Vec<u16>,
}

impl Image {
    /// Grey level of pixel (x, y); `None` outside the image.
    pub fn get(&self, x: u32, y: u32) -> Option<u16> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.data.get(y as usize * self.width as usize + x as usize).copied()
    }

    /// The image as an `image` crate buffer (`Luma8` or `Luma16`).
    pub fn to_dynamic(&self) -> image::DynamicImage {
        match self.bit_depth {
            BitDepth::Eight => {
                let bytes: Vec<u8> = self.data.iter().map(|&v| v.min(255) as u8).collect();
                match ImageBuffer::<Luma<u8>, Vec<u8>>::from_raw(self.width, self.height, bytes) {
                    Some(b) => image::DynamicImage::ImageLuma8(b),
                    None => image::DynamicImage::new_luma8(self.width, self.height),
                }
            }
            BitDepth::Sixteen => {
                match ImageBuffer::<Luma<u16>, Vec<u16>>::from_raw(self.width, self.height, self.data.clone()) {
                    Some(b) => image::DynamicImage::ImageLuma16(b),
                    None => image::DynamicImage::new_luma16(self.width, self.height),
                }
            }
        }
    }

    /// The PNG file of the image (8- or 16-bit grayscale as `bit_depth`).
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        self.to_dynamic()
            .write_to(&mut bytes, image::ImageFormat::Png)
            .map_err(|e| Error::invalid("image", format!("cannot encode PNG: {e}")))?;
        Ok(bytes.into_inner())
    }

    /// Writes the image as PNG to `path` atomically (the parent directory must exist).
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let bytes = self.encode_png().map_err(|e| Error::Image { path: path.to_owned(), message: e.to_string() })?;
        write_atomic(path, &bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_8_and_16_bit() {
        for (depth, data) in
            [(BitDepth::Eight, vec![0u16, 40, 210, 255, 7, 9]), (BitDepth::Sixteen, vec![0, 1, 65535, 300, 40000, 9])]
        {
            let img = Image { width: 3, height: 2, bit_depth: depth, data };
            let png = img.encode_png().unwrap();
            let back = image::load_from_memory(&png).unwrap();
            let values: Vec<u16> = match depth {
                BitDepth::Eight => back.to_luma8().into_raw().into_iter().map(u16::from).collect(),
                BitDepth::Sixteen => back.to_luma16().into_raw(),
            };
            assert_eq!(values, img.data);
            assert_eq!(img.get(2, 1), Some(img.data[5]));
            assert_eq!(img.get(3, 0), None);
        }
    }
}
