//! The V4L2 camera's formats and their conversion to mono pixels, as pure functions (the
//! device itself is `camera::v4l2`, behind the cargo feature `v4l2`).
//!
//! Negotiation: of the pixel formats the device offers, the first of [`PREFERENCE`] is
//! taken: `Y16 ` (16-bit grey, little-endian: a 10- or 12-bit sensor's samples as the
//! driver scales them), `GREY` (8-bit grey), then `YUYV` (4:2:2 colour). Any other offer is
//! refused (set a mono or YUYV format with the device's own tool).
//!
//! `YUYV` is made grey as a colour file is ([`super`]'s module docs): each pixel's Y'CbCr is
//! turned into R'G'B' by ITU-R BT.601 in its limited range, V4L2's default for YUYV,
//!
//! ```text
//! R = 1.164 (Y - 16) + 1.596 (Cr - 128)
//! G = 1.164 (Y - 16) - 0.392 (Cb - 128) - 0.813 (Cr - 128)
//! B = 1.164 (Y - 16) + 2.017 (Cb - 128)
//! ```
//!
//! (each clamped to 0..=255), then weighed by BT.709, 0.2126 R + 0.7152 G + 0.0722 B,
//! rounded. Two horizontal neighbours share their Cb and Cr (`Y0 Cb Y1 Cr`).

use image::GrayImage;

use super::{Gray16Image, Pixels};

/// A pixel layout the V4L2 camera reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelLayout {
    /// `Y16 `: 16-bit grey, little-endian.
    Y16,
    /// `GREY`: 8-bit grey.
    Grey,
    /// `YUYV`: 4:2:2 Y'CbCr, 2 bytes a pixel.
    Yuyv,
}

/// The layouts in the order they are preferred.
pub const PREFERENCE: [PixelLayout; 3] = [PixelLayout::Y16, PixelLayout::Grey, PixelLayout::Yuyv];

impl PixelLayout {
    /// The layout's V4L2 four-character code.
    pub fn fourcc(self) -> [u8; 4] {
        match self {
            PixelLayout::Y16 => *b"Y16 ",
            PixelLayout::Grey => *b"GREY",
            PixelLayout::Yuyv => *b"YUYV",
        }
    }

    /// Bytes of one pixel.
    pub fn bytes_per_pixel(self) -> usize {
        match self {
            PixelLayout::Grey => 1,
            PixelLayout::Y16 | PixelLayout::Yuyv => 2,
        }
    }
}

/// The preferred layout among the device's `offered` four-character codes, or a one-line
/// refusal listing them.
pub fn choose_layout(offered: &[[u8; 4]]) -> Result<PixelLayout, String> {
    PREFERENCE.into_iter().find(|l| offered.contains(&l.fourcc())).ok_or_else(|| {
        let names: Vec<String> = offered.iter().map(|c| String::from_utf8_lossy(c).trim_end().to_owned()).collect();
        format!(
            "offers no format etlcal reads (it reads Y16, GREY or YUYV; it offers {}): set one with v4l2-ctl --set-fmt-video",
            if names.is_empty() { "none".to_owned() } else { names.join(", ") }
        )
    })
}

/// The mono pixels of a `width` x `height` frame in `layout`, rows `stride` bytes apart.
///
/// Errors: a buffer shorter than the frame, or a stride shorter than a row (one line).
pub fn frame_pixels(
    layout: PixelLayout,
    data: &[u8],
    [width, height]: [u32; 2],
    stride: usize,
) -> Result<Pixels, String> {
    let (w, h) = (width as usize, height as usize);
    let row = w * layout.bytes_per_pixel();
    if stride < row {
        return Err(format!("a row of {w} px needs {row} bytes; the driver says {stride}"));
    }
    let needed = if h == 0 { 0 } else { (h - 1) * stride + row };
    if data.len() < needed {
        return Err(format!("a {width} x {height} frame came with {} bytes, not {needed}", data.len()));
    }
    let rows = (0..h).map(|y| &data[y * stride..y * stride + row]);
    let short = || format!("a {width} x {height} frame does not fit its size");
    Ok(match layout {
        PixelLayout::Grey => {
            Pixels::Mono8(GrayImage::from_raw(width, height, rows.flatten().copied().collect()).ok_or_else(short)?)
        }
        PixelLayout::Y16 => {
            let raw = rows.flat_map(|r| r.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]]))).collect();
            Pixels::Mono16(Gray16Image::from_raw(width, height, raw).ok_or_else(short)?)
        }
        PixelLayout::Yuyv => {
            let raw = rows.flat_map(yuyv_row_to_grey).collect();
            Pixels::Mono8(GrayImage::from_raw(width, height, raw).ok_or_else(short)?)
        }
    })
}

