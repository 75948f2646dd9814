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

/// The most pixels one byte of a TIFF's strips or tiles can stand for: 32768. LZW (the
/// most expanding of the codings TIFF allows and the decoder reads: none, PackBits, LZW,
/// deflate) writes codes of at least 9 bits, each for at most 4096 bytes, so under 4096
/// bytes a byte of code; a pixel takes at least one bit (1-bit grey). The strips are bounded
/// by the file only when they do not overlap: see [`read_image`].
pub const MAX_TIFF_PIXELS_PER_BYTE: u64 = 8 * 4096;

/// Decodes the image file at `path` (PNG, JPEG, TIFF; the format from the content, not
/// the extension). Refused before anything is decoded or allocated for the pixels: a path
/// that is not a regular file (a FIFO, a device), an image whose header declares more than
/// [`MAX_IMAGE_PIXELS`] pixels, and a JPEG or PNG whose header declares more pixels than
/// its file's size can code ([`MAX_JPEG_PIXELS_PER_BYTE`], [`MAX_PNG_PIXELS_PER_BYTE`]):
/// a truncated or forged file that the decoder would otherwise fill in and the detector
/// search at full size. A TIFF's strips (or tiles) must lie in its file without sharing
/// bytes, and together code no more than [`MAX_TIFF_PIXELS_PER_BYTE`] px a byte: strips
/// that all point at the same bytes would let a file of a few kB declare 256 Mpx. A file
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
    // (name, bound, the bytes that code the pixels, what they are called)
    let (name, per_byte, coded_bytes, what) = match format {
        ImageFormat::Jpeg => ("JPEG", MAX_JPEG_PIXELS_PER_BYTE, file_bytes, "bytes"),
        ImageFormat::Png => ("PNG", MAX_PNG_PIXELS_PER_BYTE, file_bytes, "bytes"),
        ImageFormat::Tiff => ("TIFF", MAX_TIFF_PIXELS_PER_BYTE, tiff_coded_bytes(path, file_bytes)?, "bytes of strips"),
        _ => return Ok(()),
    };
    let pixels = u64::from(w) * u64::from(h);
    if pixels > coded_bytes.saturating_mul(per_byte) {
        return Err(Error::Image {
            path: path.to_owned(),
            message: format!(
                "declares {w} x {h} px, more than its {coded_bytes} {what} can code as {name} (at most \
                 {per_byte} px a byte): a truncated or forged file, refused before decoding"
            ),
        });
    }
    Ok(())
}

/// The bytes of the first image's strips (or tiles) of the TIFF at `path`, a file of
/// `file_bytes` bytes. Refused: strips that overlap one another or run past the file's end
/// (a file whose strips share bytes codes more pixels than its size says), and tags that
/// do not parse (the decoder would fail on them anyway).
fn tiff_coded_bytes(path: &Path, file_bytes: u64) -> Result<u64> {
    use tiff::tags::Tag;
    let refuse = |message: String| Error::Image { path: path.to_owned(), message };
    let file = std::fs::File::open(path).map_err(|source| Error::Io { path: path.to_owned(), source })?;
    let mut decoder = tiff::decoder::Decoder::new(std::io::BufReader::new(file))
        .map_err(|e| refuse(format!("not a TIFF the decoder reads: {e}")))?;
    let mut ranges = Vec::new();
    for (offsets, counts) in [(Tag::StripOffsets, Tag::StripByteCounts), (Tag::TileOffsets, Tag::TileByteCounts)] {
        let read = |d: &mut tiff::decoder::Decoder<_>, tag| {
            d.find_tag_unsigned_vec::<u64>(tag).map_err(|e| refuse(format!("its tag {tag:?} does not parse: {e}")))
        };
        let (Some(o), Some(c)) = (read(&mut decoder, offsets)?, read(&mut decoder, counts)?) else { continue };
        if o.len() != c.len() {
            return Err(refuse(format!("{} strip offsets but {} byte counts", o.len(), c.len())));
        }
        ranges.extend(o.into_iter().zip(c));
    }
    ranges.sort_unstable();
    let mut end = 0u64;
    for &(offset, count) in &ranges {
        if count == 0 {
            continue;
        }
        let stop = offset.saturating_add(count);
        if offset < end || stop > file_bytes {
            return Err(refuse(format!(
                "a strip of bytes {offset}..{stop} overlaps another or runs past the file's {file_bytes} bytes: a \
                 forged file, refused before decoding"
            )));
        }
        end = stop.max(end);
    }
    Ok(ranges.iter().map(|r| r.1).sum())
}
