//! The one image reader refuses, before decoding, what would cost far more than its file:
//! a header beyond the pixel limit, and a JPEG or PNG whose header declares more pixels
//! than its bytes can code (docs/RELIABILITY.md, "Inputs and limits").

use std::io::Cursor;
use std::path::Path;

use etl_image::{read_image, Error, MAX_JPEG_PIXELS_PER_BYTE, MAX_PNG_PIXELS_PER_BYTE, MAX_TIFF_PIXELS_PER_BYTE};
use image::{GrayImage, ImageFormat, Luma};

/// `img` encoded as `format`.
fn encode(img: &GrayImage, format: ImageFormat) -> Vec<u8> {
    let mut bytes = Cursor::new(Vec::new());
    img.write_to(&mut bytes, format).unwrap();
    bytes.into_inner()
}

/// An 8 x 8 grey JPEG whose frame header (SOF0) declares `w` x `h` px instead.
fn jpeg_declaring(w: u16, h: u16) -> Vec<u8> {
    let mut b = encode(&GrayImage::from_pixel(8, 8, Luma([128])), ImageFormat::Jpeg);
    let sof = b.windows(2).position(|m| m == [0xFF, 0xC0]).expect("a baseline JPEG has SOF0");
    // FFC0, length (2), precision (1), height (2), width (2).
    b[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
    b[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
    b
}

/// A 1 x 1 grey PNG whose header (IHDR, CRC mended) declares `w` x `h` px instead.
fn png_declaring(w: u32, h: u32) -> Vec<u8> {
    let mut b = encode(&GrayImage::from_pixel(1, 1, Luma([128])), ImageFormat::Png);
    // Signature (8), IHDR length (4), "IHDR" (4), width (4), height (4), 5 bytes, CRC.
    assert_eq!(&b[12..16], b"IHDR");
    b[16..20].copy_from_slice(&w.to_be_bytes());
    b[20..24].copy_from_slice(&h.to_be_bytes());
    let crc = crc32fast::hash(&b[12..29]);
    b[29..33].copy_from_slice(&crc.to_be_bytes());
    b
}

/// An uncompressed 8-bit grey little-endian TIFF of `w` x `h` px, one row a strip, whose
/// strips all point at the same `w` bytes when `shared` (else each has its own row).
fn tiff_strips(w: u32, h: u32, shared: bool) -> Vec<u8> {
    let rows = if shared { 1 } else { h };
    let data: Vec<u8> = (0..w * rows).map(|x| (x * 7) as u8).collect();
    let offsets: Vec<u32> = (0..h).map(|r| 8 + if shared { 0 } else { r * w }).collect();
    let offs_at = 8 + data.len() as u32;
    let cnts_at = offs_at + 4 * h;
    let ifd_at = cnts_at + 4 * h;
    let mut b = b"II*\0".to_vec();
    b.extend(ifd_at.to_le_bytes());
    b.extend(&data);
    offsets.iter().for_each(|o| b.extend(o.to_le_bytes()));
    (0..h).for_each(|_| b.extend(w.to_le_bytes()));
    // (tag, type: 3 short / 4 long, count, value or offset)
    let entries = [
        (256u16, 4u16, 1u32, w),
        (257, 4, 1, h),
        (258, 3, 1, 8),
        (259, 3, 1, 1),
        (262, 3, 1, 1),
        (273, 4, h, offs_at),
        (278, 4, 1, 1),
        (279, 4, h, cnts_at),
    ];
    b.extend((entries.len() as u16).to_le_bytes());
    for (tag, ty, n, v) in entries {
        b.extend(tag.to_le_bytes());
        b.extend(ty.to_le_bytes());
        b.extend(n.to_le_bytes());
        b.extend(v.to_le_bytes());
    }
    b.extend(0u32.to_le_bytes());
    b
}

/// The message of reading `bytes` as a file, which must be an image error naming it.
fn refused(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    match read_image(&path) {
        Err(Error::Image { path: p, message }) => {
            assert_eq!(p, path);
            let line = Error::Image { path: p, message: message.clone() }.to_string();
            assert_eq!(line.lines().count(), 1, "{line}");
            message
        }
        other => panic!("{name}: {other:?}"),
    }
}

/// The fuzzer's slow input, rebuilt: a few hundred bytes of JPEG declaring 2471 x 65280
/// px (161 Mpx) were decoded and searched in full (3 s and 636 MB in a release build,
/// 13 s under the fuzzer). Its header alone now refuses it.
#[test]
fn a_tiny_jpeg_declaring_161_megapixels_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = jpeg_declaring(2471, 65280);
    assert!(bytes.len() < 1000, "{}", bytes.len());
    let m = refused(dir.path(), "huge.jpg", &bytes);
    let want =
        format!("declares 2471 x 65280 px, more than its {} bytes can code as JPEG (at most 512 px", bytes.len());
    assert!(m.starts_with(&want) && m.contains("refused before decoding"), "{m}");
    // Just within the bound it is decoded (and the decoder fills what the file lacks).
    let side = ((bytes.len() as u64 * MAX_JPEG_PIXELS_PER_BYTE) as f64).sqrt() as u16;
    let path = dir.path().join("within.jpg");
    std::fs::write(&path, jpeg_declaring(side, side)).unwrap();
    let img = read_image(&path).unwrap();
    assert_eq!((img.width(), img.height()), (u32::from(side), u32::from(side)));
}

#[test]
fn a_tiny_png_declaring_256_megapixels_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = png_declaring(16384, 16384);
    let m = refused(dir.path(), "huge.png", &bytes);
    assert!(m.starts_with("declares 16384 x 16384 px, more than its") && m.contains("as PNG (at most 8256 px"), "{m}");
}