/// One YUYV row made grey (module docs); an odd last pixel has its Y byte and shares the
/// pair's Cb, Cr when present, else is taken as neutral (Cb = Cr = 128).
fn yuyv_row_to_grey(row: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(row.len() / 2);
    for quad in row.chunks(4) {
        let (cb, cr) = (quad.get(1).copied().unwrap_or(128), quad.get(3).copied().unwrap_or(128));
        out.push(ycbcr_to_grey(quad[0], cb, cr));
        if let Some(&y1) = quad.get(2) {
            out.push(ycbcr_to_grey(y1, cb, cr));
        }
    }
    out
}

/// One BT.601 limited-range Y'CbCr sample as BT.709-weighted grey (module docs).
pub fn ycbcr_to_grey(y: u8, cb: u8, cr: u8) -> u8 {
    let (y, cb, cr) = (1.164 * (f64::from(y) - 16.0), f64::from(cb) - 128.0, f64::from(cr) - 128.0);
    let r = (y + 1.596 * cr).clamp(0.0, 255.0);
    let g = (y - 0.392 * cb - 0.813 * cr).clamp(0.0, 255.0);
    let b = (y + 2.017 * cb).clamp(0.0, 255.0);
    (0.2126 * r + 0.7152 * g + 0.0722 * b).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_preferred_format_is_chosen_and_others_are_refused_naming_the_offer() {
        assert_eq!(choose_layout(&[*b"YUYV", *b"GREY"]), Ok(PixelLayout::Grey));
        assert_eq!(choose_layout(&[*b"YUYV", *b"Y16 ", *b"GREY"]), Ok(PixelLayout::Y16));
        assert_eq!(choose_layout(&[*b"MJPG", *b"YUYV"]), Ok(PixelLayout::Yuyv));
        let e = choose_layout(&[*b"MJPG", *b"H264"]).unwrap_err();
        assert!(e.contains("it offers MJPG, H264") && !e.contains('\n'), "{e}");
    }

    /// BT.601 limited-range codes of known colours (ITU-R BT.601's own table: white
    /// 235/128/128, black 16/128/128, red 81/90/240, green 145/54/34, blue 41/240/110)
    /// come out as the BT.709 luma of their R'G'B'.
    #[test]
    fn yuyv_colours_become_their_bt709_luma() {
        assert_eq!(ycbcr_to_grey(235, 128, 128), 255);
        assert_eq!(ycbcr_to_grey(16, 128, 128), 0);
        let cases =
            [((81, 90, 240), 0.2126 * 255.0), ((145, 54, 34), 0.7152 * 255.0), ((41, 240, 110), 0.0722 * 255.0)];
        for ((y, cb, cr), want) in cases {
            let got = f64::from(ycbcr_to_grey(y, cb, cr));
            assert!((got - want).abs() <= 1.5, "Y'CbCr ({y}, {cb}, {cr}): {got}, want {want:.1}");
        }
    }

    #[test]
    fn frames_of_each_layout_read_with_their_stride() {
        // 3 x 2 GREY with 4 bytes a row (one of padding).
        let Pixels::Mono8(g) = frame_pixels(PixelLayout::Grey, &[1, 2, 3, 0, 4, 5, 6, 0], [3, 2], 4).unwrap() else {
            panic!()
        };
        assert_eq!(g.as_raw(), &[1, 2, 3, 4, 5, 6]);
        // 2 x 1 Y16, little-endian.
        let Pixels::Mono16(g) = frame_pixels(PixelLayout::Y16, &[0x34, 0x12, 0xff, 0x0f], [2, 1], 4).unwrap() else {
            panic!()
        };
        assert_eq!(g.as_raw(), &[0x1234, 0x0fff]);
        // 2 x 1 YUYV: white and black sharing neutral chroma.
        let Pixels::Mono8(g) = frame_pixels(PixelLayout::Yuyv, &[235, 128, 16, 128], [2, 1], 4).unwrap() else {
            panic!()
        };
        assert_eq!(g.as_raw(), &[255, 0]);
        let e = frame_pixels(PixelLayout::Grey, &[1, 2, 3], [3, 2], 3).unwrap_err();
        assert_eq!(e, "a 3 x 2 frame came with 3 bytes, not 6");
        assert!(frame_pixels(PixelLayout::Y16, &[0; 8], [3, 1], 4).unwrap_err().contains("needs 6 bytes"));
    }
}
