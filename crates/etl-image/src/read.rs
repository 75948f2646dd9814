//! Reading an image file: one decoder for detection and sharpness.

use std::path::Path;

use image::{DynamicImage, ImageFormat};

use crate::{Error, Result};

pub use etl_formats::observations::MAX_IMAGE_PIXELS;

/// The most pixels one byte of a Huffman-coded JPEG can stand for: 512. Every 8 x 8 block
/// of the full-resolution component is coded in the first scan with at least one bit (its
/// DC difference's Huffman code, 1 bit at the shortest), so a file of `n` bytes holds at
/// most 8 n blocks, 512 n pixels. (Arithmetic-coded JPEG, which could go further, is not
/// read by the decoder at all.) A camera's JPEG is far below it: a uniform grey image with
/// the standard tables takes 6 bits a block, about 85 px a byte.
pub const MAX_JPEG_PIXELS_PER_BYTE: u64 = 512;

/// The most pixels one byte of a PNG can stand for: 8256. Deflate expands a byte to at
/// most 1032 (a 258-byte match coded in 2 bits) and a pixel takes at least one bit of the
/// decompressed rows (1-bit grey), so `n` bytes hold at most 1032 x 8 n pixels.
pub const MAX_PNG_PIXELS_PER_BYTE: u64 = 8 * 1032;

/// Decodes the image file at `path` (PNG, JPEG, TIFF; the format from the content, not
/// the extension). Refused before anything is decoded or allocated for the pixels: a path
/// that is not a regular file (a FIFO, a device), an image whose header declares more than
/// [`MAX_IMAGE_PIXELS`] pixels, and a JPEG or PNG whose header declares more pixels than
/// its file's size can code ([`MAX_JPEG_PIXELS_PER_BYTE`], [`MAX_PNG_PIXELS_PER_BYTE`]):
/// a truncated or forged file that the decoder would otherwise fill in and the detector
/// search at full size. (TIFF has no such bound: its strips may share their bytes.) A file
/// that cannot be opened is [`Error::Io`]; one that cannot be decoded is [`Error::Image`].
pub fn read_image(path: &Path) -> Result<DynamicImage> {
    let file_bytes = etl_formats::output::check_input(path)?.map(|m| m.len());
    let open = || {
        image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|source| Error::Io { path: path.to_owned(), source })
    };
    let reader = open()?;
    let format = reader.format();
    let (w, h) =
        reader.into_dimensions().map_err(|e| Error::Image { path: path.to_owned(), message: e.to_string() })?;
    check_pixels(path, w, h)?;
    if let (Some(format), Some(bytes)) = (format, file_bytes) {
        check_declared_size(path, format, w, h, bytes)?;
    }
    open()?.decode().map_err(|e| Error::Image { path: path.to_owned(), message: e.to_string() })
}

/// Refuses an image of `w` x `h` px above [`MAX_IMAGE_PIXELS`].
pub(crate) fn check_pixels(path: &Path, w: u32, h: u32) -> Result<()> {
    if u64::from(w) * u64::from(h) > MAX_IMAGE_PIXELS {
        return Err(Error::Image {
            path: path.to_owned(),
            message: format!(
                "{w} x {h} px is more than the limit of {MAX_IMAGE_PIXELS} pixels: refused before decoding"
            ),
        });
    }
    Ok(())
}

/// Refuses a `format` file of `file_bytes` bytes whose header declares `w` x `h` px, more
/// than that many bytes can code (JPEG and PNG; see [`read_image`]).
fn check_declared_size(path: &Path, format: ImageFormat, w: u32, h: u32, file_bytes: u64) -> Result<()> {
    let (name, per_byte) = match format {
        ImageFormat::Jpeg => ("JPEG", MAX_JPEG_PIXELS_PER_BYTE),
        ImageFormat::Png => ("PNG", MAX_PNG_PIXELS_PER_BYTE),
        _ => return Ok(()),
    };
    let pixels = u64::from(w) * u64::from(h);
    if pixels > file_bytes.saturating_mul(per_byte) {
        return Err(Error::Image {
            path: path.to_owned(),
            message: format!(
                "declares {w} x {h} px, more than its {file_bytes} bytes can code as {name} (at most {per_byte} px a \
                 byte): a truncated or forged file, refused before decoding"
            ),
        });
    }
    Ok(())
}
