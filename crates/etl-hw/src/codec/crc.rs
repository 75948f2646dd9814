//! CRC-16/ARC, which Optotune calls "CRC-16-IBM" (facts sheet section 3): reflected
//! polynomial 0xA001, init 0, no final XOR, appended low byte first.

/// CRC-16/ARC of `data` (check value of `b"123456789"` is 0xBB3D).
///
/// ```
/// assert_eq!(etl_hw::codec::crc16_arc(b"123456789"), 0xBB3D);
/// ```
pub fn crc16_arc(data: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    for &b in data {
        crc ^= u16::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xA001 } else { crc >> 1 };
        }
    }
    crc
}

/// Appends the CRC of `frame` to it, low byte first.
pub fn append_crc(frame: &mut Vec<u8>) {
    let c = crc16_arc(frame);
    frame.extend_from_slice(&c.to_le_bytes());
}

/// Whether the last two bytes of `frame` are the CRC of the bytes before them
/// (equivalently: the CRC over the whole frame is 0, MAN16 section 5.7).
pub fn crc_ok(frame: &[u8]) -> bool {
    frame.len() >= 2 && crc16_arc(frame) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value_is_crc16_arc_not_modbus() {
        assert_eq!(crc16_arc(b"123456789"), 0xBB3D);
        // MODBUS (init 0xFFFF) would give C1 10 for TCA; ARC gives B0 D0.
        assert_eq!(crc16_arc(b"TCA").to_le_bytes(), [0xB0, 0xD0]);
    }

    #[test]
    fn crc_over_frame_with_crc_is_zero() {
        let mut f = b"Aw\x04\xb2".to_vec();
        append_crc(&mut f);
        assert_eq!(f, [0x41, 0x77, 0x04, 0xB2, 0x26, 0x93]);
        assert!(crc_ok(&f));
        f[2] ^= 1;
        assert!(!crc_ok(&f));
        assert!(!crc_ok(&[0x00]));
    }
}
