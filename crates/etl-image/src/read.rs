//! Reading an image file: one decoder for detection and sharpness.

use std::path::Path;

use image::DynamicImage;

use crate::{Error, Result};

/// Decodes the image file at `path` (PNG, JPEG, TIFF; the format from the content, not
/// the extension). A file that cannot be opened is [`Error::Io`]; one that cannot be
/// decoded is [`Error::Image`].
pub fn read_image(path: &Path) -> Result<DynamicImage> {
    image::ImageReader::open(path)
        .map_err(|source| Error::Io { path: path.to_owned(), source })?
        .with_guessed_format()
        .map_err(|source| Error::Io { path: path.to_owned(), source })?
        .decode()
        .map_err(|e| Error::Image { path: path.to_owned(), message: e.to_string() })
}
