//! Units on the wire: current codes, temperatures x 16, focal-power codes by firmware type
//! (facts sheet sections 4.1, 4.4, 4.5).

/// Current code at the max-current calibration: 4095 (MAN16 section 5.4 defines the max
/// current as the output at code 4095 and the vendor sheet's formulas use 4095; MAN16's
/// "4096" elsewhere differs by 0.024 %).
pub const FULL_SCALE_CODE: f64 = 4095.0;

/// The driver's default max-current calibration, mA (29284 x 0.01).
pub const DEFAULT_MAX_CURRENT_MA: f64 = 292.84;

/// The `TCA` value meaning "no sensor connected".
pub const NO_SENSOR_RAW: i16 = 4095;

/// Temperatures a lens sensor can report, degC (SE97 range); outside it a reading is
/// treated as "no sensor".
pub const SENSOR_RANGE_C: [f64; 2] = [-40.0, 125.0];

/// The current code for `ma` (rounded to nearest, saturated to the i16 range; callers
/// clamp to the driver's limits first). NaN gives 0.
///
/// ```
/// use etl_hw::codec::scaling::current_code;
/// assert_eq!(current_code(100.0, 292.84), 1398);
/// assert_eq!(current_code(-50.0, 292.84), -699);
/// ```
pub fn current_code(ma: f64, max_current_ma: f64) -> i16 {
    let c = (ma * FULL_SCALE_CODE / max_current_ma).round();
    // `as` saturates and maps NaN to 0.
    c as i16
}

/// The current in mA of a current code.
pub fn current_ma(code: i16, max_current_ma: f64) -> f64 {
    f64::from(code) * max_current_ma / FULL_SCALE_CODE
}

/// The temperature of a raw sensor value (degC x 16), or None for the no-sensor value
/// 4095 and readings outside [`SENSOR_RANGE_C`].
pub fn temperature_c(raw: i16) -> Option<f64> {
    if raw == NO_SENSOR_RAW {
        return None;
    }
    let t = f64::from(raw) / 16.0;
    (SENSOR_RANGE_C[0]..=SENSOR_RANGE_C[1]).contains(&t).then_some(t)
}

/// The raw value (degC x 16, rounded) of a temperature, as the sensor quantises it.
pub fn temperature_raw(t_c: f64) -> i16 {
    (t_c * 16.0).round() as i16
}

/// The firmware type (`H` reply), which decides the focal-power encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FirmwareType {
    /// Type A (EL-10-30-C era): FP code = (dpt + 5) x 200.
    A,
    /// Types B, C, E, F (and any other letter): FP code = dpt x 200.
    Other(u8),
}

impl FirmwareType {
    /// From the `H` reply letter.
    pub fn from_letter(letter: u8) -> Self {
        if letter == b'A' {
            FirmwareType::A
        } else {
            FirmwareType::Other(letter)
        }
    }

    /// The letter.
    pub fn letter(self) -> char {
        match self {
            FirmwareType::A => 'A',
            FirmwareType::Other(l) => char::from(l),
        }
    }

    /// The focal-power code of `dpt` dioptres (rounded, saturated; NaN gives the code of
    /// 0 after the offset, callers check finiteness first).
    ///
    /// ```
    /// use etl_hw::codec::scaling::FirmwareType;
    /// assert_eq!(FirmwareType::A.fp_code(5.0), 2000);
    /// assert_eq!(FirmwareType::Other(b'C').fp_code(-1.5), -300);
    /// ```
    pub fn fp_code(self, dpt: f64) -> i16 {
        let offset = if self == FirmwareType::A { 5.0 } else { 0.0 };
        ((dpt + offset) * 200.0).round() as i16
    }

    /// Dioptres of a focal-power code.
    pub fn fp_dpt(self, code: i16) -> f64 {
        let offset = if self == FirmwareType::A { 5.0 } else { 0.0 };
        f64::from(code) / 200.0 - offset
    }
}
