//! Reading an image file: one decoder for detection and sharpness.

use std::path::Path;

use image::DynamicImage;

use crate::{Error, Result};

pub use etl_formats::observations::MAX_IMAGE_PIXELS;

/// Decodes the image file at `path` (PNG, JPEG, TIFF; the format from the content, not
/// the extension). A path that is not a regular file (a FIFO, a device) is refused before
/// it is opened, and an image of more than [`MAX_IMAGE_PIXELS`] pixels from its header,
/// before it is decoded (nothing is allocated for it). A file that cannot be opened is
/// [`Error::Io`]; one that cannot be decoded is [`Error::Image`].
pub fn read_image(path: &Path) -> Result<DynamicImage> {
    etl_formats::output::check_input(path)?;
    let open = || {
        image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|source| Error::Io { path: path.to_owned(), source })
    };
    let (w, h) =
        open()?.into_dimensions().map_err(|e| Error::Image { path: path.to_owned(), message: e.to_string() })?;
    check_pixels(path, w, h)?;
    open()?.decode().map_err(|e| Error::Image { path: path.to_owned(), message: e.to_string() })
}

/// Refuses an image of `w` x `h` px above [`MAX_IMAGE_PIXELS`].
pub fn check_pixels(path: &Path, w: u32, h: u32) -> Result<()> {
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
