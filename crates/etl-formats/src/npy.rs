//! NumPy's `.npy` format (version 1.0) for a 2-D float32 array: what `numpy.load` reads,
//! e.g. rectification maps for `cv2.remap`.
//!
//! Layout: the magic `\x93NUMPY`, version 1.0, a little-endian u16 header length, the
//! header (a Python dict literal `{'descr': '<f4', 'fortran_order': False, 'shape': (h, w), }`
//! padded with spaces and a final newline so that the data starts at a multiple of 64
//! bytes), then the row-major little-endian data.

use crate::{Error, Result};

/// The bytes of a `.npy` file holding `data` as a (rows, cols) float32 array, row-major.
/// Errors: `data` not of `rows * cols` values.
pub fn npy_f32(rows: usize, cols: usize, data: &[f32]) -> Result<Vec<u8>> {
    if data.len() != rows * cols {
        return Err(Error::invalid("data", format!("{} values for a {rows} x {cols} array", data.len())));
    }
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    // 10 bytes of magic, version and length before the header; the header ends in '\n'.
    let total = (10 + header.len() + 1).div_ceil(64) * 64;
    header.push_str(&" ".repeat(total - 10 - header.len() - 1));
    header.push('\n');
    let mut out = Vec::with_capacity(total + 4 * data.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_header_is_aligned_and_the_data_follow() {
        let b = npy_f32(2, 3, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.5]).unwrap();
        assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
        let n = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + n) % 64, 0);
        let header = std::str::from_utf8(&b[10..10 + n]).unwrap();
        assert!(
            header.starts_with("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }") && header.ends_with('\n')
        );
        assert_eq!(b.len(), 10 + n + 24);
        assert_eq!(f32::from_le_bytes(b[10 + n + 20..].try_into().unwrap()), 6.5);
        assert!(npy_f32(2, 2, &[1.0]).is_err());
    }
}