/// The hostile-user battery's slow input: 16000 strips of one row all pointing at the same
/// 16000 bytes declare 256 Mpx in 144 kB, which was decoded and searched for more than
/// 20 s. The same image with its own bytes per strip is read.
#[test]
fn a_tiff_whose_strips_share_their_bytes_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let m = refused(dir.path(), "shared.tif", &tiff_strips(16000, 16000, true));
    assert!(
        m.starts_with("a strip of bytes 8..16008 overlaps another") && m.contains("refused before decoding"),
        "{m}"
    );
    let small = tiff_strips(300, 200, true);
    let m = refused(dir.path(), "small-shared.tif", &small);
    assert!(m.contains("overlaps another"), "{m}");
    let path = dir.path().join("own.tif");
    std::fs::write(&path, tiff_strips(300, 200, false)).unwrap();
    let img = read_image(&path).unwrap().to_luma8();
    assert_eq!(img.dimensions(), (300, 200));
    assert_eq!(img.get_pixel(5, 3).0[0], ((3 * 300 + 5) * 7) as u8);
    // A strip past the file's end: cut the last row's bytes off the data.
    let mut cut = tiff_strips(300, 200, false);
    let at = cut.len() - 4 * 8 - 12 * 8 - 2 - 4 * 200; // the last byte count
    cut[at..at + 4].copy_from_slice(&(10_000_000u32).to_le_bytes());
    let m = refused(dir.path(), "past-end.tif", &cut);
    assert!(m.contains("runs past the file's"), "{m}");
}

#[test]
fn a_header_beyond_the_pixel_limit_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let m = refused(dir.path(), "limit.png", &png_declaring(20000, 20000));
    assert_eq!(m, "20000 x 20000 px is more than the limit of 268435456 pixels: refused before decoding");
    let m = refused(dir.path(), "limit.jpg", &jpeg_declaring(65000, 65000));
    assert_eq!(m, "65000 x 65000 px is more than the limit of 268435456 pixels: refused before decoding");
}

/// The most compressible images the encoders write (one grey level, the largest blocks of
/// nothing) stay well inside the bounds: the bounds refuse forged headers, not images.
#[test]
fn the_most_compressible_real_images_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let flat = GrayImage::from_pixel(2048, 1536, Luma([77]));
    for (format, name, per_byte) in [
        (ImageFormat::Jpeg, "flat.jpg", MAX_JPEG_PIXELS_PER_BYTE),
        (ImageFormat::Png, "flat.png", MAX_PNG_PIXELS_PER_BYTE),
        (ImageFormat::Tiff, "flat.tif", MAX_TIFF_PIXELS_PER_BYTE),
    ] {
        let bytes = encode(&flat, format);
        let ratio = (2048 * 1536) as f64 / bytes.len() as f64;
        assert!(ratio < per_byte as f64 / 2.0, "{name}: {ratio:.0} px a byte");
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        let img = read_image(&path).unwrap().to_luma8();
        assert_eq!(img.dimensions(), (2048, 1536), "{name}");
        assert!(img.pixels().all(|p| p.0[0].abs_diff(77) <= 1), "{name}");
    }
}
